/* One tree traced from 4 threads at once gives, bit for bit, what one
 * thread gives. */
#include <pthread.h>

#include "common.h"

#define THREADS 4
#define RAYS 40000

typedef struct {
    const Tree *tree;
    const CorayScene *scene;
    const CorayRay *rays;
    CorayHit *hits;
    uint8_t *occ;
    uint32_t traversal;
    CorayStatus status;
} Job;

static void *run(void *arg) {
    Job *j = arg;
    KdStack stack; /* one stack per thread; the tree handle is shared */
    CorayStatus s = coray_kdtree_intersect(&j->tree->tree, j->traversal, j->rays, j->hits, RAYS, &stack, sizeof stack, NULL);
    if (s == CORAY_STATUS_OK)
        s = coray_kdtree_occluded(&j->tree->tree, j->traversal, j->rays, j->occ, RAYS, &stack, sizeof stack, NULL);
    j->status = s;
    return NULL;
}

int main(void) {
    TestScene ts;
    Tree tree;
    CorayRay *rays = malloc(sizeof(CorayRay) * RAYS);
    CorayHit *ref = malloc(sizeof(CorayHit) * RAYS);
    uint8_t *ref_occ = malloc(RAYS);
    Job jobs[THREADS];
    pthread_t th[THREADS];
    uint32_t trav;
    int i;
    rng_state = 14;
    ts = scene_random(4000, 600, 600, 1.0f);
    tree = tree_build(&ts.view, CORAY_KD_PRESET_AUTO);
    rays_random(rays, RAYS, 1.0f);
    for (trav = 0; trav < 2; trav++) {
        KdStack stack;
        CHECK_STATUS(coray_kdtree_intersect(&tree.tree, trav, rays, ref, RAYS, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        CHECK_STATUS(coray_kdtree_occluded(&tree.tree, trav, rays, ref_occ, RAYS, &stack, sizeof stack, NULL), CORAY_STATUS_OK);
        for (i = 0; i < THREADS; i++) {
            jobs[i].tree = &tree;
            jobs[i].scene = &ts.view;
            jobs[i].rays = rays;
            jobs[i].hits = malloc(sizeof(CorayHit) * RAYS);
            jobs[i].occ = malloc(RAYS);
            jobs[i].traversal = trav;
            CHECK(pthread_create(&th[i], NULL, run, &jobs[i]) == 0);
        }
        for (i = 0; i < THREADS; i++) {
            CHECK(pthread_join(th[i], NULL) == 0);
            CHECK(jobs[i].status == CORAY_STATUS_OK);
            CHECK(memcmp(jobs[i].hits, ref, sizeof(CorayHit) * RAYS) == 0);
            CHECK(memcmp(jobs[i].occ, ref_occ, RAYS) == 0);
            free(jobs[i].hits);
            free(jobs[i].occ);
        }
    }
    free(tree.arena);
    free(rays);
    free(ref);
    free(ref_occ);
    scene_free(&ts);
    return finish("threads");
}
