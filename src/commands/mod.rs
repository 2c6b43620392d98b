//! The subcommands, as library functions the thin binary calls with plain request structs.

pub mod bench;
pub mod bvh;
pub mod devices;
pub mod frames;
pub mod merge;
pub mod render;
pub mod tune;

/// How a command that can be interrupted ended, when it did not fail.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// Everything asked for was done.
    Complete,
    /// Interrupted (Ctrl-C, `SIGTERM`) after some of the work: what was done is written
    /// (an image with fewer samples per pixel, the benchmark rows measured), and the exit
    /// status says it is partial.
    Partial,
}

impl Ending {
    /// The exit status: 0 when complete, 3 for a partial result.
    pub fn exit_code(self) -> u8 {
        match self {
            Ending::Complete => 0,
            Ending::Partial => 3,
        }
    }
}
