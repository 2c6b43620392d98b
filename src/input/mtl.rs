//! Materials of an OBJ file from its MTL library, through `tobj`: the diffuse colour `Kd`
//! and the emitted radiance `Ke` of each material, mapped onto the triangles, and their
//! textures: `map_Kd` (base colour, sRGB), `map_Ke` (emission, sRGB), `map_d` (cut-out
//! mask: alpha below 0.5 is a hole) and `norm`/`map_Bump`/`bump` (tangent-space normal
//! map), with the options `-clamp on|off` and `-bm` (the normal map's strength); other
//! options are read past. Texture paths are relative to the OBJ file's folder.

use std::cell::RefCell;
use std::path::Path;

use crate::error::Result;
use crate::input::io_reason;
use crate::input::texture::{ColorSpace, load_texture};
use crate::material::{Bsdf, Material, Materials, Texture, Wrap};

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
    let mut material = Material::emitting(albedo, emission);
    scattering(m, &mut material);
    material
}

/// A number of the MTL keys tobj does not know (`Pr`, `Pm`, `Tr`), if it is one.
fn extra(m: &tobj::Material, key: &str) -> Option<f32> {
    let v: f32 = m
        .unknown_param
        .get(key)?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    v.is_finite().then_some(v)
}

/// The scattering model of an MTL material, as common importers map it (the table in
/// docs/rendering.md): `illum` 3 and 5 a conductor, 4, 6 and 7 a dielectric of index `Ni`
/// tinted by `Tf`, 9 or a dissolve `d` below 1 (`Tr` above 0) a thin dielectric, 2 with a
/// `Ks` above 0 a plastic whose coating `Ks` tints, `Ni` above 1 their index (else 1.5);
/// roughness from `Pr`, else from `Ns`
/// (1 - sqrt(Ns / 1000), as Blender's importer), metalness from `Pm` (the PBR extension:
/// glTF's model, a plastic blended with a metal of the base colour).
fn scattering(m: &tobj::Material, out: &mut Material) {
    let unit = |v: f32| v.clamp(0.0, 1.0);
    let ks = m
        .specular
        .filter(|k| k.iter().all(|c| c.is_finite()))
        .map(|k| k.map(unit));
    let opacity = m
        .dissolve
        .filter(|d| d.is_finite())
        .or_else(|| extra(m, "Tr").map(|t| 1.0 - t));
    let bsdf = match m.illumination_model {
        Some(3 | 5) => Bsdf::Conductor,
        Some(4 | 6 | 7) => Bsdf::Dielectric,
        Some(9) => Bsdf::ThinDielectric,
        _ if opacity.is_some_and(|d| d < 1.0) => Bsdf::ThinDielectric,
        Some(2) if ks.is_some_and(|k| k.iter().any(|&c| c > 0.0)) => Bsdf::Plastic,
        _ if m.unknown_param.contains_key("Pm") || m.unknown_param.contains_key("Pr") => {
            Bsdf::Plastic
        }
        _ => Bsdf::Diffuse,
    };
    out.bsdf = bsdf.code();
    let from_ns = m
        .shininess
        .filter(|s| s.is_finite())
        .map(|ns| 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt());
    out.roughness = match (extra(m, "Pr"), from_ns, bsdf) {
        (Some(pr), _, _) => unit(pr),
        (None, Some(r), Bsdf::Plastic | Bsdf::Conductor | Bsdf::Dielectric) => r,
        // Mirrors and clear glass unless the file says otherwise.
        (None, None, Bsdf::Conductor | Bsdf::Dielectric) => 0.0,
        (None, _, _) => out.roughness,
    };
    if let Some(pm) = extra(m, "Pm") {
        out.metallic = unit(pm);
    }
    // `Ni 1`, which exporters write when nothing was set, leaves the default 1.5.
    if let Some(ni) = m
        .optical_density
        .filter(|n| n.is_finite() && *n > 1.0 && *n <= 16.0)
    {
        out.ior = ni;
    }
    match bsdf {
        Bsdf::Plastic => out.specular = ks.unwrap_or([1.0; 3]),
        Bsdf::Dielectric | Bsdf::ThinDielectric => {
            if let Some(tf) = m.unknown_param.get("Tf") {
                let v: Vec<f32> = tf
                    .split_whitespace()
                    .filter_map(|w| w.parse().ok())
                    .collect();
                if let [r, g, b] | [r @ g @ b] = v.as_slice()
                    && [r, g, b].iter().all(|c| c.is_finite())
                {
                    out.specular = [unit(*r), unit(*g), unit(*b)];
                }
            }
        }
        _ => {}
    }
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
) -> Result<(Materials, Vec<String>)> {
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
        return Ok((Materials::default(), warnings));
    }
    let mut materials = vec![Material::default()];
    materials.extend(list.iter().map(convert));
    let mut textures = Textures::default();
    let folder = obj.parent().unwrap_or(Path::new(""));
    for (m, ours) in list.iter().zip(&mut materials[1..]) {
        textures.attach(m, ours, folder, &mut warnings)?;
    }
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
    Ok((
        Materials {
            list: materials,
            per_triangle,
            textures: textures.list,
        },
        warnings,
    ))
}

/// The textures of a library, each file read once per colour space.
#[derive(Default)]
struct Textures {
    list: Vec<Texture>,
    seen: Vec<(std::path::PathBuf, ColorSpace, [Wrap; 2], i32)>,
}

/// A texture line's value split into its options and the file name: `-clamp on` gives
/// the wrap mode, `-bm x` the strength of a normal map; other options are skipped with as
/// many values as MTL gives them.
fn map_options(value: &str) -> (String, Wrap, f32) {
    let words: Vec<&str> = value.split_whitespace().collect();
    let (mut wrap, mut strength) = (Wrap::Repeat, 1.0);
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') && words[i].len() > 1 {
        let takes = match words[i] {
            "-clamp" => {
                if words.get(i + 1) == Some(&"on") {
                    wrap = Wrap::Clamp;
                }
                1
            }
            "-bm" => {
                strength = words.get(i + 1).and_then(|w| w.parse().ok()).unwrap_or(1.0);
                1
            }
            "-o" | "-s" | "-t" => {
                // one to three numbers
                let numbers = words[i + 1..]
                    .iter()
                    .take(3)
                    .take_while(|w| w.parse::<f32>().is_ok())
                    .count();
                numbers.max(1)
            }
            "-mm" => 2,
            _ => 1,
        };
        i += 1 + takes;
    }
    (words[i.min(words.len())..].join(" "), wrap, strength)
}

impl Textures {
    /// Fills `ours`' texture slots from `m`'s maps. A missing file is a warning (a
    /// missing base colour map leaves the surface grey); a file that does not decode is
    /// an error.
    fn attach(
        &mut self,
        m: &tobj::Material,
        ours: &mut Material,
        folder: &Path,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        let normal = m
            .normal_texture
            .clone()
            .or_else(|| m.unknown_param.get("norm").cloned());
        let maps = [
            (m.diffuse_texture.clone(), ColorSpace::Srgb, "map_Kd"),
            (
                m.unknown_param.get("map_Ke").cloned(),
                ColorSpace::Srgb,
                "map_Ke",
            ),
            (m.dissolve_texture.clone(), ColorSpace::Linear, "map_d"),
            (normal, ColorSpace::Linear, "norm"),
        ];
        for (value, space, key) in maps {
            let Some(value) = value else { continue };
            let (name, wrap, strength) = map_options(&value);
            if name.is_empty() {
                continue;
            }
            let path = folder.join(&name);
            if !path.is_file() {
                warnings.push(format!(
                    "material {}: its {key} texture {} is missing{}",
                    m.name,
                    path.display(),
                    match key {
                        "map_Kd" => "; the surface is grey",
                        _ => "; it is left out",
                    }
                ));
                if key == "map_Kd" {
                    ours.albedo = crate::material::DEFAULT_ALBEDO;
                }
                continue;
            }
            let index = self.load(&path, space, [wrap; 2], key == "map_d")?;
            match key {
                "map_Kd" => ours.base_texture = index,
                "map_Ke" => {
                    ours.emission_texture = index;
                    // A map without a Ke factor glows as the map says.
                    if !ours.emits() {
                        ours.emission = [1.0; 3];
                    }
                }
                "map_d" => {
                    ours.alpha_texture = index;
                    ours.alpha_cutoff = 0.5;
                }
                _ => {
                    ours.normal_texture = index;
                    ours.normal_scale = strength;
                }
            }
        }
        Ok(())
    }

    /// The index of the texture of `path` read in `space`, reading it the first time. A
    /// `mask` takes its alpha from the file's alpha channel, or from its red channel when
    /// it has none (a grey-scale `map_d`).
    fn load(&mut self, path: &Path, space: ColorSpace, wrap: [Wrap; 2], mask: bool) -> Result<i32> {
        let key = (path.to_path_buf(), space, wrap);
        if let Some(seen) = self
            .seen
            .iter()
            .find(|s| (&s.0, s.1, s.2) == (&key.0, key.1, key.2))
        {
            return Ok(seen.3);
        }
        let mut texture = load_texture(path, space, wrap)?;
        if mask && texture.texels.iter().all(|t| t[3] == 1.0) {
            for t in &mut texture.texels {
                t[3] = t[0];
            }
        }
        let index = self.list.len() as i32;
        self.list.push(texture);
        self.seen.push((key.0, key.1, key.2, index));
        Ok(index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_options_are_read_and_the_name_kept() {
        assert_eq!(
            map_options("wood.png"),
            ("wood.png".into(), Wrap::Repeat, 1.0)
        );
        assert_eq!(
            map_options("-clamp on -bm 0.5 -s 2 2 1 my wood.png"),
            ("my wood.png".into(), Wrap::Clamp, 0.5)
        );
        assert_eq!(map_options("-o 0.5 n.png").0, "n.png");
    }

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
