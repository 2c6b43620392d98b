//! The OpenCL kernels (brute force and BVH) against the CPU brute-force reference: the same
//! triangle on every pixel, differing only by ties, on generated scenes seen from outside,
//! inside and at grazing angles, and on the shared real meshes when they are present.

mod common;

use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Builder, Bvh};
use cltrace::camera::Camera;
use cltrace::camera::CameraSettings;
use cltrace::device::ClDevice;
use cltrace::device::tracer::ClTracer;
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::intersect::triangles_in_order;
use cltrace::mesh::Mesh;
use cltrace::render::{Frame, Shade, ShadeParams, cpu};
use common::*;

struct Case {
    name: String,
    mesh: Mesh,
    camera: Camera,
}

fn case(name: &str, mesh: Mesh, settings: CameraSettings) -> Case {
    let camera = Camera::from_settings(&settings, &mesh.bounds()).unwrap();
    Case {
        name: name.to_string(),
        mesh,
        camera,
    }
}

fn small(width: u32, height: u32) -> CameraSettings {
    CameraSettings {
        width: Some(width),
        height: Some(height),
        ..Default::default()
    }
}

fn cases() -> Vec<Case> {
    let soup = |triangles, seed| generate(Generator::Soup { triangles, seed });
    vec![
        case("soup of 2000", soup(2000, 1), small(64, 48)),
        case("soup of 300, odd size", soup(300, 7), small(37, 23)),
        case("cube", generate(Generator::Cube {}), small(48, 48)),
        case(
            "cube edge-on",
            generate(Generator::Cube {}),
            CameraSettings {
                eye: Some([0.0, 0.0, 4.0]),
                look_at: Some([0.0, 0.0, 0.0]),
                ..small(49, 49)
            },
        ),
        case(
            "sphere",
            generate(Generator::Sphere { subdivisions: 3 }),
            small(64, 64),
        ),
        case(
            "inside a sphere",
            generate(Generator::Sphere { subdivisions: 2 }),
            CameraSettings {
                eye: Some([0.1, 0.2, 0.3]),
                look_at: Some([1.0, 0.0, 0.0]),
                fov: Some(120.0),
                ..small(48, 32)
            },
        ),
        case(
            "nested boxes",
            generate(Generator::NestedBoxes { count: 6 }),
            small(48, 40),
        ),
        case(
            "inside nested boxes",
            generate(Generator::NestedBoxes { count: 6 }),
            CameraSettings {
                eye: Some([0.05, 0.02, 0.01]),
                look_at: Some([0.0, 0.0, -1.0]),
                fov: Some(100.0),
                ..small(40, 40)
            },
        ),
        case(
            "landscape at a grazing angle",
            generate(Generator::Landscape {
                resolution: 24,
                seed: 3,
            }),
            CameraSettings {
                eye: Some([-1.5, 0.2, -1.5]),
                look_at: Some([1.0, 0.0, 1.0]),
                ..small(64, 32)
            },
        ),
        case(
            "small sphereflake",
            generate(Generator::Sphereflake {
                levels: 1,
                subdivisions: 1,
                ground: 8,
            }),
            small(48, 36),
        ),
    ]
}

fn reference(c: &Case) -> Frame {
    let tracer = cltrace::brute::BruteForce {
        triangles: triangles_in_order(&c.mesh, 0..c.mesh.triangle_count() as u32),
    };
    let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
    cpu::render(
        &tracer,
        &c.camera.pinhole(),
        c.camera.width,
        c.camera.height,
        &shade,
        None,
    )
}

fn cl_brute(device: &ClDevice, c: &Case) -> Frame {
    let program = ClTracer::compile_brute(device).unwrap();
    let tris = triangles_in_order(&c.mesh, 0..c.mesh.triangle_count() as u32);
    let mut tracer = ClTracer::brute(device, &program, &tris).unwrap();
    let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
    tracer
        .render(
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &shade,
            false,
        )
        .unwrap()
        .0
}

fn cl_bvh(device: &ClDevice, c: &Case, options: &BuildOptions) -> Frame {
    let bvh = Bin32Bvh::new(Bvh::build(&c.mesh, options), &c.mesh);
    let program = ClTracer::compile_bvh(device, bvh.depth).unwrap();
    let mut tracer = ClTracer::bvh(device, &program, &bvh).unwrap();
    let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
    tracer
        .render(
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &shade,
            false,
        )
        .unwrap()
        .0
}

fn check(c: &Case, what: &str, reference: &Frame, frame: &Frame) {
    let tris = triangles_in_order(&c.mesh, 0..c.mesh.triangle_count() as u32);
    match compare_frames(reference, frame, &c.camera.pinhole(), &tris) {
        Ok(ties) => eprintln!("{}: {what} matches ({ties} ties)", c.name),
        Err(e) => panic!("{}: {what} differs from the CPU reference: {e}", c.name),
    }
}

#[test]
fn opencl_brute_force_matches_the_cpu_reference() {
    let device = device();
    for c in cases() {
        let reference = reference(&c);
        assert!(
            coverage(&reference) > 0,
            "{}: the camera sees nothing",
            c.name
        );
        check(&c, "cl-brute", &reference, &cl_brute(&device, &c));
    }
}

#[test]
fn opencl_bvh_matches_the_cpu_reference() {
    let device = device();
    let sweep = BuildOptions {
        builder: Builder::Sweep,
        ..Default::default()
    };
    let one_per_leaf = BuildOptions {
        max_leaf_size: 1,
        bins: 16,
        ..Default::default()
    };
    for c in cases() {
        let reference = reference(&c);
        check(
            &c,
            "cl-bvh (binned)",
            &reference,
            &cl_bvh(&device, &c, &BuildOptions::default()),
        );
        check(
            &c,
            "cl-bvh (sweep, leaves of one)",
            &reference,
            &cl_bvh(&device, &c, &sweep),
        );
        check(
            &c,
            "cl-bvh (16 bins, leaves of one)",
            &reference,
            &cl_bvh(&device, &c, &one_per_leaf),
        );
    }
}

#[test]
fn every_layout_matches_the_cpu_reference() {
    use cltrace::bvh::{DeviceLayout, Layout};
    let device = device();
    for c in cases() {
        let reference = reference(&c);
        let bvh = Bvh::build(&c.mesh, &BuildOptions::default());
        let sah = bvh.stats().sah_cost;
        let flat = Bin32Bvh::new(bvh, &c.mesh);
        for layout in Layout::ALL {
            let laid = DeviceLayout::new(flat.clone(), layout, sah);
            let program =
                ClTracer::compile(&device, Some((layout, laid.stack_size)), false).unwrap();
            let mut tracer = ClTracer::with_layout(&device, &program, &laid).unwrap();
            let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
            let (frame, _) = tracer
                .render(
                    &c.camera.pinhole(),
                    c.camera.width,
                    c.camera.height,
                    &shade,
                    false,
                )
                .unwrap();
            check(
                &c,
                &format!("cl-bvh ({})", layout.name()),
                &reference,
                &frame,
            );
        }
    }
}

#[test]
fn cpu_bvh_matches_the_cpu_reference() {
    for c in cases() {
        let reference = reference(&c);
        let bvh = Bin32Bvh::new(Bvh::build(&c.mesh, &BuildOptions::default()), &c.mesh);
        let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
        let frame = cpu::render(
            &bvh,
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &shade,
            None,
        );
        check(&c, "cpu-bvh", &reference, &frame);
    }
}

#[test]
fn pixels_and_colours_agree_between_kernels_and_host() {
    // Beyond the hit records, the shaded colours of the three shade modes agree to within
    // one step of 8-bit rounding (the device's sqrt and division may differ in the last bit).
    let device = device();
    let c = &cases()[4];
    for shade in [Shade::Normal, Shade::Depth, Shade::Lambert] {
        let params = ShadeParams::new(shade, &c.camera, &c.mesh.bounds());
        let tris = triangles_in_order(&c.mesh, 0..c.mesh.triangle_count() as u32);
        let host = cpu::render(
            &cltrace::brute::BruteForce {
                triangles: tris.clone(),
            },
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &params,
            None,
        );
        let program = ClTracer::compile_brute(&device).unwrap();
        let mut tracer = ClTracer::brute(&device, &program, &tris).unwrap();
        let (frame, _) = tracer
            .render(
                &c.camera.pinhole(),
                c.camera.width,
                c.camera.height,
                &params,
                false,
            )
            .unwrap();
        for (i, (a, b)) in host.colors.iter().zip(&frame.colors).enumerate() {
            let (a, b) = (a.to_le_bytes(), b.to_le_bytes());
            let worst = a.iter().zip(b).map(|(x, y)| x.abs_diff(y)).max().unwrap();
            assert!(
                worst <= 1,
                "{shade:?}: pixel {i} is {a:?} on the host, {b:?} on the device"
            );
        }
    }
}

/// The real meshes, when present: the BVH kernel against the CPU brute force.
#[test]
fn opencl_bvh_matches_on_the_bunny_and_the_teapot() {
    let device = device();
    for (name, size) in [("stanford_bunny.obj", 96), ("utah_teapot.obj", 128)] {
        let Some(path) = shared_scene(name) else {
            continue;
        };
        let mesh = load_mesh(&path).unwrap();
        let c = Case {
            name: name.to_string(),
            camera: auto_camera(&mesh, size, size),
            mesh,
        };
        let reference = reference(&c);
        check(
            &c,
            "cl-bvh",
            &reference,
            &cl_bvh(&device, &c, &BuildOptions::default()),
        );
    }
}

/// A tree deeper than the kernel's stack (compiled too small on purpose) must be reported,
/// not turned into a wrong image.
#[test]
fn stack_overflow_is_an_error_not_an_image() {
    let device = device();
    let c = &cases()[0];
    let bvh = Bin32Bvh::new(Bvh::build(&c.mesh, &BuildOptions::default()), &c.mesh);
    assert!(bvh.depth > 3);
    let program = ClTracer::compile_bvh(&device, 2).unwrap();
    let mut tracer = ClTracer::bvh(&device, &program, &bvh).unwrap();
    let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
    let err = tracer
        .render(
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &shade,
            false,
        )
        .unwrap_err();
    assert!(err.to_string().contains("overflowed"), "{err}");
    // The same tracer recovers once given a kernel with the right stack.
    let program = ClTracer::compile_bvh(&device, bvh.depth).unwrap();
    let mut tracer = ClTracer::bvh(&device, &program, &bvh).unwrap();
    assert!(
        tracer
            .render(
                &c.camera.pinhole(),
                c.camera.width,
                c.camera.height,
                &shade,
                false
            )
            .is_ok()
    );
}

/// Arbitrary rays from a buffer, closest and any hit, brute force and BVH, against the host.
#[test]
fn ray_buffers_match_the_host_for_closest_and_any_hits() {
    use cltrace::geometry::Ray;
    use cltrace::intersect::ClosestHit;
    use glam::Vec3;

    let device = device();
    let mesh = generate(Generator::Soup {
        triangles: 3000,
        seed: 5,
    });
    let brute = cltrace::brute::BruteForce {
        triangles: triangles_in_order(&mesh, 0..mesh.triangle_count() as u32),
    };
    let flat = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let mut state = 12345u32;
    let mut unit = move || {
        state = state.wrapping_mul(1664525).wrapping_add(1013904223);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let rays: Vec<Ray> = (0..4000)
        .map(|_| {
            let o = Vec3::new(unit(), unit(), unit()) * 2.0 - 0.5;
            let d = Vec3::new(unit(), unit(), unit()) - 0.5;
            Ray::new(o, if d.length() > 1e-3 { d } else { Vec3::X })
        })
        .collect();
    let t_max = 0.7;
    let mut bvh_tracer = ClTracer::bvh(
        &device,
        &ClTracer::compile_bvh(&device, flat.depth).unwrap(),
        &flat,
    )
    .unwrap();
    let mut brute_tracer = ClTracer::brute(
        &device,
        &ClTracer::compile_brute(&device).unwrap(),
        &brute.triangles,
    )
    .unwrap();
    for any_hit in [false, true] {
        let from_bvh = bvh_tracer.trace_rays(&rays, t_max, any_hit).unwrap();
        let from_brute = brute_tracer.trace_rays(&rays, t_max, any_hit).unwrap();
        let mut hits = 0;
        for (i, ray) in rays.iter().enumerate() {
            let expected = brute.trace(ray, t_max, false);
            for (what, got) in [("cl-bvh", from_bvh[i]), ("cl-brute", from_brute[i])] {
                match expected {
                    None => assert!(
                        got.is_miss(),
                        "{what}, any_hit {any_hit}, ray {i}: hit {got:?} where the host sees nothing"
                    ),
                    Some((prim, t)) if !any_hit => {
                        let distance = t * ray.dir.length();
                        assert_eq!(got.prim, prim as u32, "{what}, ray {i}");
                        assert!(
                            (got.t - distance).abs() <= 1e-5 * distance,
                            "{what}, ray {i}: {} vs {distance}",
                            got.t
                        );
                    }
                    Some(_) => {
                        // Any hit will do, as long as it is a real one before t_max.
                        let tri = &brute.triangles[got.prim as usize];
                        let t = hit_distance(ray, tri).unwrap_or_else(|| {
                            panic!("{what}, ray {i}: reported triangle {} is not hit", got.prim)
                        });
                        assert!(
                            t <= t_max * ray.dir.length() * (1.0 + 1e-5),
                            "{what}, ray {i}: hit beyond t_max"
                        );
                    }
                }
            }
            hits += expected.is_some() as usize;
            assert_eq!(
                flat.occluded(ray, t_max),
                expected.is_some(),
                "host BVH any-hit, ray {i}"
            );
        }
        assert!(
            hits > 200 && hits < 3800,
            "the rays should both hit and miss ({hits} hits)"
        );
    }
}

/// Rays lying in the planes of the boxes' faces (a direction component exactly zero, the
/// origin on a face's plane) are inside those slabs: every layout's kernel must find what
/// brute force finds, here the edges of nested boxes grazed along their faces.
#[test]
fn rays_along_box_faces_match_brute_force() {
    use cltrace::bvh::{DeviceLayout, Layout};
    use cltrace::geometry::Ray;
    use cltrace::intersect::ClosestHit;
    use glam::Vec3;

    let device = device();
    let mesh = generate(Generator::NestedBoxes { count: 3 });
    let brute = cltrace::brute::BruteForce {
        triangles: triangles_in_order(&mesh, 0..mesh.triangle_count() as u32),
    };
    // Every vertex coordinate value, so rays run exactly in the planes of the boxes' faces.
    let mut planes: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    planes.sort_by(f32::total_cmp);
    planes.dedup();
    let mut rays = Vec::new();
    for &a in &planes {
        for &b in planes.iter().step_by(3) {
            for (o, d) in [
                (Vec3::new(-3.0, a, b), Vec3::X),
                (Vec3::new(a, -3.0, b), Vec3::Y),
                (Vec3::new(a, b, 3.0), Vec3::NEG_Z),
                (Vec3::new(-3.0, a, b), Vec3::new(1.0, 0.0, 0.37)),
                // Subnormal components: their inverses overflow to infinity.
                (Vec3::new(-3.0, a, b), Vec3::new(1.0, 1e-41, -1e-42)),
                (Vec3::new(a, 3.0, b), Vec3::new(-2e-40, -1.0, 0.0)),
            ] {
                rays.push(Ray::new(o, d));
            }
        }
    }
    let bvh = Bvh::build(&mesh, &BuildOptions::default());
    let sah = bvh.stats().sah_cost;
    let flat = Bin32Bvh::new(bvh, &mesh);
    let mut hits = 0;
    for layout in Layout::ALL {
        let laid = DeviceLayout::new(flat.clone(), layout, sah);
        let program = ClTracer::compile(&device, Some((layout, laid.stack_size)), false).unwrap();
        let got = ClTracer::with_layout(&device, &program, &laid)
            .unwrap()
            .trace_rays(&rays, f32::INFINITY, false)
            .unwrap();
        hits = 0;
        for (i, ray) in rays.iter().enumerate() {
            let expected = brute
                .closest_hit(ray, f32::INFINITY)
                .map(|(p, t)| (p as u32, t * ray.dir.length()));
            let host = flat
                .closest_hit(ray, f32::INFINITY)
                .map(|(j, t)| (flat.triangles[j].prim, t * ray.dir.length()));
            let got = (!got[i].is_miss()).then_some((got[i].prim, got[i].t));
            // The same triangle, or a tie: another triangle really hit at the same distance.
            let agrees = |a: Option<(u32, f32)>| match (a, expected) {
                (None, None) => true,
                (Some((p, t)), Some((q, u))) => {
                    p == q && t == u
                        || (t - u).abs() <= TIE * u
                            && hit_distance(ray, &brute.triangles[p as usize])
                                .is_some_and(|h| (h - u).abs() <= TIE * u)
                }
                _ => false,
            };
            assert!(
                agrees(got),
                "{}: ray {i} {ray:?}: brute force {expected:?}, kernel {got:?}",
                layout.name()
            );
            assert!(
                agrees(host),
                "host BVH: ray {i} {ray:?}: brute force {expected:?}, host {host:?}"
            );
            hits += expected.is_some() as usize;
        }
    }
    assert!(hits > rays.len() / 4, "{hits} of {} rays hit", rays.len());
}
