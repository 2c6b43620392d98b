//! Wavefront OBJ through `tobj`: polygons cut into triangles by ear clipping
//! ([`crate::mesh::triangulate_polygon`]), every object and group merged into one triangle
//! list in file order.

use std::borrow::Cow;
use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::{MeshFile, Polygons, mtl, quoted, unused_note};
use crate::error::{Error, Result};
use crate::material::Materials;
use crate::mesh::{Mesh, coordinate_problem};

/// Parses an OBJ file's bytes; `path` names it in errors and locates its `mtllib` files.
/// Without `read_materials` no MTL file is opened and every triangle is grey.
pub(super) fn parse(path: &Path, bytes: &[u8], read_materials: bool) -> Result<MeshFile> {
    // A UTF-8 byte order mark would hide the first line's keyword from tobj, and a first
    // `v` line dropped that way shifts every index after it.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if let Some(nul) = bytes.iter().position(|&b| b == 0) {
        let line = 1 + bytes[..nul].iter().filter(|&&b| b == b'\n').count();
        return Err(Error::input_at(
            path,
            line,
            "the file holds NUL bytes: binary data or UTF-16 text, not OBJ text",
        ));
    }
    let mut unused = Unused::default();
    let text = positions_only(bytes, &mut unused);
    let bytes: &[u8] = &text;
    let options = tobj::LoadOptions {
        single_index: true,
        // tobj fans polygons from their first corner, which is wrong for concave ones:
        // they are cut here, by ear clipping.
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // A missing or broken MTL file must not stop the geometry: it comes back as an error
    // in `library`, and the mesh turns grey with a warning.
    let failures = std::cell::RefCell::new(Vec::new());
    let load_library = |name: &Path| match read_materials {
        true => mtl::load_library(path, name, &failures),
        false => Err(tobj::LoadError::OpenFileFailed),
    };
    let (models, library) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, load_library)
        .map_err(|e| describe(path, bytes, e))?;

    let mut mesh = Mesh::default();
    let mut polygons = Polygons::default();
    // Triangles of each model, for its material.
    let mut per_model = Vec::with_capacity(models.len());
    let mut corners = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let offset = mesh.positions.len() as u32;
        let before = mesh.triangles.len();
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        // tobj leaves the arities out when every face is a triangle.
        if m.face_arities.is_empty() {
            mesh.triangles.extend(
                m.indices
                    .chunks_exact(3)
                    .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
            );
        } else {
            let mut start = 0;
            for &arity in &m.face_arities {
                let face = &m.indices[start..start + arity as usize];
                start += arity as usize;
                if face.is_empty() {
                    return Err(empty_face(path, bytes));
                }
                corners.clear();
                corners.extend(face.iter().map(|&i| i + offset));
                polygons.cut(&mesh.positions, &corners, &mut mesh.triangles);
            }
        }
        per_model.push(mesh.triangles.len() - before);
    }
    check_positions(path, bytes, &mesh)?;
    let mut warnings = Vec::new();
    let materials = match read_materials {
        true => {
            let failures = failures.into_inner();
            let (materials, failed) = mtl::assign(&models, &per_model, library, failures, path);
            warnings.extend(failed);
            materials
        }
        false => Materials::default(),
    };
    warnings.extend(polygons.warnings(path));
    Ok(MeshFile {
        mesh,
        materials,
        warnings,
        notes: unused.note(path).into_iter().collect(),
        camera: None,
    })
}

/// What an OBJ file holds that cltrace reads past: `vn`, `vt` lines and vertex colours.
#[derive(Default)]
struct Unused {
    normals: bool,
    texture_coordinates: bool,
    colours: bool,
}

impl Unused {
    fn note(&self, path: &Path) -> Option<String> {
        let what: Vec<&str> = [
            (self.normals, "vertex normals"),
            (self.texture_coordinates, "texture coordinates"),
            (self.colours, "vertex colours"),
        ]
        .into_iter()
        .filter_map(|(has, what)| has.then_some(what))
        .collect();
        unused_note(path, &what)
    }
}

/// The error for an `f` line without vertices (tobj gives it no line), at its line.
fn empty_face(path: &Path, bytes: &[u8]) -> Error {
    match first_line(bytes, |words| {
        (words == ["f"]).then(|| "a face without vertices".to_string())
    }) {
        Some((line, message)) => Error::input_at(path, line, message),
        None => Error::input(path, "a face without vertices"),
    }
}

/// The text tobj is given: what cltrace reads (positions and faces) with every line kept
/// in place, so that line numbers stay right. Texture coordinates and normals are blanked
/// out and face references cut to their vertex index: tobj checks `vt`/`vn` references with
/// arithmetic that overflows (a panic in debug builds) on `f 1/0 2/0 3/0`. A `usemtl` or
/// `mtllib` without a name goes too: tobj fails on the first and cannot open the second. Line (`l`) and point (`p`) elements go too: tobj
/// would make a triangle of `l 1 2 3`. Vertex colours are dropped too: tobj refuses a
/// file where only some vertices have them. What is dropped is recorded in `unused`.
fn positions_only<'a>(bytes: &'a [u8], unused: &mut Unused) -> Cow<'a, [u8]> {
    let mut out: Option<Vec<u8>> = None;
    let mut done = 0;
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        match (rewrite_line(line, unused), &mut out) {
            (None, Some(out)) => out.extend_from_slice(line),
            (None, None) => {}
            (Some(new), out) => out
                .get_or_insert_with(|| {
                    let mut v = Vec::with_capacity(bytes.len());
                    v.extend_from_slice(&bytes[..done]);
                    v
                })
                .extend_from_slice(&new),
        }
        done += line.len();
    }
    match out {
        Some(out) => Cow::Owned(out),
        None => Cow::Borrowed(bytes),
    }
}

/// The replacement for one line (ending in a newline), or `None` to keep it. Words are
/// split as tobj splits them, at any Unicode whitespace (a vertical tab or a no-break space
/// too): a `vt` reference that tobj sees but this missed would reach tobj's overflowing
/// arithmetic. A line that is not UTF-8 is kept, for tobj to refuse.
fn rewrite_line(line: &[u8], unused: &mut Unused) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(line).ok()?;
    let mut words = text.split_whitespace();
    let keyword = words.next()?;
    let rebuilt = |words: &mut dyn Iterator<Item = &str>| {
        let mut new = keyword.to_string();
        for w in words {
            new.push(' ');
            new.push_str(w);
        }
        new.push('\n');
        Some(new.into_bytes())
    };
    match keyword {
        "vt" => {
            unused.texture_coordinates = true;
            Some(b"\n".to_vec())
        }
        "vn" => {
            unused.normals = true;
            Some(b"\n".to_vec())
        }
        // Lines and points are not surfaces, but tobj makes a triangle of `l 1 2 3`.
        "l" | "p" => Some(b"\n".to_vec()),
        // tobj takes the name after the first space, so a tab or leading blank would lose
        // it: write `keyword name` (names may hold spaces), or nothing without a name.
        "usemtl" | "mtllib" => {
            let name = text.trim_start()[keyword.len()..].trim();
            let new = match name.is_empty() {
                true => "\n".to_string(),
                false => format!("{keyword} {name}\n"),
            };
            (new != text).then(|| new.into_bytes())
        }
        "f" if text.contains('/') => rebuilt(&mut words.map(|w| {
            match w.split('/').next() {
                // `/2` has no vertex index: keep it whole for tobj to refuse
                Some(v) if !v.is_empty() => v,
                _ => w,
            }
        })),
        // `v x y z r g b`: keep `v x y z`
        "v" if words.clone().count() == 6 => {
            unused.colours = true;
            rebuilt(&mut words.take(3))
        }
        _ => None,
    }
}

/// Refuses a NaN, infinite or too large vertex that a triangle uses, naming its line.
/// tobj does not say which line a vertex came from, so the first `v` line with the same
/// value is taken; [`Mesh::check`] still catches anything this misses.
fn check_positions(path: &Path, bytes: &[u8], mesh: &Mesh) -> Result<()> {
    let Some((bad, problem)) = mesh.triangles.iter().flatten().find_map(|&v| {
        let p = mesh.positions[v as usize];
        coordinate_problem(p).map(|problem| (p, problem))
    }) else {
        return Ok(());
    };
    let same = |p: Vec3| {
        p.to_array()
            .iter()
            .zip(bad.to_array())
            .all(|(&a, b)| a == b || (a.is_nan() && b.is_nan()))
    };
    let found = first_line(bytes, |words| {
        (words.first() == Some(&"v") && parse_vertex(&words[1..]).is_some_and(same))
            .then(|| format!("vertex with {problem}"))
    });
    match found {
        Some((line, message)) => Err(Error::input_at(path, line, message)),
        None => Ok(()),
    }
}

/// A `v` line's position as tobj computes it: `x y z`, divided by `w` when there is one.
fn parse_vertex(words: &[&str]) -> Option<Vec3> {
    let numbers: Vec<f32> = words
        .iter()
        .take(4)
        .map(|w| w.parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .ok()?;
    match (numbers.as_slice(), words.len()) {
        ([x, y, z, w], 4) => Some(Vec3::new(x / w, y / w, z / w)),
        ([x, y, z, ..], _) => Some(Vec3::new(*x, *y, *z)),
        _ => None,
    }
}

/// Turns a `tobj` error into one line naming the file and, by scanning the text again,
/// the offending line (tobj itself does not report lines).
fn describe(path: &Path, bytes: &[u8], err: tobj::LoadError) -> Error {
    use tobj::LoadError::*;
    let found = match err {
        ReadError => not_utf8(bytes).map(|line| (line, "the file is not UTF-8 text".to_string())),
        PositionParseError | ScalingByZeroError | ColorParseError => {
            first_line(bytes, |words| match words.first() {
                Some(&"v") => vertex_problem(&words[1..]),
                _ => None,
            })
        }
        FaceParseError | FaceVertexOutOfBounds => bad_face(bytes),
        _ => None,
    };
    match found {
        Some((line, message)) => Error::input_at(path, line, message),
        None => Error::input(path, format!("cannot parse OBJ: {err}")),
    }
}

/// Why tobj refuses a `v` line with these words after the `v`, if it does: it takes
/// `x y z`, `x y z w` (w not 0) or `x y z r g b`.
fn vertex_problem(words: &[&str]) -> Option<String> {
    let numbers = |ws: &[&str]| ws.iter().all(|w| w.parse::<f32>().is_ok());
    if words.len() < 3 || !numbers(&words[..3]) || !matches!(words.len(), 3 | 4 | 6) {
        return Some("a vertex needs three numbers, as `v x y z`".to_string());
    }
    match words.get(3).map(|w| w.parse::<f32>()) {
        Some(Err(_)) if words.len() == 4 => Some(format!(
            "vertex weight {} is not a number",
            quoted(words[3])
        )),
        Some(Ok(w)) if words.len() == 4 && w == 0.0 => Some("vertex weight w is 0".to_string()),
        _ => None,
    }
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
                Err(_) => Some(format!("face vertex {} is not an index", quoted(w))),
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
