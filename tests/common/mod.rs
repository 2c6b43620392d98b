//! Shared test helpers: scenes, the OpenCL device, the per-pixel oracle comparison, the
//! checks every tracer is held to ([`tracers`]) and the `cltrace` binary ([`command`]).

#![allow(dead_code)]

pub mod command;
pub mod tracers;

use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::sync::OnceLock;

use cltrace::brute::BruteForce;
use cltrace::bvh::{BuildOptions, Builder};
use cltrace::camera::{Camera, Pinhole};
use cltrace::device::{ClDevice, DeviceInfo, DeviceSelector, list_devices};
use cltrace::geometry::Ray;
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::intersect::ClosestHit;
use cltrace::intersect::WatertightRay;
use cltrace::intersect::{Triangle, triangles_in_order};
use cltrace::mesh::Mesh;
use cltrace::render::Frame;
use glam::Vec3;
use proptest::prelude::*;

/// The device the single-device OpenCL tests run on: `CLTRACE_DEVICE` if set, else the
/// default (in CI, PoCL or Intel's CPU runtime, whichever the loader lists first).
pub fn device() -> ClDevice {
    let selector = DeviceSelector::from_flag_or_env(None).expect("valid CLTRACE_DEVICE");
    ClDevice::select(&selector).unwrap_or_else(|e| panic!("the OpenCL tests need a device: {e}"))
}

/// The OpenCL implementations CI holds every kernel to: what to call each, its platform's
/// name, and the script that installs it.
const IMPLEMENTATIONS: [(&str, &str, &str); 2] = [
    (
        "PoCL",
        "Portable Computing Language",
        "scripts/setup-debian.sh",
    ),
    (
        "Intel's OpenCL CPU runtime",
        "Intel(R) OpenCL",
        "scripts/setup-intel-opencl.sh",
    ),
];

/// Every OpenCL device found, opened once for the whole test binary, so that a program is
/// compiled once per device (Intel's runtime takes seconds a build and keeps no cache of
/// its own). Where PoCL or Intel's runtime is missing, a notice says so and its device is
/// not tested, except in CI (`CI` set), which installs both and fails without either.
/// `CLTRACE_TEST_DEVICES` (selectors as `--device` takes them, e.g. `gpu`) keeps only the
/// devices it names: on a GPU host, the GPU without the host's CPU device, which compiles
/// the path tracer for minutes. CI refuses it, as it must test every implementation.
pub fn devices() -> &'static [ClDevice] {
    static DEVICES: OnceLock<Vec<ClDevice>> = OnceLock::new();
    DEVICES.get_or_init(|| {
        let found = list_devices().unwrap_or_default();
        if let Ok(list) = std::env::var("CLTRACE_TEST_DEVICES") {
            assert!(
                std::env::var_os("CI").is_none(),
                "CI tests every device: unset CLTRACE_TEST_DEVICES"
            );
            let selectors: Vec<DeviceSelector> = list
                .split(',')
                .map(|s| s.parse().expect("a selector"))
                .collect();
            let named = DeviceSelector::pick_each(&selectors, &found)
                .unwrap_or_else(|e| panic!("CLTRACE_TEST_DEVICES={list}: {e}"));
            return named.into_iter().map(open).collect();
        }
        for (what, platform, script) in IMPLEMENTATIONS {
            if !found.iter().any(|d| d.platform_name() == platform) {
                assert!(
                    std::env::var_os("CI").is_none(),
                    "CI must test the kernels on {what} (platform \"{platform}\"): install it \
                     with {script}"
                );
                eprintln!(
                    "notice: {what} is not installed ({script} installs it): the kernels are \
                     not tested on it"
                );
            }
        }
        assert!(!found.is_empty(), "the OpenCL tests need a device");
        found.iter().map(open).collect()
    })
}

/// Opens the device `d` describes, or fails the test naming it.
fn open(d: &DeviceInfo) -> ClDevice {
    let selector = d.index().parse().expect("an index is a selector");
    ClDevice::select(&selector).unwrap_or_else(|e| panic!("{}: {e}", label(d)))
}

/// A device as failure messages name it: its index, name and platform.
pub fn label(device: &DeviceInfo) -> String {
    format!(
        "{} {} ({})",
        device.index(),
        device.name,
        device.platform_name()
    )
}

/// Runs `check` on every device ([`devices`]), each to its end even when another fails;
/// then fails with every device's failure, each named after its device.
pub fn on_every_device(check: impl Fn(&'static ClDevice)) {
    let mut failures = Vec::new();
    for device in devices() {
        if let Err(panic) = std::panic::catch_unwind(AssertUnwindSafe(|| check(device))) {
            let message = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("(a panic without a message)");
            failures.push(format!("on {}: {message}", label(&device.info)));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

pub fn generate(g: Generator) -> Mesh {
    g.generate().expect("valid generator")
}

/// The shared scenes' folder: `CLTRACE_SCENES`, else `../shared/scenes`; a relative path is
/// taken from the crate's root.
pub fn scenes_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    match std::env::var_os("CLTRACE_SCENES") {
        Some(dir) if !dir.is_empty() => root.join(dir),
        _ => root.join("../shared/scenes"),
    }
}

/// `<scenes_dir()>/<name>` when the shared meshes are there; otherwise prints a notice and
/// returns `None`, so the test skips the part that needs it.
pub fn shared_scene(name: &str) -> Option<PathBuf> {
    let path = scenes_dir().join(name);
    if path.exists() {
        Some(path)
    } else {
        eprintln!(
            "notice: {} is absent; skipping the part of the test that needs it",
            path.display()
        );
        None
    }
}

/// Relative distance within which two different triangles count as a tie.
pub const TIE: f32 = 1e-5;

/// How far a kernel's barycentrics may be from the host's: well above the few ulp near 1
/// (6e-8 each) that the division may cost, well below what a different triangle or a
/// different point on it would give.
pub const BARYCENTRIC_TOLERANCE: f32 = 1e-5;

/// Checks `frame` against the `reference` frame pixel by pixel: the same triangle, or a tie
/// (both triangles really hit within [`TIE`] relative distance of each other). `triangles`
/// are the mesh's triangles in file order, to re-check ties independently. Returns how many
/// pixels differed by a tie, or a description of the first real mismatch.
pub fn compare_frames(
    reference: &Frame,
    frame: &Frame,
    camera: &Pinhole,
    triangles: &[Triangle],
) -> Result<usize, String> {
    assert_eq!(
        (reference.width, reference.height),
        (frame.width, frame.height)
    );
    if !reference.barycentrics.is_empty() {
        assert_eq!(
            frame.barycentrics.len(),
            reference.barycentrics.len(),
            "barycentrics"
        );
    }
    let mut ties = 0;
    for y in 0..frame.height {
        for x in 0..frame.width {
            let (a, b) = (reference.hit(x, y), frame.hit(x, y));
            let close = |s: f32, t: f32| (s - t).abs() <= TIE * s.abs().max(t.abs());
            if a.prim == b.prim {
                let i = (y * frame.width + x) as usize;
                // Barycentrics, where both frames have them, agree to a few ulp of [0, 1]
                // (a division, which OpenCL lets be 2.5 ulp off).
                let (p, q) = (reference.barycentrics.get(i), frame.barycentrics.get(i));
                if let (Some(p), Some(q)) = (p, q)
                    && (p[0] - q[0]).abs().max((p[1] - q[1]).abs()) > BARYCENTRIC_TOLERANCE
                {
                    return Err(format!(
                        "pixel ({x}, {y}): triangle {} at barycentrics {p:?} vs {q:?}",
                        a.prim
                    ));
                }
                if a.is_miss() || close(a.t, b.t) {
                    continue;
                }
                return Err(format!(
                    "pixel ({x}, {y}): triangle {} at {} vs {}",
                    a.prim, a.t, b.t
                ));
            }
            let ray = camera.ray(x, y);
            let tie = !a.is_miss()
                && !b.is_miss()
                && close(a.t, b.t)
                && hit_distance(&ray, &triangles[b.prim as usize]).is_some_and(|t| close(t, a.t));
            if !tie {
                return Err(format!(
                    "pixel ({x}, {y}): reference triangle {} at {}, got triangle {} at {}",
                    a.prim as i64, a.t, b.prim as i64, b.t
                ));
            }
            ties += 1;
        }
    }
    Ok(ties)
}

/// Distance along `ray` to `tri`, if the ray hits it.
pub fn hit_distance(ray: &Ray, tri: &Triangle) -> Option<f32> {
    WatertightRay::new(ray)
        .intersect_stored(tri, f32::INFINITY)
        .map(|t| t * ray.dir.length())
}

/// Number of pixels that hit something.
pub fn coverage(frame: &Frame) -> usize {
    frame.hits.iter().filter(|h| !h.is_miss()).count()
}

pub fn auto_camera(mesh: &Mesh, width: u32, height: u32) -> Camera {
    Camera::bench(&mesh.bounds(), width, height).unwrap()
}

/// A builder setting for the BVH tests.
pub fn options(builder: Builder, bins: u32, max_leaf_size: u32) -> BuildOptions {
    BuildOptions {
        builder,
        bins,
        max_leaf_size,
        ..Default::default()
    }
}

pub fn all_options() -> Vec<BuildOptions> {
    vec![
        BuildOptions::default(),
        options(Builder::Binned, 32, 8),
        options(Builder::Binned, 2, 1),
        options(Builder::Binned, 16, 4),
        options(Builder::Binned, 64, 255),
        options(Builder::Sweep, 32, 8),
        options(Builder::Sweep, 32, 1),
    ]
}

/// Closest hits of `tracer` (any implementation of [`ClosestHit`]) equal brute force's:
/// the same triangle at the same ray parameter, or an exact tie (another triangle really
/// hit at the same parameter); and its any-hit answers agree: something is hit exactly
/// when brute force's closest hit exists, and the triangle it names is really hit.
pub fn same_hits<T: ClosestHit>(mesh: &Mesh, tracer: &T, rays: &[Ray]) -> Result<(), String> {
    let brute = BruteForce {
        triangles: triangles_in_order(mesh, 0..mesh.triangle_count() as u32),
    };
    let prim = |i: usize| tracer.triangles()[i].prim as usize;
    for (i, ray) in rays.iter().enumerate() {
        let a = brute.closest_hit(ray, f32::INFINITY);
        let b = tracer.closest_hit(ray, f32::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some((ia, ta)), Some((ib, tb))) => {
                let prim_b = prim(ib);
                let tie = ta == tb && hit_distance(ray, &brute.triangles[prim_b]).is_some();
                if ia != prim_b && !tie {
                    return Err(format!(
                        "ray {i}: brute force hits {ia} at {ta}, the tracer {prim_b} at {tb}"
                    ));
                }
                if ta != tb {
                    return Err(format!(
                        "ray {i}: triangle {ia} at {ta} by brute force, {tb} by the tracer"
                    ));
                }
            }
            (a, b) => return Err(format!("ray {i}: brute force {a:?}, the tracer {b:?}")),
        }
        match (a, tracer.trace(ray, f32::INFINITY, true)) {
            (None, None) => {}
            (Some(_), Some((j, _))) => {
                if hit_distance(ray, &brute.triangles[prim(j)]).is_none() {
                    return Err(format!(
                        "ray {i}: the any-hit triangle {} is not hit",
                        prim(j)
                    ));
                }
            }
            (a, any) => {
                return Err(format!(
                    "ray {i}: brute force's closest hit {a:?}, the tracer's any hit {any:?}"
                ));
            }
        }
    }
    Ok(())
}

/// `n` copies of one triangle.
pub fn copies(tri: [Vec3; 3], n: usize) -> Mesh {
    Mesh::new(tri.to_vec(), vec![[0, 1, 2]; n])
}

/// Zero-area triangles along one line: boxes without area.
pub fn collinear() -> Mesh {
    let line: Vec<Vec3> = (0..300)
        .map(|i| Vec3::new(i as f32 * 0.1, 0.0, 0.0))
        .collect();
    let tris = (0..100u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    Mesh::new(line, tris)
}

/// Triangles sharing a corner, each 1.45 times larger than the last: the SAH wants a chain
/// far deeper than a balanced tree.
pub fn chain() -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..74 {
        let s = 1.45f32.powi(i);
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend([Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)]);
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    mesh
}

/// One ray straight down onto each triangle of [`chain`].
pub fn chain_rays() -> Vec<Ray> {
    (0..74)
        .map(|i| {
            Ray::new(
                Vec3::new(0.3, 0.3, 0.0) * 1.45f32.powi(i) + Vec3::Z,
                Vec3::NEG_Z,
            )
        })
        .collect()
}

/// Rays from points around the mesh's box towards points inside it.
pub fn rays_for(mesh: &Mesh, seed: u64, count: usize) -> Vec<Ray> {
    let b = mesh.bounds();
    let (c, r) = (b.center(), b.extent().length().max(1e-3));
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut unit = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    (0..count)
        .map(|_| {
            let from = c + Vec3::new(unit(), unit(), unit()) * r * 1.5;
            let to = c + Vec3::new(unit(), unit(), unit()) * b.extent() * 0.5;
            let dir = to - from;
            Ray::new(from, if dir.length() > 0.0 { dir } else { Vec3::Z })
        })
        .collect()
}

/// Random triangle soups of 1 to `max_triangles - 1` triangles.
pub fn mesh_strategy(max_triangles: usize) -> impl Strategy<Value = Mesh> {
    // Coordinates from a small set of values now and then, so that shared vertices,
    // coincident centroids, flat boxes and zero-area triangles all occur.
    let coord = prop_oneof![
        4 => -10.0f32..10.0,
        1 => prop::sample::select(vec![0.0f32, 1.0, -1.0, 2.5]),
    ];
    let corner = [coord.clone(), coord.clone(), coord].prop_map(Vec3::from);
    prop::collection::vec([corner.clone(), corner.clone(), corner], 1..max_triangles).prop_map(
        |tris| {
            let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
            let triangles = (0..tris.len() as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect();
            Mesh::new(positions, triangles)
        },
    )
}

/// The generated test scenes, and the bunny and teapot when the shared meshes are there.
pub fn test_scenes() -> Vec<(String, Mesh)> {
    let mut scenes: Vec<(String, Mesh)> = [
        Generator::Soup {
            triangles: 5000,
            seed: 11,
        },
        Generator::Sphere { subdivisions: 4 },
        Generator::Landscape {
            resolution: 64,
            seed: 5,
        },
        Generator::NestedBoxes { count: 20 },
        Generator::Sphereflake {
            levels: 2,
            subdivisions: 1,
            ground: 32,
        },
    ]
    .into_iter()
    .map(|g| (g.name(), generate(g)))
    .collect();
    for name in ["stanford_bunny.obj", "utah_teapot.obj"] {
        if let Some(path) = shared_scene(name) {
            scenes.push((name.to_string(), load_mesh(&path).unwrap()));
        }
    }
    scenes
}

/// A small counter-based generator of uniform numbers in [0, 1) for the sampling tests.
pub fn uniform(i: u64, dim: u64) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ dim.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 31;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 29;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// The chi-square test of goodness of fit of sample counts against expected counts, as
/// Mitsuba's test suite runs it: bins expecting fewer than 5 are pooled into one, and the
/// statistic is held to its quantile at upper-tail probability 1e-4 (z = 3.719, by Wilson
/// and Hilferty's approximation). `None` if it passes, else why not.
pub fn chi_square_fails(observed: &[f64], expected: &[f64]) -> Option<String> {
    let (mut chi2, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e >= 5.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else if pool_o > 20.0 {
        return Some(format!(
            "{pool_o} samples where the density expects {pool_e:.1}"
        ));
    }
    let k = dof.saturating_sub(1).max(1) as f64;
    let a = 2.0 / (9.0 * k);
    let limit = k * (1.0 - a + 3.719 * a.sqrt()).powi(3);
    (chi2 > limit).then(|| format!("chi-square {chi2:.1} over {dof} bins, limit {limit:.1}"))
}
