//! `cltrace render`'s flags.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use cltrace::bvh::Layout;
use cltrace::camera::CameraSettings;
use cltrace::commands::render::RenderRequest;
use cltrace::input::scene_file::RenderSettings;
use cltrace::render::{Method, Shade};
use cltrace::report::Verbosity;

use super::build::BuildArgs;
use super::values::{choice, parse_vec3};

#[derive(Args)]
pub struct RenderArgs {
    /// A scene file (.toml) or a mesh (.obj, .obj.gz, .ply, .ply.gz); the built-in default
    /// scene when omitted. Flags override the scene file's settings.
    scene: Option<PathBuf>,

    /// Output image; the format follows the extension: png, bmp, ppm, jpg
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,

    /// Image width in pixels (1 to 16384) [default: scene's, else 1280]
    #[arg(long)]
    width: Option<u32>,

    /// Image height in pixels (1 to 16384) [default: scene's, else 720]
    #[arg(long)]
    height: Option<u32>,

    /// Vertical field of view in degrees, in (0, 180) [default: scene's, else 45]
    #[arg(long)]
    fov: Option<f32>,

    /// Eye position `x,y,z` [default: auto framing, in front of the mesh along +z]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<[f32; 3]>,

    /// Point to look at `x,y,z` [default: centre of the mesh's bounding box]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    look_at: Option<[f32; 3]>,

    /// Up direction `x,y,z` [default: 0,1,0]
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    up: Option<[f32; 3]>,

    /// OpenCL device: `P:D` index (see `cltrace devices`), `gpu`, `cpu`, or part of its
    /// name [default: the first GPU, else the first device]
    #[arg(long, env = "CLTRACE_DEVICE")]
    device: Option<String>,

    /// How rays find their closest hit [default: scene's, else cl-bvh]
    #[arg(long, value_parser = choice::<Method>())]
    method: Option<Method>,

    /// BVH node layout of cl-bvh [default: scene's, else bin32]
    #[arg(long, value_parser = choice::<Layout>())]
    layout: Option<Layout>,

    /// How hits are coloured [default: scene's, else lambert]; ao, shadow and path
    /// accumulate samples (--spp) and trace secondary rays
    #[arg(long, value_parser = choice::<Shade>())]
    shade: Option<Shade>,

    /// Samples per pixel for ao, shadow and path, 1 to 65536 [default: scene's, else 16
    /// for path, 4 for shadow, 1 for ao]; Ctrl-C stops early and writes what accumulated
    #[arg(long)]
    spp: Option<u32>,

    /// Seed of the random numbers: the same command on the same device gives the same image
    /// [default: scene's, else 0]
    #[arg(long)]
    seed: Option<u32>,

    /// Ambient occlusion rays per sample, 1 to 1024 [default: scene's, else 16]
    #[arg(long)]
    ao_samples: Option<u32>,

    /// How far ambient occlusion rays reach, in scene units [default: scene's, else a
    /// quarter of the scene's bounding radius]
    #[arg(long)]
    ao_distance: Option<f32>,

    /// Bounces of the path tracer, 0 to 1024 [default: scene's, else 8]
    #[arg(long)]
    max_bounces: Option<u32>,

    /// The light of --shade shadow: `sun:x,y,z` (the direction towards it) or
    /// `point:x,y,z` (its position) [default: scene's, else sun:-0.4,1,0.6]
    #[arg(long, allow_hyphen_values = true)]
    light: Option<String>,

    /// Also write the raw per-pixel hit records here (8 bytes a pixel: u32 triangle, f32 distance)
    #[arg(long, value_name = "FILE")]
    hits: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// If the OpenCL device fails (none found, kernel build, out of memory, lost), render on
    /// the host instead of stopping with the error
    #[arg(long, value_enum, value_name = "WHERE")]
    fallback: Option<Fallback>,

    /// Print nothing but errors
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,

    /// Also print mesh, camera, device and BVH details
    #[arg(short, long)]
    verbose: bool,
}

impl RenderArgs {
    pub fn request(self) -> RenderRequest {
        RenderRequest {
            scene: self.scene,
            camera: CameraSettings {
                eye: self.eye,
                look_at: self.look_at,
                up: self.up,
                fov: self.fov,
                width: self.width,
                height: self.height,
            },
            render: RenderSettings {
                method: self.method,
                layout: self.layout,
                shade: self.shade,
                spp: self.spp,
                seed: self.seed,
                ao_samples: self.ao_samples,
                ao_distance: self.ao_distance,
                max_bounces: self.max_bounces,
                light: self.light,
            },
            output: self.output,
            hits: self.hits,
            device: self.device,
            build: self.build.options(),
            fallback_to_cpu: self.fallback == Some(Fallback::Cpu),
            tune_cache: cltrace::tune::cache_path(),
            verbosity: Verbosity::from_flags(self.quiet, self.verbose),
        }
    }
}

/// Where `--fallback` sends a render whose OpenCL device fails: one place for now, named so
/// that the flag reads `--fallback cpu`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Fallback {
    /// The same method on the host: cl-bvh becomes cpu-bvh, cl-brute cpu-brute.
    Cpu,
}
