//! Scene input: meshes from Wavefront OBJ and Stanford PLY files (optionally gzip-compressed)
//! and from the built-in generators, and the TOML scene files that name them.

pub mod generate;
mod obj;
mod ply;
pub mod scene_file;

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Mesh file formats, told apart by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
}

impl MeshFormat {
    /// The format and whether the file is gzip-compressed, from its name:
    /// `.obj`, `.obj.gz`, `.ply`, `.ply.gz` (case-insensitive).
    pub fn from_path(path: &Path) -> Option<(MeshFormat, bool)> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let (stem, gzip) = match name.strip_suffix(".gz") {
            Some(stem) => (stem.to_string(), true),
            None => (name, false),
        };
        let format = if stem.ends_with(".obj") {
            MeshFormat::Obj
        } else if stem.ends_with(".ply") {
            MeshFormat::Ply
        } else {
            return None;
        };
        Some((format, gzip))
    }
}

/// Reads a mesh file: OBJ or PLY, plain or gzip-compressed. Every failure is an
/// [`Error::Input`] naming the file, and the line where the parser knows it.
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    let (format, gzip) = MeshFormat::from_path(path).ok_or_else(|| {
        Error::input(
            path,
            "unknown mesh format: expected a .obj, .obj.gz, .ply or .ply.gz file",
        )
    })?;
    let bytes = read_file(path, gzip)?;
    let mesh = match format {
        MeshFormat::Obj => obj::parse(path, &bytes)?,
        MeshFormat::Ply => ply::parse(path, &bytes)?,
    };
    mesh.check(path)?;
    Ok(mesh)
}

/// The whole file, decompressed if `gzip`.
fn read_file(path: &Path, gzip: bool) -> Result<Vec<u8>> {
    if path.is_dir() {
        return Err(Error::input(path, "is a directory, not a mesh file"));
    }
    let raw = std::fs::read(path).map_err(|e| Error::input(path, io_reason(&e)))?;
    if !gzip {
        return Ok(raw);
    }
    let mut out = Vec::with_capacity(raw.len() * 4);
    flate2::read::GzDecoder::new(raw.as_slice())
        .read_to_end(&mut out)
        .map_err(|e| Error::input(path, format!("cannot decompress gzip data: {e}")))?;
    Ok(out)
}

/// A short reason for an I/O error, without the "(os error N)" noise.
pub(crate) fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => {
            let text = e.to_string();
            match text.find(" (os error") {
                Some(i) => text[..i].to_string(),
                None => text,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension() {
        let f = |s: &str| MeshFormat::from_path(Path::new(s));
        assert_eq!(f("a/bunny.obj"), Some((MeshFormat::Obj, false)));
        assert_eq!(f("DRAGON.OBJ.GZ"), Some((MeshFormat::Obj, true)));
        assert_eq!(f("x.ply"), Some((MeshFormat::Ply, false)));
        assert_eq!(f("x.ply.gz"), Some((MeshFormat::Ply, true)));
        assert_eq!(f("x.stl"), None);
        assert_eq!(f("x.gz"), None);
    }
}
