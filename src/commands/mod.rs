//! The subcommands, as library functions the thin binary calls.

pub mod bvh;
pub mod devices;
pub mod render;
