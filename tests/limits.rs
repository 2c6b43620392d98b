//! Device limits: a frame or accumulation image larger than what the device allocates at
//! once is rendered band by band and comes out the same; a scene larger than the device is
//! refused before upload, naming both of the device's numbers.

use std::sync::atomic::AtomicBool;

use crate::common::command::{cltrace, text};
use crate::common::*;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Bvh};
use cltrace::camera::Camera;
use cltrace::device::tracer::ClTracer;
use cltrace::input::generate::Generator;
use cltrace::render::integrator::{Accumulation, Lighting, SampleSettings};
use cltrace::render::{Shade, ShadeParams};

#[test]
fn images_larger_than_one_allocation_are_rendered_in_bands() {
    let mesh = generate(Generator::Sphere { subdivisions: 3 });
    let bvh = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let camera = Camera::bench(&mesh.bounds(), 96, 80).unwrap();
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds());
    let settings = SampleSettings {
        lighting: Lighting::Ao {
            samples: 4,
            distance: 0.5,
        },
        offset: 1e-4,
        seed: 9,
    };
    let device = device();
    let render = |budget: Option<u64>| {
        let program = every_kernel(&device, &bvh);
        let mut tracer = ClTracer::bvh(&device, &program, &bvh).unwrap();
        if let Some(bytes) = budget {
            tracer.limit_image_bytes(bytes);
        }
        let (frame, times) = tracer
            .render(&camera.pinhole(), 96, 80, &shade, false)
            .unwrap();
        let mut acc = Accumulation::new(96, 80);
        tracer
            .render_samples(
                &camera.pinhole(),
                &settings,
                0..3,
                &mut acc,
                &AtomicBool::new(false),
                &mut |_, _| {},
            )
            .unwrap();
        (frame, times.launches, acc)
    };
    let (whole, _, whole_acc) = render(None);
    // Images of at most a few rows at once, as on a device with a small largest allocation.
    let (banded, launches, banded_acc) = render(Some(4 * 1024));
    assert!(
        launches >= 10,
        "only {launches} launches: the bands were not small"
    );
    assert_eq!(whole.hits, banded.hits);
    assert_eq!(whole.colors, banded.colors);
    assert_eq!(whole_acc.pixels, banded_acc.pixels);
    // Counted in line band by band, and for the whole image with the first sample's counts
    // read on another queue into the buffer the last read-back reuses.
    assert_eq!(whole_acc.rays, banded_acc.rays);
}

/// A program of every kernel for `bvh`'s scene.
fn every_kernel(device: &cltrace::device::ClDevice, bvh: &Bin32Bvh) -> cltrace::device::Program {
    ClTracer::compile(
        device,
        Some((cltrace::bvh::Layout::Bin32, bvh.depth)),
        cltrace::device::Kernels::ALL,
    )
    .unwrap()
}

/// The rays a render reports while it samples: the first sample's count times the samples
/// done, once a thread has read that count back, and at the end every ray counted.
#[test]
fn progress_reports_the_first_sample_s_rays_then_all_of_them() {
    let mesh = generate(Generator::Sphere { subdivisions: 3 });
    let bvh = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let camera = Camera::bench(&mesh.bounds(), 160, 120).unwrap();
    let settings = SampleSettings {
        lighting: Lighting::Path { max_bounces: 3 },
        offset: 1e-4,
        seed: 5,
    };
    let device = device();
    let program = every_kernel(&device, &bvh);
    let mut tracer = ClTracer::bvh(&device, &program, &bvh).unwrap();
    let mut render = |samples: std::ops::Range<u32>| {
        let mut acc = Accumulation::new(160, 120);
        let mut reports = Vec::new();
        tracer
            .render_samples(
                &camera.pinhole(),
                &settings,
                samples,
                &mut acc,
                &AtomicBool::new(false),
                &mut |done, rays| reports.push((done, rays)),
            )
            .unwrap();
        (acc.rays, reports)
    };
    let (first, _) = render(0..1);
    let (all, reports) = render(0..24);
    assert!(all > 24 * 160 * 120, "{all} rays for paths of one to four");
    assert_eq!(reports.last(), Some(&(24, Some(all))));
    for &(done, rays) in &reports[..reports.len() - 1] {
        if let Some(rays) = rays {
            assert_eq!(rays, first * done as u64, "after {done} samples");
        }
    }
}

/// Buffers larger than the staging buffer (64 MB) go to the device in pinned chunks: a
/// hillside of 1.6 million triangles (78 MB of them) traces as the host does, hit for hit.
#[test]
fn scenes_larger_than_the_staging_buffer_upload_whole() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("hill.toml");
    let mesh = "[[mesh]]\ngenerator = { kind = \"hillside\", resolution = 900 }\n";
    std::fs::write(&scene, mesh).unwrap();
    let hits = |method: &str| {
        let file = dir.path().join(format!("{method}.bin"));
        let mut cmd = cltrace();
        cmd.arg("render")
            .arg(&scene)
            .args([
                "--method",
                method,
                "--shade",
                "depth",
                "--crease-angle",
                "0",
                "-q",
            ])
            .args(["--width", "96", "--height", "72", "-o"])
            .arg(dir.path().join(format!("{method}.png")))
            .arg("--hits")
            .arg(&file);
        crate::common::command::succeeded(&crate::common::command::run(cmd));
        std::fs::read(file).unwrap()
    };
    let host = hits("cpu-bvh");
    assert!(
        host.chunks(8).any(|h| h[..4] != [0xff; 4]),
        "the hillside is seen"
    );
    assert_eq!(hits("cl-bvh"), host);
}

#[test]
fn a_scene_larger_than_the_device_is_refused_before_upload() {
    let mesh = generate(Generator::Sphere { subdivisions: 4 });
    let bvh = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let mut device = device();
    device.info.max_allocation = 64 * 1024;
    device.info.global_memory = 1 << 30;
    let program = ClTracer::compile_bvh(&device, bvh.depth).unwrap();
    let err = ClTracer::bvh(&device, &program, &bvh)
        .err()
        .expect("refused");
    let msg = err.to_string();
    assert!(
        msg.contains("1024 MiB of global memory") && msg.contains("at most 1 MiB at once"),
        "{msg}"
    );
    assert_eq!(err.exit_code(), 1);
    device.info.max_allocation = 1 << 30;
    device.info.global_memory = 1 << 20;
    let msg = ClTracer::bvh(&device, &program, &bvh)
        .err()
        .expect("refused")
        .to_string();
    assert!(msg.contains("1 MiB of global memory"), "{msg}");
}

/// Without `--fallback` a missing device is the run's error (exit 1, no file); with
/// `--fallback cpu` the render happens on the host and says so.
#[test]
fn fallback_to_the_cpu_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.png");
    let run = |extra: &[&str]| {
        cltrace()
            .args([
                "render", "--device", "9:9", "--width", "16", "--height", "12", "-o",
            ])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let failed = run(&[]);
    assert_eq!(failed.status.code(), Some(1));
    assert!(!out.exists());
    let fell_back = run(&["--fallback", "cpu"]);
    let stderr = text(&fell_back.stderr);
    assert!(fell_back.status.success(), "{stderr}");
    assert!(
        stderr.contains("rendering with cpu-bvh instead"),
        "{stderr}"
    );
    assert_eq!(image::open(&out).unwrap().width(), 16);
}

/// A kernel that does not compile is an error carrying the device's build log.
#[test]
fn a_failed_kernel_build_shows_the_build_log() {
    let device = device();
    let Err(err) = device.build_source(
        "broken.cl",
        "__kernel void k(__global float* x) { x[0] = undefined_name; }",
        "",
    ) else {
        panic!("the build should fail");
    };
    let msg = err.to_string();
    assert!(
        msg.starts_with("kernel broken.cl failed to build on"),
        "{msg}"
    );
    assert!(
        msg.contains("build log:") && msg.contains("undefined_name"),
        "{msg}"
    );
    assert_eq!(err.exit_code(), 1);
}
