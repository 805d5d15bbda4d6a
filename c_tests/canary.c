/* No byte outside the given arenas and output arrays is written: each sits
 * between guard zones of a known pattern, which must survive build and
 * trace. Inside the tree arena, nothing past the layout's used bytes is
 * written either, and a failing build writes nothing at all. */
#include "common.h"

#define GUARD 4096
#define PATTERN 0xA5

static unsigned char *guarded(size_t bytes) {
    unsigned char *p = arena_alloc(bytes + 2 * GUARD);
    memset(p, PATTERN, bytes + 2 * GUARD);
    return p + GUARD; /* GUARD is a multiple of 16: still aligned */
}
static int intact(const unsigned char *p, size_t from, size_t to) {
    size_t i;
    for (i = from; i < to; i++)
        if (p[i] != PATTERN) return 0;
    return 1;
}
/* Zeros (the room a build packed its tree out of), then the pattern. */
static int zeros_then_intact(const unsigned char *p, size_t from, size_t to) {
    while (from < to && p[from] == 0) from++;
    return intact(p, from, to);
}
static int guards_intact(unsigned char *user, size_t bytes) {
    return intact(user - GUARD, 0, GUARD) && intact(user + bytes, 0, GUARD);
}

int main(void) {
    TestScene ts;
    size_t n, nr = 4000, k;
    uint32_t preset;
    CorayRay *rays;
    rng_state = 13;
    ts = scene_random(1000, 200, 200, 1.0f);
    n = ts.nt + ts.ns + ts.nc;
    rays = malloc(sizeof(CorayRay) * nr);
    rays_random(rays, nr, 1.0f);
    for (preset = 0; preset < 2; preset++) {
        CorayKdParams p = coray_kdtree_params_default(preset);
        CorayRequirements req = requirements0();
        CorayKdTreeInfo info;
        CorayKdTree tree;
        size_t sizes[3];
        memset(&info, 0, sizeof info);
        info.struct_size = sizeof info;
        CHECK_STATUS(coray_kdtree_requirements(n, &p, &req), CORAY_STATUS_OK);
        sizes[0] = req.arena_bytes;
        sizes[1] = (req.arena_min_bytes + req.arena_bytes) / 2 + 3;
        sizes[2] = req.arena_min_bytes;
        for (k = 0; k < 3; k++) {
            unsigned char *arena = guarded(sizes[k]);
            unsigned char *scratch = guarded(req.scratch_bytes);
            unsigned char *hits = guarded(sizeof(CorayHit) * nr);
            unsigned char *occ = guarded(nr);
            unsigned char *stats = guarded(sizeof(CorayTraceStats));
            unsigned char *stack = guarded(CORAY_KDTREE_STACK_BYTES);
            ((CorayTraceStats *)stats)->struct_size = sizeof(CorayTraceStats);
            CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, sizes[k], scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_open(arena, sizes[k], &ts.view, &tree), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_info(&tree, &info), CORAY_STATUS_OK);
            CHECK(info.arena_bytes_used <= sizes[k]);
            /* The tree is packed at the start; the rest of the room the
               build laid out is zeroed, past it nothing is touched. */
            CHECK(zeros_then_intact(arena, info.arena_bytes_used, sizes[k]));
            if (k == 0) CHECK(info.arena_bytes_used < sizes[k]);
            CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, (CorayHit *)hits, nr, stack, CORAY_KDTREE_STACK_BYTES, (CorayTraceStats *)stats), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_intersect(&tree, 1, rays, (CorayHit *)hits, nr, stack, CORAY_KDTREE_STACK_BYTES, (CorayTraceStats *)stats), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_occluded(&tree, 1, rays, occ, nr, stack, CORAY_KDTREE_STACK_BYTES, (CorayTraceStats *)stats), CORAY_STATUS_OK);
            CHECK(guards_intact(arena, sizes[k]));
            CHECK(guards_intact(scratch, req.scratch_bytes));
            CHECK(guards_intact(hits, sizeof(CorayHit) * nr));
            CHECK(guards_intact(occ, nr));
            CHECK(guards_intact(stats, sizeof(CorayTraceStats)));
            CHECK(guards_intact(stack, CORAY_KDTREE_STACK_BYTES));
            /* A failing build writes nothing at all. */
            memset(arena, PATTERN, sizes[k]);
            CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_min_bytes - 1, scratch, req.scratch_bytes, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
            CHECK(intact(arena, 0, sizes[k]));
            free(arena - GUARD);
            free(scratch - GUARD);
            free(hits - GUARD);
            free(occ - GUARD);
            free(stats - GUARD);
            free(stack - GUARD);
        }
    }
    free(rays);
    scene_free(&ts);
    return finish("canary");
}
