//! The structs shared with the kernels have the same size and field offsets on the host
//! and on the device: `probe.cl` reports the device compiler's layout.

use crate::common;

use std::mem::{offset_of, size_of};

use cltrace::bvh::Bin32Node;
use cltrace::bvh::bin64::Bin64Node;
use cltrace::bvh::cwbvh::CwbvhNode;
use cltrace::bvh::{wide4::Wide4Node, wide8::Wide8Node};
use cltrace::device::KernelSource;
use cltrace::intersect::Triangle;
use cltrace::material::Material;
use cltrace::render::Hit;

#[test]
fn device_structs_match_the_rust_structs() {
    let host: Vec<(&str, usize)> = vec![
        ("sizeof(Triangle)", size_of::<Triangle>()),
        ("Triangle.v0", offset_of!(Triangle, v0)),
        ("Triangle.prim", offset_of!(Triangle, prim)),
        ("Triangle.v1", offset_of!(Triangle, v1)),
        ("Triangle.material", offset_of!(Triangle, material)),
        ("Triangle.v2", offset_of!(Triangle, v2)),
        ("sizeof(Bin32Node)", size_of::<Bin32Node>()),
        ("Bin32Node.min", offset_of!(Bin32Node, min)),
        (
            "Bin32Node.left_or_first",
            offset_of!(Bin32Node, left_or_first),
        ),
        ("Bin32Node.max", offset_of!(Bin32Node, max)),
        (
            "Bin32Node.right_or_count",
            offset_of!(Bin32Node, right_or_count),
        ),
        ("sizeof(Hit)", size_of::<Hit>()),
        ("Hit.prim", offset_of!(Hit, prim)),
        ("Hit.t", offset_of!(Hit, t)),
        ("sizeof(Material)", size_of::<Material>()),
        ("Material.albedo", offset_of!(Material, albedo)),
        ("Material.emission", offset_of!(Material, emission)),
        ("sizeof(Bin64Node)", size_of::<Bin64Node>()),
        ("Bin64Node.right_xy", offset_of!(Bin64Node, right_xy)),
        ("Bin64Node.z", offset_of!(Bin64Node, z)),
        ("Bin64Node.refs", offset_of!(Bin64Node, refs)),
        ("sizeof(Wide4Node)", size_of::<Wide4Node>()),
        ("Wide4Node.max_z", offset_of!(Wide4Node, max_z)),
        ("Wide4Node.child", offset_of!(Wide4Node, child)),
        ("Wide4Node.count", offset_of!(Wide4Node, count)),
        ("sizeof(Wide8Node)", size_of::<Wide8Node>()),
        ("Wide8Node.max_z", offset_of!(Wide8Node, max_z)),
        ("Wide8Node.child", offset_of!(Wide8Node, child)),
        ("Wide8Node.count", offset_of!(Wide8Node, count)),
        ("sizeof(CwbvhNode)", size_of::<CwbvhNode>()),
        ("CwbvhNode.exponent", offset_of!(CwbvhNode, exponent)),
        ("CwbvhNode.inner_mask", offset_of!(CwbvhNode, inner_mask)),
        ("CwbvhNode.child_base", offset_of!(CwbvhNode, child_base)),
        (
            "CwbvhNode.triangle_base",
            offset_of!(CwbvhNode, triangle_base),
        ),
        ("CwbvhNode.meta", offset_of!(CwbvhNode, meta)),
        ("CwbvhNode.lo_x", offset_of!(CwbvhNode, lo_x)),
        ("CwbvhNode.hi_x", offset_of!(CwbvhNode, hi_x)),
        ("CwbvhNode.hi_z", offset_of!(CwbvhNode, hi_z)),
    ];
    // The thesis's node is 32 bytes; a triangle is three 16-byte corners.
    assert_eq!(size_of::<Bin32Node>(), 32);
    assert_eq!(size_of::<Triangle>(), 48);
    assert_eq!(size_of::<Hit>(), 8);
    assert_eq!(size_of::<Bin64Node>(), 64);
    assert_eq!((size_of::<Wide4Node>(), size_of::<Wide8Node>()), (128, 256));
    // Five 16-byte rows, read as vectors by the kernel.
    assert_eq!(size_of::<CwbvhNode>(), 80);
    assert_eq!(offset_of!(CwbvhNode, lo_x), 32);

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
