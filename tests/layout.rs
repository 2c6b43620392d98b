//! The structs shared with the kernels have the same size and field offsets on the host
//! and on the device: `probe.cl` reports the device compiler's layout.

mod common;

use std::mem::{offset_of, size_of};

use cltrace::device::KernelSource;
use cltrace::layout::{BvhNode, Triangle};
use cltrace::render::Hit;

#[test]
fn device_structs_match_the_rust_structs() {
    let host: Vec<(&str, usize)> = vec![
        ("sizeof(Triangle)", size_of::<Triangle>()),
        ("Triangle.v0", offset_of!(Triangle, v0)),
        ("Triangle.prim", offset_of!(Triangle, prim)),
        ("Triangle.v1", offset_of!(Triangle, v1)),
        ("Triangle.v2", offset_of!(Triangle, v2)),
        ("sizeof(BvhNode)", size_of::<BvhNode>()),
        ("BvhNode.min", offset_of!(BvhNode, min)),
        ("BvhNode.left_or_first", offset_of!(BvhNode, left_or_first)),
        ("BvhNode.max", offset_of!(BvhNode, max)),
        (
            "BvhNode.right_or_count",
            offset_of!(BvhNode, right_or_count),
        ),
        ("sizeof(Hit)", size_of::<Hit>()),
        ("Hit.prim", offset_of!(Hit, prim)),
        ("Hit.t", offset_of!(Hit, t)),
    ];
    // The thesis's node is 32 bytes; a triangle is three 16-byte corners.
    assert_eq!(size_of::<BvhNode>(), 32);
    assert_eq!(size_of::<Triangle>(), 48);
    assert_eq!(size_of::<Hit>(), 8);

    let device = common::device();
    let program = device.build(KernelSource::Probe, &[]).unwrap();
    let out = ocl::Buffer::<u32>::builder()
        .queue(device.queue.clone())
        .len(host.len())
        .fill_val(u32::MAX)
        .build()
        .unwrap();
    let kernel = ocl::Kernel::builder()
        .program(&program)
        .name("probe_layout")
        .queue(device.queue.clone())
        .global_work_size(1)
        .arg(&out)
        .build()
        .unwrap();
    unsafe { kernel.enq().unwrap() };
    let mut reported = vec![0u32; host.len()];
    out.read(&mut reported).enq().unwrap();
    for ((what, expected), got) in host.iter().zip(&reported) {
        assert_eq!(*got as usize, *expected, "{what} on {}", device.info.name);
    }
}
