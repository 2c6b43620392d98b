//! The OpenCL kernels (brute force and BVH), on every device, against the CPU brute-force
//! reference: the same triangle on every pixel, differing only by ties, on generated scenes
//! seen from outside, inside and at grazing angles, and on the shared real meshes when they
//! are present. The
//! checks are generic: [`host_frames_match`] over implementations of `ClosestHit`,
//! [`device_frames_match`] over the OpenCL tracers (`DeviceTracer`), and the ray-buffer
//! tests ask every tracer on both sides the same rays.

use crate::common::tracers::{DeviceTracer, Ties, check_every_device, check_host, in_file_order};
use crate::common::*;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::Layout;
use cltrace::bvh::{BuildOptions, Builder, Bvh};
use cltrace::camera::Camera;
use cltrace::camera::CameraSettings;
use cltrace::device::ClDevice;
use cltrace::device::tracer::ClTracer;
use cltrace::geometry::Ray;
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::intersect::ClosestHit;
use cltrace::intersect::triangles_in_order;
use cltrace::mesh::Mesh;
use cltrace::render::{Frame, MISS, Shade, ShadeParams, cpu};
use glam::Vec3;

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
    let shade =
        ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds()).with_barycentrics(true);
    cpu::render(
        &tracer,
        &c.camera.pinhole(),
        c.camera.width,
        c.camera.height,
        &shade,
        None,
    )
}

/// `tracer`'s frame of the case, Lambert-shaded, with its BVH built with `options`.
fn device_frame(
    device: &ClDevice,
    tracer: DeviceTracer,
    c: &Case,
    options: &BuildOptions,
) -> Frame {
    let mut cl = tracer.prepare(device, &c.mesh, options);
    // With barycentrics: the hit records' version 2 is checked on every layout too.
    let shade =
        ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds()).with_barycentrics(true);
    cl.render(
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

/// The host tracer `make` builds (any implementation of `ClosestHit`) renders every case
/// like the reference.
fn host_frames_match<T: ClosestHit>(what: &str, make: impl Fn(&Mesh) -> T) {
    for c in cases() {
        let reference = reference(&c);
        let shade =
            ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds()).with_barycentrics(true);
        let frame = cpu::render(
            &make(&c.mesh),
            &c.camera.pinhole(),
            c.camera.width,
            c.camera.height,
            &shade,
            None,
        );
        check(&c, what, &reference, &frame);
    }
}

/// Each of `tracers`, its BVH built with each of `builds`, renders every case like the
/// reference (which must see something).
fn device_frames_match(tracers: &[DeviceTracer], builds: &[(&str, BuildOptions)]) {
    on_every_device(|device| {
        for c in cases() {
            let reference = reference(&c);
            assert!(
                coverage(&reference) > 0,
                "{}: the camera sees nothing",
                c.name
            );
            for &tracer in tracers {
                for (build, options) in builds {
                    let frame = device_frame(device, tracer, &c, options);
                    check(
                        &c,
                        &format!("{} ({build})", tracer.name()),
                        &reference,
                        &frame,
                    );
                    if tracer == DeviceTracer::Brute {
                        break; // no tree to build
                    }
                }
            }
        }
    });
}

fn default_build() -> (&'static str, BuildOptions) {
    ("auto", BuildOptions::default())
}

#[test]
fn opencl_brute_force_matches_the_cpu_reference() {
    device_frames_match(&[DeviceTracer::Brute], &[default_build()]);
}

#[test]
fn opencl_bvh_matches_the_cpu_reference() {
    let sweep = BuildOptions {
        builder: Builder::Sweep,
        ..Default::default()
    };
    let one_per_leaf = BuildOptions {
        builder: Builder::Binned,
        max_leaf_size: 1,
        bins: 16,
        ..Default::default()
    };
    device_frames_match(
        &[DeviceTracer::Bvh(Layout::Bin32)],
        &[
            default_build(),
            ("sweep, leaves of one", sweep),
            ("16 bins, leaves of one", one_per_leaf),
        ],
    );
}

#[test]
fn every_layout_matches_the_cpu_reference() {
    device_frames_match(&DeviceTracer::layouts(), &[default_build()]);
}

#[test]
fn cpu_bvh_matches_the_cpu_reference() {
    for opts in all_options() {
        host_frames_match(&format!("cpu-bvh ({opts:?})"), |mesh| {
            Bin32Bvh::new(Bvh::build(mesh, &opts), mesh)
        });
    }
}

#[test]
fn pixels_and_colours_agree_between_kernels_and_host() {
    // Beyond the hit records, the shaded colours of the three shade modes agree to within
    // one step of 8-bit rounding (the device's sqrt and division may differ in the last bit).
    on_every_device(|device| {
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
            let program = ClTracer::compile_brute(device).unwrap();
            let mut tracer = ClTracer::brute(device, &program, &tris).unwrap();
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
    });
}

#[test]
fn a_frame_of_hits_alone_has_the_full_frames_hits_and_no_colours() {
    // The benchmark's closest-hit query leaves the colour image out (colors null in the
    // kernel): its hits are the full frame's on every layout, and on the host.
    on_every_device(|device| {
        let c = &cases()[4];
        let full = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
        let bare = full.with_colors(false);
        let (pinhole, w, h) = (c.camera.pinhole(), c.camera.width, c.camera.height);
        let brute = cltrace::brute::BruteForce {
            triangles: triangles_in_order(&c.mesh, 0..c.mesh.triangle_count() as u32),
        };
        let host_full = cpu::render(&brute, &pinhole, w, h, &full, None);
        let host_bare = cpu::render(&brute, &pinhole, w, h, &bare, None);
        assert!(
            coverage(&host_full) > 0,
            "{}: the camera sees nothing",
            c.name
        );
        assert_eq!(host_bare.hits, host_full.hits, "host");
        assert!(
            host_bare.colors.iter().all(|&x| x == 0),
            "host: a colour was shaded"
        );
        for tracer in DeviceTracer::layouts() {
            let mut cl = tracer.prepare(device, &c.mesh, &BuildOptions::default());
            let with = cl.render(&pinhole, w, h, &full, false).unwrap().0;
            let without = cl.render(&pinhole, w, h, &bare, false).unwrap().0;
            let name = tracer.name();
            assert_eq!(without.hits, with.hits, "{name}: the hits changed");
            assert!(
                with.colors.iter().all(|&x| x != 0),
                "{name}: a colour is missing"
            );
            assert!(
                without.colors.iter().all(|&x| x == 0),
                "{name}: a colour was stored"
            );
        }
    });
}

/// The real meshes, when present: the BVH kernels of every layout against the CPU brute
/// force.
#[test]
fn opencl_bvh_matches_on_the_bunny_and_the_teapot() {
    on_every_device(|device| {
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
            for tracer in DeviceTracer::layouts() {
                let frame = device_frame(device, tracer, &c, &BuildOptions::default());
                check(&c, &tracer.name(), &reference, &frame);
            }
        }
    });
}

/// A tree deeper than the kernel's stack (compiled too small on purpose) must be reported,
/// not turned into a wrong image.
#[test]
fn stack_overflow_is_an_error_not_an_image() {
    on_every_device(|device| {
        let c = &cases()[0];
        let bvh = Bin32Bvh::new(Bvh::build(&c.mesh, &BuildOptions::default()), &c.mesh);
        assert!(bvh.depth > 3);
        let program = ClTracer::compile_bvh(device, 2).unwrap();
        let mut tracer = ClTracer::bvh(device, &program, &bvh).unwrap();
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
        let program = ClTracer::compile_bvh(device, bvh.depth).unwrap();
        let mut tracer = ClTracer::bvh(device, &program, &bvh).unwrap();
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
    });
}

/// Arbitrary rays from a buffer, closest and any hit, ending at `t_max`: every tracer on
/// the host and on every device against brute force on the host (the same triangle, no
/// ties in a random soup).
#[test]
fn ray_buffers_match_the_host_for_closest_and_any_hits() {
    let mesh = generate(Generator::Soup {
        triangles: 3000,
        seed: 5,
    });
    let triangles = in_file_order(&mesh);
    let rays = random_rays(4000, 12345);
    let question = (0.7, Ties::None);
    let brute = cltrace::brute::BruteForce {
        triangles: triangles.clone(),
    };
    let flat = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let mut results = vec![
        check_host("cpu-brute", &brute, &rays, question, &triangles),
        check_host("cpu-bvh", &flat, &rays, question, &triangles),
    ];
    for device in devices() {
        results.extend(check_every_device(
            device, &mesh, &rays, question, &triangles, "",
        ));
    }
    for hits in results {
        let hits = hits.unwrap_or_else(|e| panic!("{e}"));
        assert!(
            hits > 200 && hits < 3800,
            "the rays should both hit and miss ({hits} hits)"
        );
    }
}

/// `count` rays from around the unit cube in random directions (every dominant axis, both
/// ways), from the stream `seed`.
fn random_rays(count: usize, seed: u32) -> Vec<Ray> {
    let mut state = seed;
    let mut unit = move || {
        state = state.wrapping_mul(1664525).wrapping_add(1013904223);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    (0..count)
        .map(|_| {
            let o = Vec3::new(unit(), unit(), unit()) * 2.0 - 0.5;
            let d = Vec3::new(unit(), unit(), unit()) - 0.5;
            Ray::new(o, if d.length() > 1e-3 { d } else { Vec3::X })
        })
        .collect()
}

/// The triangle test reads a vertex's coordinates along the ray's axes in one of two forms
/// (cl/intersect.cl): GPUs pick them one at a time (`AXIS_PICKS`), other devices permute
/// the vertex by selects. Every device runs its own form in the other tests; here it also
/// runs the picks, on every tracer, against brute force on the host.
#[test]
fn the_triangle_tests_picked_axes_match_the_host() {
    let mesh = generate(Generator::Soup {
        triangles: 2000,
        seed: 6,
    });
    let triangles = in_file_order(&mesh);
    let rays = random_rays(3000, 777);
    let question = (0.7, Ties::None);
    for device in devices() {
        let results =
            check_every_device(device, &mesh, &rays, question, &triangles, "-D AXIS_PICKS");
        for hits in results {
            let hits = hits.unwrap_or_else(|e| panic!("{e}"));
            assert!(hits > 100 && hits < 2900, "{hits} hits of 3000 rays");
        }
    }
}

/// Rays lying in the planes of the boxes' faces (a direction component exactly zero, the
/// origin on a face's plane) are inside those slabs: every tracer must find what brute
/// force finds, here the edges of nested boxes grazed along their faces.
#[test]
fn rays_along_box_faces_match_brute_force() {
    let mesh = generate(Generator::NestedBoxes { count: 3 });
    let triangles = in_file_order(&mesh);
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
    // The same triangle, or a tie: another triangle really hit at the same distance.
    let question = (f32::INFINITY, Ties::Allowed);
    let flat = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
    let mut results = vec![check_host("cpu-bvh", &flat, &rays, question, &triangles)];
    for device in devices() {
        results.extend(check_every_device(
            device, &mesh, &rays, question, &triangles, "",
        ));
    }
    for hits in results {
        let hits = hits.unwrap_or_else(|e| panic!("{e}"));
        assert!(hits > rays.len() / 4, "{hits} of {} rays hit", rays.len());
    }
}

/// Cases made to catch a tile entry (cl/trace.cl, `tile_entries`) that leaves out a leaf
/// a ray of its tile meets: a soup far from the origin, where rounding is coarse; and
/// slivers with a corner on the camera ray of each pixel along the tiles' edges (every
/// 8th row and column, and the next: the work-group shapes' sides divide 8), reaching
/// out of the tile into its neighbour's frustum.
fn entry_cases() -> Vec<Case> {
    let mut far = generate(Generator::Soup {
        triangles: 500,
        seed: 5,
    });
    for p in &mut far.positions {
        *p += Vec3::new(3.0e4, -2.0e4, 1.0e4);
    }
    let (width, height) = (64u32, 48u32);
    let settings = CameraSettings {
        eye: Some([0.0, 0.0, 0.0]),
        look_at: Some([0.0, 0.0, -1.0]),
        fov: Some(50.0),
        ..small(width, height)
    };
    let unit = cltrace::geometry::Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::splat(1.0),
    };
    let pinhole = Camera::from_settings(&settings, &unit).unwrap().pinhole();
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let edge = |v: u32| v % 8 == 7 || v.is_multiple_of(8);
    for y in 0..height {
        for x in (0..width).filter(|&x| edge(x) || edge(y)) {
            // Away from the pixel's own tile: right of a tile's last column, left of the
            // first, and likewise in rows.
            let out_x = if x % 8 == 7 { 1.0 } else { -1.0 };
            let out_y = if y % 8 == 7 { 1.0 } else { -1.0 };
            let depth = 2.0 + 0.01 * (positions.len() % 97) as f32;
            let at = |fx: f32, fy: f32| pinhole.ray_at(fx, fy).dir * depth;
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            let n = positions.len() as u32;
            positions.extend([
                pinhole.ray(x, y).dir * depth,
                at(fx + 0.4 * out_x, fy),
                at(fx + 0.4 * out_x, fy + 0.4 * out_y),
            ]);
            triangles.push([n, n + 1, n + 2]);
        }
    }
    vec![
        case("a soup far from the origin", far, small(64, 48)),
        case(
            "slivers along the tiles' edges",
            Mesh::new(positions, triangles),
            settings,
        ),
    ]
}

/// A perspective camera's rays start from their tile's entry node: on every layout and
/// device, `trace_primary`'s hits (from the entries) equal `trace_primary_general`'s
/// (from the root) bit for bit, and the reference's, on every case. Each device runs
/// both ways of finding the entries: a pass before the rays, and each work-group finding
/// its own (`GROUP_ENTRIES`, which GPUs take for some layouts), the latter on the cases
/// made to catch a wrong entry.
#[test]
fn camera_rays_from_their_tiles_entry_nodes_find_the_hits_from_the_root() {
    let pass = cases().into_iter().chain(entry_cases()).map(|c| (c, ""));
    let group = entry_cases().into_iter().map(|c| (c, "-D GROUP_ENTRIES"));
    let cases: Vec<_> = pass.chain(group).collect();
    on_every_device(|device| {
        for (c, form) in &cases {
            let reference = reference(c);
            assert!(coverage(&reference) > 0, "{}: sees nothing", c.name);
            for tracer in DeviceTracer::layouts() {
                let options = BuildOptions::default();
                let mut cl = tracer.prepare_built_with(device, &c.mesh, &options, form);
                let shade = ShadeParams::new(Shade::Lambert, &c.camera, &c.mesh.bounds());
                let pinhole = c.camera.pinhole();
                let (w, h) = (c.camera.width, c.camera.height);
                let entries = cl.render(&pinhole, w, h, &shade, false).unwrap().0;
                let from_root = shade.with_barycentrics(true);
                let root = cl.render(&pinhole, w, h, &from_root, false).unwrap().0;
                let what = format!("{} {form} on {}", tracer.name(), device.info.name);
                for (i, (a, b)) in entries.hits.iter().zip(&root.hits).enumerate() {
                    assert!(
                        a.prim == b.prim && a.t.to_bits() == b.t.to_bits(),
                        "{}: {what}: pixel {i} hits {a:?} from its tile's entry, {b:?} from the root",
                        c.name
                    );
                }
                check(c, &what, &reference, &root);
            }
        }
    });
}

/// The entries are worth their pass: on a landscape seen from above, filling the middle
/// of the view (an open surface: a tile's frustum meets only the part below it), some
/// tiles start below the root and the tiles that see nothing trace nothing (MISS); a
/// camera turned away sees nothing from any tile.
#[test]
fn tiles_seeing_part_of_a_mesh_start_below_the_root_and_empty_tiles_trace_nothing() {
    let mesh = generate(Generator::Landscape {
        resolution: 32,
        seed: 9,
    });
    let above = CameraSettings {
        eye: Some([0.0, 4.0, 0.0]),
        look_at: Some([0.0, 0.0, 0.0]),
        up: Some([0.0, 0.0, -1.0]),
        fov: Some(60.0),
        ..small(96, 64)
    };
    let away = CameraSettings {
        look_at: Some([0.0, 8.0, 0.0]),
        ..above
    };
    let camera = |s: &CameraSettings| Camera::from_settings(s, &mesh.bounds()).unwrap();
    let (above, away) = (camera(&above), camera(&away));
    on_every_device(|device| {
        for tracer in DeviceTracer::layouts() {
            let mut cl = tracer.prepare(device, &mesh, &BuildOptions::default());
            let what = format!("{} on {}", tracer.name(), device.info.name);
            let entries = cl
                .tile_entries(&above.pinhole(), above.width, above.height)
                .unwrap()
                .expect("a BVH program has tile_entries");
            let miss = entries.iter().filter(|&&e| e == MISS).count();
            let below = entries.iter().filter(|&&e| e != MISS && e != 0).count();
            assert!(miss > 0, "{what}: no tile is empty: {entries:?}");
            assert!(
                below > 0,
                "{what}: every tile starts at the root: {entries:?}"
            );
            let entries = cl
                .tile_entries(&away.pinhole(), away.width, away.height)
                .unwrap()
                .unwrap();
            assert!(entries.iter().all(|&e| e == MISS), "{what}: {entries:?}");
        }
    });
}
