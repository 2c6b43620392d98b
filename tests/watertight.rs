//! Watertightness: on closed meshes (a sphere, a cube, nested boxes and, when the shared
//! meshes are there, the closed parts of the Utah teapot), rays aimed exactly at points of
//! the surface where triangles meet, at several points along every shared edge (its
//! midpoint among them) and at every vertex whose triangles close around it, from outside
//! towards the centre, from random directions and exactly along the axes. Every such ray
//! passes through the closed surface at that point, so it must hit something no farther
//! than the point: a miss means it slipped between two triangles. (Rays that only touch
//! the surface there, at a silhouette, are left out, unless they meet the seam exactly:
//! see `Seam::crossed_by`.) Checked on every tracer: on the CPU each implementation of
//! `ClosestHit` (brute force and BVH), on every OpenCL device the brute-force kernels and
//! the BVH kernels of every layout; and, so that the test can fail, a Möller–Trumbore test
//! with strict inequalities must let some of the same rays through.

use std::collections::HashMap;

use cltrace::brute::BruteForce;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Bvh};
use cltrace::device::tracer::ClTracer;
use cltrace::geometry::Ray;
use cltrace::input::generate::Generator;
use cltrace::input::load_mesh;
use cltrace::intersect::ClosestHit;
use cltrace::intersect::{Triangle, triangles_in_order};
use cltrace::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;

use crate::common;
use crate::common::tracers::DeviceTracer;

/// Every ray reaches its surface point at t = 1. A hit up to this far counts: the point is
/// rounded onto its edge, and the ray onto the point.
const T_MAX: f32 = 1.0 + 1e-4;

/// A closed surface and the rays aimed at its seams.
struct Case {
    name: String,
    mesh: Mesh,
    rays: Vec<Ray>,
}

/// How to aim: points along each edge (fractions from one end), random directions per
/// point, and every how many-th shared edge and closed vertex to use.
struct Aim {
    fractions: &'static [f32],
    random: usize,
    stride: usize,
}

/// A vertex's identity by position (-0 and +0 alike), so that seams with duplicated
/// vertices close.
fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Where triangles of the closed part meet.
enum Seam {
    /// An edge `a`-`b` shared by exactly two triangles, whose third corners are `c`.
    Edge { a: Vec3, b: Vec3, c: [Vec3; 2] },
    /// A vertex whose triangles close around it, consistently wound: each `(x, y)` is a
    /// triangle `(v, x, y)`.
    Vertex { v: Vec3, fan: Vec<(Vec3, Vec3)> },
}

/// A ray along `d` this far from a triangle's plane (the cosine between `d` and the
/// normal) counts as crossing it; closer to the plane, rounding the point onto the seam
/// may legitimately miss.
const MIN_COSINE: f32 = 1e-3;

/// The sign of `d` against the triangle `(a, b, c)`'s normal: 1 or -1, 0 where the ray lies
/// exactly in its plane, `None` where it is too close to the plane to tell.
fn side(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Option<i32> {
    let n = (b - a).cross(c - a);
    let s = n.dot(d);
    if s == 0.0 {
        Some(0)
    } else if s.abs() >= MIN_COSINE * n.length() * d.length() {
        Some(s.signum() as i32)
    } else {
        None
    }
}

impl Seam {
    /// Whether a ray along `d` through the seam must hit there. It must where it passes
    /// through the surface: at an edge, the two triangles lie strictly on opposite sides of
    /// the plane through the edge along `d`; at a vertex, the ray sees every triangle of
    /// the fan strictly from the same side. Where it only touches the surface (a silhouette,
    /// both triangles on one side), the point rounded onto the seam may legitimately miss
    /// both; except where the ray is exact: along an axis, through a vertex or an edge
    /// parallel to an axis, the ray meets the seam exactly, and a triangle whose edge or
    /// corner it meets is hit (the ray lying in the plane of the others), as on a cube.
    fn crossed_by(&self, d: Vec3) -> bool {
        let axis = |v: Vec3| v.to_array().iter().filter(|&&x| x == 0.0).count() == 2;
        // Signs of the triangles as seen along d: strictly one way, or exactly edge-on.
        let touches = |sides: &[i32]| {
            sides.iter().any(|&k| k != 0)
                && (sides.iter().all(|&k| k >= 0) || sides.iter().all(|&k| k <= 0))
        };
        match self {
            Seam::Edge { a, b, c } => {
                // Both triangles written with the edge as a -> b: their normals' signs
                // against d say on which side of the ray's plane each lies.
                match (side(*a, *b, c[0], d), side(*a, *b, c[1], d)) {
                    (Some(s), Some(t)) if s * t < 0 => true,
                    (Some(s), Some(t)) if s * t == 0 => {
                        touches(&[s, t]) && axis(d) && axis(*b - *a)
                    }
                    _ => false,
                }
            }
            Seam::Vertex { v, fan } => {
                let sides: Option<Vec<i32>> = fan.iter().map(|&(x, y)| side(*v, x, y, d)).collect();
                sides.is_some_and(|s| {
                    s.iter().all(|&k| k == 1)
                        || s.iter().all(|&k| k == -1)
                        || (axis(d) && touches(&s))
                })
            }
        }
    }

    /// The points of the seam rays are aimed at.
    fn points(&self, fractions: &[f32]) -> Vec<Vec3> {
        match self {
            Seam::Edge { a, b, .. } => fractions.iter().map(|&f| *a + (*b - *a) * f).collect(),
            Seam::Vertex { v, .. } => vec![*v],
        }
    }
}

/// The seams of `mesh`'s closed part (vertices matched by position, triangles of zero area
/// left out): the edges shared by exactly two triangles, and the vertices all of whose
/// edges are such and whose triangles are consistently wound around them.
fn seams(mesh: &Mesh) -> (Vec<Seam>, Vec<Seam>) {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut points = Vec::new();
    let mut id = |p: Vec3| {
        *ids.entry(key(p)).or_insert_with(|| {
            points.push(p);
            points.len() as u32 - 1
        })
    };
    let mut triangles = Vec::new();
    for i in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.corners(i);
        if (b - a).cross(c - a) != Vec3::ZERO {
            triangles.push([id(a), id(b), id(c)]);
        }
    }
    // Edge (low, high) -> the third corners of its triangles.
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    // Vertex -> its fan, each triangle turned to start at the vertex.
    let mut fans: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    for &[a, b, c] in &triangles {
        for (u, v, w) in [(a, b, c), (b, c, a), (c, a, b)] {
            edges.entry((u.min(v), u.max(v))).or_default().push(w);
            fans.entry(u).or_default().push((v, w));
        }
    }
    let p = |i: u32| points[i as usize];
    let shared = |u: u32, v: u32| {
        edges
            .get(&(u.min(v), u.max(v)))
            .is_some_and(|c| c.len() == 2)
    };
    let mut edge_seams: Vec<((u32, u32), Seam)> = edges
        .iter()
        .filter(|(_, c)| c.len() == 2)
        .map(|(&(u, v), c)| {
            let seam = Seam::Edge {
                a: p(u),
                b: p(v),
                c: [p(c[0]), p(c[1])],
            };
            ((u, v), seam)
        })
        .collect();
    let mut vertex_seams: Vec<(u32, Seam)> = fans
        .iter()
        .filter(|&(&v, fan)| {
            // Closed and consistently wound: every neighbour follows v once and precedes
            // it once, along edges shared by two triangles.
            let mut count: HashMap<u32, (u32, u32)> = HashMap::new();
            for &(x, y) in fan {
                count.entry(x).or_default().0 += 1;
                count.entry(y).or_default().1 += 1;
            }
            fan.len() >= 3
                && count
                    .iter()
                    .all(|(&w, &(after, before))| after == 1 && before == 1 && shared(v, w))
        })
        .map(|(&v, fan)| {
            let fan = fan.iter().map(|&(x, y)| (p(x), p(y))).collect();
            (v, Seam::Vertex { v: p(v), fan })
        })
        .collect();
    // Hash order is random; the rays should not be.
    edge_seams.sort_by_key(|(k, _)| *k);
    vertex_seams.sort_by_key(|(k, _)| *k);
    (
        edge_seams.into_iter().map(|(_, s)| s).collect(),
        vertex_seams.into_iter().map(|(_, s)| s).collect(),
    )
}

/// A small deterministic random number generator (64-bit LCG).
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A random unit vector.
    fn direction(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.unit(), self.unit(), self.unit()) * 2.0 - 1.0;
            let len = v.length();
            if len > 0.1 && len <= 1.0 {
                return v / len;
            }
        }
    }
}

/// Directions to aim at `p` from: from outside towards the centre `c`, `random` random
/// ones, and the six axis directions exactly.
fn directions(p: Vec3, c: Vec3, random: usize, rng: &mut Lcg) -> Vec<Vec3> {
    let mut dirs = Vec::new();
    let inward = (c - p).normalize_or_zero();
    if inward != Vec3::ZERO {
        dirs.push(inward);
    }
    dirs.extend((0..random).map(|_| rng.direction()));
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        dirs.extend([axis, -axis]);
    }
    dirs
}

/// A ray that reaches `p` at t = 1, coming along the unit direction `dir` from `far` away.
/// Along an axis only one coordinate of the origin differs from p's and the direction has
/// exact zeros: the ray lies exactly in the planes through p.
fn ray_to(p: Vec3, dir: Vec3, far: f32) -> Ray {
    let origin = p - dir * far;
    if dir.abs().max_element() == 1.0 {
        Ray::new(origin, dir * far)
    } else {
        Ray::new(origin, p - origin)
    }
}

/// Rays aimed at the seams: every ray that passes through the surface at a seam point.
/// Returns them with the number of seam edges and vertices used and of tangent rays left
/// out.
fn seam_rays(mesh: &Mesh, aim: &Aim) -> (Vec<Ray>, usize, usize, usize) {
    let (edges, vertices) = seams(mesh);
    let bounds = mesh.bounds();
    let (c, radius) = (bounds.center(), bounds.extent().length() * 0.5);
    let far = 3.0 * radius;
    let mut rng = Lcg(0x5eed);
    let mut rays = Vec::new();
    let mut tangent = 0;
    let used_edges: Vec<&Seam> = edges.iter().step_by(aim.stride).collect();
    let used_vertices: Vec<&Seam> = vertices.iter().step_by(aim.stride).collect();
    for seam in used_edges.iter().chain(&used_vertices) {
        for p in seam.points(aim.fractions) {
            for dir in directions(p, c, aim.random, &mut rng) {
                if seam.crossed_by(dir) {
                    rays.push(ray_to(p, dir, far));
                } else {
                    tangent += 1;
                }
            }
        }
    }
    (rays, used_edges.len(), used_vertices.len(), tangent)
}

fn case(name: &str, mesh: Mesh, aim: &Aim) -> Case {
    let (rays, edges, vertices, tangent) = seam_rays(&mesh, aim);
    assert!(edges > 0 && vertices > 0, "{name}: no seams");
    eprintln!(
        "{name}: {} rays through {edges} shared edges and {vertices} closed vertices \
         ({tangent} tangent ones left out)",
        rays.len()
    );
    Case {
        name: name.to_string(),
        mesh,
        rays,
    }
}

const GENEROUS: Aim = Aim {
    fractions: &[0.5, 0.1, 0.3, 0.7, 0.9],
    random: 4,
    stride: 1,
};

fn cases() -> Vec<Case> {
    let generate = common::generate;
    let mut cases = vec![
        case(
            "sphere",
            generate(Generator::Sphere { subdivisions: 3 }),
            &Aim {
                fractions: &[0.5, 0.2, 0.8],
                random: 2,
                stride: 1,
            },
        ),
        case("cube", generate(Generator::Cube {}), &GENEROUS),
        case(
            "nested boxes",
            generate(Generator::NestedBoxes { count: 5 }),
            &GENEROUS,
        ),
    ];
    if let Some(path) = common::shared_scene("utah_teapot.obj") {
        let mesh = load_mesh(&path).unwrap();
        // About 6000 triangles: every 4th seam keeps the brute-force runs short.
        let aim = Aim {
            fractions: &[0.5, 0.25],
            random: 1,
            stride: 4,
        };
        cases.push(case("utah teapot (closed parts)", mesh, &aim));
    }
    cases
}

/// Rays that reported no hit up to the surface point (closest hit, any hit), for any
/// implementation of `ClosestHit`.
fn cpu_misses<T: ClosestHit>(tracer: &T, rays: &[Ray]) -> (usize, usize) {
    rays.par_iter()
        .map(|ray| {
            (
                tracer.closest_hit(ray, T_MAX).is_none() as usize,
                !tracer.occluded(ray, T_MAX) as usize,
            )
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// The same for an OpenCL tracer.
fn device_misses(tracer: &mut ClTracer, rays: &[Ray]) -> (usize, usize) {
    let mut count = |any_hit| {
        let hits = tracer.trace_rays(rays, T_MAX, any_hit).unwrap();
        assert_eq!(hits.len(), rays.len());
        hits.iter().filter(|h| h.is_miss()).count()
    };
    (count(false), count(true))
}

/// Möller–Trumbore with strict inequalities: a ray exactly through an edge or vertex hits
/// neither triangle there. Not watertight, on purpose.
fn strict_moller_trumbore(ray: &Ray, tri: &Triangle, t_max: f32) -> bool {
    let (v0, v1, v2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv;
    if !(u > 0.0 && u < 1.0) {
        return false;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv;
    if !(v > 0.0 && u + v < 1.0) {
        return false;
    }
    let t = e2.dot(q) * inv;
    t > 0.0 && t < t_max
}

#[test]
fn rays_through_seams_never_slip_between_triangles() {
    let mut failures = Vec::new();
    for c in cases() {
        let n = c.mesh.triangle_count() as u32;
        let brute = BruteForce {
            triangles: triangles_in_order(&c.mesh, 0..n),
        };
        let flat = Bin32Bvh::new(Bvh::build(&c.mesh, &BuildOptions::default()), &c.mesh);
        let mut results = vec![
            ("cpu-brute".to_string(), cpu_misses(&brute, &c.rays)),
            ("cpu-bvh".to_string(), cpu_misses(&flat, &c.rays)),
        ];
        for device in common::devices() {
            for tracer in DeviceTracer::all() {
                let mut cl = tracer.prepare(device, &c.mesh, &BuildOptions::default());
                let name = format!("{} on {}", tracer.name(), common::label(&device.info));
                results.push((name, device_misses(&mut cl, &c.rays)));
            }
        }
        for (tracer, (closest, any)) in results {
            eprintln!(
                "{}: {tracer}: {closest} closest-hit and {any} any-hit misses",
                c.name
            );
            if closest + any > 0 {
                failures.push(format!(
                    "{}: {tracer}: {closest} of {} rays slipped through (closest hit), {any} \
                     (any hit)",
                    c.name,
                    c.rays.len()
                ));
            }
        }

        // The same rays find the gaps of an intersector that is not watertight.
        let strict_misses = c
            .rays
            .par_iter()
            .filter(|ray| {
                !brute
                    .triangles
                    .iter()
                    .any(|tri| strict_moller_trumbore(ray, tri, T_MAX))
            })
            .count();
        eprintln!("{}: strict Möller–Trumbore: {strict_misses} misses", c.name);
        assert!(
            strict_misses > 0,
            "{}: the rays do not find the gaps of a strict Möller–Trumbore test, so they \
             test nothing",
            c.name
        );
    }
    assert!(
        failures.is_empty(),
        "rays slipped between triangles:\n{}",
        failures.join("\n")
    );
}

/// The seam finder: the cube's 18 edges (12 sides, 6 face diagonals) are all shared by two
/// triangles, and its 8 corners are closed; open one face and they no longer are. A ray
/// through an edge crosses it unless it runs along the faces' outside.
#[test]
fn seams_of_a_cube_and_of_an_open_box() {
    let mut cube = Generator::Cube {}.generate().unwrap();
    let (edges, vertices) = seams(&cube);
    assert_eq!((edges.len(), vertices.len()), (18, 8));
    // The +x face's top side, between the +x and +y faces.
    let edge = edges
        .iter()
        .find(|s| matches!(s, Seam::Edge { a, b, .. } if a.x == 1.0 && b.x == 1.0 && a.y == 1.0 && b.y == 1.0))
        .unwrap();
    assert!(edge.crossed_by(Vec3::new(-1.0, -1.0, 0.1).normalize()));
    assert!(edge.crossed_by(-Vec3::X)); // exactly along the +y face, onto the +x face's side
    assert!(!edge.crossed_by(Vec3::new(-1.0, 0.0, 0.1).normalize())); // ... not exactly
    assert!(!edge.crossed_by(Vec3::new(1.0, -1.0, 0.0).normalize())); // grazing the corner
    assert!(!edge.crossed_by(Vec3::Z)); // along the edge
    let corner = vertices
        .iter()
        .find(|s| matches!(s, Seam::Vertex { v, .. } if *v == Vec3::ONE))
        .unwrap();
    assert!(corner.crossed_by(-Vec3::ONE.normalize()));
    assert!(corner.crossed_by(-Vec3::X)); // into the +x face's corner, along the +y and +z
    assert!(!corner.crossed_by(Vec3::new(1.0, -1.0, 0.2).normalize()));
    cube.triangles.truncate(10);
    let (edges, vertices) = seams(&cube);
    // The open face's 4 sides and diagonal are gone; so are its 4 corners.
    assert_eq!((edges.len(), vertices.len()), (13, 4));
}
