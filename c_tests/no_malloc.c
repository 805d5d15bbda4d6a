/* coray never allocates: count malloc, calloc, realloc and free (and their
 * aligned cousins) while building and tracing; the count must be 0. This
 * program interposes the allocator for the whole process, Rust std included. */
#include <stddef.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

static volatile int counting = 0;
static volatile long alloc_calls = 0;

void *malloc(size_t n) {
    if (counting) alloc_calls++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    if (counting) alloc_calls++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    if (counting) alloc_calls++;
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (counting) alloc_calls++;
    __libc_free(p);
}
int posix_memalign(void **out, size_t align, size_t n) {
    if (counting) alloc_calls++;
    *out = __libc_memalign(align, n);
    return *out ? 0 : 12;
}
void *aligned_alloc(size_t align, size_t n) {
    if (counting) alloc_calls++;
    return __libc_memalign(align, n);
}
void *memalign(size_t align, size_t n) {
    if (counting) alloc_calls++;
    return __libc_memalign(align, n);
}

#include "common.h"

static KdStack stack;

int main(void) {
    TestScene ts;
    CorayRequirements req = requirements0();
    void *arena, *scratch;
    CorayRay *rays;
    CorayHit *hits;
    uint8_t *occ;
    CorayTraceStats st = stats0();
    CorayShape shape = shape0();
    CorayKdTree tree;
    size_t n, nr = 20000;
    uint32_t preset, trav;
    long probe;

    rng_state = 12;
    ts = scene_random(3000, 500, 500, 1.0f);
    n = ts.nt + ts.ns + ts.nc;
    rays = malloc(sizeof(CorayRay) * nr);
    hits = malloc(sizeof(CorayHit) * nr);
    occ = malloc(nr);
    rays_random(rays, nr, 1.0f);

    /* The counter works: one malloc while counting is seen. */
    counting = 1;
    free(malloc(16));
    counting = 0;
    probe = alloc_calls;
    CHECK(probe == 2);
    alloc_calls = 0;

    for (preset = 0; preset < 2; preset++) {
        CorayKdParams p = coray_kdtree_params_default(preset);
        p.omit_ropes = 0; /* the casts and the patch query below walk ropes */
        CHECK_STATUS(coray_kdtree_requirements(n, &p, &req), CORAY_STATUS_OK);
        arena = arena_alloc(req.arena_bytes);
        scratch = arena_alloc(req.scratch_bytes);
        counting = 1;
        CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_open(arena, req.arena_bytes, &ts.view, &tree), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_validate(&tree, NULL, 0, &shape), CORAY_STATUS_OK);
        for (trav = 0; trav < 2; trav++) {
            CHECK_STATUS(coray_kdtree_intersect(&tree, trav, rays, hits, nr, &stack, sizeof stack, &st), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_occluded(&tree, trav, rays, occ, nr, &stack, sizeof stack, &st), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_intersect1(&tree, trav, rays, hits, &stack, sizeof stack, &st), CORAY_STATUS_OK);
        }
        /* LCTS image casting and patch visibility, scratch allocated before counting. */
        {
            CorayCamera cam;
            CorayCastParams cp = coray_cast_params_default();
            CorayRequirements cr = requirements0(), pr_req = requirements0();
            uint32_t sch;
            float a[12] = {-0.5f, -0.5f, 1.5f, 0.5f, -0.5f, 1.5f, 0.5f, 0.5f, 1.5f, -0.5f, 0.5f, 1.5f};
            float b[9] = {-0.3f, -0.3f, -1.5f, 0.3f, -0.3f, -1.5f, 0.0f, 0.3f, -1.5f};
            CorayPatchResult pr;
            void *cs, *ps;
            memset(&cam, 0, sizeof cam);
            cam.struct_size = sizeof cam;
            cam.from[2] = 3.0f;
            cam.up[1] = 1.0f;
            cam.angle_deg = 45.0f;
            cam.width = 64;
            cam.height = 48;
            memset(&pr, 0, sizeof pr);
            pr.struct_size = sizeof pr;
            counting = 0;
            cp.scheme = CORAY_CAST_HLCTS_2D;
            CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_patch_requirements(256, &pr_req), CORAY_STATUS_OK);
            cs = arena_alloc(cr.scratch_bytes);
            ps = arena_alloc(pr_req.scratch_bytes);
            counting = 1;
            for (sch = CORAY_CAST_SLCTS_1D; sch <= CORAY_CAST_HLCTS_2D; sch++) {
                cp.scheme = sch;
                CHECK_STATUS(coray_kdtree_cast_image(&tree, &cam, &cp, cs, cr.scratch_bytes, &stack, sizeof stack, hits, NULL), CORAY_STATUS_OK);
            }
            CHECK_STATUS(coray_kdtree_patch_visibility(&tree, a, 4, b, 3, 4, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &pr, &st), CORAY_STATUS_OK);
            counting = 0;
            free(cs);
            free(ps);
            counting = 1;
        }
        /* Error paths too. */
        CHECK_STATUS(coray_kdtree_open(arena, 10, &ts.view, &tree), CORAY_STATUS_CORRUPT_ARENA);
        CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits, nr, &stack, 16, &st), CORAY_STATUS_ARENA_TOO_SMALL);
        counting = 0;
        printf("preset %u: %ld allocator calls during build, validate and %zu x 5 traces\n", preset, alloc_calls, nr);
        CHECK(alloc_calls == 0);
        free(arena);
        free(scratch);
    }
    free(rays);
    free(hits);
    free(occ);
    scene_free(&ts);
    return finish("no_malloc");
}
