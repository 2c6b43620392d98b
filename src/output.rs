//! Output files: the image (format by extension) and the raw per-pixel hit records. Both
//! are written under a temporary name beside the target and renamed into place, so a failed
//! run never leaves a partial file.

use std::io::{BufWriter, Write};
use std::path::Path;

use image::ImageFormat;

use crate::error::{Error, Result};
use crate::render::Frame;

/// The image format for `path`'s extension: png, bmp, ppm, jpg/jpeg. Checked before any
/// work starts, so that a long render never ends in "unknown format".
pub fn image_format(path: &Path) -> Result<ImageFormat> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let format = match ext.as_str() {
        "png" => ImageFormat::Png,
        "bmp" => ImageFormat::Bmp,
        "ppm" => ImageFormat::Pnm,
        "jpg" | "jpeg" => ImageFormat::Jpeg,
        _ => {
            return Err(Error::Invalid(format!(
                "{}: unknown image format `.{ext}`: use .png, .bmp, .ppm or .jpg",
                path.display()
            )));
        }
    };
    check_folder(path)?;
    Ok(format)
}

/// Refuses an output path whose folder does not exist (before the render, not after).
pub fn check_folder(path: &Path) -> Result<()> {
    let folder = folder_of(path);
    if !folder.is_dir() {
        return Err(Error::Invalid(format!(
            "{}: the folder {} does not exist",
            path.display(),
            folder.display()
        )));
    }
    Ok(())
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes the frame's colours as an image, atomically.
pub fn write_image(frame: &Frame, path: &Path) -> Result<()> {
    let format = image_format(path)?;
    let image = frame.to_rgb_image();
    write_atomically(path, |w| {
        image
            .write_to(w, format)
            .map_err(|e| Error::output(path, e))
    })
}

/// Writes the raw hit records: little-endian, row-major, 8 bytes a pixel (u32 triangle
/// index, 0xFFFFFFFF for a miss, then f32 distance, +inf for a miss), no header.
pub fn write_hits(frame: &Frame, path: &Path) -> Result<()> {
    check_folder(path)?;
    write_atomically(path, |w| {
        let mut bytes = Vec::with_capacity(frame.hits.len() * 8);
        for h in &frame.hits {
            bytes.extend_from_slice(&h.prim.to_le_bytes());
            bytes.extend_from_slice(&h.t.to_le_bytes());
        }
        w.write_all(&bytes).map_err(|e| Error::output(path, e))
    })
}

/// Writes through `fill` into a temporary file in `path`'s folder, then renames it to
/// `path`. On any failure the temporary file is removed and `path` is left untouched.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> Result<()>,
) -> Result<()> {
    let folder = folder_of(path);
    let mut tmp = tempfile::Builder::new()
        .prefix(".cltrace-")
        .suffix(".tmp")
        .tempfile_in(folder)
        .map_err(|e| {
            Error::output(
                path,
                format!("cannot create a file in {}: {e}", folder.display()),
            )
        })?;
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
        assert_eq!(image_format(Path::new("a.PNG")).unwrap(), ImageFormat::Png);
        assert_eq!(
            image_format(Path::new("a.jpeg")).unwrap(),
            ImageFormat::Jpeg
        );
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
        write_hits(&f, &path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 16);
        assert_eq!(&bytes[0..4], &[0xFF; 4]);
        assert_eq!(
            f32::from_le_bytes(bytes[4..8].try_into().unwrap()),
            f32::INFINITY
        );
        assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 7);
        assert_eq!(f32::from_le_bytes(bytes[12..16].try_into().unwrap()), 2.5);
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
