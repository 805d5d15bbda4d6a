//! The thesis' observations as data: each [`Claim`] is the sentence it
//! makes and a [`Check`] from a small vocabulary (one method faster than
//! another on some scenes, two close, a spread, an order of growth, two
//! rankings that agree, one ladder faster than another), which
//! [`check`] evaluates on a study's points with the numbers that decide it.
//!
//! Methods are named by patterns: alternatives split by `|`, `*` matching
//! any text, and `$` a part that must be the same on both sides of a
//! comparison (`proj-$-2d-comb` against `proj-$-2d-2d` compares each
//! builder with itself).

use super::{find, methods, sizes, Metric, Point, Study};
use serde::Serialize;

/// Which scenes a check looks at.
#[derive(Clone, Copy, Debug)]
pub enum Scenes {
    /// Every size of every ladder.
    Every,
    /// Every size of one ladder.
    Ladder(&'static str),
    /// The largest size of one ladder.
    Largest(&'static str),
    /// Of the largest size of each ladder, the one with the least 2D overlap.
    LeastOverlap,
    /// Of the largest size of each ladder, the one with the most 2D overlap.
    MostOverlap,
}

/// How many comparisons must hold.
#[derive(Clone, Copy, Debug)]
pub enum Need {
    /// Every one.
    All,
    /// More than half.
    Majority,
    /// At least this many.
    AtLeast(usize),
    /// The sums over all scenes (not each scene) compare so.
    Total,
}

/// What is checked.
#[derive(Clone, Copy, Debug)]
pub enum Check {
    /// The best of `a` has a smaller `metric` than the best of `b`, per
    /// scene and per binding of `$`.
    Smaller {
        /// Methods that should be smaller.
        a: &'static str,
        /// Methods they are compared with.
        b: &'static str,
        /// What is compared.
        metric: Metric,
        /// Where.
        scenes: Scenes,
        /// How often.
        need: Need,
    },
    /// `a` and `b` within a factor `within` of each other on every scene.
    Close {
        /// One method.
        a: &'static str,
        /// The other.
        b: &'static str,
        /// What is compared.
        metric: Metric,
        /// Where.
        scenes: Scenes,
        /// The largest ratio allowed.
        within: f64,
    },
    /// On every scene, the largest over the smallest `metric` among
    /// `methods` is at most `within`.
    Spread {
        /// The methods.
        methods: &'static str,
        /// What is compared.
        metric: Metric,
        /// The largest ratio allowed.
        within: f64,
    },
    /// The growth of `metric` with the object count (slope of log over
    /// log) of `method` rises along `ladders`.
    GrowthOrder {
        /// The method.
        method: &'static str,
        /// What grows.
        metric: Metric,
        /// The ladders, slowest growth first.
        ladders: &'static [&'static str],
    },
    /// At the largest size of each ladder, the ladder where `cause` is
    /// largest is the one where `effect` (mean over `methods`) is largest.
    SameLargest {
        /// The driving figure (of any method's point).
        cause: Metric,
        /// The figure that should follow it.
        effect: Metric,
        /// Whose `effect` is averaged.
        methods: &'static str,
    },
    /// At the largest size both ladders have, more than half of all
    /// methods have a smaller `metric` in `faster` than in `slower`.
    LadderSmaller {
        /// The ladder that should be faster.
        faster: &'static str,
        /// The other.
        slower: &'static str,
        /// What is compared.
        metric: Metric,
    },
}

/// One observation of the thesis.
#[derive(Clone, Copy, Debug)]
pub struct Claim {
    /// Its number in the output.
    pub id: &'static str,
    /// What the thesis says.
    pub text: &'static str,
    /// How it is checked.
    pub check: Check,
}

/// A claim checked: confirmed or not, with the numbers.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// The claim's number.
    pub id: &'static str,
    /// What the thesis says.
    pub text: &'static str,
    /// `Some(true)`: confirmed; `Some(false)`: not; `None`: the points
    /// do not decide it (sizes left out).
    pub confirmed: Option<bool>,
    /// The numbers that decide it.
    pub evidence: String,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = match self.confirmed {
            Some(true) => "confirmed",
            Some(false) => "not confirmed",
            None => "undecided",
        };
        write!(f, "{}. {}: {v} ({})", self.id, self.text, self.evidence)
    }
}

/// Whether `name` matches the one-alternative pattern `pat` (`*` any
/// text, `$` a part that is returned).
fn matches<'n>(pat: &str, name: &'n str) -> Option<Option<&'n str>> {
    fn go<'n>(p: &[u8], n: &'n str, at: usize, bound: Option<&'n str>) -> Option<Option<&'n str>> {
        let rest = &n.as_bytes()[at..];
        match p.first() {
            None => rest.is_empty().then_some(bound),
            Some(b'*') | Some(b'$') => {
                for end in (at..=n.len()).rev() {
                    let b = if p[0] == b'$' {
                        Some(&n[at..end])
                    } else {
                        bound
                    };
                    if let Some(r) = go(&p[1..], n, end, b) {
                        return Some(r);
                    }
                }
                None
            }
            Some(c) => (rest.first() == Some(c)).then(|| go(&p[1..], n, at + 1, bound))?,
        }
    }
    go(pat.as_bytes(), name, 0, None)
}

/// The methods of `all` that `pattern` selects under `binding` (`None`:
/// the alternatives without `$`).
fn select<'a>(pattern: &str, binding: Option<&str>, all: &'a [String]) -> Vec<&'a str> {
    all.iter()
        .map(String::as_str)
        .filter(|m| {
            pattern
                .split('|')
                .any(|alt| match (matches(alt, m), binding) {
                    (Some(None), None) => !alt.contains('$'),
                    (Some(Some(b)), Some(want)) => b == want,
                    _ => false,
                })
        })
        .collect()
}

/// The bindings of `$` in `pattern` over `all`, and `None` when an
/// alternative without `$` selects something.
fn bindings(pattern: &str, all: &[String]) -> Vec<Option<String>> {
    let mut v: Vec<Option<String>> = Vec::new();
    for m in all {
        for alt in pattern.split('|') {
            if let Some(b) = matches(alt, m) {
                let b = b.map(str::to_string);
                if !v.contains(&b) {
                    v.push(b);
                }
            }
        }
    }
    v
}

/// The scenes (ladder, size) `s` names.
fn scenes(s: Scenes, study: &Study, pts: &[Point]) -> Vec<(&'static str, u32)> {
    let largest = |l: &'static str| sizes(pts, l).last().map(|&s| (l, s));
    match s {
        Scenes::Every => study
            .ladders
            .iter()
            .flat_map(|l| sizes(pts, l.name).into_iter().map(move |s| (l.name, s)))
            .collect(),
        Scenes::Ladder(l) => sizes(pts, l).into_iter().map(|s| (l, s)).collect(),
        Scenes::Largest(l) => largest(l).into_iter().collect(),
        Scenes::LeastOverlap | Scenes::MostOverlap => {
            let mut v: Vec<(f64, (&'static str, u32))> = study
                .ladders
                .iter()
                .filter_map(|l| {
                    let (n, s) = largest(l.name)?;
                    let p = pts.iter().find(|p| p.ladder == n && p.size == s)?;
                    Some((p.overlap, (n, s)))
                })
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let pick = if matches!(s, Scenes::LeastOverlap) {
                v.first()
            } else {
                v.last()
            };
            pick.map(|p| p.1).into_iter().collect()
        }
    }
}

/// The smallest `metric` among `methods` on one scene, with its method.
fn best<'a>(
    pts: &[Point],
    (l, s): (&str, u32),
    methods: &[&'a str],
    metric: Metric,
) -> Option<(f64, &'a str)> {
    methods
        .iter()
        .filter_map(|m| Some((metric.of(find(pts, l, s, m)?)?, *m)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// Slope of log(y) against log(x) by least squares: the growth rate.
pub fn slope(v: &[(f64, f64)]) -> f64 {
    let n = v.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = v.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let cov: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    cov / var.max(1e-12)
}

/// Evaluates one claim on a study's points.
pub fn check(claim: &Claim, study: &Study, pts: &[Point]) -> Verdict {
    let all = methods(pts);
    let (confirmed, evidence) = match claim.check {
        Check::Smaller {
            a,
            b,
            metric,
            scenes: sc,
            need,
        } => {
            let (mut wins, mut total) = (0usize, 0usize);
            let (mut sum_a, mut sum_b) = (0.0, 0.0);
            let mut worst: Option<(f64, String)> = None;
            for scene in scenes(sc, study, pts) {
                for bind in bindings(a, &all) {
                    let (sa, sb) = (
                        select(a, bind.as_deref(), &all),
                        select(b, bind.as_deref(), &all),
                    );
                    let (Some((va, _)), Some((vb, mb))) =
                        (best(pts, scene, &sa, metric), best(pts, scene, &sb, metric))
                    else {
                        continue;
                    };
                    total += 1;
                    wins += usize::from(va < vb);
                    sum_a += va;
                    sum_b += vb;
                    let margin = vb / va;
                    if worst.as_ref().is_none_or(|w| margin < w.0) {
                        worst = Some((margin, format!("{} {} against {mb}", scene.0, scene.1)));
                    }
                }
            }
            let ok = match need {
                Need::All => wins == total,
                Need::Majority => wins * 2 > total,
                Need::AtLeast(k) => wins >= k,
                Need::Total => sum_a < sum_b,
            };
            let detail = match (need, worst) {
                (Need::Total, _) => format!(
                    "{} summed over {total} scenes: {sum_a:.3} against {sum_b:.3}",
                    metric.name()
                ),
                (_, Some((m, at))) => format!(
                    "smaller in {wins} of {total}; smallest margin (other / it) {m:.2} at {at}"
                ),
                _ => String::new(),
            };
            ((total > 0).then_some(ok), detail)
        }
        Check::Close {
            a,
            b,
            metric,
            scenes: sc,
            within,
        } => {
            let mut ratios = Vec::new();
            for (l, s) in scenes(sc, study, pts) {
                let get = |m| find(pts, l, s, m).and_then(|p| metric.of(p));
                if let (Some(x), Some(y)) = (get(a), get(b)) {
                    ratios.push(y / x);
                }
            }
            let ok = ratios.iter().all(|r| r.max(1.0 / r) <= within);
            let list: Vec<String> = ratios.iter().map(|r| format!("{r:.2}")).collect();
            (
                (!ratios.is_empty()).then_some(ok),
                format!(
                    "{b} / {a} per scene: {}; allowed within {within}",
                    list.join(" ")
                ),
            )
        }
        Check::Spread {
            methods: ms,
            metric,
            within,
        } => {
            let sel = select(ms, None, &all);
            let mut worst: Option<(f64, String)> = None;
            for (l, s) in scenes(Scenes::Every, study, pts) {
                let v: Vec<f64> = sel
                    .iter()
                    .filter_map(|m| metric.of(find(pts, l, s, m)?))
                    .collect();
                let (lo, hi) = v
                    .iter()
                    .fold((f64::MAX, 0f64), |(a, b), &x| (a.min(x), b.max(x)));
                if lo > 0.0 && worst.as_ref().is_none_or(|w| hi / lo > w.0) {
                    worst = Some((hi / lo, format!("{l} {s}")));
                }
            }
            match worst {
                Some((r, at)) => (
                    Some(r <= within),
                    format!("largest max / min {r:.2} at {at}; allowed {within}"),
                ),
                None => (None, "no scene".into()),
            }
        }
        Check::GrowthOrder {
            method,
            metric,
            ladders,
        } => {
            let growth: Vec<Option<f64>> = ladders
                .iter()
                .map(|l| {
                    let v: Vec<(f64, f64)> = sizes(pts, l)
                        .into_iter()
                        .filter_map(|s| {
                            let p = find(pts, l, s, method)?;
                            Some((p.objects as f64, metric.of(p)?))
                        })
                        .collect();
                    (v.len() >= 2).then(|| slope(&v))
                })
                .collect();
            let shown: Vec<String> = ladders
                .iter()
                .zip(&growth)
                .map(|(l, g)| format!("{l} {}", g.map_or("-".into(), |g| format!("{g:.3}"))))
                .collect();
            let known: Option<Vec<f64>> = growth.into_iter().collect();
            (
                known.map(|g| g.windows(2).all(|w| w[0] < w[1])),
                format!(
                    "slopes of log {} over log objects: {}",
                    metric.name(),
                    shown.join(", ")
                ),
            )
        }
        Check::SameLargest {
            cause,
            effect,
            methods: ms,
        } => {
            let sel = select(ms, None, &all);
            let mut rows = Vec::new();
            for l in study.ladders {
                let Some(&s) = sizes(pts, l.name).last() else {
                    continue;
                };
                let e: Vec<f64> = sel
                    .iter()
                    .filter_map(|m| effect.of(find(pts, l.name, s, m)?))
                    .collect();
                let c = pts
                    .iter()
                    .find(|p| p.ladder == l.name && p.size == s)
                    .and_then(|p| cause.of(p));
                if let (Some(c), false) = (c, e.is_empty()) {
                    rows.push((l.name, c, e.iter().sum::<f64>() / e.len() as f64));
                }
            }
            let top = |f: fn(&(&str, f64, f64)) -> f64| {
                rows.iter()
                    .max_by(|a, b| f(a).total_cmp(&f(b)))
                    .map(|r| r.0)
            };
            let shown: Vec<String> = rows
                .iter()
                .map(|(l, c, e)| format!("{l}: {} {c:.2}, {} {e:.3}", cause.name(), effect.name()))
                .collect();
            (
                (!rows.is_empty()).then(|| top(|r| r.1) == top(|r| r.2)),
                shown.join("; "),
            )
        }
        Check::LadderSmaller {
            faster,
            slower,
            metric,
        } => {
            let common = sizes(pts, slower)
                .into_iter()
                .filter(|s| sizes(pts, faster).contains(s))
                .max();
            match common {
                None => (None, "the two ladders share no size".into()),
                Some(s) => {
                    let n = all.len();
                    let wins = all
                        .iter()
                        .filter(|m| {
                            let v = |l| find(pts, l, s, m).and_then(|p| metric.of(p));
                            matches!((v(faster), v(slower)), (Some(a), Some(b)) if a < b)
                        })
                        .count();
                    (
                        Some(wins * 2 > n),
                        format!("size {s}: smaller in `{faster}` for {wins} of {n} methods"),
                    )
                }
            }
        }
    };
    Verdict {
        id: claim.id,
        text: claim.text,
        confirmed,
        evidence,
    }
}

/// Every claim of a study, checked.
pub fn check_all(study: &Study, pts: &[Point]) -> Vec<Verdict> {
    study.claims.iter().map(|c| check(c, study, pts)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_bind_and_match() {
        assert_eq!(
            matches("proj-$-2d-comb", "proj-nn-chain-2d-comb"),
            Some(Some("nn-chain"))
        );
        assert_eq!(matches("proj-*-2d", "proj-rtree-dummy-2d"), Some(None));
        assert_eq!(matches("tdbs", "tdbs-sah"), None);
        assert_eq!(matches("tdbs", "tdbs"), Some(None));
        let all: Vec<String> = [
            "tdbs",
            "rtree",
            "proj-tdbs-2d-2d",
            "proj-rtree-2d-2d",
            "proj-rtree-2d-comb",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        assert_eq!(select("rtree|proj-rtree-$", None, &all), vec!["rtree"]);
        assert_eq!(
            select("rtree|proj-rtree-$", Some("2d-2d"), &all),
            vec!["proj-rtree-2d-2d"]
        );
        assert_eq!(
            bindings("tdbs|proj-tdbs-$", &all),
            vec![None, Some("2d-2d".to_string())]
        );
        assert_eq!(
            select("proj-$-2d-comb", Some("rtree"), &all),
            vec!["proj-rtree-2d-comb"]
        );
    }

    fn pt(ladder: &'static str, size: u32, method: &str, render_s: f64) -> Point {
        Point {
            ladder,
            size,
            objects: 10 * size as usize,
            method: method.into(),
            build_ms: 1.0,
            split: None,
            render_s,
            render_rays: 0,
            objects_per_ray: Some(1.0),
            cost_per_box: None,
            cost_per_prim: None,
            shadow_s: 1.0,
            shadow_uniform_s: None,
            mismatches: 0,
            overlap: size as f64,
            secondary_per_primary: 0.0,
        }
    }

    /// A claim is confirmed by numbers that bear it out and refuted by
    /// numbers that do not.
    #[test]
    fn smaller_decides_both_ways() {
        let study = &super::super::bvh::STUDY;
        let claim = Claim {
            id: "t",
            text: "tdbs fastest",
            check: Check::Smaller {
                a: "tdbs",
                b: "rtree|rstar",
                metric: Metric::RenderS,
                scenes: Scenes::Every,
                need: Need::All,
            },
        };
        let mut pts = vec![
            pt("balls", 1, "tdbs", 1.0),
            pt("balls", 1, "rtree", 2.0),
            pt("balls", 1, "rstar", 1.5),
            pt("balls", 2, "tdbs", 2.0),
            pt("balls", 2, "rtree", 3.0),
            pt("balls", 2, "rstar", 2.5),
        ];
        let v = check(&claim, study, &pts);
        assert_eq!(v.confirmed, Some(true), "{v}");
        assert!(
            v.evidence.contains("2 of 2") && v.evidence.contains("1.25"),
            "{v}"
        );
        pts[5].render_s = 1.9;
        assert_eq!(check(&claim, study, &pts).confirmed, Some(false));
        assert_eq!(check(&claim, study, &[]).confirmed, None);
    }
}
