//! The subcommands, as library functions the thin binary calls.

pub mod devices;
pub mod render;
