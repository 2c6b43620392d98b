//! `cltrace render`: scene in, image out, every stage timed.

use std::path::PathBuf;

use crate::bvh::BuildOptions;
use crate::camera::Camera;
use crate::camera::CameraSettings;
use crate::device::{ClDevice, DeviceSelector};
use crate::error::Error;
use crate::error::Result;
use crate::geometry::Aabb;
use crate::input::scene_file::{RenderSettings, SceneDescription};
use crate::output;
use crate::render::integrator::{Accumulation, Light, Lighting, SampleSettings};
use crate::render::{Frame, Method, Shade, ShadeParams, tone_map};
use crate::renderer::{PrepareOptions, Renderer};
use crate::report::{Timings, Verbosity};

// The render settings' defaults and limits, declared here once: the render applies them
// where neither the flags nor the scene file give a setting, and the flags' help
// (src/flags/render.rs) is built from them. The camera's are in `crate::camera`
// (`DEFAULT_WIDTH`, `DEFAULT_HEIGHT`, `AUTO_FOV`, `MAX_RESOLUTION`); cl-bvh's layout
// defaults to the tuned one, else the device's (`crate::device::default_layout`).

/// The method when neither the scene nor the flags name one.
pub const DEFAULT_METHOD: Method = Method::ClBvh;
/// The shading when neither the scene nor the flags name one.
pub const DEFAULT_SHADE: Shade = Shade::Lambert;
/// Samples per pixel when none are given: path tracing needs many, a hard shadow a few
/// (for smooth edges), ambient occlusion one (its rays are in `--ao-samples`).
pub const DEFAULT_SPP: [(Shade, u32); 3] = [(Shade::Path, 16), (Shade::Shadow, 4), (Shade::Ao, 1)];
/// The most samples per pixel accepted (float sums stay exact to about 1 part in 10^3).
pub const MAX_SPP: u32 = 65536;
/// The seed of the random numbers of the progressive modes.
pub const DEFAULT_SEED: u32 = 0;
/// Ambient occlusion rays per sample.
pub const DEFAULT_AO_SAMPLES: u32 = 16;
/// The most ambient occlusion rays per sample accepted (`--ao-samples`).
pub const MAX_AO_SAMPLES: u32 = 1024;
/// Ambient occlusion rays reach this share of the scene's bounding radius by default.
pub const AO_DISTANCE_SHARE: f32 = 0.25;
/// Bounces of the path tracer.
pub const DEFAULT_MAX_BOUNCES: u32 = 8;
/// The most bounces accepted (`--max-bounces`; 0 is direct light only).
pub const MAX_BOUNCES: u32 = 1024;
/// The light of the shadow mode: a sun from above, left and in front (+z, where the auto
/// framing puts the eye).
pub const DEFAULT_LIGHT: &str = "sun:-0.4,1,0.6";

/// The stop flag of progressive renders: set (by Ctrl-C, in the binary) to end sampling
/// early and write what has accumulated.
pub static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Everything `cltrace render` was asked to do.
#[derive(Clone, Debug, Default)]
pub struct RenderRequest {
    /// A scene file (`.toml`) or a mesh file; `None` for the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Camera settings from flags; they override the scene file's.
    pub camera: CameraSettings,
    /// Render settings from flags; they override the scene file's.
    pub render: RenderSettings,
    /// The image to write; its extension picks the format.
    pub output: PathBuf,
    /// Where to write the raw hit records, if anywhere.
    pub hits: Option<PathBuf>,
    /// `--device` (or `CLTRACE_DEVICE`), for OpenCL methods.
    pub device: Option<String>,
    /// How to build the BVH, for BVH methods.
    pub build: BuildOptions,
    /// When the OpenCL device fails (none found, a failed build, out of memory, lost),
    /// render with the same method on the host (cl-bvh becomes cpu-bvh, cl-brute
    /// cpu-brute) instead of ending the run with the error.
    pub fallback_to_cpu: bool,
    /// The tuning cache to read the device's layout and work-group from (`cltrace tune`
    /// writes it); `None` reads none.
    pub tune_cache: Option<PathBuf>,
    /// How much goes to stderr: the summary and stage timings, details with `--verbose`.
    pub verbosity: Verbosity,
}

/// What a finished render reports.
#[derive(Clone, Debug)]
pub(crate) struct RenderOutcome {
    pub(crate) frame: Frame,
    pub(crate) method: Method,
    /// The OpenCL device's name, for OpenCL methods.
    pub(crate) device: Option<String>,
    pub(crate) timings: Timings,
}

/// Refuses sampling settings out of range before any work is done.
pub(crate) fn check_sampling(render: &RenderSettings) -> Result<()> {
    let range = |name: &str, value: Option<u32>, lo: u32, hi: u32| match value {
        Some(v) if !(lo..=hi).contains(&v) => Err(Error::Invalid(format!(
            "{name} {v} is out of range: use {lo} to {hi}"
        ))),
        _ => Ok(()),
    };
    range("--spp", render.spp, 1, MAX_SPP)?;
    range("--ao-samples", render.ao_samples, 1, MAX_AO_SAMPLES)?;
    range("--max-bounces", render.max_bounces, 0, MAX_BOUNCES)?;
    if let Some(d) = render.ao_distance
        && !(d > 0.0 && d.is_finite())
    {
        return Err(Error::Invalid(format!(
            "--ao-distance {d} must be a positive number"
        )));
    }
    if let Some(light) = &render.light {
        light.parse::<Light>().map_err(Error::Invalid)?;
    }
    Ok(())
}

/// The sampling of a progressive shade mode, with its samples per pixel, from the settings
/// (defaults filled in; `None` for the modes that shade one hit).
pub(crate) fn sample_settings(
    render: &RenderSettings,
    shade: Shade,
    bounds: &Aabb,
) -> Result<Option<(SampleSettings, u32)>> {
    let radius = (bounds.extent().length() * 0.5).max(f32::MIN_POSITIVE);
    let lighting = match shade {
        Shade::Ao => Lighting::Ao {
            samples: render.ao_samples.unwrap_or(DEFAULT_AO_SAMPLES),
            distance: render.ao_distance.unwrap_or(AO_DISTANCE_SHARE * radius),
        },
        Shade::Shadow => Lighting::Shadow {
            light: render
                .light
                .as_deref()
                .unwrap_or(DEFAULT_LIGHT)
                .parse()
                .map_err(Error::Invalid)?,
        },
        Shade::Path => Lighting::Path {
            max_bounces: render.max_bounces.unwrap_or(DEFAULT_MAX_BOUNCES),
        },
        Shade::Normal | Shade::Depth | Shade::Lambert => return Ok(None),
    };
    let default_spp = DEFAULT_SPP
        .iter()
        .find(|(s, _)| *s == shade)
        .map_or(1, |(_, n)| *n);
    let settings = SampleSettings {
        lighting,
        offset: 1e-4 * radius,
        seed: render.seed.unwrap_or(DEFAULT_SEED),
    };
    Ok(Some((settings, render.spp.unwrap_or(default_spp))))
}

/// Runs a render request and reports it on stderr: the image written (size, method,
/// device) and the stage timings.
pub fn render(req: &RenderRequest) -> Result<()> {
    let outcome = run(req)?;
    let on = outcome
        .device
        .map(|d| format!(" on {d}"))
        .unwrap_or_default();
    req.verbosity.say(format!(
        "wrote {} ({}x{}, {}{on})",
        req.output.display(),
        outcome.frame.width,
        outcome.frame.height,
        outcome.method.name(),
    ));
    req.verbosity.say(outcome.timings.summary());
    Ok(())
}

/// Runs a render request end to end. Every check that needs no work (output format and
/// folder, resolution, field of view, device) happens before the mesh is loaded. With
/// `fallback_to_cpu` (`--fallback cpu`), a device failure (none found, a failed build, out of memory, lost)
/// reruns the render on the host, saying so; without it, it is the run's error.
pub(crate) fn run(req: &RenderRequest) -> Result<RenderOutcome> {
    let scene = SceneDescription::named(req.scene.as_deref())?;
    let method = req
        .render
        .method
        .or(scene.render.method)
        .unwrap_or(DEFAULT_METHOD);
    match render_with(req, &scene, method) {
        Err(e @ Error::Device(_)) if req.fallback_to_cpu => {
            let host = match method {
                Method::ClBrute => Method::CpuBrute,
                _ => Method::CpuBvh,
            };
            req.verbosity.say(format!(
                "note: {e}; rendering with {} instead (--fallback cpu)",
                host.name()
            ));
            render_with(req, &scene, host)
        }
        outcome => outcome,
    }
}

fn render_with(
    req: &RenderRequest,
    scene: &SceneDescription,
    method: Method,
) -> Result<RenderOutcome> {
    let v = req.verbosity;
    let camera_settings = req.camera.over(scene.camera);
    let render = req.render.clone().over(scene.render.clone());
    let shade = render.shade.unwrap_or(DEFAULT_SHADE);
    check_sampling(&render)?;

    output::image_format(&req.output)?;
    req.build.check()?;
    if let Some(hits) = &req.hits {
        output::check_folder(hits)?;
    }
    crate::camera::check_settings(&camera_settings)?;
    let selector = DeviceSelector::from_flag_or_env(req.device.as_deref())?;

    // Opening a GPU driver takes a few hundred milliseconds: do it while the mesh loads.
    // A device error still wins over a mesh error, as it would have come first.
    let mut timings = Timings::default();
    let (device, mesh) = std::thread::scope(|s| {
        let opening = method
            .uses_opencl()
            .then(|| s.spawn(|| ClDevice::select(&selector)));
        let mesh = timings.time("load", || scene.mesh.load_with_materials());
        let device = match opening {
            Some(handle) => Some(handle.join().expect("opening a device does not panic")?),
            None => None,
        };
        Ok::<_, crate::Error>((device, mesh?))
    })?;
    let crate::input::MeshFile {
        mesh,
        materials,
        warnings,
        notes,
    } = mesh;
    for warning in warnings {
        v.say(format!("warning: {warning}"));
    }
    for note in notes {
        v.detail(format!("note: {note}"));
    }
    if let Some(d) = &device {
        v.detail(format!("device: {}", d.info));
    }
    v.detail(format!(
        "mesh: {} ({} triangles, {} vertices, {} of zero area)",
        scene.mesh.name(),
        mesh.triangle_count(),
        mesh.positions.len(),
        mesh.degenerate_count()
    ));
    let bounds = mesh.bounds();
    let camera = Camera::from_settings(&camera_settings, &bounds)?;
    v.detail(format!(
        "camera: eye {:?}, look-at {:?}, up {:?}, fov {}, {}x{}",
        camera.eye.to_array(),
        camera.look_at.to_array(),
        camera.up.to_array(),
        camera.fov,
        camera.width,
        camera.height
    ));
    let sampling = sample_settings(&render, shade, &bounds)?;
    let shade = ShadeParams::new(shade, &camera, &bounds);

    // What `cltrace tune` found for this device: its layout unless one is asked for, and
    // its work-group shape.
    let tuned = match (&device, method) {
        (Some(d), Method::ClBvh) => req
            .tune_cache
            .as_deref()
            .and_then(|path| crate::tune::TuneCache::load(path).get(&d.info).cloned()),
        _ => None,
    };
    let tuned_layout = tuned.as_ref().map(|t| t.layout);
    let options = PrepareOptions {
        build: req.build,
        layout: render.layout.or(tuned.as_ref().map(|t| t.layout)),
        work_group: tuned.map(|t| t.work_group),
        sampling: sampling.is_some(),
    };
    let mut renderer = Renderer::prepare(
        method,
        &mesh,
        &materials,
        &options,
        device.as_ref(),
        &mut timings,
    )?;
    if let Some((layout, [across, down])) = renderer.kernels() {
        let what = match layout {
            None => "brute force".to_string(),
            Some(l) if render.layout.is_some() => format!("{} layout (asked for)", l.name()),
            Some(l) if tuned_layout == Some(l) => format!("{} layout (tuning cache)", l.name()),
            Some(l) => format!("{} layout (the device's default)", l.name()),
        };
        let cache = match (&req.tune_cache, tuned_layout) {
            (Some(path), Some(_)) => format!(", tuned in {}", path.display()),
            _ => String::new(),
        };
        v.detail(format!(
            "kernels: {what}, {across}x{down} work-groups{cache}"
        ));
    }
    if let Some(s) = &renderer.bvh {
        v.detail(format!(
            "bvh: {} nodes, {} leaves, depth {}, mean leaf {:.2}, SAH cost {:.2}, {} threads",
            s.nodes,
            s.leaves,
            s.depth,
            s.mean_leaf_size,
            s.sah_cost,
            rayon::current_num_threads()
        ));
    }
    let (mut frame, times) = renderer.render(&camera, &shade, v.progress())?;
    let (traced, read_back) = if method.uses_opencl() {
        ("kernel", "read-back")
    } else {
        ("trace", "read-back")
    };
    timings.add(traced, times.trace_ms);
    if method.uses_opencl() {
        timings.add(read_back, times.read_back_ms);
    }
    if let Some((settings, spp)) = sampling {
        let mut accumulation = Accumulation::new(camera.width, camera.height);
        let times = renderer.render_samples(
            &camera,
            &settings,
            0..spp,
            &mut accumulation,
            &STOP,
            v.progress(),
        )?;
        timings.add("samples", times.trace_ms);
        if method.uses_opencl() {
            timings.add(read_back, times.read_back_ms);
        }
        let taken = accumulation.pixels.iter().map(|p| p[3] as u64).sum::<u64>() as f64
            / accumulation.pixels.len() as f64;
        if taken < spp as f64 {
            v.say(format!(
                "stopped early: {taken:.1} of {spp} samples per pixel were taken; writing those"
            ));
        }
        v.detail(format!(
            "samples: {taken:.1} per pixel, {:.2} million rays, {:.1} Mrays/s",
            accumulation.rays as f64 / 1e6,
            accumulation.rays as f64 / times.trace_ms.max(1e-9) / 1e3
        ));
        let radiance = accumulation.radiance();
        frame.colors = tone_map(&radiance, shade.shade);
        frame.radiance = Some(radiance);
    }

    timings.time("write", || -> Result<()> {
        output::write_image(&frame, &req.output)?;
        if let Some(hits) = &req.hits {
            output::write_hits(&frame, hits)?;
        }
        Ok(())
    })?;
    Ok(RenderOutcome {
        frame,
        method,
        device: device.map(|d| d.info.name),
        timings,
    })
}
