//! Texture files in: any image the `image` crate reads (PNG, JPEG, EXR, HDR, BMP, PNM),
//! decoded to linear RGBA ([`crate::material::Texture`]).

use std::path::Path;

use crate::error::{Error, Result};
use crate::material::{Texture, Wrap};

/// How a texture's stored values map to what the renderer reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// Colours (base colour, emission): 8- and 16-bit images are sRGB-encoded and decoded to
    /// linear; float images (EXR, HDR) are linear already.
    Srgb,
    /// Data (normal maps, masks, metallic-roughness, occlusion): values as stored.
    Linear,
}

/// Largest width or height of a texture accepted: far above any real texture, low enough
/// that a forged header is an error rather than an exhausted machine.
pub const MAX_TEXTURE_SIZE: u32 = 16384;

/// Reads a texture file. A missing file is [`Error::Input`] like a corrupt one; the
/// callers that treat a missing texture as a warning check for the file first.
pub fn load_texture(path: &Path, space: ColorSpace, wrap: [Wrap; 2]) -> Result<Texture> {
    let bytes = std::fs::read(path).map_err(|e| Error::input(path, super::io_reason(&e)))?;
    decode_texture(path, &bytes, space, wrap)
}

/// Decodes an image file's bytes to a texture; `path_for_messages` names it in errors and
/// becomes its name.
pub fn decode_texture(
    path_for_messages: &Path,
    bytes: &[u8],
    space: ColorSpace,
    wrap: [Wrap; 2],
) -> Result<Texture> {
    let path = path_for_messages;
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::input(path, format!("cannot read the texture: {e}")))?;
    if reader.format().is_none() {
        return Err(Error::input(
            path,
            "not an image format cltrace reads (PNG, JPEG, EXR, HDR, BMP, PNM)",
        ));
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIZE);
    limits.max_image_height = Some(MAX_TEXTURE_SIZE);
    let mut reader = reader;
    reader.limits(limits);
    let image = reader.decode().map_err(|e| {
        Error::input(
            path,
            format!(
                "cannot decode the texture: {}",
                super::clean_line(&e.to_string())
            ),
        )
    })?;
    let float = matches!(
        image.color(),
        image::ColorType::Rgb32F | image::ColorType::Rgba32F
    );
    let rgba = image.to_rgba32f();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err(Error::input(path, "the texture has no texels"));
    }
    let decode = space == ColorSpace::Srgb && !float;
    let texels = rgba
        .pixels()
        .map(|p| {
            let [r, g, b, a] = p.0;
            let c = |v: f32| {
                let v = if v.is_finite() { v } else { 0.0 };
                if decode { srgb_to_linear(v) } else { v }
            };
            [c(r), c(g), c(b), if a.is_finite() { a } else { 1.0 }]
        })
        .collect();
    Ok(Texture {
        name: path.display().to_string(),
        width,
        height,
        texels,
        wrap,
    })
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(pixels: &[[u8; 4]], width: u32) -> Vec<u8> {
        let height = pixels.len() as u32 / width;
        let img = image::RgbaImage::from_raw(width, height, pixels.concat()).unwrap();
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn srgb_textures_are_decoded_to_linear_and_data_ones_kept() {
        let bytes = png(&[[255, 188, 0, 128], [0, 0, 0, 255]], 2);
        let p = Path::new("t.png");
        let srgb = decode_texture(p, &bytes, ColorSpace::Srgb, [Wrap::Repeat; 2]).unwrap();
        assert_eq!((srgb.width, srgb.height), (2, 1));
        assert!((srgb.texels[0][0] - 1.0).abs() < 1e-6);
        assert!(
            (srgb.texels[0][1] - 0.5029).abs() < 1e-3,
            "{:?}",
            srgb.texels[0]
        );
        assert!(
            (srgb.texels[0][3] - 128.0 / 255.0).abs() < 1e-6,
            "alpha stays linear"
        );
        let data = decode_texture(p, &bytes, ColorSpace::Linear, [Wrap::Repeat; 2]).unwrap();
        assert!((data.texels[0][1] - 188.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn corrupt_textures_are_one_line_errors() {
        let p = Path::new("bad.png");
        let mut bytes = png(&[[1, 2, 3, 4]; 16], 4);
        bytes.truncate(bytes.len() / 2);
        let e = decode_texture(p, &bytes, ColorSpace::Srgb, [Wrap::Repeat; 2])
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.png") && !e.contains('\n'), "{e}");
        let e = decode_texture(p, b"not an image", ColorSpace::Srgb, [Wrap::Repeat; 2])
            .unwrap_err()
            .to_string();
        assert!(e.contains("not an image format"), "{e}");
    }
}
