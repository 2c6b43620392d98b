#![deny(missing_docs)]
//! cltrace: a BVH ray tracer for any OpenCL device.
//!
//! The modules, bottom layer first; each uses only those above it in this list
//! (`tests/module_graph.rs` keeps it so):
//!
//! - [`error`], [`geometry`]: the error type; rays and boxes.
//! - [`mesh`], [`camera`], [`interrupt`], [`huge_pages`]: the triangle mesh every stage
//!   reads; the pinhole camera and its exact pixel-to-ray arithmetic; the Ctrl-C flag long
//!   work polls; the binary's allocator, which puts large buffers in huge pages.
//! - [`intersect`], [`animation`]: the stored triangle, the watertight ray/triangle test
//!   and the robust slab test (mirrored in `cl/intersect.cl`), and
//!   [`intersect::ClosestHit`], what every host tracer answers; the camera of each frame of
//!   a scene's keyframes or turntable.
//! - [`material`], [`light`]: materials per triangle; the lights besides emitters.
//! - [`brute`], [`bvh`]: brute force on the host;
//!   the SAH builders and the device layouts (`bin32`, `bin64`, `wide4`, `wide8`, `cwbvh`),
//!   each with its host traversal or box test.
//! - [`render`], [`report`]: host shading, sampling and the path tracer's reference;
//!   timings and verbosity.
//! - [`input`], [`output`]: meshes, materials and scene files in; images and hit records
//!   out, written atomically.
//! - [`device`]: the OpenCL host side, the only module that speaks OpenCL: devices,
//!   programs assembled from `cl/`, pitched images, the tracer.
//! - [`renderer`]: the four methods behind one face.
//! - [`bench`](mod@bench), [`tune`]: the cross-device benchmark table; the fastest layout and
//!   work-group per device, cached.
//! - [`commands`]: the subcommands the `cltrace` binary runs (its flags live in the
//!   binary, `src/flags/`).

// In layer order (see above); rustfmt keeps each group as it is.
pub mod error;
pub mod geometry;
pub(crate) mod hash;

pub mod camera;
pub mod huge_pages;
pub mod interrupt;
pub mod mesh;

pub mod animation;
pub mod intersect;

pub mod brute;
pub mod bvh;
pub mod light;
pub mod material;

pub mod render;
pub mod report;

pub mod input;
pub mod output;

pub mod device;

pub mod renderer;

pub mod bench;

pub mod tune;

pub mod commands;

pub use error::{Error, Result};
