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
} Proj;

static Proj proj_build(const CorayScene *s, const CorayProjParams *p, const CorayProjPlane *plane) {
    CorayProjRequirements req;
    Proj h;
    void *scratch;
    size_t n = s->triangle_count + s->sphere_count + s->cone_count;
    CHECK_STATUS(coray_proj_requirements(n, p, &req), CORAY_STATUS_OK);
    h.bytes = req.proj_bytes;
    h.arena = arena_alloc(h.bytes);
    scratch = arena_alloc(req.scratch_bytes);
    CHECK_STATUS(coray_proj_build(s, p, plane, h.arena, h.bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    free(scratch);
    return h;
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
    CHECK_STATUS(coray_proj_plane_camera(&cam, &plane), CORAY_STATUS_OK);
    CHECK(plane.kind == CORAY_PLANE_PERSPECTIVE && plane.eye[2] == eye[2]);
    rays_camera(rays, res, res, eye);
    CHECK_STATUS(coray_kdtree_intersect(kd.arena, kd.bytes, &ts.view, CORAY_TRAVERSAL_HIERARCHICAL, rays, want, n, NULL), CORAY_STATUS_OK);
    for (i = 0; i < n; i++) nhit += want[i].geom_id != CORAY_INVALID_ID;
    CHECK(nhit > n / 5);

    /* Camera rays: every builder, both criteria, all schemes. */
    for (c = CORAY_PROJ_CRITERIA_2D; c <= CORAY_PROJ_CRITERIA_DUMMY; c++)
        for (b = CORAY_BVH_TDBS; b <= CORAY_BVH_NN_CHAIN; b++) {
            CorayProjParams p = coray_proj_params_default(c, b);
            CorayProjInfo info;
            CorayProjStats st;
            Proj h;
            void *stack, *copy;
            if (b == CORAY_BVH_NN) continue; /* the chain makes its joins */
            h = proj_build(&ts.view, &p, &plane);
            CHECK_STATUS(coray_proj_info(h.arena, h.bytes, &info), CORAY_STATUS_OK);
            CHECK(info.builder == b && info.criteria == c && info.object_count > 0);
            CHECK(c == CORAY_PROJ_CRITERIA_2D || info.object_count == ts.nt + ts.ns + ts.nc);
            CHECK(info.plane.eye[0] == plane.eye[0]);
            CHECK_STATUS(coray_proj_validate(h.arena, h.bytes, &ts.view), CORAY_STATUS_OK);
            stack = malloc(info.stack_bytes);
            for (s = CORAY_PROJ_SCHEME_2D; s <= CORAY_PROJ_SCHEME_COMBINATION; s++) {
                size_t bad = 0;
                CHECK_STATUS(coray_proj_intersect(h.arena, h.bytes, &ts.view, s, rays, got, n, stack, info.stack_bytes, &st), CORAY_STATUS_OK);
                for (i = 0; i < n; i++) bad += !same(&got[i], &want[i]);
                CHECK(bad == 0);
                CHECK(st.bvh.trace.rays == n);
                CHECK(s == CORAY_PROJ_SCHEME_3D ? st.rect_tests == 0 : st.rect_tests > 0);
                if (s == CORAY_PROJ_SCHEME_2D) CHECK(st.bvh.box_cost == 4 * st.bvh.box_tests);
                if (bad) printf("  criteria %u builder %u scheme %u: %zu rays differ\n", c, b, s, bad);
            }
            /* A copy elsewhere traces the same; the zeroed original is no hierarchy. */
            copy = arena_alloc(h.bytes);
            memcpy(copy, h.arena, h.bytes);
            memset(h.arena, 0, h.bytes);
            CHECK_STATUS(coray_proj_intersect(copy, h.bytes, &ts.view, CORAY_PROJ_SCHEME_2D, rays, got, n, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
            for (i = 0; i < n; i++) CHECK(same(&got[i], &want[i]));
            CHECK_STATUS(coray_proj_info(h.arena, h.bytes, &info), CORAY_STATUS_CORRUPT_ARENA);
            /* Errors: a ray off the eye, a bad scheme, another scene, a short stack. */
            {
                CorayRay off = rays[0];
                CorayScene other = ts.view;
                off.org[0] += 0.25f;
                CHECK_STATUS(coray_proj_intersect(copy, h.bytes, &ts.view, 0, &off, got, 1, stack, info.stack_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
                CHECK_STATUS(coray_proj_intersect(copy, h.bytes, &ts.view, 3, rays, got, 1, stack, info.stack_bytes, NULL), CORAY_STATUS_INVALID_PARAMETER);
                other.cone_count--;
                CHECK_STATUS(coray_proj_intersect(copy, h.bytes, &other, 0, rays, got, 1, stack, info.stack_bytes, NULL), CORAY_STATUS_SCENE_MISMATCH);
                CHECK_STATUS(coray_proj_intersect(copy, h.bytes, &ts.view, 0, rays, got, 1, stack, info.stack_bytes - 1, NULL), CORAY_STATUS_ARENA_TOO_SMALL);
            }
            /* A root box that is not its entries' union fails validation. */
            ((float *)((char *)copy + 128))[0] -= 1.0f;
            CHECK_STATUS(coray_proj_validate(copy, h.bytes, &ts.view), CORAY_STATUS_CORRUPT_ARENA);
            free(copy);
            free(stack);
            free(h.arena);
        }

    /* Exact fit and one byte less. */
    {
        CorayProjParams p = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_RSTAR);
        CorayProjRequirements req;
        size_t needed = 0;
        void *a, *sc;
        CHECK_STATUS(coray_proj_requirements(ts.nt + ts.ns + ts.nc, &p, &req), CORAY_STATUS_OK);
        a = arena_alloc(req.proj_bytes);
        sc = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.proj_bytes - 1, sc, req.scratch_bytes, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.proj_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.proj_bytes, sc, req.scratch_bytes - 1, &needed), CORAY_STATUS_ARENA_TOO_SMALL);
        CHECK(needed == req.scratch_bytes);
        CHECK_STATUS(coray_proj_build(&ts.view, &p, &plane, a, req.proj_bytes, sc, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(coray_proj_validate(a, req.proj_bytes, &ts.view), CORAY_STATUS_OK);
        p.criteria = 2;
        CHECK_STATUS(coray_proj_requirements(10, &p, &req), CORAY_STATUS_INVALID_PARAMETER);
        CHECK(coray_proj_params_default(2, 0).struct_size == 0);
        free(a);
        free(sc);
    }

    /* Shadow rays through light planes: inside (cube), outside (one face), directional. */
    {
        CorayLight lights[3] = {{CORAY_LIGHT_POINT, {0.1f, 0.2f, 0.05f}},
                                {CORAY_LIGHT_POINT, {0.4f, 3.5f, 1.0f}},
                                {CORAY_LIGHT_DIRECTIONAL, {-0.3f, -1.0f, -0.2f}}};
        float lo[3] = {-1.1f, -1.1f, -1.1f}, hi[3] = {1.1f, 1.1f, 1.1f};
        uint32_t expect_count[3] = {6, 1, 1}, li;
        for (li = 0; li < 3; li++) {
            CorayProjPlane planes[6];
            uint32_t count = 0, k;
            size_t ns = 0, blocked = 0;
            Proj faces[6];
            CorayProjParams p = coray_proj_params_default(li == 1 ? CORAY_PROJ_CRITERIA_DUMMY : CORAY_PROJ_CRITERIA_2D,
                                                          li == 2 ? CORAY_BVH_RTREE : CORAY_BVH_TDBS);
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
            CHECK_STATUS(coray_kdtree_occluded(kd.arena, kd.bytes, &ts.view, 0, shadow, want_occ, ns, NULL), CORAY_STATUS_OK);
            for (s = CORAY_PROJ_SCHEME_2D; s <= CORAY_PROJ_SCHEME_COMBINATION; s++)
                for (i = 0; i < ns; i++) {
                    uint32_t face = 99;
                    CorayProjInfo info;
                    void *stack;
                    CHECK_STATUS(coray_proj_light_plane_for(&lights[li], &lo, &hi, &shadow[i], &face), CORAY_STATUS_OK);
                    CHECK(face < count);
                    if (face >= count) continue;
                    CHECK_STATUS(coray_proj_info(faces[face].arena, faces[face].bytes, &info), CORAY_STATUS_OK);
                    stack = malloc(info.stack_bytes);
                    CHECK_STATUS(coray_proj_occluded(faces[face].arena, faces[face].bytes, &ts.view, s, &shadow[i], &occ[i], 1, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
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
