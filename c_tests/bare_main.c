/* Linked against the bare coray library (no Rust std): static arenas, no
 * allocator anywhere in the program, one build and a few traces. */
#include <stdint.h>
#include <stdio.h>

#include "coray.h"

static _Alignas(16) unsigned char arena[1 << 16];
static _Alignas(16) unsigned char scratch[1 << 16];
static _Alignas(16) unsigned char stack[CORAY_KDTREE_STACK_BYTES];

int main(void) {
    static const float vertices[] = {-5, 0, -5, 5, 0, -5, 5, 0, 5, -5, 0, 5};
    static const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
    static const float spheres[] = {0, 1, 0, 1, 3, 1, 0, 0.5f};
    static const float cones[] = {-3, 0, 0, 0.5f, -3, 2, 0, 0.5f};
    CorayScene scene = coray_scene_default();
    CorayKdParams params = coray_kdtree_params_default(CORAY_KD_PRESET_PAPER);
    CorayKdTree tree;
    CorayRay rays[3] = {{{0, 10, 0}, 0, {0, -1, 0}, 1e30f}, {{3, 10, 0}, 0, {0, -1, 0}, 1e30f}, {{-3, 1, 5}, 0, {0, 0, -1}, 1e30f}};
    CorayHit hits[3];
    uint8_t occ[3];
    scene.vertices = vertices;
    scene.vertex_count = 4;
    scene.indices = indices;
    scene.triangle_count = 2;
    scene.spheres = spheres;
    scene.sphere_count = 2;
    scene.cones = cones;
    scene.cone_count = 1;
    if (coray_kdtree_build(&scene, &params, arena, sizeof arena, scratch, sizeof scratch, NULL) != CORAY_STATUS_OK) return 1;
    if (coray_kdtree_open(arena, sizeof arena, &scene, &tree) != CORAY_STATUS_OK) return 2;
    if (coray_kdtree_validate(&tree, NULL, 0, NULL) != CORAY_STATUS_OK) return 2;
    if (coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_ROPES, rays, hits, 3, stack, sizeof stack, NULL) != CORAY_STATUS_OK) return 3;
    if (coray_kdtree_occluded(&tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, occ, 3, stack, sizeof stack, NULL) != CORAY_STATUS_OK) return 4;
    if (hits[0].t != 8.0f || hits[0].geom_id != CORAY_GEOM_SPHERES || hits[0].prim_id != 0) return 5;
    if (hits[1].t != 8.5f || hits[1].prim_id != 1) return 6;
    if (hits[2].t != 4.5f || hits[2].geom_id != CORAY_GEOM_CONES) return 7;
    if (!occ[0] || !occ[1] || !occ[2]) return 8;
    /* A corrupted arena gets a status, never an abort: the root's children
       pointed at itself, a reference past the scene. */
    ((uint32_t *)arena)[32] = 0;
    if (coray_kdtree_validate(&tree, NULL, 0, NULL) != CORAY_STATUS_CORRUPT_ARENA) return 9;
    if (coray_kdtree_intersect(&tree, CORAY_TRAVERSAL_HIERARCHICAL, rays, hits, 3, stack, sizeof stack, NULL) == CORAY_STATUS_INTERNAL_ERROR) return 10;
    puts("bare: ok");
    return 0;
}
