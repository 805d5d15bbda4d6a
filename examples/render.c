/* A small renderer on coray's C API: reads an NFF scene (v, b, l, f, s, c,
 * p, pp), builds a kd-tree in memory it allocates itself, traces the
 * camera's image on N threads (rows handed out by an atomic counter),
 * shades with Lambert and one shadow ray per light, and writes a PPM.
 *
 *   render SCENE.nff OUT.ppm [THREADS]
 *
 * Build against the installed library:
 *   cc render.c $(pkg-config --cflags --libs coray) -lpthread -lm -o render
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <coray.h>

/* Growable arrays of the scene. */
typedef struct {
    float *v;
    size_t n, cap;
} Floats;
typedef struct {
    uint32_t *v;
    size_t n, cap;
} Uints;

static void push_f(Floats *a, float x) {
    if (a->n == a->cap) {
        a->cap = a->cap ? 2 * a->cap : 256;
        a->v = realloc(a->v, a->cap * sizeof(float));
        if (!a->v) exit(2);
    }
    a->v[a->n++] = x;
}
static void push_u(Uints *a, uint32_t x) {
    if (a->n == a->cap) {
        a->cap = a->cap ? 2 * a->cap : 256;
        a->v = realloc(a->v, a->cap * sizeof(uint32_t));
        if (!a->v) exit(2);
    }
    a->v[a->n++] = x;
}

typedef struct {
    Floats vertices, spheres, cones, lights, colors; /* colors: r g b per primitive */
    Uints indices;
    float from[3], at[3], up[3], angle, background[3];
    int width, height;
} Nff;

static int next_floats(FILE *f, float *out, int n) {
    for (int i = 0; i < n; i++)
        if (fscanf(f, "%f", &out[i]) != 1) return 0;
    return 1;
}

/* The NFF subset the SPD uses; polygons as triangle fans (convex ones:
 * concave polygons need coray's ear clipping, in coray-scenes). */
static int read_nff(const char *path, Nff *s) {
    FILE *f = fopen(path, "r");
    char cmd[64];
    float color[3] = {0.8f, 0.8f, 0.8f};
    if (!f) return 0;
    memset(s, 0, sizeof *s);
    s->width = s->height = 256;
    s->angle = 45;
    s->up[1] = 1;
    while (fscanf(f, "%63s", cmd) == 1) {
        if (cmd[0] == '#') {
            int c;
            while ((c = fgetc(f)) != EOF && c != '\n') {}
        } else if (!strcmp(cmd, "v")) {
            char w[32];
            float hither;
            if (fscanf(f, "%31s", w) != 1 || !next_floats(f, s->from, 3) || fscanf(f, "%31s", w) != 1 ||
                !next_floats(f, s->at, 3) || fscanf(f, "%31s", w) != 1 || !next_floats(f, s->up, 3) ||
                fscanf(f, "%31s %f %31s %f %31s %d %d", w, &s->angle, w, &hither, w, &s->width, &s->height) != 7)
                return 0;
        } else if (!strcmp(cmd, "b")) {
            if (!next_floats(f, s->background, 3)) return 0;
        } else if (!strcmp(cmd, "l")) {
            float p[3];
            char rest[256];
            if (!next_floats(f, p, 3)) return 0;
            /* An optional colour on the same line (r g b): read past it;
             * this renderer's lights are white. */
            if (!fgets(rest, sizeof rest, f)) rest[0] = 0;
            for (int k = 0; k < 3; k++) push_f(&s->lights, p[k]);
        } else if (!strcmp(cmd, "f")) {
            float rest[5];
            if (!next_floats(f, color, 3) || !next_floats(f, rest, 5)) return 0;
        } else if (!strcmp(cmd, "s")) {
            float sp[4];
            if (!next_floats(f, sp, 4)) return 0;
            for (int k = 0; k < 4; k++) push_f(&s->spheres, k == 3 ? fabsf(sp[k]) : sp[k]);
        } else if (!strcmp(cmd, "c")) {
            float c[8];
            if (!next_floats(f, c, 8)) return 0;
            for (int k = 0; k < 8; k++) push_f(&s->cones, (k == 3 || k == 7) ? fabsf(c[k]) : c[k]);
        } else if (!strcmp(cmd, "p") || !strcmp(cmd, "pp")) {
            int n, normals = !strcmp(cmd, "pp");
            uint32_t first = (uint32_t)(s->vertices.n / 3);
            if (fscanf(f, "%d", &n) != 1 || n < 3 || n > (1 << 20)) return 0;
            for (int i = 0; i < n; i++) {
                float p[6];
                if (!next_floats(f, p, normals ? 6 : 3)) return 0;
                for (int k = 0; k < 3; k++) push_f(&s->vertices, p[k]);
            }
            for (int i = 1; i + 1 < n; i++) {
                push_u(&s->indices, first);
                push_u(&s->indices, first + (uint32_t)i);
                push_u(&s->indices, first + (uint32_t)i + 1);
                for (int k = 0; k < 3; k++) push_f(&s->colors, color[k]);
            }
            continue;
        } else {
            fprintf(stderr, "unknown NFF command %s\n", cmd);
            return 0;
        }
        if (!strcmp(cmd, "s") || !strcmp(cmd, "c"))
            for (int k = 0; k < 3; k++) push_f(&s->colors, color[k]);
    }
    fclose(f);
    return 1;
}

typedef struct {
    const Nff *nff;
    const CorayScene *scene;
    const CorayKdTree *tree;
    unsigned char *image;
    atomic_int next_row;
    float eye[3], fwd[3], right[3], upv[3];
} Job;

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* The colour of a hit: triangles' colours come first in Nff.colors, then
 * the spheres', then the cones'. */
static const float *color_of(const Nff *s, const CorayHit *h) {
    size_t i = h->prim_id;
    if (h->geom_id == CORAY_GEOM_SPHERES) i += s->indices.n / 3;
    if (h->geom_id == CORAY_GEOM_CONES) i += s->indices.n / 3 + s->spheres.n / 4;
    return &s->colors.v[3 * i];
}

static void *render_rows(void *arg) {
    Job *j = arg;
    const Nff *s = j->nff;
    _Alignas(16) static _Thread_local unsigned char stack[CORAY_KDTREE_STACK_BYTES];
    /* One tracer per thread: the checks once, then one call per ray. */
    CorayTracer tracer;
    int w = s->width, h = s->height, y;
    if (coray_kdtree_tracer(j->tree, CORAY_TRAVERSAL_HIERARCHICAL, stack, sizeof stack, &tracer) != CORAY_STATUS_OK)
        exit(3);
    while ((y = atomic_fetch_add(&j->next_row, 1)) < h) {
        for (int x = 0; x < w; x++) {
            float sx = (2.0f * ((float)x + 0.5f) / (float)w - 1.0f), sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)h);
            CorayRay ray;
            CorayHit hit;
            float c[3];
            for (int k = 0; k < 3; k++) {
                ray.org[k] = j->eye[k];
                ray.dir[k] = j->fwd[k] + sx * j->right[k] + sy * j->upv[k];
            }
            ray.tnear = 0;
            ray.tfar = INFINITY;
            if (coray_kdtree_tracer_intersect1(&tracer, &ray, &hit) != CORAY_STATUS_OK)
                exit(3);
            memcpy(c, s->background, sizeof c);
            if (hit.geom_id != CORAY_INVALID_ID) {
                float p[3], n[3], nl = sqrtf(dot3(hit.ng, hit.ng));
                const float *base = color_of(s, &hit);
                for (int k = 0; k < 3; k++) {
                    p[k] = ray.org[k] + hit.t * ray.dir[k];
                    n[k] = hit.ng[k] / nl;
                    c[k] = 0.1f * base[k];
                }
                if (dot3(n, ray.dir) > 0)
                    for (int k = 0; k < 3; k++) n[k] = -n[k];
                for (size_t l = 0; l < s->lights.n / 3; l++) {
                    float d[3], len;
                    CorayRay sh;
                    uint8_t blocked;
                    for (int k = 0; k < 3; k++) d[k] = s->lights.v[3 * l + k] - p[k];
                    len = sqrtf(dot3(d, d));
                    for (int k = 0; k < 3; k++) d[k] /= len;
                    if (dot3(n, d) <= 0) continue;
                    for (int k = 0; k < 3; k++) {
                        sh.org[k] = p[k];
                        sh.dir[k] = d[k];
                    }
                    sh.tnear = 1e-4f * (len > 1 ? len : 1);
                    sh.tfar = len;
                    if (coray_kdtree_tracer_occluded1(&tracer, &sh, &blocked) != CORAY_STATUS_OK)
                        exit(3);
                    if (!blocked)
                        for (int k = 0; k < 3; k++) c[k] += base[k] * dot3(n, d) / sqrtf((float)(s->lights.n / 3));
                }
            }
            for (int k = 0; k < 3; k++) {
                float v = c[k] < 0 ? 0 : c[k] > 1 ? 1 : c[k];
                j->image[3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)k] = (unsigned char)(powf(v, 1 / 2.2f) * 255 + 0.5f);
            }
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    Nff s;
    int threads = argc > 3 ? atoi(argv[3]) : 4;
    if (argc < 3 || threads < 1 || threads > 256) {
        fprintf(stderr, "usage: render SCENE.nff OUT.ppm [THREADS]\n");
        return 2;
    }
    if (coray_version() >> 16 != CORAY_VERSION_MAJOR) {
        fprintf(stderr, "libcoray %u.x does not match coray.h %d.x\n", coray_version() >> 16, CORAY_VERSION_MAJOR);
        return 2;
    }
    if (!read_nff(argv[1], &s)) {
        fprintf(stderr, "%s: cannot read it as NFF\n", argv[1]);
        return 2;
    }
    CorayScene scene = coray_scene_default();
    scene.vertices = s.vertices.v;
    scene.vertex_count = s.vertices.n / 3;
    scene.indices = s.indices.v;
    scene.triangle_count = s.indices.n / 3;
    scene.spheres = s.spheres.v;
    scene.sphere_count = s.spheres.n / 4;
    scene.cones = s.cones.v;
    scene.cone_count = s.cones.n / 8;

    CorayKdParams params = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    CorayRequirements req = coray_requirements_default();
    size_t prims = scene.triangle_count + scene.sphere_count + scene.cone_count;
    CorayStatus st = coray_kdtree_requirements(prims, &params, &req);
    void *arena = NULL, *scratch = NULL;
    if (st != CORAY_STATUS_OK || posix_memalign(&arena, CORAY_ARENA_ALIGN, req.arena_bytes) != 0 ||
        posix_memalign(&scratch, CORAY_ARENA_ALIGN, req.scratch_bytes) != 0) {
        fprintf(stderr, "requirements: %s\n", coray_status_str(st));
        return 1;
    }
    st = coray_kdtree_build(&scene, &params, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL);
    free(scratch);
    CorayKdTree tree;
    if (st == CORAY_STATUS_OK) st = coray_kdtree_open(arena, req.arena_bytes, &scene, &tree);
    if (st != CORAY_STATUS_OK) {
        fprintf(stderr, "build: %s\n", coray_status_str(st));
        return 1;
    }

    Job job;
    memset(&job, 0, sizeof job);
    job.nff = &s;
    job.scene = &scene;
    job.tree = &tree;
    job.image = malloc((size_t)s.width * (size_t)s.height * 3);
    atomic_init(&job.next_row, 0);
    {
        float l, half = tanf(s.angle * 3.14159265f / 360.0f), aspect = (float)s.width / (float)s.height;
        for (int k = 0; k < 3; k++) {
            job.eye[k] = s.from[k];
            job.fwd[k] = s.at[k] - s.from[k];
        }
        l = sqrtf(dot3(job.fwd, job.fwd));
        for (int k = 0; k < 3; k++) job.fwd[k] /= l;
        job.right[0] = job.fwd[1] * s.up[2] - job.fwd[2] * s.up[1];
        job.right[1] = job.fwd[2] * s.up[0] - job.fwd[0] * s.up[2];
        job.right[2] = job.fwd[0] * s.up[1] - job.fwd[1] * s.up[0];
        l = sqrtf(dot3(job.right, job.right));
        for (int k = 0; k < 3; k++) job.right[k] *= half * aspect / l;
        job.upv[0] = (job.right[1] * job.fwd[2] - job.right[2] * job.fwd[1]) / (aspect);
        job.upv[1] = (job.right[2] * job.fwd[0] - job.right[0] * job.fwd[2]) / (aspect);
        job.upv[2] = (job.right[0] * job.fwd[1] - job.right[1] * job.fwd[0]) / (aspect);
    }
    pthread_t th[256];
    for (int i = 0; i < threads; i++) pthread_create(&th[i], NULL, render_rows, &job);
    for (int i = 0; i < threads; i++) pthread_join(th[i], NULL);

    FILE *out = fopen(argv[2], "wb");
    if (!out) return 1;
    fprintf(out, "P6\n%d %d\n255\n", s.width, s.height);
    fwrite(job.image, 3, (size_t)s.width * (size_t)s.height, out);
    fclose(out);
    printf("%s: %zu primitives, %dx%d on %d threads -> %s\n", argv[1], prims, s.width, s.height, threads, argv[2]);
    free(job.image);
    free(arena);
    return 0;
}
