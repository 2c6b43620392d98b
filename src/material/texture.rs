//! Textures as the renderer keeps them: linear RGBA texels in rows, the first row the
//! image's top, with a wrap mode per axis. Files become textures in `crate::input`
//! (`input/texture.rs`); this module knows nothing of files.

/// What a texture coordinate outside [0, 1] reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The texture tiles the plane (OBJ's and glTF's default).
    #[default]
    Repeat,
    /// The edge texels extend outwards (MTL `-clamp on`, glTF `CLAMP_TO_EDGE`).
    Clamp,
    /// Every other tile is mirrored (glTF `MIRRORED_REPEAT`).
    Mirror,
}

impl Wrap {
    /// The code the kernels read (`WRAP_*` in the generated constants).
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::Clamp => 1,
            Wrap::Mirror => 2,
        }
    }
}

/// A texture: `width * height` linear RGBA texels, row by row from the image's top row.
/// Colour textures (base colour, emission) were sRGB in their file and are stored linear;
/// data textures (normals, masks, metallic-roughness, occlusion) are stored as read.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages: a file name or "glTF image 3".
    pub name: String,
    /// Width in texels, at least 1.
    pub width: u32,
    /// Height in texels, at least 1.
    pub height: u32,
    /// The texels, `width * height` of them, row-major from the top row.
    pub texels: Vec<[f32; 4]>,
    /// Wrap mode along u (across a row) and along v (down the columns).
    pub wrap: [Wrap; 2],
}

impl Texture {
    /// A 1x1 texture of one value: what a missing texture file becomes (grey), and tests.
    pub fn solid(value: [f32; 4]) -> Texture {
        Texture {
            name: "solid".into(),
            width: 1,
            height: 1,
            texels: vec![value],
            wrap: [Wrap::Repeat; 2],
        }
    }
}

/// A texture's entry in the table the kernels read (`TextureInfo` in cl/texture.cl): where
/// its mip chain starts in [`DeviceTextures::texels`], its level-0 size and wrap modes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TextureInfo {
    /// Index of level 0's first texel.
    pub offset: u32,
    /// Level 0's width in texels.
    pub width: u32,
    /// Level 0's height in texels.
    pub height: u32,
    /// Mip levels, down to 1x1.
    pub levels: u32,
    /// [`Wrap::code`] along u.
    pub wrap_u: u32,
    /// [`Wrap::code`] along v.
    pub wrap_v: u32,
    /// Padding to 32 bytes; always 0.
    pub pad: [u32; 2],
}

/// Every texture of a scene as the kernels read it: each a chain of mip levels (each half
/// the size of the one before, by a 2x2 box filter, down to 1x1) of RGBA half-precision
/// texels, 8 bytes each, all in one buffer. Half precision keeps HDR values (to 65504) at a
/// quarter of f32's memory traffic; the chain adds a third. The host reads the same halves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeviceTextures {
    /// One entry per texture, in [`crate::material::Materials::textures`] order.
    pub infos: Vec<TextureInfo>,
    /// The texels, as `half` bits, four per texel.
    pub texels: Vec<u16>,
}

impl DeviceTextures {
    /// The mip chains of `textures`.
    pub fn new(textures: &[Texture]) -> DeviceTextures {
        let mut out = DeviceTextures::default();
        for t in textures {
            let offset = (out.texels.len() / 4) as u32;
            let (mut w, mut h) = (t.width as usize, t.height as usize);
            let mut level = t.texels.clone();
            let mut levels = 1;
            loop {
                out.texels
                    .extend(level.iter().flatten().map(|&v| to_half(v)));
                if w == 1 && h == 1 {
                    break;
                }
                let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
                let mut next = Vec::with_capacity(nw * nh);
                for y in 0..nh {
                    for x in 0..nw {
                        let mut sum = [0.0f32; 4];
                        let (x0, y0) = ((2 * x).min(w - 1), (2 * y).min(h - 1));
                        let (x1, y1) = ((2 * x + 1).min(w - 1), (2 * y + 1).min(h - 1));
                        for (xx, yy) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
                            let p = level[yy * w + xx];
                            for c in 0..4 {
                                sum[c] += p[c];
                            }
                        }
                        next.push(sum.map(|s| s * 0.25));
                    }
                }
                (w, h, level) = (nw, nh, next);
                levels += 1;
            }
            out.infos.push(TextureInfo {
                offset,
                width: t.width,
                height: t.height,
                levels,
                wrap_u: t.wrap[0].code(),
                wrap_v: t.wrap[1].code(),
                pad: [0; 2],
            });
        }
        out
    }

    /// Bytes on the device.
    pub fn bytes(&self) -> u64 {
        (self.infos.len() * size_of::<TextureInfo>() + self.texels.len() * 2) as u64
    }

    /// Texel (x, y) of the level starting at texel `offset`, `w` wide.
    fn fetch(&self, offset: u32, w: i32, x: i32, y: i32) -> [f32; 4] {
        let i = 4 * (offset as usize + (y * w + x) as usize);
        [0, 1, 2, 3].map(|c| half::f16::from_bits(self.texels[i + c]).to_f32())
    }

    /// `texture_bilinear` in cl/texture.cl.
    fn bilinear(&self, t: &TextureInfo, level: u32, u: f32, v: f32) -> [f32; 4] {
        let mut offset = t.offset;
        let (mut w, mut h) = (t.width as i32, t.height as i32);
        for _ in 0..level {
            offset += (w * h) as u32;
            w = (w / 2).max(1);
            h = (h / 2).max(1);
        }
        let fx = reduce_coordinate(u, t.wrap_u) * w as f32 - 0.5;
        let fy = reduce_coordinate(1.0 - v, t.wrap_v) * h as f32 - 0.5;
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let xa = wrap_texel(x0 as i32, w, t.wrap_u);
        let xb = wrap_texel(x0 as i32 + 1, w, t.wrap_u);
        let ya = wrap_texel(y0 as i32, h, t.wrap_v);
        let yb = wrap_texel(y0 as i32 + 1, h, t.wrap_v);
        let a = self.fetch(offset, w, xa, ya);
        let b = self.fetch(offset, w, xb, ya);
        let c = self.fetch(offset, w, xa, yb);
        let d = self.fetch(offset, w, xb, yb);
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * tx;
            let bottom = c[k] + (d[k] - c[k]) * tx;
            top + (bottom - top) * ty
        })
    }

    /// Texture `index` at `uv`, trilinear between the levels around `lod`: `sample_texture`
    /// in cl/texture.cl.
    pub fn sample(&self, index: i32, uv: [f32; 2], lod: f32) -> [f32; 4] {
        let t = &self.infos[index as usize];
        let lod = lod.max(0.0).min((t.levels - 1) as f32);
        let l0 = lod.floor();
        let f = lod - l0;
        let a = self.bilinear(t, l0 as u32, uv[0], uv[1]);
        if f > 0.0 {
            let b = self.bilinear(t, l0 as u32 + 1, uv[0], uv[1]);
            std::array::from_fn(|k| a[k] + (b[k] - a[k]) * f)
        } else {
            a
        }
    }
}

/// A value as half bits, finite: beyond the half range it saturates at +-65504.
fn to_half(v: f32) -> u16 {
    let v = if v.is_nan() {
        0.0
    } else {
        v.clamp(-65504.0, 65504.0)
    };
    half::f16::from_f32(v).to_bits()
}

/// `wrap_texel` in cl/texture.cl.
fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    if mode == Wrap::Clamp.code() {
        return i.clamp(0, n - 1);
    }
    if mode == Wrap::Mirror.code() {
        let m = i.rem_euclid(2 * n);
        return if m < n { m } else { 2 * n - 1 - m };
    }
    i.rem_euclid(n)
}

/// `reduce_coordinate` in cl/texture.cl.
fn reduce_coordinate(u: f32, mode: u32) -> f32 {
    let u = if u.abs() < 1e7 { u } else { 0.0 };
    if mode == Wrap::Clamp.code() {
        u.clamp(-1.0, 2.0)
    } else if mode == Wrap::Mirror.code() {
        u - 2.0 * (u * 0.5).floor()
    } else {
        u - u.floor()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(n: u32) -> Texture {
        Texture {
            name: "checker".into(),
            width: n,
            height: n,
            texels: (0..n * n)
                .map(|i| {
                    let v = ((i % n + i / n) % 2) as f32;
                    [v, v, v, 1.0]
                })
                .collect(),
            wrap: [Wrap::Repeat; 2],
        }
    }

    #[test]
    fn mip_chains_go_down_to_one_texel_and_average() {
        let d = DeviceTextures::new(&[checker(8), Texture::solid([0.25, 0.5, 1.0, 1.0])]);
        assert_eq!(d.infos[0].levels, 4);
        assert_eq!(d.infos[1].offset, 64 + 16 + 4 + 1);
        // the 1x1 level of a checkerboard is its mean
        let top = d.sample(0, [0.3, 0.7], 3.0);
        assert!((top[0] - 0.5).abs() < 1e-3, "{top:?}");
        assert_eq!(d.sample(1, [5.5, -3.2], 0.0), [0.25, 0.5, 1.0, 1.0]);
    }

    #[test]
    fn texel_centres_read_exactly_and_wrap_modes_differ() {
        let d = DeviceTextures::new(&[checker(4)]);
        // texel (0, 0) is the top-left one: v near 1
        let at = |u: f32, v: f32| d.sample(0, [u, v], 0.0)[0];
        assert_eq!(at(0.125, 0.875), 0.0);
        assert_eq!(at(0.375, 0.875), 1.0);
        assert_eq!(at(1.125, 0.875), 0.0, "repeat");
        assert_eq!(at(0.25, 0.875), 0.5, "between two texels");
        let mut clamp = checker(4);
        clamp.wrap = [Wrap::Clamp; 2];
        let mut mirror = checker(4);
        mirror.wrap = [Wrap::Mirror; 2];
        let d = DeviceTextures::new(&[clamp, mirror]);
        assert_eq!(d.sample(0, [1.9, 0.875], 0.0)[0], 1.0, "the last column");
        assert_eq!(
            d.sample(1, [1.125, 0.875], 0.0)[0],
            1.0,
            "mirrored: the last column"
        );
        assert_eq!(d.sample(0, [f32::NAN, 0.875], 0.0)[0], 0.0);
    }
}
