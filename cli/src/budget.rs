//! What the command may ask of this machine, checked before it allocates:
//! image sides (one limit for `--res` and NFF files, the core's), scene
//! sizes, threads and repeats, and the memory a job needs against the
//! memory the machine has. Every refusal names the limit.

use coray::kd::{KdEvent, KdNode, KdRequirements, KdRopes};
use coray::limits::MAX_IMAGE_SIDE;
use std::mem::size_of;

/// The share of available memory a job may plan to use.
const MEMORY_SHARE: f64 = 0.75;

/// Bytes of memory this machine has available now (`MemAvailable` of
/// /proc/meminfo; 4 GiB where that cannot be read).
pub fn available_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024)
        })
        .unwrap_or(4 << 30)
}

fn gib(b: f64) -> String {
    format!("{:.1} GiB", b / (1u64 << 30) as f64)
}

/// Refuses `what` when it needs more than [`MEMORY_SHARE`] of the
/// available memory.
pub fn check_memory(what: &str, bytes: f64) -> Result<(), String> {
    let avail = available_memory() as f64;
    if bytes > avail * MEMORY_SHARE {
        return Err(format!(
            "{what} needs about {} of memory; this machine has {} available and a job may plan \
             {:.0}% of it ({})",
            gib(bytes),
            gib(avail),
            MEMORY_SHARE * 100.0,
            gib(avail * MEMORY_SHARE)
        ));
    }
    Ok(())
}

/// One image side: 1 to the core's [`MAX_IMAGE_SIDE`].
pub fn check_side(what: &str, side: u64) -> Result<u32, String> {
    if side == 0 || side > MAX_IMAGE_SIDE as u64 {
        return Err(format!(
            "{what} must be 1 to {MAX_IMAGE_SIDE} pixels, not {side}"
        ));
    }
    Ok(side as u32)
}

/// `--threads` and `--repeat`: at least 1, at most `max`.
pub fn check_count(what: &str, n: usize, max: usize) -> Result<usize, String> {
    if n == 0 || n > max {
        return Err(format!("{what} must be 1 to {max}, not {n}"));
    }
    Ok(n)
}

/// Bytes of a kd-tree built with `req`, scratch included (the peak).
pub fn kd_bytes(req: &KdRequirements) -> f64 {
    (req.nodes * size_of::<KdNode>()
        + req.ropes * size_of::<KdRopes>()
        + req.rope_ids * 4
        + req.refs * 4
        + req.events * size_of::<KdEvent>()
        + req.prim_flags) as f64
}

/// Bytes per pixel of a benchmark or comparison: the primary ray, the
/// reference's and one method's hits, and per light a shadow ray with its
/// light index and two answers.
pub fn bytes_per_pixel(lights: usize) -> f64 {
    let ray = size_of::<coray::Ray>();
    let hit = size_of::<coray::Hit>();
    (ray + 3 * hit + lights.max(1) * (ray + size_of::<usize>() + 2)) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_named_in_refusals() {
        assert_eq!(check_side("--res", 1), Ok(1));
        let e = check_side("--res", 100_000).unwrap_err();
        assert!(e.contains("32768") && e.contains("100000"), "{e}");
        assert!(check_side("resolution", 0).is_err());
        assert!(check_count("--threads", 0, 64)
            .unwrap_err()
            .contains("1 to 64"));
        let e = check_memory("a test", 1e18).unwrap_err();
        assert!(e.contains("available"), "{e}");
        assert!(check_memory("a test", 1.0).is_ok());
    }
}
