//! The subcommands, as library functions the thin binary calls with plain request structs.

pub mod bench;
pub mod bvh;
pub mod devices;
pub mod render;
pub mod tune;
