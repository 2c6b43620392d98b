//! `cltrace tune`: measures each OpenCL device's layouts and work-group shapes
//! (`crate::tune::tune_device`), prints them as a Markdown table and keeps the best in the
//! tuning cache.

use std::path::PathBuf;

use crate::device::{ClDevice, DeviceSelector, list_devices};
use crate::error::{Error, Result};
use crate::input::scene_file::SceneDescription;
use crate::report::{Verbosity, print_data};
use crate::tune::{TuneCache, Tuning, tune_device};

/// Everything `cltrace tune` was asked to do.
#[derive(Clone, Debug)]
pub struct TuneRequest {
    /// A scene file or a mesh; `None` for the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Device selectors; `None` for every device.
    pub devices: Option<Vec<String>>,
    /// Timed frames per combination, after one warm-up frame.
    pub repetitions: u32,
    /// The cache file the results go into (other devices' entries are kept); `None` when
    /// no location is known, which is an error.
    pub cache: Option<PathBuf>,
    /// How much goes to stderr: which device is tuned, its best and where it was saved.
    pub verbosity: Verbosity,
}

/// Tunes every chosen device, printing each measured combination, and saves the best of
/// each in the cache. The measurements themselves never read the cache: every layout and
/// work-group shape is set explicitly. Interrupted (Ctrl-C), it ends with
/// [`Error::Interrupted`] and leaves the cache as it was: a half-tuned device's best is
/// not known.
pub fn tune(req: &TuneRequest) -> Result<()> {
    let verbosity = req.verbosity;
    let path = req.cache.as_ref().ok_or_else(|| {
        Error::Invalid("no cache location: set CLTRACE_TUNE_CACHE or HOME".into())
    })?;
    // The cache must be writable before an hour of measuring, not after.
    if let Some(folder) = path.parent().filter(|f| !f.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder).map_err(|e| Error::output(path, e))?;
    }
    crate::output::check_output(path)?;
    let scene = SceneDescription::named(req.scene.as_deref())?;
    let mesh = scene.meshes.load()?;
    let all = list_devices()?;
    let chosen: Vec<_> = match &req.devices {
        None => all.clone(),
        Some(selectors) => selectors
            .iter()
            .map(|s| s.parse::<DeviceSelector>()?.pick(&all).cloned())
            .collect::<Result<_>>()?,
    };
    let mut cache = TuneCache::load(path);
    print_data(
        "| device | layout | work-group | primary Mrays/s | diffuse Mrays/s |\n|---|---|---|---|---|\n",
    );
    for info in chosen {
        let device = ClDevice::open(info)?;
        verbosity.say(format!(
            "tuning {} on {}",
            device.info.name,
            scene.meshes.name()
        ));
        let results = tune_device(&device, &mesh, req.repetitions, &mut |r| {
            print_data(&format!(
                "| {} | {} | {}x{} | {:.1} | {:.1} |\n",
                device.info.name,
                r.layout.name(),
                r.work_group[0],
                r.work_group[1],
                r.primary_mrays,
                r.diffuse_mrays
            ));
        })?;
        let best = &results[0];
        verbosity.say(format!(
            "best on {}: {} with {}x{} work-groups ({:.1} primary, {:.1} diffuse Mrays/s)",
            device.info.name,
            best.layout.name(),
            best.work_group[0],
            best.work_group[1],
            best.primary_mrays,
            best.diffuse_mrays
        ));
        cache.devices.insert(
            device.info.key(),
            Tuning {
                layout: best.layout,
                work_group: best.work_group,
                primary_mrays: best.primary_mrays,
                diffuse_mrays: best.diffuse_mrays,
                scene: scene.meshes.name(),
            },
        );
    }
    cache.save(path)?;
    verbosity.say(format!("saved to {}", path.display()));
    Ok(())
}
