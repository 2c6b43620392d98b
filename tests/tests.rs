//! The integration tests, linked once: each `tests/<name>.rs` is the module `<name>` of this
//! one test binary (`cargo test --release --test tests <name>` runs one of them), with the
//! shared helpers in `tests/common/`.

mod common;

mod bad_input_corpus;
mod bsdf;
mod bvh;
mod bvh_optimize;
mod camera;
mod cli;
mod commands;
mod concurrency;
mod frames;
mod fuzz_regressions;
mod gltf;
mod interrupt;
mod kernel_sources;
mod layout;
mod lights;
mod limits;
mod loaders;
mod mitsuba;
mod module_graph;
mod oclgrind;
mod opencl_vs_cpu;
mod parts;
mod program_cache;
mod run_report;
mod scene_files;
mod secondary;
mod slurm;
mod surfaces;
mod tracers;
mod watertight;
