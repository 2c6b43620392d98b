//! Scene input: meshes from Wavefront OBJ and Stanford PLY files (optionally gzip-compressed),
//! glTF 2.0 files and the built-in generators, and the TOML scene files that name them.

pub mod generate;
mod gltf;
pub mod lights;
mod mtl;
mod obj;
mod ply;
pub mod scene;
pub mod scene_file;
pub mod texture;

use std::io::Read;
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::material::Materials;
use crate::mesh::{Mesh, Triangulation, triangulate_polygon};

pub use mtl::parse_library as parse_material_library;

/// Mesh file formats, told apart by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`), with materials from its MTL libraries.
    Obj,
    /// Stanford PLY (`.ply`): ASCII or binary, geometry only.
    Ply,
    /// glTF 2.0 JSON (`.gltf`), with its buffers and images in files beside it or in data
    /// URIs.
    Gltf,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
}

impl MeshFormat {
    /// The format and whether the file is gzip-compressed, from its name:
    /// `.obj`, `.obj.gz`, `.ply`, `.ply.gz`, `.gltf`, `.glb` (case-insensitive).
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
        } else if stem.ends_with(".gltf") && !gzip {
            MeshFormat::Gltf
        } else if stem.ends_with(".glb") && !gzip {
            MeshFormat::Glb
        } else {
            return None;
        };
        Some((format, gzip))
    }
}

/// Reads a mesh file: OBJ or PLY, plain or gzip-compressed, or glTF. Every failure is an
/// [`Error::Input`] naming the file, and the line where the parser knows it.
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    Ok(read_mesh(path, false)?.mesh)
}

/// A mesh file's triangles and materials.
pub struct MeshFile {
    /// The triangles in file order, checked by [`Mesh::check`].
    pub mesh: Mesh,
    /// An OBJ's materials from its MTL files (`Kd`, `Ke`), a glTF file's PBR materials and
    /// textures; grey for PLY.
    pub materials: Materials,
    /// What the file holds that is wrong but no reason to refuse it, each a line to warn
    /// with: why the materials are grey although the file names some (a missing or broken
    /// MTL file), how many polygons could not be cut exactly.
    pub warnings: Vec<String>,
    /// What the verbose output says about the file besides its size: the vertex
    /// attributes read, what was read past (unsupported glTF parts), each a line.
    pub notes: Vec<String>,
    /// The file's own camera (a glTF file's first perspective camera): the default when
    /// neither the flags nor the scene file place the camera.
    pub camera: Option<crate::camera::CameraSettings>,
}

/// Reads a mesh file with its materials, as [`load_mesh`] does plus the OBJ's MTL files.
pub fn load_mesh_with_materials(path: &Path) -> Result<MeshFile> {
    read_mesh(path, true)
}

fn read_mesh(path: &Path, read_materials: bool) -> Result<MeshFile> {
    // A folder is named as one whatever its name, before its extension is judged.
    if path.is_dir() {
        return Err(Error::input(path, "is a directory, not a mesh file"));
    }
    let (format, gzip) = MeshFormat::from_path(path).ok_or_else(|| {
        Error::input(
            path,
            "unknown mesh format: expected a .obj, .obj.gz, .ply, .ply.gz, .gltf or .glb file",
        )
    })?;
    let bytes = read_file(path)?;
    // A glTF file's URIs are relative to its folder.
    let folder = path.parent().unwrap_or(Path::new("."));
    parse(path, format, gzip, &bytes, read_materials, Some(folder))
}

/// Parses a mesh file's bytes (decompressing them first if `gzip`) as [`load_mesh`] does
/// after reading the file: the fuzz targets and tests call it without a file system.
/// `path_for_messages` only names the file in errors. A glTF file whose buffers are
/// external files is refused (there is no folder to read them from).
pub fn parse_mesh_bytes(
    path_for_messages: &Path,
    format: MeshFormat,
    gzip: bool,
    bytes: &[u8],
) -> Result<Mesh> {
    Ok(parse(path_for_messages, format, gzip, bytes, false, None)?.mesh)
}

/// Parses a glTF or GLB file's bytes with its materials and textures, as
/// [`load_mesh_with_materials`] does, without a file system: buffers and images must be
/// in data URIs or the GLB's binary chunk (an external one is an error). For the fuzz
/// targets and tests.
pub fn parse_gltf_bytes(path_for_messages: &Path, bytes: &[u8]) -> Result<MeshFile> {
    let file = gltf::parse(path_for_messages, bytes, None, true)?;
    file.mesh.check(path_for_messages)?;
    Ok(file)
}

fn parse(
    path: &Path,
    format: MeshFormat,
    gzip: bool,
    bytes: &[u8],
    read_materials: bool,
    folder: Option<&Path>,
) -> Result<MeshFile> {
    let decompressed;
    let bytes = if gzip {
        decompressed = gunzip(path, bytes)?;
        decompressed.as_slice()
    } else {
        bytes
    };
    let file = match format {
        MeshFormat::Obj => obj::parse(path, bytes, read_materials)?,
        MeshFormat::Ply => ply::parse(path, bytes)?,
        MeshFormat::Gltf | MeshFormat::Glb => gltf::parse(path, bytes, folder, read_materials)?,
    };
    file.mesh.check(path)?;
    let mut file = file;
    file.notes.extend(attributes_note(path, &file.mesh));
    Ok(file)
}

/// The verbose note of the vertex attributes a mesh file gave, or `None` for none.
pub(crate) fn attributes_note(path: &Path, mesh: &Mesh) -> Option<String> {
    let what: Vec<&str> = [
        (!mesh.normals.is_empty(), "vertex normals"),
        (!mesh.uvs.is_empty(), "texture coordinates"),
        (!mesh.colors.is_empty(), "vertex colours"),
    ]
    .into_iter()
    .filter_map(|(has, what)| has.then_some(what))
    .collect();
    let list = match what.as_slice() {
        [] => return None,
        [one] => one.to_string(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    };
    Some(format!("{}: read its {list}", path.display()))
}

/// The polygons of a file cut into triangles, with count of those that could not be cut
/// exactly, for the loader's warning.
#[derive(Default)]
pub(crate) struct Polygons {
    not_simple: usize,
    too_costly: usize,
}

impl Polygons {
    /// Cuts the polygon `corners` (indices into `positions`) into triangles appended to
    /// `out`, as [`triangulate_polygon`] does, and counts it if it had to be fanned.
    pub(crate) fn cut(&mut self, positions: &[Vec3], corners: &[u32], out: &mut Vec<[u32; 3]>) {
        match triangulate_polygon(positions, corners, out) {
            Triangulation::NotSimple => self.not_simple += 1,
            Triangulation::TooCostly => self.too_costly += 1,
            Triangulation::Ears | Triangulation::Flat => {}
        }
    }

    /// The warnings for `path`: how many polygons were fanned because they are not simple,
    /// or too large to cut.
    pub(crate) fn warnings(&self, path: &Path) -> Vec<String> {
        let counted = |count: usize, why: &str| {
            let (noun, verb) = match count {
                1 => ("polygon", "is"),
                _ => ("polygons", "are"),
            };
            format!(
                "{count} {noun} of {} {verb} {why}: fan-triangulated",
                path.display()
            )
        };
        let mut out = Vec::new();
        if self.not_simple > 0 {
            out.push(counted(self.not_simple, "not simple"));
        }
        if self.too_costly > 0 {
            out.push(counted(self.too_costly, "too large to ear-clip"));
        }
        out
    }
}

/// The whole file.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    if path.is_dir() {
        return Err(Error::input(path, "is a directory, not a mesh file"));
    }
    std::fs::read(path).map_err(|e| Error::input(path, io_reason(&e)))
}

/// The most bytes a gzip-compressed mesh may expand to: far above any mesh cltrace can
/// index, low enough that a decompression bomb is an error rather than an exhausted machine.
pub(crate) const MAX_DECOMPRESSED_BYTES: u64 = 4 << 30;

/// gzip data decompressed.
fn gunzip(path: &Path, raw: &[u8]) -> Result<Vec<u8>> {
    gunzip_at_most(path, raw, MAX_DECOMPRESSED_BYTES)
}

fn gunzip_at_most(path: &Path, raw: &[u8], limit: u64) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(raw.len().saturating_mul(4));
    flate2::read::GzDecoder::new(raw)
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| Error::input(path, format!("cannot decompress gzip data: {e}")))?;
    if out.len() as u64 > limit {
        return Err(Error::input(
            path,
            format!("decompresses to more than {limit} bytes: refused"),
        ));
    }
    Ok(out)
}

/// Text from a file, quoted in backticks for an error message: control characters
/// escaped (a message stays one clean line) and cut after 60 characters.
pub(crate) fn quoted(text: &str) -> String {
    let mut out = String::from("`");
    for (i, c) in text.chars().enumerate() {
        if i == 60 {
            out.push_str("...");
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out.push('`');
    out
}

/// `text` as one clean line: line breaks become spaces, other control characters escapes.
pub(crate) fn clean_line(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\n' | '\r' => out.push(' '),
            c if c.is_control() => out.extend(c.escape_default()),
            c => out.push(c),
        }
    }
    out
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
        assert_eq!(f("Scene.GLTF"), Some((MeshFormat::Gltf, false)));
        assert_eq!(f("scene.glb"), Some((MeshFormat::Glb, false)));
        assert_eq!(f("scene.glb.gz"), None);
        assert_eq!(f("x.stl"), None);
        assert_eq!(f("x.gz"), None);
    }

    /// Data that expands past the bound is refused (a bomb), data within it comes back whole.
    #[test]
    fn gzip_expansion_is_bounded() {
        use std::io::Write;
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        gz.write_all(&vec![b'#'; 1 << 20]).unwrap();
        let raw = gz.finish().unwrap();
        let path = Path::new("bomb.obj.gz");
        assert_eq!(gunzip_at_most(path, &raw, 1 << 20).unwrap().len(), 1 << 20);
        let err = gunzip_at_most(path, &raw, (1 << 20) - 1)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bomb.obj.gz") && err.contains("refused"),
            "{err}"
        );
    }
}
