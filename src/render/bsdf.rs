//! The scattering models of [`Bsdf`], the host's version of cl/bsdf.cl: evaluation (for
//! light samples), sampling (for the next bounce) and the density of each, so that the
//! path tracer can weigh light and BSDF samples against each other (multiple importance
//! sampling). Directions are in a frame about the shading normal (z up), both pointing
//! away from the surface: `wo` towards where the light goes (the viewer), `wi` towards
//! where it comes from.
//!
//! Models: Lambert; GGX microfacets (Trowbridge-Reitz, alpha = roughness²) sampled by
//! their visible normals (Heitz 2018, "Sampling the GGX distribution of visible normals")
//! with the height-correlated masking-shadowing term, for conductors (exact Fresnel of a
//! complex index, or Schlick's from a colour), rough dielectrics (Walter et al. 2007,
//! reflection and refraction, total internal reflection) and a plastic's coating over a
//! Lambertian base; smooth (delta) versions below [`SMOOTH_ROUGHNESS`]; a thin dielectric
//! sheet; and glTF's metalness as a blend with a Schlick metal of the base colour.

use std::f32::consts::PI;

use glam::Vec3;

use crate::material::surface::SurfacePoint;
use crate::material::{Bsdf, Material};

/// Perceptual roughness below which a microfacet model is a perfect mirror or refractor
/// (alpha below 1e-3): GGX that sharp has densities beyond single precision.
pub const SMOOTH_ROUGHNESS: f32 = 0.03;

/// [`Bsdf::Diffuse`]'s code as the kernels name it.
pub const BSDF_DIFFUSE: u32 = Bsdf::Diffuse.code();
/// [`Bsdf::Conductor`]'s code.
pub const BSDF_CONDUCTOR: u32 = Bsdf::Conductor.code();
/// [`Bsdf::Dielectric`]'s code.
pub const BSDF_DIELECTRIC: u32 = Bsdf::Dielectric.code();
/// [`Bsdf::ThinDielectric`]'s code.
pub const BSDF_THIN_DIELECTRIC: u32 = Bsdf::ThinDielectric.code();
/// [`Bsdf::Plastic`]'s code.
pub const BSDF_PLASTIC: u32 = Bsdf::Plastic.code();

/// A material at one hit, as the models read it (`Shading` in cl/bsdf.cl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// A [`Bsdf`] code.
    pub bsdf: u32,
    /// Base colour (textured).
    pub albedo: Vec3,
    /// Tint of the specular part ([`crate::material::Material::specular`]).
    pub specular: Vec3,
    /// Conductor's complex index of refraction, real part; `eta.x == 0` for Schlick's
    /// from the base colour.
    pub eta: Vec3,
    /// Its imaginary part.
    pub k: Vec3,
    /// Index of refraction across the surface, the far side's over the near side's.
    pub ior: f32,
    /// GGX alpha (roughness squared).
    pub alpha: f32,
    /// Share of the Schlick metal of the base colour, in [0, 1].
    pub metallic: f32,
}

/// What sampling found: the direction, the estimator's weight (`f · |cos| / pdf`), the
/// density (0 for a delta lobe), and whether the light passed through the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The direction the light comes from.
    pub wi: Vec3,
    /// `f · |cos| / pdf`.
    pub weight: Vec3,
    /// The density of `wi` (solid angle); 0 for a delta lobe.
    pub pdf: f32,
    /// Whether a delta lobe (mirror, refraction) gave `wi`.
    pub delta: bool,
    /// Whether `wi` is on the far side of the surface.
    pub transmitted: bool,
}

impl Shading {
    /// `shading_at` in cl/bsdf.cl: material `m` at the hit `sp`.
    pub fn at(m: &Material, sp: &SurfacePoint) -> Shading {
        Shading {
            bsdf: m.bsdf,
            albedo: sp.albedo,
            specular: Vec3::from(m.specular),
            eta: Vec3::from(m.eta),
            k: Vec3::from(m.k),
            ior: if m.bsdf == BSDF_DIELECTRIC && !sp.front_face {
                1.0 / m.ior
            } else {
                m.ior
            },
            alpha: sp.roughness * sp.roughness,
            // NaN as 0.
            metallic: if sp.metallic > 0.0 {
                sp.metallic.min(1.0)
            } else {
                0.0
            },
        }
    }

    /// Whether the perceptual roughness makes the microfacet lobes mirrors.
    pub fn smooth(&self) -> bool {
        self.alpha < SMOOTH_ROUGHNESS * SMOOTH_ROUGHNESS
    }

    /// Whether every lobe is a delta lobe: light samples cannot reach it.
    pub fn all_delta(&self) -> bool {
        let smooth = self.smooth();
        let base = self.bsdf == BSDF_THIN_DIELECTRIC
            || (smooth && (self.bsdf == BSDF_CONDUCTOR || self.bsdf == BSDF_DIELECTRIC));
        base && (self.metallic <= 0.0 || smooth)
    }

    /// The chance of sampling the plastic's coating rather than its base, from `wo`.
    fn coating_share(&self, cos_o: f32) -> f32 {
        let f = fresnel_dielectric(cos_o, self.ior);
        let s = f * self.specular.max_element();
        let d = (1.0 - f) * self.albedo.max_element();
        if s + d > 0.0 { s / (s + d) } else { 1.0 }
    }

    /// The share of the plastic's Lambertian base that comes out between `wi` and `wo`
    /// (cosines): through the coating in and out, the light that the coating's underside
    /// reflects back summed (Mitsuba 3's `plastic`, linear: a base colour of 1 scatters
    /// about all the light the coating lets in).
    fn plastic_base(&self, cos_o: f32, cos_i: f32) -> f32 {
        let eta = self.ior;
        let through =
            (1.0 - fresnel_dielectric(cos_i, eta)) * (1.0 - fresnel_dielectric(cos_o, eta));
        through / (eta * eta * (1.0 - fresnel_diffuse_reflectance(1.0 / eta)))
    }

    /// The conductor Fresnel of the base model at cosine `c`.
    fn conductor_fresnel(&self, c: f32) -> Vec3 {
        if self.eta.x > 0.0 {
            fresnel_conductor(c, self.eta, self.k) * self.specular
        } else {
            schlick(self.albedo * self.specular, c)
        }
    }

    /// `f · cos(wi)` and the density of sampling `wi`, over every lobe that is not a delta.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let smooth = self.smooth();
        let m = self.metallic;
        let mut f = Vec3::ZERO;
        let mut pdf = 0.0;
        if m > 0.0 && !smooth && wi.z > 0.0 {
            let (fm, pm) = microfacet_reflection(wo, wi, self.alpha, |c| schlick(self.albedo, c));
            f += fm * m;
            pdf += pm * m;
        }
        let b = 1.0 - m;
        if b <= 0.0 {
            return (f, pdf);
        }
        match self.bsdf {
            BSDF_CONDUCTOR if !smooth && wi.z > 0.0 => {
                let (fc, pc) =
                    microfacet_reflection(wo, wi, self.alpha, |c| self.conductor_fresnel(c));
                f += fc * b;
                pdf += pc * b;
            }
            BSDF_DIELECTRIC if !smooth => {
                let (fd, pd) = rough_dielectric(wo, wi, self.alpha, self.ior, self.specular);
                f += fd * b;
                pdf += pd * b;
            }
            BSDF_PLASTIC if wi.z > 0.0 => {
                let share = self.coating_share(wo.z);
                if !smooth {
                    let (fs, ps) = microfacet_reflection(wo, wi, self.alpha, |c| {
                        self.specular * fresnel_dielectric(c, self.ior)
                    });
                    f += fs * b;
                    pdf += ps * (b * share);
                }
                f += self.albedo * (self.plastic_base(wo.z, wi.z) * wi.z / PI * b);
                pdf += wi.z / PI * (b * (1.0 - share));
            }
            BSDF_DIFFUSE if wi.z > 0.0 => {
                f += self.albedo * (wi.z / PI * b);
                pdf += wi.z / PI * b;
            }
            _ => {}
        }
        (f, pdf)
    }

    /// A direction for the next bounce from four uniform numbers: `u_lobe` picks the lobe,
    /// `u1, u2` the direction in it, `u_rt` reflection or refraction. `None` where the
    /// sample is lost (below the surface, a microfacet facing away).
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u1: f32, u2: f32, u_rt: f32) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let smooth = self.smooth();
        let m = self.metallic;
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        let delta = |wi: Vec3, weight: Vec3, transmitted: bool| {
            Some(BsdfSample {
                wi,
                weight,
                pdf: 0.0,
                delta: true,
                transmitted,
            })
        };
        // A direction from a lobe that is not a delta: weighed by every such lobe.
        let mixed = |wi: Vec3| {
            let (f, pdf) = self.eval(wo, wi);
            (pdf > 0.0).then(|| BsdfSample {
                wi,
                weight: f / pdf,
                pdf,
                delta: false,
                transmitted: wi.z < 0.0,
            })
        };
        let reflect = |h: Vec3| h * (2.0 * wo.dot(h)) - wo;
        if u_lobe < m {
            if smooth {
                return delta(mirror, schlick(self.albedo, wo.z), false);
            }
            let wi = reflect(ggx_visible_normal(wo, self.alpha, u1, u2));
            return if wi.z > 0.0 { mixed(wi) } else { None };
        }
        let u = (u_lobe - m) / (1.0 - m);
        match self.bsdf {
            BSDF_CONDUCTOR => {
                if smooth {
                    return delta(mirror, self.conductor_fresnel(wo.z), false);
                }
                let wi = reflect(ggx_visible_normal(wo, self.alpha, u1, u2));
                if wi.z > 0.0 { mixed(wi) } else { None }
            }
            BSDF_DIELECTRIC => {
                if smooth {
                    let f = fresnel_dielectric(wo.z, self.ior);
                    if u_rt < f {
                        return delta(mirror, Vec3::ONE, false);
                    }
                    let wi = refract(wo, Vec3::Z, self.ior)?;
                    return delta(wi, self.specular / (self.ior * self.ior), true);
                }
                let h = ggx_visible_normal(wo, self.alpha, u1, u2);
                let f = fresnel_dielectric(wo.dot(h), self.ior);
                let wi = if u_rt < f {
                    let wi = reflect(h);
                    (wi.z > 0.0).then_some(wi)?
                } else {
                    let wi = refract(wo, h, self.ior)?;
                    (wi.z < 0.0).then_some(wi)?
                };
                mixed(wi)
            }
            BSDF_THIN_DIELECTRIC => {
                let mut r = fresnel_dielectric(wo.z, self.ior);
                if r < 1.0 {
                    // The light bounced back and forth inside the sheet, summed.
                    let t = 1.0 - r;
                    r += t * t * r / (1.0 - r * r);
                }
                if u_rt < r {
                    delta(mirror, Vec3::ONE, false)
                } else {
                    delta(-wo, self.specular, true)
                }
            }
            BSDF_PLASTIC => {
                let share = self.coating_share(wo.z);
                if u < share {
                    if smooth {
                        let f = fresnel_dielectric(wo.z, self.ior);
                        return delta(mirror, self.specular * (f / share), false);
                    }
                    let wi = reflect(ggx_visible_normal(wo, self.alpha, u1, u2));
                    return if wi.z > 0.0 { mixed(wi) } else { None };
                }
                mixed(local_cosine(u1, u2))
            }
            _ => mixed(local_cosine(u1, u2)),
        }
    }
}

/// A cosine-weighted direction about +z: the local frame's version of
/// [`super::sampling::cosine_direction`].
fn local_cosine(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// The orthonormal basis about unit `n` of Duff et al. (JCGT 2017), as
/// [`super::sampling::cosine_direction`] builds it: tangent, bitangent.
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Fresnel reflectance of unpolarised light arriving at cosine `cos_i` (> 0) from the side
/// whose index is 1 onto one of index `eta`; 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The Fresnel reflectance of a dielectric of relative index `eta` averaged over the
/// cosine-weighted hemisphere: the fits of Egan and Hilgeman (1973) below 1 and of d'Eon
/// and Irving (2011) above, as Mitsuba 3 uses them.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let i = 1.0 / eta;
        let (i2, i3) = (i * i, i * i * i);
        0.919317 - 3.4793 * i + 6.75335 * i2 - 7.80989 * i3 + 4.98554 * i2 * i2 - 1.36881 * i2 * i3
    }
}

/// Fresnel reflectance of a conductor of complex index `eta + i k`, per channel, at cosine
/// `c` (the closed form in S. Lagarde, "Memo on Fresnel equations", 2013).
pub fn fresnel_conductor(c: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c = c.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - Vec3::splat(s2);
    let a2b2 = (t0 * t0 + eta * eta * k * k * 4.0).max(Vec3::ZERO);
    let a2b2 = Vec3::new(a2b2.x.sqrt(), a2b2.y.sqrt(), a2b2.z.sqrt());
    let t1 = a2b2 + Vec3::splat(c2);
    let a = ((a2b2 + t0) * 0.5).max(Vec3::ZERO);
    let a = Vec3::new(a.x.sqrt(), a.y.sqrt(), a.z.sqrt());
    let t2 = a * (2.0 * c);
    let rs = (t1 - t2) / (t1 + t2).max(Vec3::splat(1e-12));
    let t3 = a2b2 * c2 + Vec3::splat(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(Vec3::splat(1e-12));
    (rp + rs) * 0.5
}

/// Schlick's approximation from the reflectance `f0` at normal incidence.
pub fn schlick(f0: Vec3, c: f32) -> Vec3 {
    let m = (1.0 - c).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3::ONE - f0) * m5
}

/// The GGX density of microfacet normals `h` (local frame).
pub fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's Lambda for GGX, for direction `w`.
fn ggx_lambda(w: Vec3, alpha: f32) -> f32 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return f32::INFINITY;
    }
    let t2 = (1.0 - c2).max(0.0) / c2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * t2).sqrt())
}

/// The masking of `w` alone.
pub fn ggx_g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(w, alpha))
}

/// Height-correlated masking-shadowing of `wo` and `wi`.
pub fn ggx_g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha))
}

/// The density of the visible normal `h` seen from `wo`.
pub fn ggx_visible_pdf(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    ggx_g1(wo, alpha) * wo.dot(h).max(0.0) * ggx_d(h, alpha) / wo.z
}

/// A GGX normal visible from `wo` (Heitz 2018).
pub fn ggx_visible_normal(wo: Vec3, alpha: f32, u1: f32, u2: f32) -> Vec3 {
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * (r * phi.sin());
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// `wo` refracted through a surface of normal `n` (on `wo`'s side) into index `eta`
/// relative to `wo`'s side; `None` under total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wo);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wo / eta + n * (cos_i / eta - cos_t))
}

/// `f · cos(wi)` and the density of a GGX reflection lobe with Fresnel `fresnel` (of the
/// cosine between `wo` and the half vector), sampled by visible normals.
fn microfacet_reflection(
    wo: Vec3,
    wi: Vec3,
    alpha: f32,
    fresnel: impl Fn(f32) -> Vec3,
) -> (Vec3, f32) {
    let h = wo + wi;
    if wi.z <= 0.0 || h == Vec3::ZERO {
        return (Vec3::ZERO, 0.0);
    }
    let h = h.normalize();
    let oh = wo.dot(h);
    if oh <= 0.0 {
        return (Vec3::ZERO, 0.0);
    }
    let d = ggx_d(h, alpha);
    let f = fresnel(oh) * (d * ggx_g2(wo, wi, alpha) / (4.0 * wo.z));
    let pdf = ggx_visible_pdf(wo, h, alpha) / (4.0 * oh);
    (f, pdf)
}

/// `f · |cos(wi)|` and the density of a rough dielectric (Walter et al. 2007, as in
/// pbrt-v4): reflection above, refraction below, each chosen by its Fresnel share.
/// `tint` colours the transmission; radiance through is scaled by 1 / eta².
fn rough_dielectric(wo: Vec3, wi: Vec3, alpha: f32, eta: f32, tint: Vec3) -> (Vec3, f32) {
    let reflect = wi.z > 0.0;
    let etap = if reflect { 1.0 } else { eta };
    let h = wi * etap + wo;
    if wi.z == 0.0 || h == Vec3::ZERO {
        return (Vec3::ZERO, 0.0);
    }
    let h = h.normalize();
    let h = if h.z < 0.0 { -h } else { h };
    let (ih, oh) = (wi.dot(h), wo.dot(h));
    // A microfacet that faces away from either direction.
    if ih * wi.z < 0.0 || oh < 0.0 {
        return (Vec3::ZERO, 0.0);
    }
    let f = fresnel_dielectric(oh, eta);
    let d = ggx_d(h, alpha);
    let g = ggx_g2(wo, wi, alpha);
    let vis = ggx_visible_pdf(wo, h, alpha);
    if reflect {
        let value = f * d * g / (4.0 * wo.z);
        (Vec3::splat(value), vis / (4.0 * oh) * f)
    } else {
        let denom = (ih + oh / etap) * (ih + oh / etap);
        let ft = (1.0 - f) * d * g * (ih * oh / (wo.z * denom)).abs() / (etap * etap);
        (tint * ft, vis * (ih.abs() / denom) * (1.0 - f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_is_the_textbook_value() {
        // ((n - 1) / (n + 1))² for glass, and for a conductor with k.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        let (n, k) = (0.2f32, 3.0f32);
        let r = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let f = fresnel_conductor(1.0, Vec3::splat(n), Vec3::splat(k));
        assert!((f.x - r).abs() < 1e-5, "{f} against {r}");
        // Grazing light is reflected whole; beyond the critical angle inside glass too.
        assert!(fresnel_dielectric(1e-4, 1.5) > 0.99);
        assert_eq!(fresnel_dielectric(0.5, 1.0 / 1.5), 1.0);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let wi = refract(wo, Vec3::Z, 1.5).unwrap();
        assert!((wi.length() - 1.0).abs() < 1e-5);
        let (sin_o, sin_i) = (wo.x, -wi.x);
        assert!((sin_o - 1.5 * sin_i).abs() < 1e-5, "{wi}");
        assert!(wi.z < 0.0);
    }
}
