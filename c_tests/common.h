/* Shared helpers of the C test programs: a seeded generator, scenes, rays,
 * aligned arenas and a check macro. Header-only so each program is one file. */
#ifndef CORAY_C_TESTS_COMMON_H
#define CORAY_C_TESTS_COMMON_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "coray.h"

static int failures = 0;
#define CHECK(cond)                                                              \
    do {                                                                         \
        if (!(cond)) {                                                           \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            failures++;                                                          \
        }                                                                        \
    } while (0)
#define CHECK_STATUS(expr, want)                                                          \
    do {                                                                                  \
        CorayStatus got_ = (expr);                                                        \
        if (got_ != (want)) {                                                             \
            fprintf(stderr, "%s:%d: %s gave %d (%s), want %d\n", __FILE__, __LINE__, #expr, \
                    (int)got_, coray_status_str((int)got_), (int)(want));                 \
            failures++;                                                                   \
        }                                                                                 \
    } while (0)

/* SplitMix64. */
static uint64_t rng_state = 1;
static uint64_t rng_u64(void) {
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static inline float rng_f(void) { return (float)(rng_u64() >> 40) / (float)(1 << 24); }
static inline float rng_range(float lo, float hi) { return lo + (hi - lo) * rng_f(); }
static inline void rng_unit(float v[3]) {
    for (;;) {
        float l;
        v[0] = rng_range(-1, 1);
        v[1] = rng_range(-1, 1);
        v[2] = rng_range(-1, 1);
        l = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (l > 1e-4f && l <= 1.0f) {
            l = sqrtf(l);
            v[0] /= l;
            v[1] /= l;
            v[2] /= l;
            return;
        }
    }
}

/* An owned scene: random small triangles (some sharing edges, as meshes
 * do), spheres and open cones in [-s, s]^3. */
typedef struct {
    float *vertices;
    uint32_t *indices;
    float *spheres;
    float *cones;
    size_t nv, nt, ns, nc;
    CorayScene view;
} TestScene;

static inline void scene_view(TestScene *t) {
    t->view = coray_scene_default();
    t->view.vertices = t->vertices;
    t->view.vertex_count = t->nv;
    t->view.indices = t->indices;
    t->view.triangle_count = t->nt;
    t->view.spheres = t->spheres;
    t->view.sphere_count = t->ns;
    t->view.cones = t->cones;
    t->view.cone_count = t->nc;
}

/* nt triangles as nt/2 quads split along a diagonal (shared edges), spheres, cones. */
static inline TestScene scene_random(size_t nt, size_t ns, size_t nc, float s) {
    TestScene t;
    size_t i, q;
    float size = s * 0.06f;
    nt &= ~(size_t)1;
    t.nv = nt * 2;
    t.nt = nt;
    t.ns = ns;
    t.nc = nc;
    t.vertices = malloc(sizeof(float) * 3 * (t.nv + 1));
    t.indices = malloc(sizeof(uint32_t) * 3 * (nt + 1));
    t.spheres = malloc(sizeof(float) * 4 * (ns + 1));
    t.cones = malloc(sizeof(float) * 8 * (nc + 1));
    for (q = 0; q < nt / 2; q++) {
        float c[3], a[3], b[3];
        int k;
        for (k = 0; k < 3; k++) c[k] = rng_range(-s, s);
        rng_unit(a);
        rng_unit(b);
        for (k = 0; k < 3; k++) {
            float ea = a[k] * size * rng_range(0.3f, 1.0f), eb = b[k] * size * rng_range(0.3f, 1.0f);
            t.vertices[(4 * q + 0) * 3 + k] = c[k] - ea - eb;
            t.vertices[(4 * q + 1) * 3 + k] = c[k] + ea - eb;
            t.vertices[(4 * q + 2) * 3 + k] = c[k] + ea + eb;
            t.vertices[(4 * q + 3) * 3 + k] = c[k] - ea + eb;
        }
        t.indices[6 * q + 0] = (uint32_t)(4 * q);
        t.indices[6 * q + 1] = (uint32_t)(4 * q + 1);
        t.indices[6 * q + 2] = (uint32_t)(4 * q + 2);
        t.indices[6 * q + 3] = (uint32_t)(4 * q);
        t.indices[6 * q + 4] = (uint32_t)(4 * q + 2);
        t.indices[6 * q + 5] = (uint32_t)(4 * q + 3);
    }
    for (i = 0; i < ns; i++) {
        int k;
        for (k = 0; k < 3; k++) t.spheres[4 * i + k] = rng_range(-s, s);
        t.spheres[4 * i + 3] = rng_range(0.005f, 0.04f) * s;
    }
    for (i = 0; i < nc; i++) {
        float d[3], r0 = rng_range(0.002f, 0.03f) * s;
        int k;
        rng_unit(d);
        for (k = 0; k < 3; k++) {
            t.cones[8 * i + k] = rng_range(-s, s);
            t.cones[8 * i + 4 + k] = t.cones[8 * i + k] + d[k] * rng_range(0.02f, 0.1f) * s;
        }
        t.cones[8 * i + 3] = r0;
        t.cones[8 * i + 7] = (i % 3 == 0) ? r0 : rng_range(0.0f, 0.03f) * s;
    }
    (void)i;
    scene_view(&t);
    return t;
}

static inline void scene_free(TestScene *t) {
    free(t->vertices);
    free(t->indices);
    free(t->spheres);
    free(t->cones);
}

/* Rays from outside towards the scene and from inside in any direction. */
static inline void rays_random(CorayRay *r, size_t n, float s) {
    size_t i;
    for (i = 0; i < n; i++) {
        float u[3], target[3];
        int k;
        rng_unit(u);
        if (i % 2 == 0) {
            for (k = 0; k < 3; k++) {
                target[k] = rng_range(-s, s);
                r[i].org[k] = u[k] * 3.0f * s;
                r[i].dir[k] = target[k] - r[i].org[k];
            }
            r[i].tnear = 0.0f;
            r[i].tfar = INFINITY;
        } else {
            for (k = 0; k < 3; k++) {
                r[i].org[k] = rng_range(-s, s);
                r[i].dir[k] = u[k];
            }
            r[i].tnear = 0.0f;
            r[i].tfar = rng_range(0.1f, 3.0f) * s;
        }
    }
}

/* A pinhole camera at `eye` looking at the origin, w x h rays. */
static inline void rays_camera(CorayRay *r, int w, int h, const float eye[3]) {
    float f[3], rt[3], up[3], l;
    int x, y, k;
    for (k = 0; k < 3; k++) f[k] = -eye[k];
    l = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (k = 0; k < 3; k++) f[k] /= l;
    rt[0] = f[2]; rt[1] = 0; rt[2] = -f[0];
    l = sqrtf(rt[0] * rt[0] + rt[2] * rt[2]);
    rt[0] /= l; rt[2] /= l;
    up[0] = rt[1] * f[2] - rt[2] * f[1];
    up[1] = rt[2] * f[0] - rt[0] * f[2];
    up[2] = rt[0] * f[1] - rt[1] * f[0];
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            CorayRay *ray = &r[(size_t)y * (size_t)w + (size_t)x];
            float px = (2.0f * ((float)x + 0.5f) / (float)w - 1.0f) * 0.6f;
            float py = (1.0f - 2.0f * ((float)y + 0.5f) / (float)h) * 0.6f;
            for (k = 0; k < 3; k++) {
                ray->org[k] = eye[k];
                ray->dir[k] = f[k] + px * rt[k] + py * up[k];
            }
            ray->tnear = 0.0f;
            ray->tfar = INFINITY;
        }
}

static inline void *arena_alloc(size_t bytes) {
    void *p = NULL;
    if (posix_memalign(&p, CORAY_ARENA_ALIGN, bytes ? bytes : 16) != 0) {
        fprintf(stderr, "out of memory for a %zu-byte arena\n", bytes);
        exit(2);
    }
    return p;
}

/* Output structs with their struct_size set. */
static inline CorayRequirements requirements0(void) { return coray_requirements_default(); }
static inline CorayTraceStats stats0(void) { return coray_trace_stats_default(); }
static inline CorayShape shape0(void) { return coray_shape_default(); }

/* A kd traversal stack: one per thread. */
typedef struct {
    _Alignas(16) unsigned char bytes[CORAY_KDTREE_STACK_BYTES];
} KdStack;

/* A built and opened tree with its ideal arena (scratch freed). */
typedef struct {
    void *arena;
    size_t bytes;
    CorayKdTree tree;
} Tree;

static inline Tree tree_build_with(const CorayScene *scene, const CorayKdParams *params) {
    CorayKdParams p = *params;
    CorayRequirements req = requirements0();
    Tree t;
    void *scratch;
    size_t n = scene->triangle_count + scene->sphere_count + scene->cone_count;
    CHECK_STATUS(coray_kdtree_requirements(n, &p, &req), CORAY_STATUS_OK);
    t.bytes = req.arena_bytes;
    t.arena = arena_alloc(req.arena_bytes);
    scratch = arena_alloc(req.scratch_bytes);
    CHECK_STATUS(coray_kdtree_build(scene, &p, t.arena, t.bytes, scratch, req.scratch_bytes, NULL), CORAY_STATUS_OK);
    free(scratch);
    CHECK_STATUS(coray_kdtree_open(t.arena, t.bytes, scene, &t.tree), CORAY_STATUS_OK);
    return t;
}

/* A tree with the preset's parameters (AUTO: no ropes, PAPER: ropes). */
static inline Tree tree_build(const CorayScene *scene, CorayKdPreset preset) {
    CorayKdParams p = coray_kdtree_params_default(preset);
    return tree_build_with(scene, &p);
}

/* A tree with the preset's parameters and ropes, for rope traversal and casts. */
static inline Tree tree_build_roped(const CorayScene *scene, CorayKdPreset preset) {
    CorayKdParams p = coray_kdtree_params_default(preset);
    p.omit_ropes = 0;
    return tree_build_with(scene, &p);
}

static inline int finish(const char *name) {
    if (failures) {
        fprintf(stderr, "%s: %d check(s) failed\n", name, failures);
        return 1;
    }
    printf("%s: ok\n", name);
    return 0;
}

#endif
