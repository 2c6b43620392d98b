//! The progressive shade modes on the host: ambient occlusion, a light with hard shadows,
//! and a diffuse path tracer with next-event estimation. Each sample of each pixel is a
//! pure function of (seed, pixel, sample), mirrored by the kernels of cl/integrator.cl, so the
//! host is the reference the devices are compared with.

use std::f32::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::sampling::{Sampler, bounce_dim, cosine_direction, triangle_point};
use crate::camera::Pinhole;
use crate::geometry::Ray;
use crate::intersect::ClosestHit;
use crate::intersect::Triangle;
use crate::material::Material;

/// Share of the light in `shadow` mode that reaches surfaces the light does not.
pub const SHADOW_AMBIENT: f32 = 0.1;
/// Bounces after which Russian roulette may end a path.
pub const ROULETTE_AFTER: u32 = 3;

/// The light of `--shade shadow`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A light infinitely far away, in this direction (from the surface towards the light).
    Directional(Vec3),
    /// A light at this point.
    Point(Vec3),
}

impl std::str::FromStr for Light {
    type Err = String;

    /// `sun:x,y,z` (a direction towards the light) or `point:x,y,z` (its position).
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!("`{s}` is not a light: use `sun:x,y,z` (direction towards it) or `point:x,y,z`")
        };
        let (kind, xyz) = s.split_once(':').ok_or_else(bad)?;
        let v: Vec<f32> = xyz
            .split(',')
            .map(|c| c.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        let [x, y, z] = v[..] else { return Err(bad()) };
        let p = Vec3::new(x, y, z);
        if !p.is_finite() {
            return Err(bad());
        }
        match kind.trim() {
            "sun" if p.length() > 0.0 => Ok(Light::Directional(p.normalize())),
            "sun" => Err(format!("`{s}`: a sun's direction cannot be zero")),
            "point" => Ok(Light::Point(p)),
            _ => Err(bad()),
        }
    }
}

/// How each sample finds its radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lighting {
    /// The unoccluded share of `samples` cosine-weighted rays of length `distance`.
    Ao {
        /// Occlusion rays per sample.
        samples: u32,
        /// How far each ray looks for an occluder, in world units.
        distance: f32,
    },
    /// Albedo under one light, with hard shadows and a little ambient light.
    Shadow {
        /// The one light.
        light: Light,
    },
    /// Diffuse path tracing: next-event estimation to emitting triangles where there are
    /// any, a sky otherwise, Russian roulette after a few bounces.
    Path {
        /// Diffuse bounces after the first hit, at most; 0 lights the first hit only.
        max_bounces: u32,
    },
}

/// Everything a sample needs besides the geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSettings {
    /// How a sample finds its radiance.
    pub lighting: Lighting,
    /// How far secondary rays start off the surface, along its normal (1e-4 of the scene
    /// radius, as in the benchmark protocol).
    pub offset: f32,
    /// The seed of the random numbers: with the pixel and the sample index it fixes every
    /// number a sample draws.
    pub seed: u32,
}

/// The emitting triangles, for next-event estimation: indices into the tracer's triangles
/// and the cumulative distribution of their areas.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Emitters {
    pub(crate) triangles: Vec<u32>,
    /// `cdf[i]`: the area of emitters 0..=i over the total, the last one exactly 1.
    pub(crate) cdf: Vec<f32>,
    pub(crate) total_area: f32,
}

impl Emitters {
    pub(crate) fn new(triangles: &[Triangle], materials: &[Material]) -> Self {
        let mut list = Vec::new();
        let mut areas = Vec::new();
        for (i, t) in triangles.iter().enumerate() {
            if materials[t.material as usize].emits() {
                let area = 0.5
                    * (Vec3::from(t.v1) - Vec3::from(t.v0))
                        .cross(Vec3::from(t.v2) - Vec3::from(t.v0))
                        .length();
                if area > 0.0 {
                    list.push(i as u32);
                    areas.push(area as f64);
                }
            }
        }
        let total: f64 = areas.iter().sum();
        let mut acc = 0.0;
        let mut cdf: Vec<f32> = areas
            .iter()
            .map(|a| {
                acc += a;
                (acc / total) as f32
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Emitters {
            triangles: list,
            cdf,
            total_area: total as f32,
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The emitter whose CDF interval holds `u` (binary search, as the kernel does).
    pub(crate) fn pick(&self, u: f32) -> usize {
        let (mut lo, mut hi) = (0usize, self.cdf.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if u < self.cdf[mid] {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    }
}

/// The sky seen by rays that leave a scene without emitters: white at the horizon, blue
/// overhead, grey below.
pub(crate) fn sky(d: Vec3) -> Vec3 {
    let up = d.y / d.length();
    if up >= 0.0 {
        Vec3::ONE.lerp(Vec3::new(0.45, 0.65, 1.0), up)
    } else {
        Vec3::ONE.lerp(Vec3::splat(0.35), -up)
    }
}

/// The ray of pixel (x, y), jittered within the pixel by the sampler's first two numbers.
pub(crate) fn jittered_ray(camera: &Pinhole, x: u32, y: u32, s: &Sampler) -> Ray {
    let fx = x as f32 + s.get(0);
    let fy = y as f32 + s.get(1);
    let d = |k: usize| (camera.p0[k] + fx * camera.du[k]) + fy * camera.dv[k];
    Ray::new(
        Vec3::from_slice(&camera.eye[..3]),
        Vec3::new(d(0), d(1), d(2)),
    )
}

/// The unit geometric normal of `t`, turned to face `dir`'s origin side.
pub(crate) fn facing_normal(t: &Triangle, dir: Vec3) -> Vec3 {
    let v0 = Vec3::from(t.v0);
    let n = (Vec3::from(t.v1) - v0)
        .cross(Vec3::from(t.v2) - v0)
        .normalize();
    if n.dot(dir) > 0.0 { -n } else { n }
}

/// One sample of pixel (x, y): its radiance and the number of rays traced for it.
pub(crate) fn sample_pixel(
    tracer: &(impl ClosestHit + ?Sized),
    materials: &[Material],
    emitters: &Emitters,
    camera: &Pinhole,
    settings: &SampleSettings,
    (x, y, width): (u32, u32, u32),
    sample: u32,
) -> (Vec3, u32) {
    let s = Sampler::new(settings.seed, y * width + x, sample);
    let mut ray = jittered_ray(camera, x, y, &s);
    let tris = tracer.triangles();
    let mut rays = 1;
    let Some((i, t)) = tracer.closest_hit(&ray, f32::INFINITY) else {
        let background = match settings.lighting {
            Lighting::Path { .. } if emitters.is_empty() => sky(ray.dir),
            _ => Vec3::ZERO,
        };
        return (background, rays);
    };
    match settings.lighting {
        Lighting::Ao { samples, distance } => {
            let n = facing_normal(&tris[i], ray.dir);
            let origin = ray.at(t) + n * settings.offset;
            let mut open = 0;
            for k in 0..samples {
                let d = cosine_direction(
                    n,
                    s.get(bounce_dim(0) + 2 * k),
                    s.get(bounce_dim(0) + 2 * k + 1),
                );
                open += !tracer.occluded(&Ray::new(origin, d), distance) as u32;
            }
            rays += samples;
            (Vec3::splat(open as f32 / samples.max(1) as f32), rays)
        }
        Lighting::Shadow { light } => {
            let tri = &tris[i];
            let m = &materials[tri.material as usize];
            let n = facing_normal(tri, ray.dir);
            let p = ray.at(t);
            let origin = p + n * settings.offset;
            let (l, reach) = match light {
                Light::Directional(d) => (d.normalize(), f32::INFINITY),
                Light::Point(q) => {
                    let w = q - origin;
                    (w.normalize(), w.length())
                }
            };
            let cos = n.dot(l);
            let lit = cos > 0.0 && {
                rays += 1;
                !tracer.occluded(&Ray::new(origin, l), reach)
            };
            let direct = if lit { cos } else { 0.0 };
            let shade = SHADOW_AMBIENT + (1.0 - SHADOW_AMBIENT) * direct;
            (Vec3::from(m.albedo) * shade + Vec3::from(m.emission), rays)
        }
        Lighting::Path { max_bounces } => {
            let mut radiance = Vec3::ZERO;
            let mut throughput = Vec3::ONE;
            let mut hit = Some((i, t));
            let mut bounce = 0;
            loop {
                let Some((i, t)) = hit else {
                    if emitters.is_empty() {
                        radiance += throughput * sky(ray.dir);
                    }
                    break;
                };
                let tri = &tris[i];
                let m = &materials[tri.material as usize];
                let n = facing_normal(tri, ray.dir);
                if bounce == 0 {
                    // Later bounces reach emitters through next-event estimation instead.
                    radiance += throughput * Vec3::from(m.emission);
                }
                let origin = ray.at(t) + n * settings.offset;
                let albedo = Vec3::from(m.albedo);
                let dim = bounce_dim(bounce);
                if !emitters.is_empty() {
                    let e = &tris[emitters.triangles[emitters.pick(s.get(dim))] as usize];
                    let q = triangle_point(
                        Vec3::from(e.v0),
                        Vec3::from(e.v1),
                        Vec3::from(e.v2),
                        s.get(dim + 1),
                        s.get(dim + 2),
                    );
                    let w = q - origin;
                    let d2 = w.length_squared();
                    let l = w / d2.sqrt();
                    let cos_here = n.dot(l);
                    let cos_there = facing_normal(e, l).dot(-l);
                    if cos_here > 0.0 && cos_there > 0.0 {
                        rays += 1;
                        if !tracer.occluded(&Ray::new(origin, l), d2.sqrt() * (1.0 - 1e-4)) {
                            let le = Vec3::from(materials[e.material as usize].emission);
                            radiance += throughput * albedo / PI
                                * le
                                * (cos_here * cos_there / d2 * emitters.total_area);
                        }
                    }
                }
                if bounce == max_bounces {
                    break;
                }
                throughput *= albedo;
                if bounce >= ROULETTE_AFTER {
                    let keep = throughput.max_element().min(0.95);
                    if s.get(dim + 3) >= keep {
                        break;
                    }
                    throughput /= keep;
                }
                ray = Ray::new(origin, cosine_direction(n, s.get(dim + 4), s.get(dim + 5)));
                rays += 1;
                hit = tracer.closest_hit(&ray, f32::INFINITY);
                bounce += 1;
            }
            (radiance, rays)
        }
    }
}

/// Per-pixel sums of radiance with their sample counts, and the rays traced for them.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Red, green, blue sums and the number of samples, per pixel, row-major.
    pub pixels: Vec<[f32; 4]>,
    /// Rays traced for these sums (camera, occlusion and bounce rays).
    pub rays: u64,
}

impl Accumulation {
    /// A `width` x `height` accumulation with no samples.
    pub fn new(width: u32, height: u32) -> Self {
        Accumulation {
            width,
            height,
            pixels: vec![[0.0; 4]; width as usize * height as usize],
            rays: 0,
        }
    }

    /// Mean radiance per pixel (black where no sample was taken).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.pixels
            .iter()
            .map(|p| {
                if p[3] > 0.0 {
                    [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }
}

/// Samples `spp` of every pixel on the host (rayon over rows). `stop`, once set, ends the
/// work after the rows under way; each pixel keeps the samples it got.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_samples(
    tracer: &(impl ClosestHit + ?Sized),
    materials: &[Material],
    emitters: &Emitters,
    camera: &Pinhole,
    width: u32,
    settings: &SampleSettings,
    samples: std::ops::Range<u32>,
    accumulation: &mut Accumulation,
    stop: &AtomicBool,
) {
    let w = width as usize;
    let rays: u64 = accumulation
        .pixels
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            if stop.load(Ordering::Relaxed) {
                return 0;
            }
            let mut rays = 0u64;
            for (x, px) in row.iter_mut().enumerate() {
                for s in samples.clone() {
                    let (l, r) = sample_pixel(
                        tracer,
                        materials,
                        emitters,
                        camera,
                        settings,
                        (x as u32, y as u32, width),
                        s,
                    );
                    px[0] += l.x;
                    px[1] += l.y;
                    px[2] += l.z;
                    px[3] += 1.0;
                    rays += r as u64;
                }
            }
            rays
        })
        .sum();
    accumulation.rays += rays;
}
