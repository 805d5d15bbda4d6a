/* The documented status of every bad input (docs/c-api.md), struct_size
 * versioning, outputs written only on success, overlapping buffers,
 * exact-fit arenas, relocation (copy and save/load) and corruption
 * detection, for the kd-tree. */
#include "common.h"

static int same_hits(const CorayHit *a, const CorayHit *b, size_t n) {
    size_t i;
    for (i = 0; i < n; i++)
        if (a[i].geom_id != b[i].geom_id || a[i].prim_id != b[i].prim_id || memcmp(&a[i].t, &b[i].t, 4) != 0) return 0;
    return 1;
}

static KdStack stack;

int main(void) {
    TestScene ts;
    CorayKdParams p = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    CorayRequirements req = requirements0();
    void *arena, *scratch, *copy;
    size_t needed = 0, n, i;
    CorayRay rays[512];
    CorayHit hits[512], hits2[512];
    uint8_t occ[512];
    CorayTraceStats st = stats0();
    CorayKdTreeInfo info;
    CorayShape shape = shape0();
    CorayKdTree tree, bad_tree;
    int s;

    memset(&info, 0, sizeof info);
    info.struct_size = sizeof info;
    rng_state = 11;
    ts = scene_random(2000, 300, 300, 1.0f);
    n = ts.nt + ts.ns + ts.nc;
    rays_random(rays, 512, 1.0f);

    /* Version and status strings: every code has one, unknown ones too. */
    CHECK(coray_version() == ((CORAY_VERSION_MAJOR << 16) | (CORAY_VERSION_MINOR << 8) | CORAY_VERSION_PATCH));
    for (s = -1; s <= 11; s++) CHECK(coray_status_str(s) != NULL && strlen(coray_status_str(s)) > 0);
    CHECK(strcmp(coray_status_str(CORAY_STATUS_OK), "ok") == 0);

    /* Requirements. */
    CHECK_STATUS(coray_kdtree_requirements(n, NULL, &req), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_requirements(n, &p, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_requirements((size_t)1 << 30, &p, &req), CORAY_STATUS_TOO_MANY_PRIMITIVES);
    {
        CorayKdParams bad = p;
        CorayRequirements small = requirements0();
        bad.struct_size = 8;
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        bad = p;
        bad.cost_traversal = NAN;
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        bad = p;
        bad.empty_bonus = 1.5f;
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        bad = p;
        bad.max_depth = 61;
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        /* omit_ropes (1.2): AUTO leaves the ropes out, PAPER keeps them; 2
         * (1.5) leaves out the empty leaves beside full ones too; 0 to 2 only. */
        CHECK(p.omit_ropes == 1 && coray_kdtree_params_default(CORAY_KD_PRESET_PAPER).omit_ropes == 0);
        bad = p;
        bad.omit_ropes = 3;
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        bad = coray_kdtree_params_default(99);
        CHECK(bad.struct_size == 0);
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
        small.struct_size = 3;
        CHECK_STATUS(coray_kdtree_requirements(n, &p, &small), CORAY_STATUS_INVALID_PARAMETER);
    }
    /* A newer caller's larger struct is fine when its extra bytes are zero. */
    {
        struct {
            CorayKdParams p;
            uint32_t future[4];
        } newer;
        memset(&newer, 0, sizeof newer);
        newer.p = p;
        newer.p.struct_size = sizeof newer;
        CHECK_STATUS(coray_kdtree_requirements(n, &newer.p, &req), CORAY_STATUS_OK);
        newer.future[2] = 1;
        CHECK_STATUS(coray_kdtree_requirements(n, &newer.p, &req), CORAY_STATUS_INVALID_PARAMETER);
    }
    CHECK_STATUS(coray_kdtree_requirements(n, &p, &req), CORAY_STATUS_OK);
    CHECK(req.arena_min_bytes > 0 && req.arena_min_bytes < req.arena_bytes);
    CHECK(req.scratch_min_bytes > 0 && req.scratch_min_bytes < req.scratch_bytes);
    CHECK(req.stack_bytes == CORAY_KDTREE_STACK_BYTES);

    arena = arena_alloc(req.arena_bytes + 64);
    scratch = arena_alloc(req.scratch_bytes + 64);

    /* Build: null, misaligned, too small (with the bytes needed), overlap, bad scene. */
    CHECK_STATUS(coray_kdtree_build(NULL, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, NULL, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, NULL, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, NULL, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, (char *)arena + 4, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, (char *)scratch + 8, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
    needed = 0;
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_min_bytes - 1, scratch, req.scratch_bytes, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
    CHECK(needed == req.arena_min_bytes);
    needed = 0;
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, scratch, req.scratch_min_bytes - 1, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
    CHECK(needed == req.scratch_min_bytes);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, arena, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
    {
        /* The arena over the scene's own arrays. */
        CorayScene v = ts.view;
        v.vertices = (const float *)scratch;
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
        v = ts.view;
        v.struct_size = 4;
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
        v = ts.view;
        v.vertices = NULL;
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
        v = ts.view;
        v.spheres = (const float *)((const char *)ts.spheres + 1);
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
        v = ts.view;
        v.vertex_count = 2; /* triangle indices now point past the vertices */
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_INDEX_OUT_OF_RANGE);
    }

    /* Exact fit: the minimum arenas build (one leaf, truncated), and trace. */
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_min_bytes, scratch, req.scratch_min_bytes, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_open(arena, req.arena_min_bytes, &ts.view, &tree), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_info(&tree, &info), CORAY_STATUS_OK);
    CHECK(info.node_count == 1 && info.truncated == 1 && info.arena_bytes_used == req.arena_min_bytes);
    CHECK_STATUS(coray_kdtree_validate(&tree, NULL, 0, &shape), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);

    /* Ideal arenas: a full tree; the same hits as the one-leaf tree. */
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_open(arena, req.arena_bytes, &ts.view, &tree), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_info(&tree, &info), CORAY_STATUS_OK);
    CHECK(info.node_count > 1 && info.truncated == 0 && info.valid_prim_count == n);
    CHECK(info.stack_bytes == CORAY_KDTREE_STACK_BYTES);
    CHECK_STATUS(coray_kdtree_validate(&tree, NULL, 0, &shape), CORAY_STATUS_OK);
    CHECK(shape.node_count == info.node_count && shape.leaf_count == info.leaf_count && shape.depth == info.depth);
    CHECK_STATUS(coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits, 512, &stack, sizeof stack, &st), CORAY_STATUS_OK);
    CHECK(st.rays == 512 && st.traversal_steps == st.interior_steps + st.leaf_steps && st.prim_tests > 0);
    CHECK(same_hits(hits, hits2, 512));
    /* The same tree with ropes: the same nodes, leaves and references, 48
     * bytes more per leaf and 4 per node (rounded up to 16), the same hits
     * by either traversal. */
    {
        CorayKdParams pr = p;
        CorayRequirements rr = requirements0();
        CorayKdTreeInfo ri = info;
        Tree roped;
        pr.omit_ropes = 0;
        CHECK_STATUS(coray_kdtree_requirements(n, &pr, &rr), CORAY_STATUS_OK);
        CHECK(rr.arena_min_bytes == req.arena_min_bytes + 48 + 16);
        roped = tree_build_with(&ts.view, &pr);
        CHECK_STATUS(coray_kdtree_info(&roped.tree, &ri), CORAY_STATUS_OK);
        CHECK(ri.node_count == info.node_count && ri.leaf_count == info.leaf_count && ri.ref_count == info.ref_count);
        CHECK(ri.arena_bytes_used == info.arena_bytes_used + 48 * (size_t)info.leaf_count + ((4 * (size_t)info.node_count + 15) / 16) * 16);
        CHECK_STATUS(coray_kdtree_intersect(&roped.tree, CORAY_TRAVERSAL_ROPES, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        CHECK(same_hits(hits, hits2, 512));
        free(roped.arena);
    }
    /* Compact (omit_ropes 2): the same leaves and references, fewer nodes
     * (node 1 stands for the empty leaves left out), 8 bytes less for each,
     * the same hits and statistics. */
    {
        CorayKdParams pc = p;
        CorayKdTreeInfo ci = info;
        CorayShape cs = shape;
        CorayTraceStats cst;
        Tree compact;
        pc.omit_ropes = 2;
        compact = tree_build_with(&ts.view, &pc);
        CHECK_STATUS(coray_kdtree_info(&compact.tree, &ci), CORAY_STATUS_OK);
        CHECK(ci.leaf_count == info.leaf_count && ci.ref_count == info.ref_count && ci.depth == info.depth);
        CHECK(ci.node_count < info.node_count && ci.node_count + shape.empty_leaf_count >= info.node_count + 1);
        CHECK(ci.arena_bytes_used == info.arena_bytes_used - ((8 * (size_t)info.node_count + 15) / 16) * 16
                                         + ((8 * (size_t)ci.node_count + 15) / 16) * 16);
        CHECK_STATUS(coray_kdtree_validate(&compact.tree, NULL, 0, &cs), CORAY_STATUS_OK);
        CHECK(cs.leaf_count == shape.leaf_count && cs.empty_leaf_count == shape.empty_leaf_count && cs.ref_count == shape.ref_count);
        cst = stats0();
        CHECK_STATUS(coray_kdtree_intersect(&compact.tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits2, 512, &stack, sizeof stack, &cst), CORAY_STATUS_OK);
        CHECK(same_hits(hits, hits2, 512) && cst.traversal_steps == st.traversal_steps && cst.prim_tests == st.prim_tests);
        free(compact.arena);
    }
    {
        size_t nhit = 0;
        for (i = 0; i < 512; i++) nhit += hits[i].geom_id != CORAY_INVALID_ID;
        CHECK(nhit > 50);
    }

    /* Open: bad arenas, bad handles. */
    CHECK_STATUS(coray_kdtree_open(NULL, req.arena_bytes, &ts.view, &bad_tree), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_open((char *)arena + 16, req.arena_bytes - 16, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_open(arena, 100, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_open(arena, info.arena_bytes_used - 1, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_open(arena, req.arena_bytes, &ts.view, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_open(arena, req.arena_bytes, &ts.view, (CorayKdTree *)arena), CORAY_STATUS_INVALID_PARAMETER);
    {
        CorayScene v = ts.view;
        v.sphere_count--;
        CHECK_STATUS(coray_kdtree_open(arena, req.arena_bytes, &v, &bad_tree), CORAY_STATUS_SCENE_MISMATCH);
    }
    memset(&bad_tree, 0, sizeof bad_tree);
    CHECK_STATUS(coray_kdtree_info(&bad_tree, &info), CORAY_STATUS_INVALID_PARAMETER);
    bad_tree = tree;
    bad_tree.opaque[3] ^= 64; /* a handle changed by hand is refused, not followed */
    CHECK_STATUS(coray_kdtree_intersect(&bad_tree, 0, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_INVALID_PARAMETER);

    /* Trace: bad inputs. */
    CHECK_STATUS(coray_kdtree_intersect(&tree, 7, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, NULL, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, NULL, 512, &stack, sizeof stack, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, NULL, NULL, 0, NULL, 0, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(NULL, 0, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 512, NULL, 0, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 512, &stack, sizeof stack - 1, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 512, stack.bytes + 4, sizeof stack - 16, NULL), CORAY_STATUS_MISALIGNED);
    CHECK_STATUS(coray_kdtree_intersect1(&tree, 0, NULL, hits2, &stack, sizeof stack, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_occluded1(&tree, 0, rays, NULL, &stack, sizeof stack, NULL), CORAY_STATUS_NULL_POINTER);
    /* Overlaps: rays as hits, the stack inside the hits, the hits over the arena. */
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, (CorayHit *)rays, 512, &stack, sizeof stack, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 64, hits2, sizeof hits2, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, (CorayHit *)arena, 4, &stack, sizeof stack, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 4, &stack, sizeof stack, (CorayTraceStats *)(void *)hits2), CORAY_STATUS_INVALID_PARAMETER);
    /* Outputs are untouched on failure: here a misaligned statistics struct. */
    memset(hits2, 0x5A, sizeof hits2);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 512, &stack, sizeof stack, (CorayTraceStats *)((char *)&st + 1)), CORAY_STATUS_MISALIGNED);
    CHECK(((unsigned char *)hits2)[0] == 0x5A && ((unsigned char *)hits2)[sizeof hits2 - 1] == 0x5A);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 9, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK(((unsigned char *)hits2)[0] == 0x5A && ((unsigned char *)hits2)[sizeof hits2 - 1] == 0x5A);
    /* Statistics: the caller's struct_size bytes, no more. */
    {
        CorayTraceStats old = stats0();
        memset(&old, 0x77, sizeof old);
        old.struct_size = 5 * sizeof(uint64_t); /* below the 1.0 size */
        CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 4, &stack, sizeof stack, &old), CORAY_STATUS_INVALID_PARAMETER);
    }

    /* Bad rays: NaN, zero direction, empty interval give a miss, not an error. */
    {
        CorayRay bad[3];
        CorayHit bh[3];
        memset(bad, 0, sizeof bad);
        bad[0].dir[0] = NAN; bad[0].tfar = INFINITY;
        bad[1].tfar = INFINITY;
        bad[2].dir[1] = 1; bad[2].tnear = 2; bad[2].tfar = 1;
        CHECK_STATUS(coray_kdtree_intersect(&tree, 1, bad, bh, 3, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        for (i = 0; i < 3; i++) CHECK(bh[i].geom_id == CORAY_INVALID_ID && bh[i].prim_id == CORAY_INVALID_ID);
    }

    /* Ropes give the same hits; occluded agrees with intersect; one ray at a time too. */
    CHECK_STATUS(coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_ROPES, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
    CHECK(same_hits(hits, hits2, 512));
    CHECK_STATUS(coray_kdtree_occluded(&tree, CORAY_TRAVERSAL_ROPES, rays, occ, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
    for (i = 0; i < 512; i++) CHECK(occ[i] == (hits[i].geom_id != CORAY_INVALID_ID));
    for (i = 0; i < 512; i++) {
        CorayHit h;
        uint8_t o;
        CHECK_STATUS(coray_kdtree_intersect1(&tree, 0, &rays[i], &h, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_occluded1(&tree, 1, &rays[i], &o, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        CHECK(same_hits(&h, &hits[i], 1) && o == occ[i]);
    }
    /* A tracer per thread: the same answers, its statistics summed; a
       tracer the make call did not fill is refused. */
    {
        static KdStack tstack;
        CorayTracer tracer, zeroed;
        CorayTraceStats ts_all = {.struct_size = sizeof ts_all}, ts_one = {.struct_size = sizeof ts_one};
        memset(&zeroed, 0, sizeof zeroed);
        CHECK_STATUS(coray_kdtree_tracer(&tree, 7, &tstack, sizeof tstack, &tracer), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_kdtree_tracer(&tree, CORAY_TRAVERSAL_ROPES, &tstack, sizeof tstack - 1, &tracer), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK_STATUS(coray_kdtree_tracer(&tree, CORAY_TRAVERSAL_ROPES, &tstack, sizeof tstack, &tracer), CORAY_STATUS_OK);
        for (i = 0; i < 512; i++) {
            CorayHit h;
            uint8_t o;
            CHECK_STATUS(coray_kdtree_tracer_intersect1(&tracer, &rays[i], &h), CORAY_STATUS_OK);
            CHECK_STATUS(coray_kdtree_tracer_occluded1(&tracer, &rays[i], &o), CORAY_STATUS_OK);
            CHECK(same_hits(&h, &hits[i], 1) && o == occ[i]);
        }
        CHECK_STATUS(coray_kdtree_tracer_intersect1(&zeroed, &rays[0], &hits2[0]), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_kdtree_tracer_intersect1(&tracer, NULL, &hits2[0]), CORAY_STATUS_NULL_POINTER);
        CHECK_STATUS(coray_kdtree_tracer_intersect1(&tracer, &rays[0], (CorayHit *)&rays[0]), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_tracer_stats(&tracer, &ts_one), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_ROPES, rays, hits2, 512, &stack, sizeof stack, &ts_all), CORAY_STATUS_OK);
        CHECK(ts_one.rays == 1024 && ts_all.rays == 512);
        CHECK(ts_one.traversal_steps > ts_all.traversal_steps && ts_one.prim_tests >= ts_all.prim_tests);
    }

    /* Relocation: copy the arena elsewhere; save it to a file and load it. */
    copy = arena_alloc(info.arena_bytes_used);
    memcpy(copy, arena, info.arena_bytes_used);
    memset(arena, 0, req.arena_bytes);
    CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &tree), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_validate(&tree, NULL, 0, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(&tree, 0, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
    CHECK(same_hits(hits, hits2, 512));
    {
        FILE *f = tmpfile();
        CHECK(f != NULL);
        if (f) {
            CHECK(fwrite(copy, 1, info.arena_bytes_used, f) == info.arena_bytes_used);
            rewind(f);
            CHECK(fread(arena, 1, info.arena_bytes_used, f) == info.arena_bytes_used);
            fclose(f);
        }
        CHECK_STATUS(coray_kdtree_open(arena, info.arena_bytes_used, &ts.view, &tree), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_intersect(&tree, 1, rays, hits2, 512, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        CHECK(same_hits(hits, hits2, 512));
    }

    /* Corruption: header words, a node, a reference. */
    {
        uint32_t *words = (uint32_t *)copy;
        words[0] ^= 1; /* magic */
        CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
        words[0] ^= 1;
        words[1] = 99; /* version */
        CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
        memcpy(copy, arena, info.arena_bytes_used);
        words[23]++; /* nodes_offset: no longer the layout the formulas give */
        CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &bad_tree), CORAY_STATUS_CORRUPT_ARENA);
        memcpy(copy, arena, info.arena_bytes_used);
        /* First node (the root, at byte 128): point its children elsewhere. */
        words[32] += 4 << 2;
        CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &bad_tree), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_validate(&bad_tree, NULL, 0, NULL), CORAY_STATUS_CORRUPT_ARENA);
        memcpy(copy, arena, info.arena_bytes_used);
        /* The first reference renamed to another primitive (header word 26
           is the references' offset): validate sees it. */
        words[words[26] / 4] ^= 1;
        CHECK_STATUS(coray_kdtree_open(copy, info.arena_bytes_used, &ts.view, &bad_tree), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_validate(&bad_tree, NULL, 0, NULL), CORAY_STATUS_CORRUPT_ARENA);
    }

    free(copy);
    free(arena);
    free(scratch);
    scene_free(&ts);
    return finish("api_contract");
}
