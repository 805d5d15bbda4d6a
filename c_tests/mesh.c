/* README example: a triangle mesh, the wide hierarchy in caller memory, one ray per call. */
#include <stdio.h>
#include <stdlib.h>

#include "coray.h"

int main(void) {
    /* An octahedron |x| + |y| + |z| = 1: 6 vertices, 8 counter-clockwise triangles. */
    static const float v[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    static const uint32_t tri[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    CorayScene scene = coray_scene_default();
    scene.vertices = v, scene.vertex_count = 6, scene.indices = tri, scene.triangle_count = 8;

    /* Ask for the sizes, lend the memory (coray never allocates), build, open. */
    CorayWideParams params = coray_wide_params_default();
    CorayRequirements req = coray_requirements_default();
    void *arena = NULL, *scratch = NULL, *stack = NULL;
    CorayWide wide;
    if (coray_wide_requirements(8, &params, &req) != CORAY_STATUS_OK ||
        posix_memalign(&arena, CORAY_ARENA_ALIGN, req.arena_bytes) != 0 ||
        posix_memalign(&scratch, CORAY_ARENA_ALIGN, req.scratch_bytes) != 0 ||
        posix_memalign(&stack, CORAY_ARENA_ALIGN, req.stack_bytes) != 0)
        return 1;
    CorayStatus s = coray_wide_build(&scene, &params, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL);
    free(scratch); /* free again once the build returns */
    if (s == CORAY_STATUS_OK) s = coray_wide_open(arena, req.arena_bytes, &scene, &wide);

    /* One tracer per thread: its calls skip the checks the tracer made once. */
    CorayTracer tracer;
    if (s == CORAY_STATUS_OK) s = coray_wide_tracer(&wide, stack, req.stack_bytes, &tracer);
    CorayRay ray = {{0.25f, 0.25f, 5}, 0, {0, 0, -1}, 1e30f};
    CorayHit hit;
    if (s == CORAY_STATUS_OK) s = coray_wide_tracer_intersect1(&tracer, &ray, &hit);
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "coray: %s\n", coray_status_str(s));
        return 1;
    }
    /* ng = (v0 - v1) x (v2 - v0): here it points along the ray (never flipped). */
    printf("triangle %u at t = %g, u = %g, v = %g, ng = (%g, %g, %g)\n", hit.prim_id, (double)hit.t,
           (double)hit.u, (double)hit.v, (double)hit.ng[0], (double)hit.ng[1], (double)hit.ng[2]);
    free(arena), free(stack);
    return !(hit.prim_id == 0 && hit.t > 4.4999f && hit.t < 4.5001f && hit.ng[2] < 0);
}
