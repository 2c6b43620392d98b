//! Random numbers and the sampling of directions and of points on triangles, mirrored in
//! cl/sampling.cl so that the host reference and the devices draw the same numbers.
//!
//! The generator is counter-based: a number is a hash of (seed, pixel, sample, dimension),
//! so any pixel's any sample can be drawn in any order, on any device, with no state.

use glam::Vec3;

/// Chris Wellons' `lowbias32` integer hash: every input bit flips each output bit with
/// probability close to one half.
#[inline]
pub(crate) fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// The random stream of one sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sampler {
    key: u32,
}

impl Sampler {
    pub(crate) fn new(seed: u32, pixel: u32, sample: u32) -> Self {
        Sampler {
            key: hash(hash(hash(seed ^ 0x9e37_79b9) ^ pixel) ^ sample),
        }
    }

    /// Dimension `dim` of the stream, uniform in [0, 1).
    #[inline]
    pub(crate) fn get(&self, dim: u32) -> f32 {
        (hash(self.key ^ dim.wrapping_mul(0x85eb_ca6b)) >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

/// Dimensions of the stream: 0-1 jitter the pixel, then `DIMS_PER_BOUNCE` per bounce: the
/// emitter and its point (+0 to +2), Russian roulette (+3), the BSDF sample's direction,
/// lobe and side (+4 to +7), the environment's light sample (+8, +9).
pub const DIMS_PER_BOUNCE: u32 = 10;

/// The first dimension of the lens point of a thin-lens camera ([`disk_point`]): far above
/// any bounce's (at most about 2 + 10 · 1025), so that opening the lens shifts no other
/// number and a pinhole's samples stay bit for bit what they were.
pub const LENS_DIM: u32 = 0x8000_0000;
/// Pairs [`disk_point`] tries before it gives the disk's centre.
pub const LENS_TRIES: u32 = 16;

/// The first dimension of bounce `b`.
pub(crate) fn bounce_dim(b: u32) -> u32 {
    2 + b * DIMS_PER_BOUNCE
}

/// A unit direction about the unit normal `n`, cosine-weighted (pdf cos / pi), from two
/// uniform numbers, through the orthonormal basis of Duff et al. (JCGT 2017).
pub(crate) fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - u1).max(0.0).sqrt();
    let (t, b) = basis(n);
    t * x + b * y + n * z
}

/// Two unit vectors completing `n` to an orthonormal basis (Duff et al. 2017).
pub(crate) fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A uniform point of the unit disk from dimensions `dim`, `dim + 1`, ...: the first of
/// [`LENS_TRIES`] pairs in the square [-1, 1)² that falls inside it, else the centre (with
/// probability (1 - π/4)^16, about 2e-11). Rejection rather than a polar map: no sin and
/// cos, whose device versions may differ from the host's in the last bit, so that the lens
/// rays of the kernels are the host's bit for bit.
pub(crate) fn disk_point(s: &Sampler, dim: u32) -> (f32, f32) {
    for k in 0..LENS_TRIES {
        let a = 2.0 * s.get(dim + 2 * k) - 1.0;
        let b = 2.0 * s.get(dim + 2 * k + 1) - 1.0;
        if a * a + b * b < 1.0 {
            return (a, b);
        }
    }
    (0.0, 0.0)
}

/// A uniform point on the triangle (a, b, c) from two uniform numbers.
pub(crate) fn triangle_point(a: Vec3, b: Vec3, c: Vec3, u1: f32, u2: f32) -> Vec3 {
    let su = u1.sqrt();
    let (w0, w1) = (1.0 - su, u2 * su);
    a * w0 + b * w1 + c * (1.0 - w0 - w1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_uniform_and_independent() {
        let n = 20000;
        let mut sum = 0.0;
        let mut pairs = 0.0;
        for i in 0..n {
            let s = Sampler::new(7, i, 3);
            let (a, b) = (s.get(0), s.get(1));
            assert!((0.0..1.0).contains(&a));
            sum += a as f64;
            pairs += ((a - 0.5) * (b - 0.5)) as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.01);
        assert!((pairs / n as f64).abs() < 0.005);
        assert_ne!(Sampler::new(1, 2, 3).get(0), Sampler::new(2, 2, 3).get(0));
        assert_ne!(Sampler::new(1, 2, 3).get(0), Sampler::new(1, 2, 4).get(0));
    }

    #[test]
    fn disk_points_are_uniform_in_the_unit_disk() {
        let n = 20000;
        let (mut inner, mut mean) = (0, (0.0f64, 0.0f64));
        for i in 0..n {
            let (a, b) = disk_point(&Sampler::new(3, i, 1), LENS_DIM);
            let r2 = a * a + b * b;
            assert!(r2 < 1.0);
            inner += (r2 < 0.25) as u32;
            mean.0 += a as f64;
            mean.1 += b as f64;
        }
        // A quarter of the area lies within radius 1/2.
        assert!((inner as f64 / n as f64 - 0.25).abs() < 0.015, "{inner}");
        assert!((mean.0 / n as f64).abs() < 0.02 && (mean.1 / n as f64).abs() < 0.02);
    }

    #[test]
    fn cosine_directions_lie_in_the_hemisphere_with_mean_cosine_two_thirds() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let mut mean = 0.0;
        for i in 0..10000 {
            let s = Sampler::new(1, i, 0);
            let d = cosine_direction(n, s.get(0), s.get(1));
            assert!((d.length() - 1.0).abs() < 1e-4);
            assert!(d.dot(n) >= -1e-6);
            mean += d.dot(n) as f64;
        }
        assert!(
            (mean / 10000.0 - 2.0 / 3.0).abs() < 0.01,
            "{}",
            mean / 10000.0
        );
    }
}
