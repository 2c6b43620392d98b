//! `cltrace tune`: for each OpenCL device, the BVH layout and work-group shape that trace
//! fastest, measured on a scene and remembered in a cache file that later renders read.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::bench::{RayKind, diffuse_rays};
use crate::bvh::Layout;
use crate::camera::Camera;
use crate::device::{ClDevice, DeviceInfo};
use crate::error::{Error, Result};
use crate::material::Materials;
use crate::mesh::Mesh;
use crate::output::write_atomically;
use crate::render::{Method, Shade, ShadeParams};
use crate::renderer::{PrepareOptions, Renderer};
use crate::report::Timings;

/// Work-group shapes tried (pixels across, down); those over a device's limit are skipped.
pub const SHAPES: [[usize; 2]; 8] = [
    [8, 4],
    [8, 8],
    [16, 4],
    [16, 8],
    [16, 16],
    [32, 2],
    [32, 4],
    [64, 1],
];

/// What `tune` found best for a device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// The layout cl-bvh renders in on this device.
    pub layout: Layout,
    /// The work-group shape of its kernels: pixels across, down (one of [`SHAPES`]).
    pub work_group: [usize; 2],
    /// Its primary-ray speed on the tuning scene, millions of rays per second (the best is
    /// chosen by the geometric mean of this and `diffuse_mrays`).
    pub primary_mrays: f64,
    /// Its speed on the benchmark protocol's diffuse rays, millions of rays per second.
    pub diffuse_mrays: f64,
    /// The scene it was measured on.
    pub(crate) scene: String,
}

/// The tuning cache: `CLTRACE_TUNE_CACHE`, else `$XDG_CACHE_HOME/cltrace/tune.toml`, else
/// `~/.cache/cltrace/tune.toml`.
pub fn cache_path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CLTRACE_TUNE_CACHE") {
        return Some(PathBuf::from(p));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("cltrace").join("tune.toml"))
}

/// Every device's tuning, keyed by [`DeviceInfo::key`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct TuneCache {
    pub(crate) devices: BTreeMap<String, Tuning>,
}

impl TuneCache {
    /// Reads the cache; a missing or unreadable one is empty (tuning is an optimisation,
    /// never a reason to fail a render).
    pub fn load(path: &Path) -> TuneCache {
        std::fs::read_to_string(path)
            .ok()
            .and_then(|text| toml::from_str(&text).ok())
            .unwrap_or_default()
    }

    pub(crate) fn save(&self, path: &Path) -> Result<()> {
        if let Some(folder) = path.parent() {
            std::fs::create_dir_all(folder).map_err(|e| Error::output(path, e))?;
        }
        let text = format!(
            "# cltrace tune: the fastest BVH layout and work-group per OpenCL device.\n{}",
            toml::to_string(self).map_err(|e| Error::output(path, e))?
        );
        write_atomically(path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())
                .map_err(|e| Error::output(path, e))
        })
    }

    /// The tuning for `device`, if it was tuned with the same driver.
    pub fn get(&self, device: &DeviceInfo) -> Option<&Tuning> {
        self.devices.get(&device.key())
    }
}

/// One measured combination.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TuneResult {
    pub(crate) layout: Layout,
    pub(crate) work_group: [usize; 2],
    pub(crate) primary_mrays: f64,
    pub(crate) diffuse_mrays: f64,
}

impl TuneResult {
    /// The score the best is chosen by: the geometric mean of both ray kinds' speeds.
    pub(crate) fn score(&self) -> f64 {
        (self.primary_mrays * self.diffuse_mrays).sqrt()
    }
}

/// Measures every layout and work-group shape on `device` (1920x1080, auto framing, primary
/// and diffuse rays, median of `repetitions` frames after a warm-up) and returns them all,
/// best first. `on_result` sees each as it is measured.
pub(crate) fn tune_device(
    device: &ClDevice,
    mesh: &Mesh,
    repetitions: u32,
    on_result: &mut dyn FnMut(&TuneResult),
) -> Result<Vec<TuneResult>> {
    let camera = Camera::bench(&mesh.bounds(), 1920, 1080)?;
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds());
    let rays = diffuse_rays(mesh, &camera, 1);
    let mut results = Vec::new();
    for layout in Layout::ALL {
        let options = PrepareOptions {
            layout: Some(layout),
            ..Default::default()
        };
        let mut renderer = Renderer::prepare(
            Method::ClBvh,
            mesh,
            &Materials::default(),
            &options,
            Some(device),
            &mut Timings::default(),
        )?;
        for shape in SHAPES {
            if shape[0] * shape[1] > device.info.max_work_group_size {
                continue;
            }
            renderer.set_work_group(shape)?;
            crate::interrupt::check()?;
            let median = |kind: RayKind, renderer: &mut Renderer| -> Result<f64> {
                let mut frame = || -> Result<f64> {
                    Ok(match kind {
                        RayKind::Diffuse => {
                            renderer.trace_rays(&rays, f32::INFINITY, false)?.1.trace_ms
                        }
                        // Tuning measures primary and diffuse rays only.
                        RayKind::Primary | RayKind::Diffuse16 | RayKind::Path => {
                            renderer.render(&camera, &shade, false)?.1.trace_ms
                        }
                    })
                };
                frame()?;
                let mut ms: Vec<f64> = (0..repetitions.max(1))
                    .map(|_| frame())
                    .collect::<Result<_>>()?;
                ms.sort_by(f64::total_cmp);
                Ok(ms[ms.len() / 2])
            };
            let primary = median(RayKind::Primary, &mut renderer)?;
            let diffuse = median(RayKind::Diffuse, &mut renderer)?;
            let result = TuneResult {
                layout,
                work_group: shape,
                primary_mrays: camera.width as f64 * camera.height as f64 / primary / 1e3,
                diffuse_mrays: rays.len() as f64 / diffuse / 1e3,
            };
            on_result(&result);
            results.push(result);
        }
    }
    results.sort_by(|a, b| b.score().total_cmp(&a.score()));
    Ok(results)
}
