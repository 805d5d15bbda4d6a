/* Projection hierarchies through the C ABI: for every builder and both
 * criteria, camera rays by all three schemes give the kd-tree's hits, and
 * shadow rays through a light's planes (a cube, a single face, a
 * directional plane) its any-hit answers; exact-fit arenas build and one
 * byte less reports the size; a copied arena traces the same; rays off the
 * eye, bad schemes, other scenes and corrupt arenas get their status. */
#include "common.h"

typedef struct {
    void *arena;
    size_t bytes;
    CorayProj handle;
} Proj;

static CorayProjInfo info0(void) {
    CorayProjInfo i;
    memset(&i, 0, sizeof i);
    i.struct_size = sizeof i;
    return i;
}

static Proj proj_build(const CorayScene *s, const CorayProjParams *p, const CorayProjPlane *plane) {
    CorayRequirements req = requirements0();
    Proj h;
    void *scratch;
    size_t n = s->triangle_count + s->sphere_count + s->cone_count;
    CHECK_STATUS(coray_proj_requirements(n, p, &req), CORAY_STATUS_OK);
    h.bytes = req.arena_bytes;
    h.arena = arena_alloc(h.bytes);
    scratch = arena_alloc(req.scratch_bytes);
    CHECK_STATUS(coray_proj_build(s, p, plane, h.arena, h.bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    free(scratch);
    CHECK_STATUS(coray_proj_open(h.arena, h.bytes, s, &h.handle), CORAY_STATUS_OK);
    return h;
}

static CorayStatus validate(const CorayProj *h) {
    CorayProjInfo info = info0();
    void *stack;
    CorayStatus s = coray_proj_info(h, &info);
    if (s != CORAY_STATUS_OK) return s;
    stack = arena_alloc(info.stack_bytes);
    s = coray_proj_validate(h, stack, info.stack_bytes, NULL);
    free(stack);
    return s;
}

/* Same hit at the same t, or another primitive at exactly that t. */
static int same(const CorayHit *a, const CorayHit *b) {
    if ((a->geom_id == CORAY_INVALID_ID) != (b->geom_id == CORAY_INVALID_ID)) return 0;
    return a->geom_id == CORAY_INVALID_ID || a->t == b->t;
}

int main(void) {
    TestScene ts;
    CorayCamera cam;
    CorayProjPlane plane;
    Tree kd;
    KdStack kst;
    int res = 64;
    size_t n = (size_t)res * (size_t)res, i, nhit = 0;
    CorayRay *rays = malloc(n * sizeof *rays), *shadow = malloc(n * sizeof *shadow);
    CorayHit *want = malloc(n * sizeof *want), *got = malloc(n * sizeof *got);
    uint8_t *want_occ = malloc(n), *occ = malloc(n);
    float eye[3] = {0.3f, 0.9f, 2.8f};
    uint32_t b, c, s;
    rng_state = 51;
    ts = scene_random(2000, 300, 300, 1.0f);
    kd = tree_build(&ts.view, CORAY_KD_PRESET_AUTO);
    memset(&cam, 0, sizeof cam);
    cam.struct_size = sizeof cam;
    memcpy(cam.from, eye, sizeof eye);
    cam.up[1] = 1.0f;
    cam.angle_deg = 60.0f;
    cam.width = cam.height = (uint32_t)res;
    memset(&plane, 0, sizeof plane);
    plane.struct_size = sizeof plane;
    CHECK_STATUS(coray_proj_camera_plane(&cam, &plane), CORAY_STATUS_OK);
    CHECK(plane.kind == CORAY_PLANE_PERSPECTIVE && plane.eye[2] == eye[2]);
    rays_camera(rays, res, res, eye);
    CHECK_STATUS(coray_kdtree_intersect(&kd.tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, want, n, &kst, sizeof kst, NULL), CORAY_STATUS_OK);
    for (i = 0; i < n; i++) nhit += want[i].geom_id != CORAY_INVALID_ID;
    CHECK(nhit > n / 5);

    /* Camera rays: every builder, both criteria, all schemes. */
    for (c = CORAY_PROJ_CRITERIA_2D; c <= CORAY_PROJ_CRITERIA_DUMMY; c++)
        for (b = CORAY_BVH_BUILDER_TDBS; b <= CORAY_BVH_BUILDER_NN_CHAIN; b++) {
            CorayProjParams p = coray_proj_params_default(c, b);
            CorayProjInfo info = info0();
            CorayTraceStats st = stats0();
            Proj h;
            CorayProj ch, oh;
            void *stack, *copy;
            if (b == CORAY_BVH_BUILDER_NN) continue; /* the chain makes its joins */
            h = proj_build(&ts.view, &p, &plane);
            CHECK_STATUS(coray_proj_info(&h.handle, &info), CORAY_STATUS_OK);
            CHECK(info.builder == b && info.criteria == c && info.ref_count > 0);
            CHECK(c == CORAY_PROJ_CRITERIA_2D || info.ref_count == ts.nt + ts.ns + ts.nc);
            CHECK(info.plane.eye[0] == plane.eye[0]);
            CHECK_STATUS(validate(&h.handle), CORAY_STATUS_OK);
            stack = arena_alloc(info.stack_bytes);
            for (s = CORAY_PROJ_SCHEME_2D; s <= CORAY_PROJ_SCHEME_COMBINATION; s++) {
                size_t bad = 0;
                CHECK_STATUS(coray_proj_intersect(&h.handle, s, rays, got, n, stack, info.stack_bytes, &st), CORAY_STATUS_OK);
                for (i = 0; i < n; i++) bad += !same(&got[i], &want[i]);
                CHECK(bad == 0);
                CHECK(st.rays == n);
                CHECK(s == CORAY_PROJ_SCHEME_3D ? st.rect_tests == 0 : st.rect_tests > 0);
                if (s == CORAY_PROJ_SCHEME_2D) CHECK(st.box_cost == 4 * st.box_tests);
                if (bad) printf("  criteria %u builder %u scheme %u: %zu rays differ\n", c, b, s, bad);
            }
            /* A copy elsewhere traces the same; the zeroed original is no hierarchy. */
            copy = arena_alloc(h.bytes);
            memcpy(copy, h.arena, h.bytes);
            memset(h.arena, 0, h.bytes);
            CHECK_STATUS(coray_proj_open(copy, h.bytes, &ts.view, &ch), CORAY_STATUS_OK);
            CHECK_STATUS(coray_proj_intersect(&ch, CORAY_PROJ_SCHEME_2D, rays, got, n, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
            for (i = 0; i < n; i++) CHECK(same(&got[i], &want[i]));
            CHECK_STATUS(coray_proj_open(h.arena, h.bytes, &ts.view, &oh), CORAY_STATUS_CORRUPT_ARENA);
            /* Errors: a ray off the eye (nothing written), a bad scheme, another scene, a short stack. */
            {
                CorayRay off[2];
                CorayScene other = ts.view;
                off[0] = rays[0];
                off[1] = rays[1];
                off[1].org[0] += 0.25f;
                memset(got, 0x5A, 2 * sizeof *got);
                CHECK_STATUS(coray_proj_intersect(&ch, 0, off, got, 2, stack, info.stack_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
                CHECK(((unsigned char *)got)[0] == 0x5A);
                CHECK_STATUS(coray_proj_intersect(&ch, 3, rays, got, 1, stack, info.stack_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
                other.cone_count--;
                CHECK_STATUS(coray_proj_open(copy, h.bytes, &other, &oh), CORAY_STATUS_SCENE_MISMATCH);
                CHECK_STATUS(coray_proj_intersect(&ch, 0, rays, got, 1, stack, info.stack_bytes - 1, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
                CHECK_STATUS(coray_proj_intersect(&ch, 0, NULL, NULL, 0, NULL, 0, NULL), CORAY_STATUS_OK);
            }
            /* A root box that is not its entries' union fails validation. */
            ((float *)((char *)copy + 128))[0] -= 1.0f;
            CHECK_STATUS(validate(&ch), CORAY_STATUS_CORRUPT_ARENA);
            free(copy);
            free(stack);
            free(h.arena);
        }

    /* Exact fit and one byte less. */
    {
        CorayProjParams p = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_BUILDER_RSTAR);
        CorayRequirements req = requirements0();
        CorayProj hd;
        size_t needed = 0;
        void *a, *sc;
        CHECK_STATUS(coray_proj_requirements(ts.nt + ts.ns + ts.nc, &p, &req), CORAY_STATUS_OK);
        a = arena_alloc(req.arena_bytes);
        sc = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.arena_bytes - 1, sc, req.scratch_bytes, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.arena_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.arena_bytes, sc, req.scratch_bytes - 1, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.scratch_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.arena_bytes, sc, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(coray_proj_open(a, req.arena_bytes, &ts.view, &hd), CORAY_STATUS_OK);
        CHECK_STATUS(validate(&hd), CORAY_STATUS_OK);
        p.criteria = 2;
        CHECK_STATUS(coray_proj_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
        CHECK(coray_proj_params_default(2, 0).struct_size == 0);
        free(a);
        free(sc);
    }

    /* Shadow rays through light planes: inside (cube), outside (one face), directional. */
    {
        CorayLight lights[3] = {{sizeof(CorayLight), CORAY_LIGHT_POINT, {0.1f, 0.2f, 0.05f}},
                                {sizeof(CorayLight), CORAY_LIGHT_POINT, {0.4f, 3.5f, 1.0f}},
                                {sizeof(CorayLight), CORAY_LIGHT_DIRECTIONAL, {-0.3f, -1.0f, -0.2f}}};
        float lo[3] = {-1.1f, -1.1f, -1.1f}, hi[3] = {1.1f, 1.1f, 1.1f};
        uint32_t expect_count[3] = {6, 1, 1}, li;
        for (li = 0; li < 3; li++) {
            CorayProjPlane planes[6];
            uint32_t count = 0, k;
            size_t ns = 0, blocked = 0;
            Proj faces[6];
            CorayProjParams p = coray_proj_params_default(li == 1 ? CORAY_PROJ_CRITERIA_DUMMY : CORAY_PROJ_CRITERIA_2D,
                                                          li == 2 ? CORAY_BVH_BUILDER_RTREE : CORAY_BVH_BUILDER_TDBS);
            CHECK_STATUS(coray_proj_light_planes(&lights[li], &lo, &hi, planes, &count), CORAY_STATUS_OK);
            CHECK(count == expect_count[li]);
            for (k = 0; k < count; k++) faces[k] = proj_build(&ts.view, &p, &planes[k]);
            for (i = 0; i < n; i++) {
                CorayRay *r = &shadow[ns];
                float pt[3], d[3], len = 0;
                int a;
                if (want[i].geom_id == CORAY_INVALID_ID) continue;
                for (a = 0; a < 3; a++) pt[a] = rays[i].org[a] + want[i].t * rays[i].dir[a];
                for (a = 0; a < 3; a++) d[a] = li == 2 ? -lights[li].v[a] : lights[li].v[a] - pt[a];
                len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (a = 0; a < 3; a++) {
                    r->org[a] = pt[a];
                    r->dir[a] = d[a] / len;
                }
                r->tnear = 1e-3f;
                r->tfar = li == 2 ? INFINITY : len;
                ns++;
            }
            CHECK_STATUS(coray_kdtree_occluded(&kd.tree, 0, shadow, want_occ, ns, &kst, sizeof kst, NULL), CORAY_STATUS_OK);
            for (s = CORAY_PROJ_SCHEME_2D; s <= CORAY_PROJ_SCHEME_COMBINATION; s++)
                for (i = 0; i < ns; i++) {
                    uint32_t face = 99;
                    CorayProjInfo info = info0();
                    void *stack;
                    CHECK_STATUS(coray_proj_light_plane_for(&lights[li], &lo, &hi, &shadow[i], &face), CORAY_STATUS_OK);
                    CHECK(face < count);
                    if (face >= count) continue;
                    CHECK_STATUS(coray_proj_info(&faces[face].handle, &info), CORAY_STATUS_OK);
                    stack = arena_alloc(info.stack_bytes);
                    CHECK_STATUS(coray_proj_occluded1(&faces[face].handle, s, &shadow[i], &occ[i], stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
                    free(stack);
                    CHECK(occ[i] == want_occ[i]);
                    blocked += occ[i];
                }
            CHECK(blocked > 0 && blocked < 3 * ns);
            /* A ray away from the light is refused by its planes. */
            {
                CorayRay away = shadow[0];
                uint32_t face;
                int a;
                for (a = 0; a < 3; a++) away.dir[a] = -away.dir[a];
                CHECK_STATUS(coray_proj_light_plane_for(&lights[li], &lo, &hi, &away, &face), CORAY_STATUS_INVALID_PARAMETER);
            }
            printf("light %u: %u plane(s), %zu shadow rays, %zu blocked over 3 schemes\n", li, count, ns, blocked);
            for (k = 0; k < count; k++) free(faces[k].arena);
        }
    }
    scene_free(&ts);
    free(kd.arena);
    free(rays);
    free(shadow);
    free(want);
    free(got);
    free(want_occ);
    free(occ);
    return finish("proj");
}
