/* LCTS through the C ABI: every casting scheme (the packet tiles too)
 * gives the hierarchical traversal's image bit for bit; patch-to-patch visibility equals casting
 * the same segments one by one; bad parameters get their status. */
#include "common.h"

static CorayCamera camera(uint32_t w, uint32_t h) {
    CorayCamera c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.from[0] = 0.3f; c.from[1] = 0.9f; c.from[2] = 2.8f;
    c.up[1] = 1.0f;
    c.angle_deg = 50.0f;
    c.width = w;
    c.height = h;
    return c;
}

static KdStack stack;

int main(void) {
    TestScene ts;
    Tree tree;
    CorayCamera cam = camera(97, 61);
    size_t n = (size_t)cam.width * cam.height, i;
    CorayHit *ref = malloc(n * sizeof(CorayHit)), *hits = malloc(n * sizeof(CorayHit));
    uint32_t scheme;
    CorayCastParams cp = coray_cast_params_default();
    CorayTraceStats st = stats0(), st_ref = stats0();
    CorayRequirements cr = requirements0();
    void *scratch;
    rng_state = 31;
    ts = scene_random(3000, 400, 400, 1.0f);
    tree = tree_build(&ts.view, CORAY_KD_PRESET_PAPER);

    cp.scheme = CORAY_CAST_HIERARCHICAL;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
    CHECK(cr.scratch_bytes == 0 && cr.stack_bytes == CORAY_KDTREE_STACK_BYTES);
    CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, ref, &st_ref), CORAY_STATUS_OK);
    {
        size_t nhit = 0;
        for (i = 0; i < n; i++) nhit += ref[i].geom_id != CORAY_INVALID_ID;
        CHECK(nhit > n / 10);
    }
    for (scheme = CORAY_CAST_ROPES; scheme <= CORAY_CAST_PACKETS; scheme++) {
        cp = coray_cast_params_default();
        cp.scheme = scheme;
        CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
        /* Packets need no scratch, as the hierarchical cast. */
        if (scheme == CORAY_CAST_PACKETS) CHECK(cr.scratch_bytes == 0 && cr.stack_bytes == CORAY_KDTREE_STACK_BYTES);
        scratch = arena_alloc(cr.scratch_bytes);
        if (cr.scratch_bytes > 0) {
            CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, scratch, cr.scratch_bytes - 1, &stack, sizeof stack, hits, &st), CORAY_STATUS_ARENA_TOO_SMALL);
            /* The scratch and the hits in one buffer. */
            CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, hits, cr.scratch_bytes, &stack, sizeof stack, hits, &st), CORAY_STATUS_INVALID_PARAMETER);
        }
        memset(hits, 0, n * sizeof(CorayHit));
        CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, scratch, cr.scratch_bytes, &stack, sizeof stack, hits, &st), CORAY_STATUS_OK);
        CHECK(memcmp(hits, ref, n * sizeof(CorayHit)) == 0);
        CHECK(st.rays == st_ref.rays);
        if (scheme >= CORAY_CAST_SLCTS_1D && scheme <= CORAY_CAST_HLCTS_2D) CHECK(st.windows > 0);
        if (scheme == CORAY_CAST_PACKETS) CHECK(st.windows == 0);
        /* Only SLCTS windows without a shared leaf start at an entry node. */
        CHECK(st.windows_entered <= st.windows - st.windows_shared);
        if (scheme != CORAY_CAST_SLCTS_1D && scheme != CORAY_CAST_SLCTS_2D) CHECK(st.windows_entered == 0);
        printf("scheme %u: %llu traversal steps (hierarchical %llu), %llu windows, %llu shared, %llu entered\n", scheme,
               (unsigned long long)st.traversal_steps, (unsigned long long)st_ref.traversal_steps,
               (unsigned long long)st.windows, (unsigned long long)st.windows_shared,
               (unsigned long long)st.windows_entered);
        free(scratch);
    }
    /* Tiles of the image cast one by one into buffers of their own (uneven,
     * a one-pixel column among them) give the whole image's hits, by every
     * scheme; rectangles that are empty or leave the image are refused; a
     * struct of 1.0's size (no rectangle fields) casts the whole image. */
    {
        const uint32_t xs[4] = {0, 1, 40, 97}, ys[3] = {0, 30, 61};
        CorayHit *tile = malloc(n * sizeof(CorayHit));
        size_t a, b, wrong = 0;
        uint32_t x, y;
        for (scheme = CORAY_CAST_HIERARCHICAL; scheme <= CORAY_CAST_PACKETS; scheme++) {
            for (b = 0; b < 2; b++) {
                for (a = 0; a < 3; a++) {
                    cp = coray_cast_params_default();
                    cp.scheme = scheme;
                    cp.rect_x = xs[a];
                    cp.rect_y = ys[b];
                    cp.rect_width = xs[a + 1] - xs[a];
                    cp.rect_height = ys[b + 1] - ys[b];
                    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
                    scratch = arena_alloc(cr.scratch_bytes);
                    CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, scratch, cr.scratch_bytes, &stack, sizeof stack, tile, NULL), CORAY_STATUS_OK);
                    for (y = 0; y < cp.rect_height; y++)
                        for (x = 0; x < cp.rect_width; x++)
                            wrong += memcmp(&tile[y * cp.rect_width + x], &ref[(size_t)(cp.rect_y + y) * cam.width + cp.rect_x + x], sizeof(CorayHit)) != 0;
                    free(scratch);
                }
            }
        }
        CHECK(wrong == 0);
        {
            const uint32_t bad[4][4] = {{1, 0, 0, 0}, {0, 0, 5, 0}, {90, 0, 8, 61}, {0xFFFFFFFFu, 0, 2, 1}};
            for (a = 0; a < 4; a++) {
                cp = coray_cast_params_default();
                cp.rect_x = bad[a][0];
                cp.rect_y = bad[a][1];
                cp.rect_width = bad[a][2];
                cp.rect_height = bad[a][3];
                CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
                CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, tile, NULL), CORAY_STATUS_INVALID_PARAMETER);
            }
        }
        cp = coray_cast_params_default();
        cp.struct_size = offsetof(CorayCastParams, rect_x);
        cp.rect_x = 3; /* beyond the caller's struct: not read */
        cp.rect_width = 1;
        CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
        memset(hits, 0, n * sizeof(CorayHit));
        CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, hits, NULL), CORAY_STATUS_OK);
        CHECK(memcmp(hits, ref, n * sizeof(CorayHit)) == 0);
        free(tile);
    }
    /* Bad parameters. */
    cp = coray_cast_params_default();
    cp.scheme = 9;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
    cp.scheme = CORAY_CAST_PACKETS + 1;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
    cp = coray_cast_params_default();
    cp.scheme = CORAY_CAST_SLCTS_2D;
    cp.window_width = 1;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
    /* Packets have no windows: the window fields are not read. */
    cp.scheme = CORAY_CAST_PACKETS;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
    cp = coray_cast_params_default();
    cp.history_capacity = 0;
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
    {
        CorayCamera bad = cam;
        bad.width = 0;
        cp = coray_cast_params_default();
        CHECK_STATUS(coray_kdtree_cast_requirements(&bad, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
        bad = cam;
        bad.angle_deg = NAN;
        CHECK_STATUS(coray_kdtree_cast_requirements(&bad, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
        bad = cam;
        memcpy(bad.at, bad.from, sizeof bad.at); /* the eye on the point looked at */
        CHECK_STATUS(coray_kdtree_cast_requirements(&bad, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
        bad = cam;
        bad.up[0] = bad.at[0] - bad.from[0]; /* up along the view */
        bad.up[1] = bad.at[1] - bad.from[1];
        bad.up[2] = bad.at[2] - bad.from[2];
        CHECK_STATUS(coray_kdtree_cast_requirements(&bad, &cp, &cr), CORAY_STATUS_INVALID_PARAMETER);
        CHECK_STATUS(coray_kdtree_cast_requirements(NULL, &cp, &cr), CORAY_STATUS_NULL_POINTER);
    }
    cp = coray_cast_params_default();
    cp.scheme = CORAY_CAST_SLCTS_2D; /* a scheme with scratch */
    CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, hits, NULL), CORAY_STATUS_NULL_POINTER);
    /* The default scheme: packets, no scratch, on a tree without ropes too. */
    cp = coray_cast_params_default();
    CHECK(cp.scheme == CORAY_CAST_PACKETS && cp.window_width == 5 && cp.window_height == 5);
    CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
    CHECK(cr.scratch_bytes == 0);
    CHECK_STATUS(coray_kdtree_cast_image(&tree.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, hits, NULL), CORAY_STATUS_OK);
    CHECK(memcmp(hits, ref, n * sizeof(CorayHit)) == 0);

    /* Patch-to-patch visibility against casting the same segments. */
    {
        CorayRequirements pr_req = requirements0();
        void *ps;
        int pair, partial = 0;
        CHECK_STATUS(coray_kdtree_patch_requirements(512, &pr_req), CORAY_STATUS_OK);
        ps = arena_alloc(pr_req.scratch_bytes);
        for (pair = 0; pair < 20; pair++) {
            float a[12], b[12], u[3], v[3], ca[3], cb[3];
            int k, ia, ib, nside = 4, visible = 0;
            CorayPatchResult r;
            memset(&r, 0, sizeof r);
            r.struct_size = sizeof r;
            for (k = 0; k < 3; k++) {
                ca[k] = rng_range(-1, 1);
                cb[k] = rng_range(-1, 1);
            }
            rng_unit(u);
            rng_unit(v);
            for (k = 0; k < 3; k++) {
                float s = 0.05f;
                a[0 + k] = ca[k] - s * u[k] - s * v[k];
                a[3 + k] = ca[k] + s * u[k] - s * v[k];
                a[6 + k] = ca[k] + s * u[k] + s * v[k];
                a[9 + k] = ca[k] - s * u[k] + s * v[k];
                b[0 + k] = cb[k] - s * u[k];
                b[3 + k] = cb[k] + s * v[k];
                b[6 + k] = cb[k] + s * u[k];
            }
            CHECK_STATUS(coray_kdtree_patch_visibility(&tree.tree, a, 4, b, 3, (uint32_t)nside, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &r, &st), CORAY_STATUS_OK);
            /* The same sample points: bilinear on the quad, the triangle map on the triangle. */
            for (ia = 0; ia < nside * nside; ia++) {
                float su = (float)(ia % nside) / (float)(nside - 1), sv = (float)(ia / nside) / (float)(nside - 1), P[3];
                for (k = 0; k < 3; k++) {
                    float e0 = a[k] + (a[3 + k] - a[k]) * su, e1 = a[9 + k] + (a[6 + k] - a[9 + k]) * su;
                    P[k] = e0 + (e1 - e0) * sv;
                }
                for (ib = 0; ib < nside * nside; ib++) {
                    float tu = (float)(ib % nside) / (float)(nside - 1), tv = (float)(ib / nside) / (float)(nside - 1), Q[3];
                    CorayRay ray;
                    CorayHit h;
                    for (k = 0; k < 3; k++) Q[k] = b[k] + (b[3 + k] - b[k]) * (tu * (1 - tv)) + (b[6 + k] - b[k]) * (tu * tv);
                    for (k = 0; k < 3; k++) {
                        ray.org[k] = P[k];
                        ray.dir[k] = Q[k] - P[k];
                    }
                    ray.tnear = 1e-4f;
                    ray.tfar = 1.0f - 1e-4f;
                    CHECK_STATUS(coray_kdtree_intersect1(&tree.tree, CORAY_TRAVERSAL_HIERARCHICAL, &ray, &h, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
                    visible += h.geom_id == CORAY_INVALID_ID;
                }
            }
            CHECK(r.samples == (uint32_t)(nside * nside * nside * nside));
            CHECK(r.visible == (uint32_t)visible);
            partial += visible > 0 && visible < (int)r.samples;
        }
        printf("patch pairs: 20, partly visible: %d\n", partial);
        CHECK(partial > 0);
        {
            float a[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
            float b[9] = {0, 0, 2, 1, 0, 2, 0, 1, 2};
            CorayPatchResult r;
            memset(&r, 0, sizeof r);
            r.struct_size = sizeof r;
            CHECK_STATUS(coray_kdtree_patch_visibility(&tree.tree, a, 2, b, 3, 4, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &r, NULL), CORAY_STATUS_INVALID_PARAMETER);
            CHECK_STATUS(coray_kdtree_patch_visibility(&tree.tree, a, 3, b, 3, 4, 1e-4f, ps, 8, &stack, sizeof stack, &r, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
            /* 256 samples per side would count 2^32 segments in 32 bits: refused. */
            CHECK_STATUS(coray_kdtree_patch_visibility(&tree.tree, a, 3, b, 3, 256, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &r, NULL), CORAY_STATUS_INVALID_PARAMETER);
        }
        /* A tree without ropes (AUTO's default): the hierarchical cast runs,
         * every scheme that walks ropes and the patch query are refused
         * with NO_ROPES before writing anything; with ropes they run and
         * give the hierarchical cast's hits. */
        {
            Tree plain = tree_build(&ts.view, CORAY_KD_PRESET_AUTO);
            Tree roped = tree_build_roped(&ts.view, CORAY_KD_PRESET_AUTO);
            CorayHit *plain_ref = malloc(n * sizeof(CorayHit));
            float a[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
            float b[9] = {0, 0, 2, 1, 0, 2, 0, 1, 2};
            CorayPatchResult r;
            memset(&r, 0, sizeof r);
            r.struct_size = sizeof r;
            cp = coray_cast_params_default();
            cp.scheme = CORAY_CAST_HIERARCHICAL;
            CHECK_STATUS(coray_kdtree_cast_image(&plain.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, plain_ref, NULL), CORAY_STATUS_OK);
            for (scheme = CORAY_CAST_ROPES; scheme <= CORAY_CAST_HLCTS_2D; scheme++) {
                cp = coray_cast_params_default();
                cp.scheme = scheme;
                CHECK_STATUS(coray_kdtree_cast_requirements(&cam, &cp, &cr), CORAY_STATUS_OK);
                scratch = arena_alloc(cr.scratch_bytes);
                memset(hits, 0xAB, n * sizeof(CorayHit));
                CHECK_STATUS(coray_kdtree_cast_image(&plain.tree, &cam, &cp, scratch, cr.scratch_bytes, &stack, sizeof stack, hits, NULL), CORAY_STATUS_NO_ROPES);
                for (i = 0; i < n; i++) CHECK(hits[i].geom_id == 0xABABABABu);
                CHECK_STATUS(coray_kdtree_cast_image(&roped.tree, &cam, &cp, scratch, cr.scratch_bytes, &stack, sizeof stack, hits, NULL), CORAY_STATUS_OK);
                CHECK(memcmp(hits, plain_ref, n * sizeof(CorayHit)) == 0);
                free(scratch);
            }
            /* Packets walk no ropes: the plain tree casts them. */
            cp = coray_cast_params_default();
            cp.scheme = CORAY_CAST_PACKETS;
            memset(hits, 0xAB, n * sizeof(CorayHit));
            CHECK_STATUS(coray_kdtree_cast_image(&plain.tree, &cam, &cp, NULL, 0, &stack, sizeof stack, hits, NULL), CORAY_STATUS_OK);
            CHECK(memcmp(hits, plain_ref, n * sizeof(CorayHit)) == 0);
            CHECK_STATUS(coray_kdtree_patch_visibility(&plain.tree, a, 3, b, 3, 4, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &r, NULL), CORAY_STATUS_NO_ROPES);
            CHECK(r.samples == 0);
            CHECK_STATUS(coray_kdtree_patch_visibility(&roped.tree, a, 3, b, 3, 4, 1e-4f, ps, pr_req.scratch_bytes, &stack, sizeof stack, &r, NULL), CORAY_STATUS_OK);
            CHECK(r.samples == 256);
            CHECK(strcmp(coray_status_str(CORAY_STATUS_NO_ROPES), "unknown status") != 0);
            free(plain_ref);
            free(plain.arena);
            free(roped.arena);
        }
        free(ps);
    }
    free(ref);
    free(hits);
    free(tree.arena);
    scene_free(&ts);
    return finish("lcts");
}
