/* coray_kdtree_build_jobs: the kd build's jobs on the caller's threads
 * give the arena coray_kdtree_build gives, byte for byte, whoever runs the
 * jobs (4 pthreads, one thread in reverse, nobody, no runner); a runner
 * that misuses run_job gets statuses, and the tree is still the same. Run
 * under helgrind by the test suite (the jobs write one arena at once). */
#include <pthread.h>

#include "common.h"

#define THREADS 4

/* What one runner saw. */
typedef struct {
    size_t job_count, flags_bytes, next;
    pthread_mutex_t lock;
    CorayKdRunJob run_job;
    void *jobs;
    CorayStatus worst;
    int calls;
    void *arena; /* for the misuse runner: flags inside the arena */
} Runner;

static void note(Runner *r, CorayStatus s) {
    pthread_mutex_lock(&r->lock);
    if (s != CORAY_STATUS_OK) r->worst = s;
    r->calls++;
    pthread_mutex_unlock(&r->lock);
}

/* A worker: takes the next job until none is left, with its own flags. */
static void *worker(void *arg) {
    Runner *r = arg;
    uint8_t *flags = malloc(r->flags_bytes);
    for (;;) {
        size_t job;
        pthread_mutex_lock(&r->lock);
        job = r->next++;
        pthread_mutex_unlock(&r->lock);
        if (job >= r->job_count) break;
        note(r, r->run_job(r->jobs, job, flags, r->flags_bytes));
    }
    free(flags);
    return NULL;
}

static void start(Runner *r, size_t job_count, size_t flags_bytes, CorayKdRunJob run_job, void *jobs) {
    r->job_count = job_count;
    r->flags_bytes = flags_bytes;
    r->run_job = run_job;
    r->jobs = jobs;
    r->next = 0;
}

static void run_threads(void *ctx, size_t job_count, size_t flags_bytes, CorayKdRunJob run_job, void *jobs) {
    Runner *r = ctx;
    pthread_t th[THREADS];
    int i;
    start(r, job_count, flags_bytes, run_job, jobs);
    for (i = 0; i < THREADS; i++) CHECK(pthread_create(&th[i], NULL, worker, r) == 0);
    for (i = 0; i < THREADS; i++) CHECK(pthread_join(th[i], NULL) == 0);
}

static void run_reversed(void *ctx, size_t job_count, size_t flags_bytes, CorayKdRunJob run_job, void *jobs) {
    Runner *r = ctx;
    uint8_t *flags = malloc(flags_bytes);
    size_t j;
    start(r, job_count, flags_bytes, run_job, jobs);
    for (j = job_count; j-- > 0;) note(r, run_job(jobs, j, flags, flags_bytes));
    free(flags);
}

static void run_none(void *ctx, size_t job_count, size_t flags_bytes, CorayKdRunJob run_job, void *jobs) {
    start(ctx, job_count, flags_bytes, run_job, jobs);
}

/* Every misuse gets its status; job 0 then runs once, the rest in the build. */
static void run_badly(void *ctx, size_t job_count, size_t flags_bytes, CorayKdRunJob run_job, void *jobs) {
    Runner *r = ctx;
    uint8_t *flags = malloc(flags_bytes);
    start(r, job_count, flags_bytes, run_job, jobs);
    CHECK_STATUS(run_job(NULL, 0, flags, flags_bytes), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(run_job(jobs, job_count, flags, flags_bytes), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(run_job(jobs, 0, flags, flags_bytes - 1), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(run_job(jobs, 0, NULL, flags_bytes), CORAY_STATUS_NULL_POINTER);
    CHECK_STATUS(run_job(jobs, 0, r->arena, flags_bytes), CORAY_STATUS_INVALID_PARAMETER);
    CHECK_STATUS(run_job(jobs, 0, flags, flags_bytes), CORAY_STATUS_OK);
    CHECK_STATUS(run_job(jobs, 0, flags, flags_bytes), CORAY_STATUS_INVALID_PARAMETER);
    r->calls = 1;
    free(flags);
}

/* Builds with `run_jobs` (NULL: none), jobs made for `job_threads` threads,
   and checks the arena against `want`; returns the number of jobs. */
static size_t check_build(const CorayScene *scene, CorayKdRunJobs run_jobs, const char *what, const void *want,
                          size_t bytes, size_t scratch_bytes, int expect_calls, uint32_t job_threads) {
    CorayKdParams p = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    p.job_threads = job_threads;
    void *arena = arena_alloc(bytes), *scratch = arena_alloc(scratch_bytes);
    Runner r;
    memset(&r, 0, sizeof r);
    pthread_mutex_init(&r.lock, NULL);
    r.arena = arena;
    memset(arena, 0xA5, bytes);
    CHECK_STATUS(coray_kdtree_build_jobs(scene, &p, arena, bytes, scratch, scratch_bytes, NULL, run_jobs, &r),
                 CORAY_STATUS_OK);
    if (run_jobs) {
        CHECK(r.job_count >= 2 && r.job_count <= 32);
        CHECK(r.flags_bytes == scene->triangle_count + scene->sphere_count + scene->cone_count);
        CHECK_STATUS(r.worst, CORAY_STATUS_OK);
        CHECK(expect_calls < 0 ? r.calls == (int)r.job_count : r.calls == expect_calls);
    }
    if (memcmp(arena, want, bytes) != 0) {
        fprintf(stderr, "%s: the arena differs from coray_kdtree_build's\n", what);
        failures++;
    }
    pthread_mutex_destroy(&r.lock);
    free(arena);
    free(scratch);
    return r.job_count;
}

int main(void) {
    TestScene ts;
    CorayKdParams p = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    CorayRequirements req = requirements0();
    CorayKdTreeInfo info = coray_kdtree_info_default();
    Tree ref;
    rng_state = 21;
    ts = scene_random(3000, 400, 400, 1.0f);
    ref = tree_build(&ts.view, CORAY_KD_PRESET_AUTO);
    CHECK_STATUS(coray_kdtree_requirements(ts.nt + ts.ns + ts.nc, &p, &req), CORAY_STATUS_OK);
    CHECK_STATUS(coray_kdtree_info(&ref.tree, &info), CORAY_STATUS_OK);
    CHECK(info.truncated == 0);
    size_t jobs_default = check_build(&ts.view, run_threads, "4 threads", ref.arena, ref.bytes, req.scratch_bytes, -1, 0);
    check_build(&ts.view, run_reversed, "reversed", ref.arena, ref.bytes, req.scratch_bytes, -1, 0);
    check_build(&ts.view, run_none, "no job run", ref.arena, ref.bytes, req.scratch_bytes, 0, 0);
    check_build(&ts.view, run_badly, "misused", ref.arena, ref.bytes, req.scratch_bytes, 1, 0);
    check_build(&ts.view, NULL, "no runner", ref.arena, ref.bytes, req.scratch_bytes, 0, 0);
    /* Jobs made for 2 and for 16 threads: fewer and more of them, the same
       arena. */
    size_t jobs_two = check_build(&ts.view, run_threads, "made for 2", ref.arena, ref.bytes, req.scratch_bytes, -1, 2);
    size_t jobs_many = check_build(&ts.view, run_threads, "made for 16", ref.arena, ref.bytes, req.scratch_bytes, -1, 16);
    CHECK(jobs_two < jobs_default && jobs_default < jobs_many);
    free(ref.arena);
    scene_free(&ts);
    return finish("build_jobs");
}
