/* Every structure traced from 4 threads at once gives, bit for bit, what
 * one thread gives: the kd-tree (both traversals), a TDBS hierarchy, an
 * R*-tree, the wide hierarchy, a projection hierarchy, LCTS and packet
 * image casts (whole and by tiles) and patch-to-patch visibility. Structures are shared read-only; each thread brings its own
 * stack and scratch. Run under helgrind by the test suite. */
#include <pthread.h>

#include "common.h"

#define THREADS 4
#define RAYS 6000
#define RES 48

/* Everything the threads share, built once. */
typedef struct {
    Tree kd;
    CorayBvh bvh, rtree;
    size_t bvh_stack, rtree_stack;
    CorayProj proj;
    size_t proj_stack;
    CorayWide wide;
    size_t wide_stack;
    CorayCamera cam;
    const CorayRay *rays, *eye_rays;
    void *arenas[4];
} Shared;

/* What one run of every task gives. */
typedef struct {
    CorayHit hits[7][RAYS];
    uint8_t occ[7][RAYS];
    CorayHit image[4][RES * RES];
    CorayPatchResult patch;
    CorayStatus status;
} Out;

static const Shared *shared;

static void note(Out *o, CorayStatus s) {
    if (s != CORAY_STATUS_OK && o->status == CORAY_STATUS_OK) o->status = s;
}

static void *stack_for(size_t bytes) { return arena_alloc(bytes); }

/* Every task once, on this thread's own stacks and scratch. */
static void run_all(Out *o) {
    const Shared *s = shared;
    KdStack kst;
    void *bst = stack_for(s->bvh_stack), *rst = stack_for(s->rtree_stack), *pst = stack_for(s->proj_stack);
    void *wst = stack_for(s->wide_stack);
    uint32_t trav;
    int k;
    o->status = CORAY_STATUS_OK;
    for (trav = 0; trav < 2; trav++) {
        note(o, coray_kdtree_intersect(&s->kd.tree, trav, s->rays, o->hits[trav], RAYS, &kst, sizeof kst, NULL));
        note(o, coray_kdtree_occluded(&s->kd.tree, trav, s->rays, o->occ[trav], RAYS, &kst, sizeof kst, NULL));
    }
    note(o, coray_bvh_intersect(&s->bvh, s->rays, o->hits[2], RAYS, bst, s->bvh_stack, NULL));
    note(o, coray_bvh_occluded(&s->bvh, s->rays, o->occ[2], RAYS, bst, s->bvh_stack, NULL));
    note(o, coray_bvh_intersect(&s->rtree, s->rays, o->hits[3], RAYS, rst, s->rtree_stack, NULL));
    note(o, coray_bvh_occluded(&s->rtree, s->rays, o->occ[3], RAYS, rst, s->rtree_stack, NULL));
    note(o, coray_wide_intersect(&s->wide, s->rays, o->hits[6], RAYS, wst, s->wide_stack, NULL));
    note(o, coray_wide_occluded(&s->wide, s->rays, o->occ[6], RAYS, wst, s->wide_stack, NULL));
    for (k = 0; k < 2; k++) {
        uint32_t scheme = k == 0 ? CORAY_PROJ_SCHEME_2D : CORAY_PROJ_SCHEME_COMBINATION;
        note(o, coray_proj_intersect(&s->proj, scheme, s->eye_rays, o->hits[4 + k], RES * RES, pst, s->proj_stack, NULL));
        note(o, coray_proj_occluded(&s->proj, scheme, s->eye_rays, o->occ[4 + k], RES * RES, pst, s->proj_stack, NULL));
    }
    for (k = 0; k < 2; k++) {
        CorayCastParams cp = coray_cast_params_default();
        CorayRequirements req = requirements0();
        void *scratch;
        cp.scheme = k == 0 ? CORAY_CAST_SLCTS_2D : CORAY_CAST_HLCTS_2D;
        note(o, coray_kdtree_cast_requirements(&s->cam, &cp, &req));
        scratch = arena_alloc(req.scratch_bytes);
        note(o, coray_kdtree_cast_image(&s->kd.tree, &s->cam, &cp, scratch, req.scratch_bytes, &kst, sizeof kst, o->image[k], NULL));
        free(scratch);
    }
    /* The packet cast (the default scheme), of the whole image and of its
     * four uneven tiles, each into a buffer of its own. */
    {
        CorayCastParams cp = coray_cast_params_default();
        CorayHit tile[RES * RES];
        const uint32_t cut[3] = {0, 17, RES};
        uint32_t a, b, x, y;
        note(o, coray_kdtree_cast_image(&s->kd.tree, &s->cam, &cp, NULL, 0, &kst, sizeof kst, o->image[2], NULL));
        for (b = 0; b < 2; b++) {
            for (a = 0; a < 2; a++) {
                cp.rect_x = cut[a];
                cp.rect_y = cut[b];
                cp.rect_width = cut[a + 1] - cut[a];
                cp.rect_height = cut[b + 1] - cut[b];
                note(o, coray_kdtree_cast_image(&s->kd.tree, &s->cam, &cp, NULL, 0, &kst, sizeof kst, tile, NULL));
                for (y = 0; y < cp.rect_height; y++)
                    for (x = 0; x < cp.rect_width; x++)
                        o->image[3][(cp.rect_y + y) * RES + cp.rect_x + x] = tile[y * cp.rect_width + x];
            }
        }
    }
    {
        float a[12] = {-0.5f, 1.2f, -0.5f, 0.5f, 1.2f, -0.5f, 0.5f, 1.2f, 0.5f, -0.5f, 1.2f, 0.5f};
        float b[9] = {-0.6f, -1.2f, -0.4f, 0.6f, -1.2f, -0.3f, 0.0f, -1.2f, 0.6f};
        CorayRequirements req = requirements0();
        void *scratch;
        o->patch = coray_patch_result_default();
        note(o, coray_kdtree_patch_requirements(256, &req));
        scratch = arena_alloc(req.scratch_bytes);
        note(o, coray_kdtree_patch_visibility(&s->kd.tree, a, 4, b, 3, 7, 1e-4f, scratch, req.scratch_bytes, &kst, sizeof kst, &o->patch, NULL));
        free(scratch);
    }
    free(bst);
    free(rst);
    free(pst);
    free(wst);
}

static void *thread_main(void *arg) {
    run_all(arg);
    return NULL;
}

static CorayBvh build_bvh(const CorayScene *view, CorayBvhBuilder b, void **arena, size_t *stack_bytes) {
    CorayBvhParams p = coray_bvh_params_default(b);
    CorayRequirements req = requirements0();
    CorayBvh h;
    void *scratch;
    CHECK_STATUS(coray_bvh_requirements(view->triangle_count + view->sphere_count + view->cone_count, &p, &req), CORAY_STATUS_OK);
    *arena = arena_alloc(req.arena_bytes);
    scratch = arena_alloc(req.scratch_bytes);
    CHECK_STATUS(coray_bvh_build(view, &p, *arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    free(scratch);
    CHECK_STATUS(coray_bvh_open(*arena, req.arena_bytes, view, &h), CORAY_STATUS_OK);
    *stack_bytes = req.stack_bytes;
    return h;
}

int main(void) {
    TestScene ts;
    Shared s;
    Out *ref = malloc(sizeof(Out)), *outs = malloc(sizeof(Out) * THREADS);
    CorayRay *rays = malloc(sizeof(CorayRay) * RAYS), *eye_rays = malloc(sizeof(CorayRay) * RES * RES);
    pthread_t th[THREADS];
    const float eye[3] = {0.4f, 0.7f, 3.0f};
    int i;
    rng_state = 14;
    ts = scene_random(3000, 400, 400, 1.0f);
    rays_random(rays, RAYS, 1.0f);
    rays_camera(eye_rays, RES, RES, eye);
    memset(&s, 0, sizeof s);
    s.rays = rays;
    s.eye_rays = eye_rays;
    s.kd = tree_build_roped(&ts.view, CORAY_KD_PRESET_AUTO);
    s.bvh = build_bvh(&ts.view, CORAY_BVH_BUILDER_TDBS, &s.arenas[0], &s.bvh_stack);
    s.rtree = build_bvh(&ts.view, CORAY_BVH_BUILDER_RSTAR, &s.arenas[1], &s.rtree_stack);
    s.cam = coray_camera_default();
    memcpy(s.cam.from, eye, sizeof eye);
    s.cam.up[1] = 1.0f;
    s.cam.angle_deg = 50.0f;
    s.cam.width = s.cam.height = RES;
    {
        CorayProjParams p = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_BUILDER_RSTAR);
        CorayProjPlane plane = coray_proj_plane_default();
        CorayRequirements req = requirements0();
        void *scratch;
        CHECK_STATUS(coray_proj_camera_plane(&s.cam, &plane), CORAY_STATUS_OK);
        CHECK_STATUS(coray_proj_requirements(ts.nt + ts.ns + ts.nc, &p, &req), CORAY_STATUS_OK);
        s.arenas[2] = arena_alloc(req.arena_bytes);
        scratch = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, s.arenas[2], req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        free(scratch);
        CHECK_STATUS(coray_proj_open(s.arenas[2], req.arena_bytes, &ts.view, &s.proj), CORAY_STATUS_OK);
        s.proj_stack = req.stack_bytes;
    }
    {
        CorayWideParams p = coray_wide_params_default();
        CorayWideInfo info = coray_wide_info_default();
        CorayRequirements req = requirements0();
        void *scratch;
        CHECK_STATUS(coray_wide_requirements(ts.nt + ts.ns + ts.nc, &p, &req), CORAY_STATUS_OK);
        s.arenas[3] = arena_alloc(req.arena_bytes);
        scratch = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_wide_build(&ts.view, &p, s.arenas[3], req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        free(scratch);
        CHECK_STATUS(coray_wide_open(s.arenas[3], req.arena_bytes, &ts.view, &s.wide), CORAY_STATUS_OK);
        CHECK_STATUS(coray_wide_info(&s.wide, &info), CORAY_STATUS_OK);
        s.wide_stack = info.stack_bytes;
    }
    shared = &s;

    memset(ref, 0, sizeof *ref);
    run_all(ref);
    CHECK_STATUS(ref->status, CORAY_STATUS_OK);
    CHECK(ref->patch.samples == 49 * 49 && ref->patch.visible > 0 && ref->patch.visible < ref->patch.samples);
    memset(outs, 0, sizeof(Out) * THREADS);
    for (i = 0; i < THREADS; i++) CHECK(pthread_create(&th[i], NULL, thread_main, &outs[i]) == 0);
    for (i = 0; i < THREADS; i++) {
        CHECK(pthread_join(th[i], NULL) == 0);
        CHECK_STATUS(outs[i].status, CORAY_STATUS_OK);
        CHECK(memcmp(outs[i].hits, ref->hits, sizeof ref->hits) == 0);
        CHECK(memcmp(outs[i].occ, ref->occ, sizeof ref->occ) == 0);
        CHECK(memcmp(outs[i].image, ref->image, sizeof ref->image) == 0);
        CHECK(outs[i].patch.visible == ref->patch.visible && outs[i].patch.samples == ref->patch.samples && outs[i].patch.cut_len == ref->patch.cut_len);
    }
    /* The two kd traversals and the hierarchies agree with each other too;
     * the wide one gives the kd-tree's hits bit for bit. */
    CHECK(memcmp(ref->occ[0], ref->occ[2], RAYS) == 0 && memcmp(ref->occ[0], ref->occ[3], RAYS) == 0);
    CHECK(memcmp(ref->occ[0], ref->occ[6], RAYS) == 0 && memcmp(ref->hits[0], ref->hits[6], sizeof ref->hits[0]) == 0);
    /* Every image cast gives the same pixels, tiles or not. */
    for (i = 1; i < 4; i++) CHECK(memcmp(ref->image[i], ref->image[0], sizeof ref->image[0]) == 0);
    free(s.kd.arena);
    for (i = 0; i < 4; i++) free(s.arenas[i]);
    free(ref);
    free(outs);
    free(rays);
    free(eye_rays);
    scene_free(&ts);
    return finish("threads");
}
