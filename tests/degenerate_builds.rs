//! Every builder over degenerate inputs (identical, collinear, coplanar
//! primitives) in O(n log n), the nearest-neighbour matching in O(n^2)
//! (its nature): each build of a large such scene must return within a
//! limit far above what those bounds cost here and far below what one
//! more power of n would, and its result must validate. Before the fixes,
//! TDBS and TDBS-SAH made a chain of identical primitives (O(n^2): 100,000
//! took minutes) and NN matching was O(n^3) on them (2,000 took 5 s).

mod common;

use common::*;
use coray::bvh::{Builder, BvhStackItem, RTreeParams};
use coray::kd::KdParams;
use coray::owned::{BvhBuild, OwnedBvh, OwnedKd, OwnedWide};
use coray::Vec3;

/// `n` copies of one small triangle, `n` of one sphere.
fn identical(n: usize) -> OwnedScene {
    let mut o = OwnedScene::default();
    for _ in 0..n {
        o.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        o.spheres.push(coray::Sphere {
            center: [0.0, 0.0, 1.0],
            radius: 0.5,
        });
    }
    o
}

/// `n` small spheres in a row along x (`s 0.001 i 0 0 0.0004`) and `n`
/// triangles along it.
fn collinear(n: usize) -> OwnedScene {
    let mut o = OwnedScene::default();
    for i in 0..n {
        let x = 0.001 * i as f32;
        o.spheres.push(coray::Sphere {
            center: [x, 0.0, 0.0],
            radius: 0.0004,
        });
        let p = Vec3::new(x, 0.1, 0.0);
        o.add_triangle(
            p,
            p + Vec3::new(0.0004, 0.0, 0.0),
            p + Vec3::new(0.0, 0.0004, 0.0),
        );
    }
    o
}

/// `n` triangles on one plane, on a grid.
fn coplanar(n: usize) -> OwnedScene {
    let mut o = OwnedScene::default();
    let side = (n as f32).sqrt().ceil() as usize;
    for i in 0..n {
        let (x, y) = ((i % side) as f32, (i / side) as f32);
        o.add_triangle(
            Vec3::new(x, y, 0.0),
            Vec3::new(x + 0.9, y, 0.0),
            Vec3::new(x, y + 0.9, 0.0),
        );
    }
    o
}

/// Builds `scene` with every O(n log n) builder and validates each.
fn near_linear_builds(o: OwnedScene) {
    let s = o.scene();
    let kd = OwnedKd::new(&s, &KdParams::auto()).unwrap();
    kd.tree(s).unwrap().validate().unwrap();
    let wide = OwnedWide::new(&s, 8).unwrap();
    wide.view(s).unwrap().validate().unwrap();
    for how in [
        BvhBuild::Static(Builder::Tdbs, 1),
        BvhBuild::Static(Builder::TdbsSah, 4),
        BvhBuild::Static(Builder::NnChain, 1),
        BvhBuild::RTree(RTreeParams::rtree()),
        BvhBuild::RTree(RTreeParams::rstar()),
    ] {
        let b = OwnedBvh::new(&s, how).unwrap();
        let v = b.view(s).unwrap();
        let min = matches!(how, BvhBuild::RTree(_)).then_some(3);
        let mut stack = vec![BvhStackItem::default(); v.stack_len()];
        if min.is_none() {
            v.validate(None, &mut stack).unwrap();
        } else {
            b.validate(s).unwrap();
        }
    }
}

#[test]
fn identical_primitives_build_in_n_log_n() {
    watchdog(60, "identical", || near_linear_builds(identical(50_000)));
}

#[test]
fn collinear_primitives_build_in_n_log_n() {
    watchdog(60, "collinear", || near_linear_builds(collinear(50_000)));
}

#[test]
fn coplanar_primitives_build_in_n_log_n() {
    watchdog(60, "coplanar", || near_linear_builds(coplanar(100_000)));
}

/// NN matching is quadratic by nature; on degenerate inputs it stays so
/// (10,000 identical primitives took minutes when it was cubic).
#[test]
fn nn_matching_stays_quadratic_on_degenerate_inputs() {
    for (what, o) in [
        ("identical", identical(5_000)),
        ("collinear", collinear(5_000)),
        ("coplanar", coplanar(10_000)),
    ] {
        watchdog(30, what, move || {
            let s = o.scene();
            let b = OwnedBvh::new(&s, BvhBuild::Static(Builder::Nn, 1)).unwrap();
            let v = b.view(s).unwrap();
            v.validate(None, &mut vec![BvhStackItem::default(); v.stack_len()])
                .unwrap();
        });
    }
}

/// A kd-tree over a few identical triangles and spheres: the builders'
/// face cells around planar primitives rounded to nothing in nodes of
/// subnormal thickness and put splits on the nodes' faces, which
/// `validate` refused ("split outside its node") from 3 copies up.
#[test]
fn kd_trees_over_few_identical_primitives_validate() {
    for n in [2, 3, 10, 100] {
        let o = identical(n);
        let s = o.scene();
        for p in [KdParams::auto(), KdParams::paper(), KdParams::compact()] {
            let kd = OwnedKd::new(&s, &p).unwrap();
            kd.tree(s).unwrap().validate().unwrap();
        }
    }
}
