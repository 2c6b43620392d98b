//! `cltrace render`'s flags. The camera and render settings are the scene file's
//! ([`CameraSettings`], [`RenderSettings`]), flag for key; each group maps into its
//! settings struct in one place (the `From` impls below), and the help of each setting is
//! built from the default and limits the render applies ([`help`]).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use cltrace::bvh::Layout;
use cltrace::camera::{CameraSettings, Projection, View};
use cltrace::commands::frames::{FrameRange, Frames};
use cltrace::commands::render::RenderRequest;
use cltrace::input::lights::{EnvironmentFlags, EnvironmentSource, parse_environment_flag};
use cltrace::input::scene_file::RenderSettings;
use cltrace::output::HitsFormat;
use cltrace::render::integrator::{Region, parse_sample_range};
use cltrace::render::{Method, Shade};
use cltrace::report::Verbosity;

use super::build::BuildArgs;
use super::values::{choice, parse_vec3, whole_number};

#[derive(Args)]
pub struct RenderArgs {
    /// A scene file (.toml: a mesh or several [[mesh]] tables, optionally a [ground]) or a
    /// mesh (.obj, .obj.gz, .ply, .ply.gz); the built-in default scene when omitted. Flags
    /// override the scene file's settings.
    scene: Option<PathBuf>,

    /// Output image; the format follows the extension: png, bmp, ppm, jpg (8-bit sRGB),
    /// exr, pfm (32-bit float, linear)
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,

    #[command(flatten)]
    camera: CameraArgs,

    /// OpenCL device: `P:D` index (see `cltrace devices`), `gpu`, `cpu`, or part of its
    /// name; or several, comma-separated (`gpu,cpu`, `0:0,1:0`) or `all`, to split the
    /// samples of ao, shadow and path over them (faster devices take more; the image is the
    /// same) [default: the first GPU, else the first device]
    #[arg(long, env = "CLTRACE_DEVICE")]
    device: Option<String>,

    /// Render only the pixels x0..x1, y0..y1 (ends exclusive) into a part: an OpenEXR file
    /// of per-pixel sums and sample counts for `cltrace merge` (ao, shadow, path)
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region)]
    region: Option<Region>,

    /// Render only the sample indices FIRST..END (END exclusive) into a part, as --region
    /// does; parts of different sample ranges add up exactly in `cltrace merge`
    #[arg(long, value_name = "FIRST..END", value_parser = parse_samples, conflicts_with = "spp")]
    samples: Option<std::ops::Range<u32>>,

    #[command(flatten)]
    settings: SettingsArgs,

    #[command(flatten)]
    environment: EnvironmentArgs,

    /// Also write the raw per-pixel hit records here (8 bytes a pixel: u32 triangle, f32
    /// distance; --hits-format v2 adds the barycentrics)
    #[arg(long, value_name = "FILE")]
    hits: Option<PathBuf>,

    /// The layout of --hits's records
    #[arg(long, value_name = "FORMAT", value_parser = choice::<HitsFormat>(), requires = "hits", default_value = "v1")]
    hits_format: HitsFormat,

    /// Also write a JSON summary of the run here: version, device, layout, work-group,
    /// samples, rays, every stage's time, wall time, the files written
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// If the OpenCL device fails (none found, kernel build, out of memory, lost), render on
    /// the host instead of stopping with the error
    #[arg(long, value_enum, value_name = "WHERE")]
    fallback: Option<Fallback>,

    /// Render frames of the scene file's camera animation ([[camera.keyframe]] tables or a
    /// [camera.turntable]): A..B is frames A to B-1, A..=B frames A to B, N frame N. Each
    /// frame is a render of its own, to -o's frame pattern: %d, or %0Nd for N digits
    /// (out_%04d.png); --hits and --json need one too. Without --frames, an animated scene
    /// renders frame 0
    #[arg(long, value_name = "A..B")]
    frames: Option<FrameRange>,

    /// With --frames: leave each frame whose outputs all exist as it is (to resume a run)
    #[arg(long, requires = "frames")]
    skip_existing: bool,

    /// Print nothing but errors
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,

    /// Also print mesh, camera, device and BVH details
    #[arg(short, long)]
    verbose: bool,
}

fn parse_region(s: &str) -> Result<Region, String> {
    s.parse()
}

fn parse_samples(s: &str) -> Result<std::ops::Range<u32>, String> {
    parse_sample_range(s)
}

/// Where `--fallback` sends a render whose OpenCL device fails: one place for now, named so
/// that the flag reads `--fallback cpu`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Fallback {
    /// The same method on the host: cl-bvh becomes cpu-bvh, cl-brute cpu-brute.
    Cpu,
}

/// The scene file's `[camera]` keys, as flags.
#[derive(Args)]
struct CameraArgs {
    /// Which view frames the mesh where --eye and --look-at leave it open [default:
    /// scene's, else auto]
    #[arg(long = "camera", value_parser = choice::<View>())]
    view: Option<View>,

    #[arg(value_parser = whole_number, long, help = help::width())]
    width: Option<u32>,

    #[arg(value_parser = whole_number, long, help = help::height())]
    height: Option<u32>,

    #[arg(long, help = help::fov())]
    fov: Option<f32>,

    /// Eye position `x,y,z` [default: the view's: auto fits the mesh's box from the
    /// front-right and above]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<[f32; 3]>,

    /// Point to look at `x,y,z` [default: centre of the mesh's bounding box]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    look_at: Option<[f32; 3]>,

    /// Up direction `x,y,z` [default: 0,1,0]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    up: Option<[f32; 3]>,

    /// How rays leave the camera [default: scene's, else perspective]
    #[arg(long, value_parser = choice::<Projection>())]
    projection: Option<Projection>,

    /// Height of the orthographic image plane, in scene units, above 0 [default: scene's,
    /// else fitted to the mesh's box]
    #[arg(long, allow_hyphen_values = true)]
    ortho_height: Option<f32>,

    /// Lens diameter for depth of field, in scene units; 0 is a pinhole. Blurs only in
    /// the progressive modes (ao, shadow, path) [default: scene's, else 0]
    #[arg(long, allow_hyphen_values = true)]
    aperture: Option<f32>,

    /// Distance in focus, along the view direction, in scene units [default: scene's,
    /// else the look-at point's distance]
    #[arg(long, allow_hyphen_values = true, conflicts_with = "focus_on")]
    focus_distance: Option<f32>,

    /// Focus on the point `x,y,z` (the focus distance is its distance along the view)
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    focus_on: Option<[f32; 3]>,
}

impl From<CameraArgs> for CameraSettings {
    fn from(a: CameraArgs) -> CameraSettings {
        CameraSettings {
            view: a.view,
            eye: a.eye,
            look_at: a.look_at,
            up: a.up,
            fov: a.fov,
            width: a.width,
            height: a.height,
            projection: a.projection,
            ortho_height: a.ortho_height,
            aperture: a.aperture,
            focus_distance: a.focus_distance,
            focus_on: a.focus_on,
        }
    }
}

/// The scene file's `[render]` keys, as flags.
#[derive(Args)]
struct SettingsArgs {
    #[arg(long, value_parser = choice::<Method>(), help = help::method())]
    method: Option<Method>,

    #[arg(long, value_parser = choice::<Layout>(), help = help::layout())]
    layout: Option<Layout>,

    #[arg(long, value_parser = choice::<Shade>(), help = help::shade())]
    shade: Option<Shade>,

    #[arg(value_parser = whole_number, long, help = help::spp())]
    spp: Option<u32>,

    #[arg(value_parser = whole_number, long, help = help::seed())]
    seed: Option<u32>,

    #[arg(value_parser = whole_number, long, help = help::ao_samples())]
    ao_samples: Option<u32>,

    #[arg(long, help = help::ao_distance())]
    ao_distance: Option<f32>,

    #[arg(value_parser = whole_number, long, help = help::max_bounces())]
    max_bounces: Option<u32>,

    #[arg(long, allow_hyphen_values = true, help = help::light())]
    light: Option<String>,

    #[arg(long, value_name = "DEGREES", help = help::crease_angle())]
    crease_angle: Option<f32>,

    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true",
          help = help::two_sided_lights())]
    two_sided_lights: Option<bool>,
}

impl From<SettingsArgs> for RenderSettings {
    fn from(a: SettingsArgs) -> RenderSettings {
        RenderSettings {
            method: a.method,
            layout: a.layout,
            shade: a.shade,
            spp: a.spp,
            seed: a.seed,
            ao_samples: a.ao_samples,
            ao_distance: a.ao_distance,
            max_bounces: a.max_bounces,
            light: a.light,
            crease_angle: a.crease_angle,
            two_sided_lights: a.two_sided_lights,
        }
    }
}

impl RenderArgs {
    pub fn request(self) -> RenderRequest {
        RenderRequest {
            scene: self.scene,
            camera: self.camera.into(),
            render: self.settings.into(),
            output: self.output,
            hits: self.hits,
            hits_format: self.hits_format,
            json: self.json,
            device: self.device,
            region: self.region,
            samples: self.samples,
            build: self.build.options(),
            fallback_to_cpu: self.fallback == Some(Fallback::Cpu),
            tune_cache: cltrace::tune::cache_path(),
            program_cache: cltrace::device::program_cache_folder(),
            verbosity: Verbosity::from_flags(self.quiet, self.verbose),
            frames: self.frames.map(|range| Frames {
                range,
                skip_existing: self.skip_existing,
            }),
            frame: 0,
            environment: self.environment.into(),
        }
    }
}

/// The environment of `--shade path`, over the scene file's `[environment]` or `[sky]`.
#[derive(Args)]
struct EnvironmentArgs {
    /// Light from every direction at infinity for `--shade path`: an equirectangular image
    /// (.hdr, .exr, or any texture format; +y up, Mitsuba's orientation), or R,G,B for one
    /// colour (a background that lights the scene); it replaces the scene's [environment]
    /// or [sky] and the default sky [default: scene's, else none: without emitters or
    /// other lights, rays that leave the scene see a fixed sky]
    #[arg(long, value_name = "FILE|R,G,B", value_parser = parse_environment_flag)]
    environment: Option<EnvironmentSource>,

    /// Scales the environment's radiance (0 or more) [default: scene's, else 1]
    #[arg(long, value_name = "X")]
    environment_intensity: Option<f32>,

    /// Turns the environment about +y, degrees, right-handed [default: scene's, else 0]
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true)]
    environment_rotate: Option<f32>,
}

impl From<EnvironmentArgs> for EnvironmentFlags {
    fn from(a: EnvironmentArgs) -> EnvironmentFlags {
        EnvironmentFlags {
            source: a.environment,
            intensity: a.environment_intensity,
            rotate: a.environment_rotate,
        }
    }
}

/// The help of the settings a scene file can also give, with the defaults and limits that
/// apply when neither does.
mod help {
    use std::fmt::Display;

    use cltrace::camera::{AUTO_FOV, DEFAULT_HEIGHT, DEFAULT_WIDTH, MAX_RESOLUTION};
    use cltrace::commands::render::{
        AO_DISTANCE_SHARE, DEFAULT_AO_SAMPLES, DEFAULT_LIGHT, DEFAULT_MAX_BOUNCES, DEFAULT_METHOD,
        DEFAULT_SEED, DEFAULT_SHADE, DEFAULT_SPP, MAX_AO_SAMPLES, MAX_BOUNCES, MAX_SPP,
    };
    use cltrace::device::DeviceKind;

    /// `[default: scene's, else X]`.
    fn or_scene(default: impl Display) -> String {
        format!("[default: scene's, else {default}]")
    }

    pub fn width() -> String {
        format!(
            "Image width in pixels (1 to {MAX_RESOLUTION}) {}",
            or_scene(DEFAULT_WIDTH)
        )
    }

    pub fn height() -> String {
        format!(
            "Image height in pixels (1 to {MAX_RESOLUTION}) {}",
            or_scene(DEFAULT_HEIGHT)
        )
    }

    pub fn fov() -> String {
        format!(
            "Vertical field of view in degrees, in (0, 180) {}",
            or_scene(AUTO_FOV)
        )
    }

    pub fn method() -> String {
        format!(
            "How rays find their closest hit {}",
            or_scene(DEFAULT_METHOD.name())
        )
    }

    pub fn layout() -> String {
        format!(
            "BVH node layout of cl-bvh {}",
            or_scene(format!(
                "the one `cltrace tune` found for the device, else {} on CPUs and {} on \
                 other devices",
                DeviceKind::Cpu.default_layout().name(),
                DeviceKind::Gpu.default_layout().name()
            ))
        )
    }

    pub fn shade() -> String {
        format!(
            "How hits are coloured {}; ao, shadow and path accumulate samples (--spp) and trace \
             secondary rays",
            or_scene(DEFAULT_SHADE.name())
        )
    }

    pub fn spp() -> String {
        let defaults = DEFAULT_SPP
            .iter()
            .map(|(shade, spp)| format!("{spp} for {}", shade.name()))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "Samples per pixel for ao, shadow and path, 1 to {MAX_SPP} {}; Ctrl-C stops early \
             and, once every pixel has a sample, writes them (exit status 3)",
            or_scene(defaults)
        )
    }

    pub fn seed() -> String {
        format!(
            "Seed of the random numbers: the same command on the same device gives the same \
             image {}",
            or_scene(DEFAULT_SEED)
        )
    }

    pub fn ao_samples() -> String {
        format!(
            "Ambient occlusion rays per sample, 1 to {MAX_AO_SAMPLES} {}",
            or_scene(DEFAULT_AO_SAMPLES)
        )
    }

    pub fn ao_distance() -> String {
        format!(
            "How far ambient occlusion rays reach, in scene units {}",
            or_scene(format_args!(
                "{AO_DISTANCE_SHARE} of the scene's bounding radius"
            ))
        )
    }

    pub fn crease_angle() -> String {
        use cltrace::mesh::DEFAULT_CREASE_ANGLE;
        format!(
            "Smooth normals where the mesh has none: faces meeting at less than this angle \
             shade as one curved surface, sharper edges stay sharp; 0 renders faceted \
             {}",
            or_scene(format_args!("{DEFAULT_CREASE_ANGLE} degrees"))
        )
    }

    pub fn two_sided_lights() -> String {
        format!(
            "Emitting surfaces shine from both faces; without it they shine only from their \
             front face, the side from which their corners run counter-clockwise, as in pbrt, \
             Mitsuba and LuxCoreRender {}",
            or_scene("false")
        )
    }

    pub fn max_bounces() -> String {
        format!(
            "Bounces of the path tracer, 0 to {MAX_BOUNCES} {}",
            or_scene(DEFAULT_MAX_BOUNCES)
        )
    }

    pub fn light() -> String {
        format!(
            "The light of --shade shadow: `sun:x,y,z` (the direction towards it) or \
             `point:x,y,z` (its position) {}",
            or_scene(DEFAULT_LIGHT)
        )
    }
}
