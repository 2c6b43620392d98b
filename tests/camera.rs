//! The camera for people: the auto view fits every corner of the mesh's box inside the
//! image with a margin and keeps the eye outside the box; the bench view is the benchmark
//! protocol's, unchanged; the kernels' orthographic and thin-lens rays are the host's bit
//! for bit; an aperture of 0 is the pinhole; a point in focus stays sharp; and impossible
//! cameras are one-line errors.

use std::sync::atomic::AtomicBool;

use crate::common::command::cltrace;
use crate::common::tracers::DeviceTracer;
use crate::common::*;
use cltrace::bvh::{BuildOptions, Layout};
use cltrace::camera::{Camera, CameraSettings, Pinhole, Projection, View};
use cltrace::device::ClDevice;
use cltrace::geometry::{Aabb, Ray};
use cltrace::input::generate::Generator;
use cltrace::intersect::triangles_in_order;
use cltrace::material::{Material, Materials};
use cltrace::mesh::Mesh;
use cltrace::render::integrator::{Accumulation, Light, Lighting, SampleSettings, sample_ray};
use cltrace::render::{Method, Shade, ShadeParams, cpu};
use cltrace::renderer::{PrepareOptions, Renderer};
use cltrace::report::Timings;
use glam::{DVec3, Vec3};

fn settings(width: u32, height: u32) -> CameraSettings {
    CameraSettings {
        width: Some(width),
        height: Some(height),
        ..Default::default()
    }
}

fn boxed(min: [f32; 3], max: [f32; 3]) -> Aabb {
    Aabb::from_points([Vec3::from(min), Vec3::from(max)])
}

fn corners(b: &Aabb) -> Vec<Vec3> {
    (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            )
        })
        .collect()
}

/// Where `p` lands in `camera`'s image, in [-1, 1] from edge to edge on both axes (y up),
/// and its depth along the view.
fn project(camera: &Camera, p: Vec3) -> (f64, f64, f64) {
    let eye = camera.eye().as_dvec3();
    let forward = (camera.look_at().as_dvec3() - eye).normalize();
    let right = forward.cross(camera.up().as_dvec3()).normalize();
    let up = right.cross(forward);
    let q = p.as_dvec3() - eye;
    let depth = q.dot(forward);
    let half_h = ((camera.fov() as f64).to_radians() * 0.5).tan();
    let half_w = half_h * camera.width as f64 / camera.height as f64;
    (
        q.dot(right) / depth / half_w,
        q.dot(up) / depth / half_h,
        depth,
    )
}

fn inside(b: &Aabb, p: Vec3) -> bool {
    (0..3).all(|k| p[k] >= b.min[k] && p[k] <= b.max[k])
}

#[test]
fn the_auto_view_fits_every_corner_with_a_margin_and_keeps_the_eye_outside() {
    let shapes = [
        (
            "flat landscape",
            boxed([-50.0, 0.0, -50.0], [50.0, 2.0, 50.0]),
        ),
        ("tall thin box", boxed([-0.1, 0.0, -0.1], [0.1, 10.0, 0.1])),
        ("cube", boxed([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0])),
        ("long rod", boxed([0.0, 0.0, 0.0], [100.0, 1.0, 1.0])),
        (
            "far from the origin",
            boxed([1e4, 1e4, 1e4], [1e4 + 1.0, 1e4 + 3.0, 1e4 + 2.0]),
        ),
    ];
    for (name, b) in shapes {
        for (w, h) in [(1280, 720), (400, 800), (64, 64)] {
            for fov in [None, Some(20.0), Some(90.0)] {
                let s = CameraSettings {
                    fov,
                    ..settings(w, h)
                };
                let c = Camera::from_settings(&s, &b).unwrap();
                let what = format!("{name}, {w}x{h}, fov {fov:?}: eye {:?}", c.eye());
                assert!(!inside(&b, c.eye()), "{what}: the eye is inside the box");
                assert_eq!(c.look_at(), b.center(), "{what}");
                let (mut widest, mut tallest) = (0.0f64, 0.0f64);
                for p in corners(&b) {
                    let (x, y, depth) = project(&c, p);
                    assert!(depth > 0.0, "{what}: corner {p:?} behind the eye");
                    widest = widest.max(x.abs());
                    tallest = tallest.max(y.abs());
                }
                // Inside the image less the margin, and fitted: one axis reaches it.
                assert!(
                    widest <= 0.951 && tallest <= 0.951,
                    "{what}: {widest} {tallest}"
                );
                assert!(
                    widest.max(tallest) > 0.94,
                    "{what}: not fitted ({widest}, {tallest})"
                );
                // From the front-right and above.
                let back = (c.eye() - c.look_at()).normalize();
                assert!(
                    back.x > 0.3 && back.y > 0.3 && back.z > 0.3,
                    "{what}: {back:?}"
                );
            }
        }
    }
}

#[test]
fn the_auto_view_of_a_flat_scene_sees_it_from_above_not_edge_on() {
    // The bench view of a landscape is a sliver; the auto view's projected box fills the
    // image's height far better.
    let b = boxed([-50.0, 0.0, -50.0], [50.0, 2.0, 50.0]);
    let tall = |c: &Camera| {
        let ys: Vec<f64> = corners(&b).iter().map(|&p| project(c, p).1).collect();
        ys.iter().cloned().fold(f64::MIN, f64::max) - ys.iter().cloned().fold(f64::MAX, f64::min)
    };
    let auto = Camera::from_settings(&settings(1280, 720), &b).unwrap();
    let bench = Camera::bench(&b, 1280, 720).unwrap();
    assert!(tall(&auto) > 1.0, "auto: {}", tall(&auto));
    assert!(tall(&bench) < 0.1, "bench: {}", tall(&bench));
}

#[test]
fn the_bench_view_is_the_benchmark_protocols() {
    let b = boxed([0.0, 2.0, -1.0], [2.0, 4.0, 5.0]);
    let r = b.extent().length() * 0.5;
    let expected = b.center() + Vec3::new(0.0, 0.0, r / (45f32.to_radians() * 0.5).sin());
    let by_name = Camera::from_settings(
        &CameraSettings {
            view: Some(View::Bench),
            ..settings(640, 480)
        },
        &b,
    )
    .unwrap();
    let bench = Camera::bench(&b, 640, 480).unwrap();
    assert_eq!(bench, by_name);
    // Bit for bit the f32 formula it always was.
    assert_eq!(bench.eye(), expected);
    assert_eq!(bench.look_at(), b.center());
    assert_eq!(bench.up(), Vec3::Y);
    assert_eq!(bench.fov(), 45.0);
    assert_eq!(bench.projection(), Projection::Perspective);
    assert_eq!(bench.aperture(), 0.0);
}

#[test]
fn given_keys_override_the_auto_view() {
    let b = boxed([-1.0; 3], [1.0; 3]);
    let c = Camera::from_settings(
        &CameraSettings {
            look_at: Some([0.5, 0.0, 0.0]),
            ..settings(64, 48)
        },
        &b,
    )
    .unwrap();
    assert_eq!(c.look_at(), Vec3::new(0.5, 0.0, 0.0));
    assert!(!inside(&b, c.eye()));
    for p in corners(&b) {
        let (x, y, _) = project(&c, p);
        assert!(x.abs() <= 0.951 && y.abs() <= 0.951);
    }
    let c = Camera::from_settings(
        &CameraSettings {
            eye: Some([0.0, 0.0, 9.0]),
            ..settings(64, 48)
        },
        &b,
    )
    .unwrap();
    assert_eq!(
        (c.eye(), c.look_at()),
        (Vec3::new(0.0, 0.0, 9.0), Vec3::ZERO)
    );
    // A z-up scene seen with up = +z: still from above, the eye outside.
    let c = Camera::from_settings(
        &CameraSettings {
            up: Some([0.0, 0.0, 1.0]),
            ..settings(64, 48)
        },
        &boxed([-5.0, -5.0, 0.0], [5.0, 5.0, 1.0]),
    )
    .unwrap();
    assert!(c.eye().z > 1.0, "{:?}", c.eye());
}

/// The rays the probe kernel computes for `pinhole`: per pixel, the primary ray and the
/// ray of sample `sample` of the progressive modes.
fn kernel_rays(
    device: &ClDevice,
    pinhole: &Pinhole,
    (w, h): (u32, u32),
    seed: u32,
    sample: u32,
) -> Vec<(Ray, Ray)> {
    let program = device.compile_probe().unwrap();
    let cam: &[f32] = bytemuck::cast_slice(std::slice::from_ref(pinhole));
    let cam: Vec<ocl::prm::Float4> = cam
        .chunks(4)
        .map(|c| ocl::prm::Float4::new(c[0], c[1], c[2], c[3]))
        .collect();
    let cam_buf = ocl::Buffer::<ocl::prm::Float4>::builder()
        .queue(device.queue.clone())
        .len(cam.len())
        .copy_host_slice(&cam)
        .build()
        .unwrap();
    let n = (w * h) as usize * 4;
    let out = ocl::Buffer::<ocl::prm::Float4>::builder()
        .queue(device.queue.clone())
        .len(n)
        .build()
        .unwrap();
    let kernel = ocl::Kernel::builder()
        .program(&program)
        .name("probe_camera_rays")
        .queue(device.queue.clone())
        .global_work_size((w as usize, h as usize))
        .arg(&cam_buf)
        .arg(w)
        .arg(h)
        .arg(seed)
        .arg(sample)
        .arg(&out)
        .build()
        .unwrap();
    unsafe { kernel.enq().unwrap() };
    let mut v = vec![ocl::prm::Float4::new(0.0, 0.0, 0.0, 0.0); n];
    out.read(&mut v).enq().unwrap();
    let v3 = |f: ocl::prm::Float4| Vec3::new(f[0], f[1], f[2]);
    v.chunks(4)
        .map(|c| (Ray::new(v3(c[0]), v3(c[1])), Ray::new(v3(c[2]), v3(c[3]))))
        .collect()
}

fn cameras() -> Vec<(&'static str, CameraSettings)> {
    let base = settings(23, 17);
    vec![
        ("perspective pinhole", base),
        (
            "orthographic",
            CameraSettings {
                projection: Some(Projection::Orthographic),
                ..base
            },
        ),
        (
            "perspective thin lens",
            CameraSettings {
                aperture: Some(0.3),
                focus_distance: Some(2.5),
                ..base
            },
        ),
        (
            "orthographic thin lens",
            CameraSettings {
                projection: Some(Projection::Orthographic),
                ortho_height: Some(3.0),
                aperture: Some(0.2),
                focus_on: Some([0.0, 0.0, 0.0]),
                ..base
            },
        ),
    ]
}

fn same_bits(a: &Ray, b: &Ray) -> bool {
    let bits = |r: &Ray| {
        let (o, d) = (r.origin.to_array(), r.dir.to_array());
        [o[0], o[1], o[2], d[0], d[1], d[2]].map(f32::to_bits)
    };
    bits(a) == bits(b)
}

#[test]
fn the_kernels_camera_rays_are_the_hosts_bit_for_bit() {
    let b = boxed([-1.0, -0.5, -1.0], [1.0, 0.5, 1.0]);
    on_every_device(|device| {
        for (name, s) in cameras() {
            let camera = Camera::from_settings(&s, &b).unwrap();
            let pinhole = camera.pinhole();
            let (w, h) = (camera.width, camera.height);
            for sample in [0, 7] {
                let rays = kernel_rays(device, &pinhole, (w, h), 5, sample);
                for y in 0..h {
                    for x in 0..w {
                        let (primary, sampled) = &rays[(y * w + x) as usize];
                        let host = pinhole.ray(x, y);
                        assert!(
                            same_bits(primary, &host),
                            "{name}: pixel ({x}, {y}): kernel {primary:?}, host {host:?}"
                        );
                        let host = sample_ray(&pinhole, (x, y, w), 5, sample);
                        assert!(
                            same_bits(sampled, &host),
                            "{name}: pixel ({x}, {y}) sample {sample}: kernel {sampled:?}, \
                             host {host:?}"
                        );
                    }
                }
            }
        }
    });
}

#[test]
fn an_aperture_of_zero_is_the_pinhole_exactly() {
    let b = boxed([-1.0; 3], [1.0; 3]);
    let pinhole = Camera::from_settings(&settings(16, 9), &b)
        .unwrap()
        .pinhole();
    let closed = Camera::from_settings(
        &CameraSettings {
            aperture: Some(0.0),
            focus_distance: Some(3.0),
            ..settings(16, 9)
        },
        &b,
    )
    .unwrap()
    .pinhole();
    assert_eq!(pinhole, closed);
    assert!(!closed.has_lens());
    for (x, y) in [(0, 0), (15, 8), (7, 4)] {
        for sample in 0..4 {
            let a = sample_ray(&pinhole, (x, y, 16), 1, sample);
            // What the pinhole's jittered ray always was: eye, p0 + fx du + fy dv.
            let j = pinhole.ray_at(
                x as f32 + sampler_number(1, y * 16 + x, sample, 0),
                y as f32 + sampler_number(1, y * 16 + x, sample, 1),
            );
            assert!(same_bits(&a, &j), "{a:?} {j:?}");
            assert!(same_bits(&a, &sample_ray(&closed, (x, y, 16), 1, sample)));
        }
    }
}

/// Dimension `dim` of the random stream of (seed, pixel, sample), as src/render/sampling.rs
/// draws it.
fn sampler_number(seed: u32, pixel: u32, sample: u32, dim: u32) -> f32 {
    let hash = |mut x: u32| {
        x ^= x >> 16;
        x = x.wrapping_mul(0x7feb_352d);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846c_a68b);
        x ^= x >> 16;
        x
    };
    let key = hash(hash(hash(seed ^ 0x9e37_79b9) ^ pixel) ^ sample);
    (hash(key ^ dim.wrapping_mul(0x85eb_ca6b)) >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[test]
fn every_lens_sample_through_a_point_meets_at_the_focus_plane() {
    let b = boxed([-1.0; 3], [1.0; 3]);
    for (name, s) in cameras().into_iter().filter(|(n, _)| n.contains("lens")) {
        let camera = Camera::from_settings(&s, &b).unwrap();
        let p = camera.pinhole();
        let eye = camera.eye().as_dvec3();
        let forward = (camera.look_at().as_dvec3() - eye).normalize();
        let focus = camera.focus_distance() as f64;
        let at_focus = |r: &Ray| {
            let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
            let t = (focus - (o - eye).dot(forward)) / d.dot(forward);
            o + d * t
        };
        let (fx, fy) = (5.25, 11.5);
        let sharp = at_focus(&p.ray_at(fx, fy));
        let mut spread = 0.0f64;
        let mut origins: Vec<DVec3> = Vec::new();
        for i in 0..64 {
            let u = (sampler_number(9, i, 0, 0) * 2.0 - 1.0) * 0.7;
            let v = (sampler_number(9, i, 0, 1) * 2.0 - 1.0) * 0.7;
            let r = p.lens_ray(fx, fy, (u, v));
            spread = spread.max((at_focus(&r) - sharp).length());
            origins.push(r.origin.as_dvec3());
        }
        assert!(spread < 1e-5 * focus, "{name}: rays meet within {spread}");
        // And they do leave the lens at different points, within its radius.
        let r = camera.aperture() as f64 * 0.5;
        let base = p.ray_at(fx, fy).origin.as_dvec3();
        assert!(origins.iter().all(|o| (*o - base).length() <= r * 1.0001));
        assert!(origins.iter().any(|o| (*o - base).length() > 0.3 * r));
    }
    // focus_on: the focus distance is the point's depth along the view.
    let c = Camera::from_settings(
        &CameraSettings {
            eye: Some([0.0, 0.0, 5.0]),
            look_at: Some([0.0, 0.0, 0.0]),
            aperture: Some(0.1),
            focus_on: Some([3.0, 1.0, 1.0]),
            ..settings(8, 8)
        },
        &b,
    )
    .unwrap();
    assert_eq!(c.focus_distance(), 4.0);
    // Without a focus key, the look-at point is in focus.
    let c = Camera::from_settings(
        &CameraSettings {
            aperture: Some(0.1),
            ..settings(8, 8)
        },
        &b,
    )
    .unwrap();
    assert!((c.focus_distance() - (c.look_at() - c.eye()).length()).abs() < 1e-6);
}

#[test]
fn orthographic_rays_are_parallel_and_span_the_height() {
    let b = boxed([-2.0, -1.0, -3.0], [2.0, 1.0, 3.0]);
    let c = Camera::from_settings(
        &CameraSettings {
            projection: Some(Projection::Orthographic),
            ortho_height: Some(4.0),
            eye: Some([0.0, 0.0, 10.0]),
            look_at: Some([0.0, 0.0, 0.0]),
            ..settings(20, 10)
        },
        &b,
    )
    .unwrap();
    let p = c.pinhole();
    let (top_left, bottom_right) = (p.ray_at(0.0, 0.0), p.ray_at(20.0, 10.0));
    assert_eq!(top_left.dir, Vec3::NEG_Z);
    assert_eq!(bottom_right.dir, Vec3::NEG_Z);
    assert!((top_left.origin - Vec3::new(-4.0, 2.0, 10.0)).length() < 1e-5);
    assert!((bottom_right.origin - Vec3::new(4.0, -2.0, 10.0)).length() < 1e-5);
    // Fitted: every corner inside, with the margin, on both axes.
    let fitted = Camera::from_settings(
        &CameraSettings {
            projection: Some(Projection::Orthographic),
            ..settings(20, 10)
        },
        &b,
    )
    .unwrap();
    assert!(!inside(&b, fitted.eye()));
    let p = fitted.pinhole();
    let forward = (fitted.look_at() - fitted.eye()).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let (half_h, half_w) = (fitted.ortho_height() * 0.5, fitted.ortho_height());
    let mut reach = 0.0f32;
    for q in corners(&b) {
        let q = q - fitted.eye();
        let (x, y) = (q.dot(right) / half_w, q.dot(up) / half_h);
        assert!(x.abs() <= 0.951 && y.abs() <= 0.951, "{x} {y}");
        reach = reach.max(x.abs()).max(y.abs());
        assert!(q.dot(forward) > 0.0);
    }
    assert!(reach > 0.94, "{reach}");
    assert!(p.ray(10, 5).dir.dot(forward) > 0.9999);
}

#[test]
fn orthographic_frames_from_the_kernels_match_the_host() {
    let mesh = generate(Generator::Sphereflake {
        levels: 1,
        subdivisions: 1,
        ground: 8,
    });
    let camera = Camera::from_settings(
        &CameraSettings {
            projection: Some(Projection::Orthographic),
            ..settings(48, 36)
        },
        &mesh.bounds(),
    )
    .unwrap();
    let shade = ShadeParams::new(Shade::Lambert, &camera, &mesh.bounds());
    let tris = triangles_in_order(&mesh, 0..mesh.triangle_count() as u32);
    let reference = cpu::render(
        &cltrace::brute::BruteForce {
            triangles: tris.clone(),
        },
        &camera.pinhole(),
        48,
        36,
        &shade,
        None,
    );
    assert!(coverage(&reference) > 48 * 36 / 4);
    on_every_device(|device| {
        for tracer in [DeviceTracer::Brute, DeviceTracer::Bvh(Layout::default())] {
            let mut cl = tracer.prepare(device, &mesh, &BuildOptions::default());
            let frame = cl
                .render(&camera.pinhole(), 48, 36, &shade, false)
                .unwrap()
                .0;
            if let Err(e) = compare_frames(&reference, &frame, &camera.pinhole(), &tris) {
                panic!("{}: {e}", tracer.name());
            }
        }
    });
}

fn shadow_samples(
    method: Method,
    device: Option<&ClDevice>,
    mesh: &Mesh,
    camera: &Camera,
) -> Accumulation {
    let materials = Materials::uniform(Material::diffuse([0.8, 0.6, 0.4]));
    let options = PrepareOptions {
        build: BuildOptions::default(),
        layout: Some(Layout::default()),
        work_group: None,
        kernels: cltrace::device::Kernels::ALL,
        crease_angle: None,
        two_sided_lights: false,
        lights: Default::default(),
    };
    let mut renderer = Renderer::prepare(
        method,
        mesh,
        &materials,
        &options,
        device,
        &mut Timings::default(),
    )
    .unwrap();
    let settings = SampleSettings {
        lighting: Lighting::Shadow {
            light: Light::Directional(Vec3::new(0.3, 1.0, 0.5).normalize()),
        },
        offset: 1e-4 * mesh.bounds().extent().length(),
        seed: 3,
    };
    let mut acc = Accumulation::new(camera.width, camera.height);
    renderer
        .render_samples(
            camera,
            &settings,
            0..4,
            &mut acc,
            &AtomicBool::new(false),
            false,
        )
        .unwrap();
    acc
}

#[test]
fn thin_lens_samples_from_the_kernels_match_the_host() {
    let mesh = generate(Generator::Sphereflake {
        levels: 1,
        subdivisions: 1,
        ground: 8,
    });
    for (name, s) in cameras().into_iter().filter(|(n, _)| n.contains("lens")) {
        let s = CameraSettings {
            aperture: Some(0.3 * mesh.bounds().extent().length()),
            focus_distance: None,
            focus_on: None,
            ..s
        };
        let camera = Camera::from_settings(
            &CameraSettings {
                ortho_height: None,
                ..s
            },
            &mesh.bounds(),
        )
        .unwrap();
        let host = shadow_samples(Method::CpuBvh, None, &mesh, &camera).radiance();
        on_every_device(|device| {
            let dev = shadow_samples(Method::ClBvh, Some(device), &mesh, &camera).radiance();
            // The same rays hit the same triangles; the shading may differ by the device's
            // normalize in the last bits. Pixels on an edge may tie.
            let close = |a: &[f32; 3], b: &[f32; 3]| (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-4);
            let differing = host.iter().zip(&dev).filter(|(a, b)| !close(a, b)).count();
            assert!(
                differing <= host.len() / 100,
                "{name}: {differing} of {} pixels differ",
                host.len()
            );
        });
    }
}

/// Runs `cltrace render` on a small cube with `args`; returns (exit code, stderr).
fn render(args: &[&str]) -> (Option<i32>, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let out = cltrace()
        .args([
            "render", "--width", "16", "--height", "12", "--method", "cpu-bvh",
        ])
        .args(args)
        .arg("-o")
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        dir,
    )
}

#[test]
fn impossible_cameras_exit_2_with_one_line() {
    for args in [
        vec!["--aperture", "-1"],
        vec!["--aperture", "nan"],
        vec!["--aperture", "0.1", "--focus-distance", "0"],
        vec!["--aperture", "0.1", "--focus-distance", "-2"],
        vec!["--projection", "orthographic", "--ortho-height", "0"],
        vec!["--eye", "1,2,3", "--look-at", "1,2,3"],
        vec!["--up", "0,0,0"],
        vec![
            "--eye",
            "0,0,5",
            "--look-at",
            "0,0,0",
            "--focus-on",
            "0,0,9",
        ],
    ] {
        let (code, stderr, dir) = render(&args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error:"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "{args:?}"
        );
    }
}

#[test]
fn the_camera_flags_render() {
    for args in [
        vec!["--camera", "bench"],
        vec!["--camera", "auto", "--projection", "orthographic"],
        vec!["--shade", "ao", "--spp", "2", "--aperture", "0.2"],
        vec![
            "--shade",
            "ao",
            "--spp",
            "2",
            "--aperture",
            "0.2",
            "--focus-on",
            "0,0,0",
        ],
    ] {
        let (code, stderr, dir) = render(&args);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
        assert!(!stderr.contains("warning:"), "{args:?}: {stderr}");
        assert!(dir.path().join("x.png").exists());
    }
    // A lens in a single-hit mode renders the pinhole's image and says so, once.
    let (code, stderr, _dir) = render(&["--shade", "lambert", "--aperture", "0.2"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(stderr.matches("warning:").count(), 1, "{stderr}");
    assert!(stderr.contains("progressive"), "{stderr}");
}
