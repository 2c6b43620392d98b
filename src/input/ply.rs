//! Stanford PLY (ASCII, binary little- and big-endian) through `ply-rs-bw`: the `vertex`
//! element's x, y, z and the `face` element's index list, faces of any size cut into
//! triangles by ear clipping ([`crate::mesh::triangulate_polygon`]).

use std::io::{BufReader, Cursor};
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{Encoding, Property, PropertyAccess, PropertyAccessResult};

use super::{MeshFile, Polygons, unused_note};
use crate::error::{Error, Result};
use crate::material::Materials;
use crate::mesh::Mesh;

/// Vertex properties cltrace reads past, by what they are: normals, texture coordinates
/// (under the names PLY writers use) and colours.
const UNUSED: [(&str, &[&str]); 3] = [
    ("vertex normals", &["nx", "ny", "nz"]),
    (
        "texture coordinates",
        &[
            "s",
            "t",
            "u",
            "v",
            "texture_u",
            "texture_v",
            "texture_s",
            "texture_t",
        ],
    ),
    (
        "vertex colours",
        &[
            "red",
            "green",
            "blue",
            "alpha",
            "diffuse_red",
            "diffuse_green",
            "diffuse_blue",
        ],
    ),
];

/// Parses a PLY file's bytes; `path` names it in messages. Its triangles are grey.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<MeshFile> {
    let mut reader = Reader::new(BufReader::new(Cursor::new(bytes)));
    let header = Parser::<Vertex>::new()
        .read_header(&mut reader)
        .map_err(|e| describe(path, e, true))?;
    // Lines mean something in the header and in an ASCII body, not in a binary one.
    let fail = |e| describe(path, e, header.encoding == Encoding::Ascii);
    for needed in ["vertex", "face"] {
        if !header.elements.contains_key(needed) {
            return Err(Error::input(
                path,
                format!("the PLY header declares no `{needed}` element, so there are no triangles"),
            ));
        }
    }

    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut unused = Vec::new();
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                for axis in ["x", "y", "z"] {
                    if !element.properties.contains_key(axis) {
                        return Err(Error::input(
                            path,
                            format!("the vertex element has no `{axis}` property"),
                        ));
                    }
                }
                unused = UNUSED
                    .iter()
                    .filter(|(_, names)| names.iter().any(|n| element.properties.contains_key(*n)))
                    .map(|(what, _)| *what)
                    .collect();
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?;
            }
            "face" => {
                if !element.properties.contains_key("vertex_indices")
                    && !element.properties.contains_key("vertex_index")
                {
                    return Err(Error::input(
                        path,
                        "the face element has no `vertex_indices` list",
                    ));
                }
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?;
            }
            // An element without properties has no bytes in a binary body, so reading
            // it does nothing, as many times as its count says: 2^64 - 1 would never end.
            _ if element.properties.is_empty() && header.encoding != Encoding::Ascii => {}
            // Other elements (edges, materials, ...) are read past and dropped.
            _ => {
                Parser::<Ignored>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?;
            }
        }
    }

    let positions: Vec<Vec3> = vertices.iter().map(|v| v.0).collect();
    let mut triangles = Vec::with_capacity(faces.len());
    let mut polygons = Polygons::default();
    let mut corners = Vec::new();
    for (i, face) in faces.iter().enumerate() {
        let idx = &face.0;
        if let Some(&bad) = idx.iter().find(|&&v| v < 0 || v >= positions.len() as i64) {
            return Err(Error::input(
                path,
                format!(
                    "face {i} uses vertex {bad}, but there are only {} vertices",
                    positions.len()
                ),
            ));
        }
        corners.clear();
        corners.extend(idx.iter().map(|&v| v as u32));
        polygons.cut(&positions, &corners, &mut triangles);
    }
    Ok(MeshFile {
        mesh: Mesh::new(positions, triangles),
        materials: Materials::default(),
        warnings: polygons.warnings(path),
        notes: unused_note(path, &unused).into_iter().collect(),
        camera: None,
    })
}

/// One line for a `ply-rs-bw` error, at its line where `lines` (the text it read is lines
/// of text, not binary data).
fn describe(path: &Path, e: ParseError, lines: bool) -> Error {
    let text = e.to_string();
    // The error's Display puts "Line N: " in front; the line goes in our own prefix.
    let text = match e.line() {
        Some(line) => text
            .strip_prefix(&format!("Line {line}: "))
            .unwrap_or(&text)
            .to_string(),
        None => text,
    };
    let message = one_line(&text);
    match e.line() {
        Some(line) if lines => Error::input_at(path, line, message),
        _ => Error::input(path, format!("cannot parse PLY: {message}")),
    }
}

/// `ply-rs-bw` messages come in tab-indented parts: the summary, `String: 'the line'` and
/// `Error: ...` details. This keeps the summary, the offending text (shortened) and the
/// readable details, and drops the parser generator's internals, all on one line.
fn one_line(text: &str) -> String {
    let mut parts = Vec::new();
    for part in text.split("\n\t") {
        let part = part.trim();
        if part.starts_with("Error: ParseError {") {
            continue;
        }
        match part.strip_prefix("String: ") {
            Some(quoted) => {
                let inner = quoted.trim_matches('\'').trim();
                let short: String = inner.chars().take(60).collect();
                let more = if inner.chars().count() > 60 {
                    "..."
                } else {
                    ""
                };
                let quoted = format!("`{short}{more}`");
                // nested errors quote the same line again
                if !parts.contains(&quoted) {
                    parts.push(quoted);
                }
            }
            None => parts.push(part.to_string()),
        }
    }
    let joined = parts.join(" ");
    let clean: String = joined
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    let words: Vec<&str> = clean.split_whitespace().collect();
    let mut message: String = words.join(" ").chars().take(300).collect();
    while message.ends_with(',') {
        message.pop();
    }
    message
}

/// Any numeric property as a float, so that double or integer coordinates work too.
fn as_f64(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

/// Any integer list property as i64 indices.
fn as_indices(p: Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
        _ => return None,
    })
}

struct Vertex(Vec3);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex(Vec3::ZERO)
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        match as_f64(&property) {
            Some(v) => {
                self.0[axis] = v as f32;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

struct Face(Vec<i64>);

impl PropertyAccess for Face {
    fn new() -> Self {
        Face(Vec::new())
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        match as_indices(property) {
            Some(indices) => {
                self.0 = indices;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Ignored
    }
}
