//! `cltrace bench`'s flags.

use std::path::PathBuf;
use std::sync::LazyLock;

use clap::Args;

use cltrace::bench::{BenchRequest, RayKind};
use cltrace::bvh::Layout;
use cltrace::commands::bench::BenchCommand;
use cltrace::render::Method;
use cltrace::report::Verbosity;

use super::build::BuildArgs;
use super::values::{
    all_names, choice, device_list, parse_resolution, parse_work_group, triangle_count,
    whole_number,
};

/// Every method and every layout: the defaults of the lists.
static METHODS: LazyLock<String> = LazyLock::new(all_names::<Method>);
static LAYOUTS: LazyLock<String> = LazyLock::new(all_names::<Layout>);

pub const EXAMPLES: &str = "\
Examples:
  cltrace bench                                   the built-in scene, every method and device
  cltrace bench --scenes ../shared/scenes --csv results.csv
  cltrace bench bunny.obj --methods cl-bvh --devices gpu --resolutions 1920x1080
  cltrace bench scenes/materials.toml --rays path --path-spp 64 --methods cl-bvh

Each run: auto framing, one warm-up frame, then --repetitions frames; kernel time is the
device's (OpenCL profiling events) or the trace's wall time (CPU methods). Mrays/s use the
median. Brute-force runs whose frames (warm-up and repetitions together) are estimated to
take more than --brute-budget seconds are listed as skipped, with the estimate.

`--rays path` adds path-tracing rows: a frame is --path-spp samples of every pixel with the
scene's materials, paths of --path-bounces bounces (that plus 2 segments, as Mitsuba 3's
max_depth counts them); Msamples/s are pixels x spp over the median sampling time, Mrays/s
count every segment and shadow ray traced (the CSV and JSON `rays` of a frame).";

#[derive(Args)]
pub struct BenchArgs {
    /// Scene files or meshes to measure [default: the built-in scene]
    scenes: Vec<PathBuf>,

    /// Also measure every mesh (.obj, .obj.gz, .ply, .ply.gz) in this folder
    #[arg(long = "scenes", value_name = "DIR")]
    scene_folders: Vec<PathBuf>,

    /// Methods to measure, comma-separated
    #[arg(
        long,
        value_parser = choice::<Method>(),
        value_delimiter = ',',
        default_value = METHODS.as_str()
    )]
    methods: Vec<Method>,

    /// BVH node layouts to measure cl-bvh in, comma-separated
    #[arg(
        long,
        value_parser = choice::<Layout>(),
        value_delimiter = ',',
        default_value = LAYOUTS.as_str()
    )]
    layouts: Vec<Layout>,

    /// OpenCL devices: `all`, or comma-separated selectors (`P:D`, `gpu`, `cpu`, part of a name)
    #[arg(long, default_value = "all")]
    devices: String,

    /// Ray kinds to measure, comma-separated (path tracing only when named) [default:
    /// primary,diffuse; with --scaling: primary]
    #[arg(long, value_parser = choice::<RayKind>(), value_delimiter = ',')]
    rays: Option<Vec<RayKind>>,

    /// Samples per pixel of a path-tracing frame (`--rays path`), 1 to 65536
    #[arg(value_parser = whole_number, long, value_name = "N", default_value_t = 16)]
    path_spp: u32,

    /// Bounces of the path tracer (`--rays path`), 0 to 1024; paths are 2 segments longer
    #[arg(value_parser = whole_number, long, value_name = "N", default_value_t = 8)]
    path_bounces: u32,

    /// Resolutions, comma-separated `WxH`
    #[arg(long, value_delimiter = ',', value_parser = parse_resolution, default_value = "1920x1080,512x512")]
    resolutions: Vec<(u32, u32)>,

    /// Untimed frames before the timed ones
    #[arg(value_parser = whole_number, long, default_value_t = 1)]
    warmup: u32,

    /// Timed frames per run
    #[arg(value_parser = whole_number, long, default_value_t = 5)]
    repetitions: u32,

    /// Skip brute-force runs (all their frames) estimated to take longer than this, in seconds
    #[arg(long, default_value_t = 10.0)]
    brute_budget: f64,

    /// Also write the rows as CSV
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,

    /// Also write the rows as JSON
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,

    /// Instead of scenes: the BVH methods at 1920x1080 on generated hillsides of 10 thousand
    /// to 10 million triangles (or --scaling-to), to show how build time, memory and speed
    /// grow
    #[arg(long)]
    scaling: bool,

    /// With --scaling, also draw build time and Mrays/s against triangles into this PNG
    #[arg(long, value_name = "FILE.png", requires = "scaling")]
    plot: Option<PathBuf>,

    /// With --scaling, the largest hillside, in triangles (`300M`, `2G` or a count; up to
    /// 2,147,352,578): the study measures each power of ten from 10 thousand below it,
    /// then it, and stops with a note at the first size memory cannot hold
    #[arg(long, value_name = "TRIANGLES", requires = "scaling", value_parser = triangle_count, default_value = "10M")]
    scaling_to: u64,

    /// Launch the OpenCL kernels in work-groups of this shape, `WxH` pixels (arbitrary rays
    /// in groups of W*H), instead of each device's default (16x8 on GPUs, else 8x8): what
    /// `cltrace tune` varies
    #[arg(long, value_name = "WxH", value_parser = parse_work_group)]
    work_group: Option<[usize; 2]>,

    #[command(flatten)]
    build: BuildArgs,

    /// Print nothing but the table and errors
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,

    /// Also print each row as it is measured
    #[arg(short, long)]
    verbose: bool,
}

impl BenchArgs {
    pub fn command(self) -> BenchCommand {
        BenchCommand {
            request: BenchRequest {
                scenes: self.scenes,
                generated: Vec::new(),
                scene_folders: self.scene_folders,
                methods: self.methods,
                layouts: self.layouts,
                devices: device_list(&self.devices),
                ray_kinds: match (self.rays, self.scaling) {
                    (Some(kinds), _) => kinds,
                    (None, false) => RayKind::DEFAULT.to_vec(),
                    (None, true) => vec![RayKind::Primary],
                },
                path_spp: self.path_spp,
                path_bounces: self.path_bounces,
                resolutions: self.resolutions,
                warmup: self.warmup,
                repetitions: self.repetitions,
                brute_budget_s: self.brute_budget,
                build: self.build.options(),
                work_group: self.work_group,
                verbosity: Verbosity::from_flags(self.quiet, self.verbose),
            },
            scaling: self.scaling,
            scaling_to: self.scaling_to,
            csv: self.csv,
            json: self.json,
            plot: self.plot,
        }
    }
}
