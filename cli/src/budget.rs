//! What the command may ask of this machine, checked before it allocates:
//! image sides (one limit for `--res` and NFF files, the core's), scene
//! sizes, threads and repeats, and the memory a job needs against the
//! memory the machine has. Every refusal names the limit.

use coray::kd::{KdEvent, KdNode, KdRequirements, KdRopes};
use coray::limits::MAX_IMAGE_SIDE;
use std::mem::size_of;

/// Bytes a rendered pixel takes: its linear colour (three f32) and its
/// 8-bit RGB.
pub const IMAGE_BYTES_PER_PIXEL: f64 = 15.0;

/// The share of available memory a job may plan to use.
const MEMORY_SHARE: f64 = 0.75;

/// Bytes of memory this process may still take: the least of the
/// machine's (`MemAvailable` of /proc/meminfo), its address-space limit's
/// (`ulimit -v`: RLIMIT_AS less the process's VmSize) and its control
/// group's (cgroup v2 `memory.max` less `memory.current`, or v1
/// `memory.limit_in_bytes` less `memory.usage_in_bytes`). 4 GiB where none
/// can be read.
pub fn available_memory() -> u64 {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let machine = read("/proc/meminfo").and_then(|s| kib_field(&s, "MemAvailable:"));
    let ulimit = read("/proc/self/limits")
        .and_then(|s| address_space_limit(&s))
        .map(|lim| {
            let used = read("/proc/self/status")
                .and_then(|s| kib_field(&s, "VmSize:"))
                .unwrap_or(0);
            lim.saturating_sub(used)
        });
    let group = read("/proc/self/cgroup").and_then(|s| cgroup_room(&s, read));
    [machine, ulimit, group]
        .into_iter()
        .flatten()
        .min()
        .unwrap_or(4 << 30)
}

/// A `Name:   N kB` line of /proc/meminfo or /proc/self/status, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// The soft limit of /proc/self/limits' "Max address space" line, in
/// bytes (`None` when unlimited).
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Room left in this process's memory control group: cgroup v2's
/// `memory.max - memory.current` (the unified hierarchy's `0::PATH`
/// line), else v1's `memory.limit_in_bytes - memory.usage_in_bytes` (the
/// `N:memory:PATH` line). `None` when unlimited or unreadable.
fn cgroup_room(cgroup: &str, read: impl Fn(&str) -> Option<String>) -> Option<u64> {
    let num = |p: String| -> Option<u64> { read(&p)?.trim().parse().ok() };
    for line in cgroup.lines() {
        let mut f = line.splitn(3, ':');
        let (_, controllers, path) = (f.next()?, f.next()?, f.next()?);
        let path = path.trim_end_matches('/');
        let (max, used) = if controllers.is_empty() {
            let dir = format!("/sys/fs/cgroup{path}");
            (
                num(format!("{dir}/memory.max")),
                num(format!("{dir}/memory.current")),
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            let dir = format!("/sys/fs/cgroup/memory{path}");
            (
                num(format!("{dir}/memory.limit_in_bytes")),
                num(format!("{dir}/memory.usage_in_bytes")),
            )
        } else {
            continue;
        };
        // v1 writes "no limit" as a number near 2^63.
        if let Some(max) = max.filter(|&m| m < 1 << 60) {
            return Some(max.saturating_sub(used.unwrap_or(0)));
        }
    }
    None
}

/// A vector of `n` copies of `value`, or a message naming `what` when
/// the memory cannot be had (never an abort on a failed allocation).
pub fn try_vec<T: Clone>(what: &str, n: usize, value: T) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        format!(
            "{what} needs {} of memory, which could not be had",
            gib((n as f64) * size_of::<T>() as f64)
        )
    })?;
    v.resize(n, value);
    Ok(v)
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
            "{what} needs about {} of memory; {} is available (the least of the machine's, its \
             ulimit's and its control group's) and a job may plan {:.0}% of it ({})",
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

    #[test]
    fn limits_are_read_from_proc_and_cgroup_files() {
        assert_eq!(
            kib_field(
                "MemTotal: 9 kB\nMemAvailable:    2048 kB\n",
                "MemAvailable:"
            ),
            Some(2 << 20)
        );
        assert_eq!(
            kib_field("VmPeak: 1 kB\nVmSize:\t  4 kB\n", "VmSize:"),
            Some(4096)
        );
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         8192000000           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(8_192_000_000));
        let unlimited = limits.replace("8192000000", "unlimited");
        assert_eq!(address_space_limit(&unlimited), None);
        let files = |p: &str| {
            Some(
                match p {
                    "/sys/fs/cgroup/a/b/memory.max" => "1000\n",
                    "/sys/fs/cgroup/a/b/memory.current" => "300\n",
                    "/sys/fs/cgroup/memory/x/memory.limit_in_bytes" => "5000",
                    "/sys/fs/cgroup/memory/x/memory.usage_in_bytes" => "1000",
                    "/sys/fs/cgroup/memory/y/memory.limit_in_bytes" => "9223372036854771712",
                    "/sys/fs/cgroup/max/memory.max" => "max\n",
                    _ => return None,
                }
                .to_string(),
            )
        };
        assert_eq!(cgroup_room("0::/a/b\n", files), Some(700));
        assert_eq!(cgroup_room("4:cpu:/\n3:memory,foo:/x\n", files), Some(4000));
        assert_eq!(cgroup_room("3:memory:/y\n", files), None);
        assert_eq!(cgroup_room("0::/max\n", files), None);
        assert!(available_memory() > 0);
    }

    #[test]
    fn failed_allocations_are_messages() {
        let e = try_vec("a test", usize::MAX / 16, 0u64).unwrap_err();
        assert!(
            e.contains("a test") && e.contains("could not be had"),
            "{e}"
        );
        assert_eq!(try_vec("a test", 3, 7u8), Ok(vec![7, 7, 7]));
    }
}
