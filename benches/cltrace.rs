//! Criterion benchmarks of the stages: BVH build, CPU and OpenCL traversal, mesh loading.
//! Everything runs on generated meshes, so `cargo bench` needs nothing but an OpenCL driver
//! (without one, the OpenCL benchmark prints a notice and is left out).

use std::hint::black_box;
use std::io::Write;

use criterion::{Criterion, criterion_group, criterion_main};

use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Bvh};
use cltrace::camera::Camera;
use cltrace::device::tracer::ClTracer;
use cltrace::device::{ClDevice, DeviceSelector};
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::mesh::Mesh;
use cltrace::render::{Shade, ShadeParams, cpu};

fn hillside(triangles: u64) -> Mesh {
    Generator::Hillside {
        resolution: ((triangles as f64 / 2.0).sqrt().round()) as u32,
        seed: 1,
    }
    .generate()
    .unwrap()
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh build");
    group.sample_size(20);
    for (name, mesh) in [
        ("70k triangles (bunny-sized)", hillside(70_000)),
        ("1M triangles", hillside(1_000_000)),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| Bvh::build(black_box(&mesh), &BuildOptions::default()))
        });
    }
    group.finish();
}

fn scene() -> (Mesh, Bin32Bvh, Camera) {
    let mesh = hillside(70_000);
    let bvh = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let camera = Camera::bench(&mesh.bounds(), 512, 512).unwrap();
    (mesh, bvh, camera)
}

fn cpu_traversal(c: &mut Criterion) {
    let (mesh, bvh, camera) = scene();
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds());
    let mut group = c.benchmark_group("traversal");
    group.sample_size(10);
    group.bench_function("cpu-bvh, 512x512 primary, 70k triangles", |b| {
        b.iter(|| cpu::render(&bvh, &camera.pinhole(), 512, 512, &shade, None))
    });
    group.finish();
}

fn opencl_traversal(c: &mut Criterion) {
    let device = match DeviceSelector::from_flag_or_env(None).and_then(|s| ClDevice::select(&s)) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("notice: no OpenCL device ({e}); the OpenCL traversal benchmark is left out");
            return;
        }
    };
    let (mesh, bvh, camera) = scene();
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds());
    let program = ClTracer::compile_bvh(&device, bvh.depth).unwrap();
    let mut tracer = ClTracer::bvh(&device, &program, &bvh).unwrap();
    let mut group = c.benchmark_group("traversal");
    group.sample_size(10);
    group.bench_function(
        format!(
            "cl-bvh on {}, 512x512 primary, 70k triangles (wall)",
            device.info.name
        ),
        |b| {
            b.iter(|| {
                tracer
                    .render(&camera.pinhole(), 512, 512, &shade, false)
                    .unwrap()
            })
        },
    );
    group.finish();
}

fn loading(c: &mut Criterion) {
    let mesh = hillside(70_000);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hillside.obj");
    let mut text = String::new();
    for p in &mesh.positions {
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::File::create(&path)
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let mut group = c.benchmark_group("loading");
    group.sample_size(20);
    group.bench_function("OBJ, 70k triangles", |b| {
        b.iter(|| load_mesh(black_box(&path)).unwrap())
    });
    group.finish();
}

criterion_group!(benches, build, cpu_traversal, opencl_traversal, loading);
criterion_main!(benches);
