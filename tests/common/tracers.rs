//! Every tracer the tests hold to the same questions: on the host each implementation of
//! [`ClosestHit`] (`BruteForce`, `Bin32Bvh`), on the OpenCL device the brute-force kernels
//! and the BVH kernels of every layout ([`DeviceTracer::all`]), all answering through
//! [`ClTracer::trace_rays`] and [`ClTracer::render`].

use cltrace::bvh::{Bin32Bvh, BuildOptions, Bvh, DeviceLayout, Layout};
use cltrace::device::{ClDevice, ClTracer, Kernels};
use cltrace::geometry::Ray;
use cltrace::intersect::{ClosestHit, Triangle, triangles_in_order};
use cltrace::mesh::Mesh;

use super::{TIE, collinear, copies, hit_distance, label, rays_for, same_hits, test_scenes};
use glam::Vec3;

/// One of the OpenCL tracers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeviceTracer {
    /// The brute-force kernels, every triangle in file order.
    Brute,
    /// The BVH kernels of one node layout.
    Bvh(Layout),
}

impl DeviceTracer {
    /// The brute-force kernels, then the BVH kernels of each layout.
    pub fn all() -> Vec<DeviceTracer> {
        std::iter::once(DeviceTracer::Brute)
            .chain(Layout::ALL.map(DeviceTracer::Bvh))
            .collect()
    }

    /// The BVH kernels of each layout.
    pub fn layouts() -> Vec<DeviceTracer> {
        Layout::ALL.map(DeviceTracer::Bvh).to_vec()
    }

    /// As `cltrace bench` names it: `cl-brute`, `cl-bvh:<layout>`.
    pub fn name(self) -> String {
        match self {
            DeviceTracer::Brute => "cl-brute".into(),
            DeviceTracer::Bvh(layout) => format!("cl-bvh:{}", layout.name()),
        }
    }

    /// Compiles its kernels and uploads `mesh` to `device`, the BVH built with `options`.
    pub fn prepare<'d>(
        self,
        device: &'d ClDevice,
        mesh: &Mesh,
        options: &BuildOptions,
    ) -> ClTracer<'d> {
        self.prepare_built_with(device, mesh, options, "")
    }

    /// [`DeviceTracer::prepare`] with `build_options` after cltrace's own (`-D NAME`: a
    /// kernel form another kind of device takes).
    pub fn prepare_built_with<'d>(
        self,
        device: &'d ClDevice,
        mesh: &Mesh,
        options: &BuildOptions,
        build_options: &str,
    ) -> ClTracer<'d> {
        match self {
            DeviceTracer::Brute => {
                let program = device
                    .compile_program(None, Kernels::TRACING, build_options)
                    .unwrap();
                ClTracer::brute(device, &program, &in_file_order(mesh)).unwrap()
            }
            DeviceTracer::Bvh(layout) => {
                let bvh = Bvh::build(mesh, options);
                let sah = bvh.stats().sah_cost;
                let laid = DeviceLayout::new(Bin32Bvh::new(bvh, mesh), layout, sah);
                let program = device
                    .compile_program(
                        Some((layout, laid.stack_size)),
                        Kernels::TRACING,
                        build_options,
                    )
                    .unwrap();
                ClTracer::with_layout(device, &program, &laid).unwrap()
            }
        }
    }
}

/// The mesh's triangles in file order: triangle `i` is index `i`.
pub fn in_file_order(mesh: &Mesh) -> Vec<Triangle> {
    triangles_in_order(mesh, 0..mesh.triangle_count() as u32)
}

/// One answer of a tracer about one ray: the triangle hit (its index in file order) and
/// the distance along the ray (in the scene's units), or `None` for a miss.
pub type Answer = Option<(u32, f32)>;

/// A host tracer's answer.
pub fn host_answer<T: ClosestHit + ?Sized>(
    tracer: &T,
    ray: &Ray,
    t_max: f32,
    any_hit: bool,
) -> Answer {
    tracer
        .trace(ray, t_max, any_hit)
        .map(|(i, t)| (tracer.triangles()[i].prim, t * ray.dir.length()))
}

/// A device tracer's answers, one per ray.
pub fn device_answers(
    tracer: &mut ClTracer,
    rays: &[Ray],
    t_max: f32,
    any_hit: bool,
) -> Vec<Answer> {
    let hits = tracer.trace_rays(rays, t_max, any_hit).unwrap();
    assert_eq!(hits.len(), rays.len());
    hits.iter()
        .map(|h| (!h.is_miss()).then_some((h.prim, h.t)))
        .collect()
}

/// Whether ties count: may a tracer name another triangle than brute force does?
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ties {
    /// Yes, one really hit within [`TIE`] relative distance of brute force's hit.
    Allowed,
    /// No: the same triangle (for scenes where ties do not occur).
    None,
}

/// Whether `got` is as good an answer as brute force's closest hit `expected` for `ray`:
/// both miss, or both hit the same triangle within [`TIE`] relative distance, or (where
/// `ties` allows) another triangle really hit that close. `triangles` are in file order.
pub fn same_closest_hit(
    ray: &Ray,
    expected: Answer,
    got: Answer,
    triangles: &[Triangle],
    ties: Ties,
) -> bool {
    let near = |s: f32, t: f32| (s - t).abs() <= TIE * s.abs().max(t.abs());
    match (expected, got) {
        (None, None) => true,
        (Some((p, s)), Some((q, t))) => {
            (p == q && near(s, t))
                || (ties == Ties::Allowed
                    && near(s, t)
                    && hit_distance(ray, &triangles[q as usize]).is_some_and(|u| near(u, s)))
        }
        _ => false,
    }
}

/// Whether `got` is a valid any-hit answer where brute force's closest hit is `expected`:
/// a miss exactly where brute force misses, otherwise a triangle really hit no farther
/// than `t_max` along the ray.
pub fn valid_any_hit(
    ray: &Ray,
    t_max: f32,
    expected: Answer,
    got: Answer,
    triangles: &[Triangle],
) -> bool {
    match (expected, got) {
        (None, None) => true,
        (Some(_), Some((q, _))) => hit_distance(ray, &triangles[q as usize])
            .is_some_and(|t| t <= t_max * ray.dir.length() * (1.0 + TIE)),
        _ => false,
    }
}

/// Checks one tracer's closest and any hits for `rays` (up to `t_max`) against brute force
/// on the host; returns the number of rays brute force sees hit, or the first disagreement.
pub fn check_answers(
    what: &str,
    rays: &[Ray],
    (t_max, ties): (f32, Ties),
    triangles: &[Triangle],
    closest: &[Answer],
    any: &[Answer],
) -> Result<usize, String> {
    let brute = cltrace::brute::BruteForce {
        triangles: triangles.to_vec(),
    };
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let expected = host_answer(&brute, ray, t_max, false);
        if !same_closest_hit(ray, expected, closest[i], triangles, ties) {
            return Err(format!(
                "{what}: ray {i} {ray:?}: brute force {expected:?}, closest hit {:?}",
                closest[i]
            ));
        }
        if !valid_any_hit(ray, t_max, expected, any[i], triangles) {
            return Err(format!(
                "{what}: ray {i} {ray:?}: brute force {expected:?}, any hit {:?}",
                any[i]
            ));
        }
        hits += expected.is_some() as usize;
    }
    Ok(hits)
}

/// [`check_answers`] for a host tracer.
pub fn check_host<T: ClosestHit + ?Sized>(
    what: &str,
    tracer: &T,
    rays: &[Ray],
    (t_max, ties): (f32, Ties),
    triangles: &[Triangle],
) -> Result<usize, String> {
    let answers = |any_hit| -> Vec<Answer> {
        rays.iter()
            .map(|r| host_answer(tracer, r, t_max, any_hit))
            .collect()
    };
    check_answers(
        what,
        rays,
        (t_max, ties),
        triangles,
        &answers(false),
        &answers(true),
    )
}

/// [`check_answers`] for a device tracer.
pub fn check_device(
    what: &str,
    tracer: &mut ClTracer,
    rays: &[Ray],
    (t_max, ties): (f32, Ties),
    triangles: &[Triangle],
) -> Result<usize, String> {
    let closest = device_answers(tracer, rays, t_max, false);
    let any = device_answers(tracer, rays, t_max, true);
    check_answers(what, rays, (t_max, ties), triangles, &closest, &any)
}

/// The meshes every tracer is asked about: the test scenes ([`test_scenes`]) and the
/// degenerate meshes (one triangle, coincident copies, zero-area ones along a line). Not
/// the chain of `bvh.rs`: its triangles overlap in one plane, so random rays meet ties
/// that differ in the last bit, and it spans twelve orders of magnitude.
pub fn question_meshes() -> Vec<(String, Mesh)> {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut meshes = test_scenes();
    meshes.extend([
        ("one triangle".to_string(), copies(tri, 1)),
        ("1000 copies of one triangle".to_string(), copies(tri, 1000)),
        ("collinear".to_string(), collinear()),
    ]);
    meshes
}

/// Rays for [`question_meshes`]: fewer on the large meshes, where brute force is slow.
fn question_rays(mesh: &Mesh) -> Vec<Ray> {
    let count = if mesh.triangle_count() > 20_000 {
        200
    } else {
        1000
    };
    rays_for(mesh, 99, count)
}

/// The host tracer `make` builds for a mesh (any implementation of [`ClosestHit`]) finds
/// exactly brute force's closest hits, and valid any hits, on every question mesh
/// ([`same_hits`]).
pub fn agrees_with_brute_force<T: ClosestHit>(what: &str, make: impl Fn(&Mesh) -> T) {
    for (name, mesh) in question_meshes() {
        same_hits(&mesh, &make(&mesh), &question_rays(&mesh))
            .unwrap_or_else(|e| panic!("{what}, {name}: {e}"));
    }
}

/// [`check_device`] on every device tracer ([`DeviceTracer::all`]) of `mesh` on `device`,
/// its kernels built with `build_options` after cltrace's own (see
/// [`DeviceTracer::prepare_built_with`]), each named after its tracer, the device and the
/// options.
pub fn check_every_device(
    device: &ClDevice,
    mesh: &Mesh,
    rays: &[Ray],
    question: (f32, Ties),
    triangles: &[Triangle],
    build_options: &str,
) -> Vec<Result<usize, String>> {
    DeviceTracer::all()
        .into_iter()
        .map(|tracer| {
            let mut cl =
                tracer.prepare_built_with(device, mesh, &BuildOptions::default(), build_options);
            let mut what = format!("{} on {}", tracer.name(), label(&device.info));
            if !build_options.is_empty() {
                what += &format!(", {build_options}");
            }
            check_device(&what, &mut cl, rays, question, triangles)
        })
        .collect()
}

/// The device tracer `tracer` finds brute force's closest hits (or ties) and valid any
/// hits on every question mesh, through [`ClTracer::trace_rays`].
pub fn device_agrees_with_brute_force(device: &ClDevice, tracer: DeviceTracer) {
    for (name, mesh) in question_meshes() {
        let mut cl = tracer.prepare(device, &mesh, &BuildOptions::default());
        let rays = question_rays(&mesh);
        let what = format!("{}, {name}", tracer.name());
        check_device(
            &what,
            &mut cl,
            &rays,
            (f32::INFINITY, Ties::Allowed),
            &in_file_order(&mesh),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
