/* Past one machine: a tree built once and saved (`coray build SCENE -o
 * scene.coray`), traced by every rank of an MPI job. Each rank maps the
 * file (one copy in each machine's page cache), checks and opens it, casts
 * its band of the image's rows (CorayCastParams' rectangle: each pixel
 * gets what the whole image's cast gives it), and rank 0 gathers the bands
 * and writes the image: the same bytes as trace_saved's one-process cast.
 *
 *   mpirun -n RANKS trace_mpi scene.coray OUT.ppm [SIZE]
 *
 * Build: mpicc trace_mpi.c $(pkg-config --cflags --libs coray) -lm -o trace_mpi
 */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

#include "saved_view.h"

/* Rows [first, first + count) of `size` rows for `rank` of `ranks`. */
static void band(int size, int rank, int ranks, int *first, int *count) {
    *first = (int)((long long)size * rank / ranks);
    *count = (int)((long long)size * (rank + 1) / ranks) - *first;
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    int rank, ranks;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    int size = argc > 3 ? atoi(argv[3]) : 256;
    if (argc < 3 || size < 1 || size > 8192 || ranks > size) {
        if (rank == 0) fprintf(stderr, "usage: mpirun -n RANKS trace_mpi scene.coray OUT.ppm [SIZE >= RANKS]\n");
        MPI_Finalize();
        return 2;
    }
    CoraySaved saved;
    CorayKdTreeInfo info = coray_kdtree_info_default();
    int ok = open_saved(argv[1], &saved) == 0 && coray_kdtree_info(&saved.tree, &info) == CORAY_STATUS_OK;
    CorayCamera cam = saved_camera(&saved, &info, size);

    /* This rank's rows, cast as one rectangle of the camera's image. */
    int first, rows;
    band(size, rank, ranks, &first, &rows);
    CorayCastParams cast = coray_cast_params_default();
    cast.rect_x = 0, cast.rect_y = (uint32_t)first, cast.rect_width = (uint32_t)size, cast.rect_height = (uint32_t)rows;
    CorayRequirements req = coray_requirements_default();
    size_t n = (size_t)size * (size_t)rows;
    CorayHit *hits = malloc(n * sizeof *hits);
    unsigned char *rgb = malloc(n * 3);
    void *scratch = NULL, *stack = NULL;
    ok = ok && hits && rgb && coray_kdtree_cast_requirements(&cam, &cast, &req) == CORAY_STATUS_OK &&
         posix_memalign(&scratch, CORAY_ARENA_ALIGN, req.scratch_bytes ? req.scratch_bytes : 16) == 0 &&
         posix_memalign(&stack, CORAY_ARENA_ALIGN, req.stack_bytes) == 0;
    if (ok) {
        CorayStatus s = coray_kdtree_cast_image(&saved.tree, &cam, &cast, scratch, req.scratch_bytes, stack,
                                                req.stack_bytes, hits, NULL);
        if (s != CORAY_STATUS_OK) fprintf(stderr, "rank %d: cast: %s\n", rank, coray_status_str(s));
        ok = s == CORAY_STATUS_OK;
    }
    for (size_t i = 0; ok && i < n; i++) shade(&hits[i], rgb + 3 * i);

    /* Every rank agrees the image can be made, then rank 0 gathers it. */
    int all_ok = 0;
    MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
    int status = 1;
    if (all_ok) {
        int *counts = malloc((size_t)ranks * sizeof *counts), *offsets = malloc((size_t)ranks * sizeof *offsets);
        unsigned char *image = rank == 0 ? malloc((size_t)size * (size_t)size * 3) : NULL;
        for (int r = 0; r < ranks; r++) {
            int f, c;
            band(size, r, ranks, &f, &c);
            counts[r] = c * size * 3;
            offsets[r] = f * size * 3;
        }
        MPI_Gatherv(rgb, (int)(n * 3), MPI_UNSIGNED_CHAR, image, counts, offsets, MPI_UNSIGNED_CHAR, 0,
                    MPI_COMM_WORLD);
        status = 0;
        if (rank == 0) {
            FILE *out = fopen(argv[2], "wb");
            if (out && fprintf(out, "P6\n%d %d\n255\n", size, size) > 0 &&
                fwrite(image, 1, (size_t)size * (size_t)size * 3, out) == (size_t)size * (size_t)size * 3) {
                printf("%s: %dx%d cast by %d ranks -> %s\n", argv[1], size, size, ranks, argv[2]);
            } else {
                status = 1;
            }
            if (out) fclose(out);
        }
        free(image), free(counts), free(offsets);
    }
    free(hits), free(rgb), free(scratch), free(stack);
    MPI_Finalize();
    return status;
}
