//! Every method the command knows, in one registry: a [`Method`] parses and
//! prints its own name, and says how it is built ([`crate::built`]). The
//! help texts, the error messages, `render --accel`, `bench --methods` and
//! the tables all take their names from here.

use coray::bvh::{Builder, RTreeParams};
use coray::kd::{KdParams, Traversal};
use coray::lcts::Scheme;
use coray::owned::BvhBuild;
use coray::proj::{Criteria, ProjBuilder, ProjScheme};
use coray_scenes::nff::shown;
use std::fmt;

/// A kd-tree build preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// SAH termination, depth bound from N.
    Auto,
    /// The LCTS paper's: depth 16, leaves of 2.
    Paper,
    /// `auto` without the empty leaves beside full ones (no ropes).
    Compact,
}

impl Preset {
    /// The names, for help and errors.
    pub const NAMES: [&'static str; 3] = ["auto", "paper", "compact"];

    /// Parses `auto`, `paper` or `compact`.
    pub fn parse(s: &str) -> Result<Preset, String> {
        match s {
            "auto" => Ok(Preset::Auto),
            "paper" => Ok(Preset::Paper),
            "compact" => Ok(Preset::Compact),
            _ => Err(format!(
                "unknown preset `{}` (have: {})",
                shown(s),
                Preset::NAMES.join(", ")
            )),
        }
    }

    /// The build parameters.
    pub fn params(self) -> KdParams {
        match self {
            Preset::Auto => KdParams::auto(),
            Preset::Paper => KdParams::paper(),
            Preset::Compact => KdParams::compact(),
        }
    }

    /// The C preset and `omit_ropes` of these parameters (ropes kept when
    /// `ropes`, where the preset has none; a compact tree never has them).
    pub fn c_params(self, ropes: bool) -> (coray_ffi::CorayKdPreset, u32) {
        match self {
            Preset::Auto => (coray_ffi::CORAY_KD_PRESET_AUTO, !ropes as u32),
            Preset::Paper => (coray_ffi::CORAY_KD_PRESET_PAPER, !ropes as u32),
            Preset::Compact => (coray_ffi::CORAY_KD_PRESET_AUTO, 2),
        }
    }
}

/// Most primitives a leaf entry of the `wide` method holds (the surface
/// area heuristic decides below it): the library's default.
pub const WIDE_LEAF_SIZE: u32 = coray::wide::DEFAULT_LEAF_SIZE;

/// The hierarchy builders by name.
pub const BVH_NAMES: [(&str, BvhBuild); 7] = [
    ("tdbs", BvhBuild::Static(Builder::Tdbs, 1)),
    ("tdbs-sah", BvhBuild::Static(Builder::TdbsSah, 1)),
    ("nn", BvhBuild::Static(Builder::Nn, 1)),
    ("nn-chain", BvhBuild::Static(Builder::NnChain, 1)),
    ("rtree", BvhBuild::RTree(RTreeParams::rtree())),
    ("rstar", BvhBuild::RTree(RTreeParams::rstar())),
    (
        "rstar-reinsert",
        BvhBuild::RTree(RTreeParams {
            forced_reinsert: true,
            ..RTreeParams::rstar()
        }),
    ),
];

/// The builders a projection hierarchy is made with, by name.
pub const PROJ_BUILDERS: [&str; 4] = ["tdbs", "nn-chain", "rtree", "rstar"];

/// How Embree is called in a benchmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeCall {
    /// `rtcIntersect1` / `rtcOccluded1`, one ray at a time.
    One,
    /// `rtcIntersect8` / `rtcOccluded8` on packets of 8 (4 x 2 pixel blocks
    /// of primary rays; 8 consecutive rays of the other sets).
    Eight,
}

/// A projection method: builder, criteria, scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjMethod {
    /// The builder.
    pub builder: ProjBuilder,
    /// What the structure is built on.
    pub criteria: Criteria,
    /// How nodes are tested.
    pub scheme: ProjScheme,
    /// The builder's name (also the global 3D hierarchy's).
    pub builder_name: &'static str,
}

/// How a structure traced through the C ABI gets its rays (names of the
/// kd-tree's calls; the wide hierarchy's alike, `coray_wide_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CCalls {
    /// One `coray_kdtree_intersect` / `_occluded` call per chunk of rays
    /// (`kd-c`, `wide-c`).
    Arrays,
    /// One `coray_kdtree_tracer_intersect1` / `_occluded1` call per ray on a
    /// tracer per thread (`kd-c1`, `wide-c1`): what a renderer tracing one
    /// ray at a time should call.
    Tracer,
    /// One `coray_kdtree_intersect1` / `_occluded1` call per ray with the
    /// handle and stack, checked in full on every call (`kd-c1-handle`,
    /// `wide-c1-handle`).
    Handle,
}

impl CCalls {
    /// The suffix of the method names (`kd-c1`: `-c1`).
    fn suffix(self) -> &'static str {
        match self {
            CCalls::Arrays => "-c",
            CCalls::Tracer => "-c1",
            CCalls::Handle => "-c1-handle",
        }
    }

    fn of_suffix(s: &str) -> Option<CCalls> {
        [CCalls::Arrays, CCalls::Tracer, CCalls::Handle]
            .into_iter()
            .find(|c| c.suffix() == s)
    }
}

/// One way of tracing rays that the command can build and time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// A kd-tree traced ray by ray: the preset (`None`: the command's
    /// `--preset`) and the traversal.
    Kd {
        /// Build preset, or the command's.
        preset: Option<Preset>,
        /// Hierarchical or ropes.
        traversal: Traversal,
    },
    /// A kd-tree built, opened and traced through the C ABI with the
    /// command's preset, hierarchically: what a C caller pays per call.
    KdC {
        /// How the rays are handed over.
        calls: CCalls,
    },
    /// The wide hierarchy built (default parameters), opened and traced
    /// through the C ABI.
    WideC {
        /// How the rays are handed over.
        calls: CCalls,
    },
    /// A kd-tree casting the camera's image by an LCTS scheme.
    Cast {
        /// The scheme (hierarchical and rope casts are its references).
        scheme: Scheme,
    },
    /// A bounding volume hierarchy.
    Bvh {
        /// Its name in [`BVH_NAMES`].
        name: &'static str,
        /// How it is built.
        build: BvhBuild,
    },
    /// The wide (8-ary) hierarchy collapsed from the binary SAH one.
    Wide {
        /// Most primitives per leaf entry.
        leaf_size: u32,
        /// Arrays traced in packets of eight coherent rays (`wide-packet`).
        packets: bool,
    },
    /// Projection hierarchies (camera, light planes) and a global 3D one.
    Proj(ProjMethod),
    /// Intel Embree 3, the reference (needs feature `embree`).
    Embree(EmbreeCall),
}

impl Method {
    /// Every method of this build, in table order: the kd-tree's, the LCTS
    /// casts, the hierarchies, Embree's.
    pub fn all() -> Vec<Method> {
        let mut v = vec![
            Method::kd(Traversal::Hierarchical),
            Method::kd(Traversal::Ropes),
            Method::kd(Traversal::Packets),
        ];
        v.extend(Method::casts());
        // The image cast in packet tiles: the casts' fastest, beside them.
        v.push(Method::Cast {
            scheme: Scheme::Packets,
        });
        v.extend(
            BVH_NAMES
                .iter()
                .map(|&(name, build)| Method::Bvh { name, build }),
        );
        v.push(Method::wide());
        v.push(Method::wide_packets());
        if cfg!(feature = "embree") {
            v.push(Method::Embree(EmbreeCall::One));
            v.push(Method::Embree(EmbreeCall::Eight));
        }
        v
    }

    /// The kd-tree with the command's preset.
    pub fn kd(traversal: Traversal) -> Method {
        Method::Kd {
            preset: None,
            traversal,
        }
    }

    /// The wide hierarchy with its default leaves.
    pub fn wide() -> Method {
        Method::Wide {
            leaf_size: WIDE_LEAF_SIZE,
            packets: false,
        }
    }

    /// The wide hierarchy tracing arrays in packets of eight.
    pub fn wide_packets() -> Method {
        Method::Wide {
            leaf_size: WIDE_LEAF_SIZE,
            packets: true,
        }
    }

    /// The kd-tree the LCTS casts walk: the command's preset, with ropes
    /// (traced by them when used as a ray method).
    pub fn kd_for_casts() -> Method {
        Method::kd(Traversal::Ropes)
    }

    /// The four LCTS image casts with the paper's windows.
    pub fn casts() -> Vec<Method> {
        [
            Scheme::Slcts1d { n: 5 },
            Scheme::Slcts2d { n: 5, m: 5 },
            Scheme::Hlcts1d,
            Scheme::Hlcts2d,
        ]
        .into_iter()
        .map(|scheme| Method::Cast { scheme })
        .collect()
    }

    /// Every projection method: 2D criteria with the three schemes; dummy
    /// (3D structure) with 2D and combination (its 3D scheme is the plain
    /// 3D hierarchy).
    pub fn projections() -> Vec<Method> {
        let mut v = Vec::new();
        for b in PROJ_BUILDERS {
            for (c, schemes) in [
                (
                    Criteria::TwoD,
                    &[
                        ProjScheme::TwoD,
                        ProjScheme::ThreeD,
                        ProjScheme::Combination,
                    ][..],
                ),
                (
                    Criteria::Dummy,
                    &[ProjScheme::TwoD, ProjScheme::Combination][..],
                ),
            ] {
                for &s in schemes {
                    v.push(Method::Proj(ProjMethod {
                        builder: proj_builder(b),
                        criteria: c,
                        scheme: s,
                        builder_name: b,
                    }));
                }
            }
        }
        v
    }

    /// The names of every method family, for help texts and errors.
    pub fn help() -> String {
        let names: Vec<String> = Method::all().iter().map(|m| m.to_string()).collect();
        format!(
            "{}, kd-paper, kd-paper-rope, kd-paper-packet, kd-compact, kd-compact-packet, kd-c, kd-c1, kd-c1-handle, wide-packet, wide-c, wide-c1, wide-c1-handle, \
             slcts1d:N, slcts2d:NxM, wide:N, wide-packet:N, \
             and proj-BUILDER-CRITERIA-SCHEME (BUILDER {}, CRITERIA 2d|dummy, SCHEME 2d|3d|comb)",
            names.join(", "),
            PROJ_BUILDERS.join("|")
        )
    }

    /// Parses a method name.
    pub fn parse(s: &str) -> Result<Method, String> {
        Method::try_parse(s)
            .ok_or_else(|| format!("unknown method `{}` (have: {})", shown(s), Method::help()))
    }

    fn try_parse(s: &str) -> Option<Method> {
        let kd = |preset, traversal| Some(Method::Kd { preset, traversal });
        match s {
            "kd" => return kd(None, Traversal::Hierarchical),
            "kd-rope" => return kd(None, Traversal::Ropes),
            "kd-paper" => return kd(Some(Preset::Paper), Traversal::Hierarchical),
            "kd-paper-rope" => return kd(Some(Preset::Paper), Traversal::Ropes),
            "kd-auto" => return kd(Some(Preset::Auto), Traversal::Hierarchical),
            "kd-auto-rope" => return kd(Some(Preset::Auto), Traversal::Ropes),
            "kd-packet" => return kd(None, Traversal::Packets),
            "kd-paper-packet" => return kd(Some(Preset::Paper), Traversal::Packets),
            "kd-auto-packet" => return kd(Some(Preset::Auto), Traversal::Packets),
            "kd-compact" => return kd(Some(Preset::Compact), Traversal::Hierarchical),
            "kd-compact-rope" => return kd(Some(Preset::Compact), Traversal::Ropes),
            "kd-compact-packet" => return kd(Some(Preset::Compact), Traversal::Packets),
            "slcts1d" => return cast(Scheme::Slcts1d { n: 5 }),
            "slcts2d" => return cast(Scheme::Slcts2d { n: 5, m: 5 }),
            "hlcts1d" => return cast(Scheme::Hlcts1d),
            "hlcts2d" => return cast(Scheme::Hlcts2d),
            "cast-packets" => return cast(Scheme::Packets),
            "wide" => return Some(Method::wide()),
            "wide-packet" => return Some(Method::wide_packets()),
            "embree" => return Some(Method::Embree(EmbreeCall::One)),
            "embree8" => return Some(Method::Embree(EmbreeCall::Eight)),
            _ => {}
        }
        if let Some(calls) = s.strip_prefix("kd").and_then(CCalls::of_suffix) {
            return Some(Method::KdC { calls });
        }
        if let Some(calls) = s.strip_prefix("wide").and_then(CCalls::of_suffix) {
            return Some(Method::WideC { calls });
        }
        let window = |v: &str| v.parse::<u32>().ok().filter(|&n| (2..=1024).contains(&n));
        if let Some(n) = s.strip_prefix("slcts1d:") {
            return cast(Scheme::Slcts1d { n: window(n)? });
        }
        let leaf_size = |n: &str| n.parse::<u32>().ok().filter(|&n| (1..=64).contains(&n));
        if let Some(n) = s.strip_prefix("wide:") {
            return Some(Method::Wide {
                leaf_size: leaf_size(n)?,
                packets: false,
            });
        }
        if let Some(n) = s.strip_prefix("wide-packet:") {
            return Some(Method::Wide {
                leaf_size: leaf_size(n)?,
                packets: true,
            });
        }
        if let Some(nm) = s.strip_prefix("slcts2d:") {
            let (n, m) = nm.split_once('x')?;
            return cast(Scheme::Slcts2d {
                n: window(n)?,
                m: window(m)?,
            });
        }
        if let Some(&(name, build)) = BVH_NAMES.iter().find(|(n, _)| *n == s) {
            return Some(Method::Bvh { name, build });
        }
        let rest = s.strip_prefix("proj-")?;
        let (b, rest) = PROJ_BUILDERS.iter().find_map(|b| {
            rest.strip_prefix(b)
                .and_then(|r| r.strip_prefix('-'))
                .map(|r| (*b, r))
        })?;
        let (c, sc) = rest.split_once('-')?;
        let criteria = match c {
            "2d" => Criteria::TwoD,
            "dummy" => Criteria::Dummy,
            _ => return None,
        };
        let scheme = match sc {
            "2d" => ProjScheme::TwoD,
            "3d" if criteria == Criteria::TwoD => ProjScheme::ThreeD,
            "comb" => ProjScheme::Combination,
            _ => return None,
        };
        Some(Method::Proj(ProjMethod {
            builder: proj_builder(b),
            criteria,
            scheme,
            builder_name: b,
        }))
    }

    /// Whether this method is available in this build.
    pub fn available(&self) -> Result<(), String> {
        if matches!(self, Method::Embree(_)) && !cfg!(feature = "embree") {
            return Err(format!(
                "method `{self}` needs Embree: build coray with `--features embree` \
                 (Debian's libembree-dev)"
            ));
        }
        Ok(())
    }
}

fn cast(scheme: Scheme) -> Option<Method> {
    Some(Method::Cast { scheme })
}

fn proj_builder(name: &str) -> ProjBuilder {
    match name {
        "tdbs" => ProjBuilder::Static(Builder::Tdbs),
        "nn-chain" => ProjBuilder::Static(Builder::NnChain),
        "rtree" => ProjBuilder::RTree(RTreeParams::rtree()),
        _ => ProjBuilder::RTree(RTreeParams::rstar()),
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Method::Kd { preset, traversal } => {
                let p = match preset {
                    None => "",
                    Some(Preset::Auto) => "-auto",
                    Some(Preset::Paper) => "-paper",
                    Some(Preset::Compact) => "-compact",
                };
                let t = match traversal {
                    Traversal::Hierarchical => "",
                    Traversal::Ropes => "-rope",
                    Traversal::Packets => "-packet",
                };
                write!(f, "kd{p}{t}")
            }
            Method::KdC { calls } => write!(f, "kd{}", calls.suffix()),
            Method::WideC { calls } => write!(f, "wide{}", calls.suffix()),
            Method::Cast { scheme } => match scheme {
                Scheme::Slcts1d { n: 5 } => f.write_str("slcts1d"),
                Scheme::Slcts1d { n } => write!(f, "slcts1d:{n}"),
                Scheme::Slcts2d { n: 5, m: 5 } => f.write_str("slcts2d"),
                Scheme::Slcts2d { n, m } => write!(f, "slcts2d:{n}x{m}"),
                Scheme::Hlcts1d => f.write_str("hlcts1d"),
                Scheme::Hlcts2d => f.write_str("hlcts2d"),
                Scheme::Hierarchical => f.write_str("cast-hierarchical"),
                Scheme::Ropes => f.write_str("cast-ropes"),
                Scheme::Packets => f.write_str("cast-packets"),
            },
            Method::Bvh { name, .. } => f.write_str(name),
            Method::Wide {
                leaf_size: WIDE_LEAF_SIZE,
                packets: false,
            } => f.write_str("wide"),
            Method::Wide {
                leaf_size: WIDE_LEAF_SIZE,
                packets: true,
            } => f.write_str("wide-packet"),
            Method::Wide {
                leaf_size,
                packets: false,
            } => write!(f, "wide:{leaf_size}"),
            Method::Wide {
                leaf_size,
                packets: true,
            } => write!(f, "wide-packet:{leaf_size}"),
            Method::Proj(p) => {
                let c = match p.criteria {
                    Criteria::TwoD => "2d",
                    Criteria::Dummy => "dummy",
                };
                let s = match p.scheme {
                    ProjScheme::TwoD => "2d",
                    ProjScheme::ThreeD => "3d",
                    ProjScheme::Combination => "comb",
                };
                write!(f, "proj-{}-{c}-{s}", p.builder_name)
            }
            Method::Embree(EmbreeCall::One) => f.write_str("embree"),
            Method::Embree(EmbreeCall::Eight) => f.write_str("embree8"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every method prints a name that parses back to it.
    #[test]
    fn names_round_trip() {
        let mut all = Method::all();
        all.extend(Method::projections());
        all.push(Method::Cast {
            scheme: Scheme::Slcts2d { n: 7, m: 3 },
        });
        all.push(Method::Cast {
            scheme: Scheme::Slcts1d { n: 9 },
        });
        all.push(Method::Wide {
            leaf_size: 8,
            packets: false,
        });
        all.push(Method::Wide {
            leaf_size: 4,
            packets: true,
        });
        for m in [
            "kd-paper",
            "kd-paper-rope",
            "kd-paper-packet",
            "kd-compact",
            "kd-compact-rope",
            "kd-compact-packet",
            "embree",
            "embree8",
            "kd-c",
            "kd-c1",
            "kd-c1-handle",
            "wide-c",
            "wide-c1",
            "wide-c1-handle",
        ] {
            all.push(Method::parse(m).unwrap());
        }
        for m in all {
            assert_eq!(Method::parse(&m.to_string()), Ok(m), "{m}");
        }
        assert_eq!(Method::projections().len(), 20);
    }

    /// Malformed names are refused with the list of names.
    #[test]
    fn bad_names_are_refused() {
        for bad in [
            "slcts2d:7",
            "slcts2d:7x",
            "slcts1d:",
            "slcts1d:-2",
            "slcts1d:1",
            "wide:0",
            "wide:65",
            "wide:",
            "wide-packet:0",
            "wide-packet:",
            "wide-c2",
            "kd-c1-",
            "hlcts2d:4x4",
            "proj-tdbs-dummy-3d",
            "proj-x-2d-2d",
            "kdd",
        ] {
            let e = Method::parse(bad).unwrap_err();
            assert!(
                e.contains("rstar-reinsert") && e.contains("proj-BUILDER"),
                "{bad}: {e}"
            );
        }
    }
}
