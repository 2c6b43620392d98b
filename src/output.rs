//! Output files: the image (format by extension) and the raw per-pixel hit records. Both
//! are written under a temporary name beside the target and renamed into place, so a failed
//! run never leaves a partial file. Every output is checked before any work starts
//! ([`check_output`]): its folder exists and takes a new file. `/dev/null` takes any format
//! and is not written at all; another special file (a named pipe) is written straight
//! into, never renamed over.

pub mod part;

use std::io::{BufWriter, Write};
use std::path::Path;

use exr::prelude::{
    Encoding, Image as ExrImage, Layer, LayerAttributes, SpecificChannels, Vec2, WritableImage,
};
use image::ImageFormat;

use crate::error::{Error, Result};
use crate::render::Frame;

/// An output image format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum OutputFormat {
    /// 8-bit sRGB through the `image` crate (png, bmp, jpg).
    Display(ImageFormat),
    /// 8-bit sRGB as binary PPM (`P6`), which every PPM reader takes (the `image` crate
    /// writes PAM, `P7`, which most reject).
    Ppm,
    /// OpenEXR, 32-bit float linear radiance.
    Exr,
    /// Portable float map, 32-bit float linear radiance.
    Pfm,
    /// `/dev/null`: nothing is encoded or written (a run for its hit records or timings).
    Discard,
}

/// The path that discards an output.
const DEV_NULL: &str = "/dev/null";

/// The image format for `path`'s extension: png, bmp, ppm, jpg/jpeg, exr, pfm. Checked
/// before any work starts, so that a long render never ends in "unknown format".
pub(crate) fn image_format(path: &Path) -> Result<OutputFormat> {
    if path == Path::new(DEV_NULL) {
        return Ok(OutputFormat::Discard);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let format = match ext.as_str() {
        "png" => OutputFormat::Display(ImageFormat::Png),
        "bmp" => OutputFormat::Display(ImageFormat::Bmp),
        "ppm" => OutputFormat::Ppm,
        "jpg" | "jpeg" => OutputFormat::Display(ImageFormat::Jpeg),
        "exr" => OutputFormat::Exr,
        "pfm" => OutputFormat::Pfm,
        _ => {
            return Err(Error::Invalid(format!(
                "{}: unknown image format `.{ext}`: use .png, .bmp, .ppm, .jpg, .exr or .pfm",
                path.display()
            )));
        }
    };
    check_output(path)?;
    Ok(format)
}

/// Refuses, before any work, an output that could not be written after it: a folder that
/// does not exist or takes no new file (permissions, a read-only file system), or a path
/// that is a folder. Each is an [`Error::Output`] naming the user's path (exit status 1).
pub fn check_output(path: &Path) -> Result<()> {
    if path == Path::new(DEV_NULL) {
        return Ok(());
    }
    if path.is_dir() {
        return Err(Error::output(path, "is a directory"));
    }
    if is_special(path) {
        return Ok(());
    }
    let folder = folder_of(path);
    if !folder.is_dir() {
        return Err(Error::output(
            path,
            format!("the folder {} does not exist", folder.display()),
        ));
    }
    // The only sure test of "can a file be made here" is making one; it is removed at once.
    temporary_in(folder)
        .map(drop)
        .map_err(|e| cannot_create(path, folder, e))
}

/// "PATH: cannot create a file in FOLDER: the system's reason", without the temporary
/// file's name, which tempfile puts in its errors and which means nothing to the user.
fn cannot_create(path: &Path, folder: &Path, e: std::io::Error) -> Error {
    let reason = match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code).to_string(),
        None => e.kind().to_string(),
    };
    Error::output(
        path,
        format!("cannot create a file in {}: {reason}", folder.display()),
    )
}

/// Whether `path` exists and is neither a regular file nor a folder (a named pipe, a
/// device): such a file is written into, not replaced.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// A new temporary file in `folder`, as readable as the user's umask lets any new file be
/// (tempfile makes it private, 0600, by default).
fn temporary_in(folder: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(".cltrace-").suffix(".tmp");
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    builder.tempfile_in(folder)
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes the frame as an image, atomically: display formats get the colours (tone-mapped
/// radiance for the progressive modes), float formats the linear radiance (or, for the
/// modes that shade one hit, the colours as numbers in [0, 1]).
pub(crate) fn write_image(frame: &Frame, path: &Path) -> Result<()> {
    match image_format(path)? {
        OutputFormat::Display(format) => {
            let image = frame.to_rgb_image();
            write_atomically(path, |w| {
                image
                    .write_to(w, format)
                    .map_err(|e| Error::output(path, e))
            })
        }
        OutputFormat::Ppm => {
            let image = frame.to_rgb_image();
            write_atomically(path, |w| {
                write!(w, "P6\n{} {}\n255\n", frame.width, frame.height)
                    .and_then(|()| w.write_all(image.as_raw()))
                    .map_err(|e| Error::output(path, e))
            })
        }
        OutputFormat::Exr => {
            let pixels = linear(frame);
            let width = frame.width as usize;
            // Scan lines in increasing order: the same frame gives the same bytes (the
            // `image` crate's EXR writer stores its blocks in whatever order its threads
            // finish them), and ZIP makes a rendered frame about two thirds the size.
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let [r, g, b] = pixels[p.y() * width + p.x()];
                (r, g, b)
            });
            let image = ExrImage::from_layer(Layer::new(
                (width, frame.height as usize),
                LayerAttributes::default(),
                Encoding::SMALL_LOSSLESS,
                channels,
            ));
            write_atomically(path, |w| {
                image
                    .write()
                    .to_buffered(w)
                    .map_err(|e| Error::output(path, e))
            })
        }
        OutputFormat::Pfm => {
            let pixels = linear(frame);
            write_atomically(path, |w| {
                write_pfm(w, frame.width, &pixels).map_err(|e| Error::output(path, e))
            })
        }
        OutputFormat::Discard => Ok(()),
    }
}

/// The frame's radiance, or its colours as floats when it has none.
fn linear(frame: &Frame) -> Vec<[f32; 3]> {
    match &frame.radiance {
        Some(r) => r.clone(),
        None => frame
            .colors
            .iter()
            .map(|c| {
                let [r, g, b, _] = c.to_le_bytes();
                [r as f32 / 255.0, g as f32 / 255.0, b as f32 / 255.0]
            })
            .collect(),
    }
}

/// A colour portable float map: `PF`, the size, `-1.0` (little-endian), then rows of
/// RGB floats from the bottom row up.
fn write_pfm(w: &mut impl Write, width: u32, pixels: &[[f32; 3]]) -> std::io::Result<()> {
    let height = pixels.len() / width.max(1) as usize;
    write!(w, "PF\n{width} {height}\n-1.0\n")?;
    let mut bytes = Vec::with_capacity(pixels.len() * 12);
    for row in pixels.chunks(width as usize).rev() {
        for p in row {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    w.write_all(&bytes)
}

/// The layout of the raw hit records (`--hits-format`). Both are little-endian,
/// row-major, without a header.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HitsFormat {
    /// Version 1, 8 bytes a pixel: u32 triangle index (0xFFFFFFFF for a miss), f32
    /// distance (+inf for a miss).
    #[default]
    V1,
    /// Version 2, 16 bytes a pixel: version 1's fields, then the hit's barycentric weights
    /// of the triangle's vertices 1 and 2 as two f32 (vertex 0's is 1 minus their sum; 0
    /// and 0 for a miss).
    V2,
}

impl HitsFormat {
    /// Every format.
    pub const ALL: [HitsFormat; 2] = [HitsFormat::V1, HitsFormat::V2];

    /// The format's name, for `--hits-format`.
    pub fn name(self) -> &'static str {
        match self {
            HitsFormat::V1 => "v1",
            HitsFormat::V2 => "v2",
        }
    }

    /// One line on the format, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            HitsFormat::V1 => "8 bytes a pixel: u32 triangle, f32 distance",
            HitsFormat::V2 => "16 bytes a pixel: v1, then f32 barycentrics of vertices 1 and 2",
        }
    }

    /// Bytes per pixel.
    pub fn record_bytes(self) -> usize {
        match self {
            HitsFormat::V1 => 8,
            HitsFormat::V2 => 16,
        }
    }
}

impl std::str::FromStr for HitsFormat {
    type Err = String;

    /// The format [`HitsFormat::name`] names.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        crate::error::by_name(s, &HitsFormat::ALL, HitsFormat::name, "hit record format")
    }
}

/// Writes the raw hit records in `format` ([`HitsFormat`]). Version 2 needs the frame's
/// barycentrics ([`crate::render::ShadeParams::with_barycentrics`]).
pub(crate) fn write_hits(frame: &Frame, path: &Path, format: HitsFormat) -> Result<()> {
    check_output(path)?;
    if format == HitsFormat::V2 && frame.barycentrics.len() != frame.hits.len() {
        return Err(Error::Invalid(
            "version 2 hit records need the frame's barycentrics".into(),
        ));
    }
    if path == Path::new(DEV_NULL) {
        return Ok(());
    }
    write_atomically(path, |w| {
        let mut bytes = Vec::with_capacity(frame.hits.len() * format.record_bytes());
        for (i, h) in frame.hits.iter().enumerate() {
            bytes.extend_from_slice(&h.prim.to_le_bytes());
            bytes.extend_from_slice(&h.t.to_le_bytes());
            if format == HitsFormat::V2 {
                for b in frame.barycentrics[i] {
                    bytes.extend_from_slice(&b.to_le_bytes());
                }
            }
        }
        w.write_all(&bytes).map_err(|e| Error::output(path, e))
    })
}

/// Writes through `fill` into a temporary file in `path`'s folder, then renames it to
/// `path`. On any failure the temporary file is removed and `path` is left untouched. A
/// special file (a named pipe) is written straight into. A second Ctrl-C waits for the
/// write ([`crate::interrupt::Writing`]).
pub(crate) fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> Result<()>,
) -> Result<()> {
    let _writing = crate::interrupt::Writing::start();
    if is_special(path) {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| Error::output(path, e))?;
        let mut w = BufWriter::new(&mut file);
        fill(&mut w)?;
        return w.flush().map_err(|e| Error::output(path, e));
    }
    let folder = folder_of(path);
    let mut tmp = temporary_in(folder).map_err(|e| cannot_create(path, folder, e))?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.flush().map_err(|e| Error::output(path, e))?;
    }
    tmp.persist(path)
        .map_err(|e| Error::output(path, e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Hit;

    #[test]
    fn formats_by_extension() {
        let display = OutputFormat::Display;
        assert_eq!(
            image_format(Path::new("a.PNG")).unwrap(),
            display(ImageFormat::Png)
        );
        assert_eq!(
            image_format(Path::new("a.jpeg")).unwrap(),
            display(ImageFormat::Jpeg)
        );
        assert_eq!(image_format(Path::new("a.exr")).unwrap(), OutputFormat::Exr);
        assert_eq!(image_format(Path::new("a.pfm")).unwrap(), OutputFormat::Pfm);
        assert!(image_format(Path::new("a.tiff")).is_err());
        assert!(image_format(Path::new("a")).is_err());
        assert!(image_format(Path::new("/no/such/folder/a.png")).is_err());
    }

    #[test]
    fn hits_file_layout() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.bin");
        let mut f = Frame::new(2, 1);
        f.hits[1] = Hit { prim: 7, t: 2.5 };
        write_hits(&f, &path, HitsFormat::V1).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 16);
        assert_eq!(&bytes[0..4], &[0xFF; 4]);
        assert_eq!(
            f32::from_le_bytes(bytes[4..8].try_into().unwrap()),
            f32::INFINITY
        );
        assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 7);
        assert_eq!(f32::from_le_bytes(bytes[12..16].try_into().unwrap()), 2.5);
        // Version 2 needs barycentrics, and appends them to each record.
        assert!(write_hits(&f, &path, HitsFormat::V2).is_err());
        f.barycentrics = vec![[0.0, 0.0], [0.25, 0.5]];
        write_hits(&f, &path, HitsFormat::V2).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 32);
        assert_eq!(u32::from_le_bytes(bytes[16..20].try_into().unwrap()), 7);
        let f32_at = |i: usize| f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        assert_eq!((f32_at(8), f32_at(12)), (0.0, 0.0));
        assert_eq!((f32_at(20), f32_at(24), f32_at(28)), (2.5, 0.25, 0.5));
    }

    #[test]
    fn float_images_hold_the_radiance() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = Frame::new(2, 2);
        f.radiance = Some(vec![
            [0.0, 1.0, 2.0],
            [3.0, 4.0, 5.0],
            [6.0, 7.0, 8.0],
            [9.0, 10.0, 11.5],
        ]);
        let pfm = dir.path().join("x.pfm");
        write_image(&f, &pfm).unwrap();
        let bytes = std::fs::read(&pfm).unwrap();
        let header = b"PF\n2 2\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        let floats: Vec<f32> = bytes[header.len()..]
            .chunks(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        // Bottom row first.
        assert_eq!(&floats[..6], &[6.0, 7.0, 8.0, 9.0, 10.0, 11.5]);
        let exr = dir.path().join("x.exr");
        write_image(&f, &exr).unwrap();
        let back = image::open(&exr).unwrap().into_rgb32f();
        assert_eq!(back.get_pixel(1, 1).0, [9.0, 10.0, 11.5]);
    }

    #[test]
    fn exr_blocks_were_stored_in_the_order_threads_finished_them() {
        // Enough scan-line blocks for several threads, pixels that compress unevenly.
        let (w, h) = (97u32, 300u32);
        let mut f = Frame::new(w, h);
        f.radiance = Some(
            (0..w * h)
                .map(|i| {
                    let v = (i.wrapping_mul(2_654_435_761) >> 8) as f32 / 1e6;
                    [v, v * 0.5, (i % 7) as f32]
                })
                .collect(),
        );
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
        for _ in 0..3 {
            write_image(&f, &a).unwrap();
            write_image(&f, &b).unwrap();
            let same = std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap();
            assert!(same, "the same frame gave two EXR files");
        }
        let back = image::open(&a).unwrap().into_rgb32f();
        let radiance = f.radiance.as_ref().unwrap();
        for (i, p) in back.pixels().enumerate() {
            assert_eq!(p.0, radiance[i]);
        }
    }

    #[test]
    fn a_failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.png");
        let r = write_atomically(&path, |_| Err(Error::Invalid("boom".into())));
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
