//! A scene's lights as a scene file or the command line describe them (`[environment]`,
//! `[sky]`, `[[light]]`), checked as they are read and turned into [`Lights`] once the
//! environment's image is read.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::light::{Environment, Lights, Punctual};

/// Texels across a baked sun and sky (and half as many down): a texel of 0.35° holds the
/// sun's disc (0.53°) in a few texels, so its shadows stay sharp and its samples find it.
pub const SKY_WIDTH: u32 = 1024;

/// Where the environment's light comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentSource {
    /// An equirectangular image (`.hdr`, `.exr`, or any texture format).
    File(PathBuf),
    /// One colour from every direction: a background that lights the scene.
    Color([f32; 3]),
    /// A sun and sky (Preetham et al. 1999), baked into an image of [`SKY_WIDTH`].
    Sky {
        /// Towards the sun, unit, +y up.
        sun: [f32; 3],
        /// Haze, 1.7 (clear) to 10.
        turbidity: f32,
    },
}

/// An environment as described: where its light comes from, how bright, how turned.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentDescription {
    /// The light.
    pub source: EnvironmentSource,
    /// Scales the radiance.
    pub intensity: f32,
    /// Degrees about +y, right-handed.
    pub rotate: f32,
}

/// A scene's lights besides its emitters, described; [`LightsDescription::load`] reads
/// what it names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightsDescription {
    /// The environment, if any.
    pub environment: Option<EnvironmentDescription>,
    /// Point, spot and directional lights.
    pub punctual: Vec<Punctual>,
}

impl LightsDescription {
    /// The lights, the environment's image read (or its sky baked).
    pub fn load(&self) -> Result<Lights> {
        let environment = self
            .environment
            .as_ref()
            .map(load_environment)
            .transpose()?;
        Ok(Lights {
            environment,
            punctual: self.punctual.clone(),
        })
    }

    /// One line per light for fingerprints and reports: what each is, exactly.
    pub fn describe(&self) -> String {
        format!("{:?}", self)
    }
}

fn load_environment(d: &EnvironmentDescription) -> Result<Environment> {
    let (width, height, rgb) = match &d.source {
        EnvironmentSource::Color(c) => {
            return Ok(Environment::constant(Vec3::from(*c), d.intensity));
        }
        EnvironmentSource::Sky { sun, turbidity } => {
            let sky = crate::light::sky::Sky {
                sun: Vec3::from(*sun).normalize(),
                turbidity: *turbidity,
                intensity: 1.0,
            };
            (SKY_WIDTH, SKY_WIDTH / 2, sky.bake(SKY_WIDTH, SKY_WIDTH / 2))
        }
        EnvironmentSource::File(path) => read_map(path)?,
    };
    Ok(Environment::new(width, height, &rgb, d.intensity, d.rotate))
}

/// An environment map's linear RGB texels, row-major from the top; a negative texel is
/// an error (non-finite ones read as 0, as in every texture).
fn read_map(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    use crate::input::texture::{ColorSpace, load_texture};
    use crate::material::Wrap;
    let t =
        load_texture(path, ColorSpace::Srgb, [Wrap::Repeat, Wrap::Clamp]).map_err(|e| match e {
            Error::Input {
                path,
                line,
                message,
            } => Error::Input {
                path,
                line,
                message: message.replace("the texture", "the environment map"),
            },
            e => e,
        })?;
    if let Some(k) = t
        .texels
        .iter()
        .position(|p| p[..3].iter().any(|&c| c < 0.0))
    {
        let (i, j) = (k as u32 % t.width, k as u32 / t.width);
        return Err(Error::input(
            path,
            format!("environment map texel ({i}, {j}) is negative: light cannot be"),
        ));
    }
    let rgb = t.texels.iter().map(|p| [p[0], p[1], p[2]]).collect();
    Ok((t.width, t.height, rgb))
}

/// A number for every channel, or one per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rgb(pub(crate) [f32; 3]);

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Ok(Rgb(super::scene_file::one_or_three(d)?))
    }
}

/// Checks a colour or power: finite and not negative in every channel.
fn light_value(key: &str, v: [f32; 3]) -> std::result::Result<Vec3, String> {
    match v.iter().all(|c| c.is_finite() && *c >= 0.0) {
        true => Ok(Vec3::from(v)),
        false => Err(format!(
            "{key} {v:?}: each channel must be finite and 0 or more"
        )),
    }
}

fn finite_point(key: &str, v: [f32; 3]) -> std::result::Result<Vec3, String> {
    match v.iter().all(|c| c.is_finite()) {
        true => Ok(Vec3::from(v)),
        false => Err(format!("{key} {v:?}: must be finite")),
    }
}

fn unit(key: &str, v: [f32; 3]) -> std::result::Result<Vec3, String> {
    let d = finite_point(key, v)?;
    match d.length() > 0.0 {
        true => Ok(d.normalize()),
        false => Err(format!("{key} {v:?}: a direction cannot be zero")),
    }
}

/// The `[environment]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EnvironmentTable {
    file: Option<PathBuf>,
    color: Option<[f32; 3]>,
    intensity: Option<f32>,
    rotate: Option<f32>,
}

fn intensity_and_rotate(
    intensity: Option<f32>,
    rotate: Option<f32>,
) -> std::result::Result<(f32, f32), String> {
    let intensity = intensity.unwrap_or(1.0);
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(format!(
            "intensity {intensity}: must be finite and 0 or more"
        ));
    }
    let rotate = rotate.unwrap_or(0.0);
    if !rotate.is_finite() {
        return Err(format!("rotate {rotate}: must be finite (degrees)"));
    }
    Ok((intensity, rotate))
}

impl EnvironmentTable {
    /// The environment; `base` anchors a relative file.
    pub(crate) fn check(self, base: &Path) -> std::result::Result<EnvironmentDescription, String> {
        let source = match (self.file, self.color) {
            (Some(file), None) => EnvironmentSource::File(base.join(file)),
            (None, Some(c)) => EnvironmentSource::Color(light_value("color", c)?.to_array()),
            (Some(_), Some(_)) => {
                return Err("[environment] takes a file or a color, not both".into());
            }
            (None, None) => return Err("[environment] needs a file or a color".into()),
        };
        let (intensity, rotate) = intensity_and_rotate(self.intensity, self.rotate)?;
        Ok(EnvironmentDescription {
            source,
            intensity,
            rotate,
        })
    }
}

/// The `[sky]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SkyTable {
    sun_direction: Option<[f32; 3]>,
    latitude: Option<f32>,
    longitude: Option<f32>,
    time: Option<String>,
    turbidity: Option<f32>,
    intensity: Option<f32>,
    rotate: Option<f32>,
}

impl SkyTable {
    pub(crate) fn check(self) -> std::result::Result<EnvironmentDescription, String> {
        let place = (self.latitude, self.longitude, self.time);
        let sun = match (self.sun_direction, place) {
            (Some(d), (None, None, None)) => unit("sun_direction", d)?,
            (None, (Some(lat), Some(lon), Some(time))) => {
                crate::light::sky::sun_direction(lat, lon, &time)?
            }
            (Some(_), _) => {
                return Err(
                    "[sky] takes sun_direction or latitude, longitude and time, not both".into(),
                );
            }
            (None, _) => {
                return Err(
                    "[sky] needs sun_direction, or latitude, longitude and time (UTC)".into(),
                );
            }
        };
        let turbidity = self.turbidity.unwrap_or(3.0);
        if !(1.7..=10.0).contains(&turbidity) {
            return Err(format!("[sky] turbidity {turbidity}: must be in [1.7, 10]"));
        }
        let (intensity, rotate) = intensity_and_rotate(self.intensity, self.rotate)?;
        Ok(EnvironmentDescription {
            source: EnvironmentSource::Sky {
                sun: sun.to_array(),
                turbidity,
            },
            intensity,
            rotate,
        })
    }
}

/// A `[[light]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightTable {
    #[serde(rename = "type")]
    kind: String,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    intensity: Option<Rgb>,
    irradiance: Option<Rgb>,
    cutoff: Option<f32>,
    beam: Option<f32>,
}

impl LightTable {
    pub(crate) fn check(self) -> std::result::Result<Punctual, String> {
        let kind = self.kind.as_str();
        let refuse = |key: &str, given: bool, for_kinds: &str| match given {
            true => Err(format!("{key} is for {for_kinds}, not a {kind} light")),
            false => Ok(()),
        };
        let need = |key: &str, v: Option<[f32; 3]>| {
            v.ok_or_else(|| format!("a {kind} light needs {key} = [x, y, z]"))
        };
        match kind {
            "point" | "spot" => {
                refuse(
                    "irradiance",
                    self.irradiance.is_some(),
                    "directional lights",
                )?;
                let position = finite_point("position", need("position", self.position)?)?;
                let intensity = light_value("intensity", self.intensity.map_or([1.0; 3], |i| i.0))?;
                if kind == "point" {
                    refuse(
                        "direction",
                        self.direction.is_some(),
                        "spot and directional lights",
                    )?;
                    refuse("cutoff", self.cutoff.is_some(), "spot lights")?;
                    refuse("beam", self.beam.is_some(), "spot lights")?;
                    return Ok(Punctual::Point {
                        position,
                        intensity,
                    });
                }
                let direction = unit("direction", need("direction", self.direction)?)?;
                let cutoff = self.cutoff.unwrap_or(20.0);
                if !(cutoff > 0.0 && cutoff <= 90.0) {
                    return Err(format!("spot cutoff {cutoff}: must be in (0, 90] degrees"));
                }
                let beam = self.beam.unwrap_or(0.75 * cutoff);
                if !(0.0..=cutoff).contains(&beam) {
                    return Err(format!(
                        "spot beam {beam}: must be in [0, cutoff {cutoff}] degrees"
                    ));
                }
                Ok(Punctual::Spot {
                    position,
                    direction,
                    intensity,
                    cutoff: cutoff.to_radians(),
                    beam: beam.to_radians(),
                })
            }
            "directional" => {
                refuse("position", self.position.is_some(), "point and spot lights")?;
                refuse(
                    "intensity",
                    self.intensity.is_some(),
                    "point and spot lights",
                )?;
                refuse("cutoff", self.cutoff.is_some(), "spot lights")?;
                refuse("beam", self.beam.is_some(), "spot lights")?;
                let direction = unit("direction", need("direction", self.direction)?)?;
                let irradiance =
                    light_value("irradiance", self.irradiance.map_or([1.0; 3], |i| i.0))?;
                Ok(Punctual::Directional {
                    direction,
                    irradiance,
                })
            }
            other => Err(format!(
                "light type \"{other}\": use \"point\", \"spot\" or \"directional\""
            )),
        }
    }
}

/// `--environment`: a file, or `r,g,b` for a constant colour.
pub fn parse_environment_flag(s: &str) -> std::result::Result<EnvironmentSource, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let numbers: Option<Vec<f32>> = parts.iter().map(|p| p.trim().parse().ok()).collect();
    if let (3, Some(v)) = (parts.len(), numbers) {
        let c = light_value("--environment", [v[0], v[1], v[2]])?;
        return Ok(EnvironmentSource::Color(c.to_array()));
    }
    if s.is_empty() {
        return Err("--environment needs a file or r,g,b".into());
    }
    Ok(EnvironmentSource::File(PathBuf::from(s)))
}

/// The environment flags of `cltrace render`, over a scene's lights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnvironmentFlags {
    /// `--environment`: replaces the scene's environment or sky.
    pub source: Option<EnvironmentSource>,
    /// `--environment-intensity`.
    pub intensity: Option<f32>,
    /// `--environment-rotate`, degrees.
    pub rotate: Option<f32>,
}

impl EnvironmentFlags {
    /// `lights` with these flags applied; intensity and rotation without an environment
    /// anywhere are an error.
    pub fn over(&self, mut lights: LightsDescription) -> Result<LightsDescription> {
        let bad = |m: String| {
            Error::Invalid(
                m.replacen("intensity", "--environment-intensity", 1)
                    .replacen("rotate", "--environment-rotate", 1),
            )
        };
        let (intensity, rotate) = intensity_and_rotate(self.intensity, self.rotate).map_err(bad)?;
        if let Some(source) = &self.source {
            lights.environment = Some(EnvironmentDescription {
                source: source.clone(),
                intensity,
                rotate,
            });
            return Ok(lights);
        }
        if self.intensity.is_none() && self.rotate.is_none() {
            return Ok(lights);
        }
        let Some(env) = lights.environment.as_mut() else {
            return Err(Error::Invalid(
                "--environment-intensity and --environment-rotate need an environment: give \
                 --environment or an [environment] or [sky] table"
                    .into(),
            ));
        };
        if self.intensity.is_some() {
            env.intensity = intensity;
        }
        if self.rotate.is_some() {
            env.rotate = rotate;
        }
        Ok(lights)
    }
}
