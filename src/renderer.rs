//! The four methods behind one face: [`Renderer::prepare`] does the per-scene work (BVH
//! build and layout, kernel compilation, upload), then `Renderer::render` traces primary
//! frames, [`Renderer::render_samples`] accumulates the progressive shade modes and
//! `Renderer::trace_rays` traces arbitrary rays.

pub mod schedule;

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;

use crate::brute::BruteForce;
use crate::bvh::{Bin32Bvh, Bin32Node, BuildOptions, Bvh, BvhStats, DeviceLayout, Layout};
use crate::camera::Camera;
use crate::device::{ClDevice, ClTracer, Kernels, Program, default_layout};
use crate::error::Result;
use crate::geometry::Ray;
use crate::intersect::{ClosestHit, Triangle, triangles_in_order};
use crate::light::Lights;
use crate::material::Materials;
use crate::material::surface::{Surface, SurfaceFeatures};
use crate::mesh::{DEFAULT_CREASE_ANGLE, Mesh};
use crate::render::integrator::{self, Accumulation, Emitters, SampleSettings};
use crate::render::{Frame, Hit, Method, ShadeParams, cpu};
use crate::report::{Progress, Timings};

/// A method made ready for one mesh (on one device, for the OpenCL methods).
pub struct Renderer<'d> {
    tracer: Tracer<'d>,
    /// The materials, vertex data and textures the shading reads.
    surface: Surface,
    /// The emitting triangles, as indices into the tracer's triangle order.
    emitters: Emitters,
    /// The other lights.
    lights: Arc<Lights>,
    /// The BVH's statistics, for the BVH methods.
    pub(crate) bvh: Option<BvhStats>,
    /// Bytes of scene data the tracer reads (triangles, and nodes for a BVH).
    pub(crate) scene_bytes: usize,
}

enum Tracer<'d> {
    CpuBrute(BruteForce),
    CpuBvh(Bin32Bvh),
    Cl(Box<ClTracer<'d>>),
}

/// How [`Renderer::prepare`] readies a method.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrepareOptions {
    /// How the BVH methods build their tree.
    pub build: BuildOptions,
    /// The node layout `cl-bvh` uploads (the host methods always use the thesis's); `None`
    /// takes the device's default ([`default_layout`]).
    pub layout: Option<Layout>,
    /// The OpenCL kernels' work-group shape (pixels across, down); `None` for the
    /// tracer's default. One the device cannot run is ignored (it may come from a stale
    /// tuning cache).
    pub work_group: Option<[usize; 2]>,
    /// The kernels to compile (OpenCL methods): by default the closest-hit ones.
    pub kernels: Kernels,
    /// The crease angle of smooth normals, in degrees, for triangle corners without a
    /// normal (0: faceted); `None` takes [`DEFAULT_CREASE_ANGLE`].
    pub crease_angle: Option<f32>,
    /// Emitters shine from both faces, not only from the front one (their winding's side).
    pub two_sided_lights: bool,
    /// The lights besides emitting triangles (shared, not copied, between the renderers
    /// of several devices).
    pub lights: Arc<Lights>,
}

/// What tracing cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceTimes {
    /// Device time of the kernel launches (OpenCL) or wall time of the trace (CPU), ms.
    pub(crate) trace_ms: f64,
    /// Host wall time of reading results back (OpenCL only), ms.
    pub(crate) read_back_ms: f64,
}

impl<'d> Renderer<'d> {
    /// Builds and lays out the BVH (stages "build", "layout"), compiles the kernels
    /// ("compile") and uploads the scene ("upload"), as `method` needs, into `timings`.
    /// OpenCL methods need `device`.
    pub fn prepare(
        method: Method,
        mesh: &Mesh,
        materials: &Materials,
        options: &PrepareOptions,
        device: Option<&'d ClDevice>,
        timings: &mut Timings,
    ) -> Result<Self> {
        std::thread::scope(|s| {
            let program = compile_meanwhile(s, method, mesh, materials, options, device);
            let built = Self::build(method, mesh, materials, options, timings);
            let surface = Self::surface(mesh, materials, options, timings);
            Self::prepare_built(
                method, mesh, materials, options, built, surface, device, program, timings,
            )
        })
    }

    /// [`Renderer::prepare`] for each of several devices, the BVH and the surface data
    /// made once and the devices prepared at once, each on its own thread: the renderers of
    /// one frame split over devices ([`schedule`]). `options[i]` is for `devices[i]`. The
    /// devices' stages are timed as the slowest device's.
    pub(crate) fn prepare_each(
        method: Method,
        mesh: &Mesh,
        materials: &Materials,
        options: &[PrepareOptions],
        devices: &[&'d ClDevice],
        timings: &mut Timings,
    ) -> Result<Vec<Self>> {
        let prepared: Vec<(Result<Self>, Timings)> = std::thread::scope(|s| {
            let programs: Vec<_> = devices
                .iter()
                .zip(options)
                .map(|(&device, options)| {
                    compile_meanwhile(s, method, mesh, materials, options, Some(device))
                })
                .collect();
            let built = Self::build(method, mesh, materials, &options[0], timings);
            let surface = Self::surface(mesh, materials, &options[0], timings);
            let threads: Vec<_> = devices
                .iter()
                .zip(options)
                .zip(programs)
                .map(|((&device, options), program)| {
                    let (built, surface) = (built.clone(), surface.clone());
                    s.spawn(move || {
                        let mut own = Timings::default();
                        let renderer = Self::prepare_built(
                            method,
                            mesh,
                            materials,
                            options,
                            built,
                            surface,
                            Some(device),
                            program,
                            &mut own,
                        );
                        (renderer, own)
                    })
                })
                .collect();
            threads
                .into_iter()
                .map(|t| t.join().expect("preparing a device does not panic"))
                .collect()
        });
        let slowest = prepared
            .iter()
            .map(|(_, t)| t)
            .max_by(|a, b| a.total_ms().total_cmp(&b.total_ms()));
        for (stage, ms) in slowest.into_iter().flat_map(|t| t.stages()) {
            timings.add(stage, ms);
        }
        prepared.into_iter().map(|(r, _)| r).collect()
    }

    /// The surface data the kernels shade with: smooth normals where the mesh has none
    /// (stage "surface").
    fn surface(
        mesh: &Mesh,
        materials: &Materials,
        options: &PrepareOptions,
        timings: &mut Timings,
    ) -> Surface {
        timings.time("surface", || {
            let crease = options.crease_angle.unwrap_or(DEFAULT_CREASE_ANGLE);
            let mut smooth;
            let mesh = match crease > 0.0 {
                true => {
                    smooth = mesh.clone();
                    smooth.fill_normals(crease);
                    &smooth
                }
                false => mesh,
            };
            Surface::new(mesh, materials)
        })
    }

    /// The BVH in the thesis's layout, with its statistics, for the BVH methods.
    fn build(
        method: Method,
        mesh: &Mesh,
        materials: &Materials,
        options: &PrepareOptions,
        timings: &mut Timings,
    ) -> Option<(Bin32Bvh, BvhStats)> {
        if !method.uses_bvh() {
            return None;
        }
        let (bvh, stats) = timings.time("build", || {
            let bvh = Bvh::build(mesh, &options.build);
            let stats = bvh.stats();
            (bvh, stats)
        });
        let flat = timings.time("layout", || {
            let mut flat = Bin32Bvh::new(bvh, mesh);
            materials.assign(&mut flat.triangles, options.two_sided_lights);
            flat
        });
        Some((flat, stats))
    }

    #[allow(clippy::too_many_arguments)]
    fn prepare_built(
        method: Method,
        mesh: &Mesh,
        materials: &Materials,
        options: &PrepareOptions,
        built: Option<(Bin32Bvh, BvhStats)>,
        surface: Surface,
        device: Option<&'d ClDevice>,
        program: impl FnOnce(SurfaceFeatures) -> Result<Program>,
        timings: &mut Timings,
    ) -> Result<Self> {
        let features = lit_features(surface.features(), options);
        let (flat, mut bvh) = match built {
            Some((flat, stats)) => (Some(flat), Some(stats)),
            None => (None, None),
        };
        let all = || {
            let mut t = triangles_in_order(mesh, 0..mesh.triangle_count() as u32);
            materials.assign(&mut t, options.two_sided_lights);
            t
        };
        let bytes = |nodes: usize, tris: usize| {
            nodes * size_of::<Bin32Node>() + tris * size_of::<Triangle>()
        };
        let device = || device.expect("OpenCL methods are given a device");
        let (tracer, scene_bytes, emitters) = match (method, flat) {
            (Method::CpuBrute, _) => {
                let triangles = all();
                let emitters =
                    timings.time("lights", || Emitters::new(&triangles, &materials.list));
                let n = triangles.len();
                (
                    Tracer::CpuBrute(BruteForce { triangles }),
                    bytes(0, n),
                    emitters,
                )
            }
            (Method::CpuBvh, Some(flat)) => {
                let emitters =
                    timings.time("lights", || Emitters::new(&flat.triangles, &materials.list));
                let b = bytes(flat.nodes.len(), flat.triangles.len());
                (Tracer::CpuBvh(flat), b, emitters)
            }
            (Method::ClBrute, _) => {
                let device = device();
                let program = timings.time("compile", || program(features))?;
                let triangles = all();
                let emitters =
                    timings.time("lights", || Emitters::new(&triangles, &materials.list));
                let tracer = timings.time("upload", || -> Result<ClTracer> {
                    let mut t = ClTracer::brute(device, &program, &triangles)?;
                    t.set_surface(&surface)?;
                    t.set_lights(&emitters, &options.lights)?;
                    Ok(t)
                })?;
                (
                    Tracer::Cl(Box::new(tracer)),
                    bytes(0, triangles.len()),
                    emitters,
                )
            }
            (Method::ClBvh, Some(flat)) => {
                let device = device();
                let sah = bvh.map_or(0.0, |s| s.sah_cost);
                let layout = options
                    .layout
                    .unwrap_or_else(|| default_layout(&device.info));
                let laid = timings.time("layout", || DeviceLayout::new(flat, layout, sah));
                // After the layout: the compressed one reorders the triangles.
                let emitters =
                    timings.time("lights", || Emitters::new(&laid.triangles, &materials.list));
                let program = timings.time("compile", || program(features))?;
                let tracer = timings.time("upload", || -> Result<ClTracer> {
                    let mut t = ClTracer::with_layout(device, &program, &laid)?;
                    t.set_surface(&surface)?;
                    t.set_lights(&emitters, &options.lights)?;
                    if let Some(shape) = options.work_group {
                        // A cache that no longer fits the device is ignored, not fatal.
                        let _ = t.set_work_group(shape);
                    }
                    Ok(t)
                })?;
                let b = laid.device_bytes();
                if let Some(s) = bvh.as_mut() {
                    s.sah_cost = laid.sah_cost;
                }
                (Tracer::Cl(Box::new(tracer)), b, emitters)
            }
            (Method::CpuBvh | Method::ClBvh, None) => unreachable!("BVH methods build a BVH above"),
        };
        Ok(Renderer {
            tracer,
            surface,
            emitters,
            lights: options.lights.clone(),
            bvh,
            scene_bytes,
        })
    }

    /// Traces one frame of primary rays. With `progress`, a long render shows a bar.
    pub(crate) fn render(
        &mut self,
        camera: &Camera,
        shade: &ShadeParams,
        progress: bool,
    ) -> Result<(Frame, TraceTimes)> {
        let (w, h) = (camera.width, camera.height);
        let pixels = w as u64 * h as u64;
        let cpu_trace = |tracer: &dyn Fn(&(dyn Fn() + Sync)) -> Frame, long: bool| {
            let bar = Progress::new(progress && long, "tracing on the CPU", h as u64, "rows");
            let start = std::time::Instant::now();
            let frame = tracer(&|| bar.inc(1));
            bar.finish();
            let times = TraceTimes {
                trace_ms: start.elapsed().as_secs_f64() * 1e3,
                read_back_ms: 0.0,
            };
            (frame, times)
        };
        let surface = &self.surface;
        let traced = match &mut self.tracer {
            Tracer::CpuBrute(t) => cpu_trace(
                &|row| cpu::render_surface(t, surface, &camera.pinhole(), w, h, shade, Some(row)),
                pixels * t.triangles.len() as u64 > 1 << 30,
            ),
            Tracer::CpuBvh(t) => cpu_trace(
                &|row| cpu::render_surface(t, surface, &camera.pinhole(), w, h, shade, Some(row)),
                pixels > 1 << 24,
            ),
            Tracer::Cl(t) => {
                let (frame, times) = t.render(&camera.pinhole(), w, h, shade, progress)?;
                let times = TraceTimes {
                    trace_ms: times.kernel_ms,
                    read_back_ms: times.read_back_ms,
                };
                (frame, times)
            }
        };
        // Interrupted, the frame misses rows: nothing of it may be written.
        crate::interrupt::check()?;
        Ok(traced)
    }

    /// Adds samples `samples` of every pixel of `accumulation`'s region (of an image the
    /// camera's size) to it, in the progressive mode `settings` names. `stop`, once set, ends the work
    /// early; each pixel keeps the samples it got. With `progress`, a bar shows samples
    /// and Mrays/s.
    pub fn render_samples(
        &mut self,
        camera: &Camera,
        settings: &SampleSettings,
        samples: std::ops::Range<u32>,
        accumulation: &mut Accumulation,
        stop: &AtomicBool,
        progress: bool,
    ) -> Result<TraceTimes> {
        let bar = Progress::new(progress, "sampling", samples.len() as u64, "samples");
        let start = std::time::Instant::now();
        let rays_before = accumulation.rays;
        let pinhole = camera.pinhole();
        let times = match &mut self.tracer {
            Tracer::Cl(t) => {
                let device = t.render_samples(
                    &pinhole,
                    settings,
                    samples.clone(),
                    accumulation,
                    stop,
                    &mut |done, rays| {
                        if let Some(rays) = rays {
                            bar.set_message(mrays(start, rays));
                        }
                        bar.set_position(done as u64);
                    },
                )?;
                TraceTimes {
                    trace_ms: device.kernel_ms,
                    read_back_ms: device.read_back_ms,
                }
            }
            tracer => {
                let host = tracer.host().expect("the OpenCL tracer is handled above");
                for s in samples {
                    if stop.load(std::sync::atomic::Ordering::Relaxed) {
                        break;
                    }
                    integrator::render_samples(
                        host,
                        &self.surface,
                        &self.emitters,
                        &self.lights,
                        &pinhole,
                        settings,
                        s..s + 1,
                        accumulation,
                        stop,
                    );
                    bar.set_message(mrays(start, accumulation.rays - rays_before));
                    bar.inc(1);
                }
                TraceTimes {
                    trace_ms: start.elapsed().as_secs_f64() * 1e3,
                    read_back_ms: 0.0,
                }
            }
        };
        bar.finish();
        Ok(times)
    }

    /// Sums of `region` kept on the device between units of a frame split over devices
    /// ([`schedule`]); `None` for the host methods, or where they do not fit on the device.
    pub(crate) fn begin_samples(
        &mut self,
        camera: &Camera,
        settings: &SampleSettings,
        region: crate::render::integrator::Region,
    ) -> Result<Option<crate::device::tracer::SampleSession>> {
        match &mut self.tracer {
            Tracer::Cl(t) => t.begin_samples(&camera.pinhole(), settings, camera.width, region),
            _ => Ok(None),
        }
    }

    /// Adds samples of some rows to a session's sums; the kernels' time, ms.
    pub(crate) fn add_samples(
        &mut self,
        session: &mut crate::device::tracer::SampleSession,
        rows: std::ops::Range<u32>,
        samples: std::ops::Range<u32>,
        stop: &AtomicBool,
    ) -> Result<f64> {
        match &mut self.tracer {
            Tracer::Cl(t) => t.add_samples(session, rows, samples, stop),
            _ => unreachable!("only the OpenCL tracer starts sessions"),
        }
    }

    /// A session's sums of the rows its units touched, read back; `None` if it took none.
    pub(crate) fn finish_samples(
        &mut self,
        session: crate::device::tracer::SampleSession,
    ) -> Result<Option<Accumulation>> {
        match &mut self.tracer {
            Tracer::Cl(t) => t.finish_samples(session),
            _ => unreachable!("only the OpenCL tracer starts sessions"),
        }
    }

    /// What the OpenCL kernels run with: the BVH layout (`None` for brute force) and the
    /// work-group shape; `None` for the host methods.
    pub(crate) fn kernels(&self) -> Option<(Option<Layout>, [usize; 2])> {
        match &self.tracer {
            Tracer::Cl(t) => Some((t.layout(), t.work_group())),
            _ => None,
        }
    }

    /// What the program cache did for the OpenCL kernels; `None` for the host methods or
    /// without a cache.
    pub(crate) fn program_cache(&self) -> Option<&crate::device::CacheUse> {
        match &self.tracer {
            Tracer::Cl(t) => t.program_cache(),
            _ => None,
        }
    }

    /// Sets the OpenCL kernels' work-group shape (ignored by the host methods).
    pub(crate) fn set_work_group(&mut self, shape: [usize; 2]) -> Result<()> {
        match &mut self.tracer {
            Tracer::Cl(t) => t.set_work_group(shape),
            _ => Ok(()),
        }
    }

    /// Traces arbitrary rays (closest hits in `(0, t_max)`, or any hits), as the bench's
    /// secondary ray kinds do.
    pub(crate) fn trace_rays(
        &mut self,
        rays: &[Ray],
        t_max: f32,
        any_hit: bool,
    ) -> Result<(Vec<Hit>, TraceTimes)> {
        let start = std::time::Instant::now();
        Ok(match &mut self.tracer {
            Tracer::Cl(t) => {
                let (hits, device) = t.trace_rays_timed(rays, t_max, any_hit)?;
                (
                    hits,
                    TraceTimes {
                        trace_ms: device.kernel_ms,
                        read_back_ms: device.read_back_ms,
                    },
                )
            }
            tracer => {
                let host = tracer.host().expect("the OpenCL tracer is handled above");
                let hits = rays
                    .par_iter()
                    .with_min_len(1024)
                    .map(|ray| match host.trace(ray, t_max, any_hit) {
                        None => Hit::NONE,
                        Some((i, t)) => Hit {
                            prim: host.triangles()[i].prim,
                            t: t * ray.dir.length(),
                        },
                    })
                    .collect();
                let times = TraceTimes {
                    trace_ms: start.elapsed().as_secs_f64() * 1e3,
                    read_back_ms: 0.0,
                };
                (hits, times)
            }
        })
    }
}

impl Tracer<'_> {
    /// The host tracer of the CPU methods (`None` for OpenCL).
    fn host(&self) -> Option<&dyn ClosestHit> {
        match self {
            Tracer::CpuBrute(t) => Some(t),
            Tracer::CpuBvh(t) => Some(t),
            Tracer::Cl(_) => None,
        }
    }
}

fn mrays(start: std::time::Instant, rays: u64) -> String {
    format!(
        "{:.1} Mrays/s",
        rays as f64 / start.elapsed().as_secs_f64() / 1e6
    )
}

/// The features the kernels are compiled for: the surface's, and the lights'.
fn lit_features(surface: SurfaceFeatures, options: &PrepareOptions) -> SurfaceFeatures {
    SurfaceFeatures {
        environment: options.lights.environment.is_some(),
        punctual: !options.lights.punctual.is_empty(),
        ..surface
    }
}

/// Starts compiling the kernels of an OpenCL `method` on `device` in `scope` while the
/// tree and the surface are built: a program depends on the layout, its largest stack
/// ([`Layout::max_stack_size`]), the kernels, the lights and the surface's features, which
/// are known before the smooth normals are computed. What it returns gives the program
/// once the surface's features are known: the one started, or where those turned out
/// otherwise (they should not), one compiled then.
fn compile_meanwhile<'s, 'd: 's>(
    scope: &'s std::thread::Scope<'s, '_>,
    method: Method,
    mesh: &Mesh,
    materials: &Materials,
    options: &PrepareOptions,
    device: Option<&'d ClDevice>,
) -> impl FnOnce(SurfaceFeatures) -> Result<Program> + Send + 's {
    let crease = options.crease_angle.unwrap_or(DEFAULT_CREASE_ANGLE);
    let expected = lit_features(
        SurfaceFeatures::before_normals(mesh, materials, crease),
        options,
    );
    let bvh = match (method, device) {
        (Method::ClBvh, Some(device)) => {
            let layout = options
                .layout
                .unwrap_or_else(|| default_layout(&device.info));
            Some((layout, layout.max_stack_size()))
        }
        _ => None,
    };
    let kernels = options.kernels;
    let compile = move |features| {
        let device = device.expect("OpenCL methods are given a device");
        ClTracer::compile_for(device, bvh, kernels, features)
    };
    let started = method
        .uses_opencl()
        .then(|| scope.spawn(move || compile(expected)));
    move |features| match started {
        Some(handle) if features == expected => handle.join().expect("compiling does not panic"),
        _ => compile(features),
    }
}
