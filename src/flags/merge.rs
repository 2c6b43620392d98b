//! `cltrace merge`'s flags.

use std::path::PathBuf;

use clap::Args;

use cltrace::commands::merge::MergeRequest;
use cltrace::report::Verbosity;

pub const EXAMPLES: &str = "\
Examples:
  cltrace render room.toml --shade path --spp 256 --region 0,0,640,360 -o tl.exr
  (... the other three quarters ...)
  cltrace merge tl.exr tr.exr bl.exr br.exr -o room.png

  cltrace render room.toml --shade path --samples 0..128 -o a.exr
  cltrace render room.toml --shade path --samples 128..256 -o b.exr
  cltrace merge a.exr b.exr -o room.exr     the same image as --spp 256, bit for bit";

#[derive(Args)]
pub struct MergeArgs {
    /// The parts: OpenEXR files from `render --region` or `--samples`, in any order
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,

    /// Output image; the format follows the extension: png, bmp, ppm, jpg (8-bit sRGB),
    /// exr, pfm (32-bit float, linear)
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,

    /// Print nothing but errors
    #[arg(short, long)]
    quiet: bool,
}

impl MergeArgs {
    pub fn request(self) -> MergeRequest {
        MergeRequest {
            parts: self.parts,
            output: self.output,
            verbosity: Verbosity::from_flags(self.quiet, false),
        }
    }
}
