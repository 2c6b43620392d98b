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

/// Per-ray constants of the slab test. Zero direction components become +-1e-30, so that
/// every product is finite (no 0 * inf) and a ray lying in a slab's plane counts as inside.
#[derive(Clone, Copy, Debug)]
pub struct RayBox {
    org: [f32; 3],
    inv: [f32; 3],
}

impl RayBox {
    pub fn new(ray: &Ray) -> Self {
        let inv = ray.dir.to_array().map(|d| {
            let d = if d.abs() < 1e-30 {
                1e-30f32.copysign(d)
            } else {
                d
            };
            1.0 / d
        });
        RayBox {
            org: ray.origin.to_array(),
            inv,
        }
    }

    /// The entry distance into `node`'s box if the ray meets it before `t_max`.
    #[inline]
    pub fn hit(&self, node: &BvhNode, t_max: f32) -> Option<f32> {
        let (o, inv) = (self.org, self.inv);
        let t0x = (node.min[0] - o[0]) * inv[0];
        let t1x = (node.max[0] - o[0]) * inv[0];
        let t0y = (node.min[1] - o[1]) * inv[1];
        let t1y = (node.max[1] - o[1]) * inv[1];
        let t0z = (node.min[2] - o[2]) * inv[2];
        let t1z = (node.max[2] - o[2]) * inv[2];
        let near = t0x.min(t1x).max(t0y.min(t1y)).max(t0z.min(t1z).max(0.0));
        let far = (t0x.max(t1x).min(t0y.max(t1y)).min(t0z.max(t1z)) * ROBUST_EXIT).min(t_max);
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
