//! `cltrace render`: scene in, image out, every stage timed.

use std::path::{Path, PathBuf};

use crate::bvh::BuildOptions;
use crate::camera::Camera;
use crate::device::{ClDevice, DeviceSelector};
use crate::error::Result;
use crate::input::scene_file::{CameraSettings, RenderSettings, SceneDescription};
use crate::output;
use crate::render::{Frame, Method, Renderer, Shade, ShadeParams};
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
    let selector = DeviceSelector::from_flag_or_env(req.device.as_deref())?;

    // Opening a GPU driver takes a few hundred milliseconds: do it while the mesh loads.
    // A device error still wins over a mesh error, as it would have come first.
    let mut timings = Timings::default();
    let (device, mesh) = std::thread::scope(|s| {
        let opening = method
            .uses_opencl()
            .then(|| s.spawn(|| ClDevice::select(&selector)));
        let mesh = timings.time("load", || scene.mesh.load());
        let device = match opening {
            Some(handle) => Some(handle.join().expect("opening a device does not panic")?),
            None => None,
        };
        Ok::<_, crate::Error>((device, mesh?))
    })?;
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
    let shade = ShadeParams::new(shade, &camera, &bounds);

    let mut renderer = Renderer::prepare(method, &mesh, &req.build, device.as_ref(), &mut timings)?;
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
    let (frame, times) = renderer.render(&camera, &shade, v.progress())?;
    if method.uses_opencl() {
        timings.add("kernel", times.trace_ms);
        timings.add("read-back", times.read_back_ms);
    } else {
        timings.add("trace", times.trace_ms);
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
