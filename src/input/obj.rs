//! Wavefront OBJ through `tobj`: polygons cut into triangles by ear clipping
//! ([`crate::mesh::triangulate_polygon`]), every object and group merged into one triangle
//! list in file order. Vertex normals (`vn`), texture coordinates (`vt`) and vertex colours
//! (`v x y z r g b`) are resolved here, not by tobj ([`Attributes`]): a vertex used with
//! different normals or coordinates is split into one vertex per combination.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use glam::{Vec2, Vec3};

use super::{MeshFile, Polygons, mtl, quoted};
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
    if let Some(mesh) = triangles_only(bytes) {
        check_positions(path, bytes, &mesh)?;
        return Ok(MeshFile {
            mesh,
            materials: Materials::default(),
            warnings: Vec::new(),
            notes: Vec::new(),
            camera: None,
        });
    }
    parse_any(path, bytes, read_materials)
}

/// [`parse`] for any OBJ file (its byte order mark taken off, no NUL in it): through tobj.
fn parse_any(path: &Path, bytes: &[u8], read_materials: bool) -> Result<MeshFile> {
    let attributes = Attributes::parse(bytes);
    let text = positions_only(bytes);
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
    // Per face in file order: its corners' vertex indices and its range of triangles.
    let mut faces: Vec<(Vec<u32>, std::ops::Range<usize>)> = Vec::new();
    let track = attributes.any();
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
            if track {
                for (i, t) in mesh.triangles[before..].iter().enumerate() {
                    faces.push((t.to_vec(), before + i..before + i + 1));
                }
            }
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
                let first = mesh.triangles.len();
                polygons.cut(&mesh.positions, &corners, &mut mesh.triangles);
                if track {
                    faces.push((corners.clone(), first..mesh.triangles.len()));
                }
            }
        }
        per_model.push(mesh.triangles.len() - before);
    }
    check_positions(path, bytes, &mesh)?;
    let mut warnings = Vec::new();
    if track && let Err(why) = attributes.apply(&mut mesh, &faces) {
        warnings.push(format!(
            "{}: its normals, texture coordinates and colours are ignored: {why}",
            path.display()
        ));
    }
    let materials = match read_materials {
        true => {
            let failures = failures.into_inner();
            let (materials, failed) = mtl::assign(&models, &per_model, library, failures, path)?;
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
        notes: Vec::new(),
        camera: None,
    })
}

/// The mesh of a file that holds nothing but `v x y z` lines, triangles of plain vertex
/// indices (`f 1 2 3`, `f -3 -2 -1`), comments, smoothing groups and blank lines, as scanned
/// meshes are written, parsed in parallel; `None` for any other file (or a bad index), which
/// goes the general way. The mesh is the general way's to the bit: vertices in the order
/// of their first use (tobj's `single_index`), the unused ones left out, numbers read by the
/// same `FromStr`. On the 2-core machine the dragon's 33 MB load in 0.1 s instead of 0.6 s.
fn triangles_only(bytes: &[u8]) -> Option<Mesh> {
    use rayon::prelude::*;
    /// One chunk's vertices, and its triangles' indices: 0-based, or for a negative
    /// (relative) index the chunk's vertex count at its line plus the index, flagged.
    #[derive(Default)]
    struct Chunk {
        positions: Vec<Vec3>,
        corners: Vec<(i64, bool)>,
    }
    fn parse_chunk(text: &[u8]) -> Option<Chunk> {
        let mut chunk = Chunk::default();
        for line in text.split(|&b| b == b'\n') {
            let line = std::str::from_utf8(line).ok()?;
            let mut words = line.split_whitespace();
            match words.next() {
                None => {}
                Some(k) if k.starts_with('#') || k == "s" => {}
                Some("v") => {
                    let mut p = [0.0f32; 3];
                    for c in &mut p {
                        *c = words.next()?.parse().ok()?;
                    }
                    if words.next().is_some() {
                        return None;
                    }
                    chunk.positions.push(Vec3::from_array(p));
                }
                Some("f") => {
                    for _ in 0..3 {
                        let i: i64 = words.next()?.parse::<isize>().ok()? as i64;
                        chunk.corners.push(match i < 0 {
                            true => (chunk.positions.len() as i64 + i, true),
                            false => (i - 1, false),
                        });
                    }
                    if words.next().is_some() {
                        return None;
                    }
                }
                Some(_) => return None,
            }
        }
        Some(chunk)
    }
    // About a megabyte a chunk, each ending at a line's end.
    let mut bounds = vec![0];
    while *bounds.last()? < bytes.len() {
        let from = (bounds.last()? + (1 << 20)).min(bytes.len());
        let end = bytes[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| from + i + 1);
        bounds.push(end);
    }
    let chunks: Vec<Chunk> = bounds
        .par_windows(2)
        .map(|w| parse_chunk(&bytes[w[0]..w[1]]))
        .collect::<Option<_>>()?;
    if chunks.iter().map(|c| c.positions.len()).sum::<usize>() > u32::MAX as usize {
        return None;
    }
    let all: Vec<Vec3> = chunks
        .iter()
        .flat_map(|c| c.positions.iter().copied())
        .collect();
    // Vertices in the order of their first use; the unused are left out, as tobj does.
    let mut renumbered = vec![u32::MAX; all.len()];
    let mut positions = Vec::new();
    let mut corners = Vec::with_capacity(chunks.iter().map(|c| c.corners.len()).sum());
    let mut before = 0i64;
    for chunk in &chunks {
        for &(i, relative) in &chunk.corners {
            let v = if relative { before + i } else { i };
            let new = renumbered.get_mut(usize::try_from(v).ok()?)?;
            if *new == u32::MAX {
                *new = positions.len() as u32;
                positions.push(all[v as usize]);
            }
            corners.push(*new);
        }
        before += chunk.positions.len() as i64;
    }
    if corners.is_empty() {
        return None;
    }
    let triangles = corners
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    Some(Mesh::new(positions, triangles))
}

/// A face corner's 0-based (vertex, texture coordinate, normal) indices, `None` where not
/// given or bad.
type Corner = (Option<usize>, Option<usize>, Option<usize>);

/// What an OBJ file says besides positions and faces: its `vt`, `vn` and vertex colour
/// lists, and for each face in file order each corner's references into them (resolved to
/// 0-based indices; `None` where the corner gives none or a bad one).
#[derive(Default)]
struct Attributes {
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// One per `v` line: its colour, if it has one.
    colors: Vec<Option<Vec3>>,
    /// Per face: per corner (vertex, texture coordinate, normal).
    faces: Vec<Vec<Corner>>,
    /// References to no `vt` or `vn` line: (1-based line, the reference).
    bad: Option<(usize, String)>,
}

impl Attributes {
    fn parse(bytes: &[u8]) -> Attributes {
        let mut a = Attributes::default();
        let text = String::from_utf8_lossy(bytes);
        let number = |w: Option<&str>| w.and_then(|w| w.parse::<f32>().ok());
        for (line, text) in text.lines().enumerate() {
            let mut words = text.split_whitespace();
            match words.next() {
                Some("v") => {
                    let w: Vec<f32> = words.filter_map(|w| w.parse().ok()).collect();
                    a.colors
                        .push((w.len() == 6).then(|| Vec3::new(w[3], w[4], w[5])));
                }
                Some("vt") => a.uvs.push(Vec2::new(
                    number(words.next()).unwrap_or(0.0),
                    number(words.next()).unwrap_or(0.0),
                )),
                Some("vn") => a.normals.push(Vec3::new(
                    number(words.next()).unwrap_or(0.0),
                    number(words.next()).unwrap_or(0.0),
                    number(words.next()).unwrap_or(0.0),
                )),
                Some("f") => {
                    let (v, t, n) = (a.colors.len(), a.uvs.len(), a.normals.len());
                    let face = words
                        .map(|w| {
                            let mut parts = w.split('/');
                            let mut next = |count: usize, bad: &mut Option<(usize, String)>| {
                                let part = parts.next().filter(|p| !p.is_empty())?;
                                let resolved = resolve(part, count);
                                if resolved.is_none() && bad.is_none() {
                                    *bad = Some((line + 1, quoted(w)));
                                }
                                resolved
                            };
                            let vertex = next(v, &mut None);
                            let uv = next(t, &mut a.bad);
                            let normal = next(n, &mut a.bad);
                            (vertex, uv, normal)
                        })
                        .collect();
                    a.faces.push(face);
                }
                _ => {}
            }
        }
        a
    }

    /// Whether the file has anything for [`Attributes::apply`] to do.
    fn any(&self) -> bool {
        !self.uvs.is_empty() || !self.normals.is_empty() || self.colors.iter().any(Option::is_some)
    }

    /// Gives `mesh` its vertex attributes: each triangle corner becomes the vertex of its
    /// (position, texture coordinate, normal) combination, so a vertex shared by faces
    /// with different normals (a crease) is split. `faces` are tobj's, in file order: each
    /// face's corners (indices into `mesh.positions`) and the triangles cut from it. An
    /// error says why nothing was read (and the mesh is left as it was).
    fn apply(
        &self,
        mesh: &mut Mesh,
        faces: &[(Vec<u32>, std::ops::Range<usize>)],
    ) -> std::result::Result<(), String> {
        if let Some((line, reference)) = &self.bad {
            return Err(format!(
                "line {line}: {reference} names a texture coordinate or normal that is not defined before it"
            ));
        }
        let own: Vec<&Vec<_>> = self.faces.iter().filter(|f| !f.is_empty()).collect();
        if own.len() != faces.len() {
            return Err(format!(
                "{} faces were read with them but {} without",
                own.len(),
                faces.len()
            ));
        }
        let has_uv = !self.uvs.is_empty();
        let has_normal = !self.normals.is_empty();
        let has_color = self.colors.iter().any(Option::is_some);
        let mut split: HashMap<(u32, Option<usize>, Option<usize>), u32> = HashMap::new();
        let (mut positions, mut normals, mut uvs, mut colors) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut triangles = mesh.triangles.clone();
        for ((corners, range), refs) in faces.iter().zip(own) {
            if corners.len() != refs.len() {
                return Err("a face has a different number of corners than tobj read".into());
            }
            for tri in &mut triangles[range.clone()] {
                for corner in tri.iter_mut() {
                    let slot = corners.iter().position(|c| c == corner).unwrap_or(0);
                    let (vertex, uv, normal) = refs[slot];
                    let key = (*corner, uv, normal);
                    let next = positions.len() as u32;
                    *corner = *split.entry(key).or_insert_with(|| {
                        positions.push(mesh.positions[key.0 as usize]);
                        if has_normal {
                            normals.push(normal.map_or(Vec3::ZERO, |n| self.normals[n]));
                        }
                        if has_uv {
                            uvs.push(uv.map_or(Vec2::ZERO, |t| self.uvs[t]));
                        }
                        if has_color {
                            let c = vertex.and_then(|v| self.colors.get(v).copied().flatten());
                            colors.push(c.map_or(Vec3::ONE, |c| c.clamp(Vec3::ZERO, Vec3::ONE)));
                        }
                        next
                    });
                }
            }
        }
        mesh.positions = positions;
        mesh.triangles = triangles;
        (mesh.normals, mesh.uvs, mesh.colors) = (normals, uvs, colors);
        Ok(())
    }
}

/// A 1-based OBJ reference (negative: counting back from the last of `count`) as a 0-based
/// index, if it names one of the `count` defined so far.
fn resolve(reference: &str, count: usize) -> Option<usize> {
    let i: i64 = reference.parse().ok()?;
    let count = count as i64;
    let index = if i > 0 { i - 1 } else { count + i };
    (i != 0 && (0..count).contains(&index)).then_some(index as usize)
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
fn positions_only(bytes: &[u8]) -> Cow<'_, [u8]> {
    let mut out: Option<Vec<u8>> = None;
    let mut done = 0;
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        match (rewrite_line(line), &mut out) {
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
fn rewrite_line(line: &[u8]) -> Option<Vec<u8>> {
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
        "vt" | "vn" => Some(b"\n".to_vec()),
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
        "v" if words.clone().count() == 6 => rebuilt(&mut words.take(3)),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel path gives the mesh tobj's path gives, to the bit: vertices in the
    /// order of first use, unused ones dropped, relative indices, comments, smoothing
    /// groups, CRLF line ends, and chunks of a megabyte (the file is larger than one).
    #[test]
    fn triangle_files_parse_in_parallel_as_tobj_parses_them() {
        let mut text = String::from("# a header\r\ns off\r\nv 9 9 9\r\n");
        let n = 60_000;
        for i in 0..n {
            let a = i as f32 * 0.37;
            text += &format!("v {} {:e} {}\r\n", a.sin(), a.cos() * 1e-3, 0.1 * a);
        }
        for i in 0..n - 2 {
            // Backwards, so that first use is not file order; every 7th relative.
            let (a, b, c) = (n - i, n - i - 1, n - i - 2);
            text += &match i % 7 {
                0 => "f -1 -2 -3\r\n\r\n".to_string(),
                _ => format!("f {a}  {b}\t{c}\r\n"),
            };
            if i % 5000 == 0 {
                text += &format!("v {i} 0 0\r\n");
            }
        }
        text += "v 5 5 5\r\n";
        assert!(text.len() > 2 << 20, "{} bytes", text.len());
        let fast = triangles_only(text.as_bytes()).expect("a file of triangles");
        let general = parse_any(Path::new("t.obj"), text.as_bytes(), false).unwrap();
        assert_eq!(fast, general.mesh);
        let unused = Vec3::splat(5.0);
        assert!(
            !fast.positions.contains(&unused),
            "the unused vertex is dropped"
        );
    }

    /// The shared scanned meshes (`../shared/scenes`, or `CLTRACE_SCENES`) parse the same
    /// both ways; skipped with a notice where they are absent.
    #[test]
    fn the_scanned_meshes_parse_in_parallel_as_tobj_parses_them() {
        let dir = std::env::var_os("CLTRACE_SCENES").map_or_else(
            || Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes"),
            std::path::PathBuf::from,
        );
        for name in ["stanford_bunny.obj", "stanford_dragon.obj.gz"] {
            let path = dir.join(name);
            let Ok(bytes) = std::fs::read(&path) else {
                eprintln!("notice: {} is absent: skipped", path.display());
                continue;
            };
            let text = match name.ends_with(".gz") {
                true => super::super::gunzip(&path, &bytes).unwrap(),
                false => bytes,
            };
            let fast = triangles_only(&text).expect("a file of triangles");
            assert_eq!(fast, parse_any(&path, &text, false).unwrap().mesh, "{name}");
        }
    }

    #[test]
    fn other_files_go_the_general_way() {
        for text in [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\n",
            "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -1 -2\n",
            "v 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\n",
        ] {
            assert!(triangles_only(text.as_bytes()).is_none(), "{text:?}");
        }
    }
}
