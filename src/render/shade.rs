//! Shading on the host, mirroring `shade_hit` in cl/shade.cl; the normal comes from the
//! surface (`crate::material::surface`, cl/surface.cl).

use glam::Vec3;

use super::Shade;
use crate::camera::Camera;
use crate::geometry::Aabb;

/// What shading needs besides the hit: the mode and, for depth, the distance range that
/// maps to white..black (the scene's bounding sphere seen from the eye).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeParams {
    pub(crate) shade: Shade,
    pub(crate) near: f32,
    pub(crate) far: f32,
    /// Whether the frame's hits carry barycentrics ([`super::Frame::barycentrics`]): what
    /// version 2 of the hit records stores.
    pub(crate) barycentrics: bool,
    /// Whether the frame's colours are computed. Without them (the benchmark's
    /// closest-hit query, which writes hit records alone as its peers do) the colours
    /// stay 0 and the kernel neither shades nor stores one.
    pub(crate) colors: bool,
}

impl ShadeParams {
    /// The parameters of `shade` for `camera` looking at a scene within `bounds`: depth
    /// maps the near and far points of the box's bounding sphere (distances from the eye,
    /// near at least 0) to white and black.
    pub fn new(shade: Shade, camera: &Camera, bounds: &Aabb) -> Self {
        let radius = bounds.extent().length() * 0.5;
        let distance = (bounds.center() - camera.eye).length();
        let near = (distance - radius).max(0.0);
        let far = (distance + radius).max(near * 1.0001 + f32::MIN_POSITIVE);
        ShadeParams {
            shade,
            near,
            far,
            barycentrics: false,
            colors: true,
        }
    }

    /// The same, with the hits' barycentrics recorded in the frame.
    pub fn with_barycentrics(self, barycentrics: bool) -> Self {
        ShadeParams {
            barycentrics,
            ..self
        }
    }

    /// The same, with the frame's colours computed or not (they stay 0).
    pub fn with_colors(self, colors: bool) -> Self {
        ShadeParams { colors, ..self }
    }

    /// The packed RGBA colour of a hit with unit (shading) normal `n` at `distance` along
    /// `dir`.
    pub(crate) fn color(&self, n: Vec3, distance: f32, dir: Vec3) -> u32 {
        match self.shade {
            Shade::Normal => pack_rgba(0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5),
            Shade::Depth => {
                let g = 1.0 - (distance - self.near) / (self.far - self.near);
                pack_rgba(g, g, g)
            }
            Shade::Lambert | Shade::Ao | Shade::Shadow | Shade::Path => {
                let d_len = (dir.x * dir.x + dir.y * dir.y + dir.z * dir.z).sqrt();
                let c = (n.x * dir.x + n.y * dir.y + n.z * dir.z).abs() / d_len;
                pack_rgba(c, c, c)
            }
        }
    }
}

/// Black, opaque: the colour of a miss.
pub(crate) const BACKGROUND: u32 = 0xFF00_0000;

fn quantize(v: f32) -> u32 {
    // clamp() in OpenCL returns the lower bound for NaN; so does this.
    let v = if v > 0.0 { v.min(1.0) } else { 0.0 };
    (v * 255.0 + 0.5) as u32
}

fn pack_rgba(r: f32, g: f32, b: f32) -> u32 {
    quantize(r) | (quantize(g) << 8) | (quantize(b) << 16) | (255 << 24)
}

/// Display colours for linear radiance: for `path`, the ACES filmic curve as fitted by
/// Narkowicz (2015), for the other modes (already within [0, 1]) a clamp; then the sRGB
/// transfer function and 8-bit rounding.
pub fn tone_map(radiance: &[[f32; 3]], shade: Shade) -> Vec<u32> {
    let curve = |x: f32| match shade {
        Shade::Path => {
            let x = x.max(0.0);
            (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
        }
        _ => x,
    };
    let srgb = |x: f32| {
        let x = x.clamp(0.0, 1.0);
        if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
    };
    // On every core: a 4K image is 25 million powf calls.
    use rayon::prelude::*;
    radiance
        .par_iter()
        .with_min_len(4096)
        .map(|&[r, g, b]| pack_rgba(srgb(curve(r)), srgb(curve(g)), srgb(curve(b))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_mapping_ends_in_srgb_bytes() {
        let c = tone_map(&[[0.0; 3], [1.0; 3], [0.5, 0.2, 0.0]], Shade::Ao);
        assert_eq!(c[0].to_le_bytes(), [0, 0, 0, 255]);
        assert_eq!(c[1].to_le_bytes(), [255, 255, 255, 255]);
        assert_eq!(c[2].to_le_bytes()[0], 188); // sRGB(0.5) = 0.7354
        let p = tone_map(&[[1e6; 3]], Shade::Path);
        assert!(
            p[0].to_le_bytes()[0] >= 254,
            "the filmic curve approaches white"
        );
    }
}
