//! `cltrace devices`: every OpenCL platform and device, as a table on stdout.

use crate::device::{DeviceInfo, INSTALL_HINT, list_devices};
use crate::error::{Error, Result};

/// The device table, one row per device; an error when there is none.
pub fn devices_table() -> Result<String> {
    let devices = list_devices()?;
    if devices.is_empty() {
        return Err(Error::Device(format!(
            "OpenCL platforms are installed but offer no device: {INSTALL_HINT}"
        )));
    }
    Ok(format_table(&devices))
}

fn mib(bytes: u64) -> String {
    format!("{} MiB", bytes >> 20)
}

pub(crate) fn format_table(devices: &[DeviceInfo]) -> String {
    let header = [
        "P:D",
        "name",
        "type",
        "compute units",
        "global memory",
        "max allocation",
        "max work-group",
        "OpenCL C",
        "platform",
    ];
    let rows: Vec<[String; 9]> = devices
        .iter()
        .map(|d| {
            [
                d.index(),
                d.name.clone(),
                d.kind.to_string(),
                d.compute_units.to_string(),
                mib(d.global_memory),
                mib(d.max_allocation),
                d.max_work_group_size.to_string(),
                d.opencl_c_version.clone(),
                d.platform_name.clone(),
            ]
        })
        .collect();
    let mut widths = header.map(str::len);
    for row in &rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let line = |cells: Vec<&str>| {
        cells
            .iter()
            .zip(widths)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect::<Vec<_>>()
            .join("  ")
            .trim_end()
            .to_string()
    };
    let mut out = line(header.to_vec()) + "\n";
    for row in &rows {
        out += &line(row.iter().map(String::as_str).collect());
        out.push('\n');
    }
    out
}
