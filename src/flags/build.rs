//! The BVH construction flags, shared by the commands that build one.

use clap::Args;

use cltrace::bvh::optimize::{MAX_ROUNDS, MIN_ROUND_GAIN};
use cltrace::bvh::{BuildOptions, Builder};

use super::values::{choice, whole_number};

/// BVH construction flags, shared by the commands that build one.
#[derive(Args)]
pub struct BuildArgs {
    /// BVH builder: binned SAH (fast), the exact sweep (slow, the quality reference), or auto:
    /// the sweep on small scenes
    #[arg(long, value_parser = choice::<Builder>(), default_value = Builder::default().name())]
    builder: Builder,

    /// Bins per axis for the binned builder (2 to 64)
    #[arg(value_parser = whole_number, long, default_value_t = BuildOptions::default().bins)]
    bins: u32,

    /// Largest leaf, in triangles (1 to 255); the SAH decides below it
    #[arg(value_parser = whole_number, long, default_value_t = BuildOptions::default().max_leaf_size)]
    max_leaf_size: u32,

    #[arg(
        value_parser = whole_number,
        long,
        value_name = "N",
        default_value_t = BuildOptions::default().optimize_rounds,
        help = optimize_help()
    )]
    optimize: u32,
}

impl BuildArgs {
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            builder: self.builder,
            bins: self.bins,
            max_leaf_size: self.max_leaf_size,
            optimize_rounds: self.optimize,
            ..BuildOptions::default()
        }
    }
}

fn optimize_help() -> String {
    format!(
        "Optimize the built tree by node reinsertion for up to N rounds (0 to {MAX_ROUNDS}; 0 is \
         off): a lower SAH cost for more build time; rounds stop early once one gains under {}%",
        MIN_ROUND_GAIN * 100.0
    )
}
