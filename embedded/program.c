/* The embedded test program: the same source runs on a Cortex-M4 (under
 * QEMU, startup.c) and on the host (host.c); both print the same `check`
 * lines, which scripts/embedded.sh compares. Everything lives in static
 * arenas: no allocator, no libm, no stdio (the platform prints a string).
 *
 * Per scene (two SPD scenes built in by `coray export`): a kd-tree with
 * both presets, validated; a 64 x 64 image cast hierarchically, by ropes,
 * by SLCTS-2D and by HLCTS-2D (instructions counted where the board can); rays made here traced one by one and as an array by
 * every traversal (packets, in this build without the packet kernels,
 * ray by ray: the same hits); shadow rays from every hit to every light. With
 * EVERY_STRUCTURE also a TDBS hierarchy, an R-tree grown by inserts and
 * shrunk by deletes, and a projection hierarchy on the camera's plane.
 * A check line carries a 64-bit FNV-1a digest of (geometry, primitive,
 * t bits) per ray, or of the shape a validation found. */
#include <stddef.h>
#include <stdint.h>

#include "coray.h"
#include "program.h"
#include "scene_mount.h"
#include "scene_rings.h"

#define SIDE 64
#define PIXELS (SIDE * SIDE)
#define ARENA_BYTES (1280u * 1024u)
#define SCRATCH_BYTES (1024u * 1024u)
#define MAX_LIGHTS 2
/* Records per traversal history in the LCTS casts: HLCTS-2D's scratch
   grows with it (at 64 x 64 pixels about 29 KiB a record), and these
   trees' rays record far fewer. */
#define HISTORY_CAPACITY 32

static _Alignas(16) uint8_t arena[ARENA_BYTES];
static _Alignas(16) uint8_t scratch[SCRATCH_BYTES];
static _Alignas(16) uint8_t stack[8192];
static CorayRay rays[PIXELS];
static CorayHit hits[PIXELS];
static CorayRay shadow[PIXELS * MAX_LIGHTS];
static uint8_t occluded[PIXELS * MAX_LIGHTS];

static int failures;

/* ---- printing without stdio ---- */

static void out_u64(uint64_t v, int hex) {
    char buf[24];
    int i = 23;
    buf[i] = 0;
    do {
        unsigned d = (unsigned)(hex ? v & 15u : v % 10u);
        buf[--i] = (char)(d < 10 ? '0' + d : 'a' + d - 10);
        v = hex ? v >> 4 : v / 10u;
    } while (v && i > 0);
    platform_print(buf + i);
}

static void line(const char *kind, const char *scene, const char *what, uint64_t v, int hex) {
    platform_print(kind);
    platform_print(" ");
    platform_print(scene);
    platform_print(" ");
    platform_print(what);
    platform_print(hex ? " 0x" : " ");
    out_u64(v, hex);
    platform_print("\n");
}

static void check(const char *scene, const char *what, uint64_t digest) {
    line("check", scene, what, digest, 1);
}

static void info(const char *scene, const char *what, uint64_t v) {
    line("info", scene, what, v, 0);
}

static void expect(int ok, const char *scene, const char *what, CorayStatus s) {
    if (!ok) {
        failures++;
        line("FAIL", scene, what, (uint64_t)s, 0);
    }
}

/* ---- digests ---- */

typedef struct {
    uint64_t h;
} Digest;

static void mix(Digest *d, uint32_t v) {
    for (int i = 0; i < 4; i++) {
        d->h ^= (v >> (8 * i)) & 0xffu;
        d->h *= 0x100000001b3ull;
    }
}

static uint32_t bits(float f) {
    union {
        float f;
        uint32_t u;
    } x = {f};
    return x.u;
}

static uint64_t digest_hits(const CorayHit *h, size_t n) {
    Digest d = {0xcbf29ce484222325ull};
    for (size_t i = 0; i < n; i++) {
        mix(&d, h[i].geom_id);
        mix(&d, h[i].prim_id);
        mix(&d, bits(h[i].t));
    }
    return d.h;
}

static uint64_t digest_bytes(const uint8_t *b, size_t n) {
    Digest d = {0xcbf29ce484222325ull};
    for (size_t i = 0; i < n; i++) mix(&d, b[i]);
    return d.h;
}

static uint64_t digest_shape(const CorayShape *s) {
    Digest d = {0xcbf29ce484222325ull};
    mix(&d, s->node_count);
    mix(&d, s->leaf_count);
    mix(&d, s->empty_leaf_count);
    mix(&d, s->ref_count);
    mix(&d, s->depth);
    return d.h;
}

/* ---- one scene ---- */

typedef struct {
    const char *name;
    CorayScene scene;
    const float *from, *at, *up, *lights;
    uint32_t light_count;
    float tan_half;
} BoardScene;

static void sub(float o[3], const float a[3], const float b[3]) {
    for (int i = 0; i < 3; i++) o[i] = a[i] - b[i];
}

static void cross(float o[3], const float a[3], const float b[3]) {
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* Newton's square root from +, *, /: the same bits wherever IEEE single
 * arithmetic is exact per operation (no libm, no fused multiply-add). */
static float root(float x) {
    if (!(x > 0.0f)) return 0.0f;
    float r = x > 1.0f ? x : 1.0f;
    for (int i = 0; i < 60; i++) r = 0.5f * (r + x / r);
    return r;
}

static void normalize(float v[3]) {
    float l = root(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0.0f)
        for (int i = 0; i < 3; i++) v[i] /= l;
}

/* The camera's ray through the centre of each pixel, row 0 on top. */
static void primary_rays(const BoardScene *s) {
    float f[3], r[3], u[3];
    sub(f, s->at, s->from);
    normalize(f);
    cross(r, f, s->up);
    normalize(r);
    cross(u, r, f);
    for (int y = 0; y < SIDE; y++) {
        for (int x = 0; x < SIDE; x++) {
            float sx = (2.0f * (x + 0.5f) / SIDE - 1.0f) * s->tan_half;
            float sy = (1.0f - 2.0f * (y + 0.5f) / SIDE) * s->tan_half;
            CorayRay *ray = &rays[y * SIDE + x];
            for (int i = 0; i < 3; i++) {
                ray->org[i] = s->from[i];
                ray->dir[i] = f[i] + r[i] * sx + u[i] * sy;
            }
            ray->tnear = 0.0f;
            ray->tfar = 1e30f;
        }
    }
}

/* From every hit towards every light, the segment short of both ends. */
static size_t shadow_rays(const BoardScene *s) {
    size_t n = 0;
    for (size_t i = 0; i < PIXELS; i++) {
        if (hits[i].geom_id == CORAY_INVALID_ID) continue;
        for (uint32_t l = 0; l < s->light_count; l++) {
            CorayRay *sr = &shadow[n++];
            for (int k = 0; k < 3; k++) {
                sr->org[k] = rays[i].org[k] + rays[i].dir[k] * hits[i].t;
                sr->dir[k] = s->lights[3 * l + k] - sr->org[k];
            }
            sr->tnear = 1e-3f;
            sr->tfar = 1.0f - 1e-3f;
        }
    }
    return n;
}

static CorayCamera camera_of(const BoardScene *s) {
    CorayCamera c = coray_camera_default();
    for (int i = 0; i < 3; i++) {
        c.from[i] = s->from[i];
        c.at[i] = s->at[i];
        c.up[i] = s->up[i];
    }
    c.angle_deg = 45.0f;
    c.width = SIDE;
    c.height = SIDE;
    return c;
}

static void kd_tree(const BoardScene *s, CorayKdPreset preset, const char *tag) {
    char what[48];
    const char *n = s->name;
    CorayKdParams params = coray_kdtree_params_default(preset);
    CorayRequirements req = coray_requirements_default();
    CorayStatus st = coray_kdtree_requirements(
        s->scene.triangle_count + s->scene.sphere_count + s->scene.cone_count, &params, &req);
    expect(st == CORAY_STATUS_OK, n, "kd requirements", st);
    info(n, tag, req.arena_bytes);
    /* Less room than the ideal arena only truncates the tree (and changes
       nothing here: both platforms get the same arena). */
    size_t arena_bytes = req.arena_bytes < ARENA_BYTES ? req.arena_bytes : ARENA_BYTES;
    size_t scratch_bytes = req.scratch_bytes < SCRATCH_BYTES ? req.scratch_bytes : SCRATCH_BYTES;
    st = coray_kdtree_build(&s->scene, &params, arena, arena_bytes, scratch, scratch_bytes, NULL);
    expect(st == CORAY_STATUS_OK, n, "kd build", st);
    platform_phase("kd build");
    CorayKdTree tree;
    st = coray_kdtree_open(arena, arena_bytes, &s->scene, &tree);
    expect(st == CORAY_STATUS_OK, n, "kd open", st);
    CorayShape shape = coray_shape_default();
    st = coray_kdtree_validate(&tree, NULL, 0, &shape);
    expect(st == CORAY_STATUS_OK, n, "kd validate", st);
    platform_phase("kd validate");
    CorayKdTreeInfo ki = coray_kdtree_info_default();
    coray_kdtree_info(&tree, &ki);
    info(n, "kd arena bytes used", ki.arena_bytes_used);
    info(n, "kd nodes", shape.node_count);
    check(n, tag, digest_shape(&shape));

    /* Images cast by coray's own camera rays: hierarchical, ropes, SLCTS-2D
       and HLCTS-2D (all but the first walk ropes: a tree without them
       refuses with NO_ROPES). Where the platform counts instructions, a
       count line gives each cast's (camera rays included). */
    CorayCamera cam = camera_of(s);
    static const struct {
        CorayCastScheme scheme;
        const char *name;
    } casts[] = {{CORAY_CAST_HIERARCHICAL, "cast hierarchical"},
                 {CORAY_CAST_ROPES, "cast ropes"},
                 {CORAY_CAST_SLCTS_2D, "cast slcts-2d"},
                 {CORAY_CAST_HLCTS_2D, "cast hlcts-2d"}};
    for (size_t c = 0; c < sizeof casts / sizeof casts[0]; c++) {
        CorayCastParams cp = coray_cast_params_default();
        cp.scheme = casts[c].scheme;
        cp.history_capacity = HISTORY_CAPACITY;
        CorayRequirements creq = coray_requirements_default();
        st = coray_kdtree_cast_requirements(&cam, &cp, &creq);
        expect(st == CORAY_STATUS_OK, n, "cast requirements", st);
        expect(creq.scratch_bytes <= SCRATCH_BYTES && creq.stack_bytes <= sizeof stack, n,
               "cast requirements", st);
        uint64_t before = platform_instructions();
        st = coray_kdtree_cast_image(&tree, &cam, &cp, scratch, SCRATCH_BYTES, stack, sizeof stack,
                                     hits, NULL);
        uint64_t after = platform_instructions();
        if (params.omit_ropes && casts[c].scheme != CORAY_CAST_HIERARCHICAL) {
            expect(st == CORAY_STATUS_NO_ROPES, n, casts[c].name, st);
            continue;
        }
        expect(st == CORAY_STATUS_OK, n, casts[c].name, st);
        const char *p = tag;
        size_t k = 0;
        while (*p && k < 20) what[k++] = *p++;
        what[k++] = ' ';
        for (p = casts[c].name; *p && k < sizeof what - 1; ) what[k++] = *p++;
        what[k] = 0;
        check(n, what, digest_hits(hits, PIXELS));
        if (before != UINT64_MAX) line("count", n, what, after - before, 0);
    }
    platform_phase("kd casts");

    /* Rays made here: both traversals, as an array and one by one. */
    primary_rays(s);
    static const struct {
        CorayTraversal t;
        const char *name;
    } travs[] = {{CORAY_TRAVERSAL_ROPES, "ropes"},
                 {CORAY_TRAVERSAL_HIERARCHICAL, "hierarchical"},
                 {CORAY_TRAVERSAL_PACKETS, "packets"}};
    uint64_t first = 0;
    for (size_t t = 0; t < 3; t++) {
        st = coray_kdtree_intersect(&tree, travs[t].t, rays, hits, PIXELS, stack, sizeof stack, NULL);
        expect(st == CORAY_STATUS_OK, n, "kd intersect", st);
        uint64_t d = digest_hits(hits, PIXELS);
        if (t == 0) first = d;
        expect(d == first, n, "traversals disagree", 0);
        for (size_t i = 0; i < PIXELS; i += 7) {
            CorayHit one;
            st = coray_kdtree_intersect1(&tree, travs[t].t, &rays[i], &one, stack, sizeof stack, NULL);
            expect(st == CORAY_STATUS_OK && bits(one.t) == bits(hits[i].t) &&
                       one.prim_id == hits[i].prim_id,
                   n, "intersect1 differs from the array call", st);
        }
        /* A tracer (the one-ray calls a renderer makes): the same hits. */
        CorayTracer tracer;
        st = coray_kdtree_tracer(&tree, travs[t].t, stack, sizeof stack, &tracer);
        expect(st == CORAY_STATUS_OK, n, "kd tracer", st);
        for (size_t i = 3; i < PIXELS; i += 7) {
            CorayHit one;
            st = coray_kdtree_tracer_intersect1(&tracer, &rays[i], &one);
            expect(st == CORAY_STATUS_OK && bits(one.t) == bits(hits[i].t) &&
                       one.prim_id == hits[i].prim_id,
                   n, "the tracer differs from the array call", st);
        }
    }
    check(n, "primary rays", first);
    size_t ns = shadow_rays(s);
    info(n, "shadow rays", ns);
    uint64_t occ_first = 0;
    for (size_t t = 0; t < 3; t++) {
        st = coray_kdtree_occluded(&tree, travs[t].t, shadow, occluded, ns, stack, sizeof stack, NULL);
        expect(st == CORAY_STATUS_OK, n, "kd occluded", st);
        uint64_t d = digest_bytes(occluded, ns);
        if (t == 0) occ_first = d;
        expect(d == occ_first, n, "shadow traversals disagree", 0);
    }
    check(n, "shadow rays", occ_first);
    platform_phase("kd traversals");
}

#ifdef EVERY_STRUCTURE
static void hierarchies(const BoardScene *s) {
    const char *n = s->name;
    size_t prims = s->scene.triangle_count + s->scene.sphere_count + s->scene.cone_count;
    CorayStatus st;
    CorayShape shape = coray_shape_default();
    CorayRequirements req = coray_requirements_default();
    CorayBvh bvh;

    /* TDBS over the scene. */
    CorayBvhParams tdbs = coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS);
    st = coray_bvh_requirements(prims, &tdbs, &req);
    expect(st == CORAY_STATUS_OK && req.arena_bytes <= ARENA_BYTES && req.scratch_bytes <= SCRATCH_BYTES,
           n, "tdbs requirements", st);
    st = coray_bvh_build(&s->scene, &tdbs, arena, req.arena_bytes, scratch, SCRATCH_BYTES, NULL);
    expect(st == CORAY_STATUS_OK, n, "tdbs build", st);
    coray_bvh_open(arena, req.arena_bytes, &s->scene, &bvh);
    st = coray_bvh_validate(&bvh, stack, sizeof stack, &shape);
    expect(st == CORAY_STATUS_OK, n, "tdbs validate", st);
    check(n, "tdbs shape", digest_shape(&shape));
    platform_phase("tdbs build and validate");
    st = coray_bvh_intersect(&bvh, rays, hits, PIXELS, stack, sizeof stack, NULL);
    expect(st == CORAY_STATUS_OK, n, "tdbs intersect", st);
    check(n, "primary rays", digest_hits(hits, PIXELS));

    /* An R*-tree that starts empty, takes every primitive by insert, then
       loses every third one by delete. */
    CorayBvhParams rt = coray_bvh_params_default(CORAY_BVH_BUILDER_RSTAR);
    rt.start_empty = 1;
    st = coray_bvh_requirements(prims, &rt, &req);
    expect(st == CORAY_STATUS_OK && req.arena_bytes <= ARENA_BYTES, n, "rtree requirements", st);
    st = coray_bvh_build(&s->scene, &rt, arena, req.arena_bytes, scratch, SCRATCH_BYTES, NULL);
    expect(st == CORAY_STATUS_OK, n, "rtree build", st);
    static const struct {
        CorayGeomId g;
        size_t count;
    } geoms[3] = {{CORAY_GEOM_TRIANGLES, 0}, {CORAY_GEOM_SPHERES, 0}, {CORAY_GEOM_CONES, 0}};
    size_t counts[3] = {s->scene.triangle_count, s->scene.sphere_count, s->scene.cone_count};
    for (int g = 0; g < 3; g++)
        for (uint32_t i = 0; i < counts[g]; i++) {
            st = coray_bvh_insert(arena, req.arena_bytes, &s->scene, geoms[g].g, i);
            expect(st == CORAY_STATUS_OK, n, "rtree insert", st);
        }
    uint32_t removed = 0;
    for (int g = 0; g < 3; g++)
        for (uint32_t i = 0; i < counts[g]; i += 3) {
            uint8_t gone = 0;
            st = coray_bvh_delete(arena, req.arena_bytes, &s->scene, geoms[g].g, i, scratch,
                                  SCRATCH_BYTES, &gone);
            expect(st == CORAY_STATUS_OK && gone, n, "rtree delete", st);
            removed += gone;
        }
    info(n, "rtree deleted", removed);
    coray_bvh_open(arena, req.arena_bytes, &s->scene, &bvh);
    CorayBvhInfo bi = coray_bvh_info_default();
    coray_bvh_info(&bvh, &bi);
    expect(bi.ref_count + removed == prims, n, "rtree count", 0);
    expect(bi.stack_bytes <= sizeof stack, n, "rtree stack", 0);
    st = coray_bvh_validate(&bvh, stack, sizeof stack, &shape);
    expect(st == CORAY_STATUS_OK, n, "rtree validate", st);
    check(n, "rtree shape", digest_shape(&shape));
    platform_phase("rtree inserts, deletes, validate");
    st = coray_bvh_intersect(&bvh, rays, hits, PIXELS, stack, sizeof stack, NULL);
    expect(st == CORAY_STATUS_OK, n, "rtree intersect", st);
    check(n, "rtree primary rays", digest_hits(hits, PIXELS));

    /* A projection hierarchy on the camera's plane, 2D criteria. */
    CorayCamera cam = camera_of(s);
    CorayProjPlane plane = coray_proj_plane_default();
    st = coray_proj_camera_plane(&cam, &plane);
    expect(st == CORAY_STATUS_OK, n, "camera plane", st);
    CorayProjParams pp = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_BUILDER_TDBS);
    st = coray_proj_requirements(prims, &pp, &req);
    expect(st == CORAY_STATUS_OK && req.arena_bytes <= ARENA_BYTES, n, "proj requirements", st);
    st = coray_proj_build(&s->scene, &pp, &plane, arena, req.arena_bytes, scratch, SCRATCH_BYTES, NULL);
    expect(st == CORAY_STATUS_OK, n, "proj build", st);
    CorayProj proj;
    coray_proj_open(arena, req.arena_bytes, &s->scene, &proj);
    st = coray_proj_validate(&proj, stack, sizeof stack, &shape);
    expect(st == CORAY_STATUS_OK, n, "proj validate", st);
    st = coray_proj_intersect(&proj, CORAY_PROJ_SCHEME_2D, rays, hits, PIXELS, stack, sizeof stack, NULL);
    expect(st == CORAY_STATUS_OK, n, "proj intersect", st);
    check(n, "primary rays", digest_hits(hits, PIXELS));
    platform_phase("bvh and proj traces, proj build");
}
#endif

/* Layout arithmetic with counts near the limits: the requirements either
   give sizes that hold at least a byte per primitive (the ideal arena no
   smaller than the minimum; kd-trees cap it at what 32-bit offsets reach)
   or refuse with a status; on a 32-bit target they must refuse what
   size_t cannot count, never wrap. Platform-dependent, so
   info lines; a wrap fails the program. */
static void limit(const char *what, size_t count, CorayStatus st, const CorayRequirements *req) {
    int wrapped = st == CORAY_STATUS_OK &&
                  (req->arena_min_bytes < count || req->arena_bytes < req->arena_min_bytes);
    expect(!wrapped && st != CORAY_STATUS_INTERNAL_ERROR, "limits", what, st);
    if (st == CORAY_STATUS_OK) {
        line("info limits", what, "min bytes", req->arena_min_bytes, 0);
        line("info limits", what, "bytes", req->arena_bytes, 0);
    } else {
        line("info limits", what, "refused, status", (uint64_t)st, 0);
    }
}

static void limits(void) {
    static const size_t counts[] = {(size_t)1 << 20, (size_t)1 << 24, (size_t)1 << 26,
                                    (size_t)1 << 30, SIZE_MAX / 64, SIZE_MAX};
    CorayRequirements req = coray_requirements_default();
    CorayKdParams kp = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        CorayStatus st = coray_kdtree_requirements(counts[i], &kp, &req);
        limit("kd", counts[i], st, &req);
#ifdef EVERY_STRUCTURE
        CorayBvhParams bp = coray_bvh_params_default(CORAY_BVH_BUILDER_RSTAR);
        st = coray_bvh_requirements(counts[i], &bp, &req);
        limit("rstar", counts[i], st, &req);
        CorayProjParams pp = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_BUILDER_TDBS);
        st = coray_proj_requirements(counts[i], &pp, &req);
        limit("proj", counts[i], st, &req);
#endif
    }
}

int program(void) {
    BoardScene scenes[2] = {
        {MOUNT_NAME,
         {sizeof(CorayScene), mount_vertices, MOUNT_VERTEX_COUNT, mount_indices, MOUNT_TRIANGLE_COUNT,
          mount_spheres, MOUNT_SPHERE_COUNT, mount_cones, MOUNT_CONE_COUNT},
         mount_from, mount_at, mount_up, mount_lights, MOUNT_LIGHT_COUNT, MOUNT_TAN_HALF_ANGLE},
        {RINGS_NAME,
         {sizeof(CorayScene), rings_vertices, RINGS_VERTEX_COUNT, rings_indices, RINGS_TRIANGLE_COUNT,
          rings_spheres, RINGS_SPHERE_COUNT, rings_cones, RINGS_CONE_COUNT},
         rings_from, rings_at, rings_up, rings_lights, RINGS_LIGHT_COUNT, RINGS_TAN_HALF_ANGLE},
    };
    info("program", "sizeof(void *)", sizeof(void *));
    limits();
    for (int i = 0; i < 2; i++) {
        if (scenes[i].light_count > MAX_LIGHTS) {
            expect(0, scenes[i].name, "too many lights", 0);
            continue;
        }
        kd_tree(&scenes[i], CORAY_KD_PRESET_AUTO, "kd auto");
        kd_tree(&scenes[i], CORAY_KD_PRESET_PAPER, "kd paper");
#ifdef EVERY_STRUCTURE
        hierarchies(&scenes[i]);
#endif
    }
    info("program", "static RAM bytes",
         sizeof arena + sizeof scratch + sizeof stack + sizeof rays + sizeof hits + sizeof shadow +
             sizeof occluded);
    platform_print(failures ? "embedded: FAILED\n" : "embedded: ok\n");
    return failures ? 1 : 0;
}
