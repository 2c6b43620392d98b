//! Scene files: a small TOML format naming a mesh or several (files, relative to the scene
//! file, or built-in generators), an optional ground plane, and camera and render settings.
//! Command-line flags override them.
//!
//! ```toml
//! mesh = "room.obj"            # or a [generator] table, e.g. kind = "sphereflake"
//!
//! [camera]                     # every key optional; missing ones use the view's framing
//! view = "auto"                # or "bench", the benchmark's straight-on view
//! eye = [0.0, 1.0, 4.0]
//! look_at = [0.0, 0.5, 0.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 45.0                   # vertical, degrees
//! width = 1280
//! height = 720
//! projection = "perspective"   # or "orthographic"
//! ortho_height = 2.0           # orthographic image height, scene units; default: fitted
//! aperture = 0.0               # lens diameter, scene units; 0 (default) is a pinhole
//! focus_distance = 4.0         # along the view; default: look_at's distance
//! focus_on = [0.0, 0.5, 0.0]   # or a point to focus on (not both)
//!
//! [render]
//! method = "cl-bvh"
//! shade = "path"               # normal, depth, lambert, ao, shadow, path
//! spp = 64                     # samples per pixel of ao, shadow and path
//! two_sided_lights = false     # emitters shine from their front face only (default)
//! ```
//!
//! Lights besides emitting materials, for `shade = "path"` ([`super::lights`]; the
//! default sky goes once any is given):
//!
//! ```toml
//! [environment]                # light from infinity: a map or one colour, not both
//! file = "sky.hdr"             # equirectangular, Mitsuba's orientation; or color = [r, g, b]
//! intensity = 1.0
//! rotate = 0.0                 # degrees about +y
//!
//! [sky]                        # instead of [environment]: a sun and sky (Preetham)
//! sun_direction = [1.0, 1.0, 0.0]   # or latitude, longitude and time (RFC 3339)
//! turbidity = 3.0              # 1.7 to 10; intensity and rotate as above
//!
//! [[light]]
//! type = "spot"                # point, spot or directional
//! position = [0.0, 2.0, 0.0]   # point, spot
//! direction = [0.0, -1.0, 0.0] # spot: its axis; directional: where its light goes
//! intensity = 10.0             # point, spot: W/sr (or [r, g, b]); directional: irradiance
//! cutoff = 20.0                # spot: degrees; beam = 15.0, full within it
//! ```
//!
//! The camera may be animated, for `cltrace render --frames` ([`crate::animation`]), by
//! keyframes or by a turntable, not both:
//!
//! ```toml
//! [[camera.keyframe]]          # as many as needed, frames strictly increasing
//! frame = 0                    # a whole number, 0 or more
//! eye = [0.0, 1.0, 4.0]        # any of eye, look_at, up, fov; at least one
//! fov = 45.0
//!
//! [[camera.keyframe]]
//! frame = 48
//! eye = [4.0, 1.0, 0.0]        # each value linear between the keys that give it, held
//!                              # before the first and after the last; one no key gives
//!                              # is the [camera] table's (else the auto framing's)
//! ```
//!
//! ```toml
//! [camera.turntable]           # turns eye (and up) about an axis through look_at
//! frames = 120                 # frames the turn takes: frame 120 is turned by `degrees`
//! degrees = 360.0              # default 360; right-handed about the axis
//! axis = [0.0, 1.0, 0.0]       # default: the camera's up
//! ```
//!
//! A turntable turns the camera the [camera] table, the flags and the auto framing give;
//! a flag beats a keyframe as it beats any scene setting.
//!
//! Several meshes are `[[mesh]]` tables instead of `mesh` (the same key, so not both; nor
//! with a `[generator]`), each placed in the scene ([`super::scene`] puts them together):
//!
//! ```toml
//! [[mesh]]
//! file = "room.obj"            # or generator = { kind = "sphere", subdivisions = 3 }
//! scale = 0.5                  # or [x, y, z]; no factor 0; a negative one mirrors
//! rotate = [0.0, 30.0, 0.0]    # degrees about x, then y, then z, each right-handed
//! translate = [1.0, 0.0, 0.0]  # applied last: scale, rotate, translate
//! material = { albedo = [0.8, 0.2, 0.2], emission = [0.0, 0.0, 0.0] }
//!                              # optional: every triangle of this mesh, instead of its own;
//!                              # also bsdf = "diffuse", "conductor", "dielectric",
//!                              # "thin-dielectric" or "plastic", roughness, metallic (0-1),
//!                              # ior, specular = [r, g, b], and for conductors
//!                              # metal = "gold" (silver, copper, aluminium, iron,
//!                              # chromium) or eta = [r, g, b], k = [r, g, b]
//!
//! [ground]                     # optional, with any form: a square facing up (+y)
//! albedo = [0.5, 0.5, 0.5]     # the default
//! height = 0.0                 # default: 1e-3 bounding radii under the lowest mesh
//! size = 40.0                  # side; default 20 bounding radii of the meshes
//! ```
//!
//! Triangles (the hit records' primitive indices) come mesh by mesh in file order, then
//! the ground's two. The auto framing, the depth shading and the default `ao_distance`
//! measure the meshes without the ground. A mirroring scale reverses each triangle's
//! winding, so front faces stay front faces. Examples: `scenes/several.toml`,
//! `scenes/materials.toml`.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use crate::animation::{Animation, Keyframe, Turntable};
use crate::bvh::Layout;
use crate::camera::{CameraSettings, Projection, View};
use crate::error::{Error, Result};
use crate::input::generate::Generator;
use crate::input::lights::{EnvironmentTable, LightTable, LightsDescription, SkyTable};
use crate::input::load_mesh;
use crate::input::scene::{Ground, PlacedMesh, SceneMeshes};
use crate::material::{Bsdf, Material};
use crate::mesh::Mesh;
use crate::render::integrator::Light;
use crate::render::{Method, Shade};

/// The default scene, built into the binary so that `cltrace render` needs no files.
pub(crate) const DEFAULT_SCENE: &str = include_str!("../../scenes/default.toml");

/// Where the mesh comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSource {
    /// An OBJ or PLY file, plain or gzip-compressed; a path from a scene file is already
    /// joined to that file's folder.
    File(PathBuf),
    /// A built-in generator with its parameters (a scene file's checked as it is parsed).
    Generator(Generator),
}

impl MeshSource {
    /// The mesh alone: the file read, or the generator run.
    pub fn load(&self) -> Result<Mesh> {
        match self {
            MeshSource::File(path) => load_mesh(path),
            MeshSource::Generator(g) => g.generate(),
        }
    }

    /// The mesh and its materials: an OBJ's from its MTL file, a generator's own, grey for
    /// the rest.
    pub(crate) fn load_with_materials(&self) -> Result<crate::input::MeshFile> {
        match self {
            MeshSource::File(path) => crate::input::load_mesh_with_materials(path),
            MeshSource::Generator(g) => {
                let mesh = g.generate()?;
                let materials = g.materials(&mesh);
                Ok(crate::input::MeshFile {
                    mesh,
                    materials,
                    warnings: Vec::new(),
                    notes: Vec::new(),
                    camera: None,
                })
            }
        }
    }

    /// The mesh's name for reports: the file name or the generator with its parameters.
    pub fn name(&self) -> String {
        match self {
            MeshSource::File(path) => path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| path.display().to_string()),
            MeshSource::Generator(g) => g.name(),
        }
    }
}

/// Render settings; `None` means "not said here".
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    /// Which tracer renders: `cpu-brute`, `cpu-bvh`, `cl-brute` or `cl-bvh` (the default).
    pub method: Option<Method>,
    /// The BVH node layout of `cl-bvh`.
    pub layout: Option<Layout>,
    /// What a pixel shows: `normal`, `depth`, `lambert` (the default), `ao`, `shadow` or
    /// `path`.
    pub shade: Option<Shade>,
    /// Samples per pixel of the progressive modes (ao, shadow, path).
    pub spp: Option<u32>,
    /// Seed of the random numbers of the progressive modes.
    pub seed: Option<u32>,
    /// Rays per sample of ambient occlusion.
    pub ao_samples: Option<u32>,
    /// Reach of the ambient occlusion rays, in scene units.
    pub ao_distance: Option<f32>,
    /// Bounces of the path tracer.
    pub max_bounces: Option<u32>,
    /// The light of the shadow mode: `sun:x,y,z` or `point:x,y,z`.
    #[serde(default, deserialize_with = "checked_light")]
    pub light: Option<String>,
    /// Smooth normals for corners the mesh gives none: the crease angle in degrees, 0 to
    /// 180 (0: faceted).
    pub crease_angle: Option<f32>,
    /// Emitters shine from both faces; without it (the default) only from the front face,
    /// the side their winding's normal points to.
    pub two_sided_lights: Option<bool>,
}

/// A scene file's `light`, checked as it is read, so that a bad one is an error at its
/// line like any other bad value (checked after parsing, it would name no line).
fn checked_light<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<String>, D::Error> {
    let text = String::deserialize(d)?;
    text.parse::<Light>().map_err(serde::de::Error::custom)?;
    Ok(Some(text))
}

impl RenderSettings {
    pub(crate) fn over(self, base: RenderSettings) -> RenderSettings {
        RenderSettings {
            method: self.method.or(base.method),
            layout: self.layout.or(base.layout),
            shade: self.shade.or(base.shade),
            spp: self.spp.or(base.spp),
            seed: self.seed.or(base.seed),
            ao_samples: self.ao_samples.or(base.ao_samples),
            ao_distance: self.ao_distance.or(base.ao_distance),
            max_bounces: self.max_bounces.or(base.max_bounces),
            light: self.light.or(base.light),
            crease_angle: self.crease_angle.or(base.crease_angle),
            two_sided_lights: self.two_sided_lights.or(base.two_sided_lights),
        }
    }
}

/// A parsed scene: the mesh to load and the settings the scene file gave.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// The meshes and the ground plane; not loaded yet.
    pub meshes: SceneMeshes,
    /// The `[camera]` table, already checked as far as it can be without the mesh; the
    /// command line's settings override it.
    pub camera: CameraSettings,
    /// The `[camera]` table's keyframes or turntable, if any.
    pub(crate) animation: Option<Animation>,
    pub(crate) render: RenderSettings,
    /// The lights besides emitters: `[environment]` or `[sky]`, and `[[light]]` tables.
    pub lights: LightsDescription,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    // Spanned, so that errors about them name their lines.
    mesh: Option<Spanned<MeshKey>>,
    generator: Option<Spanned<Generator>>,
    ground: Option<GroundTable>,
    #[serde(default)]
    camera: CameraTable,
    #[serde(default)]
    render: RenderSettings,
    environment: Option<Spanned<EnvironmentTable>>,
    sky: Option<Spanned<SkyTable>>,
    light: Option<Vec<Spanned<LightTable>>>,
}

/// The `mesh` key: one file name, or the `[[mesh]]` tables. (TOML itself refuses both in
/// one file: they are the same key.)
enum MeshKey {
    One(PathBuf),
    Several(Vec<Spanned<MeshTable>>),
}

impl<'de> Deserialize<'de> for MeshKey {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = MeshKey;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a mesh file name or [[mesh]] tables")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<MeshKey, E> {
                Ok(MeshKey::One(PathBuf::from(v)))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<MeshKey, A::Error> {
                let mut tables = Vec::new();
                while let Some(table) = seq.next_element()? {
                    tables.push(table);
                }
                Ok(MeshKey::Several(tables))
            }
        }
        d.deserialize_any(Visit)
    }
}

/// A `[[mesh]]` table: one mesh and how it is placed.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshTable {
    file: Option<PathBuf>,
    generator: Option<Generator>,
    translate: Option<Spanned<[f32; 3]>>,
    rotate: Option<Spanned<[f32; 3]>>,
    scale: Option<Spanned<Scale>>,
    material: Option<Spanned<MaterialTable>>,
}

/// A `scale`: one number for every axis, or one per axis.
struct Scale([f32; 3]);

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Ok(Scale(one_or_three(d)?))
    }
}

/// One number for every axis or channel, or three: a `scale`, a light's power.
pub(crate) fn one_or_three<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<[f32; 3], D::Error> {
    struct Visit;
    impl<'de> serde::de::Visitor<'de> for Visit {
        type Value = [f32; 3];
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number or three numbers [x, y, z]")
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<[f32; 3], E> {
            Ok([v as f32; 3])
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<[f32; 3], E> {
            Ok([v as f32; 3])
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<[f32; 3], E> {
            Ok([v as f32; 3])
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(
            self,
            mut seq: A,
        ) -> std::result::Result<[f32; 3], A::Error> {
            let mut xyz = Vec::new();
            while let Some(v) = seq.next_element::<f32>()? {
                xyz.push(v);
            }
            xyz.try_into().map_err(|v: Vec<f32>| {
                serde::de::Error::invalid_length(v.len(), &"three numbers [x, y, z]")
            })
        }
    }
    d.deserialize_any(Visit)
}

/// A `[[mesh]]` table's `material`: every triangle of that mesh gets it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialTable {
    albedo: Option<[f32; 3]>,
    emission: Option<[f32; 3]>,
    bsdf: Option<Bsdf>,
    roughness: Option<f32>,
    metallic: Option<f32>,
    ior: Option<f32>,
    specular: Option<[f32; 3]>,
    metal: Option<String>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
}

impl MaterialTable {
    /// The material, or what is wrong with it.
    fn material(self) -> std::result::Result<Material, String> {
        let albedo = self.albedo.unwrap_or(crate::material::DEFAULT_ALBEDO);
        let emission = self.emission.unwrap_or([0.0; 3]);
        if let Some(problem) = albedo_problem("material albedo", albedo) {
            return Err(problem);
        }
        if !emission.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(format!(
                "material emission {emission:?}: each channel must be finite and 0 or more"
            ));
        }
        let mut m = Material::emitting(albedo, emission);
        if let Some(b) = self.bsdf {
            m.bsdf = b.code();
        }
        for (key, value, slot) in [
            ("roughness", self.roughness, &mut m.roughness),
            ("metallic", self.metallic, &mut m.metallic),
        ] {
            if let Some(v) = value {
                if !(0.0..=1.0).contains(&v) {
                    return Err(format!("material {key} {v}: must be in [0, 1]"));
                }
                *slot = v;
            }
        }
        if let Some(ior) = self.ior {
            if !(ior.is_finite() && (1.0 / 16.0..=16.0).contains(&ior)) {
                return Err(format!("material ior {ior}: must be in [1/16, 16]"));
            }
            m.ior = ior;
        }
        if let Some(s) = self.specular {
            if let Some(problem) = albedo_problem("material specular", s) {
                return Err(problem);
            }
            m.specular = s;
        }
        if let Some(name) = &self.metal {
            if self.eta.is_some() || self.k.is_some() {
                return Err(format!(
                    "material metal \"{name}\" and eta/k: give one or the other"
                ));
            }
            let Some((_, eta, k)) = crate::material::CONDUCTORS.iter().find(|c| c.0 == name) else {
                let names: Vec<&str> = crate::material::CONDUCTORS.iter().map(|c| c.0).collect();
                return Err(format!(
                    "material metal \"{name}\": not one of {}",
                    names.join(", ")
                ));
            };
            (m.eta, m.k) = (*eta, *k);
        }
        for (key, value, slot) in [("eta", self.eta, &mut m.eta), ("k", self.k, &mut m.k)] {
            if let Some(v) = value {
                if !v.iter().all(|c| c.is_finite() && (0.0..=100.0).contains(c)) {
                    return Err(format!(
                        "material {key} {v:?}: each channel must be in [0, 100]"
                    ));
                }
                *slot = v;
            }
        }
        if self.k.is_some() && !m.eta.iter().all(|&c| c > 0.0) {
            return Err("material k without a positive eta in every channel".into());
        }
        Ok(m)
    }
}

/// The `[ground]` table; every key optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GroundTable {
    albedo: Option<Spanned<[f32; 3]>>,
    height: Option<Spanned<f32>>,
    size: Option<Spanned<f32>>,
}

/// Where a scene file's errors point: the file, and its text to find lines in.
struct Place<'a> {
    text: &'a str,
    path: &'a Path,
}

impl Place<'_> {
    fn at(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Error {
        Error::input_at(self.path, line_of(self.text, span.start), message)
    }
}

/// An albedo's problem, if it has one: each channel in [0, 1].
fn albedo_problem(key: &str, albedo: [f32; 3]) -> Option<String> {
    (!albedo.iter().all(|c| (0.0..=1.0).contains(c)))
        .then(|| format!("{key} {albedo:?}: each channel must be in [0, 1]"))
}

impl MeshTable {
    /// The mesh it places, checked; `span` is the table's.
    fn placed(
        self,
        span: std::ops::Range<usize>,
        base: &Path,
        place: &Place,
    ) -> Result<PlacedMesh> {
        let line = line_of(place.text, span.start);
        let source = match (self.file, self.generator) {
            (Some(file), None) => MeshSource::File(base.join(file)),
            (None, Some(generator)) => {
                generator
                    .check()
                    .map_err(|e| Error::input_at(place.path, line, e.to_string()))?;
                MeshSource::Generator(generator)
            }
            (Some(_), Some(_)) => {
                return Err(place.at(
                    span,
                    "a [[mesh]] gives either `file` or `generator`, not both",
                ));
            }
            (None, None) => {
                return Err(place.at(
                    span,
                    "a [[mesh]] needs `file = \"name.obj\"` or `generator = { kind = ... }`",
                ));
            }
        };
        // `limit` completes "each number must be finite".
        let finite = |key: &str, v: &Option<Spanned<[f32; 3]>>, max: f32, limit: &str| match v {
            Some(v) if !v.get_ref().iter().all(|c| c.abs() <= max) => Err(place.at(
                v.span(),
                format!("{key} {:?}: each number must be finite{limit}", v.get_ref()),
            )),
            _ => Ok(v.as_ref().map(|v| Vec3::from(*v.get_ref()))),
        };
        let max = crate::mesh::MAX_COORDINATE;
        let translate = finite(
            "translate",
            &self.translate,
            max,
            &format!(", at most {max:e}"),
        )?;
        let rotate = finite("rotate", &self.rotate, f32::MAX, " (degrees)")?;
        let scale = match &self.scale {
            None => None,
            Some(s) => {
                let xyz = s.get_ref().0;
                if !xyz.iter().all(|c| c.is_finite()) {
                    return Err(place.at(
                        s.span(),
                        format!("scale {xyz:?}: each number must be finite"),
                    ));
                }
                if xyz.contains(&0.0) {
                    return Err(place.at(
                        s.span(),
                        format!("scale {xyz:?} flattens the mesh (a singular transform): no factor may be 0"),
                    ));
                }
                Some((Vec3::from(xyz), s.span()))
            }
        };
        let transform = match (translate, rotate, &scale) {
            (None, None, None) => None,
            _ => {
                let matrix = super::scene::transform(
                    translate.unwrap_or(Vec3::ZERO),
                    rotate.unwrap_or(Vec3::ZERO),
                    scale.as_ref().map_or(Vec3::ONE, |s| s.0),
                );
                let det = glam::Mat3::from_mat4(matrix).determinant();
                // A subnormal determinant counts as zero: the inverse transpose that turns
                // the normals would lose its precision.
                if !det.is_normal() {
                    // Only the scale can do it: factors whose product leaves the f32 range.
                    let span = scale.as_ref().map_or(span.clone(), |s| s.1.clone());
                    let xyz = scale.map_or(Vec3::ONE, |s| s.0).to_array();
                    if det.is_infinite() {
                        return Err(place.at(
                            span,
                            format!("scale {xyz:?}: the factors multiply to beyond the single-precision range"),
                        ));
                    }
                    return Err(place.at(
                        span,
                        format!("scale: the transform is singular in single precision (determinant {det:e}): give factors nearer 1"),
                    ));
                }
                Some(matrix)
            }
        };
        let material = match self.material {
            None => None,
            Some(m) => {
                let span = m.span();
                Some(m.into_inner().material().map_err(|p| place.at(span, p))?)
            }
        };
        Ok(PlacedMesh {
            source,
            transform,
            material,
            line: Some(line),
        })
    }
}

impl GroundTable {
    fn ground(self, place: &Place) -> Result<Ground> {
        let albedo = match self.albedo {
            None => Ground::ALBEDO,
            Some(a) => {
                if let Some(problem) = albedo_problem("albedo", *a.get_ref()) {
                    return Err(place.at(a.span(), problem));
                }
                a.into_inner()
            }
        };
        let height = match self.height {
            Some(h) if !(0.0..=crate::mesh::MAX_COORDINATE).contains(&h.get_ref().abs()) => {
                return Err(place.at(
                    h.span(),
                    format!(
                        "height {}: must be finite, at most {:e}",
                        h.get_ref(),
                        crate::mesh::MAX_COORDINATE
                    ),
                ));
            }
            h => h.map(Spanned::into_inner),
        };
        let size = match self.size {
            Some(s) if !(f32::MIN_POSITIVE..=crate::mesh::MAX_COORDINATE).contains(s.get_ref()) => {
                return Err(place.at(
                    s.span(),
                    format!(
                        "size {}: must be more than 0, at most {:e}",
                        s.get_ref(),
                        crate::mesh::MAX_COORDINATE
                    ),
                ));
            }
            s => s.map(Spanned::into_inner),
        };
        Ok(Ground {
            albedo,
            height,
            size,
        })
    }
}

/// The `[camera]` table: [`CameraSettings`]' keys (listed again, as serde's `flatten` would
/// let unknown keys through and lose their lines) and the animation's.
#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    view: Option<View>,
    eye: Option<[f32; 3]>,
    look_at: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    width: Option<u32>,
    height: Option<u32>,
    projection: Option<Projection>,
    ortho_height: Option<f32>,
    aperture: Option<f32>,
    focus_distance: Option<f32>,
    focus_on: Option<[f32; 3]>,
    // Spanned, so that a bad key's error names its line.
    keyframe: Option<Vec<Spanned<Keyframe>>>,
    turntable: Option<Spanned<Turntable>>,
}

impl CameraTable {
    /// The settings, and the animation checked; `text` and `path` place its errors.
    fn split(self, text: &str, path: &Path) -> Result<(CameraSettings, Option<Animation>)> {
        let settings = CameraSettings {
            view: self.view,
            eye: self.eye,
            look_at: self.look_at,
            up: self.up,
            fov: self.fov,
            width: self.width,
            height: self.height,
            projection: self.projection,
            ortho_height: self.ortho_height,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            focus_on: self.focus_on,
        };
        let at = |span: std::ops::Range<usize>, message: String| {
            Error::input_at(path, line_of(text, span.start), message)
        };
        let animation = match (self.keyframe, self.turntable) {
            (None, None) => None,
            (Some(_), Some(turntable)) => {
                return Err(at(
                    turntable.span(),
                    "give either [[camera.keyframe]] tables or a [camera.turntable], not both"
                        .into(),
                ));
            }
            (Some(keys), None) => {
                let spans: Vec<_> = keys.iter().map(Spanned::span).collect();
                let keys = keys.into_iter().map(Spanned::into_inner).collect();
                Some(
                    Animation::keyframes(keys).map_err(|(i, message)| match spans.get(i) {
                        Some(span) => at(span.clone(), message),
                        None => Error::input(path, message),
                    })?,
                )
            }
            (None, Some(turntable)) => {
                let span = turntable.span();
                Some(Animation::turntable(turntable.into_inner()).map_err(|m| at(span, m))?)
            }
        };
        Ok((settings, animation))
    }
}

impl SceneDescription {
    /// The scene a command names: a scene file (`.toml`), a mesh file, or for `None` the
    /// built-in default scene.
    pub fn named(scene: Option<&Path>) -> Result<SceneDescription> {
        match scene {
            None => Ok(SceneDescription::builtin_default()),
            Some(p)
                if p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("toml")) =>
            {
                SceneDescription::load(p)
            }
            Some(p) => Ok(SceneDescription::from_mesh(p)),
        }
    }

    /// Reads a scene file; a mesh path in it is taken relative to the file's folder.
    pub(crate) fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::input(path, crate::input::io_reason(&e)))?;
        let base = path.parent().unwrap_or(Path::new(""));
        Self::parse(&text, path, base)
    }

    /// The built-in default scene.
    pub(crate) fn builtin_default() -> Self {
        Self::parse(
            DEFAULT_SCENE,
            Path::new("<built-in default scene>"),
            Path::new(""),
        )
        .expect("the built-in default scene parses")
    }

    /// A scene that is just a mesh file, with every setting left to defaults and flags.
    pub(crate) fn from_mesh(path: &Path) -> Self {
        SceneDescription {
            meshes: SceneMeshes {
                meshes: vec![PlacedMesh::plain(MeshSource::File(path.to_path_buf()))],
                ground: None,
                scene: path.to_path_buf(),
            },
            camera: CameraSettings::default(),
            animation: None,
            render: RenderSettings::default(),
            lights: LightsDescription::default(),
        }
    }

    /// Parses scene text; `path` names it in errors, `base` anchors relative mesh paths.
    pub fn parse(text: &str, path: &Path, base: &Path) -> Result<Self> {
        let file: SceneFile = toml::from_str(text).map_err(|e| {
            let message = crate::input::clean_line(e.message().trim());
            match e.span() {
                Some(span) => {
                    let line = line_of(text, span.start);
                    let message = match message.as_str() {
                        // toml says no more; the line says which key.
                        "duplicate key" => duplicate_key(text.lines().nth(line - 1)),
                        _ => message,
                    };
                    Error::input_at(path, line, message)
                }
                None => Error::input(path, message),
            }
        })?;
        // What can be checked without the mesh is checked here, so that the error names
        // the scene file.
        let (camera, animation) = file.camera.split(text, path)?;
        crate::camera::check_settings(&camera).map_err(|e| Error::input(path, e.to_string()))?;
        let place = Place { text, path };
        let meshes = match (file.mesh, file.generator) {
            (Some(mesh), None) => {
                let span = mesh.span();
                match mesh.into_inner() {
                    MeshKey::One(file) => {
                        vec![PlacedMesh::plain(MeshSource::File(base.join(file)))]
                    }
                    MeshKey::Several(tables) if tables.is_empty() => {
                        return Err(place.at(
                            span,
                            "`mesh` lists no meshes: give at least one [[mesh]] table",
                        ));
                    }
                    MeshKey::Several(tables) => tables
                        .into_iter()
                        .map(|t| {
                            let span = t.span();
                            t.into_inner().placed(span, base, &place)
                        })
                        .collect::<Result<_>>()?,
                }
            }
            (None, Some(generator)) => {
                let span = generator.span();
                let generator = generator.into_inner();
                generator
                    .check()
                    .map_err(|e| place.at(span, e.to_string()))?;
                vec![PlacedMesh::plain(MeshSource::Generator(generator))]
            }
            (Some(_), Some(generator)) => {
                return Err(place.at(
                    generator.span(),
                    "give either `mesh` (or [[mesh]] tables) or a [generator] table, not both",
                ));
            }
            (None, None) => {
                return Err(Error::input(
                    path,
                    "no mesh: give `mesh = \"file.obj\"`, [[mesh]] tables or a [generator] table",
                ));
            }
        };
        let ground = file.ground.map(|g| g.ground(&place)).transpose()?;
        fn checked<T>(
            place: &Place,
            span: std::ops::Range<usize>,
            r: std::result::Result<T, String>,
        ) -> Result<T> {
            r.map_err(|e| place.at(span, e))
        }
        let environment = match (file.environment, file.sky) {
            (Some(_), Some(sky)) => {
                return Err(place.at(
                    sky.span(),
                    "give an [environment] or a [sky] table, not both",
                ));
            }
            (Some(env), None) => {
                let span = env.span();
                Some(checked(&place, span, env.into_inner().check(base))?)
            }
            (None, Some(sky)) => {
                let span = sky.span();
                Some(checked(&place, span, sky.into_inner().check())?)
            }
            (None, None) => None,
        };
        let punctual = file
            .light
            .unwrap_or_default()
            .into_iter()
            .map(|l| {
                let span = l.span();
                checked(&place, span, l.into_inner().check())
            })
            .collect::<Result<_>>()?;
        Ok(SceneDescription {
            meshes: SceneMeshes {
                meshes,
                ground,
                scene: path.to_path_buf(),
            },
            camera,
            animation,
            render: file.render,
            lights: LightsDescription {
                environment,
                punctual,
            },
        })
    }
}

/// The message for a key given twice, at `line`: the two forms of `mesh` get their own.
fn duplicate_key(line: Option<&str>) -> String {
    let line = line.unwrap_or("").trim();
    let is_mesh = line.starts_with("[[mesh]]")
        || line
            .strip_prefix("mesh")
            .is_some_and(|rest| rest.trim_start().starts_with('='));
    match is_mesh {
        true => "give either `mesh = \"file.obj\"` or [[mesh]] tables, not both".into(),
        false => format!(
            "duplicate key: {} gives a key again",
            crate::input::quoted(line)
        ),
    }
}

fn line_of(text: &str, byte: usize) -> usize {
    1 + text.as_bytes()[..byte.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<SceneDescription> {
        SceneDescription::parse(text, Path::new("s.toml"), Path::new("dir"))
    }

    /// The scene's one mesh, as placed by the one-mesh forms: as it is.
    fn one(s: &SceneDescription) -> &MeshSource {
        assert_eq!(s.meshes.meshes.len(), 1);
        assert_eq!(s.meshes.ground, None);
        let placed = &s.meshes.meshes[0];
        assert_eq!((placed.transform, placed.material), (None, None));
        &placed.source
    }

    const SEVERAL: &str = "\
[[mesh]]
file = \"a.obj\"
translate = [1, 2, 3]

[[mesh]]
generator = { kind = \"cube\" }
rotate = [0, 90, 0]
scale = 2
material = { albedo = [0.8, 0.2, 0.2] }

[[mesh]]
file = \"b.ply\"
scale = [-1, 1, 1]
material = { emission = [4, 4, 4] }

[ground]
albedo = [0.1, 0.2, 0.3]
";

    #[test]
    fn several_meshes_parse_in_order() {
        let s = parse(SEVERAL).unwrap();
        let m = &s.meshes.meshes;
        assert_eq!(m.len(), 3);
        assert_eq!(m[0].source, MeshSource::File(PathBuf::from("dir/a.obj")));
        assert_eq!(m[1].source, MeshSource::Generator(Generator::Cube {}));
        assert_eq!(m[2].source, MeshSource::File(PathBuf::from("dir/b.ply")));
        let moved = m[0].transform.unwrap().transform_point3(Vec3::ZERO);
        assert_eq!(moved, Vec3::new(1.0, 2.0, 3.0));
        // Scaled by 2, then x turned onto -z.
        let turned = m[1].transform.unwrap().transform_point3(Vec3::X);
        assert_eq!(turned, Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(m[1].material.unwrap().albedo, [0.8, 0.2, 0.2]);
        assert_eq!(m[1].material.unwrap().emission, [0.0; 3]);
        assert_eq!(
            m[2].material.unwrap().albedo,
            crate::material::DEFAULT_ALBEDO
        );
        assert!(m[2].material.unwrap().emits());
        assert_eq!(
            [m[0].line, m[1].line, m[2].line],
            [Some(1), Some(5), Some(11)]
        );
        let ground = s.meshes.ground.unwrap();
        assert_eq!(ground.albedo, [0.1, 0.2, 0.3]);
        assert_eq!((ground.height, ground.size), (None, None));
        assert_eq!(s.meshes.name(), "a.obj + cube + b.ply + ground");
    }

    #[test]
    fn a_ground_goes_with_every_form() {
        let s = parse("mesh = \"a.obj\"\n[ground]\nheight = -1\nsize = 50\n").unwrap();
        let ground = s.meshes.ground.unwrap();
        assert_eq!((ground.height, ground.size), (Some(-1.0), Some(50.0)));
        assert_eq!(ground.albedo, Ground::ALBEDO);
        assert!(
            parse("[generator]\nkind = \"cube\"\n[ground]\n")
                .unwrap()
                .meshes
                .ground
                .is_some()
        );
    }

    #[test]
    fn bad_placements_are_errors_at_their_line() {
        let mesh = "[[mesh]]\nfile = \"a.obj\"\n";
        for (text, line, words) in [
            (format!("{mesh}scale = 0\n"), 3, "singular"),
            (format!("{mesh}scale = [1, 0, 1]\n"), 3, "singular"),
            (format!("{mesh}scale = [1e-20, 1e-20, 1]\n"), 3, "singular"),
            (format!("{mesh}scale = nan\n"), 3, "finite"),
            (format!("{mesh}scale = [1, 2]\n"), 3, "three numbers"),
            (format!("{mesh}scale = \"big\"\n"), 3, "a number"),
            (format!("{mesh}translate = [0, inf, 0]\n"), 3, "translate"),
            (format!("{mesh}rotate = [nan, 0, 0]\n"), 3, "rotate"),
            (format!("{mesh}turn = 3\n"), 3, "turn"),
            (
                format!("{mesh}material = {{ albedo = [2, 0, 0] }}\n"),
                3,
                "albedo",
            ),
            (
                format!("{mesh}material = {{ emission = [-1, 0, 0] }}\n"),
                3,
                "emission",
            ),
            (format!("{mesh}material = {{ shine = 1 }}\n"), 3, "shine"),
            (format!("mesh = \"a.obj\"\n{mesh}"), 2, "not both"),
            (
                format!("{mesh}mesh = \"a.obj\"\n"),
                3,
                "unknown field `mesh`",
            ),
            (format!("{mesh}scale = 1\nscale = 2\n"), 4, "`scale = 2`"),
            (
                format!("{mesh}[generator]\nkind = \"cube\"\n"),
                3,
                "not both",
            ),
            (
                format!("{mesh}generator = {{ kind = \"cube\" }}\n"),
                1,
                "not both",
            ),
            ("[[mesh]]\nscale = 2\n".to_string(), 1, "file"),
            ("mesh = []\n".to_string(), 1, "no meshes"),
            ("mesh = 3\n".to_string(), 1, "mesh file name"),
            (
                "[[mesh]]\ngenerator = { kind = \"soup\", triangles = 0 }\n".to_string(),
                1,
                "soup",
            ),
            (format!("{mesh}[ground]\nalbedo = [0, 0, 9]\n"), 4, "albedo"),
            (format!("{mesh}[ground]\nsize = 0\n"), 4, "size"),
            (format!("{mesh}[ground]\nheight = nan\n"), 4, "height"),
            (format!("{mesh}[ground]\ncolour = 1\n"), 4, "colour"),
        ] {
            let msg = parse(&text).unwrap_err().to_string();
            assert!(msg.starts_with(&format!("s.toml:{line}:")), "{text}\n{msg}");
            assert!(msg.contains(words), "{text}\n{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
    }

    #[test]
    fn builtin_default_parses() {
        let s = SceneDescription::builtin_default();
        assert!(matches!(one(&s), MeshSource::Generator(_)));
    }

    #[test]
    fn mesh_path_is_relative_to_the_scene() {
        let s = parse("mesh = \"a/b.obj\"\n[camera]\nfov = 30\n").unwrap();
        assert_eq!(one(&s), &MeshSource::File(PathBuf::from("dir/a/b.obj")));
        assert_eq!(s.camera.fov, Some(30.0));
    }

    #[test]
    fn generator_with_parameters() {
        let s = parse("[generator]\nkind = \"soup\"\ntriangles = 10\nseed = 3\n").unwrap();
        assert_eq!(
            one(&s),
            &MeshSource::Generator(Generator::Soup {
                triangles: 10,
                seed: 3
            })
        );
    }

    #[test]
    fn unknown_keys_are_errors_with_a_line() {
        for (text, line) in [
            ("mesh = \"x.obj\"\ncolour = 1\n", 2),
            ("mesh = \"x.obj\"\n[camera]\nzoom = 2\n", 3),
            ("[generator]\nkind = \"cube\"\nsize = 2\n", 1),
            ("[generator]\nkind = \"teapot\"\n", 2),
            ("mesh = \"x.obj\"\n[render]\nmethod = \"magic\"\n", 3),
            ("mesh = \"x.obj\"\n[render]\nlight = \"sun:1,2\"\n", 3),
        ] {
            let err = parse(text).unwrap_err();
            let msg = err.to_string();
            assert!(msg.starts_with(&format!("s.toml:{line}:")), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
    }

    #[test]
    fn exactly_one_mesh_source() {
        assert!(parse("[camera]\nfov = 40\n").is_err());
        assert!(parse("mesh = \"a.obj\"\n[generator]\nkind = \"cube\"\n").is_err());
    }

    #[test]
    fn wrong_types_are_errors() {
        assert!(parse("mesh = \"a.obj\"\n[camera]\nwidth = \"wide\"\n").is_err());
        assert!(parse("mesh = 3\n").is_err());
    }

    const KEYS: &str = "mesh = \"a.obj\"\n[camera]\nwidth = 64\n\
                        [[camera.keyframe]]\nframe = 0\neye = [0, 0, 4]\n\
                        [[camera.keyframe]]\nframe = 10\neye = [4, 0, 0]\nfov = 30\n";

    #[test]
    fn keyframes_parse_into_an_animation() {
        let s = parse(KEYS).unwrap();
        assert_eq!(s.camera.width, Some(64));
        assert_eq!(s.camera.eye, None);
        let at = |frame| {
            s.animation
                .as_ref()
                .unwrap()
                .settings_at(
                    frame,
                    &CameraSettings::default(),
                    &s.camera,
                    &crate::geometry::Aabb::from_points([glam::Vec3::ZERO, glam::Vec3::ONE]),
                )
                .unwrap()
        };
        assert_eq!(at(5).eye, Some([2.0, 0.0, 2.0]));
        assert_eq!(at(5).fov, Some(30.0));
        assert_eq!(at(5).width, Some(64));
        assert!(parse("mesh = \"a.obj\"\n").unwrap().animation.is_none());
    }

    #[test]
    fn a_turntable_parses_into_an_animation() {
        let s = parse("mesh = \"a.obj\"\n[camera.turntable]\nframes = 12\n").unwrap();
        assert!(s.animation.is_some());
        assert_eq!(s.camera, CameraSettings::default());
    }

    #[test]
    fn bad_animations_are_errors_at_their_line() {
        let turntable = "mesh = \"a.obj\"\n[camera.turntable]\nframes = 4\n";
        for (text, line, words) in [
            // A bad key's error is at its [[camera.keyframe]] line (KEYS' second is line 7).
            (KEYS.replace("frame = 10", "frame = 0"), 7, "increasing"),
            (KEYS.replace("fov = 30", "fov = 200"), 7, "field of view"),
            // Serde's errors are at the value.
            (KEYS.replace("frame = 10", "frame = -1"), 8, "-1"),
            (KEYS.replace("fov = 30", "zoom = 2"), 10, "zoom"),
            (
                format!("{KEYS}[camera.turntable]\nframes = 4\n"),
                11,
                "not both",
            ),
            (
                format!("{turntable}[[camera.keyframe]]\nframe = 1\nfov = 9\n"),
                2,
                "not both",
            ),
            (
                turntable.replace("frames = 4", "frames = 0"),
                2,
                "frames = 0",
            ),
            (format!("{turntable}axis = [0, 0, 0]\n"), 2, "axis"),
            (format!("{turntable}speed = 2\n"), 4, "speed"),
        ] {
            let msg = parse(&text).unwrap_err().to_string();
            assert!(msg.starts_with(&format!("s.toml:{line}:")), "{text}\n{msg}");
            assert!(msg.contains(words), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
    }

    #[test]
    fn overrides_take_precedence() {
        let file = CameraSettings {
            fov: Some(30.0),
            width: Some(100),
            ..Default::default()
        };
        let flags = CameraSettings {
            width: Some(200),
            ..Default::default()
        };
        let merged = flags.over(file);
        assert_eq!(merged.width, Some(200));
        assert_eq!(merged.fov, Some(30.0));
    }
}
