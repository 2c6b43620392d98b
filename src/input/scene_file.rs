//! Scene files: a small TOML format naming a mesh (a file, relative to the scene file, or a
//! built-in generator) plus camera and render settings. Command-line flags override them.
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

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::animation::{Animation, Keyframe, Turntable};
use crate::bvh::Layout;
use crate::camera::{CameraSettings, Projection, View};
use crate::error::{Error, Result};
use crate::input::generate::Generator;
use crate::input::load_mesh;
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
        }
    }
}

/// A parsed scene: the mesh to load and the settings the scene file gave.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// Where the mesh comes from; not loaded yet.
    pub mesh: MeshSource,
    /// The `[camera]` table, already checked as far as it can be without the mesh; the
    /// command line's settings override it.
    pub camera: CameraSettings,
    /// The `[camera]` table's keyframes or turntable, if any.
    pub(crate) animation: Option<Animation>,
    pub(crate) render: RenderSettings,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    mesh: Option<PathBuf>,
    generator: Option<Generator>,
    #[serde(default)]
    camera: CameraTable,
    #[serde(default)]
    render: RenderSettings,
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
            mesh: MeshSource::File(path.to_path_buf()),
            camera: CameraSettings::default(),
            animation: None,
            render: RenderSettings::default(),
        }
    }

    /// Parses scene text; `path` names it in errors, `base` anchors relative mesh paths.
    pub fn parse(text: &str, path: &Path, base: &Path) -> Result<Self> {
        let file: SceneFile = toml::from_str(text).map_err(|e| {
            let message = crate::input::clean_line(e.message().trim());
            match e.span() {
                Some(span) => Error::input_at(path, line_of(text, span.start), message),
                None => Error::input(path, message),
            }
        })?;
        // What can be checked without the mesh is checked here, so that the error names
        // the scene file.
        let in_scene = |e: Error| Error::input(path, e.to_string());
        let (camera, animation) = file.camera.split(text, path)?;
        crate::camera::check_settings(&camera).map_err(in_scene)?;
        let mesh = match (file.mesh, file.generator) {
            (Some(mesh), None) => MeshSource::File(base.join(mesh)),
            (None, Some(generator)) => {
                generator.check().map_err(in_scene)?;
                MeshSource::Generator(generator)
            }
            (Some(_), Some(_)) => {
                return Err(Error::input(
                    path,
                    "give either `mesh` or a [generator] table, not both",
                ));
            }
            (None, None) => {
                return Err(Error::input(
                    path,
                    "no mesh: give `mesh = \"file.obj\"` or a [generator] table",
                ));
            }
        };
        Ok(SceneDescription {
            mesh,
            camera,
            animation,
            render: file.render,
        })
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

    #[test]
    fn builtin_default_parses() {
        let s = SceneDescription::builtin_default();
        assert!(matches!(s.mesh, MeshSource::Generator(_)));
    }

    #[test]
    fn mesh_path_is_relative_to_the_scene() {
        let s = parse("mesh = \"a/b.obj\"\n[camera]\nfov = 30\n").unwrap();
        assert_eq!(s.mesh, MeshSource::File(PathBuf::from("dir/a/b.obj")));
        assert_eq!(s.camera.fov, Some(30.0));
    }

    #[test]
    fn generator_with_parameters() {
        let s = parse("[generator]\nkind = \"soup\"\ntriangles = 10\nseed = 3\n").unwrap();
        assert_eq!(
            s.mesh,
            MeshSource::Generator(Generator::Soup {
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
