//! `cltrace render`: scene in, image out, every stage timed.

use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};

use crate::bvh::{BuildOptions, Bvh};
use crate::camera::Camera;
use crate::device::{ClDevice, DeviceSelector};
use crate::error::Result;
use crate::input::scene_file::{CameraSettings, RenderSettings, SceneDescription};
use crate::layout::{FlatBvh, triangles_in_order};
use crate::mesh::Mesh;
use crate::output;
use crate::render::opencl::ClTracer;
use crate::render::{Frame, Method, Shade, ShadeParams, cpu};
use crate::report::{Timings, Verbosity};

/// The method when neither the scene nor the flags name one.
pub const DEFAULT_METHOD: Method = Method::ClBvh;
/// The shading when neither the scene nor the flags name one.
pub const DEFAULT_SHADE: Shade = Shade::Lambert;

/// Everything `cltrace render` was asked to do.
#[derive(Clone, Debug, Default)]
pub struct RenderRequest {
    /// A scene file (`.toml`) or a mesh file; `None` for the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Camera settings from flags; they override the scene file's.
    pub camera: CameraSettings,
    /// Render settings from flags; they override the scene file's.
    pub render: RenderSettings,
    pub output: PathBuf,
    /// Where to write the raw hit records, if anywhere.
    pub hits: Option<PathBuf>,
    /// `--device` (or `CLTRACE_DEVICE`), for OpenCL methods.
    pub device: Option<String>,
    /// How to build the BVH, for BVH methods.
    pub build: BuildOptions,
    pub verbosity: Verbosity,
}

/// What a finished render reports.
#[derive(Clone, Debug)]
pub struct RenderOutcome {
    pub frame: Frame,
    pub method: Method,
    /// The OpenCL device's name, for OpenCL methods.
    pub device: Option<String>,
    pub timings: Timings,
}

/// Reads the scene description a render request names.
pub fn describe_scene(scene: Option<&Path>) -> Result<SceneDescription> {
    match scene {
        None => Ok(SceneDescription::builtin_default()),
        Some(p)
            if p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("toml")) =>
        {
            SceneDescription::load(p)
        }
        Some(p) => Ok(SceneDescription::from_mesh(p)),
    }
}

/// Runs a render request end to end. Every check that needs no work (output format and
/// folder, resolution, field of view, device) happens before the mesh is loaded.
pub fn run(req: &RenderRequest) -> Result<RenderOutcome> {
    let v = req.verbosity;
    let scene = describe_scene(req.scene.as_deref())?;
    let camera_settings = req.camera.over(scene.camera);
    let render = req.render.over(scene.render);
    let method = render.method.unwrap_or(DEFAULT_METHOD);
    let shade = render.shade.unwrap_or(DEFAULT_SHADE);

    output::image_format(&req.output)?;
    req.build.check()?;
    if let Some(hits) = &req.hits {
        output::check_folder(hits)?;
    }
    crate::camera::check_settings(&camera_settings)?;
    let device = if method.uses_opencl() {
        let selector = DeviceSelector::from_flag_or_env(req.device.as_deref())?;
        let device = ClDevice::select(&selector)?;
        v.detail(format!("device: {}", device.info));
        Some(device)
    } else {
        None
    };

    let mut timings = Timings::default();
    let mesh = timings.time("load", || scene.mesh.load())?;
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
    let shade = ShadeParams::new(shade, &camera, &bounds);

    let frame = match method {
        Method::CpuBrute => trace_cpu_brute(&mesh, &camera, &shade, v, &mut timings),
        Method::ClBrute => {
            let device = device.as_ref().expect("opened above");
            let program = timings.time("compile", || ClTracer::compile_brute(device))?;
            let triangles = triangles_in_order(&mesh, 0..mesh.triangle_count() as u32);
            let mut tracer =
                timings.time("upload", || ClTracer::brute(device, &program, &triangles))?;
            let (frame, times) = tracer.render(
                &camera.pinhole(),
                camera.width,
                camera.height,
                &shade,
                v.progress(),
            )?;
            timings.add("kernel", times.kernel_ms);
            timings.add("read-back", times.read_back_ms);
            frame
        }
        Method::CpuBvh => {
            let bvh = build_bvh(&mesh, &req.build, v, &mut timings);
            let bar = (v.progress() && camera.width as u64 * camera.height as u64 > 1 << 24)
                .then(|| rows_bar(camera.height, "tracing on the CPU"));
            let frame = timings.time("trace", || {
                cpu::render(
                    &bvh,
                    &camera.pinhole(),
                    camera.width,
                    camera.height,
                    &shade,
                    bar.as_ref(),
                )
            });
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            frame
        }
        Method::ClBvh => {
            let device = device.as_ref().expect("opened above");
            let bvh = build_bvh(&mesh, &req.build, v, &mut timings);
            let program = timings.time("compile", || ClTracer::compile_bvh(device, bvh.depth))?;
            let mut tracer = timings.time("upload", || ClTracer::bvh(device, &program, &bvh))?;
            let (frame, times) = tracer.render(
                &camera.pinhole(),
                camera.width,
                camera.height,
                &shade,
                v.progress(),
            )?;
            timings.add("kernel", times.kernel_ms);
            timings.add("read-back", times.read_back_ms);
            frame
        }
    };

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

/// Builds the BVH and its flat layout, timed as "build", with details under `--verbose`.
fn build_bvh(mesh: &Mesh, options: &BuildOptions, v: Verbosity, timings: &mut Timings) -> FlatBvh {
    let bvh = timings.time("build", || Bvh::build(mesh, options));
    let stats = bvh.stats();
    v.detail(format!(
        "bvh: {} nodes, {} leaves, depth {}, mean leaf {:.2}, SAH cost {:.2}, {} threads",
        stats.nodes,
        stats.leaves,
        stats.depth,
        stats.mean_leaf_size,
        stats.sah_cost,
        rayon::current_num_threads()
    ));
    timings.time("layout", || FlatBvh::new(bvh, mesh))
}

fn trace_cpu_brute(
    mesh: &Mesh,
    camera: &Camera,
    shade: &ShadeParams,
    v: Verbosity,
    timings: &mut Timings,
) -> Frame {
    let tracer = cpu::BruteForce {
        triangles: triangles_in_order(mesh, 0..mesh.triangle_count() as u32),
    };
    let work = mesh.triangle_count() as f64 * camera.width as f64 * camera.height as f64;
    let bar = (v.progress() && work > 1e9).then(|| rows_bar(camera.height, "tracing on the CPU"));
    let frame = timings.time("trace", || {
        cpu::render(
            &tracer,
            &camera.pinhole(),
            camera.width,
            camera.height,
            shade,
            bar.as_ref(),
        )
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    frame
}

fn rows_bar(rows: u32, message: &'static str) -> ProgressBar {
    ProgressBar::new(rows as u64)
        .with_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} rows, {eta} left")
                .expect("valid template"),
        )
        .with_message(message)
}
