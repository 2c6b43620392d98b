//! `cltrace render`: scene in, image out, every stage timed.

use std::path::PathBuf;

use super::Ending;
use crate::bvh::BuildOptions;
use crate::camera::Camera;
use crate::camera::CameraSettings;
use crate::device::{ClDevice, DeviceSelector, Kernel, Kernels};
use crate::error::Error;
use crate::error::Result;
use crate::geometry::Aabb;
use crate::input::lights::{EnvironmentFlags, LightsDescription};
use crate::input::scene_file::{RenderSettings, SceneDescription};
use crate::mesh::Mesh;
use crate::output::{self, HitsFormat};
use crate::render::integrator::{Accumulation, Light, Lighting, Region, SampleSettings};
use crate::render::{Frame, Hit, Method, Shade, ShadeParams, tone_map};
use crate::renderer::{PrepareOptions, Renderer, TraceTimes};
use crate::report::{Timings, Verbosity, format_ms};

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
    /// The layout of the hit records.
    pub hits_format: HitsFormat,
    /// Where to write a JSON summary of the run, if anywhere ([`RunSummary`]).
    pub json: Option<PathBuf>,
    /// `--device` (or `CLTRACE_DEVICE`), for OpenCL methods: one selector, or a list
    /// (`gpu,cpu`, `all`) that splits the samples of the progressive modes over the devices.
    pub device: Option<String>,
    /// `--region`: render only these pixels, into a part ([`crate::output::part`]).
    pub region: Option<Region>,
    /// `--samples`: render only these sample indices, into a part.
    pub samples: Option<std::ops::Range<u32>>,
    /// How to build the BVH, for BVH methods.
    pub build: BuildOptions,
    /// When the OpenCL device fails (none found, a failed build, out of memory, lost),
    /// render with the same method on the host (cl-bvh becomes cpu-bvh, cl-brute
    /// cpu-brute) instead of ending the run with the error.
    pub fallback_to_cpu: bool,
    /// The tuning cache to read the device's layout and work-group from (`cltrace tune`
    /// writes it); `None` reads none.
    pub tune_cache: Option<PathBuf>,
    /// The folder compiled kernels are kept in between runs
    /// ([`crate::device::program_cache_folder`]); `None` compiles every time.
    pub program_cache: Option<PathBuf>,
    /// How much goes to stderr: the summary and stage timings, details with `--verbose`.
    pub verbosity: Verbosity,
    /// `--frames`: render these frames of the scene's camera animation instead, each to
    /// the outputs' frame patterns ([`super::frames`]).
    pub frames: Option<super::frames::Frames>,
    /// The frame of the scene's camera animation a single render takes its camera from.
    pub frame: u32,
    /// `--environment`, `--environment-intensity`, `--environment-rotate`: over the scene's.
    pub environment: EnvironmentFlags,
}

/// What a finished render reports.
#[derive(Clone, Debug)]
pub(crate) struct RenderOutcome {
    pub(crate) frame: Frame,
    pub(crate) method: Method,
    /// The OpenCL device's name, for OpenCL methods.
    pub(crate) device: Option<String>,
    pub(crate) timings: Timings,
    /// The summary `--json` writes.
    pub(crate) summary: RunSummary,
}

/// The machine-readable summary of one render (`render --json FILE`). Times are in
/// milliseconds; `stages` add up to `wall_ms`.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunSummary {
    /// cltrace's version.
    pub version: &'static str,
    /// The scene or mesh rendered.
    pub scene: String,
    /// The method that rendered it (after a `--fallback`, the host method).
    pub method: String,
    /// The OpenCL device, for OpenCL methods.
    pub device: Option<String>,
    /// The BVH layout of cl-bvh.
    pub layout: Option<String>,
    /// The OpenCL work-group shape, across and down.
    pub work_group: Option<[usize; 2]>,
    /// Where the layout and work-group came from: `asked for`, `tuning cache`, `the
    /// device's default`.
    pub kernels_from: Option<String>,
    /// Whether the compiled kernels came from the program cache.
    pub program_cache_hit: Option<bool>,
    /// Image size in pixels.
    pub width: u32,
    /// Image size in pixels.
    pub height: u32,
    /// The shade mode.
    pub shade: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Samples per pixel asked for (progressive modes).
    pub spp: Option<u32>,
    /// Samples per pixel taken, the mean over the image (fewer than `spp` when interrupted).
    pub samples_per_pixel: Option<f64>,
    /// Every ray traced: one camera ray a pixel, then the sampling's rays.
    pub rays: u64,
    /// Each stage's time, in the order they ran; `other` is the rest of the wall time.
    pub stages: Vec<Stage>,
    /// The run's wall time, from the start of the command to the last file written.
    pub wall_ms: f64,
    /// The files written (the image, the hit records), in that order.
    pub outputs: Vec<PathBuf>,
    /// False when the render was interrupted and the image holds fewer samples.
    pub complete: bool,
    /// The sampling's wall time, from its start to the sums on the host: the pixel samples
    /// over it are the speed that several devices' speeds add up to. (With one device the
    /// `samples` stage is its kernels' time, with the host's share in `launch` and
    /// `read-back`; with several it is this wall time.)
    pub sampling_ms: Option<f64>,
    /// With several devices: what each did (samples taken, busy time).
    pub devices: Vec<crate::renderer::schedule::DeviceShare>,
    /// The part written, for `--region` or `--samples`: its region and sample range.
    pub part: Option<PartSummary>,
}

/// The part a `--region`/`--samples` render wrote.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PartSummary {
    /// `x0,y0,x1,y1`.
    pub region: String,
    /// `FIRST..END`.
    pub samples: String,
    /// The fingerprint of the settings every part of the render shares.
    pub fingerprint: String,
}

/// One stage of [`RunSummary::stages`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct Stage {
    /// `load`, `build`, `compile`, ...
    pub name: &'static str,
    /// Its time in milliseconds.
    pub ms: f64,
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
    if let Some(a) = render.crease_angle
        && !(0.0..=180.0).contains(&a)
    {
        return Err(Error::Invalid(format!(
            "--crease-angle {a} is out of range: use 0 to 180 degrees"
        )));
    }
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
/// device) and the stage timings, which add up to the total. Interrupted (Ctrl-C) once
/// every pixel has a sample, the image is written with the samples taken and the ending is
/// [`Ending::Partial`]; before that, nothing is written and the error is
/// [`Error::Interrupted`]. With `frames`, renders each frame so ([`super::frames`]).
pub fn render(req: &RenderRequest) -> Result<Ending> {
    match &req.frames {
        Some(frames) => super::frames::render_frames(req, frames),
        None => super::frames::refuse_patterns(req).and_then(|()| render_single(req)),
    }
}

/// One image: [`render`] without `frames`.
pub(crate) fn render_single(req: &RenderRequest) -> Result<Ending> {
    let start = std::time::Instant::now();
    if let Some(json) = &req.json {
        output::check_output(json)?;
    }
    let mut outcome = run(req)?;
    let on = outcome
        .device
        .as_ref()
        .map(|d| format!(" on {d}"))
        .unwrap_or_default();
    let ending = match outcome.summary.complete {
        true => Ending::Complete,
        false => Ending::Partial,
    };
    let partial = match (outcome.summary.samples_per_pixel, outcome.summary.spp) {
        (Some(taken), Some(spp)) if ending == Ending::Partial => {
            format!(", interrupted: {taken:.1} of {spp} samples per pixel")
        }
        _ => String::new(),
    };
    req.verbosity.say(format!(
        "wrote {} ({}x{}, {}{on}{partial})",
        req.output.display(),
        outcome.frame.width,
        outcome.frame.height,
        outcome.method.name(),
    ));
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    outcome.timings.close(wall_ms);
    req.verbosity.say(format!(
        "{}, total {}",
        outcome.timings.summary(),
        format_ms(wall_ms)
    ));
    if let Some(json) = &req.json {
        let mut summary = outcome.summary;
        summary.wall_ms = wall_ms;
        summary.stages = outcome
            .timings
            .stages()
            .map(|(name, ms)| Stage { name, ms })
            .collect();
        let text = serde_json::to_string_pretty(&summary).expect("a summary serialises") + "\n";
        output::write_atomically(json, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())
                .map_err(|e| Error::output(json, e))
        })?;
    }
    Ok(ending)
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
        output::check_output(hits)?;
    }
    for (a, b) in [
        (Some(&req.output), req.hits.as_ref()),
        (Some(&req.output), req.json.as_ref()),
        (req.hits.as_ref(), req.json.as_ref()),
    ] {
        if let (Some(a), Some(b)) = (a, b)
            && a == b
            && a != std::path::Path::new("/dev/null")
        {
            return Err(Error::Invalid(format!(
                "{} is named for two outputs: give each its own file",
                a.display()
            )));
        }
    }
    crate::camera::check_settings(&camera_settings)?;
    let lights_described = req.environment.over(scene.lights.clone())?;
    let selectors = DeviceSelector::list_from_flag_or_env(req.device.as_deref())?;
    let part = check_part(req, &camera_settings, shade)?;

    // Opening a GPU driver takes a few hundred milliseconds: do it while the mesh loads.
    // A device error still wins over a mesh error, as it would have come first.
    let mut timings = Timings::default();
    let (devices, mesh) = std::thread::scope(|s| {
        let opening = method
            .uses_opencl()
            .then(|| s.spawn(|| ClDevice::select_each(&selectors)));
        let mesh = timings.time("load", || scene.meshes.load_with_materials());
        // What opening the devices took beyond the load is a stage of its own.
        let devices = match opening {
            Some(handle) => {
                let mut devices = timings.time("open", || {
                    handle.join().expect("opening a device does not panic")
                })?;
                for device in &mut devices {
                    if let Some(folder) = &req.program_cache {
                        device.use_program_cache(folder.clone());
                    }
                }
                devices
            }
            None => Vec::new(),
        };
        Ok::<_, crate::Error>((devices, mesh?))
    })?;
    let device = devices.first();
    // `bounds` are the meshes' without the ground plane: the camera frames them.
    let crate::input::scene::LoadedScene { file, bounds } = mesh;
    let crate::input::MeshFile {
        mesh,
        materials,
        warnings,
        notes,
        camera: file_camera,
    } = file;
    for warning in warnings {
        v.say(format!("warning: {warning}"));
    }
    for note in notes {
        v.detail(format!("note: {note}"));
    }
    crate::interrupt::check()?;
    for d in &devices {
        v.detail(format!("device: {}", d.info));
    }
    // Counting triangles of zero area is a pass over every triangle: only when shown.
    if v.shows_details() {
        v.detail(format!(
            "mesh: {} ({} triangles, {} vertices, {} of zero area)",
            scene.meshes.name(),
            mesh.triangle_count(),
            mesh.positions.len(),
            mesh.degenerate_count()
        ));
    }
    let camera_settings = match &scene.animation {
        Some(a) => a.settings_at(req.frame, &req.camera, &scene.camera, &bounds)?,
        None => with_file_camera(camera_settings, file_camera, v),
    };
    let camera = Camera::from_settings(&camera_settings, &bounds)?;
    // The lights besides emitters light the path tracer only.
    let lights = match shade {
        Shade::Path => {
            let described = &lights_described;
            let lights = match described.environment.is_some() {
                true => timings.time("environment", || described.load())?,
                false => described.load()?,
            };
            std::sync::Arc::new(lights)
        }
        _ => {
            if lights_described.environment.is_some() || !lights_described.punctual.is_empty() {
                v.detail(format!(
                    "note: the scene's environment and lights light `--shade path` only, not {}",
                    shade.name()
                ));
            }
            Default::default()
        }
    };
    v.detail(format!(
        "camera: eye {:?}, look-at {:?}, up {:?}, fov {}, {}x{}{}",
        camera.eye.to_array(),
        camera.look_at.to_array(),
        camera.up.to_array(),
        camera.fov,
        camera.width,
        camera.height,
        camera.lens_description()
    ));
    if camera.aperture() > 0.0 && !matches!(shade, Shade::Ao | Shade::Shadow | Shade::Path) {
        // A single-hit mode traces one ray through each pixel's centre: there is no lens
        // sample to blur with, so the image is the pinhole's.
        v.say(format!(
            "warning: --aperture {} blurs only in the progressive modes (ao, shadow, path); \
             {} renders as a pinhole",
            camera.aperture(),
            shade.name()
        ));
    }
    let sampling = sample_settings(&render, shade, &bounds)?;
    let shade = ShadeParams::new(shade, &camera, &bounds)
        .with_barycentrics(req.hits.is_some() && req.hits_format == HitsFormat::V2);

    // What `cltrace tune` found for each device: its layout unless one is asked for, and
    // its work-group shape.
    let tuned_for = |d: &ClDevice| match method {
        Method::ClBvh => req
            .tune_cache
            .as_deref()
            .and_then(|path| crate::tune::TuneCache::load(path).get(&d.info).cloned()),
        _ => None,
    };
    // The progressive modes trace their own camera rays: a frame of primary rays is traced
    // for the single-hit modes and for hit records only (not for a part, whose image is the
    // samples of its region).
    let primary_frame = part.is_none() && (sampling.is_none() || req.hits.is_some());
    // The kernels this frame uses: a cold compile costs about as much per kernel.
    let general = shade.barycentrics || camera.pinhole().is_orthographic();
    let kernels = match (primary_frame, general) {
        (false, _) => Kernels::NONE,
        (true, false) => Kernels::PRIMARY,
        (true, true) => Kernels::PRIMARY.with(Kernel::TracePrimaryGeneral),
    }
    .with_some(sampling.and(Kernel::sampling(shade.shade)));
    let options_for = |tuned: Option<crate::tune::Tuning>| PrepareOptions {
        build: req.build,
        layout: render.layout.or(tuned.as_ref().map(|t| t.layout)),
        work_group: tuned.map(|t| t.work_group),
        kernels,
        crease_angle: render.crease_angle,
        two_sided_lights: render.two_sided_lights.unwrap_or(false),
        lights: lights.clone(),
    };
    let tuned = device.and_then(tuned_for);
    let mut renderers = match devices.len() {
        0 | 1 => vec![Renderer::prepare(
            method,
            &mesh,
            &materials,
            &options_for(tuned),
            device,
            &mut timings,
        )?],
        _ => {
            let options: Vec<_> = devices.iter().map(|d| options_for(tuned_for(d))).collect();
            let list: Vec<&ClDevice> = devices.iter().collect();
            Renderer::prepare_each(method, &mesh, &materials, &options, &list, &mut timings)?
        }
    };
    crate::interrupt::check()?;
    let mut summary = RunSummary {
        version: env!("CARGO_PKG_VERSION"),
        scene: scene.meshes.name(),
        method: method.name().to_string(),
        device: device.map(|d| d.info.name.clone()),
        width: camera.width,
        height: camera.height,
        shade: shade.shade.name().to_string(),
        triangles: mesh.triangle_count(),
        complete: true,
        ..RunSummary::default()
    };
    for (i, renderer) in renderers.iter().enumerate() {
        let Some((layout, work_group)) = renderer.kernels() else {
            continue;
        };
        let this_tuned = devices.get(i).and_then(tuned_for).map(|t| t.layout);
        let from = match layout {
            None => None,
            Some(_) if render.layout.is_some() => Some("asked for"),
            Some(l) if this_tuned == Some(l) => Some("tuning cache"),
            Some(_) => Some("the device's default"),
        };
        let what = match (layout, from) {
            (Some(l), Some(from)) => format!("{} layout ({from})", l.name()),
            _ => "brute force".to_string(),
        };
        let cache = match (&req.tune_cache, this_tuned) {
            (Some(path), Some(_)) => format!(", tuned in {}", path.display()),
            _ => String::new(),
        };
        let [across, down] = work_group;
        let on = match devices.len() {
            0 | 1 => String::new(),
            _ => format!(" on {}", devices[i].info.name),
        };
        v.detail(format!(
            "kernels{on}: {what}, {across}x{down} work-groups{cache}"
        ));
        if i == 0 {
            summary.layout = layout.map(|l| l.name().to_string());
            summary.work_group = Some(work_group);
            summary.kernels_from = from.map(String::from);
        }
        if let Some(cache) = renderer.program_cache() {
            v.detail(cache.describe());
            if i == 0 {
                summary.program_cache_hit = Some(cache.hit());
            }
        }
    }
    if let Some(s) = &renderers[0].bvh {
        v.detail(format!(
            "bvh: {} builder, {} nodes, {} leaves, depth {}, mean leaf {:.2}, SAH cost {:.2}, \
             {} threads",
            req.build.builder.for_triangles(s.triangles).name(),
            s.nodes,
            s.leaves,
            s.depth,
            s.mean_leaf_size,
            s.sah_cost,
            rayon::current_num_threads()
        ));
    }
    let (traced, read_back) = match method.uses_opencl() {
        true => ("kernel", Some("read-back")),
        false => ("trace", None),
    };
    // Device stages are timed on the device; what the host spent around them (launches,
    // waits, a driver's compile at the first launch) is the `launch` stage.
    let add_times = |timings: &mut Timings, stage, wall_ms: f64, times: &TraceTimes| {
        timings.add(stage, times.trace_ms);
        if let Some(read_back) = read_back {
            timings.add(read_back, times.read_back_ms);
            timings.add(
                "launch",
                (wall_ms - times.trace_ms - times.read_back_ms).max(0.0),
            );
        }
    };
    let mut frame = Frame::new(camera.width, camera.height);
    if primary_frame {
        let start = std::time::Instant::now();
        let (primary, times) = renderers[0].render(&camera, &shade, v.progress())?;
        add_times(&mut timings, traced, elapsed_ms(start), &times);
        frame = primary;
        summary.rays = camera.width as u64 * camera.height as u64;
    }
    let mut accumulation = None;
    if let Some((settings, spp)) = sampling {
        let (region, samples) = match &part {
            Some((region, samples)) => (*region, samples.clone().unwrap_or(0..spp)),
            None => (Region::whole(camera.width, camera.height), 0..spp),
        };
        let mut acc = Accumulation::of_region(camera.width, camera.height, region);
        let start = std::time::Instant::now();
        let times = match renderers.len() {
            1 => renderers[0].render_samples(
                &camera,
                &settings,
                samples.clone(),
                &mut acc,
                crate::interrupt::flag(),
                v.progress(),
            )?,
            _ => {
                let names: Vec<String> = devices.iter().map(|d| d.info.name.clone()).collect();
                let (sums, shares) = crate::renderer::schedule::render_samples(
                    &mut renderers,
                    &names,
                    &camera,
                    &settings,
                    (camera.width, camera.height),
                    region,
                    samples.clone(),
                    crate::interrupt::flag(),
                    v.progress(),
                )?;
                acc = sums;
                for s in &shares {
                    let dropped = match s.dropped_from_tail {
                        true => ", dropped from the tail",
                        false => "",
                    };
                    v.detail(format!(
                        "{}: {:.1}% of the samples in {} units, busy {}{dropped}",
                        s.device,
                        100.0 * s.share,
                        s.units,
                        format_ms(s.busy_ms)
                    ));
                }
                summary.devices = shares;
                // The devices ran at once: the stage is the wall time they took.
                TraceTimes {
                    trace_ms: elapsed_ms(start),
                    read_back_ms: 0.0,
                }
            }
        };
        summary.sampling_ms = Some(elapsed_ms(start));
        add_times(&mut timings, "samples", elapsed_ms(start), &times);
        let counts = acc.pixels.iter().map(|p| p[3] as u64);
        let expected = samples.len() as f64;
        let taken = counts.clone().sum::<u64>() as f64 / acc.pixels.len() as f64;
        if taken < expected {
            // Interrupted. An image where some pixels have no sample would show holes as
            // black: nothing is written until every pixel has one.
            if counts.min().unwrap_or(0) == 0 {
                return Err(Error::Interrupted);
            }
            summary.complete = false;
        }
        v.detail(format!(
            "samples: {taken:.1} per pixel, {:.2} million rays, {:.1} Mrays/s",
            acc.rays as f64 / 1e6,
            acc.rays as f64 / times.trace_ms.max(1e-9) / 1e3
        ));
        summary.spp = Some(samples.len() as u32);
        summary.samples_per_pixel = Some(taken);
        summary.rays += acc.rays;
        if part.is_none() {
            let (radiance, colors) = timings.time("tone-map", || {
                let radiance = acc.radiance();
                let colors = tone_map(&radiance, shade.shade);
                (radiance, colors)
            });
            frame.colors = colors;
            frame.radiance = Some(radiance);
        }
        accumulation = Some((acc, samples));
    }
    if let Some((acc, samples)) = accumulation.filter(|_| part.is_some()) {
        let part = crate::output::part::Part {
            settings: part_settings(
                &mesh,
                &materials,
                &camera,
                shade.shade,
                &sampling,
                render.crease_angle,
                render.two_sided_lights.unwrap_or(false),
                (lights.any()).then_some(&lights_described),
            ),
            accumulation: acc,
            samples,
            shade: shade.shade,
        };
        summary.part = Some(PartSummary {
            region: part.accumulation.region.to_string(),
            samples: format!("{}..{}", part.samples.start, part.samples.end),
            fingerprint: part.fingerprint(),
        });
        timings.time("write", || {
            crate::output::part::write_part(&part, &req.output)
        })?;
        summary.outputs = vec![req.output.clone()];
        let device = devices_named(&devices);
        // What the renderers, the devices and the scene hold is given back as a stage
        // of its own (NVIDIA's driver takes a while).
        let start = std::time::Instant::now();
        drop(renderers);
        drop(devices);
        drop((mesh, materials));
        timings.add("release", elapsed_ms(start));
        return Ok(RenderOutcome {
            frame,
            method,
            device,
            timings,
            summary,
        });
    }
    if let Some(warning) = unlit_warning(&frame, primary_frame, &mesh, &camera, shade.shade) {
        v.say(format!("warning: {warning}"));
    }

    timings.time("write", || -> Result<()> {
        output::write_image(&frame, &req.output)?;
        if let Some(hits) = &req.hits {
            output::write_hits(&frame, hits, req.hits_format)?;
        }
        Ok(())
    })?;
    summary.outputs = std::iter::once(&req.output)
        .chain(&req.hits)
        .cloned()
        .collect();
    let device = devices_named(&devices);
    let start = std::time::Instant::now();
    drop(renderers);
    drop(devices);
    drop((mesh, materials));
    timings.add("release", elapsed_ms(start));
    Ok(RenderOutcome {
        frame,
        method,
        device,
        timings,
        summary,
    })
}

/// The part `--region`/`--samples` ask for (the region, whole when not given, and the
/// sample range, the settings' when not given), or `None` for a whole render; refused
/// before any work where it cannot be a part.
fn check_part(
    req: &RenderRequest,
    camera: &CameraSettings,
    shade: Shade,
) -> Result<Option<(Region, Option<std::ops::Range<u32>>)>> {
    if req.region.is_none() && req.samples.is_none() {
        return Ok(None);
    }
    let flags = match (req.region.is_some(), req.samples.is_some()) {
        (true, true) => "--region and --samples",
        (true, false) => "--region",
        _ => "--samples",
    };
    if !matches!(shade, Shade::Ao | Shade::Shadow | Shade::Path) {
        return Err(Error::Invalid(format!(
            "{flags} render part of the samples of ao, shadow or path; --shade {} renders \
             in one pass: leave {flags} out",
            shade.name()
        )));
    }
    let exr = req
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !exr {
        return Err(Error::Invalid(format!(
            "{}: a part (from {flags}) keeps its sums and sample counts in OpenEXR: name the \
             output *.exr, then `cltrace merge` the parts into any format",
            req.output.display()
        )));
    }
    if req.hits.is_some() {
        return Err(Error::Invalid(format!(
            "--hits records a whole frame's hits: leave it out with {flags}"
        )));
    }
    if let Some(samples) = &req.samples
        && samples.end > MAX_SPP
    {
        return Err(Error::Invalid(format!(
            "--samples {}..{}: sample indices go up to {MAX_SPP}",
            samples.start, samples.end
        )));
    }
    let width = camera.width.unwrap_or(crate::camera::DEFAULT_WIDTH);
    let height = camera.height.unwrap_or(crate::camera::DEFAULT_HEIGHT);
    let region = req.region.unwrap_or(Region::whole(width, height));
    if region.x1 > width || region.y1 > height {
        return Err(Error::Invalid(format!(
            "--region {region} is outside the {width}x{height} image"
        )));
    }
    Ok(Some((region, req.samples.clone())))
}

/// What every part of one render shares, one `key=value` a line: the scene's content (a
/// hash of the triangles and materials, so a renamed file still fits), the camera and
/// image size, and the shading. Device, method and layout are not in it: parts rendered
/// by different devices merge.
#[allow(clippy::too_many_arguments)]
fn part_settings(
    mesh: &Mesh,
    materials: &crate::material::Materials,
    camera: &Camera,
    shade: Shade,
    sampling: &Option<(SampleSettings, u32)>,
    crease_angle: Option<f32>,
    two_sided_lights: bool,
    lights: Option<&LightsDescription>,
) -> String {
    let mut bytes: Vec<u8> = Vec::new();
    let floats = mesh
        .positions
        .iter()
        .chain(&mesh.normals)
        .chain(&mesh.colors)
        .flat_map(|p| p.to_array())
        .chain(mesh.uvs.iter().flat_map(|t| t.to_array()))
        .chain(
            materials
                .textures
                .iter()
                .flat_map(|t| t.texels.iter().flatten().copied()),
        );
    for c in floats {
        bytes.extend(c.to_le_bytes());
    }
    for t in &mesh.triangles {
        for i in t {
            bytes.extend(i.to_le_bytes());
        }
    }
    for m in &materials.per_triangle {
        bytes.extend(m.to_le_bytes());
    }
    bytes.extend(format!("{:?}", materials.list).as_bytes());
    let scene = crate::hash::fnv1a(&bytes);
    let mut lines = vec![
        format!("scene={scene:016x}"),
        format!("image={}x{}", camera.width, camera.height),
        format!(
            "camera=eye {:?} look_at {:?} up {:?} fov {:?}{}",
            camera.eye.to_array(),
            camera.look_at.to_array(),
            camera.up.to_array(),
            camera.fov,
            camera.lens_description()
        ),
        format!("shade={}", shade.name()),
        format!(
            "crease={:?}",
            crease_angle.unwrap_or(crate::mesh::DEFAULT_CREASE_ANGLE)
        ),
    ];
    // Added only when set, so that parts written before the option still merge.
    if two_sided_lights {
        lines.push("two_sided_lights=true".into());
    }
    if let Some(lights) = lights {
        lines.push(format!("lights={}", lights.describe()));
    }
    if let Some((s, _)) = sampling {
        lines.push(format!("lighting={:?}", s.lighting));
        lines.push(format!("offset={:?}", s.offset));
        lines.push(format!("seed={}", s.seed));
    }
    lines.join("\n")
}

/// The devices' names for the report: `a`, or `a + b` for several.
fn devices_named(devices: &[ClDevice]) -> Option<String> {
    let names: Vec<&str> = devices.iter().map(|d| d.info.name.as_str()).collect();
    (!names.is_empty()).then(|| names.join(" + "))
}

fn elapsed_ms(start: std::time::Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// The camera the mesh file gives (a glTF file's) in place of the auto framing, when
/// neither the flags nor the scene file place the camera (any of eye, look-at, up, fov);
/// the image size stays the flags' and the scene's.
fn with_file_camera(
    settings: CameraSettings,
    file: Option<CameraSettings>,
    v: Verbosity,
) -> CameraSettings {
    let placed = settings.eye.is_some()
        || settings.look_at.is_some()
        || settings.up.is_some()
        || settings.fov.is_some();
    match file {
        Some(file) if !placed => {
            v.detail("camera: the mesh file's own");
            CameraSettings {
                width: settings.width,
                height: settings.height,
                ..file
            }
        }
        _ => settings,
    }
}

/// The camera's primary hits, traced on the host through a BVH of `mesh`.
fn host_camera_hits(mesh: &Mesh, camera: &Camera) -> Frame {
    let bvh = crate::bvh::Bvh::build(mesh, &BuildOptions::default());
    let flat = crate::bvh::Bin32Bvh::new(bvh, mesh);
    let shade = ShadeParams::new(Shade::Depth, camera, &mesh.bounds());
    let (w, h) = (camera.width, camera.height);
    crate::render::cpu::render(&flat, &camera.pinhole(), w, h, &shade, None)
}

/// A warning when the image shows nothing: every camera ray missed, or (in the modes that
/// gather light) no light reached any pixel. It says what the camera saw, since the usual
/// cause is a camera placed outside a closed room, inside a closed mesh, or facing away.
/// Without primary rays of the frame's own (`traced`: a progressive frame), a lit image
/// (if only by the sky) gets no warning, and a dark one has its camera rays traced on the
/// host to say what the camera saw.
fn unlit_warning(
    frame: &Frame,
    traced: bool,
    mesh: &Mesh,
    camera: &Camera,
    shade: Shade,
) -> Option<String> {
    let lit = match &frame.radiance {
        Some(radiance) => radiance.iter().any(|p| p.iter().any(|&c| c > 0.0)),
        None => true,
    };
    if lit && (!traced || frame.hits.iter().any(|h| h.prim != Hit::NONE.prim)) {
        return None;
    }
    // A progressive frame without primary rays of its own: the host traces them, for this
    // diagnosis only.
    let host;
    let frame = match traced {
        true => frame,
        false => {
            host = host_camera_hits(mesh, camera);
            &host
        }
    };
    let hits: Vec<usize> = (0..frame.hits.len())
        .filter(|&i| frame.hits[i].prim != Hit::NONE.prim)
        .collect();
    let place = format!(
        "the camera at {:?} looking at {:?}",
        camera.eye.to_array(),
        camera.look_at.to_array()
    );
    if hits.is_empty() {
        let bounds = mesh.bounds();
        return Some(format!(
            "the image is empty: every camera ray missed the scene (its bounds are {:?} to \
             {:?}) from {place}; set --eye and --look-at",
            bounds.min.to_array(),
            bounds.max.to_array()
        ));
    }
    if lit {
        return None;
    }
    // Which side of the surfaces the camera sees: the back of every face seen means it is
    // outside a room whose faces point inwards, or inside a mesh whose faces point out.
    let pinhole = camera.pinhole();
    let w = camera.width as usize;
    let back = hits
        .iter()
        .filter(|&&i| {
            let [a, b, c] = mesh.corners(frame.hits[i].prim as usize);
            let ray = pinhole.ray((i % w) as u32, (i / w) as u32);
            (b - a).cross(c - a).dot(ray.dir) > 0.0
        })
        .count();
    let nearest = hits
        .iter()
        .map(|&i| frame.hits[i].t)
        .fold(f32::INFINITY, f32::min);
    Some(format!(
        "no pixel is lit ({}): {:.0}% of the camera rays hit the scene, {:.0}% of those on the \
         back of a face, the nearest {nearest} away, from {place}; no light reaches what the \
         camera sees (is it outside a closed room, or inside a closed mesh?): set --eye and \
         --look-at",
        shade.name(),
        100.0 * hits.len() as f64 / frame.hits.len() as f64,
        100.0 * back as f64 / hits.len() as f64,
    ))
}
