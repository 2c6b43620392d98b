//! The BVH against brute force: structural invariants and closest hits on random meshes
//! (proptest), SAH quality of the binned builder against the exact sweep, and the
//! degenerate inputs every builder must survive.

use crate::common::*;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Builder, Bvh, MAX_DEPTH, SWEEP_UP_TO};
use cltrace::geometry::Ray;
use cltrace::input::generate::Generator;
use cltrace::intersect::ClosestHit;
use cltrace::mesh::Mesh;
use glam::Vec3;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_meshes_build_valid_trees_with_brute_force_hits(mesh in mesh_strategy(120), seed in any::<u64>()) {
        let rays = rays_for(&mesh, seed, 64);
        for opts in all_options() {
            let bvh = Bvh::build(&mesh, &opts);
            prop_assert!(bvh.check(&mesh).is_ok(), "{opts:?}: {}", bvh.check(&mesh).unwrap_err());
            let flat = Bin32Bvh::new(bvh, &mesh);
            if let Err(e) = same_hits(&mesh, &flat, &rays) {
                prop_assert!(false, "{opts:?}: {e}");
            }
        }
    }
}

#[test]
fn binned_sah_cost_is_within_5_percent_of_the_sweep() {
    for (name, mesh) in test_scenes() {
        let binned = Bvh::build(&mesh, &options(Builder::Binned, 32, 8));
        let sweep = Bvh::build(&mesh, &options(Builder::Sweep, 32, 8));
        binned.check(&mesh).unwrap();
        sweep.check(&mesh).unwrap();
        let (b, s) = (binned.stats().sah_cost, sweep.stats().sah_cost);
        eprintln!(
            "{name}: binned SAH {b:.3}, sweep {s:.3} ({:+.2}%)",
            (b / s - 1.0) * 100.0
        );
        assert!(
            b <= s * 1.05,
            "{name}: binned SAH cost {b} is more than 5% above the sweep's {s}"
        );
    }
}

/// The default builder sweeps scenes of up to `SWEEP_UP_TO` triangles and bins larger ones.
#[test]
fn auto_sweeps_small_scenes_and_bins_large_ones() {
    for (triangles, picked) in [
        (SWEEP_UP_TO, Builder::Sweep),
        (SWEEP_UP_TO + 1, Builder::Binned),
    ] {
        let mesh = generate(Generator::Soup {
            triangles: triangles as u32,
            seed: 3,
        });
        assert_eq!(mesh.triangle_count(), triangles);
        let auto = Bvh::build(&mesh, &BuildOptions::default());
        let other = if picked == Builder::Sweep {
            Builder::Binned
        } else {
            Builder::Sweep
        };
        assert_eq!(
            auto,
            Bvh::build(&mesh, &options(picked, 32, 8)),
            "{triangles}"
        );
        assert_ne!(
            auto,
            Bvh::build(&mesh, &options(other, 32, 8)),
            "{triangles}"
        );
    }
    assert!(Builder::Auto.about().contains(&format!(
        "{},{}",
        SWEEP_UP_TO / 1000,
        SWEEP_UP_TO % 1000
    )));
}

/// Builds with every option set, checks the tree and its hits, returns the default tree.
fn survives(name: &str, mesh: &Mesh) -> Bvh {
    let rays = rays_for(mesh, 5, 32);
    for opts in all_options() {
        let bvh = Bvh::build(mesh, &opts);
        bvh.check(mesh)
            .unwrap_or_else(|e| panic!("{name}, {opts:?}: {e}"));
        same_hits(mesh, &Bin32Bvh::new(bvh, mesh), &rays)
            .unwrap_or_else(|e| panic!("{name}, {opts:?}: {e}"));
    }
    Bvh::build(mesh, &BuildOptions::default())
}

#[test]
fn a_single_triangle_is_one_leaf() {
    let bvh = survives("one triangle", &copies([Vec3::ZERO, Vec3::X, Vec3::Y], 1));
    assert_eq!((bvh.nodes.len(), bvh.depth), (1, 1));
}

#[test]
fn coincident_centroids_stay_within_the_depth_limit() {
    let bvh = survives(
        "1000 copies of one triangle",
        &copies([Vec3::ZERO, Vec3::X, Vec3::Y], 1000),
    );
    assert!(bvh.depth <= MAX_DEPTH);
}

#[test]
fn flat_and_collinear_meshes_build_valid_trees() {
    // Every triangle in the plane z = 0: boxes without thickness.
    let flat = generate(Generator::Landscape {
        resolution: 20,
        seed: 0,
    });
    let flat = Mesh::new(
        flat.positions
            .iter()
            .map(|p| Vec3::new(p.x, p.z, 0.0))
            .collect(),
        flat.triangles,
    );
    survives("flat", &flat);
    survives("collinear", &collinear());
}

#[test]
fn a_million_triangles_in_one_point_build_and_never_hit() {
    let mesh = copies([Vec3::ONE; 3], 1_000_000);
    let bvh = Bvh::build(&mesh, &BuildOptions::default());
    bvh.check(&mesh).unwrap();
    assert!(bvh.depth <= MAX_DEPTH);
    let flat = Bin32Bvh::new(bvh, &mesh);
    let ray = Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::NEG_Z);
    assert_eq!(
        flat.closest_hit(&ray, f32::INFINITY),
        None,
        "zero-area triangles never hit"
    );
}

#[test]
fn depth_stays_bounded_where_the_sah_would_chain() {
    // Triangles sharing a corner, each 1.45 times larger than the last: the SAH peels off
    // the largest again and again, a tree far deeper than it is wide: depth 19 or more where
    // a balanced tree needs 7 (11 with two bins, whose grid's one plane often has every
    // centroid on one side). Under tighter limits the builder must switch to median splits
    // in time, and at the limit itself make leaves whatever their size.
    let (mesh, rays) = (chain(), chain_rays());
    for opts in all_options() {
        let natural = Bvh::build(&mesh, &opts).depth;
        assert!(
            natural > 8,
            "{opts:?}: natural depth {natural} does not test the limits"
        );
        for max_depth in [16, 8, 2].into_iter().filter(|&d| d < natural) {
            let limited = BuildOptions { max_depth, ..opts };
            let bvh = Bvh::build(&mesh, &limited);
            assert!(bvh.depth <= max_depth, "{limited:?}: depth {}", bvh.depth);
            bvh.check(&mesh).unwrap();
            same_hits(&mesh, &Bin32Bvh::new(bvh, &mesh), &rays).unwrap();
        }
    }
}

#[test]
fn meshes_large_enough_to_bin_and_partition_in_parallel_build_valid_trees() {
    // Above 65,536 triangles a node bins and partitions in parallel chunks, and above
    // 16,384 its subtrees build as parallel tasks laid out behind shared top nodes: the
    // small meshes of the other tests never reach either path.
    for generator in [
        Generator::Soup {
            triangles: 100_000,
            seed: 3,
        },
        Generator::Landscape {
            resolution: 200,
            seed: 2,
        },
    ] {
        let name = generator.name();
        let mesh = generate(generator);
        assert!(mesh.triangle_count() > 65_536, "{name} is too small");
        let rays = rays_for(&mesh, 7, 300);
        for opts in all_options() {
            let bvh = Bvh::build(&mesh, &opts);
            bvh.check(&mesh)
                .unwrap_or_else(|e| panic!("{name}, {opts:?}: {e}"));
            same_hits(&mesh, &Bin32Bvh::new(bvh, &mesh), &rays)
                .unwrap_or_else(|e| panic!("{name}, {opts:?}: {e}"));
        }
    }
}
