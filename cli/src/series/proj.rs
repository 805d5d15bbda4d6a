//! Thesis chapter 6, projection hierarchies: tree 1 to 11 (floor whole and
//! split, 7 lights; floor whole, 1 light), balls 1 to 4, gears 1 to 4,
//! every projection method beside the 3D hierarchies, and the conclusions
//! of section 6.4 as claims.

use super::claims::{Check, Claim, Need, Scenes};
use super::{Ladder, Metric, Study};
use crate::method::{Method, PROJ_BUILDERS};

/// The thesis' ladders. Its tree has 7 lights inside the scene volume; ours
/// places 7 in the scene box (and 1 for the one-light ladder).
pub const LADDERS: [Ladder; 5] = [
    Ladder {
        name: "tree, 7 lights",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 1,
        lights: 7,
    },
    Ladder {
        name: "tree, floor split, 7 lights",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 16,
        lights: 7,
    },
    Ladder {
        name: "tree, 1 light",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 1,
        lights: 1,
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

/// The 3D hierarchies, by name, as a claim pattern.
const GLOBAL: &str = "tdbs|nn-chain|rtree|rstar";

fn methods() -> Vec<Method> {
    let mut v: Vec<Method> = PROJ_BUILDERS
        .iter()
        .map(|m| Method::parse(m).expect("a registered method"))
        .collect();
    v.extend(Method::projections());
    v
}

fn plot_methods() -> Vec<String> {
    PROJ_BUILDERS
        .iter()
        .map(|m| m.to_string())
        .chain(PROJ_BUILDERS.iter().map(|b| format!("proj-{b}-2d-2d")))
        .collect()
}

const METRICS: [Metric; 7] = [
    Metric::RenderS,
    Metric::ViewMs,
    Metric::LightMs,
    Metric::GlobalMs,
    Metric::ObjectsPerRay,
    Metric::CostPerBox,
    Metric::CostPerPrim,
];

const PLOT_METRICS: [Metric; 4] = [
    Metric::RenderS,
    Metric::ProjectionMs,
    Metric::ObjectsPerRay,
    Metric::CostPerBox,
];

/// The conclusions of 6.4.
pub const CLAIMS: [Claim; 10] = [
    Claim {
        id: "1",
        text: "sorting the objects first (TDBS) yields more efficient hierarchies than inserting \
               them (R-tree, R*-tree)",
        check: Check::Smaller {
            a: "tdbs|proj-tdbs-$",
            b: "rtree|rstar|proj-rtree-$|proj-rstar-$",
            metric: Metric::RenderS,
            scenes: Scenes::Every,
            need: Need::Majority,
        },
    },
    Claim {
        id: "2",
        text: "the traversal cost of a 2D hierarchy is insignificant beside a hierarchy that \
               models the scene closely (the best 3D hierarchy beats the best pure-2D projection)",
        check: Check::Smaller {
            a: GLOBAL,
            b: "proj-*-2d",
            metric: Metric::RenderS,
            scenes: Scenes::Every,
            need: Need::Majority,
        },
    },
    Claim {
        id: "3",
        text: "area criteria (R-tree) are better with limited overlap (2D criteria, 2D scheme, \
               least overlapped scene)",
        check: Check::Smaller {
            a: "proj-rtree-2d-2d",
            b: "proj-rstar-2d-2d",
            metric: Metric::RenderS,
            scenes: Scenes::LeastOverlap,
            need: Need::All,
        },
    },
    Claim {
        id: "4",
        text: "overlap criteria (R*-tree) are better with large overlap (most overlapped scene)",
        check: Check::Smaller {
            a: "proj-rstar-2d-2d",
            b: "proj-rtree-2d-2d",
            metric: Metric::RenderS,
            scenes: Scenes::MostOverlap,
            need: Need::All,
        },
    },
    Claim {
        id: "5",
        text: "with large 2D overlap combination intersections are preferred (3 of 4 builders)",
        check: Check::Smaller {
            a: "proj-$-2d-comb",
            b: "proj-$-2d-2d",
            metric: Metric::RenderS,
            scenes: Scenes::MostOverlap,
            need: Need::AtLeast(3),
        },
    },
    Claim {
        id: "6",
        text: "with small 2D overlap a 2D intersection hierarchy is faster (3 of 4 builders)",
        check: Check::Smaller {
            a: "proj-$-2d-2d",
            b: "proj-$-2d-comb",
            metric: Metric::RenderS,
            scenes: Scenes::LeastOverlap,
            need: Need::AtLeast(3),
        },
    },
    Claim {
        id: "7",
        text: "the cost of choosing a hierarchy becomes significant with many secondary rays \
               (shadow rays asking every light lose most where secondary rays are most)",
        check: Check::SameLargest {
            cause: Metric::SecondaryPerPrimary,
            effect: Metric::UniformOverKnown,
            methods: "proj-*",
        },
    },
    Claim {
        id: "8",
        text: "objects much larger than the rest (the tree's floor) slow ray tracing: splitting \
               the floor into 16 x 16 makes most methods faster",
        check: Check::LadderSmaller {
            faster: "tree, floor split, 7 lights",
            slower: "tree, 7 lights",
            metric: Metric::RenderS,
        },
    },
    Claim {
        id: "9",
        text: "projected hierarchies are faster in large scenes with few secondary rays (tree, \
               matte, 1 light)",
        check: Check::Smaller {
            a: "proj-*",
            b: GLOBAL,
            metric: Metric::RenderS,
            scenes: Scenes::Largest("tree, 1 light"),
            need: Need::All,
        },
    },
    Claim {
        id: "9b",
        text: "and not where secondary rays abound (balls)",
        check: Check::Smaller {
            a: GLOBAL,
            b: "proj-*",
            metric: Metric::RenderS,
            scenes: Scenes::Largest("balls"),
            need: Need::All,
        },
    },
];

/// The study.
pub const STUDY: Study = Study {
    table: "proj-series",
    title: "projection hierarchies; ray tracing = whole render (shadow rays choose their \
            light plane uniformly); preprocessing split into view (camera), light (every \
            light plane) and global (3D hierarchy for secondary rays); methods: 3D \
            hierarchies by name, proj-BUILDER-CRITERIA-SCHEME",
    ladders: &LADDERS,
    methods,
    metrics: &METRICS,
    plot_metrics: &PLOT_METRICS,
    plot_methods,
    claims: &CLAIMS,
    section: "thesis chapter 6",
};
