//! `cltrace bench`: every method on every device for every scene and resolution, timed by
//! the benchmark protocol (`../shared/BENCHMARK.md`, outside the repository): auto framing,
//! warm-up, median and minimum of repetitions, device time from OpenCL profiling events; one
//! row per run.

mod scaling;
mod table;

pub(crate) use scaling::{plot_scaling, scaling_request, scaling_sizes, scaling_table};
pub(crate) use table::{markdown, write_csv, write_json};

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::bvh::Bin32Bvh;
use crate::bvh::Layout;
use crate::bvh::{BuildOptions, Bvh};
use crate::camera::{Camera, CameraSettings, View};
use crate::device::{ClDevice, DeviceSelector, Kernel, Kernels, list_devices};
use crate::error::{Error, Result};
use crate::geometry::Ray;
use crate::input::MeshFormat;
use crate::input::generate::Generator;
use crate::input::lights::LightsDescription;
use crate::input::scene::SceneMeshes;
use crate::input::scene_file::MeshSource;
use crate::material::Materials;
use crate::mesh::Mesh;
use crate::render::integrator::{Accumulation, Lighting, SampleSettings};
use crate::render::{Method, Shade, ShadeParams};
use crate::renderer::{PrepareOptions, Renderer};
use crate::report::{Progress, Timings, Verbosity};

/// The kinds of rays of the benchmark protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RayKind {
    /// One closest-hit ray per pixel from the eye, writing its hit record alone.
    Primary,
    /// For each pixel whose primary ray hit, one closest-hit ray from the hit point (offset
    /// by 1e-4 of the scene radius along the normal turned to the eye) in a cosine-weighted
    /// direction about that normal: the incoherent case.
    Diffuse,
    /// The diffuse construction with [`DIFFUSE_16_RAYS`] independent rays per hit pixel,
    /// traced as one batch: the incoherent case at full occupancy (the plain diffuse batch
    /// of a 1080p frame is about one wave of a large GPU's resident threads).
    Diffuse16,
    /// Progressive path tracing of the bench view at `--path-spp` samples per pixel and
    /// `--path-bounces` bounces: every segment counted, shadow rays included.
    Path,
}

impl RayKind {
    /// Every kind, in the order the tables list them.
    pub const ALL: [RayKind; 4] = [
        RayKind::Primary,
        RayKind::Diffuse,
        RayKind::Diffuse16,
        RayKind::Path,
    ];

    /// The kinds measured when `--rays` is not given. Path tracing is left out: a frame of
    /// it is 16 samples a pixel of up to 10 segments each, shadow rays besides (the room of
    /// scenes/materials.toml: 240 rays a pixel), so that in the default matrix (two
    /// resolutions, every method, layout and device) it would take many times as long as
    /// the other kinds together on a CPU device.
    pub const DEFAULT: [RayKind; 2] = [RayKind::Primary, RayKind::Diffuse];

    /// The kind's name: on the command line (`--rays`) and in the tables' `ray_kind` column.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Diffuse => "diffuse",
            RayKind::Diffuse16 => "diffuse-16",
            RayKind::Path => "path",
        }
    }

    /// One line on the kind, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            RayKind::Primary => {
                "One closest-hit ray per pixel from the eye (hit records only, no image)"
            }
            RayKind::Diffuse => {
                "For each pixel whose primary ray hit, one closest-hit ray from the hit point \
                 (offset by 1e-4 of the scene radius along the normal turned to the eye) in a \
                 cosine-weighted direction about that normal: the incoherent case"
            }
            RayKind::Diffuse16 => {
                "The diffuse construction with 16 independent rays per hit pixel (16 passes \
                 over the image), traced as one batch: the incoherent case at full occupancy"
            }
            RayKind::Path => {
                "Path tracing of the same view with the scene's materials, --path-spp samples \
                 a pixel, --path-bounces bounces: Msamples/s and Mrays/s over every segment, \
                 shadow rays included"
            }
        }
    }
}

impl std::str::FromStr for RayKind {
    type Err = String;

    /// The kind [`RayKind::name`] names.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::error::by_name(s, &RayKind::ALL, RayKind::name, "ray kind")
    }
}

/// Rays per hit pixel of [`RayKind::Diffuse16`].
pub(crate) const DIFFUSE_16_RAYS: u32 = 16;

/// Side of the pixel tiles that order the diffuse rays.
pub(crate) const DIFFUSE_TILE: u32 = 16;

/// The pixels of a `width` x `height` image tile by tile (`tile` x `tile` squares, row by
/// row within a tile, tiles row by row; the last ones cut at the edges).
pub(crate) fn tile_order(width: u32, height: u32, tile: u32) -> impl Iterator<Item = u32> {
    (0..height.div_ceil(tile)).flat_map(move |ty| {
        (0..width.div_ceil(tile)).flat_map(move |tx| {
            let rows = ty * tile..((ty + 1) * tile).min(height);
            rows.flat_map(move |y| {
                (tx * tile..((tx + 1) * tile).min(width)).map(move |x| y * width + x)
            })
        })
    })
}

/// The diffuse rays of the benchmark protocol for `camera`, found with a host BVH (every
/// method then traces the same rays). Directions come from the counter-based generator with
/// seed 0, keyed by pixel, so the rays are the same on every machine. They come in the order
/// of [`tile_order`], as the render kernels' 2D work-groups trace their bounces: rays from
/// neighbouring pixels start close together and share the nodes around their origins
/// (measured against scanline order: docs/performance.md, "Order of the diffuse batch"
/// under "Diffuse rays"). With `passes` above 1, the batch is that many passes over the
/// image, pass `k` drawing sample `k` of each pixel's random numbers (pass 0 is the plain
/// diffuse batch), as a renderer traces one sample of every pixel after another.
/// Public so that a harness outside cltrace can time another tracer on the very rays
/// `cltrace bench` traces (`--rays diffuse` is one pass, `diffuse-16` sixteen).
pub fn diffuse_rays(mesh: &Mesh, camera: &Camera, passes: u32) -> Vec<Ray> {
    use crate::intersect::ClosestHit;
    use crate::render::sampling::{Sampler, cosine_direction};
    use glam::Vec3;
    use rayon::prelude::*;
    let bvh = Bin32Bvh::new(Bvh::build(mesh, &BuildOptions::default()), mesh);
    let offset = 1e-4 * mesh.bounds().extent().length() * 0.5;
    let pinhole = camera.pinhole();
    let width = camera.width;
    let pixels: Vec<u32> = tile_order(camera.width, camera.height, DIFFUSE_TILE).collect();
    // Each hit pixel's origin and normal, found once for every pass.
    let hits: Vec<(u32, Vec3, Vec3)> = pixels
        .into_par_iter()
        .with_min_len(4096)
        .filter_map(|pixel| {
            let ray = pinhole.ray(pixel % width, pixel / width);
            let (i, t) = bvh.closest_hit(&ray, f32::INFINITY)?;
            let n = bvh.triangles[i].facing_normal(ray.dir);
            Some((pixel, ray.at(t) + n * offset, n))
        })
        .collect();
    (0..passes)
        .flat_map(|k| {
            hits.par_iter()
                .with_min_len(4096)
                .map(move |&(pixel, origin, n)| {
                    let s = Sampler::new(0, pixel, k);
                    Ray::new(origin, cosine_direction(n, s.get(0), s.get(1)))
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchRequest {
    /// Scenes (scene files or meshes); the built-in default scene when this and
    /// `generated` are empty.
    pub scenes: Vec<PathBuf>,
    /// Generated meshes to measure.
    pub generated: Vec<Generator>,
    /// Folders whose every mesh is added.
    pub scene_folders: Vec<PathBuf>,
    /// Methods to measure, each on every device it runs on.
    pub methods: Vec<Method>,
    /// The node layouts `cl-bvh` is measured in.
    pub layouts: Vec<Layout>,
    /// Device selectors; `None` for every device.
    pub devices: Option<Vec<String>>,
    /// Kinds of rays to trace at each resolution.
    pub ray_kinds: Vec<RayKind>,
    /// Samples per pixel of a path frame ([`RayKind::Path`]).
    pub path_spp: u32,
    /// Bounces after the first hit of a path frame: `path_bounces + 2` segments, as
    /// Mitsuba 3's `max_depth` counts them.
    pub path_bounces: u32,
    /// Image sizes (width, height in pixels), each framed automatically.
    pub resolutions: Vec<(u32, u32)>,
    /// Untimed frames before the timed ones.
    pub warmup: u32,
    /// Timed frames (at least 1): the median and minimum are reported.
    pub repetitions: u32,
    /// Brute-force runs estimated to take longer than this (seconds) are skipped.
    pub brute_budget_s: f64,
    /// How every BVH is built.
    pub build: BuildOptions,
    /// The OpenCL kernels' work-group shape (pixels across, down; the trace of arbitrary
    /// rays takes their product), instead of each device's default: what `cltrace tune`
    /// varies, here measured on every ray kind.
    pub work_group: Option<[usize; 2]>,
    /// How much goes to stderr: rows as they come with `--verbose`, the progress bar unless
    /// `--quiet`.
    pub verbosity: Verbosity,
}

/// One measured (or skipped) run: the columns of the benchmark protocol's tables.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct BenchRow {
    pub(crate) scene: String,
    pub(crate) triangles: usize,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) method: String,
    pub(crate) device: String,
    pub(crate) compute_units: u32,
    pub(crate) ray_kind: String,
    /// Rays of one frame; for path tracing every segment and shadow ray the renderer
    /// counted (the mean over the timed frames).
    pub(crate) rays: u64,
    /// Samples per pixel and path length in segments (camera ray to the last bounce's), of
    /// the path rows.
    pub(crate) spp: Option<u32>,
    pub(crate) segments: Option<u32>,
    pub(crate) load_ms: f64,
    /// BVH build time, for the BVH methods.
    pub(crate) build_ms: Option<f64>,
    pub(crate) build_threads: Option<usize>,
    /// Kernel (OpenCL, from profiling events) or trace (CPU, wall) time per frame.
    pub(crate) kernel_ms_median: Option<f64>,
    pub(crate) kernel_ms_min: Option<f64>,
    /// Host wall time around each frame (launches, waits, read-back), median.
    pub(crate) wall_ms_median: Option<f64>,
    /// Rays per second of kernel time (median), in millions.
    pub(crate) mrays_per_s: Option<f64>,
    /// Path rows: samples (pixels x spp) per second of sampling time (median), in millions.
    pub(crate) msamples_per_s: Option<f64>,
    pub(crate) sah_cost: Option<f64>,
    /// Scene data the tracer reads (triangles, nodes), MB.
    pub(crate) device_mb: f64,
    /// Why the run was not measured, e.g. a brute force over the time budget.
    pub(crate) skipped: Option<String>,
}

/// A scene to measure: its source and name, and for path rows a scene file's camera (the
/// benchmark's view fills in what it leaves open) and lights.
struct BenchScene {
    source: SceneMeshes,
    name: String,
    camera: CameraSettings,
    lights: LightsDescription,
}

impl BenchScene {
    fn of(source: SceneMeshes, name: String) -> Self {
        BenchScene {
            source,
            name,
            camera: CameraSettings::default(),
            lights: LightsDescription::default(),
        }
    }
}

/// Where a method runs: the host, or an OpenCL device.
// The device boxed: an opened device (with its program cache) is far larger than `Host`.
enum Target {
    Host,
    Device(Box<ClDevice>),
}

/// Runs the whole matrix and returns its rows (also printed as they come, with
/// `--verbose`), and whether it is complete: an interruption (Ctrl-C) ends it early with
/// the rows measured so far, or with [`Error::Interrupted`] when there are none. A progress
/// bar on stderr counts the runs.
pub(crate) fn run(req: &BenchRequest) -> Result<(Vec<BenchRow>, bool)> {
    req.build.check()?;
    if req.repetitions == 0 {
        return Err(Error::Invalid("--repetitions must be at least 1".into()));
    }
    check_path(req)?;
    for &(w, h) in &req.resolutions {
        crate::camera::check_settings(&crate::camera::CameraSettings {
            width: Some(w),
            height: Some(h),
            ..Default::default()
        })?;
    }
    let scenes = scenes(req)?;
    let targets = targets(req)?;
    let runs_per_scene: usize = req
        .methods
        .iter()
        .map(|&m| {
            let places = if m.uses_opencl() {
                targets
                    .iter()
                    .filter(|t| matches!(t, Target::Device(_)))
                    .count()
            } else {
                1
            };
            places * layouts_for(req, m).len()
        })
        .sum::<usize>()
        * req.resolutions.len()
        * req.ray_kinds.len();
    let bar = Progress::new(
        req.verbosity.progress(),
        "bench",
        (runs_per_scene * scenes.len()) as u64,
        "runs",
    );
    let mut rows = Vec::new();
    let ran = run_into(req, &scenes, &targets, &bar, &mut rows);
    bar.finish();
    match ran {
        Ok(()) => Ok((rows, true)),
        Err(Error::Interrupted) if !rows.is_empty() => Ok((rows, false)),
        Err(e) => Err(e),
    }
}

/// The matrix's runs, each row pushed to `rows` as it is measured.
fn run_into(
    req: &BenchRequest,
    scenes: &[BenchScene],
    targets: &[Target],
    bar: &Progress,
    rows: &mut Vec<BenchRow>,
) -> Result<()> {
    for scene in scenes {
        bar.set_message(format!("loading {}", scene.name));
        let start = Instant::now();
        // The materials are the path rows' alone: the other kinds trace grey geometry.
        let loaded = scene.source.load_with_materials()?;
        let (mesh, materials) = (loaded.file.mesh, loaded.file.materials);
        // And its lights, for the path rows.
        let lights = match req.ray_kinds.contains(&RayKind::Path) {
            true => std::sync::Arc::new(scene.lights.load()?),
            false => Default::default(),
        };
        let load_ms = start.elapsed().as_secs_f64() * 1e3;
        crate::interrupt::check()?;
        let mut diffuse = std::collections::HashMap::new();
        for (kind, passes) in [(RayKind::Diffuse, 1), (RayKind::Diffuse16, DIFFUSE_16_RAYS)] {
            if req.ray_kinds.contains(&kind) {
                bar.set_message(format!("{} rays for {}", kind.name(), scene.name));
                for &(w, h) in &req.resolutions {
                    let camera = Camera::bench(&mesh.bounds(), w, h)?;
                    diffuse.insert((kind, w, h), diffuse_rays(&mesh, &camera, passes));
                }
            }
        }
        for &method in &req.methods {
            for target in targets {
                let device = match (method.uses_opencl(), target) {
                    (true, Target::Device(d)) => Some(&**d),
                    (false, Target::Host) => None,
                    _ => continue,
                };
                bar.set_message(format!(
                    "{} {} {}",
                    scene.name,
                    method.name(),
                    device_name(device)
                ));
                for layout in layouts_for(req, method) {
                    let traces = req.ray_kinds.iter().any(|&k| k != RayKind::Path);
                    let paths = req.ray_kinds.contains(&RayKind::Path);
                    let mut timings = Timings::default();
                    let options = PrepareOptions {
                        build: req.build,
                        layout: Some(layout),
                        work_group: None,
                        kernels: Kernels::PRIMARY.with(Kernel::TraceRays),
                        // The protocol's primary ray is a closest-hit query, as the peers
                        // measure it: flat shading, no vertex normals interpolated (which
                        // cost the wide layouts 12% on the H200: docs/performance.md).
                        crease_angle: Some(0.0),
                        two_sided_lights: false,
                        lights: Default::default(),
                    };
                    let mut renderer = traces
                        .then(|| {
                            Renderer::prepare(
                                method,
                                &mesh,
                                &Materials::default(),
                                &options,
                                device,
                                &mut timings,
                            )
                            .and_then(|r| with_work_group(r, req.work_group))
                        })
                        .transpose()?;
                    // Path tracing renders as `render --shade path` does: the scene's
                    // materials, smooth normals, the program of PATH_KERNELS; emitters lit
                    // from their front face only, as the protocol compares renderers.
                    let mut path_timings = Timings::default();
                    let path_options = PrepareOptions {
                        kernels: PATH_KERNELS,
                        crease_angle: None,
                        lights: lights.clone(),
                        ..options.clone()
                    };
                    let mut path_renderer = paths
                        .then(|| {
                            Renderer::prepare(
                                method,
                                &mesh,
                                &materials,
                                &path_options,
                                device,
                                &mut path_timings,
                            )
                            .and_then(|r| with_work_group(r, req.work_group))
                        })
                        .transpose()?;
                    for &(width, height) in &req.resolutions {
                        for &kind in &req.ray_kinds {
                            crate::interrupt::check()?;
                            let run = Run {
                                req,
                                scene,
                                mesh: &mesh,
                                load_ms,
                                method,
                                layout,
                                device,
                                size: (width, height),
                            };
                            let batch = |kind| {
                                diffuse
                                    .get(&(kind, width, height))
                                    .map_or(&[][..], Vec::as_slice)
                            };
                            let row = match (kind, &mut renderer, &mut path_renderer) {
                                (RayKind::Primary, Some(renderer), _) => {
                                    measure(&run, &timings, renderer, None)?
                                }
                                (RayKind::Diffuse | RayKind::Diffuse16, Some(renderer), _) => {
                                    measure(&run, &timings, renderer, Some((kind, batch(kind))))?
                                }
                                (RayKind::Path, _, Some(renderer)) => {
                                    measure_path(&run, &path_timings, renderer)?
                                }
                                _ => {
                                    unreachable!("a renderer is prepared for every kind asked for")
                                }
                            };
                            if req.verbosity >= Verbosity::Verbose {
                                bar.suspend(|| {
                                    crate::report::print_message(&table::row_line(&row))
                                });
                            }
                            rows.push(row);
                            bar.inc(1);
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// The kernels of the path rows' program: the path kernel alone, as `render --shade path`
/// compiles it. A program with another kernel beside it is compiled as the tracing
/// programs are, without the sample programs' register cap, relaxed shading and rounding
/// (src/device/program.rs): on an H100 it ran the path tracer at 78 registers instead of
/// 64 (docs/bench/2026-12-06-indexed-triangles.md).
const PATH_KERNELS: Kernels = Kernels::NONE.with(Kernel::SamplePath);

/// The layouts a method is measured in: every requested one for `cl-bvh`, only the
/// thesis's (the one they use) for the others.
fn layouts_for(req: &BenchRequest, method: Method) -> Vec<Layout> {
    if method == Method::ClBvh {
        req.layouts.clone()
    } else {
        vec![Layout::Bin32]
    }
}

/// `renderer` with its kernels launched in work-groups of `shape` where one is asked for
/// (a shape the device cannot run is an error, not a silent default).
fn with_work_group<'d>(
    mut renderer: Renderer<'d>,
    shape: Option<[usize; 2]>,
) -> Result<Renderer<'d>> {
    if let Some(shape) = shape {
        renderer.set_work_group(shape)?;
    }
    Ok(renderer)
}

/// What one run measures: a scene at one size through one method, layout and device.
struct Run<'a> {
    req: &'a BenchRequest,
    scene: &'a BenchScene,
    mesh: &'a Mesh,
    load_ms: f64,
    method: Method,
    layout: Layout,
    device: Option<&'a ClDevice>,
    /// Width and height in pixels.
    size: (u32, u32),
}

impl Run<'_> {
    /// The row of this run, nothing measured yet.
    fn row(&self, kind: RayKind, rays: u64, timings: &Timings, renderer: &Renderer) -> BenchRow {
        let (method, layout, device) = (self.method, self.layout, self.device);
        BenchRow {
            scene: self.scene.name.clone(),
            triangles: self.mesh.triangle_count(),
            width: self.size.0,
            height: self.size.1,
            method: if method == Method::ClBvh {
                format!("{}:{}", method.name(), layout.name())
            } else {
                method.name().to_string()
            },
            device: device_name(device),
            compute_units: device.map_or_else(
                || rayon::current_num_threads() as u32,
                |d| d.info.compute_units,
            ),
            ray_kind: kind.name().to_string(),
            rays,
            spp: None,
            segments: None,
            load_ms: self.load_ms,
            build_ms: timings.get("build"),
            build_threads: method.uses_bvh().then(rayon::current_num_threads),
            kernel_ms_median: None,
            kernel_ms_min: None,
            wall_ms_median: None,
            mrays_per_s: None,
            msamples_per_s: None,
            sah_cost: renderer.bvh.map(|s| s.sah_cost),
            device_mb: renderer.scene_bytes as f64 / 1e6,
            skipped: None,
        }
    }

    /// Whether the run is a brute force, whose frames are estimated before they are run.
    fn brute(&self) -> bool {
        matches!(self.method, Method::CpuBrute | Method::ClBrute)
    }

    /// Why a brute-force run whose frames take `per_frame` each is skipped; `None` if they
    /// fit the budget.
    fn over_budget(&self, per_frame: Estimate) -> Option<String> {
        let req = self.req;
        let estimate_s = per_frame.seconds() * (req.warmup + req.repetitions) as f64;
        let how = match per_frame {
            Estimate::About(_) => "estimated",
            Estimate::AtLeast(_) => "at least",
        };
        (estimate_s > req.brute_budget_s).then(|| {
            format!(
                "{how} {estimate_s:.0} s for {} frames > {} s budget",
                req.warmup + req.repetitions,
                req.brute_budget_s
            )
        })
    }

    /// The brute-force estimates' sampling, which may stop once a frame surely takes
    /// longer than the budget allows.
    fn growth(&self) -> Growth {
        Growth::new(self.req.brute_budget_s / (self.req.warmup + self.req.repetitions) as f64)
    }
}

/// A primary run (`diffuse` is `None`) or a diffuse one (its kind and batch of rays): the
/// warm-up, then the timed frames.
fn measure(
    run: &Run,
    timings: &Timings,
    renderer: &mut Renderer,
    diffuse: Option<(RayKind, &[Ray])>,
) -> Result<BenchRow> {
    let (req, mesh) = (run.req, run.mesh);
    let (width, height) = run.size;
    let camera = Camera::bench(&mesh.bounds(), width, height)?;
    // A closest-hit query writes hit records alone, as the peers' kernels and the ray-batch
    // rows do: no colour is shaded or stored (4% of an H100's camera rays:
    // docs/bench/2026-12-06-tenth-session.md).
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds()).with_colors(false);
    let (kind, rays) = match diffuse {
        Some((kind, batch)) => (kind, batch.len() as u64),
        None => (RayKind::Primary, width as u64 * height as u64),
    };
    let diffuse = diffuse.map(|(_, batch)| batch);
    // One timed frame of this run: its trace (kernel) time.
    let frame = |renderer: &mut Renderer| -> Result<f64> {
        Ok(match diffuse {
            Some(batch) => renderer.trace_rays(batch, f32::INFINITY, false)?.1.trace_ms,
            None => renderer.render(&camera, &shade, false)?.1.trace_ms,
        })
    };
    let mut row = run.row(kind, rays, timings, renderer);
    if run.brute() {
        let triangles = mesh.triangle_count();
        let per_frame = match diffuse {
            Some(batch) => brute_rays_estimate_s(renderer, batch, triangles, run.growth())?,
            None => brute_estimate_s(renderer, &camera, &shade, triangles, run.growth())?,
        };
        if let Some(why) = run.over_budget(per_frame) {
            row.skipped = Some(why);
            return Ok(row);
        }
    }
    if rays == 0 {
        row.skipped = Some("no rays: the camera sees nothing".into());
        return Ok(row);
    }
    for _ in 0..req.warmup {
        frame(renderer)?;
    }
    let mut kernel = Vec::new();
    let mut wall = Vec::new();
    for _ in 0..req.repetitions {
        let start = Instant::now();
        kernel.push(frame(renderer)?);
        wall.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let median_kernel = median(&mut kernel);
    row.kernel_ms_median = Some(median_kernel);
    row.kernel_ms_min = kernel.iter().copied().reduce(f64::min);
    row.wall_ms_median = Some(median(&mut wall));
    row.mrays_per_s = Some(rays as f64 / median_kernel / 1e3);
    Ok(row)
}

/// The most samples per pixel and bounces a path row takes: as `render --spp` and
/// `--max-bounces` accept.
pub(crate) const MAX_PATH_SPP: u32 = 65536;
pub(crate) const MAX_PATH_BOUNCES: u32 = 1024;

/// Refuses path settings out of range, named by their flags, before anything is measured.
fn check_path(req: &BenchRequest) -> Result<()> {
    if !(1..=MAX_PATH_SPP).contains(&req.path_spp) {
        return Err(Error::Invalid(format!(
            "--path-spp {} is out of range: use 1 to {MAX_PATH_SPP}",
            req.path_spp
        )));
    }
    if req.path_bounces > MAX_PATH_BOUNCES {
        return Err(Error::Invalid(format!(
            "--path-bounces {} is out of range: use 0 to {MAX_PATH_BOUNCES}",
            req.path_bounces
        )));
    }
    Ok(())
}

/// The sampling of a path row, as `render --shade path` sets it up for the same scene:
/// secondary rays offset by 1e-4 of the scene radius, seed 0 (so every frame, on every
/// machine, draws the same numbers and traces the same paths).
fn path_settings(req: &BenchRequest, mesh: &Mesh) -> SampleSettings {
    let radius = (mesh.bounds().extent().length() * 0.5).max(f32::MIN_POSITIVE);
    SampleSettings {
        lighting: Lighting::Path {
            max_bounces: req.path_bounces,
        },
        offset: 1e-4 * radius,
        seed: 0,
    }
}

/// Samples `0..spp` of every pixel of `camera`'s image into a fresh accumulation: the
/// sampling time (device time for OpenCL, wall time for the host) and the rays the renderer
/// counted. An interruption (Ctrl-C) is an error: a frame cut short measures nothing.
fn path_frame(
    renderer: &mut Renderer,
    camera: &Camera,
    settings: &SampleSettings,
    spp: u32,
) -> Result<(f64, u64)> {
    let mut acc = Accumulation::new(camera.width, camera.height);
    let times = renderer.render_samples(
        camera,
        settings,
        0..spp,
        &mut acc,
        crate::interrupt::flag(),
        false,
    )?;
    crate::interrupt::check()?;
    Ok((times.trace_ms, acc.rays))
}

/// A path run: a frame is every sample of every pixel, with the scene's materials
/// (`renderer` is prepared for sampling). Samples/s are pixels x spp over the median
/// sampling time; Mrays/s count every segment and shadow ray the renderer traced, the
/// camera rays included.
fn measure_path(run: &Run, timings: &Timings, renderer: &mut Renderer) -> Result<BenchRow> {
    let (req, mesh) = (run.req, run.mesh);
    let (width, height) = run.size;
    // The scene file's camera, the benchmark's view filling in what it leaves open: the
    // protocol's view of the Cornell box is from behind its back wall, where no path enters.
    let camera = Camera::from_settings(
        &CameraSettings {
            view: Some(run.scene.camera.view.unwrap_or(View::Bench)),
            width: Some(width),
            height: Some(height),
            ..run.scene.camera
        },
        &mesh.bounds(),
    )?;
    let settings = path_settings(req, mesh);
    let samples = width as u64 * height as u64 * req.path_spp as u64;
    let mut row = run.row(RayKind::Path, 0, timings, renderer);
    row.spp = Some(req.path_spp);
    // The camera's segment, one per bounce, and the last bounce's sampled direction traced
    // for the emitter it may hit: Mitsuba 3's max_depth.
    row.segments = Some(req.path_bounces + 2);
    if run.brute() {
        let per_frame = brute_path_estimate_s(
            renderer,
            &camera,
            &settings,
            req.path_spp,
            mesh.triangle_count(),
            run.growth(),
        )?;
        if let Some(why) = run.over_budget(per_frame) {
            row.skipped = Some(why);
            return Ok(row);
        }
    }
    for _ in 0..req.warmup {
        path_frame(renderer, &camera, &settings, req.path_spp)?;
    }
    let mut kernel = Vec::new();
    let mut wall = Vec::new();
    let mut rays = 0u64;
    for _ in 0..req.repetitions {
        let start = Instant::now();
        let (ms, traced) = path_frame(renderer, &camera, &settings, req.path_spp)?;
        wall.push(start.elapsed().as_secs_f64() * 1e3);
        kernel.push(ms);
        rays += traced;
    }
    // Every frame draws the same numbers, so the frames trace the same rays (up to the
    // device's rounding): their mean is the frame's.
    row.rays = rays / req.repetitions as u64;
    let median_kernel = median(&mut kernel);
    row.kernel_ms_median = Some(median_kernel);
    row.kernel_ms_min = kernel.iter().copied().reduce(f64::min);
    row.wall_ms_median = Some(median(&mut wall));
    row.mrays_per_s = Some(row.rays as f64 / median_kernel / 1e3);
    row.msamples_per_s = Some(samples as f64 / median_kernel / 1e3);
    Ok(row)
}

/// A thumbnail of `camera`'s view with about `pixels` pixels, its aspect kept.
fn thumbnail(camera: &Camera, pixels: u64) -> Camera {
    let scale = (pixels as f64 / (camera.width as f64 * camera.height as f64)).sqrt();
    Camera {
        width: ((camera.width as f64 * scale).ceil() as u32).clamp(1, camera.width),
        height: ((camera.height as f64 * scale).ceil() as u32).clamp(1, camera.height),
        ..*camera
    }
}

/// [`brute_estimate_s`] for a path frame: one sample of growing thumbnails, scaled to
/// every sample of the image; one sample of the whole image, if it comes to that, is
/// scaled by the samples per pixel.
fn brute_path_estimate_s(
    renderer: &mut Renderer,
    camera: &Camera,
    settings: &SampleSettings,
    spp: u32,
    triangles: usize,
    mut growth: Growth,
) -> Result<Estimate> {
    let pixels = camera.width as u64 * camera.height as u64;
    let total = pixels * spp as u64;
    // Untimed first launch, as in brute_estimate_s.
    path_frame(renderer, &thumbnail(camera, 1), settings, 1)?;
    let mut n = ((1u64 << 24) / triangles.max(1) as u64).clamp(16, pixels.max(16));
    loop {
        let probe = thumbnail(camera, n.min(pixels));
        let (ms, _) = path_frame(renderer, &probe, settings, 1)?;
        let probed = probe.width as u64 * probe.height as u64;
        if let Some(estimate) = growth.estimate(probed, total, ms) {
            return Ok(estimate);
        }
        if probed >= pixels {
            return Ok(Estimate::About(ms / 1e3 * spp as f64));
        }
        n = (n * 8).min(pixels);
    }
}

/// Seconds one brute-force frame of `camera` will take, from thumbnails of the same view:
/// the first about 2^24 ray/triangle tests, each next one 8 times larger, until one takes
/// 20 ms while growing about linearly from the one before, takes longer alone than a frame
/// may (see [`Growth`]), or is the frame itself. A GPU
/// runs a thumbnail smaller than it can hold in about the time of one ray (the NVIDIA H100
/// takes 17 ms for one pixel of the bunny and 104 ms for 512x512), so time per pixel only
/// means something once more pixels take proportionally more time.
fn brute_estimate_s(
    renderer: &mut Renderer,
    camera: &Camera,
    shade: &ShadeParams,
    triangles: usize,
    mut growth: Growth,
) -> Result<Estimate> {
    let rays = camera.width as u64 * camera.height as u64;
    // A first launch can carry one-time costs (NVIDIA's driver loads the kernel lazily):
    // launch once untimed.
    let one_pixel = Camera {
        width: 1,
        height: 1,
        ..*camera
    };
    renderer.render(&one_pixel, shade, false)?;
    let mut pixels = ((1u64 << 24) / triangles as u64).clamp(16, rays);
    loop {
        let probe = thumbnail(camera, pixels);
        let (_, t) = renderer.render(&probe, shade, false)?;
        let probed = probe.width as u64 * probe.height as u64;
        if let Some(estimate) = growth.estimate(probed, rays, t.trace_ms) {
            return Ok(estimate);
        }
        pixels = (pixels * 8).min(rays);
    }
}

/// [`brute_estimate_s`] for a ray buffer: growing prefixes of the rays.
fn brute_rays_estimate_s(
    renderer: &mut Renderer,
    rays: &[Ray],
    triangles: usize,
    mut growth: Growth,
) -> Result<Estimate> {
    let mut n = ((1usize << 24) / triangles)
        .clamp(16, rays.len().max(16))
        .min(rays.len());
    // Untimed first launch, as in brute_estimate_s.
    renderer.trace_rays(&rays[..rays.len().min(1)], f32::INFINITY, false)?;
    loop {
        let (_, t) = renderer.trace_rays(&rays[..n], f32::INFINITY, false)?;
        if let Some(estimate) = growth.estimate(n as u64, rays.len() as u64, t.trace_ms) {
            return Ok(estimate);
        }
        n = (n * 8).min(rays.len());
    }
}

/// How long a brute-force frame takes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Estimate {
    /// About this many seconds (scaled from a sample on a full device).
    About(f64),
    /// At least this many seconds: one smaller sample alone took that long.
    AtLeast(f64),
}

impl Estimate {
    fn seconds(self) -> f64 {
        match self {
            Estimate::About(s) | Estimate::AtLeast(s) => s,
        }
    }
}

/// The growing samples of a brute-force estimate.
struct Growth {
    /// The previous sample: rays traced and milliseconds taken.
    last: Option<(u64, f64)>,
    /// Seconds per frame past which the exact figure no longer matters.
    enough_s: f64,
}

impl Growth {
    fn new(enough_s: f64) -> Self {
        Growth {
            last: None,
            enough_s,
        }
    }

    /// Seconds for `total` rays, once a sample of `done` rays taking `ms` can be trusted:
    /// it is the whole work, or it took 20 ms and at least half as much longer than the
    /// previous one as it has more rays (the device is full, time grows with work). A
    /// sample that alone took longer than `enough_s` also ends the sampling, as the frame
    /// takes longer still: that sample's time is then a lower bound.
    fn estimate(&mut self, done: u64, total: u64, ms: f64) -> Option<Estimate> {
        let last = self.last.replace((done, ms));
        let scaled = Estimate::About(ms / done.max(1) as f64 * total as f64 / 1e3);
        if done >= total {
            return Some(scaled);
        }
        let linear = last.is_some_and(|(last_done, last_ms)| {
            ms / last_ms.max(1e-6) >= 0.5 * done as f64 / last_done as f64
        });
        if ms >= 20.0 && linear {
            return Some(scaled);
        }
        (ms / 1e3 > self.enough_s).then_some(Estimate::AtLeast(ms / 1e3))
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    }
}

fn device_name(device: Option<&ClDevice>) -> String {
    match device {
        Some(d) => format!("{} ({})", d.info.name, d.info.platform_name),
        None => format!("host: {}", host_cpu_name()),
    }
}

/// The host processor's model name, from /proc/cpuinfo where there is one.
pub(crate) fn host_cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|name| name.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

fn scenes(req: &BenchRequest) -> Result<Vec<BenchScene>> {
    let mut scenes = Vec::new();
    let mut generated = req.generated.clone();
    if req.scenes.is_empty() && generated.is_empty() {
        generated.push(Generator::default_scene());
    }
    for g in generated {
        scenes.push(BenchScene::of(
            MeshSource::Generator(g.clone()).into(),
            g.name(),
        ));
    }
    for path in &req.scenes {
        let description = crate::input::scene_file::SceneDescription::named(Some(path))?;
        scenes.push(BenchScene {
            name: description.meshes.name(),
            source: description.meshes,
            camera: description.camera,
            lights: description.lights,
        });
    }
    for folder in &req.scene_folders {
        let mut found: Vec<PathBuf> = std::fs::read_dir(folder)
            .map_err(|e| Error::input(folder, crate::input::io_reason(&e)))?
            .filter_map(|entry| entry.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && MeshFormat::from_path(p).is_some())
            .collect();
        found.sort();
        if found.is_empty() {
            return Err(Error::input(
                folder,
                "holds no .obj, .obj.gz, .ply, .ply.gz, .gltf or .glb mesh",
            ));
        }
        scenes.extend(
            found
                .into_iter()
                .map(|p| BenchScene::of(MeshSource::File(p.clone()).into(), file_name(&p))),
        );
    }
    Ok(scenes)
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The host, if a CPU method is asked for, and the OpenCL devices, if an OpenCL one is.
fn targets(req: &BenchRequest) -> Result<Vec<Target>> {
    let mut targets = Vec::new();
    if req.methods.iter().any(|m| !m.uses_opencl()) {
        targets.push(Target::Host);
    }
    if req.methods.iter().any(|m| m.uses_opencl()) {
        let all = list_devices()?;
        let chosen: Vec<_> = match &req.devices {
            None => all.clone(),
            Some(selectors) => {
                let mut chosen: Vec<crate::device::DeviceInfo> = Vec::new();
                for s in selectors {
                    let info = s.parse::<DeviceSelector>()?.pick(&all)?.clone();
                    if !chosen.iter().any(|c| c.index() == info.index()) {
                        chosen.push(info);
                    }
                }
                chosen
            }
        };
        if chosen.is_empty() {
            return Err(Error::Device(format!(
                "no OpenCL device found: {}",
                crate::device::INSTALL_HINT
            )));
        }
        for info in chosen {
            targets.push(Target::Device(Box::new(ClDevice::open(info)?)));
        }
    }
    Ok(targets)
}

#[cfg(test)]
mod tests {
    use super::{Estimate, Growth, PATH_KERNELS, diffuse_rays, tile_order};
    use crate::camera::Camera;
    use crate::device::{Kernel, Kernels};
    use crate::mesh::Mesh;
    use glam::Vec3;

    /// The diffuse-16 batch is 16 passes of the diffuse batch's origins, the first pass the
    /// diffuse batch itself, each pass with directions of its own.
    #[test]
    fn each_pass_of_a_diffuse_batch_leaves_the_same_points_in_new_directions() {
        // A quad facing the camera, and a triangle behind it to give the bounds depth.
        let p = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, -1.0),
        ];
        let mesh = Mesh::new(p, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
        let camera = Camera::bench(&mesh.bounds(), 24, 16).unwrap();
        let one = diffuse_rays(&mesh, &camera, 1);
        let three = diffuse_rays(&mesh, &camera, 3);
        assert!(one.len() > 50, "{} rays", one.len());
        assert_eq!(three.len(), 3 * one.len());
        assert_eq!(three[..one.len()], one[..]);
        for pass in three.chunks(one.len()).skip(1) {
            for (a, b) in pass.iter().zip(&one) {
                assert_eq!(a.origin, b.origin);
                assert_ne!(a.dir, b.dir);
            }
        }
    }

    /// Every pixel once, in whole tiles where they fit, cut ones at the right and bottom.
    #[test]
    fn tile_order_visits_every_pixel_once_tile_by_tile() {
        for (w, h, tile) in [(7, 5, 2), (16, 16, 4), (5, 3, 16), (1, 1, 16), (33, 17, 8)] {
            let order: Vec<u32> = tile_order(w, h, tile).collect();
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(
                sorted,
                (0..w * h).collect::<Vec<_>>(),
                "{w}x{h} tile {tile}"
            );
        }
        let order: Vec<u32> = tile_order(5, 3, 2).collect();
        assert_eq!(order, [0, 1, 5, 6, 2, 3, 7, 8, 4, 9, 10, 11, 12, 13, 14]);
    }

    /// A GPU-like device: time nearly flat while the thumbnails are smaller than the device
    /// holds, then linear. The estimate waits for the linear part.
    #[test]
    fn estimates_wait_for_time_to_grow_with_the_work() {
        let mut g = Growth::new(100.0);
        assert_eq!(g.estimate(256, 262_144, 33.0), None, "one sample");
        assert_eq!(g.estimate(2_048, 262_144, 49.0), None, "not full yet");
        let e = g.estimate(16_384, 262_144, 330.0).expect("linear now");
        assert!(matches!(e, Estimate::About(s) if (s - 330.0 * 16.0 / 1e3).abs() < 1e-9));
        // The whole work is its own estimate, however it grew.
        let mut g = Growth::new(100.0);
        assert_eq!(g.estimate(100, 100, 5.0), Some(Estimate::About(5.0 / 1e3)));
        // Short samples are not trusted even when linear.
        let mut g = Growth::new(100.0);
        g.estimate(10, 1000, 1.0);
        assert_eq!(g.estimate(80, 1000, 8.0), None);
    }

    /// Sampling stops once one sample alone takes longer than a frame may: that sample's
    /// time is a lower bound, not a scaled guess.
    #[test]
    fn hopeless_work_stops_at_the_first_sample_over_the_limit() {
        let mut g = Growth::new(1.0);
        let e = g.estimate(1_000, 1_000_000, 1_500.0);
        assert_eq!(e, Some(Estimate::AtLeast(1.5)));
    }

    /// Regression: the path rows' program held `trace_primary` beside the path kernel, so
    /// it was compiled as a tracing program, not as `render --shade path` compiles its own.
    #[test]
    fn bench_path_rows_compiled_the_path_kernel_as_a_tracing_program() {
        assert!(PATH_KERNELS.only_sampling());
        assert_eq!(PATH_KERNELS, Kernels::NONE.with(Kernel::SamplePath));
    }
}
