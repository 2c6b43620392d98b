//! `cltrace bvh`: builds a scene's BVH and reports what it looks like and what it cost.

use std::fmt::Write;
use std::path::Path;

use crate::bvh::{BuildOptions, Bvh, INTERSECTION_COST, TRAVERSAL_COST};
use crate::commands::render::describe_scene;
use crate::error::Result;
use crate::layout::FlatBvh;
use crate::report::{Timings, format_ms};

/// Loads the scene's mesh, builds its BVH `repeat` times (the fastest build is reported)
/// and returns the report.
pub fn bvh_report(scene: Option<&Path>, options: &BuildOptions, repeat: u32) -> Result<String> {
    options.check()?;
    let scene = describe_scene(scene)?;
    let mut timings = Timings::default();
    let mesh = timings.time("load", || scene.mesh.load())?;
    let mut best_ms = f64::INFINITY;
    let mut bvh = None;
    for _ in 0..repeat.max(1) {
        let start = std::time::Instant::now();
        let built = Bvh::build(&mesh, options);
        best_ms = best_ms.min(start.elapsed().as_secs_f64() * 1e3);
        bvh = Some(built);
    }
    let bvh = bvh.expect("built at least once");
    let s = bvh.stats();
    let layout_start = std::time::Instant::now();
    let flat = FlatBvh::new(bvh, &mesh);
    let layout_ms = layout_start.elapsed().as_secs_f64() * 1e3;

    let mut out = String::new();
    let mut line = |k: &str, v: String| writeln!(out, "{k:<22}{v}").expect("writing to a String");
    line("scene", scene.mesh.name());
    line("triangles", s.triangles.to_string());
    line(
        "builder",
        format!(
            "{:?}, {} bins, max leaf {}",
            options.builder, options.bins, options.max_leaf_size
        )
        .to_lowercase(),
    );
    line("nodes", s.nodes.to_string());
    line("leaves", s.leaves.to_string());
    line("depth", s.depth.to_string());
    line(
        "leaf size",
        format!("mean {:.2}, max {}", s.mean_leaf_size, s.max_leaf_size),
    );
    line(
        "SAH cost",
        format!(
            "{:.3} (C_trav = {TRAVERSAL_COST}, C_isect = {INTERSECTION_COST})",
            s.sah_cost
        ),
    );
    line(
        "build time",
        format!(
            "{} (best of {}, {} threads)",
            format_ms(best_ms),
            repeat.max(1),
            rayon::current_num_threads()
        ),
    );
    line("layout time", format_ms(layout_ms));
    line("load time", format_ms(timings.get("load").unwrap_or(0.0)));
    line(
        "device bytes/triangle",
        format!("{:.1}", flat.bytes_per_triangle()),
    );
    Ok(out)
}
