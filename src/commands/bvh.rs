//! `cltrace bvh`: builds a scene's BVH and reports what it looks like and what it cost.

use std::fmt::Write;
use std::path::PathBuf;

use crate::bvh::{Bin32Bvh, DeviceLayout, Layout};
use crate::bvh::{BuildOptions, Builder, Bvh, INTERSECTION_COST, TRAVERSAL_COST};
use crate::error::Result;
use crate::input::scene_file::SceneDescription;
use crate::report::{Timings, format_ms};

/// Everything `cltrace bvh` was asked to do.
#[derive(Clone, Debug)]
pub struct BvhRequest {
    /// A scene file or a mesh; `None` for the built-in default scene.
    pub scene: Option<PathBuf>,
    /// How to build the BVH.
    pub build: BuildOptions,
    /// Builds (and optimizations) to run; the fastest is reported.
    pub repeat: u32,
}

/// Loads the scene's mesh, builds its BVH `repeat` times (the fastest build is reported)
/// and returns the report.
pub fn bvh_report(req: &BvhRequest) -> Result<String> {
    let (options, repeat) = (&req.build, req.repeat);
    options.check()?;
    let scene = SceneDescription::named(req.scene.as_deref())?;
    let mut timings = Timings::default();
    let mesh = timings.time("load", || scene.meshes.load())?;
    // The optimization is timed apart from the build (both the best of `repeat`).
    let build_options = BuildOptions {
        optimize_rounds: 0,
        ..*options
    };
    let mut best_ms = f64::INFINITY;
    let mut bvh = None;
    for _ in 0..repeat.max(1) {
        let start = std::time::Instant::now();
        let built = Bvh::build(&mesh, &build_options);
        best_ms = best_ms.min(start.elapsed().as_secs_f64() * 1e3);
        bvh = Some(built);
    }
    let mut bvh = bvh.expect("built at least once");
    let built_cost = bvh.stats().sah_cost;
    let mut optimized = None;
    if options.optimize_rounds > 0 {
        let mut best_opt_ms = f64::INFINITY;
        for _ in 0..repeat.max(1) {
            let mut tree = bvh.clone();
            let start = std::time::Instant::now();
            let report = tree.optimize(options.optimize_rounds, options.max_depth);
            best_opt_ms = best_opt_ms.min(start.elapsed().as_secs_f64() * 1e3);
            optimized = Some((tree, report, best_opt_ms));
        }
    }
    let optimized = optimized.map(|(tree, report, ms)| {
        bvh = tree;
        (report, ms)
    });
    let s = bvh.stats();
    let flat = Bin32Bvh::new(bvh, &mesh);
    // Every device layout made from the tree, with what it costs to make and to hold.
    let layouts: Vec<(DeviceLayout, f64)> = Layout::ALL
        .iter()
        .map(|&layout| {
            let start = std::time::Instant::now();
            let laid = DeviceLayout::new(flat.clone(), layout, s.sah_cost);
            (laid, start.elapsed().as_secs_f64() * 1e3)
        })
        .collect();

    let mut out = String::new();
    let mut line = |k: &str, v: String| writeln!(out, "{k:<22}{v}").expect("writing to a String");
    line("scene", scene.meshes.name());
    line("triangles", s.triangles.to_string());
    line(
        "builder",
        format!(
            "{}, {} bins, max leaf {}",
            builder_name(options.builder, s.triangles),
            options.bins,
            options.max_leaf_size
        ),
    );
    line("nodes", s.nodes.to_string());
    line("leaves", s.leaves.to_string());
    line("depth", s.depth.to_string());
    line(
        "leaf size",
        format!("mean {:.2}, max {}", s.mean_leaf_size, s.max_leaf_size),
    );
    let costs = format!("(C_trav = {TRAVERSAL_COST}, C_isect = {INTERSECTION_COST})");
    match optimized {
        None => line("SAH cost", format!("{:.3} {costs}", s.sah_cost)),
        Some((report, _)) => {
            line(
                &format!(
                    "SAH cost ({})",
                    options.builder.for_triangles(s.triangles).name()
                ),
                format!("{built_cost:.3} {costs}"),
            );
            line(
                "SAH cost (optimized)",
                format!(
                    "{:.3} ({:+.2}%; {} of {} moves kept)",
                    s.sah_cost,
                    (s.sah_cost / built_cost - 1.0) * 100.0,
                    report.moves,
                    report.attempts
                ),
            );
        }
    }
    line(
        "build time",
        format!(
            "{} (best of {}, {} threads)",
            format_ms(best_ms),
            repeat.max(1),
            rayon::current_num_threads()
        ),
    );
    if let Some((report, ms)) = optimized {
        line(
            "optimize time",
            format!(
                "{} (best of {}, {} of at most {} rounds, 1 thread)",
                format_ms(ms),
                repeat.max(1),
                report.rounds,
                options.optimize_rounds
            ),
        );
    }
    line("load time", format_ms(timings.get("load").unwrap_or(0.0)));
    writeln!(
        out,
        "\n{:<8}{:>10}{:>10}{:>16}{:>13}",
        "layout", "nodes", "SAH cost", "bytes/triangle", "layout time"
    )
    .expect("writing to a String");
    for (laid, ms) in &layouts {
        writeln!(
            out,
            "{:<8}{:>10}{:>10.3}{:>16.1}{:>13}",
            laid.layout.name(),
            laid.node_count,
            laid.sah_cost,
            laid.bytes_per_triangle(),
            format_ms(*ms)
        )
        .expect("writing to a String");
    }
    Ok(out)
}

/// The builder's name, with the one `auto` picked for a scene of `triangles`.
fn builder_name(builder: Builder, triangles: usize) -> String {
    match builder.for_triangles(triangles) {
        picked if picked != builder => format!("{} ({})", builder.name(), picked.name()),
        _ => builder.name().to_string(),
    }
}
