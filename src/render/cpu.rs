//! The host tracers: brute force and BVH traversal, rayon over rows. They are the
//! independent reference the tests hold every OpenCL kernel to.

use indicatif::ProgressBar;
use rayon::prelude::*;

use super::shade::BACKGROUND;
use super::{Frame, Hit, ShadeParams};
use crate::camera::Pinhole;
use crate::geometry::Ray;
use crate::layout::Triangle;
use crate::triangle::WatertightRay;

/// Anything that finds where rays hit its triangles: the host's side of `trace` in
/// cl/cltrace.h.
pub trait ClosestHit: Sync {
    /// The triangles hits refer to, in the tracer's own order.
    fn triangles(&self) -> &[Triangle];

    /// The closest hit along `ray` with `t` in `(0, t_max)` or, with `any_hit`, the first
    /// hit found there: the index into [`ClosestHit::triangles`] and the ray parameter.
    fn trace(&self, ray: &Ray, t_max: f32, any_hit: bool) -> Option<(usize, f32)>;

    /// The closest hit along `ray` in `(0, t_max)`.
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(usize, f32)> {
        self.trace(ray, t_max, false)
    }

    /// Whether anything lies along `ray` in `(0, t_max)`.
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.trace(ray, t_max, true).is_some()
    }
}

/// Every ray against every triangle, the first in order winning a tie.
pub struct BruteForce {
    pub triangles: Vec<Triangle>,
}

impl ClosestHit for BruteForce {
    fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    fn trace(&self, ray: &Ray, t_max: f32, any_hit: bool) -> Option<(usize, f32)> {
        let wray = WatertightRay::new(ray);
        let mut best = None;
        let mut t = t_max;
        for (i, tri) in self.triangles.iter().enumerate() {
            if let Some(h) = wray.intersect_stored(tri, t) {
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

/// Traces one primary ray per pixel. `progress`, if given, advances by one per row.
pub fn render(
    tracer: &impl ClosestHit,
    camera: &Pinhole,
    width: u32,
    height: u32,
    shade: &ShadeParams,
    progress: Option<&ProgressBar>,
) -> Frame {
    let mut frame = Frame::new(width, height);
    let w = width as usize;
    frame
        .hits
        .par_chunks_mut(w)
        .zip(frame.colors.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (hits, colors))| {
            for x in 0..w {
                let ray = camera.ray(x as u32, y as u32);
                (hits[x], colors[x]) = pixel(tracer, &ray, shade);
            }
            if let Some(p) = progress {
                p.inc(1);
            }
        });
    frame
}

/// The hit record and colour for one ray, exactly as `store_pixel` in cl/cltrace.h.
pub fn pixel(tracer: &impl ClosestHit, ray: &Ray, shade: &ShadeParams) -> (Hit, u32) {
    match tracer.closest_hit(ray, f32::INFINITY) {
        None => (Hit::NONE, BACKGROUND),
        Some((i, t)) => {
            let d = ray.dir;
            let distance = t * (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
            let tri = &tracer.triangles()[i];
            (
                Hit {
                    prim: tri.prim,
                    t: distance,
                },
                shade.color(tri, distance, d),
            )
        }
    }
}
