//! The watertight ray/triangle test (Woop, Benthin, Wald: "Watertight Ray/Triangle
//! Intersection", JCGT 2013), without the double-precision fallback: edge functions that
//! come out exactly zero count as inside, so a ray through a shared edge or vertex hits at
//! least one of the triangles there and never slips between them.
//!
//! Mirrored in `cl/intersect.cl` (`watertight_ray`, `intersect_triangle`, `box_entry`)
//! operation for operation and without fused multiply-adds, so the host reference and
//! every device agree on each pixel's triangle. Also here: the triangle as the
//! intersectors store it, the robust slab test of BVH boxes, and [`ClosestHit`], what every
//! host tracer answers.

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use crate::geometry::Ray;
use crate::mesh::Mesh;

/// A triangle as the intersectors read it: three corners, each padded to 16 bytes; the
/// padding holds the triangle's index in file order (`prim`, what hit records report) and
/// its material's index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    /// First corner in world space; with `prim`, the first 16-byte row the kernels load.
    pub v0: [f32; 3],
    /// The triangle's index in file order (into [`Mesh::triangles`]): what hits report.
    pub prim: u32,
    /// Second corner; equal to `v0` for a zero-area triangle.
    pub v1: [f32; 3],
    /// Index of the triangle's material in the array the shading kernels read
    /// ([`crate::material::Materials::list`]); 0 until materials are assigned.
    pub material: u32,
    /// Third corner; equal to `v0` for a zero-area triangle.
    pub v2: [f32; 3],
    /// Bits: [`TRIANGLE_MASKED`] for a triangle whose material has a cut-out mask,
    /// [`TRIANGLE_TWO_SIDED`] for an emitter that shines from both faces.
    pub flags: u32,
}

impl Triangle {
    /// A stored triangle. One of zero area (its edges' cross product exactly zero, as
    /// [`Mesh::degenerate_count`] counts them) is stored with all three corners at `v0`:
    /// rounding could let the watertight test "hit" three distinct collinear points, but
    /// with coinciding corners every edge function is exactly zero, and such a triangle
    /// never hits anywhere.
    pub(crate) fn new(corners: [glam::Vec3; 3], prim: u32) -> Self {
        let [a, mut b, mut c] = corners;
        if (b - a).cross(c - a) == glam::Vec3::ZERO {
            (b, c) = (a, a);
        }
        Triangle {
            v0: a.to_array(),
            prim,
            v1: b.to_array(),
            material: 0,
            v2: c.to_array(),
            flags: 0,
        }
    }

    /// The unit geometric normal, turned to face `dir`'s origin side.
    pub(crate) fn facing_normal(&self, dir: glam::Vec3) -> glam::Vec3 {
        let v0 = glam::Vec3::from(self.v0);
        let n = (glam::Vec3::from(self.v1) - v0)
            .cross(glam::Vec3::from(self.v2) - v0)
            .normalize();
        if n.dot(dir) > 0.0 { -n } else { n }
    }
}

/// [`Triangle::flags`] bit: the material has a cut-out mask, so a hit counts only where
/// the mask lets it (`mask_keeps` in cl/surface.cl).
pub const TRIANGLE_MASKED: u32 = 1;

/// [`Triangle::flags`] bit: an emitter that shines from both faces; without it an emitter
/// shines only from its front face, the side its winding's normal points to, as the area
/// lights of pbrt, Mitsuba and LuxCoreRender do (`surface_point` and `emitting_normal` in
/// the kernels).
pub const TRIANGLE_TWO_SIDED: u32 = 2;

/// The mesh's triangles in the order given (file order for brute force, leaf order for a
/// BVH), each carrying its file-order index; made on every core.
pub fn triangles_in_order<I>(mesh: &Mesh, order: I) -> Vec<Triangle>
where
    I: IntoParallelIterator<Item = u32>,
    I::Iter: IndexedParallelIterator,
{
    order
        .into_par_iter()
        .with_min_len(4096)
        .map(|prim| Triangle::new(mesh.corners(prim as usize), prim))
        .collect()
}

/// Anything that finds where rays hit its triangles: the host's side of `trace` in the
/// kernels (`cl/brute.cl` and each layout's traversal file).
pub trait ClosestHit: Sync {
    /// The triangles hits refer to, in the tracer's own order.
    fn triangles(&self) -> &[Triangle];

    /// The closest hit along `ray` with `t` in `(0, t_max)` or, with `any_hit`, the first
    /// hit found there: the index into [`ClosestHit::triangles`] and the ray parameter.
    fn trace(&self, ray: &Ray, t_max: f32, any_hit: bool) -> Option<(usize, f32)> {
        self.trace_filtered(ray, t_max, any_hit, &|_, _| true)
    }

    /// [`ClosestHit::trace`] counting only the hits `keeps` accepts (given the triangle's
    /// index and the ray's test constants): the cut-out masks, which the kernels test at
    /// the same point of the traversal (`HIT_COUNTS` in cl/traverse.cl).
    fn trace_filtered(
        &self,
        ray: &Ray,
        t_max: f32,
        any_hit: bool,
        keeps: &dyn Fn(usize, &WatertightRay) -> bool,
    ) -> Option<(usize, f32)>;

    /// The closest hit along `ray` in `(0, t_max)`.
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(usize, f32)> {
        self.trace(ray, t_max, false)
    }

    /// Whether anything lies along `ray` in `(0, t_max)`.
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.trace(ray, t_max, true).is_some()
    }
}

/// The per-ray constants of the test.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    org: [f32; 3],
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl WatertightRay {
    /// The constants for `ray`, as `watertight_ray` in `cl/intersect.cl` computes them: the
    /// axis along which `dir` is largest in magnitude becomes z (the other two swapped when
    /// `dir` points down it, keeping the winding), and the shear that maps `dir` onto it.
    pub fn new(ray: &Ray) -> Self {
        let dir = ray.dir.to_array();
        let (ax, ay, az) = (dir[0].abs(), dir[1].abs(), dir[2].abs());
        let kz = if ax > ay {
            if ax > az { 0 } else { 2 }
        } else if ay > az {
            1
        } else {
            2
        };
        let mut kx = if kz == 2 { 0 } else { kz + 1 };
        let mut ky = if kx == 2 { 0 } else { kx + 1 };
        let dz = dir[kz];
        // Swapping keeps the triangle's winding, so `det` has a meaningful sign.
        if dz < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        WatertightRay {
            org: ray.origin.to_array(),
            kx,
            ky,
            kz,
            sx: dir[kx] / dz,
            sy: dir[ky] / dz,
            sz: 1.0 / dz,
        }
    }

    /// The edge functions of the triangle `(v0, v1, v2)` for this ray (the unnormalised
    /// barycentrics of `v0`, `v1`, `v2`) and the vertices' depths along it:
    /// `edge_functions` in cl/intersect.cl.
    fn edge_functions(&self, v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> EdgeFunctions {
        let o = self.org;
        let sub = |v: [f32; 3]| [v[0] - o[0], v[1] - o[1], v[2] - o[2]];
        let (a, b, c) = (sub(v0), sub(v1), sub(v2));
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let (a_z, b_z, c_z) = (a[kz], b[kz], c[kz]);
        let ax = a[kx] - self.sx * a_z;
        let ay = a[ky] - self.sy * a_z;
        let bx = b[kx] - self.sx * b_z;
        let by = b[ky] - self.sy * b_z;
        let cx = c[kx] - self.sx * c_z;
        let cy = c[ky] - self.sy * c_z;
        EdgeFunctions {
            u: cx * by - cy * bx,
            v: ax * cy - ay * cx,
            w: bx * ay - by * ax,
            depths: [a_z, b_z, c_z],
        }
    }

    /// The ray parameter of the hit with the triangle `(v0, v1, v2)` if it lies in
    /// `(0, t_max)`; `None` for a miss, a hit no closer than `t_max`, or a zero-area triangle.
    pub(crate) fn intersect(
        &self,
        v0: [f32; 3],
        v1: [f32; 3],
        v2: [f32; 3],
        t_max: f32,
    ) -> Option<f32> {
        let EdgeFunctions { u, v, w, depths } = self.edge_functions(v0, v1, v2);
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let [a_z, b_z, c_z] = depths;
        let t = u * (self.sz * a_z) + v * (self.sz * b_z) + w * (self.sz * c_z);
        let inside = if det > 0.0 {
            t > 0.0 && t < t_max * det
        } else {
            t < 0.0 && t > t_max * det
        };
        inside.then(|| t / det)
    }

    /// The barycentric weights (of `v0`, `v1`, `v2`) of this ray's hit with `tri`:
    /// `hit_barycentrics` in cl/intersect.cl.
    pub fn barycentrics(&self, tri: &Triangle) -> [f32; 3] {
        let EdgeFunctions { u, v, w, .. } = self.edge_functions(tri.v0, tri.v1, tri.v2);
        let det = u + v + w;
        if det == 0.0 {
            [1.0, 0.0, 0.0]
        } else {
            [u / det, v / det, w / det]
        }
    }

    /// `WatertightRay::intersect` on a stored triangle.
    pub fn intersect_stored(&self, tri: &Triangle, t_max: f32) -> Option<f32> {
        self.intersect(tri.v0, tri.v1, tri.v2, t_max)
    }
}

/// What [`WatertightRay::edge_functions`] computes.
struct EdgeFunctions {
    u: f32,
    v: f32,
    w: f32,
    depths: [f32; 3],
}

/// Widens a box's exit distance so that rounding in the slab test never culls a box the
/// ray touches: 1 + 2 gamma(3) (Ize, "Robust BVH Ray Traversal", JCGT 2013), which in f32
/// is exactly 1 + 3 ulp.
pub const ROBUST_EXIT: f32 = 1.0 + 3.0 * f32::EPSILON;

/// Per-ray constants of the slab test, with each slab's near and far planes picked by the
/// sign of the direction (not by comparing distances, so that a NaN never stands in for
/// the wrong one).
///
/// A zero direction component gives an infinite inverse. Where the origin lies in that
/// slab's plane, `0 * inf` makes the distance NaN, which the NaN-ignoring `min` and `max`
/// skip: a ray lying in a slab's plane counts as inside it (a substitute like 1e-30 would
/// have it leave the box at t = 0). A component so small (subnormal) that its inverse
/// overflows gets `+-f32::MAX` for the near plane, an entry no later than the true one, and
/// the infinity for the far plane, an exit no earlier: both err towards visiting the box.
/// Every other ray gets the plain inverse for both.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBox {
    org: [f32; 3],
    inv_near: [f32; 3],
    inv_far: [f32; 3],
    negative: [bool; 3],
}

impl RayBox {
    pub(crate) fn new(ray: &Ray) -> Self {
        let dir = ray.dir.to_array();
        let inv_far = dir.map(|d| 1.0 / d);
        let inv_near = inv_far.map(|i| {
            if i.is_infinite() {
                f32::MAX.copysign(i)
            } else {
                i
            }
        });
        RayBox {
            org: ray.origin.to_array(),
            inv_near,
            inv_far,
            negative: dir.map(f32::is_sign_negative),
        }
    }

    /// The entry distance into the box `[min, max]` if the ray meets it before `t_max`.
    #[inline]
    pub(crate) fn hit(&self, min: &[f32; 3], max: &[f32; 3], t_max: f32) -> Option<f32> {
        let o = self.org;
        let slab = |k: usize| {
            let (near, far) = if self.negative[k] {
                (max[k], min[k])
            } else {
                (min[k], max[k])
            };
            (
                (near - o[k]) * self.inv_near[k],
                (far - o[k]) * self.inv_far[k],
            )
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let near = nx.max(ny).max(nz.max(0.0));
        let far = (fx.min(fy).min(fz) * ROBUST_EXIT).min(t_max);
        (near <= far).then_some(near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn ray(o: [f32; 3], d: [f32; 3]) -> WatertightRay {
        WatertightRay::new(&Ray::new(Vec3::from(o), Vec3::from(d)))
    }

    const V0: [f32; 3] = [0.0, 0.0, 0.0];
    const V1: [f32; 3] = [1.0, 0.0, 0.0];
    const V2: [f32; 3] = [0.0, 1.0, 0.0];

    #[test]
    fn hits_from_both_sides_with_the_right_distance() {
        let t = ray([0.25, 0.25, 2.0], [0.0, 0.0, -1.0]).intersect(V0, V1, V2, f32::INFINITY);
        assert_eq!(t, Some(2.0));
        let t = ray([0.25, 0.25, -3.0], [0.0, 0.0, 2.0]).intersect(V0, V1, V2, f32::INFINITY);
        assert_eq!(t, Some(1.5));
    }

    #[test]
    fn misses_outside_behind_and_beyond_t_max() {
        let inf = f32::INFINITY;
        assert_eq!(
            ray([0.8, 0.8, 1.0], [0.0, 0.0, -1.0]).intersect(V0, V1, V2, inf),
            None
        );
        assert_eq!(
            ray([0.2, 0.2, 1.0], [0.0, 0.0, 1.0]).intersect(V0, V1, V2, inf),
            None
        );
        assert_eq!(
            ray([0.2, 0.2, 1.0], [0.0, 0.0, -1.0]).intersect(V0, V1, V2, 1.0),
            None
        );
    }

    #[test]
    fn zero_area_triangles_never_hit() {
        let r = ray([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]);
        assert_eq!(r.intersect(V0, V0, V0, f32::INFINITY), None);
        assert_eq!(r.intersect(V0, V1, [2.0, 0.0, 0.0], f32::INFINITY), None);
    }

    #[test]
    fn a_ray_through_a_shared_edge_hits_one_of_the_two_triangles() {
        // Two triangles sharing the diagonal of the unit square.
        let d = [1.0, 1.0, 0.0];
        for i in 0..=100 {
            let s = i as f32 / 100.0;
            let r = ray([s, s, 1.0], [0.0, 0.0, -1.0]);
            let a = r.intersect(V0, V1, d, f32::INFINITY);
            let b = r.intersect(V0, d, V2, f32::INFINITY);
            assert!(a.is_some() || b.is_some(), "slipped through at s = {s}");
        }
    }
}
