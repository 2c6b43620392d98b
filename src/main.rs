//! The `cltrace` command: parses the command line and hands over to the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use cltrace::bench::{self as benchmark, BenchRequest, RayKind};
use cltrace::bvh::{BuildOptions, Builder};
use cltrace::commands::{bvh, devices, render};
use cltrace::input::scene_file::{CameraSettings, RenderSettings};
use cltrace::render::{Method, Shade};
use cltrace::report::Verbosity;

const EXAMPLES: &str = "\
Examples:
  cltrace render                                  the built-in default scene to render.png
  cltrace render bunny.obj -o bunny.png --width 512 --height 512
  cltrace render scenes/room.toml --shade normal --method cpu-brute
  cltrace render dragon.obj.gz --device cpu --hits hits.bin
  cltrace devices                                 list every OpenCL platform and device

Exit status: 0 on success, 2 for bad input (mesh, scene, camera, options), 1 for device
or output failures.";

#[derive(Parser)]
#[command(
    name = "cltrace",
    version,
    about = "A BVH ray tracer for any OpenCL device: NVIDIA GPUs and CPUs through PoCL",
    after_help = EXAMPLES
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file or a mesh to an image (one primary ray per pixel)
    #[command(after_help = EXAMPLES)]
    Render(RenderArgs),
    /// List every OpenCL platform and device, with the index `--device` accepts
    Devices,
    /// Measure every method on every OpenCL device for each scene and resolution (the
    /// benchmark protocol of BENCHMARK.md) and print a Markdown table
    #[command(after_help = BENCH_EXAMPLES)]
    Bench(BenchArgs),
    /// Build a scene's BVH and print its statistics: nodes, leaves, depth, leaf sizes,
    /// SAH cost, build time and device bytes per triangle
    Bvh(BvhArgs),
}

const BENCH_EXAMPLES: &str = "\
Examples:
  cltrace bench                                   the built-in scene, every method and device
  cltrace bench --scenes ../shared/scenes --csv results.csv
  cltrace bench bunny.obj --methods cl-bvh --devices gpu --resolutions 1920x1080

Each run: auto framing, one warm-up frame, then --repetitions frames; kernel time is the
device's (OpenCL profiling events) or the trace's wall time (CPU methods). Mrays/s use the
median. Brute-force runs whose frames (warm-up and repetitions together) are estimated to
take more than --brute-budget seconds are listed as skipped, with the estimate.";

#[derive(Args)]
struct BenchArgs {
    /// Scene files or meshes to measure [default: the built-in scene]
    scenes: Vec<PathBuf>,

    /// Also measure every mesh (.obj, .obj.gz, .ply, .ply.gz) in this folder
    #[arg(long = "scenes", value_name = "DIR")]
    scene_folders: Vec<PathBuf>,

    /// Methods to measure, comma-separated
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "cpu-brute,cpu-bvh,cl-brute,cl-bvh"
    )]
    methods: Vec<Method>,

    /// OpenCL devices: `all`, or comma-separated selectors (`P:D`, `gpu`, `cpu`, part of a name)
    #[arg(long, default_value = "all")]
    devices: String,

    /// Ray kinds to measure, comma-separated
    #[arg(long, value_enum, value_delimiter = ',', default_value = "primary")]
    rays: Vec<RayKind>,

    /// Resolutions, comma-separated `WxH`
    #[arg(long, value_delimiter = ',', value_parser = parse_resolution, default_value = "1920x1080,512x512")]
    resolutions: Vec<(u32, u32)>,

    /// Untimed frames before the timed ones
    #[arg(long, default_value_t = 1)]
    warmup: u32,

    /// Timed frames per run
    #[arg(long, default_value_t = 5)]
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
    /// to 10 million triangles, to show how build time, memory and speed grow
    #[arg(long)]
    scaling: bool,

    /// With --scaling, also draw build time and Mrays/s against triangles into this PNG
    #[arg(long, value_name = "FILE.png", requires = "scaling")]
    plot: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// Print nothing but the table and errors
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,

    /// Also print each row as it is measured
    #[arg(short, long)]
    verbose: bool,
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not a resolution `WIDTHxHEIGHT`"))?;
    match (w.trim().parse(), h.trim().parse()) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(format!("`{s}` is not a resolution `WIDTHxHEIGHT`")),
    }
}

#[derive(Args)]
struct BvhArgs {
    /// A scene file (.toml) or a mesh; the built-in default scene when omitted
    scene: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// Build this many times and report the fastest
    #[arg(long, default_value_t = 1)]
    repeat: u32,
}

/// BVH construction flags, shared by the commands that build one.
#[derive(Args)]
struct BuildArgs {
    /// BVH builder: binned SAH (fast) or the exact sweep (slow, the quality reference)
    #[arg(long, value_enum, default_value = "binned")]
    builder: Builder,

    /// Bins per axis for the binned builder (2 to 64)
    #[arg(long, default_value_t = BuildOptions::default().bins)]
    bins: u32,

    /// Largest leaf, in triangles (1 to 255); the SAH decides below it
    #[arg(long, default_value_t = BuildOptions::default().max_leaf_size)]
    max_leaf_size: u32,
}

impl BuildArgs {
    fn options(&self) -> BuildOptions {
        BuildOptions {
            builder: self.builder,
            bins: self.bins,
            max_leaf_size: self.max_leaf_size,
            ..BuildOptions::default()
        }
    }
}

#[derive(Args)]
struct RenderArgs {
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
    #[arg(long, value_enum)]
    method: Option<Method>,

    /// How hits are coloured [default: scene's, else lambert]
    #[arg(long, value_enum)]
    shade: Option<Shade>,

    /// Also write the raw per-pixel hit records here (8 bytes a pixel: u32 triangle, f32 distance)
    #[arg(long, value_name = "FILE")]
    hits: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// Print nothing but errors
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,

    /// Also print mesh, camera, device and BVH details
    #[arg(short, long)]
    verbose: bool,
}

fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<f32> = parts
        .iter()
        .map(|p| p.parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` is not three numbers `x,y,z`"))?;
    match numbers.as_slice() {
        [x, y, z] if numbers.iter().all(|v| v.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("`{s}` is not three finite numbers `x,y,z`")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Devices => devices::devices_table().map(|table| print!("{table}")),
        Command::Bench(args) => run_bench(args),
        Command::Bvh(args) => {
            bvh::bvh_report(args.scene.as_deref(), &args.build.options(), args.repeat)
                .map(|report| print!("{report}"))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn run_render(args: RenderArgs) -> cltrace::Result<()> {
    let verbosity = Verbosity::from_flags(args.quiet, args.verbose);
    let request = render::RenderRequest {
        scene: args.scene,
        camera: CameraSettings {
            eye: args.eye,
            look_at: args.look_at,
            up: args.up,
            fov: args.fov,
            width: args.width,
            height: args.height,
        },
        render: RenderSettings {
            method: args.method,
            shade: args.shade,
        },
        output: args.output,
        hits: args.hits,
        device: args.device,
        build: args.build.options(),
        verbosity,
    };
    let outcome = render::run(&request)?;
    let on = outcome
        .device
        .map(|d| format!(" on {d}"))
        .unwrap_or_default();
    verbosity.say(format!(
        "wrote {} ({}x{}, {}{on})",
        request.output.display(),
        outcome.frame.width,
        outcome.frame.height,
        outcome.method.name(),
    ));
    verbosity.say(outcome.timings.summary());
    Ok(())
}

fn run_bench(args: BenchArgs) -> cltrace::Result<()> {
    let request = BenchRequest {
        scenes: args.scenes,
        generated: Vec::new(),
        scene_folders: args.scene_folders,
        methods: args.methods,
        devices: (!args.devices.trim().eq_ignore_ascii_case("all")).then(|| {
            args.devices
                .split(',')
                .map(|s| s.trim().to_string())
                .collect()
        }),
        ray_kinds: args.rays,
        resolutions: args.resolutions,
        warmup: args.warmup,
        repetitions: args.repetitions,
        brute_budget_s: args.brute_budget,
        build: args.build.options(),
        verbosity: Verbosity::from_flags(args.quiet, args.verbose),
    };
    if let Some(csv) = &args.csv {
        cltrace::output::check_folder(csv)?;
    }
    if let Some(json) = &args.json {
        cltrace::output::check_folder(json)?;
    }
    if let Some(plot) = &args.plot {
        cltrace::output::check_folder(plot)?;
    }
    let rows = if args.scaling {
        let rows = benchmark::run(&benchmark::scaling_request(&request))?;
        print!("{}", benchmark::scaling_table(&rows));
        if let Some(plot) = &args.plot {
            benchmark::plot_scaling(&rows, plot)?;
        }
        rows
    } else {
        let rows = benchmark::run(&request)?;
        print!("{}", benchmark::markdown(&rows));
        rows
    };
    if let Some(csv) = &args.csv {
        benchmark::write_csv(&rows, csv)?;
    }
    if let Some(json) = &args.json {
        benchmark::write_json(&rows, json)?;
    }
    Ok(())
}
