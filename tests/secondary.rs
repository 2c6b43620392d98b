//! The progressive shade modes: ambient occlusion on an open plane and inside a closed box,
//! the white furnace for the path tracer, the OpenCL path tracer against the host's, the
//! same seed giving the same bytes (the OpenCL parts on every device), and Ctrl-C writing
//! what has accumulated.

use std::sync::atomic::AtomicBool;

use crate::common::command::cltrace;
use crate::common::*;
use cltrace::bvh::BuildOptions;
use cltrace::bvh::Layout;
use cltrace::camera::Camera;
use cltrace::camera::CameraSettings;
use cltrace::device::ClDevice;
use cltrace::input::generate::Generator;
use cltrace::light::{Environment, Lights, Punctual};
use cltrace::material::{Material, Materials};
use cltrace::mesh::Mesh;
use cltrace::render::Method;
use cltrace::render::integrator::{Accumulation, Lighting, SampleSettings};
use cltrace::renderer::{PrepareOptions, Renderer};
use cltrace::report::Timings;
use glam::Vec3;

fn camera(mesh: &Mesh, eye: [f32; 3], look_at: [f32; 3], fov: f32, size: (u32, u32)) -> Camera {
    let settings = CameraSettings {
        eye: Some(eye),
        look_at: Some(look_at),
        fov: Some(fov),
        width: Some(size.0),
        height: Some(size.1),
        ..Default::default()
    };
    Camera::from_settings(&settings, &mesh.bounds()).unwrap()
}

/// Samples `spp` per pixel with `method` (on `device` for the OpenCL ones).
fn accumulate(
    method: Method,
    device: Option<&ClDevice>,
    scene: (&Mesh, &Materials),
    camera: &Camera,
    lighting: Lighting,
    spp: u32,
    seed: u32,
) -> Accumulation {
    accumulate_with(
        method,
        prepare(Layout::default(), false),
        device,
        scene,
        camera,
        lighting,
        spp,
        seed,
    )
}

/// The preparation of a sampling renderer with the BVH in `layout`.
fn prepare(layout: Layout, two_sided_lights: bool) -> PrepareOptions {
    PrepareOptions {
        build: BuildOptions::default(),
        layout: Some(layout),
        work_group: None,
        kernels: cltrace::device::Kernels::ALL,
        crease_angle: None,
        two_sided_lights,
        lights: Default::default(),
    }
}

/// [`accumulate`] with other options.
#[allow(clippy::too_many_arguments)]
fn accumulate_with(
    method: Method,
    options: PrepareOptions,
    device: Option<&ClDevice>,
    (mesh, materials): (&Mesh, &Materials),
    camera: &Camera,
    lighting: Lighting,
    spp: u32,
    seed: u32,
) -> Accumulation {
    let mut renderer = Renderer::prepare(
        method,
        mesh,
        materials,
        &options,
        device,
        &mut Timings::default(),
    )
    .unwrap();
    let settings = SampleSettings {
        lighting,
        offset: 1e-4 * mesh.bounds().extent().length(),
        seed,
    };
    let mut acc = Accumulation::new(camera.width, camera.height);
    renderer
        .render_samples(
            camera,
            &settings,
            0..spp,
            &mut acc,
            &AtomicBool::new(false),
            false,
        )
        .unwrap();
    acc
}

fn methods(device: &ClDevice) -> Vec<(Method, Option<&ClDevice>)> {
    vec![
        (Method::CpuBvh, None),
        (Method::CpuBrute, None),
        (Method::ClBvh, Some(device)),
        (Method::ClBrute, Some(device)),
    ]
}

fn quad_mesh(corners: [[f32; 3]; 4]) -> Mesh {
    Mesh::new(
        corners.iter().map(|&c| Vec3::from(c)).collect(),
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

#[test]
fn ambient_occlusion_is_one_on_an_open_plane() {
    on_every_device(|device| {
        // A plane much larger than the view, seen from just above: every ray lands on it.
        let plane = quad_mesh([
            [-50.0, 0.0, -50.0],
            [50.0, 0.0, -50.0],
            [50.0, 0.0, 50.0],
            [-50.0, 0.0, 50.0],
        ]);
        let cam = camera(&plane, [0.2, 1.0, 0.5], [0.0, 0.0, 0.0], 50.0, (24, 16));
        for (method, device) in methods(device) {
            let acc = accumulate(
                method,
                device,
                (&plane, &Materials::default()),
                &cam,
                Lighting::Ao {
                    samples: 16,
                    distance: 10.0,
                },
                2,
                1,
            );
            let values: Vec<f32> = acc.radiance().iter().map(|p| p[0]).collect();
            assert!(
                values.iter().all(|&v| v == 1.0),
                "{method:?}: occlusion on an open plane: {:?}",
                values.iter().find(|&&v| v != 1.0)
            );
        }
    });
}

#[test]
fn ambient_occlusion_is_zero_inside_a_closed_box() {
    on_every_device(|device| {
        let cube = generate(Generator::Cube {});
        let cam = camera(&cube, [0.3, -0.2, 0.1], [1.0, 0.5, -1.0], 90.0, (24, 16));
        for (method, device) in methods(device) {
            let acc = accumulate(
                method,
                device,
                (&cube, &Materials::default()),
                &cam,
                Lighting::Ao {
                    samples: 32,
                    distance: 100.0,
                },
                2,
                3,
            );
            assert!(
                acc.pixels.iter().all(|p| p[3] == 2),
                "{method:?}: every pixel has its samples"
            );
            let open = acc.radiance().iter().filter(|p| p[0] != 0.0).count();
            assert_eq!(
                open, 0,
                "{method:?}: {open} pixels see past the walls of a closed box"
            );
        }
    });
}

/// A closed sphere seen from inside, albedo a and emission E everywhere (its inner faces are
/// back faces: the emitters are two-sided): radiance E / (1 - a).
#[test]
fn white_furnace_radiance_is_emission_over_one_minus_albedo() {
    on_every_device(|device| {
        let sphere = generate(Generator::Sphere { subdivisions: 2 });
        let (albedo, emission) = (0.6f32, 0.5f32);
        let materials = Materials::uniform(Material::emitting([albedo; 3], [emission; 3]));
        let cam = camera(
            &sphere,
            [0.1, 0.05, -0.1],
            [0.0, 0.0, -1.0],
            100.0,
            (32, 24),
        );
        let expected = emission / (1.0 - albedo);
        for (method, device) in [(Method::CpuBvh, None), (Method::ClBvh, Some(device))] {
            let acc = accumulate_with(
                method,
                prepare(Layout::default(), true),
                device,
                (&sphere, &materials),
                &cam,
                Lighting::Path { max_bounces: 200 },
                16,
                7,
            );
            let values: Vec<f64> = acc.radiance().iter().map(|p| p[1] as f64).collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let bound = 4.0 * sd / n.sqrt() + 1e-3;
            eprintln!("{method:?}: mean {mean:.4} (expected {expected}), +-{bound:.4}");
            assert!(
                (mean - expected as f64).abs() < bound,
                "{method:?}: mean {mean}, expected {expected} +- {bound}"
            );
        }
    });
}

/// A small closed room lit by a ceiling panel, with a box inside.
fn lit_room() -> (Mesh, Materials) {
    let mut mesh = Mesh::default();
    let mut ids = Vec::new();
    let mut add = |m: &Mesh, id: u32, ids: &mut Vec<u32>| {
        mesh.append(m);
        ids.extend(std::iter::repeat_n(id, m.triangle_count()));
    };
    let room = generate(Generator::Cube {});
    add(&room, 0, &mut ids);
    let light = quad_mesh([
        [-0.3, 0.99, -0.3],
        [0.3, 0.99, -0.3],
        [0.3, 0.99, 0.3],
        [-0.3, 0.99, 0.3],
    ]);
    add(&light, 1, &mut ids);
    let mut block = generate(Generator::Cube {});
    for p in &mut block.positions {
        *p = *p * 0.3 + Vec3::new(-0.3, -0.7, -0.2);
    }
    add(&block, 2, &mut ids);
    let materials = Materials {
        list: vec![
            Material::diffuse([0.7, 0.6, 0.5]),
            Material::emitting([0.5; 3], [8.0; 3]),
            Material::diffuse([0.2, 0.5, 0.8]),
        ],
        per_triangle: ids,
        textures: Vec::new(),
    };
    (mesh, materials)
}

/// Host and device renders of the 32 x 24 lit room agree: image means within 2% per channel
/// (the host's above `darkest`), 4x4 blocks within 10% plus, given `other` (the host at
/// another seed), 4 standard deviations of the difference of two independent renders.
#[track_caller]
fn agree_up_to_noise(
    what: &str,
    host: &[[f32; 3]],
    dev: &[[f32; 3]],
    other: Option<&[[f32; 3]]>,
    darkest: f64,
) {
    let mean = |img: &[[f32; 3]], c: usize| {
        img.iter().map(|p| p[c] as f64).sum::<f64>() / img.len() as f64
    };
    for c in 0..3 {
        let (h, d) = (mean(host, c), mean(dev, c));
        assert!(h > darkest, "{what}, channel {c}: the room is dark ({h})");
        assert!(
            (h - d).abs() <= 0.02 * h,
            "{what}, channel {c}: host mean {h}, device mean {d}"
        );
    }
    let sum = |img: &[[f32; 3]], i: usize| img[i].iter().sum::<f32>() as f64;
    for by in 0..6 {
        for bx in 0..8 {
            let (mut h, mut d, mut var) = (0.0, 0.0, 0.0);
            for i in
                (by * 4..by * 4 + 4).flat_map(|y| (bx * 4..bx * 4 + 4).map(move |x| y * 32 + x))
            {
                h += sum(host, i);
                d += sum(dev, i);
                // Twice a render's variance: that of the difference of two.
                var += other.map_or(0.0, |o| (sum(host, i) - sum(o, i)).powi(2));
            }
            let bound = 0.1 * f64::max(h, d) + 4.0 * var.sqrt() + 1e-3;
            assert!(
                (h - d).abs() <= bound,
                "{what}, block ({bx}, {by}): host {h}, device {d}, bound {bound}"
            );
        }
    }
}

#[test]
fn opencl_path_tracer_matches_the_host_path_tracer() {
    on_every_device(|device| {
        let (room, materials) = lit_room();
        assert!(materials.has_emitters());
        let cam = camera(&room, [0.0, 0.0, 0.9], [0.0, -0.2, 0.0], 70.0, (32, 24));
        let lighting = Lighting::Path { max_bounces: 6 };
        let host = accumulate(
            Method::CpuBvh,
            None,
            (&room, &materials),
            &cam,
            lighting,
            64,
            11,
        )
        .radiance();
        let dev = accumulate(
            Method::ClBvh,
            Some(device),
            (&room, &materials),
            &cam,
            lighting,
            64,
            11,
        )
        .radiance();
        // The same random streams: most pixels agree to rounding; where the device's sin and
        // cos send a path elsewhere they differ by noise. Image means within 2%, and 4x4 blocks
        // within 10%.
        agree_up_to_noise("the room", &host, &dev, None, 0.05);
    });
}

/// Every scattering model, on the lit room's block: the kernels path-trace it as the host
/// does. Same random streams, so most samples agree to rounding; where a device's sin, cos
/// or sqrt sends a path elsewhere (behind glass and mirrors that is most paths) they differ
/// by noise: image means within 2% per channel, 4x4 blocks within 10% plus 4 standard
/// deviations of the difference of two independent renders (from the host's two seeds).
#[test]
fn every_bsdf_path_traces_on_the_device_as_on_the_host() {
    use cltrace::material::{Bsdf, CONDUCTORS};
    let gold = CONDUCTORS.iter().find(|c| c.0 == "gold").unwrap();
    let with = |bsdf, roughness| Material::with_bsdf(bsdf, [0.8, 0.6, 0.3], roughness);
    let variants = [
        (
            "rough gold",
            Material {
                eta: gold.1,
                k: gold.2,
                ..with(Bsdf::Conductor, 0.4)
            },
        ),
        ("mirror", with(Bsdf::Conductor, 0.0)),
        ("glass", with(Bsdf::Dielectric, 0.0)),
        ("rough glass", with(Bsdf::Dielectric, 0.4)),
        ("window", with(Bsdf::ThinDielectric, 0.0)),
        ("plastic", with(Bsdf::Plastic, 0.0)),
        ("rough plastic", with(Bsdf::Plastic, 0.3)),
        (
            "half metal",
            Material {
                metallic: 0.5,
                ..with(Bsdf::Plastic, 0.5)
            },
        ),
    ];
    on_every_device(|device| {
        for (name, material) in variants {
            let (room, mut materials) = lit_room();
            materials.list[2] = material;
            let cam = camera(&room, [0.0, 0.0, 0.9], [-0.2, -0.5, -0.2], 60.0, (32, 24));
            let lighting = Lighting::Path { max_bounces: 6 };
            let run = |method, device, seed| {
                let acc = accumulate(
                    method,
                    device,
                    (&room, &materials),
                    &cam,
                    lighting,
                    64,
                    seed,
                );
                acc.radiance()
            };
            let host = run(Method::CpuBvh, None, 5);
            let other = run(Method::CpuBvh, None, 6);
            let dev = run(Method::ClBvh, Some(device), 5);
            agree_up_to_noise(name, &host, &dev, Some(&other), 0.02);
        }
    });
}

/// A launch of many samples, in which each work-item traces its pixel's paths one after
/// another in one loop (path regeneration), sums to exactly what launches of one sample each
/// do, in every shade mode and with a scattering model's program too: every sample stays the
/// one it was.
#[test]
fn launches_of_many_samples_sum_as_launches_of_one() {
    use cltrace::render::integrator::Light;
    on_every_device(|device| {
        let (room, lambert) = lit_room();
        let mut glass = lambert.clone();
        glass.list[2] = Material::with_bsdf(cltrace::material::Bsdf::Dielectric, [0.9; 3], 0.0);
        // The light in view, where a camera ray's weight differs from a bounce's.
        let cam = camera(&room, [0.0, -0.2, 0.9], [0.0, 0.4, -0.3], 90.0, (24, 16));
        let modes = [
            ("paths", &lambert, Lighting::Path { max_bounces: 6 }),
            (
                "paths through glass",
                &glass,
                Lighting::Path { max_bounces: 6 },
            ),
            (
                "ambient occlusion",
                &lambert,
                Lighting::Ao {
                    samples: 2,
                    distance: 0.5,
                },
            ),
            (
                "a point light",
                &lambert,
                Lighting::Shadow {
                    light: Light::Point(Vec3::new(0.0, 0.4, 0.0)),
                },
            ),
        ];
        for (name, materials, lighting) in modes {
            let options = prepare(Layout::default(), false);
            let mut renderer = Renderer::prepare(
                Method::ClBvh,
                &room,
                materials,
                &options,
                Some(device),
                &mut Timings::default(),
            )
            .unwrap();
            let settings = SampleSettings {
                lighting,
                offset: 1e-4 * room.bounds().extent().length(),
                seed: 3,
            };
            let stop = AtomicBool::new(false);
            let spp = 12;
            let mut together = Accumulation::new(cam.width, cam.height);
            renderer
                .render_samples(&cam, &settings, 0..spp, &mut together, &stop, false)
                .unwrap();
            let mut apart = Accumulation::new(cam.width, cam.height);
            for s in 0..spp {
                renderer
                    .render_samples(&cam, &settings, s..s + 1, &mut apart, &stop, false)
                    .unwrap();
            }
            assert!(together.pixels.iter().all(|p| p[3] == spp as i64));
            assert!(together.pixels == apart.pixels, "{name}: the sums differ");
            assert_eq!(together.rays, apart.rays, "{name}");
        }
    });
}

/// A sample's radiance goes into the sums rounded to the nearest unit, ties to even, on
/// every device as on the host (`to_fixed`), at ties and where a float stops having a
/// fraction (2^23 units): PoCL rounds by an addition, other compilers by the built-in
/// (cl/integrator.cl). An emitter fills the view, so that every sample is its emission
/// alone: light samples from it lie in its plane and bounces leave it for nothing.
#[test]
fn the_sums_round_ties_to_even_on_every_device() {
    use cltrace::render::integrator::{RADIANCE_SCALE, to_fixed};
    let units = [2.5f32, 3.5, 8_388_607.5];
    let emission = units.map(|u| u / RADIANCE_SCALE);
    let expected = [2, 4, 8_388_608];
    assert_eq!(emission.map(to_fixed), expected, "the host's rounding");
    on_every_device(|device| {
        let panel = quad_mesh([
            [-50.0, -50.0, 0.0],
            [50.0, -50.0, 0.0],
            [50.0, 50.0, 0.0],
            [-50.0, 50.0, 0.0],
        ]);
        let materials = Materials::uniform(Material::emitting([0.5; 3], emission));
        let cam = camera(&panel, [0.0, 0.0, 1.0], [0.0, 0.0, 0.0], 60.0, (8, 6));
        let spp = 3;
        let acc = accumulate_with(
            Method::ClBvh,
            prepare(Layout::default(), true),
            Some(device),
            (&panel, &materials),
            &cam,
            Lighting::Path { max_bounces: 4 },
            spp,
            5,
        );
        for p in &acc.pixels {
            let want = expected.map(|e| e * spp as i64);
            assert_eq!([p[0], p[1], p[2]], want, "a pixel's sums");
        }
    });
}

/// Brute force and every layout's traversal give the same samples to the bit. Regression
/// (issue 19): on an H100 this test never ended, as the brute-force path program built by
/// NVIDIA's optimizing compiler never did; NVIDIA now builds it unoptimized (`nv_options`
/// in src/device/program.rs).
#[test]
fn brute_force_and_every_bvh_layout_give_the_same_samples() {
    on_every_device(|device| {
        let (room, materials) = lit_room();
        let cam = camera(&room, [0.0, 0.0, 0.9], [0.0, -0.2, 0.0], 70.0, (24, 16));
        for lighting in [
            Lighting::Ao {
                samples: 8,
                distance: 0.5,
            },
            Lighting::Path { max_bounces: 4 },
        ] {
            let brute = accumulate(
                Method::ClBrute,
                Some(device),
                (&room, &materials),
                &cam,
                lighting,
                4,
                5,
            );
            // Layouts that reorder the triangles must keep the emitters' indices right.
            for layout in Layout::ALL {
                let bvh = accumulate_with(
                    Method::ClBvh,
                    prepare(layout, false),
                    Some(device),
                    (&room, &materials),
                    &cam,
                    lighting,
                    4,
                    5,
                );
                let differing = (bvh.pixels.iter().zip(&brute.pixels))
                    .filter(|(a, b)| a != b)
                    .count();
                assert_eq!(
                    differing,
                    0,
                    "{lighting:?}, {}: pixels differ",
                    layout.name()
                );
            }
        }
    });
}

/// A floor lit by a small panel above it, the panel's front face (its winding's side) up or
/// down.
fn floor_and_panel(panel_faces_up: bool) -> (Mesh, Materials) {
    let mut mesh = quad_mesh([
        [-2.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
        [2.0, 0.0, -2.0],
        [-2.0, 0.0, -2.0],
    ]);
    let mut panel = [
        [-0.3, 1.0, 0.3],
        [0.3, 1.0, 0.3],
        [0.3, 1.0, -0.3],
        [-0.3, 1.0, -0.3],
    ];
    if !panel_faces_up {
        panel.reverse();
    }
    mesh.append(&quad_mesh(panel));
    let materials = Materials {
        list: vec![
            Material::diffuse([0.5; 3]),
            Material::emitting([0.5; 3], [5.0; 3]),
        ],
        per_triangle: vec![0, 0, 1, 1],
        textures: Vec::new(),
    };
    (mesh, materials)
}

/// Area lights shone from their back face too: next-event estimation turned the light's
/// normal towards the shading point and camera hits counted emission on either side, so
/// the Cornell box's light lit the gap above it and cltrace came out 8% brighter than
/// Mitsuba 3 and LuxCoreRender (issue 17). An emitter shines from its front face unless
/// the scene asks for two-sided lights; the host and the kernels agree on both.
#[test]
fn area_lights_shone_from_their_back_face() {
    on_every_device(|device| {
        let lighting = Lighting::Path { max_bounces: 3 };
        let cam_for = |mesh: &Mesh| camera(mesh, [0.0, 0.5, 3.0], [0.0, 0.0, 0.0], 60.0, (24, 16));
        let render = |method, device, up: bool, two_sided: bool| {
            let (mesh, materials) = floor_and_panel(up);
            accumulate_with(
                method,
                prepare(Layout::default(), two_sided),
                device,
                (&mesh, &materials),
                &cam_for(&mesh),
                lighting,
                64,
                3,
            )
        };
        let mean = |acc: &Accumulation| {
            let img = acc.radiance();
            img.iter().map(|p| p[1] as f64).sum::<f64>() / img.len() as f64
        };
        let mut lit = Vec::new();
        for (method, device) in [(Method::CpuBvh, None), (Method::ClBvh, Some(device))] {
            // Facing away from the floor, the panel lights nothing and is seen from behind.
            let dark = render(method, device, true, false);
            assert!(
                dark.radiance().iter().all(|p| *p == [0.0; 3]),
                "{method:?}: a panel facing away lit the scene (mean {})",
                mean(&dark)
            );
            // Facing the floor, the option changes nothing: no back face is seen or lit.
            let front = render(method, device, false, false);
            assert_eq!(
                front.pixels,
                render(method, device, false, true).pixels,
                "{method:?}: two-sided lights changed a scene without visible back faces"
            );
            let two_sided = render(method, device, true, true);
            eprintln!(
                "{method:?}: facing the floor {:.4}, facing away but two-sided {:.4}",
                mean(&front),
                mean(&two_sided)
            );
            assert!(mean(&front) > 0.01, "{method:?}: the floor is dark");
            lit.push((mean(&front), mean(&two_sided)));
        }
        // The same light seen from either face: the same image up to noise (the panel's
        // corners, and so its samples, run the other way); the kernels as the host.
        for &(front, two_sided) in &lit {
            assert!(
                (front - two_sided).abs() <= 0.05 * front,
                "facing the floor {front}, two-sided facing away {two_sided}"
            );
        }
        let ((host, _), (dev, _)) = (lit[0], lit[1]);
        assert!(
            (host - dev).abs() <= 0.02 * host,
            "host mean {host}, device mean {dev}"
        );
    });
}

#[test]
fn the_same_seed_gives_the_same_bytes() {
    on_every_device(|device| {
        let (room, materials) = lit_room();
        let cam = camera(&room, [0.0, 0.0, 0.9], [0.0, -0.2, 0.0], 70.0, (24, 16));
        let lighting = Lighting::Path { max_bounces: 8 };
        let run = |seed| {
            accumulate(
                Method::ClBvh,
                Some(device),
                (&room, &materials),
                &cam,
                lighting,
                8,
                seed,
            )
        };
        let (a, b, c) = (run(42), run(42), run(43));
        let bytes = |acc: &Accumulation| {
            acc.pixels
                .iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect::<Vec<u8>>()
        };
        assert_eq!(bytes(&a), bytes(&b), "the same seed twice");
        assert_ne!(bytes(&a), bytes(&c), "another seed");
        assert_eq!(a.rays, b.rays);
    });
}

#[test]
fn bad_sampling_options_exit_2() {
    for args in [
        vec!["--shade", "path", "--spp", "0"],
        vec!["--shade", "path", "--spp", "70000"],
        vec!["--shade", "ao", "--ao-samples", "0"],
        vec!["--shade", "ao", "--ao-distance", "-1"],
        vec!["--shade", "shadow", "--light", "lamp:1,2,3"],
        vec!["--shade", "shadow", "--light", "sun:0,0,0"],
        vec!["--shade", "path", "--max-bounces", "5000"],
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = cltrace()
            .args([
                "render", "--width", "8", "--height", "8", "--method", "cpu-bvh",
            ])
            .args(&args)
            .arg("-o")
            .arg(dir.path().join("x.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error:"), "{args:?}: {stderr}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "{args:?} left a file"
        );
    }
}

/// The last bounce took a light sample and stopped, so a mirror there showed nothing of an
/// emitter (Mitsuba shows its reflection): a mirror floor at `max_bounces` 0 was black.
/// Now the last bounce traces its sampled direction for the emitter it may hit.
#[test]
fn mirrors_showed_no_light_at_the_last_bounce() {
    use cltrace::material::Bsdf;
    on_every_device(|device| {
        let (mesh, mut materials) = floor_and_panel(false);
        materials.list[0] = Material::with_bsdf(Bsdf::Conductor, [0.9; 3], 0.0);
        let cam = camera(&mesh, [0.0, 0.5, 3.0], [0.0, 0.0, 0.0], 60.0, (24, 16));
        for (method, device) in [(Method::CpuBvh, None), (Method::ClBvh, Some(device))] {
            let acc = accumulate(
                method,
                device,
                (&mesh, &materials),
                &cam,
                Lighting::Path { max_bounces: 0 },
                4,
                1,
            );
            // Pixels that see the panel itself are behind the mirror's reflection of it:
            // the panel faces down, so the camera above the floor sees only its back.
            let bright = acc.radiance().iter().filter(|p| p[0] > 1.0).count();
            assert!(bright > 0, "{method:?}: the mirror shows no light");
        }
    });
}

/// A smooth glass ball rendered black: refracted rays left from the hit point lifted onto
/// the curved surface the vertex normals describe (the shadow-terminator fix), in front of
/// the facet, and met their own triangle again. They now leave from the plain point.
#[test]
fn smooth_glass_was_black_where_its_refracted_rays_met_their_own_triangle() {
    use cltrace::material::Bsdf;
    on_every_device(|device| {
        // No vertex normals: the default crease angle computes smooth ones.
        let sphere = generate(Generator::Sphere { subdivisions: 3 });
        let glass = Materials::uniform(Material::with_bsdf(Bsdf::Dielectric, [1.0; 3], 0.0));
        let cam = camera(&sphere, [0.0, 0.0, 3.0], [0.0, 0.0, 0.0], 30.0, (16, 16));
        for (method, device) in [(Method::CpuBvh, None), (Method::ClBvh, Some(device))] {
            let img = accumulate(
                method,
                device,
                (&sphere, &glass),
                &cam,
                Lighting::Path { max_bounces: 8 },
                16,
                2,
            )
            .radiance();
            // The middle 8 x 8 pixels see the sky through the ball: at least its grey
            // below (0.35), near the horizon white.
            let middle: f32 = (4..12)
                .flat_map(|y| (4..12).map(move |x| y * 16 + x))
                .map(|i| img[i][0])
                .sum::<f32>()
                / 64.0;
            assert!(
                middle > 0.5,
                "{method:?}: the glass ball is dark ({middle})"
            );
        }
    });
}

/// `--two-sided-lights` and `[render] two_sided_lights` reach the renderer, the flag over
/// the scene file: a panel facing away from the floor lights it only when two-sided.
#[test]
fn two_sided_lights_is_a_flag_and_a_scene_key() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib panel.mtl\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nv -2 0 -2\n\
               v -0.3 1 0.3\nv 0.3 1 0.3\nv 0.3 1 -0.3\nv -0.3 1 -0.3\n\
               usemtl floor\nf 1 2 3 4\nusemtl lamp\nf 5 6 7 8\n";
    std::fs::write(dir.path().join("panel.obj"), obj).unwrap();
    std::fs::write(
        dir.path().join("panel.mtl"),
        "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n",
    )
    .unwrap();
    let scene = |two_sided: Option<bool>| {
        let path = dir.path().join(format!("scene_{two_sided:?}.toml"));
        let key = two_sided.map_or(String::new(), |b| format!("two_sided_lights = {b}\n"));
        std::fs::write(
            &path,
            format!(
                "mesh = \"panel.obj\"\n[camera]\neye = [0.0, 0.5, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                 [render]\nmethod = \"cpu-bvh\"\nshade = \"path\"\nspp = 4\n{key}"
            ),
        )
        .unwrap();
        path
    };
    let lit = |scene: &std::path::Path, args: &[&str]| {
        let out = dir.path().join("out.png");
        let run = cltrace()
            .arg("render")
            .arg(scene)
            .args(["--width", "16", "--height", "12", "-q", "-o"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let img = image::open(&out).unwrap().into_rgb8();
        img.pixels().filter(|p| p.0 != [0; 3]).count()
    };
    assert_eq!(lit(&scene(None), &[]), 0, "front faces only by default");
    assert_eq!(lit(&scene(Some(false)), &[]), 0);
    assert!(lit(&scene(Some(true)), &[]) > 0, "the scene key");
    assert!(lit(&scene(None), &["--two-sided-lights"]) > 0, "the flag");
    assert!(lit(&scene(Some(false)), &["--two-sided-lights", "true"]) > 0);
    assert_eq!(lit(&scene(Some(true)), &["--two-sided-lights", "false"]), 0);
}

/// A floor with a block on it, open to the sky: for the lights at infinity. The block's
/// material is `block`.
fn open_floor(block: Material) -> (Mesh, Materials) {
    let mut mesh = quad_mesh([
        [-2.0, -1.0, 2.0],
        [2.0, -1.0, 2.0],
        [2.0, -1.0, -2.0],
        [-2.0, -1.0, -2.0],
    ]);
    let mut cube = generate(Generator::Cube {});
    for p in &mut cube.positions {
        *p = *p * 0.4 + Vec3::new(-0.2, -0.6, -0.3);
    }
    mesh.append(&cube);
    let materials = Materials {
        list: vec![Material::diffuse([0.6, 0.6, 0.6]), block],
        per_triangle: std::iter::repeat_n(0, 2)
            .chain(std::iter::repeat_n(1, cube.triangle_count()))
            .collect(),
        textures: Vec::new(),
    };
    (mesh, materials)
}

/// A 16 x 8 environment map: a dim gradient and one bright texel above the horizon.
fn small_map(intensity: f32, rotate: f32) -> Environment {
    let rgb: Vec<[f32; 3]> = (0..16 * 8)
        .map(|k| match (k % 16, k / 16) {
            (5, 2) => [60.0, 50.0, 40.0],
            (i, j) => [0.2 + 0.05 * j as f32, 0.3, 0.4 + 0.02 * i as f32],
        })
        .collect();
    Environment::new(16, 8, &rgb, intensity, rotate)
}

/// Every kind of light: the kernels path-trace it as the host does, sample by sample (the
/// same random streams; where a device's sin, cos or acos sends a sample elsewhere they
/// differ by noise), within [`agree_up_to_noise`]'s bounds. With and without the
/// scattering models (MIS with a Lambertian scene is the environment's own).
#[test]
fn every_light_path_traces_on_the_device_as_on_the_host() {
    use cltrace::light::sky::Sky;
    use cltrace::material::Bsdf;
    let spot = Punctual::Spot {
        position: Vec3::new(0.5, 0.9, 0.5),
        direction: Vec3::new(-0.5, -1.0, -0.3).normalize(),
        intensity: Vec3::new(3.0, 2.0, 1.0),
        cutoff: 35f32.to_radians(),
        beam: 20f32.to_radians(),
    };
    let point = Punctual::Point {
        position: Vec3::new(-0.5, 0.5, 0.3),
        intensity: Vec3::new(0.5, 1.0, 1.5),
    };
    let sun = Punctual::Directional {
        direction: Vec3::new(0.4, -1.0, -0.3).normalize(),
        irradiance: Vec3::new(2.0, 1.8, 1.5),
    };
    let sky = Sky {
        sun: Vec3::new(0.5, 0.6, -0.4).normalize(),
        turbidity: 3.0,
        intensity: 1.0,
    };
    let sky_map = Environment::new(128, 64, &sky.bake(128, 64), 0.5, 0.0);
    let plastic = Material::with_bsdf(Bsdf::Plastic, [0.2, 0.4, 0.8], 0.3);
    let lambert = Material::diffuse([0.2, 0.4, 0.8]);
    let lights = |environment: Option<Environment>, punctual: Vec<Punctual>| Lights {
        environment,
        punctual,
    };
    let (room, mut two_panels) = lit_room();
    // A second, dimmer emitter: light samples pick the panels by power.
    two_panels
        .list
        .push(Material::emitting([0.5; 3], [0.5, 1.0, 2.0]));
    let block = two_panels.per_triangle.len() - 12;
    for id in &mut two_panels.per_triangle[block..block + 2] {
        *id = 3;
    }
    let (room_unlit, mut dark) = lit_room();
    dark.list[1] = Material::diffuse([0.5; 3]);
    let variants: Vec<(&str, (Mesh, Materials), Lights)> = vec![
        (
            "two emitters by power",
            (room, two_panels),
            Lights::default(),
        ),
        (
            "point and spot in the room",
            (room_unlit, dark),
            lights(None, vec![point, spot]),
        ),
        // Each program the lights compile into costs PoCL seconds in CI: three kinds here.
        (
            "a sun and a map over plastic",
            open_floor(plastic),
            lights(Some(small_map(1.5, 40.0)), vec![sun]),
        ),
        (
            "a colour and a spot over Lambert",
            open_floor(lambert),
            lights(
                Some(Environment::constant(Vec3::new(0.3, 0.4, 0.5), 1.0)),
                vec![spot],
            ),
        ),
        (
            "a map over Lambert, turned the other way",
            open_floor(lambert),
            lights(Some(small_map(1.0, -70.0)), vec![spot]),
        ),
        (
            "a sky and a point over plastic",
            open_floor(plastic),
            lights(Some(sky_map), vec![point]),
        ),
    ];
    // The host's two renders of each variant, once for every device.
    let lighting = Lighting::Path { max_bounces: 4 };
    let runs: Vec<_> = variants
        .iter()
        .map(|(name, (mesh, materials), lights)| {
            let cam = camera(mesh, [0.0, 0.0, 0.9], [-0.2, -0.5, -0.2], 60.0, (32, 24));
            let options = PrepareOptions {
                lights: std::sync::Arc::new(lights.clone()),
                ..prepare(Layout::default(), false)
            };
            let run = move |method, device: Option<&ClDevice>, seed| {
                accumulate_with(
                    method,
                    options.clone(),
                    device,
                    (mesh, materials),
                    &cam,
                    lighting,
                    64,
                    seed,
                )
                .radiance()
            };
            let host = run(Method::CpuBvh, None, 5);
            let other = run(Method::CpuBvh, None, 6);
            (name, run, host, other)
        })
        .collect();
    on_every_device(|device| {
        for (name, run, host, other) in &runs {
            let dev = run(Method::ClBvh, Some(device), 5);
            agree_up_to_noise(name, host, &dev, Some(other), 0.01);
        }
    });
}

/// Issue 17's "the same image on every device": PoCL, the Intel runtime and a GPU (each
/// device found) render one converged image of every kind of surface and light, and each
/// equals the first device's within [`agree_up_to_noise`]'s bounds (the same seeds, so the
/// images differ only where a device's sin, cos or rounding sent a path elsewhere).
#[test]
fn every_device_renders_the_same_converged_image() {
    use cltrace::material::Bsdf;
    let (mut mesh, mut materials) =
        open_floor(Material::with_bsdf(Bsdf::Plastic, [0.2, 0.4, 0.8], 0.3));
    let mut glass = generate(Generator::Sphere { subdivisions: 2 });
    for p in &mut glass.positions {
        *p = *p * 0.25 + Vec3::new(0.5, -0.75, 0.1);
    }
    mesh.append(&glass);
    materials
        .list
        .push(Material::with_bsdf(Bsdf::Dielectric, [1.0; 3], 0.0));
    materials
        .per_triangle
        .extend(std::iter::repeat_n(2, glass.triangle_count()));
    let lights = Lights {
        environment: Some(small_map(1.0, 20.0)),
        punctual: vec![Punctual::Spot {
            position: Vec3::new(-0.5, 1.0, 0.8),
            direction: Vec3::new(0.4, -1.0, -0.6).normalize(),
            intensity: Vec3::splat(2.0),
            cutoff: 30f32.to_radians(),
            beam: 15f32.to_radians(),
        }],
    };
    let options = PrepareOptions {
        lights: std::sync::Arc::new(lights),
        ..prepare(Layout::default(), false)
    };
    let cam = camera(&mesh, [0.0, 0.2, 1.2], [0.0, -0.6, -0.2], 60.0, (32, 24));
    let lighting = Lighting::Path { max_bounces: 6 };
    let run = |device: Option<&ClDevice>, method, seed| {
        accumulate_with(
            method,
            options.clone(),
            device,
            (&mesh, &materials),
            &cam,
            lighting,
            256,
            seed,
        )
        .radiance()
    };
    let other = run(None, Method::CpuBvh, 8);
    let images: Vec<(String, Vec<[f32; 3]>)> = devices()
        .iter()
        .map(|d| (d.info.name.clone(), run(Some(d), Method::ClBvh, 7)))
        .collect();
    let (first, reference) = &images[0];
    for (name, image) in &images[1..] {
        agree_up_to_noise(
            &format!("{name} against {first}"),
            reference,
            image,
            Some(&other),
            0.01,
        );
    }
    // And the host's, which every device's kernels mirror.
    agree_up_to_noise(
        first,
        &run(None, Method::CpuBvh, 7),
        reference,
        Some(&other),
        0.01,
    );
}
