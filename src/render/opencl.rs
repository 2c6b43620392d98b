//! The OpenCL renderer: uploads the scene, launches the tracing kernels over bands of rows
//! (each launch bounded in time, the band height adapted from the launches before), and
//! reads each band back from pitched device images.

use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use ocl::enums::ProfilingInfo;
use ocl::prm::Float4;

use super::{Frame, Hit, ShadeParams};
use crate::camera::Pinhole;
use crate::device::{ClDevice, KernelSource, PitchedBuffer};
use crate::error::{Error, Result};
use crate::geometry::Ray;
use crate::layout::{BvhNode, FlatBvh, Triangle};

/// Default bound on one kernel launch, in milliseconds of device time.
pub const LAUNCH_TARGET_MS: f64 = 100.0;

/// What one render on the device cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeviceTimes {
    /// Sum of the kernel launches' device time (profiling events).
    pub kernel_ms: f64,
    /// Host wall time of the rectangular reads.
    pub read_back_ms: f64,
    pub launches: u32,
}

/// The scene on the device: what every kernel's leading `SCENE_PARAMS` receive.
struct Scene {
    /// Every triangle: in file order for brute force, in leaf order under a BVH.
    triangles: ocl::Buffer<Triangle>,
    count: u32,
    bvh: Option<DeviceBvh>,
}

/// The flat BVH's nodes and the kernels' error flags (bit 0: a stack overflowed).
struct DeviceBvh {
    nodes: ocl::Buffer<BvhNode>,
    status: ocl::Buffer<u32>,
}

/// The kernels compiled for one device with their scene uploaded, ready to trace.
pub struct ClTracer<'d> {
    device: &'d ClDevice,
    program: ocl::Program,
    scene: Scene,
    primary: ocl::Kernel,
    bands: BandPlanner,
}

/// Sizes bands of rows so that each launch takes about [`LAUNCH_TARGET_MS`].
struct BandPlanner {
    /// Pixels per millisecond seen so far.
    rate: Option<f64>,
    /// Pixels of the first band when nothing has been measured yet.
    first_band_pixels: usize,
}

impl BandPlanner {
    fn next_rows(&self, width: usize, remaining: usize) -> usize {
        let pixels = match self.rate {
            Some(rate) => (rate * LAUNCH_TARGET_MS) as usize,
            None => self.first_band_pixels,
        };
        (pixels / width).clamp(1, remaining)
    }

    fn learn(&mut self, pixels: usize, ms: f64) {
        // Launches too short to time say little; never grow more than 8x at a step.
        let measured = pixels as f64 / ms.max(0.01);
        self.rate = Some(match self.rate {
            Some(old) => measured.min(old * 8.0),
            None => measured,
        });
    }
}

impl<'d> ClTracer<'d> {
    /// Compiles the kernels against a plain triangle list (brute force).
    pub fn compile_brute(device: &'d ClDevice) -> Result<ocl::Program> {
        device.build(KernelSource::Trace, &[])
    }

    /// Compiles the kernels against the BVH, with a traversal stack as deep as the tree.
    pub fn compile_bvh(device: &'d ClDevice, depth: u32) -> Result<ocl::Program> {
        device.build(
            KernelSource::Trace,
            &[("STACK_SIZE", depth.max(1).to_string())],
        )
    }

    /// Uploads the triangles (in file order) for the brute-force kernels.
    pub fn brute(
        device: &'d ClDevice,
        program: &ocl::Program,
        triangles: &[Triangle],
    ) -> Result<Self> {
        let scene = Scene {
            triangles: upload(device, triangles, "uploading triangles")?,
            count: triangles.len() as u32,
            bvh: None,
        };
        // About 16 million ray/triangle tests in the first launch.
        Self::new(
            device,
            program,
            scene,
            (1usize << 24) / triangles.len().max(1),
        )
    }

    /// Uploads the flat BVH for the BVH kernels.
    pub fn bvh(device: &'d ClDevice, program: &ocl::Program, bvh: &FlatBvh) -> Result<Self> {
        let status = ocl::Buffer::<u32>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_READ_WRITE)
            .len(1)
            .build()
            .map_err(|e| device.error("allocating the status flag", e))?;
        let scene = Scene {
            triangles: upload(device, &bvh.triangles, "uploading triangles")?,
            count: bvh.triangles.len() as u32,
            bvh: Some(DeviceBvh {
                nodes: upload(device, &bvh.nodes, "uploading BVH nodes")?,
                status,
            }),
        };
        Self::new(device, program, scene, 1 << 16)
    }

    fn new(
        device: &'d ClDevice,
        program: &ocl::Program,
        scene: Scene,
        first_band_pixels: usize,
    ) -> Result<Self> {
        let mut builder = kernel_builder(device, program, "trace_primary", &scene);
        builder
            .arg(Float4::zero())
            .arg(Float4::zero())
            .arg(Float4::zero())
            .arg(Float4::zero())
            .arg(0u32)
            .arg(0u32)
            .arg(0u32)
            .arg(0i32)
            .arg(0f32)
            .arg(0f32)
            .arg(None::<&ocl::Buffer<Hit>>)
            .arg(0u32)
            .arg(None::<&ocl::Buffer<u32>>)
            .arg(0u32);
        let primary = builder
            .build()
            .map_err(|e| device.error("creating the trace_primary kernel", e))?;
        Ok(ClTracer {
            device,
            program: program.clone(),
            scene,
            primary,
            bands: BandPlanner {
                rate: None,
                first_band_pixels,
            },
        })
    }

    /// Renders one frame. `progress` shows a bar on stderr when the render looks long.
    pub fn render(
        &mut self,
        camera: &Pinhole,
        width: u32,
        height: u32,
        shade: &ShadeParams,
        progress: bool,
    ) -> Result<(Frame, DeviceTimes)> {
        let device = self.device;
        let (w, h) = (width as usize, height as usize);
        let band_capacity = band_capacity(device, w, h);
        let hits = PitchedBuffer::<Hit>::new(device, w, band_capacity)?;
        let colors = PitchedBuffer::<u32>::new(device, w, band_capacity)?;

        let k = &self.primary;
        let set = |i: u32, e: std::result::Result<(), ocl::Error>| {
            e.map_err(|e| device.error(&format!("setting kernel argument {i}"), e))
        };
        let f4 = |v: [f32; 4]| Float4::new(v[0], v[1], v[2], v[3]);
        let a = self.scene.arg_count();
        set(a, k.set_arg(a, f4(camera.eye)))?;
        set(a + 1, k.set_arg(a + 1, f4(camera.p0)))?;
        set(a + 2, k.set_arg(a + 2, f4(camera.du)))?;
        set(a + 3, k.set_arg(a + 3, f4(camera.dv)))?;
        set(a + 4, k.set_arg(a + 4, width))?;
        set(a + 7, k.set_arg(a + 7, shade.shade.code()))?;
        set(a + 8, k.set_arg(a + 8, shade.near))?;
        set(a + 9, k.set_arg(a + 9, shade.far))?;
        set(a + 10, k.set_arg(a + 10, &hits.buffer))?;
        set(a + 11, k.set_arg(a + 11, hits.pitch as u32))?;
        set(a + 12, k.set_arg(a + 12, &colors.buffer))?;
        set(a + 13, k.set_arg(a + 13, colors.pitch as u32))?;
        self.scene.clear_status(device)?;

        let local = local_size(device);
        let mut frame = Frame::new(width, height);
        let mut times = DeviceTimes::default();
        let mut bar: Option<ProgressBar> = None;
        let mut y0 = 0usize;
        while y0 < h {
            let rows = self.bands.next_rows(w, h - y0).min(band_capacity);
            // Work-items past the band (the global size is rounded up) return at once.
            set(a + 5, k.set_arg(a + 5, y0 as u32))?;
            set(a + 6, k.set_arg(a + 6, (y0 + rows) as u32))?;
            let global = [
                w.div_ceil(local[0]) * local[0],
                rows.div_ceil(local[1]) * local[1],
            ];
            let ms = launch(
                device,
                k.cmd()
                    .global_work_offset([0, y0])
                    .global_work_size(global)
                    .local_work_size(local),
            )?;
            times.kernel_ms += ms;
            times.launches += 1;
            self.bands.learn(rows * w, ms);

            let start = Instant::now();
            hits.read_rows(device, rows, &mut frame.hits[y0 * w..])?;
            colors.read_rows(device, rows, &mut frame.colors[y0 * w..])?;
            times.read_back_ms += start.elapsed().as_secs_f64() * 1e3;

            y0 += rows;
            if progress && bar.is_none() && y0 < h {
                // Show a bar only when the remaining work looks longer than a second.
                let remaining_ms =
                    (h - y0) as f64 * w as f64 / self.bands.rate.unwrap_or(f64::INFINITY);
                if remaining_ms > 1000.0 {
                    let b = ProgressBar::new(h as u64).with_style(
                        ProgressStyle::with_template(
                            "{msg} [{bar:30}] {pos}/{len} rows, {eta} left",
                        )
                        .expect("valid template"),
                    );
                    b.set_message(format!("tracing on {}", device.info.name));
                    bar = Some(b);
                }
            }
            if let Some(b) = &bar {
                b.set_position(y0 as u64);
            }
        }
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        self.scene.check_status(device)?;
        Ok((frame, times))
    }

    /// Traces arbitrary rays: the closest hit of each in `(0, t_max)`, or with `any_hit`
    /// any hit there. Hits name triangles in file order; `t` is the distance along the ray.
    pub fn trace_rays(&mut self, rays: &[Ray], t_max: f32, any_hit: bool) -> Result<Vec<Hit>> {
        let device = self.device;
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let packed: Vec<Float4> = rays
            .iter()
            .flat_map(|r| {
                [
                    Float4::new(r.origin.x, r.origin.y, r.origin.z, t_max),
                    Float4::new(r.dir.x, r.dir.y, r.dir.z, 0.0),
                ]
            })
            .collect();
        let input = upload(device, &packed, "uploading rays")?;
        let output = ocl::Buffer::<Hit>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_WRITE_ONLY)
            .len(rays.len())
            .build()
            .map_err(|e| device.error("allocating the hit buffer", e))?;
        let mut builder = kernel_builder(device, &self.program, "trace_rays", &self.scene);
        builder
            .arg(&input)
            .arg(rays.len() as u32)
            .arg(any_hit as i32)
            .arg(&output)
            .global_work_size(rays.len());
        let kernel = builder
            .build()
            .map_err(|e| device.error("creating the trace_rays kernel", e))?;
        self.scene.clear_status(device)?;
        launch(device, kernel.cmd())?;
        let mut hits = vec![Hit::NONE; rays.len()];
        output
            .read(&mut hits)
            .enq()
            .map_err(|e| device.error("reading hits back", e))?;
        self.scene.check_status(device)?;
        Ok(hits)
    }
}

impl Scene {
    /// How many kernel arguments the scene takes (they come first).
    fn arg_count(&self) -> u32 {
        if self.bvh.is_some() { 3 } else { 2 }
    }

    fn clear_status(&self, device: &ClDevice) -> Result<()> {
        if let Some(DeviceBvh { status, .. }) = &self.bvh {
            status
                .write(&[0u32][..])
                .enq()
                .map_err(|e| device.error("clearing the status flag", e))?;
        }
        Ok(())
    }

    /// Refuses the result of kernels that raised an error flag.
    fn check_status(&self, device: &ClDevice) -> Result<()> {
        if let Some(DeviceBvh { status, .. }) = &self.bvh {
            let mut flags = [0u32];
            status
                .read(&mut flags[..])
                .enq()
                .map_err(|e| device.error("reading the kernel's status", e))?;
            if flags[0] != 0 {
                return Err(Error::Device(format!(
                    "the BVH kernel on {} overflowed its traversal stack (status {:#x}): the image would be wrong, so none was written",
                    device.info.name, flags[0]
                )));
            }
        }
        Ok(())
    }
}

/// A kernel builder with the scene's arguments in place.
fn kernel_builder<'b>(
    device: &ClDevice,
    program: &'b ocl::Program,
    name: &str,
    scene: &'b Scene,
) -> ocl::builders::KernelBuilder<'b> {
    let mut builder = ocl::Kernel::builder();
    builder
        .program(program)
        .name(name)
        .queue(device.queue.clone());
    match &scene.bvh {
        None => builder.arg(&scene.triangles).arg(scene.count),
        Some(bvh) => builder
            .arg(&bvh.nodes)
            .arg(&scene.triangles)
            .arg(&bvh.status),
    };
    builder
}

/// Enqueues a kernel, waits for it, and returns its device time in milliseconds.
fn launch(device: &ClDevice, cmd: ocl::builders::KernelCmd) -> Result<f64> {
    let mut event = ocl::Event::empty();
    unsafe {
        cmd.enew(&mut event)
            .enq()
            .map_err(|e| device.error("launching the kernel", e))?;
    }
    event
        .wait_for()
        .map_err(|e| device.error("running the kernel", e.into()))?;
    event_ms(&event).map_err(|e| device.error("reading the kernel's profiling times", e))
}

fn upload<T: ocl::OclPrm>(device: &ClDevice, data: &[T], doing: &str) -> Result<ocl::Buffer<T>> {
    ocl::Buffer::<T>::builder()
        .queue(device.queue.clone())
        .flags(ocl::flags::MEM_READ_ONLY | ocl::flags::MEM_COPY_HOST_PTR)
        .len(data.len())
        .copy_host_slice(data)
        .build()
        .map_err(|e| device.error(doing, e))
}

/// Rows the output images hold: the whole frame where the device allows, else as many
/// rows as fit in its largest allocation and an eighth of its memory.
fn band_capacity(device: &ClDevice, width: usize, height: usize) -> usize {
    let row_bytes = PitchedBuffer::<Hit>::pitch_bytes_for(device, width) as u64;
    let limit = device
        .info
        .max_allocation
        .min(device.info.global_memory / 8);
    ((limit / row_bytes) as usize).clamp(1, height)
}

/// Work-group shape: 8 x 8 pixel tiles keep neighbouring rays together.
fn local_size(device: &ClDevice) -> [usize; 2] {
    if device.info.max_work_group_size >= 64 {
        [8, 8]
    } else {
        [1, 1]
    }
}

fn event_ms(event: &ocl::Event) -> std::result::Result<f64, ocl::Error> {
    let start = event.profiling_info(ProfilingInfo::Start)?.time()?;
    let end = event.profiling_info(ProfilingInfo::End)?.time()?;
    Ok(end.saturating_sub(start) as f64 * 1e-6)
}
