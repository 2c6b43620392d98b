//! Stanford PLY (ASCII, binary little- and big-endian) through `ply-rs-bw`: the `vertex`
//! element's x, y, z and the `face` element's index list, faces of any size fan-triangulated.

use std::io::{BufReader, Cursor};
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

use crate::error::{Error, Result};
use crate::mesh::Mesh;

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let fail = |e: ply_rs_bw::parser::ParseError| match e.line() {
        Some(line) => Error::input_at(path, line, first_line_of(&e.to_string())),
        None => Error::input(
            path,
            format!("cannot parse PLY: {}", first_line_of(&e.to_string())),
        ),
    };
    let mut reader = Reader::new(BufReader::new(Cursor::new(bytes)));
    let header = Parser::<Vertex>::new()
        .read_header(&mut reader)
        .map_err(fail)?;

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
        for k in 2..idx.len() {
            triangles.push([idx[0] as u32, idx[k - 1] as u32, idx[k] as u32]);
        }
    }
    Ok(Mesh::new(positions, triangles))
}

fn first_line_of(text: &str) -> String {
    text.lines().next().unwrap_or("").trim().to_string()
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
