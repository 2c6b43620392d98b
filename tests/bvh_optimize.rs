//! The post-build optimization (node reinsertion, `BuildOptions::optimize_rounds`): the
//! optimized tree is valid, keeps every leaf, never costs more under the SAH than the built
//! one (and on a real mesh clearly less), stays within the depth limit, and finds exactly the
//! hits brute force finds.

use std::collections::BTreeMap;

use crate::common::*;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::optimize::MAX_ROUNDS;
use cltrace::bvh::{BuildOptions, Builder, Bvh, MAX_DEPTH};
use cltrace::geometry::Ray;
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::mesh::Mesh;
use glam::Vec3;
use proptest::prelude::*;

/// Every leaf as (its box's bits, its triangles sorted), counted: two trees with the same
/// leaves give the same map, whatever their topology and leaf order.
fn leaves(bvh: &Bvh) -> BTreeMap<(Vec<u32>, Vec<u32>), usize> {
    let mut out = BTreeMap::new();
    for n in bvh.nodes.iter().filter(|n| n.is_leaf()) {
        let first = n.left_or_first as usize;
        let mut tris = bvh.prim_order[first..first + n.count() as usize].to_vec();
        tris.sort_unstable();
        let bits = n.min.iter().chain(&n.max).map(|v| v.to_bits()).collect();
        *out.entry((bits, tris)).or_insert(0) += 1;
    }
    out
}

/// Builds with and without the optimization and checks everything the optimization
/// promises; returns both SAH costs (built, optimized).
fn check_optimized(
    name: &str,
    mesh: &Mesh,
    opts: &BuildOptions,
    rays: &[Ray],
) -> Result<(f64, f64), String> {
    let built = Bvh::build(mesh, opts);
    let optimized = Bvh::build(
        mesh,
        &BuildOptions {
            optimize_rounds: 20,
            ..*opts
        },
    );
    let ctx = |e: String| format!("{name}, {opts:?}: {e}");
    optimized.check(mesh).map_err(ctx)?;
    if optimized.depth > opts.max_depth {
        return Err(ctx(format!(
            "depth {} over the limit {}",
            optimized.depth, opts.max_depth
        )));
    }
    if leaves(&optimized) != leaves(&built) {
        return Err(ctx("the leaves changed".into()));
    }
    if optimized.nodes.len() != built.nodes.len() {
        return Err(ctx(format!(
            "{} nodes, {} built",
            optimized.nodes.len(),
            built.nodes.len()
        )));
    }
    // Inner boxes are exactly the union of their children's.
    for (i, n) in optimized.nodes.iter().enumerate() {
        if !n.is_leaf() {
            let (l, r) = (
                &optimized.nodes[n.left_or_first as usize],
                &optimized.nodes[n.right_or_count as usize],
            );
            let min: Vec<f32> = (0..3).map(|k| l.min[k].min(r.min[k])).collect();
            let max: Vec<f32> = (0..3).map(|k| l.max[k].max(r.max[k])).collect();
            if n.min[..] != min[..] || n.max[..] != max[..] {
                return Err(ctx(format!("node {i}'s box is not its children's union")));
            }
        }
    }
    let (before, after) = (built.stats().sah_cost, optimized.stats().sah_cost);
    if after > before {
        return Err(ctx(format!("SAH cost rose from {before} to {after}")));
    }
    same_hits(mesh, &Bin32Bvh::new(optimized, mesh), rays).map_err(ctx)?;
    Ok((before, after))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_meshes_optimize_to_valid_cheaper_trees_with_brute_force_hits(
        mesh in mesh_strategy(200),
        seed in any::<u64>(),
        max_depth in 4u32..=MAX_DEPTH,
    ) {
        let rays = rays_for(&mesh, seed, 64);
        for opts in all_options() {
            for opts in [opts, BuildOptions { max_depth, ..opts }] {
                if let Err(e) = check_optimized("random mesh", &mesh, &opts, &rays) {
                    prop_assert!(false, "{e}");
                }
            }
        }
    }
}

#[test]
fn optimized_trees_of_the_test_scenes_are_valid_cheaper_and_hit_like_brute_force() {
    for (name, mesh) in test_scenes() {
        let count = if mesh.triangle_count() > 20_000 {
            200
        } else {
            1000
        };
        let rays = rays_for(&mesh, 7, count);
        for opts in [
            BuildOptions::default(),
            options(Builder::Sweep, 32, 8),
            options(Builder::Binned, 8, 1),
        ] {
            let (before, after) =
                check_optimized(&name, &mesh, &opts, &rays).unwrap_or_else(|e| panic!("{e}"));
            eprintln!(
                "{name}, {:?} {} bins, leaves up to {}: SAH {before:.3} -> {after:.3} ({:+.2}%)",
                opts.builder,
                opts.bins,
                opts.max_leaf_size,
                (after / before - 1.0) * 100.0
            );
        }
    }
}

#[test]
fn the_cost_drops_measurably_on_a_real_mesh() {
    // The bunny, or where the shared meshes are absent a generated mesh of similar size.
    let (name, mesh) = match shared_scene("stanford_bunny.obj") {
        Some(path) => ("stanford_bunny.obj".to_string(), load_mesh(&path).unwrap()),
        None => {
            let g = Generator::Sphereflake {
                levels: 3,
                subdivisions: 1,
                ground: 100,
            };
            (g.name(), generate(g))
        }
    };
    let mut bvh = Bvh::build(&mesh, &BuildOptions::default());
    let built = bvh.clone();
    let report = bvh.optimize(10, MAX_DEPTH);
    bvh.check(&mesh).unwrap();
    let (before, after) = (built.stats().sah_cost, bvh.stats().sah_cost);
    eprintln!(
        "{name}: SAH {before:.4} -> {after:.4} ({:+.3}%) in {} rounds, {} of {} moves kept",
        (after / before - 1.0) * 100.0,
        report.rounds,
        report.moves,
        report.attempts
    );
    assert_eq!((report.cost_before, report.cost_after), (before, after));
    assert!(report.rounds >= 1 && report.moves > 0, "{report:?}");
    assert!(
        after < before * (1.0 - 0.002),
        "{name}: SAH cost {before} fell only to {after}"
    );
    // More rounds never cost more, and the optimization is deterministic.
    let mut longer = built.clone();
    longer.optimize(20, MAX_DEPTH);
    assert!(longer.stats().sah_cost <= after);
    let mut again = built.clone();
    again.optimize(10, MAX_DEPTH);
    assert_eq!(again, bvh);
    // No rounds, no change.
    let mut untouched = built.clone();
    let report = untouched.optimize(0, MAX_DEPTH);
    assert_eq!(untouched, built);
    assert_eq!((report.rounds, report.moves), (0, 0));
}

#[test]
fn the_depth_limit_holds_where_reinsertion_would_chain() {
    let (mesh, rays) = (chain(), chain_rays());
    for max_depth in [16, 10, 8] {
        let opts = BuildOptions {
            max_leaf_size: 1,
            max_depth,
            ..Default::default()
        };
        let built = Bvh::build(&mesh, &opts);
        // Unlimited, the optimization deepens the median-split tree towards the SAH's chain
        // (so the limit below is really tested)...
        let mut free = built.clone();
        free.optimize(50, MAX_DEPTH);
        free.check(&mesh).unwrap();
        assert!(
            free.depth > max_depth,
            "unlimited, depth {} stays within {max_depth}: the test tests nothing",
            free.depth
        );
        assert!(free.stats().sah_cost < built.stats().sah_cost);
        // ...but under the limit it stays within it, and still gains.
        let (before, after) = check_optimized("chain", &mesh, &opts, &rays).unwrap();
        let limited = Bvh::build(
            &mesh,
            &BuildOptions {
                optimize_rounds: 50,
                ..opts
            },
        );
        assert!(limited.depth <= max_depth, "depth {}", limited.depth);
        eprintln!(
            "chain, max depth {max_depth}: SAH {before:.3} -> {after:.3} (unlimited {:.3}, depth {})",
            free.stats().sah_cost,
            free.depth
        );
    }
}

#[test]
fn degenerate_meshes_survive_the_optimization() {
    for (name, mesh) in [
        ("one triangle", copies([Vec3::ZERO, Vec3::X, Vec3::Y], 1)),
        ("two triangles", copies([Vec3::ZERO, Vec3::X, Vec3::Y], 2)),
        ("1000 copies", copies([Vec3::ZERO, Vec3::X, Vec3::Y], 1000)),
        ("points", copies([Vec3::ONE; 3], 5000)),
        ("collinear", collinear()),
    ] {
        let rays = rays_for(&mesh, 3, 32);
        for opts in all_options() {
            check_optimized(name, &mesh, &opts, &rays).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn too_many_rounds_are_refused() {
    let ok = BuildOptions {
        optimize_rounds: MAX_ROUNDS,
        ..Default::default()
    };
    assert!(ok.check().is_ok());
    let err = BuildOptions {
        optimize_rounds: MAX_ROUNDS + 1,
        ..Default::default()
    }
    .check()
    .unwrap_err()
    .to_string();
    assert!(err.contains("--optimize"), "{err}");
}
