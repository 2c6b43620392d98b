//! The OpenCL renderer: uploads the scene, launches a tracing kernel over bands of rows
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

/// A compiled kernel with its scene uploaded, ready to render frames.
pub struct ClTracer<'d> {
    device: &'d ClDevice,
    kernel: ocl::Kernel,
    /// Index of the first camera argument; the scene's buffers come before it.
    first_camera_arg: u32,
    bands: BandPlanner,
    /// The scene on the device, kept alive as long as the kernel that reads it.
    _triangles: ocl::Buffer<Triangle>,
    _nodes: Option<ocl::Buffer<BvhNode>>,
    /// The BVH kernel's error flags; bit 0: a traversal stack overflowed.
    status: Option<ocl::Buffer<u32>>,
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
    /// Compiles the brute-force kernel.
    pub fn compile_brute(device: &'d ClDevice) -> Result<ocl::Program> {
        device.build(KernelSource::Brute, &[])
    }

    /// Uploads the triangles (in file order) for the brute-force kernel.
    pub fn brute(
        device: &'d ClDevice,
        program: &ocl::Program,
        triangles: &[Triangle],
    ) -> Result<Self> {
        let tris = upload(device, triangles, "uploading triangles")?;
        let kernel = ocl::Kernel::builder()
            .program(program)
            .name("trace_brute")
            .queue(device.queue.clone())
            .arg(&tris)
            .arg(triangles.len() as u32)
            .args_for_frame()
            .build()
            .map_err(|e| device.error("creating the trace_brute kernel", e))?;
        Ok(ClTracer {
            device,
            kernel,
            first_camera_arg: 2,
            bands: BandPlanner {
                rate: None,
                // About 16 million ray/triangle tests in the first launch.
                first_band_pixels: (1usize << 24) / triangles.len().max(1),
            },
            _triangles: tris,
            _nodes: None,
            status: None,
        })
    }

    /// Compiles the BVH kernel with a traversal stack as deep as the tree.
    pub fn compile_bvh(device: &'d ClDevice, depth: u32) -> Result<ocl::Program> {
        device.build(
            KernelSource::Bvh,
            &[("STACK_SIZE", depth.max(1).to_string())],
        )
    }

    /// Uploads the flat BVH for the BVH kernel.
    pub fn bvh(device: &'d ClDevice, program: &ocl::Program, bvh: &FlatBvh) -> Result<Self> {
        let nodes = upload(device, &bvh.nodes, "uploading BVH nodes")?;
        let tris = upload(device, &bvh.triangles, "uploading triangles")?;
        let status = ocl::Buffer::<u32>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_READ_WRITE)
            .len(1)
            .build()
            .map_err(|e| device.error("allocating the status flag", e))?;
        let kernel = ocl::Kernel::builder()
            .program(program)
            .name("trace_bvh")
            .queue(device.queue.clone())
            .arg(&nodes)
            .arg(&tris)
            .arg(&status)
            .args_for_frame()
            .build()
            .map_err(|e| device.error("creating the trace_bvh kernel", e))?;
        Ok(ClTracer {
            device,
            kernel,
            first_camera_arg: 3,
            bands: BandPlanner {
                rate: None,
                first_band_pixels: 1 << 16,
            },
            _triangles: tris,
            _nodes: Some(nodes),
            status: Some(status),
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

        let k = &self.kernel;
        let bands = &mut self.bands;
        let set = |i: u32, e: std::result::Result<(), ocl::Error>| {
            e.map_err(|e| device.error(&format!("setting kernel argument {i}"), e))
        };
        let f4 = |v: [f32; 4]| Float4::new(v[0], v[1], v[2], v[3]);
        let a = self.first_camera_arg;
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

        if let Some(status) = &self.status {
            status
                .write(&[0u32][..])
                .enq()
                .map_err(|e| device.error("clearing the status flag", e))?;
        }
        let local = local_size(device);
        let mut frame = Frame::new(width, height);
        let mut times = DeviceTimes::default();
        let mut bar: Option<ProgressBar> = None;
        let mut y0 = 0usize;
        while y0 < h {
            let rows = bands.next_rows(w, h - y0).min(band_capacity);
            // Work-items past the band (the global size is rounded up) return at once.
            set(a + 5, k.set_arg(a + 5, y0 as u32))?;
            set(a + 6, k.set_arg(a + 6, (y0 + rows) as u32))?;
            let global = [
                w.div_ceil(local[0]) * local[0],
                rows.div_ceil(local[1]) * local[1],
            ];
            let mut event = ocl::Event::empty();
            unsafe {
                k.cmd()
                    .global_work_offset([0, y0])
                    .global_work_size(global)
                    .local_work_size(local)
                    .enew(&mut event)
                    .enq()
                    .map_err(|e| device.error("launching the kernel", e))?;
            }
            event
                .wait_for()
                .map_err(|e| device.error("running the kernel", e.into()))?;
            let ms = event_ms(&event)
                .map_err(|e| device.error("reading the kernel's profiling times", e))?;
            times.kernel_ms += ms;
            times.launches += 1;
            bands.learn(rows * w, ms);

            let start = Instant::now();
            hits.read_rows(device, rows, &mut frame.hits[y0 * w..])?;
            colors.read_rows(device, rows, &mut frame.colors[y0 * w..])?;
            times.read_back_ms += start.elapsed().as_secs_f64() * 1e3;

            y0 += rows;
            if progress && bar.is_none() && y0 < h {
                // Show a bar only when the remaining work looks longer than a second.
                let remaining_ms = (h - y0) as f64 * w as f64 / bands.rate.unwrap_or(f64::INFINITY);
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
        if let Some(status) = &self.status {
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
        Ok((frame, times))
    }
}

/// Sets the kernel arguments every tracing kernel takes after its scene buffers, with
/// placeholders that `render` fills in.
trait FrameArgs {
    fn args_for_frame(&mut self) -> &mut Self;
}

impl FrameArgs for ocl::builders::KernelBuilder<'_> {
    fn args_for_frame(&mut self) -> &mut Self {
        self.arg(Float4::zero())
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
            .arg(0u32)
    }
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
