//! Replays the fuzz target's regression corpus (`fuzz/regressions/`: every
//! input that once crashed or timed out, and seeds for each family), then
//! a fixed batch of generated inputs, through the harness the fuzzer runs.

use coray::rng::SplitMix64;
use coray_fuzz_harness::run;

fn regressions() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/regressions")
}

/// Every input of `dir`, the names of those that fail.
fn replay(dir: &std::path::Path) -> (usize, Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut failed = Vec::new();
    for path in &entries {
        let data = std::fs::read(path).unwrap();
        if std::panic::catch_unwind(|| run(&data)).is_err() {
            failed.push(path.display().to_string());
        }
    }
    (entries.len(), failed)
}

/// The regression corpus; with `CORAY_REPLAY_DIR` set, that directory too
/// (a fuzzer's artifacts, to sort them).
#[test]
fn regression_corpus_replays_clean() {
    let (n, failed) = replay(&regressions());
    assert!(failed.is_empty(), "fail again: {failed:#?}");
    assert!(n >= 9, "only {n} inputs in fuzz/regressions");
    if let Ok(dir) = std::env::var("CORAY_REPLAY_DIR") {
        let (n, failed) = replay(std::path::Path::new(&dir));
        assert!(
            failed.is_empty(),
            "{} of {n} fail: {failed:#?}",
            failed.len()
        );
    }
}

/// Each family, each kind of damage, with and without a perturbed scene:
/// some arenas still validate (and must then answer as the clean one),
/// most do not; nothing panics.
#[test]
fn generated_inputs_run_clean() {
    let mut g = SplitMix64(16);
    let (mut validated, mut runs) = (0, 0);
    for family in 0..30u8 {
        for flags in 0..8u8 {
            for _ in 0..6 {
                let mut data = vec![family, flags];
                let len = 8 + g.below(200) as usize;
                data.extend((0..len).map(|_| g.next_u64() as u8));
                let r = run(&data);
                runs += 1;
                validated += usize::from(r.validated);
            }
        }
    }
    // The wide hierarchy (flag bits 4 to 7 = WIDE_FLAGS), each damage.
    let (mut wide_validated, mut wide_traced) = (0, 0);
    for flags in 0..8u8 {
        for _ in 0..30 {
            let mut data = vec![0, flags | coray_fuzz_harness::WIDE_FLAGS << 4];
            let len = 8 + g.below(200) as usize;
            data.extend((0..len).map(|_| g.next_u64() as u8));
            let r = run(&data);
            runs += 1;
            validated += usize::from(r.validated);
            wide_validated += usize::from(r.validated);
            wide_traced += usize::from(r.statuses.iter().sum::<u32>() > 4);
        }
    }
    assert!(
        wide_validated > 0 && wide_validated < 240 && wide_traced > 120,
        "wide: {wide_validated} of 240 validated, {wide_traced} traced"
    );
    assert_eq!(runs, 30 * 8 * 6 + 8 * 30);
    // Flips in padding and unused room leave a valid arena: both outcomes
    // are exercised.
    assert!(
        validated > 0 && validated < runs,
        "{validated} of {runs} validated"
    );
}

/// kd builds whose jobs a hostile runner drives (flag bit 3): indices out
/// of range, short flags, jobs run twice or never. Each arena equals the
/// clean build's (the harness asserts it); the misuse got its statuses.
#[test]
fn kd_builds_with_hostile_job_runners_match_the_clean_build() {
    let mut g = SplitMix64(17);
    let mut statuses = [0u32; coray_fuzz_harness::STATUS_COUNT];
    for family in [0u8, 3] {
        for flags in 8..16u8 {
            for _ in 0..4 {
                let mut data = vec![family, flags];
                let len = 64 + g.below(400) as usize;
                data.extend((0..len).map(|_| g.next_u64() as u8));
                let r = run(&data);
                for (s, n) in statuses.iter_mut().zip(r.run_job) {
                    *s += n;
                }
            }
        }
    }
    // Jobs ran (OK) and misuse was refused (INVALID_PARAMETER).
    assert!(statuses[0] > 0 && statuses[4] > 0, "{statuses:?}");
}

/// Scenes changed under intact arenas (flag bits 4 to 7 = SCENE_FLAGS)
/// and damaged saved files (SAVED_FLAGS), every kind of damage: the
/// harness asserts that the kd-tree refuses every changed scene, that what
/// the other families accept answers as a fresh build over it, and that
/// no damaged file opens. Both refusals are exercised.
#[test]
fn changed_scenes_and_damaged_saved_files_run_clean() {
    use coray_fuzz_harness::{SAVED_FLAGS, SCENE_FLAGS, STATUS_COUNT};
    let mut g = SplitMix64(18);
    let mut statuses = [[0u32; STATUS_COUNT]; 2];
    for (k, mode) in [SCENE_FLAGS, SAVED_FLAGS].into_iter().enumerate() {
        for flags in 0..8u8 {
            for _ in 0..20 {
                let mut data = vec![0, flags | mode << 4];
                let len = 16 + g.below(200) as usize;
                data.extend((0..len).map(|_| g.next_u64() as u8));
                let r = run(&data);
                for (s, n) in statuses[k].iter_mut().zip(r.statuses) {
                    *s += n;
                }
            }
        }
    }
    let (corrupt, damaged) = (7, 11);
    assert!(
        statuses[0][corrupt] > 0,
        "changed scenes: {:?}",
        statuses[0]
    );
    assert!(statuses[1][damaged] > 100, "saved files: {:?}", statuses[1]);
}
