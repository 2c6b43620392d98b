//! `cltrace bvh`'s flags.

use super::values::whole_number;
use std::path::PathBuf;

use clap::Args;

use cltrace::commands::bvh::BvhRequest;

use super::build::BuildArgs;

#[derive(Args)]
pub struct BvhArgs {
    /// A scene file (.toml) or a mesh; the built-in default scene when omitted
    scene: Option<PathBuf>,

    #[command(flatten)]
    build: BuildArgs,

    /// Build this many times and report the fastest
    #[arg(value_parser = whole_number, long, default_value_t = 1)]
    repeat: u32,
}

impl BvhArgs {
    pub fn request(self) -> BvhRequest {
        BvhRequest {
            build: self.build.options(),
            scene: self.scene,
            repeat: self.repeat,
        }
    }
}
