//! The progressive shade modes on the host: ambient occlusion, a light with hard shadows,
//! and a path tracer through the scattering models of [`super::bsdf`], light samples and
//! BSDF samples weighed by multiple importance sampling. Each sample of each pixel is a
//! pure function of (seed, pixel, sample), mirrored by the kernels of cl/integrator.cl, so the
//! host is the reference the devices are compared with.

use std::f32::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::{BSDF_DIFFUSE, BsdfSample, Shading, basis};
use super::sampling::{
    LENS_DIM, Sampler, bounce_dim, cosine_direction, disk_point, triangle_point,
};
use crate::camera::Pinhole;
use crate::geometry::Ray;
use crate::intersect::ClosestHit;
use crate::intersect::{TRIANGLE_TWO_SIDED, Triangle};
use crate::light::{Lights, Punctual, punctual};
use crate::material::Material;
use crate::material::surface::{BOUNCE_CONE_SPREAD, Surface};

/// Share of the light in `shadow` mode that reaches surfaces the light does not.
pub const SHADOW_AMBIENT: f32 = 0.1;
/// Bounces after which Russian roulette may end a path.
pub const ROULETTE_AFTER: u32 = 3;
/// Each sample's radiance is added as a fixed-point number with this many units per 1
/// (2^20): integer sums are exact and do not depend on the order they are added in, so a
/// render split into tiles, sample ranges or devices and merged equals the one-shot render
/// bit for bit. The step, about 1e-6, is below what an 8-bit or half-float image resolves.
pub const RADIANCE_SCALE: f32 = 1_048_576.0;
/// A sample's radiance is clamped to this (2^22) before it is added, so that 65,536
/// samples of it (the most a pixel takes) still fit the 64-bit sums; NaN adds 0.
pub const MAX_SAMPLE_RADIANCE: f32 = 4_194_304.0;

/// One component of a sample's radiance as it is added to the sums (the kernels'
/// `to_fixed`): clamped to [0, [`MAX_SAMPLE_RADIANCE`]] (NaN to 0), scaled by
/// [`RADIANCE_SCALE`] (exact: a power of two) and rounded to the nearest, ties to even.
pub fn to_fixed(v: f32) -> i64 {
    let v = if v >= 0.0 {
        v.min(MAX_SAMPLE_RADIANCE)
    } else {
        0.0
    };
    (v * RADIANCE_SCALE).round_ties_even() as i64
}

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
    /// Path tracing: next-event estimation to emitting triangles where there are
    /// any, a sky otherwise, Russian roulette after a few bounces.
    Path {
        /// Bounces after the first hit, at most; 0 lights the first hit only (by a light
        /// sample, and by a sampled direction traced for the emitter it hits).
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
/// and the cumulative distribution of their power (area times mean emission), so that a
/// dim emitter beside a bright one takes few light samples (pbrt's power light sampler).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Emitters {
    pub(crate) triangles: Vec<u32>,
    /// `cdf[i]`: the power of emitters 0..=i over the total, the last one exactly 1.
    pub(crate) cdf: Vec<f32>,
    /// The emitters' power: their areas times their materials' mean emission, summed.
    pub(crate) total_power: f32,
}

/// The density per area with which light samples pick a point of an emitter of material
/// `m`: its power per area over all emitters' (`emitter_density` in cl/integrator.cl).
pub(crate) fn emitter_density(m: &Material, total_power: f32) -> f32 {
    let le = m.emission;
    (le[0] + le[1] + le[2]) * (1.0 / 3.0) / total_power
}

impl Emitters {
    pub(crate) fn new(triangles: &[Triangle], materials: &[Material]) -> Self {
        // On every core: a scene of hundreds of millions of triangles took a second here.
        use rayon::prelude::*;
        let (list, powers): (Vec<u32>, Vec<f64>) = triangles
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .filter_map(|(i, t)| {
                let m = &materials[t.material as usize];
                if !m.emits() {
                    return None;
                }
                let area = 0.5
                    * (Vec3::from(t.v1) - Vec3::from(t.v0))
                        .cross(Vec3::from(t.v2) - Vec3::from(t.v0))
                        .length();
                let le = m.emission;
                let power = area as f64 * (le[0] + le[1] + le[2]) as f64 / 3.0;
                (power > 0.0).then_some((i as u32, power))
            })
            .unzip();
        let total: f64 = powers.iter().sum();
        let mut acc = 0.0;
        let mut cdf: Vec<f32> = powers
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
            total_power: total as f32,
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The emitter whose CDF interval holds `u` (binary search, as the kernel does).
    pub(crate) fn pick(&self, u: f32) -> usize {
        crate::light::environment::cdf_find(&self.cdf, u)
    }
}

/// The sky seen by rays that leave a scene without emitters or other lights: white at the
/// horizon, blue overhead, grey below.
pub(crate) fn sky(d: Vec3) -> Vec3 {
    let up = d.y / d.length();
    if up >= 0.0 {
        Vec3::ONE.lerp(Vec3::new(0.45, 0.65, 1.0), up)
    } else {
        Vec3::ONE.lerp(Vec3::splat(0.35), -up)
    }
}

/// The ray of pixel (x, y), jittered within the pixel by the sampler's first two numbers
/// and, with an open lens, from the lens point of dimensions [`LENS_DIM`] on (the kernels'
/// `jittered_ray`).
pub(crate) fn jittered_ray(camera: &Pinhole, x: u32, y: u32, s: &Sampler) -> Ray {
    let fx = x as f32 + s.get(0);
    let fy = y as f32 + s.get(1);
    if !camera.has_lens() {
        return camera.ray_at(fx, fy);
    }
    camera.lens_ray(fx, fy, disk_point(s, LENS_DIM))
}

/// The camera ray of one sample of pixel (x, y), as the progressive modes trace it:
/// jittered within the pixel and through the lens (for tests comparing it with the
/// kernels').
pub fn sample_ray(camera: &Pinhole, (x, y, width): (u32, u32, u32), seed: u32, sample: u32) -> Ray {
    jittered_ray(camera, x, y, &Sampler::new(seed, y * width + x, sample))
}

/// `emitting_normal` in cl/integrator.cl: the unit normal along which emitter `t` shines
/// towards a point in direction `-dir` from it: its front face's, or for a two-sided
/// emitter ([`TRIANGLE_TWO_SIDED`]) the one facing `dir`'s origin side.
pub(crate) fn emitting_normal(t: &Triangle, dir: Vec3) -> Vec3 {
    let v0 = Vec3::from(t.v0);
    let n = (Vec3::from(t.v1) - v0)
        .cross(Vec3::from(t.v2) - v0)
        .normalize();
    if t.flags & TRIANGLE_TWO_SIDED != 0 && n.dot(dir) > 0.0 {
        -n
    } else {
        n
    }
}

/// The closest hit of `ray` in `(0, t_max)` (or any hit) that `surface`'s cut-out masks
/// let through, as the kernels' traversals find it.
pub(crate) fn trace_masked(
    tracer: &(impl ClosestHit + ?Sized),
    surface: &Surface,
    ray: &Ray,
    t_max: f32,
    any_hit: bool,
) -> Option<(usize, f32)> {
    let tris = tracer.triangles();
    tracer.trace_filtered(ray, t_max, any_hit, &|i, r| surface.mask_keeps(&tris[i], r))
}

/// The width of a camera ray's cone at ray parameter `t` of the unnormalised pixel ray:
/// `camera_cone` in cl/integrator.cl.
fn camera_cone(camera: &Pinhole, t: f32) -> f32 {
    let d = camera.du;
    t * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Whether the path tracer weighs light and BSDF samples against each other (`MIS` in
/// cl/integrator.cl): for scenes with other models than Lambert, or an environment (whose
/// wide lobes light samples alone find poorly). Else emitters are found by light samples
/// alone after the camera ray.
pub(crate) fn weighs_samples(surface: &Surface, lights: &Lights) -> bool {
    surface.features().bsdfs() || lights.environment.is_some()
}

/// `scatter_from` in cl/integrator.cl: what the shading point scatters towards the eye of
/// light from unit direction `l`, per unit of irradiance, and the density with which BSDF
/// sampling picks `l`.
fn scatter_from(sh: &Shading, lambert: bool, frame: [Vec3; 3], wo_l: Vec3, l: Vec3) -> (Vec3, f32) {
    let [tn, bn, n] = frame;
    if lambert {
        let cos_here = n.dot(l).max(0.0);
        return (sh.albedo * (cos_here / PI), cos_here / PI);
    }
    sh.eval(wo_l, Vec3::new(l.dot(tn), l.dot(bn), l.dot(n)))
}

/// One sample of pixel (x, y): its radiance and the number of rays traced for it. `mis`:
/// [`weighs_samples`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_pixel(
    tracer: &(impl ClosestHit + ?Sized),
    surface: &Surface,
    emitters: &Emitters,
    lights: &Lights,
    mis: bool,
    camera: &Pinhole,
    settings: &SampleSettings,
    (x, y, width): (u32, u32, u32),
    sample: u32,
) -> (Vec3, u32) {
    let s = Sampler::new(settings.seed, y * width + x, sample);
    let mut ray = jittered_ray(camera, x, y, &s);
    let tris = tracer.triangles();
    let occluded =
        |ray: &Ray, t_max: f32| trace_masked(tracer, surface, ray, t_max, true).is_some();
    let mut rays = 1;
    // What a path tracer's ray that leaves the scene sees, and the density with which
    // light samples find it (0 for the default sky, which they do not sample).
    let background = |d: Vec3| match &lights.environment {
        Some(env) => env.radiance(d.normalize()),
        None if emitters.is_empty() && lights.punctual.is_empty() => (sky(d), 0.0),
        None => (Vec3::ZERO, 0.0),
    };
    let Some((i, t)) = trace_masked(tracer, surface, &ray, f32::INFINITY, false) else {
        let background = match settings.lighting {
            Lighting::Path { .. } => background(ray.dir).0,
            _ => Vec3::ZERO,
        };
        return (background, rays);
    };
    let hit_point = |i: usize, ray: &Ray, t: f32, cone: f32| {
        surface.point(&tris[i], (ray.origin, ray.dir), t, settings.offset, cone)
    };
    match settings.lighting {
        Lighting::Ao { samples, distance } => {
            let sp = hit_point(i, &ray, t, camera_cone(camera, t));
            let mut open = 0;
            for k in 0..samples {
                let d = cosine_direction(
                    sp.ns,
                    s.get(bounce_dim(0) + 2 * k),
                    s.get(bounce_dim(0) + 2 * k + 1),
                );
                let ng = sp.ng;
                open += (d.x * ng.x + d.y * ng.y + d.z * ng.z > 0.0
                    && !occluded(&Ray::new(sp.origin, d), distance)) as u32;
            }
            rays += samples;
            (Vec3::splat(open as f32 / samples.max(1) as f32), rays)
        }
        Lighting::Shadow { light } => {
            let sp = hit_point(i, &ray, t, camera_cone(camera, t));
            let origin = sp.origin;
            let (l, reach) = match light {
                Light::Directional(d) => (d.normalize(), f32::INFINITY),
                Light::Point(q) => {
                    let w = q - origin;
                    (w.normalize(), w.length())
                }
            };
            let cos = sp.ns.dot(l);
            let ng = sp.ng;
            let lit = cos > 0.0 && l.x * ng.x + l.y * ng.y + l.z * ng.z > 0.0 && {
                rays += 1;
                !occluded(&Ray::new(origin, l), reach)
            };
            let direct = if lit { cos } else { 0.0 };
            let shade = SHADOW_AMBIENT + (1.0 - SHADOW_AMBIENT) * direct;
            (sp.albedo * shade + sp.emission, rays)
        }
        Lighting::Path { max_bounces } => {
            let mut radiance = Vec3::ZERO;
            let mut throughput = Vec3::ONE;
            let mut hit = Some((i, t));
            let mut bounce = 0;
            let mut cone = 0.0;
            // The density of the last bounce's direction, for the power heuristic; 0 where
            // light sampling could not have found what it hits (see cl/integrator.cl).
            let mut last_pdf = 0.0f32;
            loop {
                let Some((i, t)) = hit else {
                    let (mut le, env_pdf) = background(ray.dir);
                    // Weighed against the environment's light samples, which could have
                    // found it.
                    if last_pdf > 0.0 {
                        let r = env_pdf / last_pdf;
                        le *= 1.0 / (1.0 + r * r);
                    }
                    radiance += throughput * le;
                    break;
                };
                cone = match bounce {
                    0 => camera_cone(camera, t),
                    _ => cone + BOUNCE_CONE_SPREAD * t,
                };
                let sp = hit_point(i, &ray, t, cone);
                if !mis {
                    // Emitters are reached by light samples alone after the camera ray.
                    if bounce == 0 {
                        radiance += throughput * sp.emission;
                    }
                } else if last_pdf > 0.0 && sp.emission.max_element() > 0.0 {
                    let ng = sp.ng;
                    let cos = (ng.x * ray.dir.x + ng.y * ray.dir.y + ng.z * ray.dir.z).abs();
                    let density =
                        emitter_density(&surface.material(&tris[i]), emitters.total_power);
                    let r = t * t * density / cos / last_pdf;
                    radiance += throughput * sp.emission * (1.0 / (1.0 + r * r));
                } else if last_pdf == 0.0 {
                    radiance += throughput * sp.emission;
                }
                // The last bounce's direction was traced only for the emitter it might hit.
                if bounce > max_bounces {
                    break;
                }
                let sh = Shading::at(&surface.material(&tris[i]), &sp);
                let lambert = !mis || (sh.bsdf == BSDF_DIFFUSE && sh.metallic <= 0.0);
                let (origin, n, ng) = (sp.origin, sp.ns, sp.ng);
                let (tn, bn) = basis(n);
                let wo = -ray.dir.normalize();
                let local = |v: Vec3| Vec3::new(v.dot(tn), v.dot(bn), v.dot(n));
                let wo_l = local(wo);
                let side = |d: Vec3| d.x * ng.x + d.y * ng.y + d.z * ng.z;
                let dim = bounce_dim(bounce);
                let frame = [tn, bn, n];
                let lit = !sh.all_delta();
                if !emitters.is_empty() && lit {
                    let e = &tris[emitters.triangles[emitters.pick(s.get(dim))] as usize];
                    let (u1, u2) = (s.get(dim + 1), s.get(dim + 2));
                    let q = triangle_point(
                        Vec3::from(e.v0),
                        Vec3::from(e.v1),
                        Vec3::from(e.v2),
                        u1,
                        u2,
                    );
                    let w = q - origin;
                    let d2 = w.length_squared();
                    let l = w / d2.sqrt();
                    let cos_there = emitting_normal(e, l).dot(-l);
                    if cos_there > 0.0 && side(l) > 0.0 {
                        let (f, bsdf_pdf) = scatter_from(&sh, lambert, frame, wo_l, l);
                        if f.max_element() > 0.0 {
                            rays += 1;
                            if !occluded(&Ray::new(origin, l), d2.sqrt() * (1.0 - 1e-4)) {
                                let su = u1.sqrt();
                                let le = surface.emitted(e, 1.0 - su, u2 * su);
                                let density =
                                    emitter_density(&surface.material(e), emitters.total_power);
                                let light_pdf = d2 * density / cos_there;
                                let r = bsdf_pdf / light_pdf;
                                let weight = if mis { 1.0 / (1.0 + r * r) } else { 1.0 };
                                radiance += throughput * f * le * (weight / light_pdf);
                            }
                        }
                    }
                }
                if let Some(env) = lights.environment.as_ref().filter(|_| lit) {
                    let (l, le, env_pdf) = env.sample(s.get(dim + 8), s.get(dim + 9));
                    if env_pdf > 0.0 && side(l) > 0.0 {
                        let (f, bsdf_pdf) = scatter_from(&sh, lambert, frame, wo_l, l);
                        if f.max_element() > 0.0 {
                            rays += 1;
                            if !occluded(&Ray::new(origin, l), f32::INFINITY) {
                                let r = bsdf_pdf / env_pdf;
                                radiance += throughput * f * le * (1.0 / (1.0 + r * r) / env_pdf);
                            }
                        }
                    }
                }
                // Every punctual light, each by one shadow ray: nothing else can find them.
                for light in lights.punctual.iter().filter(|_| lit).map(Punctual::pack) {
                    let (l, reach, e) = punctual::incident(&light, origin);
                    if e.max_element() > 0.0 && side(l) > 0.0 {
                        let (f, _) = scatter_from(&sh, lambert, frame, wo_l, l);
                        if f.max_element() > 0.0 {
                            rays += 1;
                            if !occluded(&Ray::new(origin, l), reach * (1.0 - 1e-4)) {
                                radiance += throughput * f * e;
                            }
                        }
                    }
                }
                if !mis && bounce == max_bounces {
                    break;
                }
                let (u1, u2) = (s.get(dim + 4), s.get(dim + 5));
                let bs = if lambert {
                    let wi = cosine_direction(n, u1, u2);
                    BsdfSample {
                        wi,
                        weight: sh.albedo,
                        pdf: wi.dot(n).max(0.0) / PI,
                        delta: false,
                        transmitted: false,
                    }
                } else {
                    let Some(mut bs) = sh.sample(wo_l, s.get(dim + 6), u1, u2, s.get(dim + 7))
                    else {
                        break;
                    };
                    bs.wi = tn * bs.wi.x + bn * bs.wi.y + n * bs.wi.z;
                    bs
                };
                throughput *= bs.weight;
                if bounce >= ROULETTE_AFTER {
                    let keep = throughput.max_element().min(0.95);
                    if s.get(dim + 3) >= keep {
                        break;
                    }
                    throughput /= keep;
                }
                // A reflected direction below the geometric surface would leave through
                // it, a refracted one above it would not.
                let cos = side(bs.wi);
                if (bs.transmitted && cos >= 0.0) || (!bs.transmitted && cos <= 0.0) {
                    break;
                }
                let from = if bs.transmitted { sp.through } else { origin };
                ray = Ray::new(from, bs.wi);
                last_pdf = if bs.delta || bs.transmitted {
                    0.0
                } else {
                    bs.pdf
                };
                rays += 1;
                hit = trace_masked(tracer, surface, &ray, f32::INFINITY, false);
                bounce += 1;
            }
            (radiance, rays)
        }
    }
}

/// A rectangle of an image's pixels: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Region {
    /// The first column.
    pub x0: u32,
    /// The first row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Region {
    /// The whole of a `width` x `height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Region {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels.
    pub fn pixels(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    /// Whether the two share a pixel.
    pub fn overlaps(&self, other: &Region) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }
}

impl std::str::FromStr for Region {
    type Err = String;

    /// `x0,y0,x1,y1`: columns x0..x1 and rows y0..y1, in pixels, the ends exclusive.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not a region: use x0,y0,x1,y1 (pixels, ends exclusive)");
        let v: Vec<u32> = s
            .split(',')
            .map(|c| c.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        let [x0, y0, x1, y1] = v[..] else {
            return Err(bad());
        };
        if x0 >= x1 || y0 >= y1 {
            return Err(format!(
                "region `{s}` is empty: x0 < x1 and y0 < y1 are needed (the ends are exclusive)"
            ));
        }
        Ok(Region { x0, y0, x1, y1 })
    }
}

/// Parses `FIRST..END`, a range of sample indices, END exclusive and above FIRST.
pub fn parse_sample_range(s: &str) -> Result<std::ops::Range<u32>, String> {
    let bad = || format!("`{s}` is not a sample range: use FIRST..END (END exclusive), e.g. 0..64");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b) = (
        a.trim().parse::<u32>().map_err(|_| bad())?,
        b.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if a >= b {
        return Err(format!(
            "sample range `{s}` is empty: END must be above FIRST"
        ));
    }
    Ok(a..b)
}

impl std::fmt::Display for Region {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// Per-pixel sums of radiance with their sample counts over a region of an image, and the
/// rays traced for them. The sums are fixed-point ([`to_fixed`]), so adding two
/// accumulations is exact.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    /// The image the region is part of (the camera's size): its width fixes each pixel's
    /// random numbers.
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// The pixels these sums are of.
    pub region: Region,
    /// Red, green, blue sums (fixed-point) and the number of samples, per pixel of the
    /// region, row-major.
    pub pixels: Vec<[i64; 4]>,
    /// Rays traced for these sums (camera, occlusion and bounce rays).
    pub rays: u64,
}

impl Accumulation {
    /// A `width` x `height` accumulation with no samples.
    pub fn new(width: u32, height: u32) -> Self {
        Self::of_region(width, height, Region::whole(width, height))
    }

    /// An accumulation of `region` of a `width` x `height` image, with no samples.
    pub fn of_region(width: u32, height: u32, region: Region) -> Self {
        assert!(
            region.x0 <= region.x1 && region.x1 <= width && region.y0 <= region.y1,
            "region {region} outside a {width}x{height} image"
        );
        assert!(
            region.y1 <= height,
            "region {region} outside {width}x{height}"
        );
        Accumulation {
            width,
            height,
            region,
            pixels: vec![[0; 4]; region.pixels()],
            rays: 0,
        }
    }

    /// The image's size, (width, height).
    pub fn image_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Adds `part`'s sums, counts and rays (of a region inside this one's) into this
    /// accumulation; `None`, with the sums partly added, if a sum would overflow.
    pub(crate) fn add(&mut self, part: &Accumulation) -> Option<()> {
        use rayon::prelude::*;
        let (r, p) = (self.region, part.region);
        let w = p.width() as usize;
        if w > 0 {
            let x = (p.x0 - r.x0) as usize;
            // Row by row on every core: a 4K frame is 33 million sums.
            self.pixels
                .par_chunks_mut(r.width() as usize)
                .skip((p.y0 - r.y0) as usize)
                .zip(part.pixels.par_chunks(w))
                .try_for_each(|(row, src)| {
                    for (d, s) in row[x..x + w].iter_mut().zip(src) {
                        for c in 0..4 {
                            d[c] = d[c].checked_add(s[c])?;
                        }
                    }
                    Some(())
                })?;
        }
        self.rays += part.rays;
        Some(())
    }

    /// Mean radiance per pixel of the region (black where no sample was taken).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        use rayon::prelude::*;
        self.pixels
            .par_iter()
            .with_min_len(4096)
            .map(mean_radiance)
            .collect()
    }
}

/// Adds a sample to a pixel's sums, as the kernels' `add_sample` does.
fn add_sample(px: &mut [i64; 4], l: Vec3) {
    px[0] += to_fixed(l.x);
    px[1] += to_fixed(l.y);
    px[2] += to_fixed(l.z);
    px[3] += 1;
}

/// The mean radiance of a pixel's sums (black without samples).
pub fn mean_radiance(p: &[i64; 4]) -> [f32; 3] {
    if p[3] > 0 {
        let n = p[3] as f64 * RADIANCE_SCALE as f64;
        [0, 1, 2].map(|c| (p[c] as f64 / n) as f32)
    } else {
        [0.0; 3]
    }
}

/// Samples `samples` of every pixel of the accumulation's region on the host (rayon over
/// rows). `stop`, once set, ends the work after the rows under way; each pixel keeps the
/// samples it got.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_samples(
    tracer: &(impl ClosestHit + ?Sized),
    surface: &Surface,
    emitters: &Emitters,
    lights: &Lights,
    camera: &Pinhole,
    settings: &SampleSettings,
    samples: std::ops::Range<u32>,
    accumulation: &mut Accumulation,
    stop: &AtomicBool,
) {
    let region = accumulation.region;
    let width = accumulation.width;
    let mis = weighs_samples(surface, lights);
    let rays: u64 = accumulation
        .pixels
        .par_chunks_mut(region.width().max(1) as usize)
        .enumerate()
        .map(|(row, pixels)| {
            if stop.load(Ordering::Relaxed) {
                return 0;
            }
            let y = region.y0 + row as u32;
            let mut rays = 0u64;
            for (col, px) in pixels.iter_mut().enumerate() {
                let x = region.x0 + col as u32;
                for s in samples.clone() {
                    let (l, r) = sample_pixel(
                        tracer,
                        surface,
                        emitters,
                        lights,
                        mis,
                        camera,
                        settings,
                        (x, y, width),
                        s,
                    );
                    add_sample(px, l);
                    rays += r as u64;
                }
            }
            rays
        })
        .sum();
    accumulation.rays += rays;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn to_fixed_clamps_rounds_to_even_and_takes_nan_as_zero() {
        assert_eq!(to_fixed(1.0), 1 << 20);
        assert_eq!(to_fixed(0.5 / RADIANCE_SCALE), 0, "a tie rounds to even: 0");
        assert_eq!(to_fixed(1.5 / RADIANCE_SCALE), 2, "a tie rounds to even: 2");
        assert_eq!(to_fixed(-3.0), 0);
        assert_eq!(to_fixed(f32::NAN), 0);
        assert_eq!(to_fixed(f32::INFINITY), 1 << 42);
        assert_eq!(to_fixed(1e30), 1 << 42);
        // The largest sum a pixel can reach still fits.
        assert!((1i64 << 42).checked_mul(65536).is_some());
    }

    #[test]
    fn sums_do_not_depend_on_the_order_they_are_added_in() {
        let values: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::splat(((i * 7919) % 1000) as f32 * 1.37e-3 + 1e-7))
            .collect();
        let mut forward = [0i64; 4];
        let mut backward = [0i64; 4];
        let (mut halves_a, mut halves_b) = ([0i64; 4], [0i64; 4]);
        for v in &values {
            add_sample(&mut forward, *v);
        }
        for v in values.iter().rev() {
            add_sample(&mut backward, *v);
        }
        for v in &values[..313] {
            add_sample(&mut halves_a, *v);
        }
        for v in &values[313..] {
            add_sample(&mut halves_b, *v);
        }
        let merged: Vec<i64> = (0..4).map(|c| halves_a[c] + halves_b[c]).collect();
        assert_eq!(forward, backward);
        assert_eq!(forward.to_vec(), merged);
        let mean = mean_radiance(&forward)[0] as f64;
        let exact = values.iter().map(|v| v.x as f64).sum::<f64>() / 1000.0;
        assert!((mean - exact).abs() < 1e-6, "{mean} vs {exact}");
    }

    #[test]
    fn regions_and_sample_ranges_parse_or_say_why_not() {
        let r: Region = "1,2,30,40".parse().unwrap();
        assert_eq!((r.x0, r.y0, r.x1, r.y1), (1, 2, 30, 40));
        assert_eq!(r.to_string(), "1,2,30,40");
        for bad in ["1,2,3", "a,b,c,d", "5,0,5,9", "0,-1,4,4", ""] {
            assert!(bad.parse::<Region>().is_err(), "{bad}");
        }
        assert_eq!(parse_sample_range("0..64").unwrap(), 0..64);
        for bad in ["64..0", "3..3", "0-64", "..4", "a..b"] {
            assert!(parse_sample_range(bad).is_err(), "{bad}");
        }
    }
}
