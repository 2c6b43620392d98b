//! The command line of `cltrace`: one module per subcommand's flags, the shared BVH build
//! flags and the value parsers. Each subcommand's flags turn into the plain request struct
//! of its library command ([`cltrace::commands`]); nothing past this module sees clap.

mod bench;
mod build;
mod bvh;
mod merge;
mod render;
mod tune;
mod values;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub use bench::BenchArgs;
pub use bvh::BvhArgs;
pub use merge::MergeArgs;
pub use render::RenderArgs;
pub use tune::TuneArgs;

const EXAMPLES: &str = "\
Examples:
  cltrace render                                  the built-in default scene to render.png
  cltrace render bunny.obj -o bunny.png --width 512 --height 512
  cltrace render scenes/room.toml --shade normal --method cpu-brute
  cltrace render dragon.obj.gz --device cpu --hits hits.bin
  cltrace render scenes/room.toml --shade path --spp 256 -o room.exr
  cltrace render bunny.obj --shade ao --ao-samples 32
  cltrace devices                                 list every OpenCL platform and device

Exit status: 0 on success, 1 for device or output failures, 2 for bad input (mesh, scene,
camera, options), 3 for a partial result after Ctrl-C, 130 for Ctrl-C with nothing written.";

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
pub enum Command {
    /// Render a scene file or a mesh to an image
    #[command(after_help = EXAMPLES, allow_negative_numbers = true)]
    Render(RenderArgs),
    /// Add the parts of a render (`render --region` or `--samples`) into one image, exactly:
    /// the same image as rendering it at once
    #[command(after_help = merge::EXAMPLES)]
    Merge(MergeArgs),
    /// List every OpenCL platform and device, with the index `--device` accepts
    Devices,
    /// Measure every method on every OpenCL device for each scene and resolution (auto
    /// framing, warm-up, the median of timed frames) and print a Markdown table
    #[command(after_help = bench::EXAMPLES)]
    Bench(BenchArgs),
    /// Find each OpenCL device's fastest BVH layout and work-group shape (primary and
    /// diffuse rays at 1920x1080) and remember them in the tuning cache, which renders read
    Tune(TuneArgs),
    /// Build a scene's BVH and print its statistics: nodes, leaves, depth, leaf sizes,
    /// SAH cost, build time and device bytes per triangle
    Bvh(BvhArgs),
}

/// The subcommand the command line asks for. Help and version are printed to stdout (and
/// the process ends) as usual; a mistake on the command line is clap's message on stderr
/// (the error, its tips such as "a similar argument exists", the possible values) without
/// the usage block, and exit status 2, like any other bad input.
pub fn parse() -> Result<Command, ExitCode> {
    match Cli::try_parse() {
        Ok(cli) => Ok(cli.command),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.render().to_string();
            let kept: Vec<&str> = text
                .lines()
                .filter(|l| !l.trim().is_empty() && !l.starts_with("Usage:"))
                .map(str::trim_end)
                .collect();
            match kept.is_empty() {
                true => cltrace::report::print_message("error: invalid arguments (see --help)"),
                false => cltrace::report::print_message(&kept.join("\n")),
            }
            Err(ExitCode::from(2))
        }
    }
}
