//! The host's BVH traversal over the flat device layout, mirroring `trace` in
//! cl/cltrace.h step for step: a per-ray stack, nearer child first, boxes farther than the
//! closest hit so far skipped.

use super::MAX_DEPTH;
use crate::geometry::Ray;
use crate::layout::{BvhNode, FlatBvh, Triangle};
use crate::render::cpu::ClosestHit;
use crate::triangle::WatertightRay;

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
pub struct RayBox {
    org: [f32; 3],
    inv_near: [f32; 3],
    inv_far: [f32; 3],
    negative: [bool; 3],
}

impl RayBox {
    pub fn new(ray: &Ray) -> Self {
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

    /// The entry distance into `node`'s box if the ray meets it before `t_max`.
    #[inline]
    pub fn hit(&self, node: &BvhNode, t_max: f32) -> Option<f32> {
        let o = self.org;
        let slab = |k: usize| {
            let (near, far) = if self.negative[k] {
                (node.max[k], node.min[k])
            } else {
                (node.min[k], node.max[k])
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

impl ClosestHit for FlatBvh {
    fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    fn trace(&self, ray: &Ray, t_max: f32, any_hit: bool) -> Option<(usize, f32)> {
        let tri_ray = WatertightRay::new(ray);
        let box_ray = RayBox::new(ray);
        let mut t = t_max;
        let mut best = None;
        let mut stack = [(0u32, 0f32); MAX_DEPTH as usize];
        let mut sp = 0;
        box_ray.hit(&self.nodes[0], t)?;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.is_leaf() {
                let first = n.left_or_first as usize;
                for i in first..first + n.count() as usize {
                    if let Some(h) = tri_ray.intersect_stored(&self.triangles[i], t) {
                        t = h;
                        best = Some((i, h));
                        if any_hit {
                            return best;
                        }
                    }
                }
            } else {
                let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
                match (
                    box_ray.hit(&self.nodes[l], t),
                    box_ray.hit(&self.nodes[r], t),
                ) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tr < tl { (r, l, tl) } else { (l, r, tr) };
                        stack[sp] = (far as u32, t_far);
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node still nearer than the closest hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let (next, entry) = stack[sp];
                if entry <= t {
                    node = next as usize;
                    break;
                }
            }
        }
    }
}
