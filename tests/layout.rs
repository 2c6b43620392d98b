//! What the host and the kernels share agrees on both sides: the structs have the same
//! size and field offsets, the constants the same values (`probe.cl` reports both as the
//! device compiler sees them), and every kernel's parameters the names and order the host
//! binds them by. A program is for one scene: a tracer refuses a program of another.

use crate::common;

use std::mem::{offset_of, size_of};
use std::sync::atomic::AtomicBool;

use cltrace::bvh::bin64::Bin64Node;
use cltrace::bvh::cwbvh::CwbvhNode;
use cltrace::bvh::{Bin32Bvh, Bin32Node, BuildOptions, Bvh, DeviceLayout, Layout};
use cltrace::bvh::{wide4::Wide4Node, wide8::Wide8Node};
use cltrace::camera::{Camera, CameraSettings, Projection};
use cltrace::device::tracer::STATUS_STACK_OVERFLOW;
use cltrace::device::{
    ClDevice, ClTracer, Kernel, Kernels, shared_constants, tile_entries_parameters,
};
use cltrace::input::generate::Generator;
use cltrace::intersect::{ROBUST_EXIT, Triangle};

use cltrace::light::punctual;
use cltrace::material::texture::TextureInfo;
use cltrace::material::{Material, Wrap, surface};
use cltrace::render::bsdf;
use cltrace::render::integrator::{
    Accumulation, Lighting, MAX_SAMPLE_RADIANCE, RADIANCE_SCALE, ROULETTE_AFTER, SHADOW_AMBIENT,
    SampleSettings,
};
use cltrace::render::sampling::{DIMS_PER_BOUNCE, LENS_DIM, LENS_TRIES};
use cltrace::render::{Hit, MISS, Shade, ShadeParams};
use ocl::core::{KernelArgInfo, KernelArgInfoResult, KernelInfo, KernelInfoResult};

/// Runs the one-work-item probe kernel `name`, which writes `len` numbers.
fn probe(device: &ClDevice, name: &str, len: usize) -> Vec<u32> {
    let program = device.compile_probe().unwrap();
    let out = ocl::Buffer::<u32>::builder()
        .queue(device.queue.clone())
        .len(len)
        .fill_val(u32::MAX)
        .build()
        .unwrap();
    let kernel = ocl::Kernel::builder()
        .program(&program)
        .name(name)
        .queue(device.queue.clone())
        .global_work_size(1)
        .arg(&out)
        .build()
        .unwrap();
    unsafe { kernel.enq().unwrap() };
    let mut reported = vec![0u32; len];
    out.read(&mut reported).enq().unwrap();
    reported
}

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
        ("Material.base_texture", offset_of!(Material, base_texture)),
        ("Material.emission", offset_of!(Material, emission)),
        (
            "Material.emission_texture",
            offset_of!(Material, emission_texture),
        ),
        ("Material.metallic", offset_of!(Material, metallic)),
        (
            "Material.normal_texture",
            offset_of!(Material, normal_texture),
        ),
        ("Material.normal_scale", offset_of!(Material, normal_scale)),
        (
            "Material.alpha_texture",
            offset_of!(Material, alpha_texture),
        ),
        ("Material.alpha_cutoff", offset_of!(Material, alpha_cutoff)),
        (
            "Material.occlusion_texture",
            offset_of!(Material, occlusion_texture),
        ),
        ("Material.specular", offset_of!(Material, specular)),
        ("Material.bsdf", offset_of!(Material, bsdf)),
        ("Material.eta", offset_of!(Material, eta)),
        ("Material.ior", offset_of!(Material, ior)),
        ("Material.k", offset_of!(Material, k)),
        ("Material.reserved", offset_of!(Material, reserved)),
        ("sizeof(TextureInfo)", size_of::<TextureInfo>()),
        ("TextureInfo.levels", offset_of!(TextureInfo, levels)),
        ("TextureInfo.wrap_v", offset_of!(TextureInfo, wrap_v)),
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
    let reported = probe(&device, "probe_layout", host.len());
    for ((what, expected), got) in host.iter().zip(&reported) {
        assert_eq!(*got as usize, *expected, "{what} on {}", device.info.name);
    }
}

/// Every constant the kernels share with the host is written once, in Rust; the device
/// compiler sees each with the Rust value (floats to the bit).
#[test]
fn device_constants_match_the_rust_constants() {
    let host: Vec<(&str, u32)> = vec![
        ("MISS", MISS),
        ("LEAF_FLAG", cltrace::bvh::LEAF_FLAG),
        ("EMPTY_SLOT", cltrace::bvh::wide::EMPTY_SLOT),
        ("STATUS_STACK_OVERFLOW", STATUS_STACK_OVERFLOW),
        ("SHADE_NORMAL", Shade::Normal.code() as u32),
        ("SHADE_DEPTH", Shade::Depth.code() as u32),
        ("SHADE_LAMBERT", Shade::Lambert.code() as u32),
        ("DIMS_PER_BOUNCE", DIMS_PER_BOUNCE),
        ("LENS_DIM", LENS_DIM),
        ("LENS_TRIES", LENS_TRIES),
        ("SHADOW_AMBIENT", SHADOW_AMBIENT.to_bits()),
        ("ROULETTE_AFTER", ROULETTE_AFTER),
        ("RADIANCE_SCALE", RADIANCE_SCALE.to_bits()),
        ("MAX_SAMPLE_RADIANCE", MAX_SAMPLE_RADIANCE.to_bits()),
        ("ROBUST_EXIT", ROBUST_EXIT.to_bits()),
        ("NO_TEXTURE", cltrace::material::NO_TEXTURE as u32),
        ("WRAP_REPEAT", Wrap::Repeat.code()),
        ("WRAP_CLAMP", Wrap::Clamp.code()),
        ("WRAP_MIRROR", Wrap::Mirror.code()),
        ("SURFACE_NORMALS", surface::SURFACE_NORMALS),
        ("SURFACE_UVS", surface::SURFACE_UVS),
        ("SURFACE_COLORS", surface::SURFACE_COLORS),
        ("TRIANGLE_MASKED", cltrace::intersect::TRIANGLE_MASKED),
        ("TRIANGLE_TWO_SIDED", cltrace::intersect::TRIANGLE_TWO_SIDED),
        ("BOUNCE_CONE_SPREAD", surface::BOUNCE_CONE_SPREAD.to_bits()),
        ("SMOOTH_ROUGHNESS", bsdf::SMOOTH_ROUGHNESS.to_bits()),
        ("BSDF_DIFFUSE", bsdf::BSDF_DIFFUSE),
        ("BSDF_CONDUCTOR", bsdf::BSDF_CONDUCTOR),
        ("BSDF_DIELECTRIC", bsdf::BSDF_DIELECTRIC),
        ("BSDF_THIN_DIELECTRIC", bsdf::BSDF_THIN_DIELECTRIC),
        ("BSDF_PLASTIC", bsdf::BSDF_PLASTIC),
        ("LIGHT_DIRECTIONAL", punctual::LIGHT_DIRECTIONAL),
        ("LIGHT_POINT", punctual::LIGHT_POINT),
        ("LIGHT_SPOT", punctual::LIGHT_SPOT),
    ];
    // The probe reports every constant the host defines for the kernels, none left out.
    let shared: Vec<&str> = shared_constants().iter().map(|c| c.0).collect();
    let probed: Vec<&str> = host.iter().map(|c| c.0).collect();
    assert_eq!(shared, probed);
    // 1 + 3 ulp, and the float nearest 0.1: the values the host reference renders with.
    assert_eq!(ROBUST_EXIT.to_bits(), 0x3F80_0003);
    assert_eq!(SHADOW_AMBIENT.to_bits(), 0x3DCC_CCCD);

    let device = common::device();
    let reported = probe(&device, "probe_constants", host.len());
    for ((name, expected), got) in host.iter().zip(&reported) {
        assert_eq!(
            got, expected,
            "{name} on {}: {got:#x}, host {expected:#x}",
            device.info.name
        );
    }
}

/// The host binds every kernel's parameters by name, in order
/// ([`Kernel::parameters`]); the device compiler's argument info of every kernel of every
/// program (brute force and each layout, with sampling) has the same names in the same
/// order.
#[test]
fn kernel_parameters_match_the_host_bindings() {
    let device = common::device();
    let scenes = std::iter::once(None).chain(Layout::ALL.map(|layout| Some((layout, 8))));
    for bvh in scenes {
        let program = device
            .compile_program(bvh, Kernels::ALL, "-cl-kernel-arg-info")
            .unwrap();
        // A BVH program holds tile_entries beside trace_primary.
        let entries = bvh.map(|_| ("tile_entries", tile_entries_parameters()));
        let kernels = Kernel::ALL.map(|k| (k.name(), k.parameters(bvh.is_some())));
        for (name, parameters) in kernels.into_iter().chain(entries) {
            let k = ocl::core::create_kernel(program.ocl(), name).unwrap();
            let count = match ocl::core::get_kernel_info(&k, KernelInfo::NumArgs).unwrap() {
                KernelInfoResult::NumArgs(n) => n,
                other => panic!("{other:?}"),
            };
            let names: Vec<String> = (0..count)
                .map(|i| {
                    match ocl::core::get_kernel_arg_info(&k, i, KernelArgInfo::Name, None).unwrap()
                    {
                        KernelArgInfoResult::Name(name) => name,
                        other => panic!("{other:?}"),
                    }
                })
                .collect();
            assert_eq!(
                names,
                parameters,
                "{name} of the {:?} program",
                bvh.map(|b| b.0)
            );
        }
    }
}

/// A program knows the scene it was compiled for: a tracer refuses one of another layout
/// or of brute force, and a launch of a kernel the program was compiled without is an
/// error.
#[test]
fn a_tracer_refuses_a_program_compiled_for_another_scene() {
    let mesh = common::generate(Generator::Sphere { subdivisions: 1 });
    let bvh = Bvh::build(&mesh, &BuildOptions::default());
    let sah = bvh.stats().sah_cost;
    let flat = Bin32Bvh::new(bvh, &mesh);
    let triangles = flat.triangles.clone();
    let device = common::device();
    let refused = |r: cltrace::error::Result<ClTracer>| {
        let err = r.err().expect("refused").to_string();
        assert!(err.contains("compiled for"), "{err}");
    };

    let brute = ClTracer::compile_brute(&device).unwrap();
    assert_eq!(brute.layout(), None);
    refused(ClTracer::bvh(&device, &brute, &flat));
    let bin32 = ClTracer::compile_bvh(&device, flat.depth).unwrap();
    assert_eq!(bin32.layout(), Some(Layout::Bin32));
    refused(ClTracer::brute(&device, &bin32, &triangles));
    let laid = DeviceLayout::new(flat.clone(), Layout::Cwbvh, sah);
    refused(ClTracer::with_layout(&device, &bin32, &laid));
    let cwbvh = ClTracer::compile(
        &device,
        Some((Layout::Cwbvh, laid.stack_size)),
        Kernels::TRACING,
    )
    .unwrap();
    refused(ClTracer::bvh(&device, &cwbvh, &flat));

    // The right program is taken, but it has no sampling kernels.
    let mut tracer = ClTracer::with_layout(&device, &cwbvh, &laid).unwrap();
    assert_eq!(tracer.layout(), Some(Layout::Cwbvh));
    let camera = common::auto_camera(&mesh, 8, 8);
    let settings = SampleSettings {
        lighting: Lighting::Path { max_bounces: 1 },
        offset: 1e-4,
        seed: 1,
    };
    let err = tracer
        .render_samples(
            &camera.pinhole(),
            &settings,
            0..1,
            &mut Accumulation::new(8, 8),
            &AtomicBool::new(false),
            &mut |_, _| {},
        )
        .expect_err("refused")
        .to_string();
    assert!(
        err.contains("sample_path kernel is not in this program"),
        "{err}"
    );

    // A program holds the kernels it was compiled with and no others: one of trace_primary
    // alone refuses an orthographic frame, which trace_primary_general traces.
    let primary =
        ClTracer::compile(&device, Some((Layout::Bin32, flat.depth)), Kernels::PRIMARY).unwrap();
    for kernel in Kernel::ALL {
        let made = ocl::core::create_kernel(primary.ocl(), kernel.name()).is_ok();
        assert_eq!(made, kernel == Kernel::TracePrimary, "{}", kernel.name());
    }
    let mut tracer = ClTracer::bvh(&device, &primary, &flat).unwrap();
    let shade = ShadeParams::new(Shade::Normal, &camera, &mesh.bounds());
    assert!(
        tracer
            .render(&camera.pinhole(), 8, 8, &shade, false)
            .is_ok()
    );
    let settings = CameraSettings {
        projection: Some(Projection::Orthographic),
        width: Some(8),
        height: Some(8),
        ..Default::default()
    };
    let ortho = Camera::from_settings(&settings, &mesh.bounds()).unwrap();
    let err = tracer
        .render(&ortho.pinhole(), 8, 8, &shade, false)
        .expect_err("refused")
        .to_string();
    assert!(
        err.contains("trace_primary_general kernel is not in this program"),
        "{err}"
    );
}
