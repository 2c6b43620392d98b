//! Stanford PLY (ASCII, binary little- and big-endian) through `ply-rs-bw`: the `vertex`
//! element's x, y, z, its normals (`nx ny nz`), texture coordinates (`s t`, `u v`,
//! `texture_u texture_v`, `texture_s texture_t`) and colours (`red green blue`, bytes or
//! floats in [0, 1], sRGB), and the `face` element's index list, faces of any size cut
//! into triangles by ear clipping ([`crate::mesh::triangulate_polygon`]).

use std::io::{BufReader, Cursor};
use std::path::Path;

use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{Encoding, Property, PropertyAccess, PropertyAccessResult};

use super::{MeshFile, Polygons};
use crate::error::{Error, Result};
use crate::material::Materials;
use crate::mesh::Mesh;

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

    let positions: Vec<Vec3> = vertices.iter().map(|v| v.position).collect();
    // An attribute counts only if every vertex has all of its parts.
    let all = |bit: u8| !vertices.is_empty() && vertices.iter().all(|v| v.has & bit == bit);
    let mut mesh = Mesh::new(Vec::new(), Vec::new());
    if all(HAS_NORMAL) {
        mesh.normals = vertices.iter().map(|v| v.normal).collect();
    }
    if all(HAS_UV) {
        mesh.uvs = vertices.iter().map(|v| v.uv).collect();
    }
    if all(HAS_COLOR) {
        let byte = vertices.iter().any(|v| v.byte_color);
        mesh.colors = vertices
            .iter()
            .map(|v| {
                let c = if byte { v.color / 255.0 } else { v.color };
                c.clamp(Vec3::ZERO, Vec3::ONE)
                    .to_array()
                    .map(super::texture::srgb_to_linear)
                    .into()
            })
            .collect();
    }
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
    mesh.positions = positions;
    mesh.triangles = triangles;
    Ok(MeshFile {
        mesh,
        materials: Materials::default(),
        warnings: polygons.warnings(path),
        notes: Vec::new(),
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

/// Which of a vertex's attribute parts were set, as bits of [`Vertex::has`]: a normal
/// needs all of nx, ny, nz (bits 0-2), a texture coordinate both parts (3-4), a colour all
/// three channels (5-7).
const HAS_NORMAL: u8 = 0b111;
const HAS_UV: u8 = 0b11 << 3;
const HAS_COLOR: u8 = 0b111 << 5;

#[derive(Default)]
struct Vertex {
    position: Vec3,
    normal: Vec3,
    uv: Vec2,
    color: Vec3,
    has: u8,
    /// Colours given as integers (0 to 255) rather than floats in [0, 1].
    byte_color: bool,
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(v) = as_f64(&property) else {
            return match name {
                "x" | "y" | "z" => PropertyAccessResult::UnsupportedType,
                _ => PropertyAccessResult::Ignored,
            };
        };
        let v32 = v as f32;
        match name {
            "x" => self.position.x = v32,
            "y" => self.position.y = v32,
            "z" => self.position.z = v32,
            "nx" => self.set(|s| s.normal.x = v32, 1),
            "ny" => self.set(|s| s.normal.y = v32, 1 << 1),
            "nz" => self.set(|s| s.normal.z = v32, 1 << 2),
            "s" | "u" | "texture_u" | "texture_s" => self.set(|s| s.uv.x = v32, 1 << 3),
            "t" | "v" | "texture_v" | "texture_t" => self.set(|s| s.uv.y = v32, 1 << 4),
            "red" | "diffuse_red" | "green" | "diffuse_green" | "blue" | "diffuse_blue" => {
                let channel = match name.trim_start_matches("diffuse_") {
                    "red" => 0,
                    "green" => 1,
                    _ => 2,
                };
                self.byte_color |= !matches!(property, Property::Float(_) | Property::Double(_));
                self.set(|s| s.color[channel] = v32, 1 << (5 + channel))
            }
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }
}

impl Vertex {
    fn set(&mut self, write: impl FnOnce(&mut Self), bit: u8) {
        write(self);
        self.has |= bit;
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
