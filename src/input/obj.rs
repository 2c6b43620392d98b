//! Wavefront OBJ through `tobj`: polygons fan-triangulated, every object and group merged
//! into one triangle list in file order.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::mesh::Mesh;

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not used yet; a missing .mtl must not stop the geometry.
    let no_materials = |_: &Path| Err(tobj::LoadError::OpenFileFailed);
    let (models, _materials) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, no_materials)
        .map_err(|e| describe(path, bytes, e))?;

    let mut mesh = Mesh::default();
    for model in &models {
        let m = &model.mesh;
        let offset = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }
    Ok(mesh)
}

/// Turns a `tobj` error into one line naming the file and, by scanning the text again,
/// the offending line (tobj itself does not report lines).
fn describe(path: &Path, bytes: &[u8], err: tobj::LoadError) -> Error {
    use tobj::LoadError::*;
    let found = match err {
        ReadError => not_utf8(bytes).map(|line| (line, "the file is not UTF-8 text".to_string())),
        PositionParseError => first_line(bytes, |words| {
            (words.first() == Some(&"v") && !vertex_ok(&words[1..]))
                .then(|| "a vertex needs three numbers, as `v x y z`".to_string())
        }),
        FaceParseError | FaceVertexOutOfBounds => bad_face(bytes),
        _ => None,
    };
    match found {
        Some((line, message)) => Error::input_at(path, line, message),
        None => Error::input(path, format!("cannot parse OBJ: {err}")),
    }
}

fn vertex_ok(words: &[&str]) -> bool {
    words.len() >= 3 && words[..3].iter().all(|w| w.parse::<f32>().is_ok())
}

/// Calls `check` with the words of each line; the first `Some` gives (1-based line, message).
fn first_line(
    bytes: &[u8],
    mut check: impl FnMut(&[&str]) -> Option<String>,
) -> Option<(usize, String)> {
    let text = String::from_utf8_lossy(bytes);
    text.lines().enumerate().find_map(|(i, line)| {
        let words: Vec<&str> = line.split_whitespace().collect();
        check(&words).map(|m| (i + 1, m))
    })
}

/// The first face whose vertex reference does not parse or points outside the vertices
/// read so far (OBJ indices start at 1; negative ones count back from the last vertex).
fn bad_face(bytes: &[u8]) -> Option<(usize, String)> {
    let mut vertices: i64 = 0;
    first_line(bytes, |words| {
        match words.first() {
        Some(&"v") => {
            vertices += 1;
            None
        }
        Some(&"f") => words[1..].iter().find_map(|w| {
            let index = w.split('/').next().unwrap_or("");
            match index.parse::<i64>() {
                Err(_) => Some(format!("face vertex `{w}` is not an index")),
                Ok(0) => Some("face vertex index 0: OBJ indices start at 1".to_string()),
                Ok(i) if i > vertices || -i > vertices => Some(format!(
                    "face vertex index {i} is out of range: {vertices} vertices are defined before this line"
                )),
                Ok(_) => None,
            }
        }),
        _ => None,
    }
    })
}

/// 1-based line of the first byte that is not valid UTF-8.
fn not_utf8(bytes: &[u8]) -> Option<usize> {
    let valid = std::str::from_utf8(bytes).err()?.valid_up_to();
    Some(1 + bytes[..valid].iter().filter(|&&b| b == b'\n').count())
}
