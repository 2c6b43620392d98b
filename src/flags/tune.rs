//! `cltrace tune`'s flags.

use std::path::PathBuf;

use clap::Args;

use cltrace::commands::tune::TuneRequest;
use cltrace::report::Verbosity;

use super::values::{device_list, whole_number};

#[derive(Args)]
pub struct TuneArgs {
    /// The scene to measure on [default: the built-in scene]
    scene: Option<PathBuf>,

    /// OpenCL devices: `all`, or comma-separated selectors
    #[arg(long, default_value = "all")]
    devices: String,

    /// Timed frames per combination (after one warm-up frame)
    #[arg(value_parser = whole_number, long, default_value_t = 3)]
    repetitions: u32,

    /// The cache file [default: CLTRACE_TUNE_CACHE, else ~/.cache/cltrace/tune.toml]
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,

    /// Print nothing but the table and errors
    #[arg(short, long)]
    quiet: bool,
}

impl TuneArgs {
    pub fn request(self) -> TuneRequest {
        TuneRequest {
            scene: self.scene,
            devices: device_list(&self.devices),
            repetitions: self.repetitions,
            cache: self.cache.or_else(cltrace::tune::cache_path),
            verbosity: Verbosity::from_flags(self.quiet, false),
        }
    }
}
