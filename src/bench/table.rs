//! The benchmark rows as a Markdown table, CSV and JSON.

use std::path::Path;

use super::BenchRow;
use crate::error::{Error, Result};
use crate::output::write_atomically;

const HEADER: [&str; 16] = [
    "scene",
    "triangles",
    "resolution",
    "method",
    "device",
    "CUs",
    "rays",
    "load ms",
    "build ms",
    "threads",
    "kernel ms (median)",
    "kernel ms (min)",
    "Mrays/s",
    "Msamples/s",
    "SAH cost",
    "device MB",
];

fn num(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(v) if v >= 100.0 => format!("{v:.0}"),
        Some(v) if v >= 10.0 => format!("{v:.1}"),
        Some(v) if v >= 1.0 => format!("{v:.2}"),
        Some(v) => format!("{v:.3}"),
    }
}

fn cells(r: &BenchRow) -> [String; 16] {
    let (median, min, mrays, msamples) = match &r.skipped {
        Some(why) => (
            format!("skipped: {why}"),
            "-".into(),
            "-".into(),
            "-".into(),
        ),
        None => (
            num(r.kernel_ms_median),
            num(r.kernel_ms_min),
            num(r.mrays_per_s),
            num(r.msamples_per_s),
        ),
    };
    // A path row names its samples per pixel and path length, which its speeds depend on.
    let kind = match (r.spp, r.segments) {
        (Some(spp), Some(segments)) => format!("{} ({spp} spp, {segments} segments)", r.ray_kind),
        _ => r.ray_kind.clone(),
    };
    [
        r.scene.clone(),
        r.triangles.to_string(),
        format!("{}x{}", r.width, r.height),
        r.method.clone(),
        r.device.clone(),
        r.compute_units.to_string(),
        kind,
        num(Some(r.load_ms)),
        num(r.build_ms),
        r.build_threads.map_or("-".into(), |t| t.to_string()),
        median,
        min,
        mrays,
        msamples,
        r.sah_cost.map_or("-".into(), |c| format!("{c:.2}")),
        format!("{:.1}", r.device_mb),
    ]
}

/// One row as a line, for progress output.
pub(super) fn row_line(r: &BenchRow) -> String {
    cells(r).join(" | ")
}

/// The rows as a Markdown table.
pub(crate) fn markdown(rows: &[BenchRow]) -> String {
    let mut out = format!("| {} |\n", HEADER.join(" | "));
    out += &format!("|{}\n", HEADER.iter().map(|_| "---|").collect::<String>());
    for r in rows {
        out += &format!("| {} |\n", cells(r).join(" | "));
    }
    out
}

/// The rows as CSV, one column per field, written atomically.
pub(crate) fn write_csv(rows: &[BenchRow], path: &Path) -> Result<()> {
    crate::output::check_output(path)?;
    write_atomically(path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        for r in rows {
            csv.serialize(r).map_err(|e| Error::output(path, e))?;
        }
        csv.flush().map_err(|e| Error::output(path, e))
    })
}

/// The rows as a JSON array of objects, written atomically.
pub(crate) fn write_json(rows: &[BenchRow], path: &Path) -> Result<()> {
    crate::output::check_output(path)?;
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(w, rows).map_err(|e| Error::output(path, e))
    })
}
