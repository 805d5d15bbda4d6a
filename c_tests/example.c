/* README example: a floor and a ball, a kd-tree in caller memory, one ray. */
#include <stdio.h>
#include <stdlib.h>

#include "coray.h"

int main(void) {
    /* A 10 x 10 floor at y = 0 (two triangles) and a ball of radius 1. */
    static const float vertices[] = {-5, 0, -5, 5, 0, -5, 5, 0, 5, -5, 0, 5};
    static const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
    static const float spheres[] = {0, 1, 0, 1}; /* x y z radius */
    static _Alignas(16) unsigned char stack[CORAY_KDTREE_STACK_BYTES];

    CorayScene scene = coray_scene_default();
    scene.vertices = vertices;
    scene.vertex_count = 4;
    scene.indices = indices;
    scene.triangle_count = 2;
    scene.spheres = spheres;
    scene.sphere_count = 1;

    /* Ask for the sizes, then hand coray its memory: it never allocates. */
    CorayKdParams params = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    CorayRequirements req = coray_requirements_default();
    if (coray_kdtree_requirements(3, &params, &req) != CORAY_STATUS_OK) return 1;
    void *arena = NULL, *scratch = NULL;
    if (posix_memalign(&arena, CORAY_ARENA_ALIGN, req.arena_bytes) != 0) return 1;
    if (posix_memalign(&scratch, CORAY_ARENA_ALIGN, req.scratch_bytes) != 0) return 1;

    CorayStatus s = coray_kdtree_build(&scene, &params, arena, req.arena_bytes, scratch, req.scratch_bytes, NULL);
    free(scratch); /* scratch is free again once the build returns */
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "build: %s\n", coray_status_str(s));
        return 1;
    }

    /* Open the arena: the handle every trace takes (arena and scene stay put). */
    CorayKdTree tree;
    if (coray_kdtree_open(arena, req.arena_bytes, &scene, &tree) != CORAY_STATUS_OK) return 1;

    /* Straight down onto the ball, then a shadow ray from the floor. */
    CorayRay ray = {{0, 10, 0}, 0.0f, {0, -1, 0}, 1e30f};
    CorayHit hit;
    CorayTraceStats stats = coray_trace_stats_default();
    s = coray_kdtree_intersect1(&tree, CORAY_TRAVERSAL_HIERARCHICAL, &ray, &hit, stack, sizeof stack, &stats);
    if (s != CORAY_STATUS_OK) return 1;
    printf("hit geometry %u primitive %u at t = %g after %llu traversal steps\n", hit.geom_id, hit.prim_id,
           (double)hit.t, (unsigned long long)stats.traversal_steps);

    CorayRay shadow = {{0.5f, 0, 0.5f}, 1e-3f, {0, 1, 0}, 100.0f};
    uint8_t occluded = 0;
    s = coray_kdtree_occluded1(&tree, CORAY_TRAVERSAL_ROPES, &shadow, &occluded, stack, sizeof stack, NULL);
    if (s != CORAY_STATUS_OK) return 1;
    printf("floor point under the ball is %s\n", occluded ? "in shadow" : "lit");

    free(arena);
    return !(hit.geom_id == CORAY_GEOM_SPHERES && hit.t == 8.0f && occluded);
}
