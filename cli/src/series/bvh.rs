//! Thesis 6.3.1, view independent hierarchies: tree 1 to 11 (floor whole
//! and split), balls 1 to 4, gears 1 to 4, each hierarchy builder beside
//! the kd-tree, and the section's observations as claims.

use super::claims::{Check, Claim, Need, Scenes};
use super::{Ladder, Metric, Study};
use crate::method::Method;

/// The thesis' ladders. The split floor's k is ours (the thesis does not
/// give it): 16 x 16 pieces, each about a branch's size at tree 11.
pub const LADDERS: [Ladder; 4] = [
    Ladder {
        name: "tree",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 1,
        lights: 0,
    },
    Ladder {
        name: "tree, floor split",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 16,
        lights: 0,
    },
    Ladder {
        name: "balls",
        scene: "balls",
        sizes: 1..=4,
        floor_split: 1,
        lights: 0,
    },
    Ladder {
        name: "gears",
        scene: "gears",
        sizes: 1..=4,
        floor_split: 1,
        lights: 0,
    },
];

/// The builders compared (the quadratic `nn` makes the chain's joins and
/// takes seconds at the larger sizes) and the kd-tree as a reference.
pub const METHODS: [&str; 6] = ["kd", "tdbs", "tdbs-sah", "nn-chain", "rtree", "rstar"];

fn methods() -> Vec<Method> {
    METHODS
        .iter()
        .map(|m| Method::parse(m).expect("a registered method"))
        .collect()
}

fn plot_methods() -> Vec<String> {
    METHODS.iter().map(|m| m.to_string()).collect()
}

const METRICS: [Metric; 5] = [
    Metric::RenderS,
    Metric::BuildMs,
    Metric::ObjectsPerRay,
    Metric::CostPerBox,
    Metric::CostPerPrim,
];

/// The observations of 6.3.1.
pub const CLAIMS: [Claim; 8] = [
    Claim {
        id: "1",
        text: "TDBS ray-traces fastest of TDBS, R-tree and R*-tree at every size of every scene",
        check: Check::Smaller {
            a: "tdbs",
            b: "rtree|rstar",
            metric: Metric::RenderS,
            scenes: Scenes::Every,
            need: Need::All,
        },
    },
    Claim {
        id: "1b",
        text: "(ours) the same with TDBS-SAH in TDBS's place",
        check: Check::Smaller {
            a: "tdbs-sah",
            b: "rtree|rstar",
            metric: Metric::RenderS,
            scenes: Scenes::Every,
            need: Need::All,
        },
    },
    Claim {
        id: "2",
        text: "tree: R-tree and R*-tree behave almost identically at all sizes",
        check: Check::Close {
            a: "rtree",
            b: "rstar",
            metric: Metric::RenderS,
            scenes: Scenes::Ladder("tree"),
            within: 1.15,
        },
    },
    Claim {
        id: "3",
        text: "gears: the R*-tree is faster than the R-tree",
        check: Check::Smaller {
            a: "rstar",
            b: "rtree",
            metric: Metric::RenderS,
            scenes: Scenes::Ladder("gears"),
            need: Need::Total,
        },
    },
    Claim {
        id: "4",
        text: "balls: the R-tree is faster than the R*-tree",
        check: Check::Smaller {
            a: "rtree",
            b: "rstar",
            metric: Metric::RenderS,
            scenes: Scenes::Ladder("balls"),
            need: Need::Total,
        },
    },
    Claim {
        id: "5",
        text: "objects tested per primary ray are nearly the same in TDBS, R-tree and R*-tree",
        check: Check::Spread {
            methods: "tdbs|rtree|rstar",
            metric: Metric::ObjectsPerRay,
            within: 1.25,
        },
    },
    Claim {
        id: "5b",
        text: "and so is the cost per actual object",
        check: Check::Spread {
            methods: "tdbs|rtree|rstar",
            metric: Metric::CostPerPrim,
            within: 1.25,
        },
    },
    Claim {
        id: "6",
        text: "ray-tracing time grows with the object count least in gears, most in balls",
        check: Check::GrowthOrder {
            method: "tdbs",
            metric: Metric::RenderS,
            ladders: &["gears", "tree", "balls"],
        },
    },
];

/// The study.
pub const STUDY: Study = Study {
    table: "bvh-series",
    title: "view independent hierarchies; costs in thesis units over primary and shadow rays; \
            kd = the SAH kd-tree, for reference",
    ladders: &LADDERS,
    methods,
    metrics: &METRICS,
    plot_metrics: &METRICS,
    plot_methods,
    claims: &CLAIMS,
    section: "thesis 6.3.1",
};
