/* The documented status of every bad input, exact-fit arenas, relocation
 * (copy and save/load) and corruption detection. */
#include "common.h"

static int same_hits(const CorayHit *a, const CorayHit *b, size_t n) {
    size_t i;
    for (i = 0; i < n; i++)
        if (a[i].geom_id != b[i].geom_id || a[i].prim_id != b[i].prim_id || memcmp(&a[i].t, &b[i].t, 4) != 0) return 0;
    return 1;
}

int main(void) {
    TestScene ts;
    CorayKdParams p = coray_kd_params_default(CORAY_KD_PRESET_AUTO);
    CorayKdRequirements req;
    void *arena, *scratch, *copy;
    size_t needed = 0, n, i;
    CorayRay rays[512];
    CorayHit hits[512], hits2[512];
    uint8_t occ[512];
    CorayTraceStats st;
    CorayKdTreeInfo info;
    CorayKdTreeStats tst;
    int s;

    rng_state = 11;
    ts = scene_random(2000, 300, 300, 1.0f);
    n = ts.nt + ts.ns + ts.nc;
    rays_random(rays, 512, 1.0f);

    /* Status strings: every code has one, unknown ones too. */
    for (s = -1; s <= 10; s++) CHECK(coray_status_str(s) != NULL && strlen(coray_status_str(s)) > 0);
    CHECK(strcmp(coray_status_str(CORAY_STATUS_OK), "ok") == 0);

    /* Requirements. */
    CHECK_STATUS(coray_kdtree_requirements(n, NULL, &req), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_requirements(n, &p, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_requirements((size_t)1 << 30, &p, &req), CORAY_STATUS_TOO_MANY_PRIMITIVES);
    {
        CorayKdParams bad = p;
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
        bad = coray_kd_params_default(99);
        CHECK(bad.struct_size == 0);
        CHECK_STATUS(coray_kdtree_requirements(n, &bad, &req), CORAY_STATUS_INVALID_PARAMETER);
    }
    CHECK_STATUS(coray_kdtree_requirements(n, &p, &req), CORAY_STATUS_OK);
    CHECK(req.tree_min_bytes > 0 && req.tree_min_bytes < req.tree_bytes);
    CHECK(req.scratch_min_bytes > 0 && req.scratch_min_bytes < req.scratch_bytes);

    arena = arena_alloc(req.tree_bytes + 64);
    scratch = arena_alloc(req.scratch_bytes + 64);

    /* Build: null, misaligned, too small (with the bytes needed), overlap, bad scene. */
    CHECK_STATUS(coray_kdtree_build(NULL, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, NULL, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, NULL, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_bytes, NULL, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, (char *)arena + 4, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_bytes, (char *)scratch + 8, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
    needed = 0;
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_min_bytes - 1, scratch, req.scratch_bytes, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
    CHECK(needed == req.tree_min_bytes);
    needed = 0;
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_bytes, scratch, req.scratch_min_bytes - 1, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
    CHECK(needed == req.scratch_min_bytes);
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_bytes, arena, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
    {
        TestScene bad = ts;
        CorayScene v = ts.view;
        v.struct_size = 4;
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
        v = ts.view;
        v.vertices = NULL;
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_NULL_POINTER);
        v = ts.view;
        v.spheres = (const float *)((const char *)ts.spheres + 1);
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_MISALIGNED);
        v = ts.view;
        v.vertex_count = 2; /* triangle indices now point past the vertices */
        CHECK_STATUS(coray_kdtree_build(&v, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_INDEX_OUT_OF_RANGE);
        (void)bad;
    }

    /* Exact fit: the minimum arenas build (one leaf, truncated), and trace. */
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_min_bytes, scratch, req.scratch_min_bytes, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_info(arena, req.tree_min_bytes, &info), CORAY_STATUS_OK);
    CHECK(info.node_count == 1 && info.truncated == 1 && info.arena_bytes_used == req.tree_min_bytes);
    CHECK_STATUS(coray_kdtree_validate(arena, req.tree_min_bytes, &ts.view, &tst), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_min_bytes, &ts.view, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits2, 512, NULL), CORAY_STATUS_OK);

    /* Ideal arenas: a full tree; the same hits as the one-leaf tree. */
    CHECK_STATUS(coray_kdtree_build(&ts.view, &p, arena, req.tree_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_info(arena, req.tree_bytes, &info), CORAY_STATUS_OK);
    CHECK(info.node_count > 1 && info.truncated == 0 && info.valid_prim_count == n);
    CHECK_STATUS(coray_kdtree_validate(arena, req.tree_bytes, &ts.view, &tst), CORAY_STATUS_OK);
    CHECK(tst.node_count == info.node_count && tst.leaf_count == info.leaf_count && tst.depth == info.depth);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits, 512, &st), CORAY_STATUS_OK);
    CHECK(st.rays == 512 && st.traversal_steps == st.interior_steps + st.leaf_steps && st.prim_tests > 0);
    CHECK(same_hits(hits, hits2, 512));
    {
        size_t nhit = 0;
        for (i = 0; i < 512; i++) nhit += hits[i].geom_id != CORAY_INVALID_ID;
        CHECK(nhit > 50);
    }

    /* Trace: bad inputs. */
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 7, rays, hits2, 512, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 0, NULL, hits2, 512, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 0, rays, NULL, 512, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 0, NULL, NULL, 0, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(NULL, req.tree_bytes, &ts.view, 0, rays, hits2, 512, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_intersect((char *)arena + 16, req.tree_bytes - 16, &ts.view, 0, rays, hits2, 512, NULL), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_intersect(arena, 100, &ts.view, 0, rays, hits2, 512, NULL), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_intersect(arena, info.arena_bytes_used - 1, &ts.view, 0, rays, hits2, 512, NULL), CORAY_STATUS_CORRUPT_ARENA);
    CHECK_STATUS(coray_kdtree_intersect1(arena, req.tree_bytes, &ts.view, 0, NULL, hits2, NULL), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(coray_kdtree_occluded1(arena, req.tree_bytes, &ts.view, 0, rays, NULL, NULL), CORAY_STATUS_NULL_POINTER);
    {
        CorayScene v = ts.view;
        v.sphere_count--;
        CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &v, 0, rays, hits2, 512, NULL), CORAY_STATUS_SCENE_MISMATCH);
    }
    /* Outputs are untouched on failure. */
    memset(hits2, 0x5A, sizeof hits2);
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 9, rays, hits2, 512, NULL), CORAY_STATUS_INVALID_PARAMETER);
    CHECK(((unsigned char *)hits2)[0] == 0x5A && ((unsigned char *)hits2)[sizeof hits2 - 1] == 0x5A);

    /* Bad rays: NaN, zero direction, empty interval give a miss, not an error. */
    {
        CorayRay bad[3];
        CorayHit bh[3];
        memset(bad, 0, sizeof bad);
        bad[0].dir[0] = NAN; bad[0].tfar = INFINITY;
        bad[1].tfar = INFINITY;
        bad[2].dir[1] = 1; bad[2].tnear = 2; bad[2].tfar = 1;
        CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, 1, bad, bh, 3, NULL), CORAY_STATUS_OK);
        for (i = 0; i < 3; i++) CHECK(bh[i].geom_id == CORAY_INVALID_ID && bh[i].prim_id == CORAY_INVALID_ID);
    }

    /* Ropes give the same hits; occluded agrees with intersect. */
    CHECK_STATUS(coray_kdtree_intersect(arena, req.tree_bytes, &ts.view, CORAY_TRAVERSAL_ROPES, rays, hits2, 512, NULL), CORAY_STATUS_OK);
    CHECK(same_hits(hits, hits2, 512));
    CHECK_STATUS(coray_kdtree_occluded(arena, req.tree_bytes, &ts.view, CORAY_TRAVERSAL_ROPES, rays, occ, 512, NULL), CORAY_STATUS_OK);
    for (i = 0; i < 512; i++) CHECK(occ[i] == (hits[i].geom_id != CORAY_INVALID_ID));

    /* Relocation: copy the arena elsewhere; save it to a file and load it. */
    copy = arena_alloc(info.arena_bytes_used);
    memcpy(copy, arena, info.arena_bytes_used);
    memset(arena, 0, req.tree_bytes);
    CHECK_STATUS(coray_kdtree_validate(copy, info.arena_bytes_used, &ts.view, NULL), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_intersect(copy, info.arena_bytes_used, &ts.view, 0, rays, hits2, 512, NULL), CORAY_STATUS_OK);
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
        CHECK_STATUS(coray_kdtree_intersect(arena, info.arena_bytes_used, &ts.view, 1, rays, hits2, 512, NULL), CORAY_STATUS_OK);
        CHECK(same_hits(hits, hits2, 512));
    }

    /* Corruption: header words, then a node in the body. */
    {
        uint32_t *words = (uint32_t *)copy;
        words[0] ^= 1; /* magic */
        CHECK_STATUS(coray_kdtree_info(copy, info.arena_bytes_used, &info), CORAY_STATUS_CORRUPT_ARENA);
        CHECK_STATUS(coray_kdtree_intersect(copy, info.arena_bytes_used, &ts.view, 0, rays, hits2, 1, NULL), CORAY_STATUS_CORRUPT_ARENA);
        words[0] ^= 1;
        words[1] = 99; /* version */
        CHECK_STATUS(coray_kdtree_validate(copy, info.arena_bytes_used, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
        memcpy(copy, arena, info.arena_bytes_used);
        words[21]++; /* nodes_offset: no longer the layout the formulas give */
        CHECK_STATUS(coray_kdtree_validate(copy, info.arena_bytes_used, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
        memcpy(copy, arena, info.arena_bytes_used);
        /* First node (the root, at byte 128): point its children elsewhere. */
        words[32] += 4 << 2;
        CHECK_STATUS(coray_kdtree_validate(copy, info.arena_bytes_used, &ts.view, NULL), CORAY_STATUS_CORRUPT_ARENA);
    }

    free(copy);
    free(arena);
    free(scratch);
    scene_free(&ts);
    return finish("api_contract");
}
