/* Hierarchies through the C ABI: every builder gives the kd-tree's hits
 * (same primitive, same t) and any-hit answers; exact-fit arenas build and
 * one byte less fails with the size needed; an R-tree filled by inserts
 * reports a full arena and stays valid; deletes leave exactly the objects
 * kept; a copied arena traces the same; bad input gets its status. */
#include "common.h"

static const char *names[] = {"tdbs", "tdbs-sah", "nn", "rtree", "rstar", "nn-chain"};
#define IS_RTREE(b) ((b) == CORAY_BVH_BUILDER_RTREE || (b) == CORAY_BVH_BUILDER_RSTAR)

/* Hits of `rays` through a kd-tree over `view` (the reference). */
static void kd_reference(const CorayScene *view, const CorayRay *rays, size_t n, CorayHit *hits, uint8_t *occ) {
    Tree kd = tree_build(view, CORAY_KD_PRESET_AUTO);
    KdStack stack;
    CHECK_STATUS(coray_kdtree_intersect(&kd.tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits, n, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_occluded(&kd.tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, occ, n, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
    free(kd.arena);
}

static CorayBvhInfo info0(void) {
    CorayBvhInfo i;
    memset(&i, 0, sizeof i);
    i.struct_size = sizeof i;
    return i;
}

/* Opens a hierarchy arena (the handle every trace takes). */
static CorayBvh open_bvh(const void *arena, size_t bytes, const CorayScene *view) {
    CorayBvh h;
    memset(&h, 0, sizeof h);
    CHECK_STATUS(coray_bvh_open(arena, bytes, view, &h), CORAY_STATUS_OK);
    return h;
}

/* Validates a hierarchy arena on a stack of the size its info gives. */
static CorayStatus validate(const void *arena, size_t bytes, const CorayScene *view, CorayShape *out) {
    CorayBvh h;
    CorayBvhInfo info = info0();
    CorayStatus s = coray_bvh_open(arena, bytes, view, &h);
    void *stack;
    if (s != CORAY_STATUS_OK) return s;
    s = coray_bvh_info(&h, &info);
    if (s != CORAY_STATUS_OK) return s;
    stack = arena_alloc(info.stack_bytes);
    s = coray_bvh_validate(&h, stack, info.stack_bytes, out);
    free(stack);
    return s;
}

/* Rays through the hierarchy against the reference: returns mismatches. */
static size_t compare(const char *what, const void *arena, size_t bytes, const CorayScene *view, const CorayRay *rays,
                      size_t n, const CorayHit *want, const uint8_t *want_occ, CorayTraceStats *st) {
    CorayBvhInfo info = info0();
    CorayHit *hits = malloc(n * sizeof *hits);
    uint8_t *occ = malloc(n);
    void *stack;
    size_t i, bad = 0;
    CorayBvh h = open_bvh(arena, bytes, view);
    CHECK_STATUS(coray_bvh_info(&h, &info), CORAY_STATUS_OK);
    stack = arena_alloc(info.stack_bytes);
    CHECK_STATUS(coray_bvh_intersect(&h, rays, hits, n, stack, info.stack_bytes, st), CORAY_STATUS_OK);
    CHECK_STATUS(coray_bvh_occluded(&h, rays, occ, n, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
    for (i = 0; i < n; i++) {
        int same = hits[i].geom_id == want[i].geom_id && hits[i].prim_id == want[i].prim_id && hits[i].t == want[i].t;
        /* Two primitives at exactly the same distance may come in either order. */
        int tie = hits[i].geom_id != CORAY_INVALID_ID && hits[i].t == want[i].t;
        if (!(same || tie) || occ[i] != want_occ[i]) {
            if (bad < 5)
                printf("  %s ray %zu: bvh %u/%u t=%.9g occ %d, kd %u/%u t=%.9g occ %d\n", what, i, hits[i].geom_id,
                       hits[i].prim_id, (double)hits[i].t, occ[i], want[i].geom_id, want[i].prim_id, (double)want[i].t,
                       want_occ[i]);
            bad++;
        }
    }
    free(stack);
    free(hits);
    free(occ);
    return bad;
}

typedef struct {
    void *arena, *scratch;
    size_t bytes, scratch_bytes;
} Bvh;

static Bvh bvh_build(const CorayScene *view, const CorayBvhParams *p, size_t capacity) {
    CorayRequirements req = requirements0();
    Bvh b;
    CHECK_STATUS(coray_bvh_requirements(capacity, p, &req), CORAY_STATUS_OK);
    b.bytes = req.arena_bytes;
    b.scratch_bytes = req.scratch_bytes;
    b.arena = arena_alloc(b.bytes);
    b.scratch = arena_alloc(b.scratch_bytes);
    CHECK_STATUS(coray_bvh_build(view, p, b.arena, b.bytes, b.scratch, b.scratch_bytes, NULL), CORAY_STATUS_OK);
    return b;
}

static void every_builder_matches_the_kd_tree(void) {
    TestScene ts;
    size_t n = 30000, nprims;
    CorayRay *rays = malloc(n * sizeof *rays);
    CorayHit *want = malloc(n * sizeof *want);
    uint8_t *want_occ = malloc(n);
    uint32_t b;
    rng_state = 41;
    ts = scene_random(2000, 400, 400, 1.0f);
    nprims = ts.nt + ts.ns + ts.nc;
    rays_random(rays, n, 1.0f);
    kd_reference(&ts.view, rays, n, want, want_occ);
    for (b = CORAY_BVH_BUILDER_TDBS; b <= CORAY_BVH_BUILDER_NN_CHAIN; b++) {
        CorayBvhParams p = coray_bvh_params_default(b);
        CorayBvhInfo info = info0();
        CorayShape vs = shape0();
        CorayTraceStats st = stats0();
        Bvh h = bvh_build(&ts.view, &p, nprims);
        CorayBvh hd = open_bvh(h.arena, h.bytes, &ts.view);
        void *copy;
        size_t bad;
        CHECK_STATUS(coray_bvh_info(&hd, &info), CORAY_STATUS_OK);
        CHECK(info.builder == b);
        CHECK(info.ref_count == nprims);
        CHECK(info.max_children == (IS_RTREE(b) ? 8u : 2u));
        CHECK(IS_RTREE(b) || info.node_count == 2 * nprims - 1);
        CHECK(info.capacity >= nprims);
        CHECK(info.arena_bytes_used <= h.bytes);
        CHECK(info.bounds_min[0] < -0.9f && info.bounds_max[0] > 0.9f);
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, &vs), CORAY_STATUS_OK);
        CHECK(vs.ref_count == nprims && vs.node_count == info.node_count && vs.depth == info.depth);
        bad = compare(names[b], h.arena, h.bytes, &ts.view, rays, n, want, want_occ, &st);
        CHECK(bad == 0);
        CHECK(st.rays == n && st.box_tests > n && st.box_cost > 0 && st.prim_cost > 0);
        /* Every box test costs 2 to 51 thesis units. */
        CHECK(st.box_cost <= 51 * st.box_tests && st.box_cost >= 2 * st.box_tests);
        printf("%s: %u nodes, depth %u, %.2f boxes and %.2f objects per ray, %zu mismatches\n", names[b],
               info.node_count, info.depth, (double)st.box_tests / (double)n, (double)st.prim_tests / (double)n, bad);
        /* The arena holds offsets only: a copy elsewhere traces the same. */
        copy = arena_alloc(h.bytes);
        memcpy(copy, h.arena, h.bytes);
        memset(h.arena, 0, h.bytes);
        CHECK(compare("copy", copy, h.bytes, &ts.view, rays, 2000, want, want_occ, NULL) == 0);
        /* Wrong scene, short stack, static insert. */
        {
            CorayScene other = ts.view;
            CorayHit hit;
            CorayBvhInfo ci = info0();
            CorayBvh ch, oh;
            void *stack = arena_alloc(64);
            other.sphere_count--;
            CHECK_STATUS(coray_bvh_open(copy, h.bytes, &other, &oh), CORAY_STATUS_SCENE_MISMATCH);
            ch = open_bvh(copy, h.bytes, &ts.view);
            CHECK_STATUS(coray_bvh_info(&ch, &ci), CORAY_STATUS_OK);
            free(stack);
            stack = arena_alloc(ci.stack_bytes);
            CHECK_STATUS(coray_bvh_intersect(&ch, rays, &hit, 1, stack, ci.stack_bytes - 1, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
            CHECK_STATUS(coray_bvh_intersect(&ch, rays, &hit, 1, NULL, ci.stack_bytes, NULL), CORAY_STATUS_NULL_POINTER);
            /* No rays need no stack. */
            CHECK_STATUS(coray_bvh_intersect(&ch, NULL, NULL, 0, NULL, 0, NULL), CORAY_STATUS_OK);
            if (!IS_RTREE(b))
                CHECK_STATUS(coray_bvh_insert(copy, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 0), CORAY_STATUS_INVALID_PARAMETER);
            /* The original arena, zeroed, is no hierarchy. */
            CHECK_STATUS(coray_bvh_open(h.arena, h.bytes, &ts.view, &oh), CORAY_STATUS_CORRUPT_ARENA);
            free(stack);
        }
        /* A node box that is not its children's union fails validation. */
        ((float *)((char *)copy + 128))[3] += 0.5f;
        CHECK_STATUS(validate(copy, h.bytes, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
        free(copy);
        free(h.arena);
        free(h.scratch);
    }
    scene_free(&ts);
    free(rays);
    free(want);
    free(want_occ);
}

/* Static builders need exactly their bytes; one less says how many. */
static void exact_fit_and_one_less(void) {
    TestScene ts;
    uint32_t b;
    rng_state = 42;
    ts = scene_random(300, 50, 50, 1.0f);
    for (b = CORAY_BVH_BUILDER_TDBS; b <= CORAY_BVH_BUILDER_NN_CHAIN; b++) {
        CorayBvhParams p = coray_bvh_params_default(b);
        CorayRequirements req = requirements0();
        size_t needed = 0, nprims = ts.nt + ts.ns + ts.nc;
        void *a, *s;
        CHECK_STATUS(coray_bvh_requirements(nprims, &p, &req), CORAY_STATUS_OK);
        a = arena_alloc(req.arena_bytes);
        s = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_bvh_build(&ts.view, &p, a, req.arena_bytes - 1, s, req.scratch_bytes, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.arena_bytes);
        needed = 0;
        CHECK_STATUS(coray_bvh_build(&ts.view, &p, a, req.arena_bytes, s, req.scratch_bytes - 1, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.scratch_bytes);
        CHECK_STATUS(coray_bvh_build(&ts.view, &p, a, req.arena_bytes, s, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(validate(a, req.arena_bytes, &ts.view, NULL), CORAY_STATUS_OK);
        /* Overlapping arenas are refused. */
        CHECK_STATUS(coray_bvh_build(&ts.view, &p, a, req.arena_bytes, a, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
        free(a);
        free(s);
    }
    scene_free(&ts);
}

/* Inserts until the arena is full, deletes down to a prefix: the tree then
 * finds exactly what a kd-tree over that prefix of the scene finds. */
static void rtree_insert_and_delete(void) {
    TestScene ts;
    size_t n = 4000, i;
    CorayRay *rays = malloc(n * sizeof *rays);
    CorayHit *want = malloc(n * sizeof *want);
    uint8_t *want_occ = malloc(n);
    uint32_t v;
    rng_state = 43;
    ts = scene_random(1000, 0, 0, 1.0f);
    rays_random(rays, n, 1.0f);
    /* R-tree, R*-tree, R*-tree with forced reinsertion. */
    for (v = 0; v < 3; v++) {
        uint32_t b = v == 0 ? CORAY_BVH_BUILDER_RTREE : CORAY_BVH_BUILDER_RSTAR;
        CorayBvhParams p = coray_bvh_params_default(b);
        CorayBvhInfo info = info0();
        CorayBvh hd;
        CorayScene prefix = ts.view;
        Bvh h;
        uint32_t inserted = 0, q;
        CorayStatus s = CORAY_STATUS_OK;
        uint8_t was = 9;
        p.start_empty = 1;
        p.forced_reinsert = v == 2;
        h = bvh_build(&ts.view, &p, 200);
        hd = open_bvh(h.arena, h.bytes, &ts.view);
        CHECK_STATUS(coray_bvh_info(&hd, &info), CORAY_STATUS_OK);
        CHECK(info.ref_count == 0 && info.capacity >= 200);
        while (inserted < ts.nt && (s = coray_bvh_insert(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, inserted)) == CORAY_STATUS_OK)
            inserted++;
        CHECK_STATUS(s, CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(inserted == info.capacity && inserted < ts.nt);
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, NULL), CORAY_STATUS_OK);
        /* The handle reads the header on each call: no need to open again. */
        CHECK_STATUS(coray_bvh_info(&hd, &info), CORAY_STATUS_OK);
        CHECK(info.ref_count == inserted);
        prefix.triangle_count = inserted;
        kd_reference(&prefix, rays, n, want, want_occ);
        CHECK(compare("full", h.arena, h.bytes, &ts.view, rays, n, want, want_occ, NULL) == 0);
        /* Delete from the back, with an absent object and an index past the scene between. */
        for (q = inserted; q-- > inserted / 2;) {
            CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, q, h.scratch, h.scratch_bytes, &was), CORAY_STATUS_OK);
            CHECK(was == 1);
        }
        CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, inserted - 1, h.scratch, h.scratch_bytes, &was), CORAY_STATUS_OK);
        CHECK(was == 0);
        CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 1u << 30, h.scratch, h.scratch_bytes, &was), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, 7, 0, h.scratch, h.scratch_bytes, &was), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_bvh_insert(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 1u << 30), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 0, h.scratch, 3, &was), CORAY_STATUS_ARENA_TOO_SMALL);
        /* The tree as scratch: overlapping buffers are refused. */
        CHECK_STATUS(coray_bvh_delete(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 0, h.arena, h.bytes, &was), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, NULL), CORAY_STATUS_OK);
        prefix.triangle_count = inserted / 2;
        kd_reference(&prefix, rays, n, want, want_occ);
        CHECK(compare("deleted", h.arena, h.bytes, &ts.view, rays, n, want, want_occ, NULL) == 0);
        /* The room freed by deletes takes new objects again. */
        for (i = inserted / 2; i < inserted; i++)
            CHECK_STATUS(coray_bvh_insert(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, (uint32_t)i), CORAY_STATUS_OK);
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, NULL), CORAY_STATUS_OK);
        /* A corrupt free-list count fails validation (header word 22: free node blocks). */
        ((uint32_t *)h.arena)[22] += 1;
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
        /* Broken R-tree parameters (word 14: M) make a corrupt arena, not a bad argument. */
        ((uint32_t *)h.arena)[22] -= 1;
        ((uint32_t *)h.arena)[14] = 1000;
        CHECK_STATUS(validate(h.arena, h.bytes, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
        CHECK_STATUS(coray_bvh_insert(h.arena, h.bytes, &ts.view, CORAY_GEOM_TRIANGLES, 0), CORAY_STATUS_CORRUPT_ARENA);
        printf("%s%s: %u objects in an arena sized for 200, half deleted and reinserted\n", names[b],
               v == 2 ? " with forced reinsertion" : "", inserted);
        free(h.arena);
        free(h.scratch);
    }
    scene_free(&ts);
    free(rays);
    free(want);
    free(want_occ);
}

static void bad_input(void) {
    CorayBvhParams p = coray_bvh_params_default(CORAY_BVH_BUILDER_RTREE);
    CorayRequirements req = requirements0();
    CHECK(coray_bvh_params_default(6).struct_size == 0);
    CHECK_STATUS(coray_bvh_requirements(10, NULL, &req), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_bvh_requirements(10, &p, NULL), CORAY_STATUS_NULL_POINTER);
    p.max_children = 3;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_RSTAR);
    p.min_children = 5;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS);
    p.leaf_size = 0;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_RTREE);
    p.insert_order = 7;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_RSTAR);
    p.forced_reinsert = 2;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_NN);
    p.struct_size--;
    CHECK_STATUS(coray_bvh_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_bvh_requirements((size_t)1 << 31, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
    p = coray_bvh_params_default(CORAY_BVH_BUILDER_NN);
    CHECK_STATUS(coray_bvh_requirements((size_t)1 << 31, &p, &req), CORAY_STATUS_TOO_MANY_PRIMITIVES);
    {
        /* An empty scene builds an empty hierarchy that misses everything. */
        CorayScene empty = coray_scene_default();
        CorayRay r = {{0, 0, -5}, 0.0f, {0, 0, 1}, INFINITY};
        CorayHit h;
        uint8_t o = 7;
        uint32_t b;
        for (b = CORAY_BVH_BUILDER_TDBS; b <= CORAY_BVH_BUILDER_NN_CHAIN; b++) {
            CorayBvhParams q = coray_bvh_params_default(b);
            CorayBvhInfo info = info0();
            Bvh e = bvh_build(&empty, &q, 0);
            CorayBvh eh = open_bvh(e.arena, e.bytes, &empty), bh;
            void *stack = arena_alloc(64);
            CHECK_STATUS(coray_bvh_info(&eh, &info), CORAY_STATUS_OK);
            CHECK(info.ref_count == 0 && info.stack_bytes <= 64);
            CHECK_STATUS(coray_bvh_intersect(&eh, &r, &h, 1, stack, 64, NULL), CORAY_STATUS_OK);
            CHECK(h.geom_id == CORAY_INVALID_ID && h.prim_id == CORAY_INVALID_ID);
            CHECK_STATUS(coray_bvh_occluded(&eh, &r, &o, 1, stack, 64, NULL), CORAY_STATUS_OK);
            CHECK(o == 0);
            CHECK_STATUS(validate(e.arena, e.bytes, &empty, NULL), CORAY_STATUS_OK);
            CHECK_STATUS(coray_bvh_open(e.arena, 64, &empty, &bh), CORAY_STATUS_CORRUPT_ARENA);
            CHECK_STATUS(coray_bvh_open((char *)e.arena + 4, e.bytes, &empty, &bh), CORAY_STATUS_MISALIGNED);
            free(stack);
            free(e.arena);
            free(e.scratch);
        }
    }
}

int main(void) {
    every_builder_matches_the_kd_tree();
    exact_fit_and_one_less();
    rtree_insert_and_delete();
    bad_input();
    return finish("bvh");
}
