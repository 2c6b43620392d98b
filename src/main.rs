//! The `cltrace` command: parses the command line and hands over to the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use cltrace::bench::{self as benchmark, BenchRequest, RayKind};
use cltrace::bvh::Layout;
use cltrace::bvh::{BuildOptions, Builder};
use cltrace::camera::CameraSettings;
use cltrace::commands::{bvh, devices, render};
use cltrace::input::scene_file::RenderSettings;
use cltrace::render::{Method, Shade};
use cltrace::report::Verbosity;

const EXAMPLES: &str = "\
Examples:
  cltrace render                                  the built-in default scene to render.png
  cltrace render bunny.obj -o bunny.png --width 512 --height 512
  cltrace render scenes/room.toml --shade normal --method cpu-brute
  cltrace render dragon.obj.gz --device cpu --hits hits.bin
  cltrace render scenes/room.toml --shade path --spp 256 -o room.exr
  cltrace render bunny.obj --shade ao --ao-samples 32
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
    /// Render a scene file or a mesh to an image
    #[command(after_help = EXAMPLES, allow_negative_numbers = true)]
    Render(RenderArgs),
    /// List every OpenCL platform and device, with the index `--device` accepts
    Devices,
    /// Measure every method on every OpenCL device for each scene and resolution (the
    /// benchmark protocol of BENCHMARK.md) and print a Markdown table
    #[command(after_help = BENCH_EXAMPLES)]
    Bench(BenchArgs),
    /// Find each OpenCL device's fastest BVH layout and work-group shape (primary and
    /// diffuse rays at 1920x1080) and remember them in the tuning cache, which renders read
    Tune(TuneArgs),
    /// Build a scene's BVH and print its statistics: nodes, leaves, depth, leaf sizes,
    /// SAH cost, build time and device bytes per triangle
    Bvh(BvhArgs),
}

#[derive(Args)]
struct TuneArgs {
    /// The scene to measure on [default: the built-in scene]
    scene: Option<PathBuf>,

    /// OpenCL devices: `all`, or comma-separated selectors
    #[arg(long, default_value = "all")]
    devices: String,

    /// Timed frames per combination (after one warm-up frame)
    #[arg(long, default_value_t = 3)]
    repetitions: u32,

    /// The cache file [default: CLTRACE_TUNE_CACHE, else ~/.cache/cltrace/tune.toml]
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,

    /// Print nothing but the table and errors
    #[arg(short, long)]
    quiet: bool,
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

    /// BVH node layouts to measure cl-bvh in, comma-separated
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "bin32,bin64,wide4,wide8,cwbvh"
    )]
    layouts: Vec<Layout>,

    /// OpenCL devices: `all`, or comma-separated selectors (`P:D`, `gpu`, `cpu`, part of a name)
    #[arg(long, default_value = "all")]
    devices: String,

    /// Ray kinds to measure, comma-separated
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "primary,diffuse"
    )]
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

    /// Optimize the built tree by node reinsertion for up to N rounds (0 to 1000; 0 is off):
    /// a lower SAH cost for more build time; rounds stop early once one gains under 0.01%
    #[arg(long, value_name = "N", default_value_t = BuildOptions::default().optimize_rounds)]
    optimize: u32,
}

impl BuildArgs {
    fn options(&self) -> BuildOptions {
        BuildOptions {
            builder: self.builder,
            bins: self.bins,
            max_leaf_size: self.max_leaf_size,
            optimize_rounds: self.optimize,
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

    /// BVH node layout of cl-bvh [default: scene's, else bin32]
    #[arg(long, value_enum)]
    layout: Option<Layout>,

    /// How hits are coloured [default: scene's, else lambert]; ao, shadow and path
    /// accumulate samples (--spp) and trace secondary rays
    #[arg(long, value_enum)]
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
    fallback: Option<render::Fallback>,

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
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Help and version go to stdout as usual; a mistake on the command line is one line
        // on stderr and exit status 2, like any other bad input.
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.render().to_string();
            let first = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("error: invalid arguments");
            eprintln!("{} (see --help)", first.trim_end());
            return ExitCode::from(2);
        }
    };
    // The first Ctrl-C asks a progressive render to stop and write what it has; a second
    // one ends the process at once.
    let _ = ctrlc::set_handler(|| {
        if render::STOP.swap(true, std::sync::atomic::Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Devices => devices::devices_table().map(|table| print!("{table}")),
        Command::Bench(args) => run_bench(args),
        Command::Tune(args) => run_tune(args),
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
            layout: args.layout,
            shade: args.shade,
            spp: args.spp,
            seed: args.seed,
            ao_samples: args.ao_samples,
            ao_distance: args.ao_distance,
            max_bounces: args.max_bounces,
            light: args.light,
        },
        output: args.output,
        hits: args.hits,
        device: args.device,
        build: args.build.options(),
        fallback: args.fallback,
        tune_cache: cltrace::tune::cache_path(),
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
        layouts: args.layouts,
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

fn run_tune(args: TuneArgs) -> cltrace::Result<()> {
    use cltrace::device::{ClDevice, DeviceSelector, list_devices};
    use cltrace::tune::{TuneCache, cache_path, tune_device};
    let verbosity = Verbosity::from_flags(args.quiet, false);
    let path = args.cache.or_else(cache_path).ok_or_else(|| {
        cltrace::Error::Invalid("no cache location: set CLTRACE_TUNE_CACHE or HOME".into())
    })?;
    let scene = cltrace::input::scene_file::SceneDescription::named(args.scene.as_deref())?;
    let mesh = scene.mesh.load()?;
    let all = list_devices()?;
    let chosen: Vec<_> = if args.devices.trim().eq_ignore_ascii_case("all") {
        all.clone()
    } else {
        args.devices
            .split(',')
            .map(|s| s.trim().parse::<DeviceSelector>()?.pick(&all).cloned())
            .collect::<cltrace::Result<_>>()?
    };
    let mut cache = TuneCache::load(&path);
    println!(
        "| device | layout | work-group | primary Mrays/s | diffuse Mrays/s |\n|---|---|---|---|---|"
    );
    for info in chosen {
        let device = ClDevice::open(info)?;
        verbosity.say(format!(
            "tuning {} on {}",
            device.info.name,
            scene.mesh.name()
        ));
        let results = tune_device(&device, &mesh, args.repetitions, &mut |r| {
            println!(
                "| {} | {} | {}x{} | {:.1} | {:.1} |",
                device.info.name,
                r.layout.name(),
                r.work_group[0],
                r.work_group[1],
                r.primary_mrays,
                r.diffuse_mrays
            );
        })?;
        let best = &results[0];
        verbosity.say(format!(
            "best on {}: {} with {}x{} work-groups ({:.1} primary, {:.1} diffuse Mrays/s)",
            device.info.name,
            best.layout.name(),
            best.work_group[0],
            best.work_group[1],
            best.primary_mrays,
            best.diffuse_mrays
        ));
        cache.devices.insert(
            device.info.key(),
            cltrace::tune::Tuning {
                layout: best.layout,
                work_group: best.work_group,
                primary_mrays: best.primary_mrays,
                diffuse_mrays: best.diffuse_mrays,
                scene: scene.mesh.name(),
            },
        );
    }
    cache.save(&path)?;
    verbosity.say(format!("saved to {}", path.display()));
    Ok(())
}
