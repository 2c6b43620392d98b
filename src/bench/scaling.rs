//! `cltrace bench --scaling`: how build time, memory and tracing speed grow with the mesh,
//! on a generated hillside of about 10 thousand to 10 million triangles.

use std::path::Path;

use plotters::prelude::*;

use super::{BenchRequest, BenchRow, RayKind};
use crate::error::{Error, Result};
use crate::input::generate::Generator;
use crate::output::write_atomically;
use crate::render::Method;

/// The triangle counts measured (a hillside of `2 r^2` triangles comes closest).
pub(crate) const SCALING_SIZES: [u64; 4] = [10_000, 100_000, 1_000_000, 10_000_000];

/// The bench request for the scaling study: the BVH methods at 1920x1080 on hillsides of
/// each size, everything else as in `base`.
pub(crate) fn scaling_request(base: &BenchRequest) -> BenchRequest {
    BenchRequest {
        scenes: Vec::new(),
        scene_folders: Vec::new(),
        generated: SCALING_SIZES
            .iter()
            .map(|&n| Generator::Hillside {
                resolution: ((n as f64 / 2.0).sqrt().round()) as u32,
                seed: 1,
            })
            .collect(),
        methods: base
            .methods
            .iter()
            .copied()
            .filter(|m| m.uses_bvh())
            .collect(),
        ray_kinds: vec![RayKind::Primary],
        resolutions: vec![(1920, 1080)],
        ..base.clone()
    }
}

/// The scaling rows as a Markdown table: build cost, memory and speed per size.
pub(crate) fn scaling_table(rows: &[BenchRow]) -> String {
    let mut out = String::from(
        "| scene | triangles | method | device | build ms | threads | bytes/triangle | SAH cost | Mrays/s |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.1} | {} | {} |\n",
            r.scene,
            r.triangles,
            r.method,
            r.device,
            r.build_ms.map_or("-".into(), |v| format!("{v:.1}")),
            r.build_threads.map_or("-".into(), |t| t.to_string()),
            r.device_mb * 1e6 / r.triangles as f64,
            r.sah_cost.map_or("-".into(), |c| format!("{c:.2}")),
            r.mrays_per_s.map_or("-".into(), |v| format!("{v:.1}")),
        );
    }
    out
}

/// Draws build time and tracing speed against triangle count (log-log) into a PNG.
pub(crate) fn plot_scaling(rows: &[BenchRow], path: &Path) -> Result<()> {
    let fail =
        |e: &dyn std::fmt::Display| Error::output(path, format!("cannot draw the plot: {e}"));
    let (width, height) = (1400u32, 560u32);
    let mut pixels = vec![255u8; (width * height * 3) as usize];
    {
        // plotters draws text with a font it is given, not with the system's.
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .map_err(|_| fail(&"the built-in font is unreadable"))?;
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        let (left, right) = root.split_horizontally(width / 2);
        let sizes = (SCALING_SIZES[0] as f64 / 2.0)..(SCALING_SIZES[3] as f64 * 2.0);

        let builds: Vec<(f64, f64)> = dedup_builds(rows);
        let max_build = builds.iter().map(|p| p.1).fold(1.0, f64::max) * 2.0;
        let mut chart = ChartBuilder::on(&left)
            .caption("BVH build time", ("sans-serif", 24))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(sizes.clone().log_scale(), (0.1..max_build).log_scale())
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("triangles")
            .y_desc("build ms")
            .x_label_formatter(&|n| count(*n))
            .y_label_formatter(&|v| format!("{v}"))
            .draw()
            .map_err(|e| fail(&e))?;
        chart
            .draw_series(
                LineSeries::new(builds.iter().copied(), BLUE.stroke_width(2)).point_size(4),
            )
            .map_err(|e| fail(&e))?;

        let max_rate = rows
            .iter()
            .filter_map(|r| r.mrays_per_s)
            .fold(1.0, f64::max)
            * 2.0;
        let mut chart = ChartBuilder::on(&right)
            .caption("primary rays, 1920x1080", ("sans-serif", 24))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(sizes.log_scale(), (0.1..max_rate).log_scale())
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("triangles")
            .y_desc("Mrays/s")
            .x_label_formatter(&|n| count(*n))
            .y_label_formatter(&|v| format!("{v}"))
            .draw()
            .map_err(|e| fail(&e))?;
        for (i, series) in series_by_target(rows).into_iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let label = series.0.clone();
            chart
                .draw_series(LineSeries::new(series.1, color.stroke_width(2)).point_size(4))
                .map_err(|e| fail(&e))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    let image = image::RgbImage::from_raw(width, height, pixels).expect("buffer matches the size");
    crate::output::check_output(path)?;
    write_atomically(path, |w| {
        image
            .write_to(w, image::ImageFormat::Png)
            .map_err(|e| Error::output(path, e))
    })
}

/// `10k`, `1M`: axis labels for triangle counts.
fn count(n: f64) -> String {
    if n >= 1e6 {
        format!("{}M", n / 1e6)
    } else if n >= 1e3 {
        format!("{}k", n / 1e3)
    } else {
        format!("{n}")
    }
}

/// One build time per mesh (every BVH row of a mesh built the same tree; the fastest counts).
fn dedup_builds(rows: &[BenchRow]) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = Vec::new();
    for r in rows {
        if let Some(ms) = r.build_ms {
            let n = r.triangles as f64;
            match points.iter_mut().find(|p| p.0 == n) {
                Some(p) => p.1 = p.1.min(ms),
                None => points.push((n, ms)),
            }
        }
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// Tracing speed against size, one series per method and device.
fn series_by_target(rows: &[BenchRow]) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        let Some(rate) = r.mrays_per_s else { continue };
        let label = if r.method == Method::CpuBvh.name() {
            format!("{} on the host", r.method)
        } else {
            format!("{} on {}", r.method, r.device)
        };
        match series.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push((r.triangles as f64, rate)),
            None => series.push((label, vec![(r.triangles as f64, rate)])),
        }
    }
    series
}
