//! The same questions to every tracer: each implementation of `ClosestHit` on the host
//! (brute force, the BVH under every builder setting) and every OpenCL tracer (the
//! brute-force kernels, the BVH kernels of each layout) must find brute force's closest
//! hits and valid any hits on the test scenes and the degenerate meshes. The checks are
//! the generic functions of `common::tracers`; each test runs them on one implementation.

use cltrace::brute::BruteForce;
use cltrace::bvh::{Bin32Bvh, Bvh};

use crate::common::tracers::{
    DeviceTracer, agrees_with_brute_force, device_agrees_with_brute_force, in_file_order,
};
use crate::common::*;

#[test]
fn host_brute_force_any_hits_agree_with_its_closest_hits() {
    agrees_with_brute_force("brute force", |mesh| BruteForce {
        triangles: in_file_order(mesh),
    });
}

#[test]
fn bin32_bvh_hits_equal_brute_force_under_every_builder_setting() {
    for opts in all_options() {
        agrees_with_brute_force(&format!("bin32 BVH, {opts:?}"), |mesh| {
            Bin32Bvh::new(Bvh::build(mesh, &opts), mesh)
        });
    }
}

#[test]
fn every_opencl_tracer_hits_like_brute_force() {
    on_every_device(|device| {
        for tracer in DeviceTracer::all() {
            device_agrees_with_brute_force(device, tracer);
        }
    });
}
