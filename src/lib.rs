//! cltrace: a BVH ray tracer for any OpenCL device.
//!
//! The stages, one module each, in the order a render runs them:
//!
//! - [`input`]: meshes from OBJ/PLY files or generators, and TOML scene files;
//! - [`mesh`]: the triangle mesh every later stage reads;
//! - [`material`]: diffuse albedo and emission per triangle;
//! - [`camera`]: the pinhole camera and its exact pixel-to-ray arithmetic;
//! - [`triangle`]: the watertight ray/triangle test (mirrored in `cl/cltrace.h`);
//! - [`bvh`]: the SAH builders, tree statistics and the host traversal;
//! - [`layout`]: the flat device structs the kernels read;
//! - [`device`]: OpenCL device selection, kernel compilation, pitched images;
//! - [`render`]: the CPU reference tracers and the OpenCL renderer;
//! - [`output`]: images and hit records, written atomically;
//! - [`bench`]: the cross-device benchmark table;
//! - [`tune`]: the fastest layout and work-group per device, cached;
//! - [`commands`]: the subcommands the `cltrace` binary runs.

pub mod bench;
pub mod brute;
pub mod bvh;
pub mod camera;
pub mod commands;
pub mod device;
pub mod error;
pub mod geometry;
pub mod input;
pub mod intersect;
pub mod material;
pub mod mesh;
pub mod output;
pub mod render;
pub mod renderer;
pub mod report;
pub mod tune;

pub use error::{Error, Result};
