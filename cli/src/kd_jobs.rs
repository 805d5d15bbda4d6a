//! Runs a kd build's jobs on the CLI's threads: the largest first, each
//! thread taking the next one as it finishes, each with its own flags.

use coray::kd::{KdJob, KdJobs};
use std::sync::Mutex;

/// Runs `jobs` on `threads` threads (this one among them); with one thread
/// it leaves them to the build's `finish`, which runs them here anyway.
pub fn run(jobs: KdJobs<'_>, threads: usize, prim_count: usize) {
    if threads <= 1 {
        return;
    }
    let mut all: Vec<KdJob> = jobs.collect();
    // Popped from the back: the largest last in the vector.
    all.sort_by_key(KdJob::weight);
    let queue = Mutex::new(all);
    let work = || {
        let mut flags = vec![0u8; prim_count];
        loop {
            let Some(job) = queue.lock().expect("job queue").pop() else {
                return;
            };
            // Flags of the scene's length: the only error a job reports.
            job.run(&mut flags).expect("flags of the scene's length");
        }
    };
    std::thread::scope(|s| {
        for _ in 1..threads {
            s.spawn(work);
        }
        work();
    });
}
