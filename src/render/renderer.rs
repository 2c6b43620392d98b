//! The four methods behind one face: [`Renderer::prepare`] does the per-scene work (BVH
//! build and layout, kernel compilation, upload), [`Renderer::render`] traces frames.

use indicatif::{ProgressBar, ProgressStyle};

use super::opencl::ClTracer;
use super::{Frame, Method, ShadeParams, cpu};
use crate::bvh::{BuildOptions, Bvh, BvhStats};
use crate::camera::Camera;
use crate::device::ClDevice;
use crate::error::Result;
use crate::layout::{BvhNode, FlatBvh, Triangle, triangles_in_order};
use crate::mesh::Mesh;
use crate::report::Timings;

/// A method made ready for one mesh (on one device, for the OpenCL methods).
pub struct Renderer<'d> {
    tracer: Tracer<'d>,
    /// The BVH's statistics, for the BVH methods.
    pub bvh: Option<BvhStats>,
    /// Bytes of scene data the tracer reads (triangles, and nodes for a BVH).
    pub scene_bytes: usize,
}

enum Tracer<'d> {
    CpuBrute(cpu::BruteForce),
    CpuBvh(FlatBvh),
    Cl(Box<ClTracer<'d>>),
}

/// What tracing one frame cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceTimes {
    /// Device time of the kernel launches (OpenCL) or wall time of the trace (CPU), ms.
    pub trace_ms: f64,
    /// Host wall time of reading the images back (OpenCL only), ms.
    pub read_back_ms: f64,
}

impl<'d> Renderer<'d> {
    /// Builds and lays out the BVH (stages "build", "layout"), compiles the kernel
    /// ("compile") and uploads the scene ("upload"), as `method` needs, into `timings`.
    /// OpenCL methods need `device`.
    pub fn prepare(
        method: Method,
        mesh: &Mesh,
        build: &BuildOptions,
        device: Option<&'d ClDevice>,
        timings: &mut Timings,
    ) -> Result<Self> {
        let (flat, bvh) = if method.uses_bvh() {
            let bvh = timings.time("build", || Bvh::build(mesh, build));
            let stats = bvh.stats();
            (
                Some(timings.time("layout", || FlatBvh::new(bvh, mesh))),
                Some(stats),
            )
        } else {
            (None, None)
        };
        let all = || triangles_in_order(mesh, 0..mesh.triangle_count() as u32);
        let bytes =
            |nodes: usize, tris: usize| nodes * size_of::<BvhNode>() + tris * size_of::<Triangle>();
        let device = || device.expect("OpenCL methods are given a device");
        let (tracer, scene_bytes) = match (method, flat) {
            (Method::CpuBrute, _) => {
                let triangles = all();
                let n = triangles.len();
                (Tracer::CpuBrute(cpu::BruteForce { triangles }), bytes(0, n))
            }
            (Method::CpuBvh, Some(flat)) => {
                let b = bytes(flat.nodes.len(), flat.triangles.len());
                (Tracer::CpuBvh(flat), b)
            }
            (Method::ClBrute, _) => {
                let device = device();
                let program = timings.time("compile", || ClTracer::compile_brute(device))?;
                let triangles = all();
                let tracer =
                    timings.time("upload", || ClTracer::brute(device, &program, &triangles))?;
                (Tracer::Cl(Box::new(tracer)), bytes(0, triangles.len()))
            }
            (Method::ClBvh, Some(flat)) => {
                let device = device();
                let program =
                    timings.time("compile", || ClTracer::compile_bvh(device, flat.depth))?;
                let tracer = timings.time("upload", || ClTracer::bvh(device, &program, &flat))?;
                (
                    Tracer::Cl(Box::new(tracer)),
                    bytes(flat.nodes.len(), flat.triangles.len()),
                )
            }
            (Method::CpuBvh | Method::ClBvh, None) => unreachable!("BVH methods build a BVH above"),
        };
        Ok(Renderer {
            tracer,
            bvh,
            scene_bytes,
        })
    }

    /// Traces one frame. With `progress`, a long render shows a bar on stderr.
    pub fn render(
        &mut self,
        camera: &Camera,
        shade: &ShadeParams,
        progress: bool,
    ) -> Result<(Frame, TraceTimes)> {
        let (w, h) = (camera.width, camera.height);
        let pixels = w as u64 * h as u64;
        let cpu_trace = |tracer: &dyn Fn(Option<&ProgressBar>) -> Frame, long: bool| {
            let bar = (progress && long).then(|| {
                ProgressBar::new(h as u64)
                    .with_style(
                        ProgressStyle::with_template(
                            "{msg} [{bar:30}] {pos}/{len} rows, {eta} left",
                        )
                        .expect("valid template"),
                    )
                    .with_message("tracing on the CPU")
            });
            let start = std::time::Instant::now();
            let frame = tracer(bar.as_ref());
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            let times = TraceTimes {
                trace_ms: start.elapsed().as_secs_f64() * 1e3,
                read_back_ms: 0.0,
            };
            (frame, times)
        };
        Ok(match &mut self.tracer {
            Tracer::CpuBrute(t) => cpu_trace(
                &|bar| cpu::render(t, &camera.pinhole(), w, h, shade, bar),
                pixels * t.triangles.len() as u64 > 1 << 30,
            ),
            Tracer::CpuBvh(t) => cpu_trace(
                &|bar| cpu::render(t, &camera.pinhole(), w, h, shade, bar),
                pixels > 1 << 24,
            ),
            Tracer::Cl(t) => {
                let (frame, times) = t.render(&camera.pinhole(), w, h, shade, progress)?;
                (
                    frame,
                    TraceTimes {
                        trace_ms: times.kernel_ms,
                        read_back_ms: times.read_back_ms,
                    },
                )
            }
        })
    }
}
