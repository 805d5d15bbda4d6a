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
 * the arrays and the scene's view); coray_saved_open reads it. The image
 * is cast from the saved view (a file without one: from the diagonal of
 * the scene's box).
 */
#include <stdio.h>
#include <stdlib.h>

#include "saved_view.h"

int main(int argc, char **argv) {
    int size = argc > 3 ? atoi(argv[3]) : 256;
    if (argc < 3 || size < 1 || size > 8192) {
        fprintf(stderr, "usage: trace_saved scene.coray OUT.ppm [SIZE]\n");
        return 2;
    }
    CoraySaved saved;
    if (open_saved(argv[1], &saved) != 0) return 1;
    const CorayKdTree tree = saved.tree;
    CorayKdTreeInfo info = coray_kdtree_info_default();
    if (coray_kdtree_info(&tree, &info) != CORAY_STATUS_OK) return 1;
    CorayCamera cam = saved_camera(&saved, &info, size);

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
    CorayStatus s = coray_kdtree_cast_image(&tree, &cam, &cast, scratch, req.scratch_bytes, stack, req.stack_bytes, hits, NULL);
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "cast: %s\n", coray_status_str(s));
        return 1;
    }
    FILE *out = fopen(argv[2], "wb");
    if (!out) return 1;
    fprintf(out, "P6\n%d %d\n255\n", size, size);
    size_t hit_count = 0;
    for (size_t i = 0; i < (size_t)size * (size_t)size; i++) {
        unsigned char px[3];
        shade(&hits[i], px);
        hit_count += hits[i].geom_id != CORAY_INVALID_ID;
        fwrite(px, 1, 3, out);
    }
    fclose(out);
    printf("%s: %u nodes, %u leaves, depth %u, validated; %dx%d cast in packets, %zu pixels hit -> %s\n", argv[1],
           info.node_count, info.leaf_count, info.depth, size, size, hit_count, argv[2]);
    free(hits);
    free(scratch);
    free(stack);
    return 0;
}
