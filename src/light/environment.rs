//! Light from every direction at infinity: an equirectangular image (or a constant colour,
//! or a baked sun and sky) seen by rays that leave the scene, importance-sampled by
//! luminance. The mirror of cl/environment.cl, operation for operation.
//!
//! The orientation is Mitsuba 3's `envmap`: +y up, a direction d (in the map's own frame)
//! at u = atan2(d.x, -d.z) / 2π (wrapped into [0, 1)), v = acos(d.y) / π, u across the
//! image, v down it. The map is turned about +y by `rotate` degrees, right-handed (Mitsuba's
//! `to_world = rotate([0, 1, 0], angle)`). Each texel is constant over its patch of the
//! sphere (a nearest lookup): the sampling density then matches the radiance exactly, texel
//! by texel, and a texel's light cannot spill into a dark neighbour that is never sampled.

use std::f32::consts::PI;

use glam::Vec3;

/// An environment ready to be looked up and sampled, on the host and (as these arrays) on
/// the device.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// Texels across (u) and down (v).
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// Per texel, row-major from the top (v = 0, +y): the radiance (times the intensity)
    /// and, in the fourth place, the sampling density over (u, v) of that texel.
    pub texels: Vec<[f32; 4]>,
    /// `marginal[j]`: the sampling probability of rows 0..=j, the last exactly 1.
    pub marginal: Vec<f32>,
    /// `conditional[j * width + i]`: the probability of columns 0..=i within row j, each
    /// row's last exactly 1.
    pub conditional: Vec<f32>,
    /// (cos, sin) of the turn about +y.
    pub rotation: [f32; 2],
}

/// Luminance of linear Rec. 709 RGB: what the sampling follows.
pub(crate) fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The cumulative sums of `weights` over their total, the last exactly 1; uniform where the
/// total is 0 (a row that is never chosen still has a valid distribution).
fn cdf(weights: &[f64]) -> Vec<f32> {
    let total: f64 = weights.iter().sum();
    let n = weights.len();
    let mut acc = 0.0;
    let mut out: Vec<f32> = weights
        .iter()
        .enumerate()
        .map(|(i, w)| {
            if total > 0.0 {
                acc += w;
                (acc / total) as f32
            } else {
                (i + 1) as f32 / n as f32
            }
        })
        .collect();
    if let Some(last) = out.last_mut() {
        *last = 1.0;
    }
    out
}

/// The index whose CDF interval holds `u` (the kernels' `cdf_find`): also how light
/// samples pick an emitter.
pub(crate) fn cdf_find(cdf: &[f32], u: f32) -> usize {
    let (mut lo, mut hi) = (0usize, cdf.len() - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < cdf[mid] {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// Where `u` falls within interval `i` of `cdf`, in [0, 1).
fn within(cdf: &[f32], i: usize, u: f32) -> f32 {
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let width = cdf[i] - lo;
    if width > 0.0 {
        ((u - lo) / width).clamp(0.0, 0.999_999_94)
    } else {
        0.5
    }
}

impl Environment {
    /// An environment from `width` x `height` linear RGB texels (row-major from the top),
    /// scaled by `intensity` and turned `rotate` degrees about +y. The caller checks that
    /// every value is finite and not negative (the input module says which texel is not).
    pub fn new(width: u32, height: u32, rgb: &[[f32; 3]], intensity: f32, rotate: f32) -> Self {
        assert_eq!(rgb.len(), width as usize * height as usize, "texel count");
        let (w, h) = (width as usize, height as usize);
        // Each texel's weight: its luminance times the solid angle its row's patch spans
        // per unit of (u, v), sin θ at the row's centre.
        let weight = |i: usize, j: usize| {
            let sin = (PI * (j as f32 + 0.5) / h as f32).sin() as f64;
            luminance(Vec3::from(rgb[j * w + i])).max(0.0) as f64 * sin
        };
        let mut rows = Vec::with_capacity(h);
        let mut conditional = Vec::with_capacity(w * h);
        for j in 0..h {
            let row: Vec<f64> = (0..w).map(|i| weight(i, j)).collect();
            rows.push(row.iter().sum::<f64>());
            conditional.extend(cdf(&row));
        }
        let total: f64 = rows.iter().sum();
        let marginal = cdf(&rows);
        // The density over (u, v): a texel's share of the total over its area 1 / (w h);
        // uniform (1) for an all-black map, which then adds nothing anyway.
        let texels = (0..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .map(|(i, j)| {
                let c = Vec3::from(rgb[j * w + i]) * intensity;
                let density = if total > 0.0 {
                    (weight(i, j) * (w * h) as f64 / total) as f32
                } else {
                    1.0
                };
                [c.x, c.y, c.z, density]
            })
            .collect();
        let a = rotate.to_radians();
        Environment {
            width,
            height,
            texels,
            marginal,
            conditional,
            rotation: [a.cos(), a.sin()],
        }
    }

    /// A constant colour from every direction: a background that lights the scene. Its
    /// rows still weigh their solid angle, so its samples are nearly uniform on the sphere.
    pub fn constant(color: Vec3, intensity: f32) -> Self {
        let rows = 32;
        Environment::new(
            1,
            rows,
            &vec![color.to_array(); rows as usize],
            intensity,
            0.0,
        )
    }

    /// Bytes its device buffers take.
    pub fn bytes(&self) -> u64 {
        (16 * self.texels.len() + 4 * (self.marginal.len() + self.conditional.len())) as u64
    }

    /// The texel index (column, row) holding the map-frame direction `d` and sin θ there.
    fn texel_of(&self, d: Vec3) -> (usize, f32) {
        let mut u = d.x.atan2(-d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        let y = d.y.clamp(-1.0, 1.0);
        let v = y.acos() * (1.0 / PI);
        let i = ((u * self.width as f32) as u32).min(self.width - 1);
        let j = ((v * self.height as f32) as u32).min(self.height - 1);
        let sin = (1.0 - y * y).max(0.0).sqrt();
        ((j * self.width + i) as usize, sin)
    }

    /// World to the map's frame: the turn undone.
    fn to_map(&self, d: Vec3) -> Vec3 {
        let [c, s] = self.rotation;
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// The map's frame to the world: turned `rotate` degrees about +y.
    fn to_world(&self, d: Vec3) -> Vec3 {
        let [c, s] = self.rotation;
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// The radiance arriving from unit direction `d` (towards the environment) and the
    /// density, per solid angle, with which [`Environment::sample`] picks `d`.
    pub fn radiance(&self, d: Vec3) -> (Vec3, f32) {
        let (k, sin) = self.texel_of(self.to_map(d));
        let t = self.texels[k];
        let pdf = if sin > 0.0 {
            t[3] / (2.0 * PI * PI * sin)
        } else {
            0.0
        };
        (Vec3::new(t[0], t[1], t[2]), pdf)
    }

    /// A direction drawn with density proportional to luminance times solid angle, from
    /// two uniform numbers: the direction, the radiance from it and its density per solid
    /// angle (0 at a pole, where the sample is to be dropped).
    pub fn sample(&self, u1: f32, u2: f32) -> (Vec3, Vec3, f32) {
        let w = self.width as usize;
        let j = cdf_find(&self.marginal, u1);
        let row = &self.conditional[j * w..(j + 1) * w];
        let i = cdf_find(row, u2);
        let v = (j as f32 + within(&self.marginal, j, u1)) / self.height as f32;
        let u = (i as f32 + within(row, i, u2)) / self.width as f32;
        let (theta, phi) = (PI * v, 2.0 * PI * u);
        let sin = theta.sin();
        let local = Vec3::new(sin * phi.sin(), theta.cos(), -sin * phi.cos());
        let t = self.texels[j * w + i];
        let pdf = if sin > 0.0 {
            t[3] / (2.0 * PI * PI * sin)
        } else {
            0.0
        };
        (self.to_world(local), Vec3::new(t[0], t[1], t[2]), pdf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> Environment {
        // A dim gradient with one bright texel.
        let (w, h) = (16, 8);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|k| {
                let (i, j) = (k % w, k / w);
                if (i, j) == (11, 2) {
                    [50.0, 40.0, 30.0]
                } else {
                    [0.1 + 0.05 * j as f32, 0.2, 0.3 + 0.01 * i as f32]
                }
            })
            .collect();
        Environment::new(w as u32, h as u32, &rgb, 2.0, 60.0)
    }

    #[test]
    fn a_sample_has_the_density_and_radiance_a_lookup_gives_it() {
        let env = map();
        let mut other_texel = 0;
        for k in 0..4000 {
            let (u1, u2) = ((k as f32 * 0.618_034) % 1.0, (k as f32 * 0.754_877_7) % 1.0);
            let (d, le, pdf) = env.sample(u1, u2);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let (le2, pdf2) = env.radiance(d);
            // Rounding on a texel's edge, or of sin θ next to a pole.
            if le2 != le || (pdf - pdf2).abs() > 1e-3 * pdf {
                other_texel += 1;
            }
        }
        assert!(
            other_texel < 8,
            "{other_texel} samples looked up another texel"
        );
    }

    #[test]
    fn the_density_integrates_to_one_and_the_rotation_turns_the_map() {
        let env = map();
        // Midpoint rule over (θ, φ): ∫ pdf dω = 1.
        let n = 512;
        let mut total = 0.0f64;
        for a in 0..n {
            for b in 0..2 * n {
                let theta = PI * (a as f32 + 0.5) / n as f32;
                let phi = PI * (b as f32 + 0.5) / n as f32;
                let d = Vec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    -theta.sin() * phi.cos(),
                );
                let (_, pdf) = env.radiance(d);
                total += (pdf * theta.sin()) as f64 * (PI as f64 / n as f64).powi(2);
            }
        }
        assert!((total - 1.0).abs() < 0.01, "∫ pdf = {total}");
        // The bright texel (11, 2) is at u = 11.5/16, v = 2.5/8 in the map's frame; turned
        // 60° about +y in the world.
        let (u, v) = (11.5 / 16.0 * 2.0 * PI, 2.5 / 8.0 * PI);
        let local = Vec3::new(v.sin() * u.sin(), v.cos(), -v.sin() * u.cos());
        let a = 60f32.to_radians();
        let world = Vec3::new(
            a.cos() * local.x + a.sin() * local.z,
            local.y,
            -a.sin() * local.x + a.cos() * local.z,
        );
        assert_eq!(env.radiance(world).0, Vec3::new(100.0, 80.0, 60.0));
        assert_ne!(env.radiance(local).0, Vec3::new(100.0, 80.0, 60.0));
    }

    #[test]
    fn a_constant_colour_is_the_same_from_everywhere() {
        let env = Environment::constant(Vec3::new(0.5, 0.6, 0.7), 2.0);
        for d in [
            Vec3::Y,
            -Vec3::Y * 0.999 + Vec3::X * 0.01,
            Vec3::X,
            Vec3::new(1.0, 1.0, -1.0),
        ] {
            assert_eq!(env.radiance(d.normalize()).0, Vec3::new(1.0, 1.2, 1.4));
        }
        // Samples are nearly uniform: the density stays within 2% of 1 / 4π off the poles.
        let (_, _, pdf) = env.sample(0.5, 0.3);
        assert!((pdf * 4.0 * PI - 1.0).abs() < 0.02, "{pdf}");
    }
}
