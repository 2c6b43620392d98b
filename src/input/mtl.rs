//! Materials of an OBJ file from its MTL library, through `tobj`: the diffuse colour `Kd`
//! and the emitted radiance `Ke` of each material, mapped onto the triangles.

use std::cell::RefCell;
use std::path::Path;

use crate::input::io_reason;
use crate::material::{Material, Materials};

/// Reads the material library `name` (as an OBJ's `mtllib` names it) beside `obj`. tobj
/// keeps only an error's kind, so what went wrong, with the path tried, is added to
/// `failures` ("cannot open its material library /a/b.mtl (no such file)").
pub(super) fn load_library(
    obj: &Path,
    name: &Path,
    failures: &RefCell<Vec<String>>,
) -> tobj::MTLLoadResult {
    let path = obj.parent().unwrap_or(Path::new("")).join(name);
    let fail = |what: &str, reason: String| {
        // Absolute, so that the message says where it looked whatever the working folder.
        let tried = std::path::absolute(&path).unwrap_or_else(|_| path.clone());
        failures.borrow_mut().push(format!(
            "cannot {what} its material library {} ({reason})",
            tried.display()
        ));
    };
    let bytes = std::fs::read(&path).map_err(|e| {
        fail("open", io_reason(&e));
        tobj::LoadError::OpenFileFailed
    })?;
    tobj::load_mtl_buf(&mut std::io::Cursor::new(complete_colours(&bytes))).inspect_err(|e| {
        fail("read", e.to_string());
    })
}

/// The materials of an MTL library's bytes as the loader reads them (the fuzz target
/// `mtl`), or tobj's reason for refusing it.
pub fn parse_library(bytes: &[u8]) -> Result<Vec<Material>, String> {
    tobj::load_mtl_buf(&mut std::io::Cursor::new(complete_colours(bytes)))
        .map(|(list, _)| list.iter().map(convert).collect())
        .map_err(|e| e.to_string())
}

/// The colour keywords whose values tobj reads as exactly three numbers.
const COLOURS: [&[u8]; 4] = [b"Ka", b"Kd", b"Ks", b"Ke"];

/// The library with every colour given as three numbers. MTL lets `g` and `b` be left
/// out (they then equal `r`: `Kd 0.5` is grey), but tobj panics on fewer than three; a
/// colour line with no value at all is dropped, as if it were not there. Words are split
/// as tobj splits them, at any Unicode whitespace (a vertical tab too): a colour this
/// missed would reach tobj's panic. A line that is not UTF-8 is kept, for tobj to refuse.
fn complete_colours(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len() + 64);
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        let Ok(text) = std::str::from_utf8(line) else {
            out.extend_from_slice(line);
            continue;
        };
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            [key, values @ ..] if COLOURS.contains(&key.as_bytes()) && values.len() < 3 => {
                if let Some(&r) = values.first() {
                    let mut padded = words.clone();
                    padded.extend(std::iter::repeat_n(r, 3 - values.len()));
                    out.extend_from_slice(padded.join(" ").as_bytes());
                    out.push(b'\n');
                }
            }
            _ => out.extend_from_slice(line),
        }
    }
    out
}

/// Our material for a tobj one: `Kd` as albedo (clamped to [0, 1]), `Ke` as emission. A
/// library without `Ke` that gives a material an ambient colour above 1 (the Cornell box of
/// Embree's samples writes its light as `Ka 20 20 20`) has that read as emission.
pub(super) fn convert(m: &tobj::Material) -> Material {
    let albedo = m
        .diffuse
        .map(|kd| {
            kd.map(|c| {
                if c.is_finite() {
                    c.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
        })
        .unwrap_or(crate::material::DEFAULT_ALBEDO);
    let emission = match (m.emissive, m.ambient) {
        (Some(ke), _) => ke,
        (None, Some(ka)) if ka.iter().any(|&c| c > 1.0) => ka,
        _ => [0.0; 3],
    };
    let emission = emission.map(|c| if c.is_finite() { c.max(0.0) } else { 0.0 });
    Material::emitting(albedo, emission)
}

/// The per-triangle materials of the models (in file order, `triangles[i]` triangles each)
/// given tobj's material list: index 0 is the default grey, then the library's materials.
/// Returns a warning for each library that could not be read, from `failures` (as
/// [`load_library`] wrote them).
pub(super) fn assign(
    models: &[tobj::Model],
    triangles: &[usize],
    library: Result<Vec<tobj::Material>, tobj::LoadError>,
    failures: Vec<String>,
    obj: &Path,
) -> (Materials, Vec<String>) {
    // tobj reports an error only when an `mtllib` was named and none could be read.
    let (list, outcome, error) = match library {
        Ok(list) => (list, "triangles with its materials are grey", None),
        Err(e) => (Vec::new(), "every triangle is grey", Some(e)),
    };
    let mut warnings: Vec<String> = failures
        .iter()
        .map(|failure| format!("{}: {failure}; {outcome}", obj.display()))
        .collect();
    if let (Some(e), true) = (error, warnings.is_empty()) {
        warnings.push(format!(
            "{}: cannot read its material library ({e}); {outcome}",
            obj.display()
        ));
    }
    if list.is_empty() {
        return (Materials::default(), warnings);
    }
    let mut materials = vec![Material::default()];
    materials.extend(list.iter().map(convert));
    let per_triangle = models
        .iter()
        .zip(triangles)
        .flat_map(|(m, &count)| {
            let id = m
                .mesh
                .material_id
                .filter(|&i| i < list.len())
                .map_or(0, |i| i as u32 + 1);
            std::iter::repeat_n(id, count)
        })
        .collect();
    (
        Materials {
            list: materials,
            per_triangle,
            textures: Vec::new(),
        },
        warnings,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kd_and_ke_and_the_ambient_convention() {
        let mut m = tobj::Material {
            diffuse: Some([0.5, 2.0, -1.0]),
            emissive: Some([3.0, 0.0, 1.0]),
            ..Default::default()
        };
        let c = convert(&m);
        assert_eq!(c.albedo, [0.5, 1.0, 0.0]);
        assert_eq!(c.emission, [3.0, 0.0, 1.0]);
        m.emissive = None;
        m.ambient = Some([20.0, 20.0, 20.0]);
        assert_eq!(convert(&m).emission, [20.0; 3]);
        m.ambient = Some([0.2, 0.2, 0.2]);
        assert!(!convert(&m).emits());
    }
}
