//! Brute force on the host: every ray against every triangle, the first in order winning
//! a tie; mirrors `trace` in `cl/brute.cl`. The independent reference the tests hold every
//! BVH traversal, on the host and on the device, to.

use crate::geometry::Ray;
use crate::intersect::{ClosestHit, Triangle, WatertightRay};

/// Every ray against every triangle, the first in order winning a tie.
pub struct BruteForce {
    /// The triangles to test, in the order ties are decided (file order, as
    /// [`crate::intersect::triangles_in_order`] gives them); hits index into this list.
    pub triangles: Vec<Triangle>,
}

impl ClosestHit for BruteForce {
    fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    fn trace_filtered(
        &self,
        ray: &Ray,
        t_max: f32,
        any_hit: bool,
        keeps: &dyn Fn(usize, &WatertightRay) -> bool,
    ) -> Option<(usize, f32)> {
        let wray = WatertightRay::new(ray);
        let mut best = None;
        let mut t = t_max;
        for (i, tri) in self.triangles.iter().enumerate() {
            if let Some(h) = wray.intersect_stored(tri, t).filter(|_| keeps(i, &wray)) {
                t = h;
                best = Some((i, h));
                if any_hit {
                    break;
                }
            }
        }
        best
    }
}
