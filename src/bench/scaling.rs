//! `cltrace bench --scaling`: how build time, memory and tracing speed grow with the mesh,
//! on generated hillsides from about 10 thousand triangles to `--scaling-to` (10 million
//! unless asked for more).

use std::path::Path;

use plotters::prelude::*;

use super::{BenchRequest, BenchRow};
use crate::error::{Error, Result};
use crate::input::generate::{Generator, MAX_RESOLUTION};
use crate::output::write_atomically;
use crate::render::Method;

/// The smallest hillside of the study, in triangles.
const SMALLEST: u64 = 10_000;

/// The largest hillside the generators make: `2 r^2` triangles at the largest resolution.
pub(crate) const LARGEST: u64 = 2 * MAX_RESOLUTION as u64 * MAX_RESOLUTION as u64;

/// The triangle counts measured up to `to`: every power of ten from 10 thousand, then `to`
/// itself. Counts outside [10 thousand, [`LARGEST`]] are an error.
pub(crate) fn scaling_sizes(to: u64) -> Result<Vec<u64>> {
    if !(SMALLEST..=LARGEST).contains(&to) {
        return Err(Error::Invalid(format!(
            "--scaling-to {to}: give between {SMALLEST} and {LARGEST} triangles (the largest hillside)"
        )));
    }
    let mut sizes: Vec<u64> = std::iter::successors(Some(SMALLEST), |n| n.checked_mul(10))
        .take_while(|&n| n < to)
        .collect();
    sizes.push(to);
    Ok(sizes)
}

/// The bench request for one size of the scaling study: the BVH methods at 1920x1080 on a
/// hillside of about `triangles`, everything else (ray kinds included) as in `base`.
pub(crate) fn scaling_request(base: &BenchRequest, triangles: u64) -> BenchRequest {
    BenchRequest {
        scenes: Vec::new(),
        scene_folders: Vec::new(),
        generated: vec![Generator::Hillside {
            resolution: ((triangles as f64 / 2.0).sqrt().round()).max(1.0) as u32,
            seed: 1,
        }],
        methods: base
            .methods
            .iter()
            .copied()
            .filter(|m| m.uses_bvh())
            .collect(),
        resolutions: vec![(1920, 1080)],
        ..base.clone()
    }
}

/// The scaling rows as a Markdown table: build cost, memory and speed per size.
pub(crate) fn scaling_table(rows: &[BenchRow]) -> String {
    let mut out = String::from(
        "| scene | triangles | method | device | rays | build ms | threads | bytes/triangle | SAH cost | Mrays/s |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {:.1} | {} | {} |\n",
            r.scene,
            r.triangles,
            r.method,
            r.device,
            r.ray_kind,
            r.build_ms.map_or("-".into(), |v| format!("{v:.1}")),
            r.build_threads.map_or("-".into(), |t| t.to_string()),
            r.device_mb * 1e6 / r.triangles as f64,
            r.sah_cost.map_or("-".into(), |c| format!("{c:.2}")),
            r.mrays_per_s.map_or("-".into(), |v| format!("{v:.1}")),
        );
    }
    out
}

/// Draws build time, device bytes per triangle and tracing speed against triangle count
/// (log scales) into a PNG.
pub(crate) fn plot_scaling(rows: &[BenchRow], path: &Path) -> Result<()> {
    let fail =
        |e: &dyn std::fmt::Display| Error::output(path, format!("cannot draw the plot: {e}"));
    let (width, height) = (2100u32, 560u32);
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
        let (left, rest) = root.split_horizontally(width / 3);
        let (middle, right) = rest.split_horizontally(width / 3);
        let largest = rows.iter().map(|r| r.triangles).max().unwrap_or(1) as f64;
        let sizes = (SMALLEST as f64 / 2.0)..(largest * 2.0);

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

        // Device memory per triangle: triangles and nodes, one point per mesh and layout.
        let mut memory: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for r in rows.iter().filter(|r| r.device_mb > 0.0) {
            let point = (r.triangles as f64, r.device_mb * 1e6 / r.triangles as f64);
            match memory.iter_mut().find(|s| s.0 == r.method) {
                Some(s) if !s.1.iter().any(|p| p.0 == point.0) => s.1.push(point),
                Some(_) => {}
                None => memory.push((r.method.clone(), vec![point])),
            }
        }
        let max_bytes = memory
            .iter()
            .flat_map(|s| s.1.iter().map(|p| p.1))
            .fold(1.0, f64::max)
            * 1.25;
        let mut chart = ChartBuilder::on(&middle)
            .caption("device memory", ("sans-serif", 24))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(sizes.clone().log_scale(), 0.0..max_bytes)
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("triangles")
            .y_desc("bytes per triangle")
            .x_label_formatter(&|n| count(*n))
            .draw()
            .map_err(|e| fail(&e))?;
        draw_lines(&mut chart, memory).map_err(|e| fail(&e))?;

        let max_rate = rows
            .iter()
            .filter_map(|r| r.mrays_per_s)
            .fold(1.0, f64::max)
            * 2.0;
        let mut chart = ChartBuilder::on(&right)
            .caption("tracing speed, 1920x1080", ("sans-serif", 24))
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
        draw_lines(&mut chart, series_by_target(rows)).map_err(|e| fail(&e))?;
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

/// Draws each named series as a line of its own colour, with a legend in the lower left.
fn draw_lines<'a, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<LogCoord<f64>, Y>>,
    series: Vec<(String, Vec<(f64, f64)>)>,
) -> std::result::Result<(), String> {
    for (i, (label, points)) in series.into_iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)).point_size(4))
            .map_err(|e| e.to_string())?
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
        .map_err(|e| e.to_string())
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

/// Tracing speed against size, one series per method, device and ray kind.
fn series_by_target(rows: &[BenchRow]) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        let Some(rate) = r.mrays_per_s else { continue };
        let label = if r.method == Method::CpuBvh.name() {
            format!("{} on the host, {}", r.method, r.ray_kind)
        } else {
            format!("{} on {}, {}", r.method, r.device, r.ray_kind)
        };
        match series.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push((r.triangles as f64, rate)),
            None => series.push((label, vec![(r.triangles as f64, rate)])),
        }
    }
    series
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_study_takes_each_power_of_ten_below_its_largest_size_then_that_size() {
        let sizes = |to| scaling_sizes(to).unwrap();
        assert_eq!(sizes(10_000), [10_000]);
        assert_eq!(sizes(10_000_000), [10_000, 100_000, 1_000_000, 10_000_000]);
        assert_eq!(
            sizes(300_000_000),
            [
                10_000,
                100_000,
                1_000_000,
                10_000_000,
                100_000_000,
                300_000_000
            ]
        );
        assert_eq!(sizes(LARGEST).last(), Some(&LARGEST));
        for bad in [0, 9_999, LARGEST + 1] {
            let err = scaling_sizes(bad).unwrap_err().to_string();
            assert!(err.contains("--scaling-to"), "{err}");
        }
    }
}
