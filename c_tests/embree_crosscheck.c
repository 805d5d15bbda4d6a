/* coray against Embree 3 on the same scenes, ray for ray: closest hits of
 * both kd traversals and of the five hierarchies, and any-hit answers. Same hit or miss, same primitive,
 * |dt| <= CORAY_TOL_SAME_T_REL max(1, t). Disagreements that are documented ties (a ray
 * grazing an edge, a silhouette or a rim; two primitives at the same
 * distance) are counted and printed apart. Every other disagreement goes to
 * a referee: both answers' primitives intersected in double precision. Where
 * the referee sides with coray, the case is counted as an Embree error (by
 * geometry: Embree's cone curves are single-precision approximations and
 * miss or misplace hits on thin cones); where it does not, the test fails. */
#include <embree3/rtcore.h>

#include "common.h"

/* Double-precision intersection of one primitive: the referee. Sets
 * *graze when the hit it returns lies within the grazing thresholds (near a
 * triangle edge, at a cone's rim). */
static double ref_t(const TestScene *ts, const CorayRay *r, unsigned geom, unsigned prim, int *graze) {
    double o[3] = {r->org[0], r->org[1], r->org[2]}, d[3] = {r->dir[0], r->dir[1], r->dir[2]};
    double best = INFINITY, roots[2], rim[2] = {1, 1};
    int k, i, n = 0;
    if (geom == CORAY_GEOM_TRIANGLES) {
        const uint32_t *ix = &ts->indices[3 * prim];
        double v0[3], e1[3], e2[3], pv[3], tv[3], qv[3], det, u, v, t;
        for (k = 0; k < 3; k++) {
            v0[k] = ts->vertices[3 * ix[0] + k];
            e1[k] = ts->vertices[3 * ix[1] + k] - v0[k];
            e2[k] = ts->vertices[3 * ix[2] + k] - v0[k];
        }
        pv[0] = d[1] * e2[2] - d[2] * e2[1]; pv[1] = d[2] * e2[0] - d[0] * e2[2]; pv[2] = d[0] * e2[1] - d[1] * e2[0];
        det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (det == 0) return INFINITY;
        for (k = 0; k < 3; k++) tv[k] = o[k] - v0[k];
        u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
        qv[0] = tv[1] * e1[2] - tv[2] * e1[1]; qv[1] = tv[2] * e1[0] - tv[0] * e1[2]; qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
        v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
        t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
        if (u < 0 || v < 0 || u + v > 1) return INFINITY;
        rim[n] = fmin(fmin(u, v), 1 - u - v);
        roots[n++] = t;
    } else if (geom == CORAY_GEOM_SPHERES) {
        const float *sp = &ts->spheres[4 * prim];
        double oc[3], a = 0, b = 0, c = 0, disc;
        for (k = 0; k < 3; k++) {
            oc[k] = o[k] - sp[k];
            a += d[k] * d[k];
            b += oc[k] * d[k];
            c += oc[k] * oc[k];
        }
        c -= (double)sp[3] * sp[3];
        disc = b * b - a * c;
        if (disc < 0) return INFINITY;
        roots[n++] = (-b - sqrt(disc)) / a;
        roots[n++] = (-b + sqrt(disc)) / a;
    } else {
        const float *cn = &ts->cones[8 * prim];
        double w[3], len = 0, q[3], qs = 0, ds = 0, qp[3], dp[3], r0 = cn[3], r1 = cn[7], slope, kk, m, A = 0, B = 0, C = 0, disc;
        for (k = 0; k < 3; k++) {
            w[k] = (double)cn[4 + k] - cn[k];
            len += w[k] * w[k];
        }
        len = sqrt(len);
        for (k = 0; k < 3; k++) {
            w[k] /= len;
            q[k] = o[k] - cn[k];
            qs += q[k] * w[k];
            ds += d[k] * w[k];
        }
        for (k = 0; k < 3; k++) {
            qp[k] = q[k] - qs * w[k];
            dp[k] = d[k] - ds * w[k];
        }
        slope = (r1 - r0) / len;
        kk = r0 + slope * qs;
        m = slope * ds;
        for (k = 0; k < 3; k++) {
            A += dp[k] * dp[k];
            B += qp[k] * dp[k];
            C += qp[k] * qp[k];
        }
        A -= m * m;
        B -= kk * m;
        C -= kk * kk;
        disc = B * B - A * C;
        if (disc < 0 || A == 0) return INFINITY;
        for (i = 0; i < 2; i++) {
            double t = (-B + (i ? 1 : -1) * sqrt(disc)) / A, sv = qs + t * ds;
            if (sv >= 0 && sv <= len && kk + m * t >= 0) {
                rim[n] = fmin(sv / len, 1 - sv / len);
                roots[n++] = t;
            }
        }
    }
    *graze = 0;
    for (i = 0; i < n; i++)
        if (roots[i] >= r->tnear && roots[i] <= r->tfar && roots[i] < best) {
            best = roots[i];
            *graze = rim[i] < 1e-4;
        }
    return best;
}

typedef struct {
    long embree_wrong[3], agree[3], occl_embree_wrong;
    long distinct, compared, hits, ties_same_t, ties_graze, disagreements, occl_compared, occl_graze, occl_disagree;
} Tally;

static RTCScene embree_scene(RTCDevice dev, const TestScene *ts) {
    RTCScene sc = rtcNewScene(dev);
    size_t i;
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
    if (ts->nt) {
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, ts->vertices, 0, 12, ts->nv);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, ts->indices, 0, 12, ts->nt);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, CORAY_GEOM_TRIANGLES);
        rtcReleaseGeometry(g);
    }
    if (ts->ns) {
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, ts->spheres, 0, 16, ts->ns);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, CORAY_GEOM_SPHERES);
        rtcReleaseGeometry(g);
    }
    if (ts->nc) {
        /* Each cone is one linear cone segment between its two end points;
         * both neighbour flags set on every segment remove the caps. */
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_CONE_LINEAR_CURVE);
        unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, 4, ts->nc);
        unsigned char *flags = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_FLAGS, 0, RTC_FORMAT_UCHAR, 1, ts->nc);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, ts->cones, 0, 16, 2 * ts->nc);
        for (i = 0; i < ts->nc; i++) {
            idx[i] = (unsigned)(2 * i);
            flags[i] = RTC_CURVE_FLAG_NEIGHBOR_LEFT | RTC_CURVE_FLAG_NEIGHBOR_RIGHT;
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, CORAY_GEOM_CONES);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(sc);
    return sc;
}

static void embree_intersect(RTCScene sc, const CorayRay *r, CorayHit *h) {
    struct RTCRayHit rh;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rh.ray.org_x = r->org[0]; rh.ray.org_y = r->org[1]; rh.ray.org_z = r->org[2];
    rh.ray.dir_x = r->dir[0]; rh.ray.dir_y = r->dir[1]; rh.ray.dir_z = r->dir[2];
    rh.ray.tnear = r->tnear; rh.ray.tfar = r->tfar; rh.ray.time = 0; rh.ray.mask = 0xFFFFFFFF;
    rh.ray.id = 0; rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(sc, &ctx, &rh);
    h->geom_id = rh.hit.geomID;
    h->prim_id = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? CORAY_INVALID_ID : rh.hit.primID;
    h->t = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
    h->u = rh.hit.u; h->v = rh.hit.v;
    h->ng[0] = rh.hit.Ng_x; h->ng[1] = rh.hit.Ng_y; h->ng[2] = rh.hit.Ng_z;
}

static int embree_occluded(RTCScene sc, const CorayRay *r) {
    struct RTCRay ray;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ray.org_x = r->org[0]; ray.org_y = r->org[1]; ray.org_z = r->org[2];
    ray.dir_x = r->dir[0]; ray.dir_y = r->dir[1]; ray.dir_z = r->dir[2];
    ray.tnear = r->tnear; ray.tfar = r->tfar; ray.time = 0; ray.mask = 0xFFFFFFFF; ray.id = 0; ray.flags = 0;
    rtcOccluded1(sc, &ctx, &ray);
    return ray.tfar == -INFINITY;
}

static float tol(float t) { return (float)CORAY_TOL_SAME_T_REL * (fabsf(t) > 1.0f ? fabsf(t) : 1.0f); }

/* A hit that a rounding error can turn into a miss: near a triangle edge,
 * tangent to a sphere or cone (silhouette), or at a cone's open rim. */
static int grazing(const CorayRay *r, const CorayHit *h) {
    float dl, nl, c;
    if (h->geom_id == CORAY_GEOM_TRIANGLES) {
        float w = 1.0f - h->u - h->v, m = h->u < h->v ? h->u : h->v;
        if (w < m) m = w;
        if (m < (float)CORAY_TOL_EDGE_BARY) return 1;
    }
    if (h->geom_id == CORAY_GEOM_CONES && (h->u < (float)CORAY_TOL_RIM_U || h->u > 1.0f - (float)CORAY_TOL_RIM_U)) return 1;
    dl = sqrtf(r->dir[0] * r->dir[0] + r->dir[1] * r->dir[1] + r->dir[2] * r->dir[2]);
    nl = sqrtf(h->ng[0] * h->ng[0] + h->ng[1] * h->ng[1] + h->ng[2] * h->ng[2]);
    c = (r->dir[0] * h->ng[0] + r->dir[1] * h->ng[1] + r->dir[2] * h->ng[2]) / (dl * nl);
    return fabsf(c) < (float)CORAY_TOL_GRAZE_COS || h->t < r->tnear + tol(r->tnear);
}

enum { SAME, TIE_T, TIE_GRAZE, EMBREE_WRONG, DISAGREE };

/* Compares closest hits ray by ray; writes each ray's class to `cls`. */
static void compare(const char *what, const TestScene *ts, const CorayRay *rays, const CorayHit *mine,
                    const CorayHit *theirs, size_t n, Tally *tl, unsigned char *cls) {
    size_t i;
    int printed = 0;
    for (i = 0; i < n; i++) {
        const CorayHit *a = &mine[i], *b = &theirs[i];
        int ha = a->geom_id != CORAY_INVALID_ID, hb = b->geom_id != CORAY_INVALID_ID;
        const char *kind = NULL;
        tl->compared++;
        tl->hits += ha;
        cls[i] = SAME;
        if (!ha && !hb) continue;
        if (ha && hb && a->geom_id == b->geom_id && a->prim_id == b->prim_id && fabsf(a->t - b->t) <= tol(a->t)) {
            tl->agree[a->geom_id]++;
            continue;
        }
        if (ha && hb && fabsf(a->t - b->t) <= tol(a->t)) {
            tl->ties_same_t++;
            cls[i] = TIE_T;
            kind = "tie: same distance";
        } else if ((ha && (!hb || a->t < b->t) && grazing(&rays[i], a)) ||
                   (hb && (!ha || b->t < a->t) && grazing(&rays[i], b))) {
            tl->ties_graze++;
            cls[i] = TIE_GRAZE;
            kind = "tie: grazing";
        } else {
            int ga = 0, gb = 0;
            double ta = ha ? ref_t(ts, &rays[i], a->geom_id, a->prim_id, &ga) : INFINITY;
            double tb = hb ? ref_t(ts, &rays[i], b->geom_id, b->prim_id, &gb) : INFINITY;
            double t_ref = ta < tb ? ta : tb;
            int ref_grazes = ta < tb ? ga : gb;
            int coray_right = isinf(t_ref) ? !ha : (ha && fabs(a->t - t_ref) <= tol((float)t_ref));
            int embree_right = isinf(t_ref) ? !hb : (hb && fabs(b->t - t_ref) <= tol((float)t_ref));
            if (!coray_right && ref_grazes) {
                tl->ties_graze++;
                cls[i] = TIE_GRAZE;
                kind = "tie: grazing (the double-precision hit lies on an edge or rim)";
            } else if (coray_right && embree_right) {
                tl->ties_same_t++;
                cls[i] = TIE_T;
                kind = "tie: both within tolerance of the double-precision answer";
            } else if (coray_right && !embree_right) {
                tl->embree_wrong[ha ? a->geom_id : b->geom_id]++;
                cls[i] = EMBREE_WRONG;
                kind = "Embree error (double-precision referee agrees with coray)";
            } else {
                tl->disagreements++;
                cls[i] = DISAGREE;
                kind = "DISAGREEMENT";
                printf("    referee: coray's primitive at t=%.9g, Embree's at t=%.9g\n", ta, tb);
            }
        }
        if (printed < 6 || kind[0] == 'D') {
            if (printed < 40)
                printf("  %s %s ray %zu org (%g %g %g) dir (%g %g %g) [%g, %g]: coray %u/%u t=%.9g u=%g | embree %u/%u t=%.9g u=%g\n",
                       what, kind, i, (double)rays[i].org[0], (double)rays[i].org[1], (double)rays[i].org[2],
                       (double)rays[i].dir[0], (double)rays[i].dir[1], (double)rays[i].dir[2], (double)rays[i].tnear,
                       (double)rays[i].tfar, a->geom_id, a->prim_id, (double)a->t, (double)a->u, b->geom_id,
                       b->prim_id, (double)b->t, (double)b->u);
            printed++;
        }
    }
}

/* Any-hit answers against Embree's (`eocc`), given each ray's closest-hit class. */
static void compare_occluded(const char *what, const CorayRay *rays, const CorayHit *mine, const CorayHit *theirs,
                             const uint8_t *occ, const uint8_t *eocc, const unsigned char *cls, size_t n, Tally *tl) {
    size_t i;
    for (i = 0; i < n; i++) {
        tl->occl_compared++;
        CHECK(occ[i] == (mine[i].geom_id != CORAY_INVALID_ID));
        if (eocc[i] != occ[i]) {
            /* Any-hit may differ only where closest hit had a tie or an Embree error. */
            const CorayHit *h = mine[i].geom_id != CORAY_INVALID_ID ? &mine[i] : &theirs[i];
            if (cls[i] == TIE_T || cls[i] == TIE_GRAZE || grazing(&rays[i], h)) tl->occl_graze++;
            else if (cls[i] == EMBREE_WRONG) tl->occl_embree_wrong++;
            else {
                tl->occl_disagree++;
                if (tl->occl_disagree < 20) printf("  %s OCCLUDED DISAGREEMENT ray %zu: coray %d embree %d\n", what, i, occ[i], eocc[i]);
            }
        }
    }
}

static void check_scene(const char *name, TestScene *ts, RTCDevice dev, int cam_res, size_t n_random, int unit_dirs,
                        Tally *tl) {
    RTCScene sc = embree_scene(dev, ts);
    uint32_t preset, trav, builder;
    size_t n_cam = (size_t)cam_res * (size_t)cam_res, n_total, i, n_surf = 0;
    CorayRay *rays;
    CorayHit *mine, *theirs;
    uint8_t *occ, *eocc, *cls;
    float eye[3] = {0.3f, 0.9f, 2.8f};
    rays = malloc(sizeof(CorayRay) * (n_cam * 2 + n_random));
    mine = malloc(sizeof(CorayHit) * (n_cam * 2 + n_random));
    theirs = malloc(sizeof(CorayHit) * (n_cam * 2 + n_random));
    occ = malloc(n_cam * 2 + n_random);
    eocc = malloc(n_cam * 2 + n_random);
    cls = malloc(n_cam * 2 + n_random);
    rays_camera(rays, cam_res, cam_res, eye);
    rays_random(rays + n_cam, n_random, 1.0f);
    /* Rays from surfaces: from Embree's camera hits, in random directions. */
    for (i = 0; i < n_cam; i++) {
        CorayHit h;
        embree_intersect(sc, &rays[i], &h);
        if (h.geom_id != CORAY_INVALID_ID) {
            CorayRay *s = &rays[n_cam + n_random + n_surf++];
            int k;
            float d[3];
            rng_unit(d);
            for (k = 0; k < 3; k++) {
                s->org[k] = rays[i].org[k] + h.t * rays[i].dir[k];
                s->dir[k] = d[k];
            }
            s->tnear = 1e-3f;
            s->tfar = INFINITY;
        }
    }
    n_total = n_cam + n_random + n_surf;
    if (unit_dirs)
        for (i = 0; i < n_total; i++) {
            float l = sqrtf(rays[i].dir[0] * rays[i].dir[0] + rays[i].dir[1] * rays[i].dir[1] + rays[i].dir[2] * rays[i].dir[2]);
            rays[i].dir[0] /= l;
            rays[i].dir[1] /= l;
            rays[i].dir[2] /= l;
            rays[i].tfar *= l;
            rays[i].tnear *= l;
        }
    tl->distinct += (long)n_total;
    for (i = 0; i < n_total; i++) {
        embree_intersect(sc, &rays[i], &theirs[i]);
        eocc[i] = (uint8_t)embree_occluded(sc, &rays[i]);
    }
    for (preset = 0; preset < 2; preset++) {
        /* With ropes: both traversals walk their own way on both trees. */
        Tree tree = tree_build_roped(&ts->view, preset);
        KdStack kst;
        for (trav = 0; trav < 2; trav++) {
            char what[64];
            snprintf(what, sizeof what, "%s/%s/%s/%s", name, unit_dirs ? "unit" : "raw", preset ? "paper" : "auto",
                     trav ? "ropes" : "hier");
            CHECK_STATUS(coray_kdtree_intersect(&tree.tree, trav, rays, mine, n_total, &kst, sizeof kst, NULL), CORAY_STATUS_OK);
            compare(what, ts, rays, mine, theirs, n_total, tl, cls);
            CHECK_STATUS(coray_kdtree_occluded(&tree.tree, trav, rays, occ, n_total, &kst, sizeof kst, NULL), CORAY_STATUS_OK);
            compare_occluded(what, rays, mine, theirs, occ, eocc, cls, n_total, tl);
        }
        free(tree.arena);
    }
    /* Hierarchies with unit directions only: unnormalised ones exercise the
     * same primitive tests (checked through the kd-trees) and Embree's cone
     * curves, and would double the run. */
    for (builder = CORAY_BVH_BUILDER_TDBS; unit_dirs && builder <= CORAY_BVH_BUILDER_NN_CHAIN; builder++) {
        static const char *bvh_names[] = {"tdbs", "tdbs-sah", "nn", "rtree", "rstar", "nn-chain"};
        CorayBvhParams p = coray_bvh_params_default(builder);
        CorayRequirements req = requirements0();
        CorayBvhInfo info;
        CorayBvh h;
        void *arena, *scratch, *stack;
        char what[64];
        /* The thesis' quadratic matching takes seconds on the 17000-object
         * scene; its joins are the chain's (tests/bvh_oracle.rs), so it is
         * cross-checked on the smaller scene only. */
        if (builder == CORAY_BVH_BUILDER_NN && ts->nt + ts->ns + ts->nc > 5000) continue;
        snprintf(what, sizeof what, "%s/%s/%s", name, unit_dirs ? "unit" : "raw", bvh_names[builder]);
        CHECK_STATUS(coray_bvh_requirements(ts->nt + ts->ns + ts->nc, &p, &req), CORAY_STATUS_OK);
        arena = arena_alloc(req.arena_bytes);
        scratch = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_bvh_build(&ts->view, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        free(scratch);
        CHECK_STATUS(coray_bvh_open(arena, req.arena_bytes, &ts->view, &h), CORAY_STATUS_OK);
        memset(&info, 0, sizeof info);
        info.struct_size = sizeof info;
        CHECK_STATUS(coray_bvh_info(&h, &info), CORAY_STATUS_OK);
        stack = arena_alloc(info.stack_bytes);
        CHECK_STATUS(coray_bvh_intersect(&h, rays, mine, n_total, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
        compare(what, ts, rays, mine, theirs, n_total, tl, cls);
        CHECK_STATUS(coray_bvh_occluded(&h, rays, occ, n_total, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
        compare_occluded(what, rays, mine, theirs, occ, eocc, cls, n_total, tl);
        free(stack);
        free(arena);
    }
    /* The wide hierarchy, unit directions as the hierarchies; its one-ray
     * call against its array call on the first rays. */
    if (unit_dirs) {
        CorayWideParams p = coray_wide_params_default();
        CorayRequirements req = requirements0();
        CorayWideInfo info = coray_wide_info_default();
        CorayShape shape = coray_shape_default();
        CorayWide h;
        void *arena, *scratch, *stack;
        char what[64];
        snprintf(what, sizeof what, "%s/unit/wide", name);
        CHECK_STATUS(coray_wide_requirements(ts->nt + ts->ns + ts->nc, &p, &req), CORAY_STATUS_OK);
        arena = arena_alloc(req.arena_bytes);
        scratch = arena_alloc(req.scratch_bytes);
        CHECK_STATUS(coray_wide_build(&ts->view, &p, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
        free(scratch);
        CHECK_STATUS(coray_wide_open(arena, req.arena_bytes, &ts->view, &h), CORAY_STATUS_OK);
        CHECK_STATUS(coray_wide_info(&h, &info), CORAY_STATUS_OK);
        CHECK_STATUS(coray_wide_validate(&h, &shape), CORAY_STATUS_OK);
        CHECK(shape.node_count == info.node_count && shape.ref_count == info.ref_count);
        CHECK(info.stack_bytes <= req.stack_bytes && info.arena_bytes_used < req.arena_bytes);
        stack = arena_alloc(info.stack_bytes);
        CHECK_STATUS(coray_wide_intersect(&h, rays, mine, n_total, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
        compare(what, ts, rays, mine, theirs, n_total, tl, cls);
        for (i = 0; i < n_total && i < 2000; i++) {
            CorayHit one;
            uint8_t o;
            CHECK_STATUS(coray_wide_intersect1(&h, &rays[i], &one, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
            CHECK(one.geom_id == mine[i].geom_id && one.prim_id == mine[i].prim_id && memcmp(&one.t, &mine[i].t, sizeof one.t) == 0);
            CHECK_STATUS(coray_wide_occluded1(&h, &rays[i], &o, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
            CHECK(o == (mine[i].geom_id != CORAY_INVALID_ID));
        }
        CHECK_STATUS(coray_wide_occluded(&h, rays, occ, n_total, stack, info.stack_bytes, NULL), CORAY_STATUS_OK);
        compare_occluded(what, rays, mine, theirs, occ, eocc, cls, n_total, tl);
        free(stack);
        free(arena);
    }
    printf("%s, %s directions: %zu rays (%zu camera, %zu random, %zu from surfaces) x 4 kd variants%s\n", name,
           unit_dirs ? "unit" : "unnormalised", n_total, n_cam, n_random, n_surf,
           unit_dirs ? ", 6 hierarchies and the wide one" : "");
    rtcReleaseScene(sc);
    free(rays);
    free(mine);
    free(theirs);
    free(occ);
    free(eocc);
    free(cls);
}

static void report(const char *mode, const Tally *tl) {
    printf("[%s] %ld distinct rays, each traced by coray's kd-trees (auto and paper, "
           "hierarchical and ropes) and, with unit directions, its hierarchies (TDBS, TDBS-SAH, NN on the smaller "
           "scene, NN chain, R-tree, R*-tree, wide)\n", mode,
           tl->distinct);
    printf("[%s] closest hit: %ld rays compared, %ld hits, %ld ties at the same distance, %ld grazing ties, %ld disagreements\n",
           mode, tl->compared, tl->hits, tl->ties_same_t, tl->ties_graze, tl->disagreements);
    printf("[%s] closest hit, agreeing hits: %ld triangles, %ld spheres, %ld cones\n", mode, tl->agree[0], tl->agree[1],
           tl->agree[2]);
    printf("[%s] closest hit, Embree errors refereed in double precision (by the true hit's geometry): %ld triangles, "
           "%ld spheres, %ld cones\n", mode, tl->embree_wrong[0], tl->embree_wrong[1], tl->embree_wrong[2]);
    printf("[%s] any hit: %ld rays compared, %ld ties, %ld Embree errors, %ld disagreements\n", mode, tl->occl_compared,
           tl->occl_graze, tl->occl_embree_wrong, tl->occl_disagree);
}

int main(void) {
    RTCDevice dev = rtcNewDevice(NULL);
    Tally unit, raw;
    TestScene a, b;
    int mode;
    memset(&unit, 0, sizeof unit);
    memset(&raw, 0, sizeof raw);
    CHECK(dev != NULL);
    rng_state = 15;
    a = scene_random(12000, 2500, 2500, 1.0f);
    rng_state = 16;
    b = scene_random(4000, 0, 0, 1.0f);
    for (mode = 1; mode >= 0; mode--) {
        Tally *tl = mode ? &unit : &raw;
        rng_state = 17;
        check_scene("mixed", &a, dev, 512, 420000, mode, tl);
        check_scene("triangles", &b, dev, 256, 120000, mode, tl);
    }
    report("unit directions", &unit);
    report("unnormalised directions", &raw);
    /* With unit directions Embree and coray must agree everywhere but on
     * documented ties. Embree 3.13's linear cone curves assume a unit ray
     * direction; with other directions its cone hits are wrong, which the
     * referee shows; coray must still agree with the referee on every ray. */
    CHECK(unit.distinct >= 1000000);
    CHECK(unit.hits > unit.compared / 10);
    CHECK(unit.disagreements == 0 && unit.occl_disagree == 0);
    CHECK(unit.embree_wrong[0] + unit.embree_wrong[1] + unit.embree_wrong[2] == 0);
    CHECK(raw.disagreements == 0 && raw.occl_disagree == 0);
    scene_free(&a);
    scene_free(&b);
    rtcReleaseDevice(dev);
    return finish("embree_crosscheck");
}
