/* A render farm's worker: maps a scene and its kd-tree saved by
 * `coray build SCENE -o scene.coray` (built once, on another machine or in
 * another process), checks it, and traces an image from it without
 * building anything. The arena holds offsets, not pointers: it opens at
 * whatever address mmap gives. Every process mapping the file shares one
 * copy of the tree in the page cache.
 *
 *   trace_saved scene.coray OUT.ppm [SIZE]
 *
 * File format: ffi/src/saved.rs (a 128-byte header with a checksum, then
 * the arrays); coray_saved_open reads it.
 */
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <coray.h>

int main(int argc, char **argv) {
    int size = argc > 3 ? atoi(argv[3]) : 256;
    if (argc < 3 || size < 1 || size > 8192) {
        fprintf(stderr, "usage: trace_saved scene.coray OUT.ppm [SIZE]\n");
        return 2;
    }
    int fd = open(argv[1], O_RDONLY);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || st.st_size <= 0) {
        fprintf(stderr, "%s: cannot read\n", argv[1]);
        return 1;
    }
    size_t len = (size_t)st.st_size;
    const unsigned char *base = mmap(NULL, len, PROT_READ, MAP_SHARED, fd, 0);
    close(fd);
    if (base == MAP_FAILED) return 1;

    /* One call checks the file (magic, version, byte order, length, a
     * checksum over every byte: it may have been damaged on its way here),
     * points the scene into it and opens and validates the tree. */
    CoraySaved saved = coray_saved_default();
    CorayStatus s = coray_saved_open(base, len, &saved);
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", argv[1], coray_status_str(s));
        return 1;
    }
    const CorayKdTree tree = saved.tree;
    CorayKdTreeInfo info = coray_kdtree_info_default();
    if (coray_kdtree_info(&tree, &info) != CORAY_STATUS_OK) return 1;

    /* A camera on the diagonal of the scene's box, looking at its centre. */
    float c[3], ext = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5f * (info.bounds_min[k] + info.bounds_max[k]);
        ext = fmaxf(ext, info.bounds_max[k] - info.bounds_min[k]);
    }
    CorayCamera cam = coray_camera_default();
    for (int k = 0; k < 3; k++) {
        cam.from[k] = c[k] + (k == 1 ? 0.8f : 1.2f) * ext;
        cam.at[k] = c[k];
    }
    cam.up[1] = 1;
    cam.angle_deg = 45;
    cam.width = cam.height = (uint32_t)size;

    /* The whole image in one call, in tiles of 4 x 2 rays (the default
     * scheme; CORAY_CAST_SLCTS_2D and the other LCTS schemes need ropes). */
    CorayCastParams cast = coray_cast_params_default();
    CorayRequirements req = coray_requirements_default();
    CorayHit *hits = malloc((size_t)size * (size_t)size * sizeof *hits);
    void *scratch = NULL, *stack = NULL;
    if (!hits || coray_kdtree_cast_requirements(&cam, &cast, &req) != CORAY_STATUS_OK ||
        posix_memalign(&scratch, CORAY_ARENA_ALIGN, req.scratch_bytes ? req.scratch_bytes : 16) != 0 ||
        posix_memalign(&stack, CORAY_ARENA_ALIGN, req.stack_bytes) != 0)
        return 1;
    s = coray_kdtree_cast_image(&tree, &cam, &cast, scratch, req.scratch_bytes, stack, req.stack_bytes, hits, NULL);
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "cast: %s\n", coray_status_str(s));
        return 1;
    }
    FILE *out = fopen(argv[2], "wb");
    if (!out) return 1;
    fprintf(out, "P6\n%d %d\n255\n", size, size);
    size_t hit_count = 0;
    for (size_t i = 0; i < (size_t)size * (size_t)size; i++) {
        const CorayHit *h = &hits[i];
        unsigned char v = 20;
        if (h->geom_id != CORAY_INVALID_ID) {
            float n = sqrtf(h->ng[0] * h->ng[0] + h->ng[1] * h->ng[1] + h->ng[2] * h->ng[2]);
            v = (unsigned char)(40 + 200 * fabsf(h->ng[1]) / n);
            hit_count++;
        }
        unsigned char px[3] = {v, v, (unsigned char)(v / 2 + 100)};
        fwrite(px, 1, 3, out);
    }
    fclose(out);
    printf("%s: %u nodes, %u leaves, depth %u, validated; %dx%d cast in packets, %zu pixels hit -> %s\n", argv[1],
           info.node_count, info.leaf_count, info.depth, size, size, hit_count, argv[2]);
    free(hits);
    free(scratch);
    free(stack);
    munmap((void *)base, len);
    return 0;
}
