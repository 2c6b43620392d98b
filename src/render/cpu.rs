//! Primary-ray frames on the host, rayon over rows, through any [`ClosestHit`] tracer: the
//! reference the OpenCL kernels' frames are compared with pixel by pixel.

use rayon::prelude::*;

use super::shade::BACKGROUND;
use super::{Frame, Hit, ShadeParams};
use crate::camera::Pinhole;
use crate::geometry::Ray;
use crate::intersect::{ClosestHit, WatertightRay};
use crate::material::surface::Surface;

/// Traces one primary ray per pixel. `on_row`, if given, is called after each row. Once
/// an interruption is asked for ([`crate::interrupt`]) the rows not yet begun are left
/// empty, for the caller to notice and discard the frame.
pub fn render(
    tracer: &impl ClosestHit,
    camera: &Pinhole,
    width: u32,
    height: u32,
    shade: &ShadeParams,
    on_row: Option<&(dyn Fn() + Sync)>,
) -> Frame {
    render_surface(
        tracer,
        &Surface::default(),
        camera,
        width,
        height,
        shade,
        on_row,
    )
}

/// [`render`] of a mesh with shading data: shading normals and cut-out masks.
pub fn render_surface(
    tracer: &impl ClosestHit,
    surface: &Surface,
    camera: &Pinhole,
    width: u32,
    height: u32,
    shade: &ShadeParams,
    on_row: Option<&(dyn Fn() + Sync)>,
) -> Frame {
    let mut frame = Frame::new(width, height);
    let w = width as usize;
    let mut barycentrics = vec![[0.0; 2]; frame.hits.len()];
    frame
        .hits
        .par_chunks_mut(w)
        .zip(frame.colors.par_chunks_mut(w))
        .zip(barycentrics.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, ((hits, colors), bary))| {
            if crate::interrupt::requested() {
                return;
            }
            for x in 0..w {
                let ray = camera.ray(x as u32, y as u32);
                (hits[x], colors[x], bary[x]) = pixel(tracer, surface, &ray, shade);
            }
            if let Some(f) = on_row {
                f();
            }
        });
    if shade.barycentrics {
        frame.barycentrics = barycentrics;
    }
    frame
}

/// The hit record and colour for one ray, exactly as `store_pixel` in cl/shade.cl, and,
/// where `shade` asks for them, the hit's barycentrics of vertices 1 and 2 as
/// `trace_primary` in cl/trace.cl writes them.
pub(crate) fn pixel(
    tracer: &impl ClosestHit,
    surface: &Surface,
    ray: &Ray,
    shade: &ShadeParams,
) -> (Hit, u32, [f32; 2]) {
    let background = if shade.colors { BACKGROUND } else { 0 };
    match super::integrator::trace_masked(tracer, surface, ray, f32::INFINITY, false) {
        None => (Hit::NONE, background, [0.0; 2]),
        Some((i, t)) => {
            let d = ray.dir;
            let distance = t * (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
            let tri = &tracer.triangles()[i];
            let n = match (shade.colors, shade.shade) {
                (false, _) | (_, super::Shade::Depth) => glam::Vec3::ZERO,
                _ => surface.shading_normal(tri, (ray.origin, d)),
            };
            let b = match shade.barycentrics {
                true => {
                    let [_, b1, b2] = WatertightRay::new(ray).barycentrics(tri);
                    [b1, b2]
                }
                false => [0.0; 2],
            };
            (
                Hit {
                    prim: tri.prim,
                    t: distance,
                },
                if shade.colors {
                    shade.color(n, distance, d)
                } else {
                    0
                },
                b,
            )
        }
    }
}
