//! The OpenCL C sources in `cl/`, embedded in the binary; the constants the host shares
//! with them; and the assembly and compilation of programs.
//!
//! A program is a list of `cl/` files in order, after a header of `#define`s that the host
//! writes from the Rust constants the kernels share ([`shared_constants`]): the common
//! structs and tests, then the scene (a BVH layout's files, or brute force), then the
//! kernels. Which files a scene needs is decided here, so that no file dispatches on a
//! layout: a layout's file is named as the layout is (`Layout::name`), and refuses to
//! compile without the define [`Layout::define`] its program is built with.

use std::ffi::CString;

use ocl::core::ClDeviceIdPtr;

use super::tracer::Kernels;
use super::{CacheUse, ClDevice, DeviceKind, first_line};
use crate::bvh::Layout;
use crate::error::{Error, Result};
use crate::material::surface::SurfaceFeatures;

/// Reads the kernel sources from this folder instead of the embedded copies (development).
const KERNEL_DIR_VAR: &str = "CLTRACE_KERNEL_DIR";
/// Extra OpenCL build options, appended to cltrace's own (development, e.g. vendor flags).
const BUILD_OPTIONS_VAR: &str = "CLTRACE_BUILD_OPTIONS";
/// The most registers a work-item of a program of sample kernels may use on devices that
/// take NVIDIA's build options. The path tracer asked for 112-137, which leaves too few
/// paths resident to hide memory latency; capped, it spills a little (to cached local
/// memory) and on the H200 ran 1.1-1.2x faster (docs/bench/2026-12-04-gpu-path.md). Of
/// 40 to 128, 64 has been the best over a diffuse box, a conductor and a glass scene
/// since the programs round division loosely: 3-4% ahead of 56 on an H100
/// (docs/bench/2026-12-05-gpu-path-options.md).
const NV_SAMPLE_REGISTERS: u32 = 64;
/// When set, every successful build's log goes to stderr too (development: with
/// `-cl-nv-verbose` NVIDIA's log gives each kernel's registers and spills).
const BUILD_LOG_VAR: &str = "CLTRACE_BUILD_LOG";

/// Every file of `cl/`, embedded: (file name, text).
const FILES: &[(&str, &str)] = &[
    ("common.cl", include_str!("../../cl/common.cl")),
    ("intersect.cl", include_str!("../../cl/intersect.cl")),
    ("camera.cl", include_str!("../../cl/camera.cl")),
    ("texture.cl", include_str!("../../cl/texture.cl")),
    ("surface.cl", include_str!("../../cl/surface.cl")),
    ("nodes.cl", include_str!("../../cl/nodes.cl")),
    ("traverse.cl", include_str!("../../cl/traverse.cl")),
    ("bin32.cl", include_str!("../../cl/bin32.cl")),
    ("bin64.cl", include_str!("../../cl/bin64.cl")),
    ("wide4.cl", include_str!("../../cl/wide4.cl")),
    ("wide8.cl", include_str!("../../cl/wide8.cl")),
    ("wide.cl", include_str!("../../cl/wide.cl")),
    ("cwbvh.cl", include_str!("../../cl/cwbvh.cl")),
    ("brute.cl", include_str!("../../cl/brute.cl")),
    ("sampling.cl", include_str!("../../cl/sampling.cl")),
    ("bsdf.cl", include_str!("../../cl/bsdf.cl")),
    ("environment.cl", include_str!("../../cl/environment.cl")),
    ("punctual.cl", include_str!("../../cl/punctual.cl")),
    ("shade.cl", include_str!("../../cl/shade.cl")),
    ("trace.cl", include_str!("../../cl/trace.cl")),
    ("integrator.cl", include_str!("../../cl/integrator.cl")),
    ("probe.cl", include_str!("../../cl/probe.cl")),
];

/// A constant the kernels share with the host, as Rust holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Constant {
    /// A `uint`.
    U32(u32),
    /// An `int`.
    I32(i32),
    /// A `float`, written exact to the bit.
    F32(f32),
}

impl Constant {
    /// The constant as an OpenCL C literal of the same type and value: `u`-suffixed for
    /// `uint`, a C99 hexadecimal float (exact bits) for `float`.
    pub(crate) fn literal(self) -> String {
        match self {
            Constant::U32(v) if v < 256 => format!("{v}u"),
            Constant::U32(v) => format!("{v:#x}u"),
            Constant::I32(v) if v < 0 => format!("({v})"),
            Constant::I32(v) => v.to_string(),
            Constant::F32(v) => hex_float(v),
        }
    }
}

/// `v` as a C99 hexadecimal float literal with an `f` suffix, exact to the bit.
fn hex_float(v: f32) -> String {
    assert!(v.is_finite(), "{v} has no OpenCL C literal");
    let bits = v.to_bits();
    let sign = if bits >> 31 != 0 { "-" } else { "" };
    let exponent = ((bits >> 23) & 0xFF) as i32;
    // 23 fraction bits, shifted to fill six hexadecimal digits.
    let fraction = (bits & 0x7F_FFFF) << 1;
    match exponent {
        0 if fraction == 0 => format!("{sign}0x0p+0f"),
        0 => format!("{sign}0x0.{fraction:06x}p-126f"),
        e => format!("{sign}0x1.{fraction:06x}p{:+}f", e - 127),
    }
}

/// Every constant the kernels share with the host, by the name the kernels use: written
/// once, in Rust, and defined in front of every program. `tests/layout.rs` has the probe
/// kernel report each as the device compiler sees it.
pub fn shared_constants() -> Vec<(&'static str, Constant)> {
    use crate::material::{Wrap, surface};
    use crate::render::{Shade, bsdf, integrator, sampling};
    use Constant::*;
    vec![
        ("MISS", U32(crate::render::MISS)),
        ("LEAF_FLAG", U32(crate::bvh::LEAF_FLAG)),
        ("EMPTY_SLOT", U32(crate::bvh::wide::EMPTY_SLOT)),
        (
            "STATUS_STACK_OVERFLOW",
            U32(super::tracer::STATUS_STACK_OVERFLOW),
        ),
        ("SHADE_NORMAL", I32(Shade::Normal.code())),
        ("SHADE_DEPTH", I32(Shade::Depth.code())),
        ("SHADE_LAMBERT", I32(Shade::Lambert.code())),
        ("DIMS_PER_BOUNCE", U32(sampling::DIMS_PER_BOUNCE)),
        ("LENS_DIM", U32(sampling::LENS_DIM)),
        ("LENS_TRIES", U32(sampling::LENS_TRIES)),
        ("SHADOW_AMBIENT", F32(integrator::SHADOW_AMBIENT)),
        ("ROULETTE_AFTER", U32(integrator::ROULETTE_AFTER)),
        ("RADIANCE_SCALE", F32(integrator::RADIANCE_SCALE)),
        ("MAX_SAMPLE_RADIANCE", F32(integrator::MAX_SAMPLE_RADIANCE)),
        ("ROBUST_EXIT", F32(crate::intersect::ROBUST_EXIT)),
        ("NO_TEXTURE", I32(crate::material::NO_TEXTURE)),
        ("WRAP_REPEAT", U32(Wrap::Repeat.code())),
        ("WRAP_CLAMP", U32(Wrap::Clamp.code())),
        ("WRAP_MIRROR", U32(Wrap::Mirror.code())),
        ("SURFACE_NORMALS", U32(surface::SURFACE_NORMALS)),
        ("SURFACE_UVS", U32(surface::SURFACE_UVS)),
        ("SURFACE_COLORS", U32(surface::SURFACE_COLORS)),
        ("TRIANGLE_MASKED", U32(crate::intersect::TRIANGLE_MASKED)),
        (
            "TRIANGLE_TWO_SIDED",
            U32(crate::intersect::TRIANGLE_TWO_SIDED),
        ),
        ("BOUNCE_CONE_SPREAD", F32(surface::BOUNCE_CONE_SPREAD)),
        ("SMOOTH_ROUGHNESS", F32(bsdf::SMOOTH_ROUGHNESS)),
        ("BSDF_DIFFUSE", U32(bsdf::BSDF_DIFFUSE)),
        ("BSDF_CONDUCTOR", U32(bsdf::BSDF_CONDUCTOR)),
        ("BSDF_DIELECTRIC", U32(bsdf::BSDF_DIELECTRIC)),
        ("BSDF_THIN_DIELECTRIC", U32(bsdf::BSDF_THIN_DIELECTRIC)),
        ("BSDF_PLASTIC", U32(bsdf::BSDF_PLASTIC)),
        (
            "LIGHT_DIRECTIONAL",
            U32(crate::light::punctual::LIGHT_DIRECTIONAL),
        ),
        ("LIGHT_POINT", U32(crate::light::punctual::LIGHT_POINT)),
        ("LIGHT_SPOT", U32(crate::light::punctual::LIGHT_SPOT)),
    ]
}

/// The header in front of every program: [`shared_constants`] as `#define`s.
fn constants_header() -> String {
    let mut header = String::from(
        "/* The constants the kernels share with the host, written from their Rust \
         definitions (src/device/program.rs, shared_constants). */\n",
    );
    for (name, value) in shared_constants() {
        header.push_str(&format!("#define {name} {}\n", value.literal()));
    }
    header
}

/// The text of `cl/<name>`: the embedded copy or, with `CLTRACE_KERNEL_DIR` set, the file
/// in that folder (for trying kernel changes without rebuilding).
fn file_text(name: &str) -> String {
    match std::env::var_os(KERNEL_DIR_VAR) {
        Some(dir) => {
            std::fs::read_to_string(std::path::Path::new(&dir).join(name)).unwrap_or_else(|e| {
                // An unreadable override must not silently fall back.
                format!("#error \"{KERNEL_DIR_VAR}: cannot read {name}: {e}\"\n")
            })
        }
        None => FILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("cl/{name} is not embedded"))
            .1
            .to_string(),
    }
}

/// The files of `cl/` that trace a BVH in `layout`, in program order: its own file, named
/// as the layout is, and for the wide layouts the traversal they share after it.
fn layout_files(layout: Layout) -> Vec<String> {
    let own = format!("{}.cl", layout.name());
    match layout {
        Layout::Wide4 | Layout::Wide8 => vec![own, "wide.cl".into()],
        Layout::Bin32 | Layout::Bin64 | Layout::Cwbvh => vec![own],
    }
}

/// The defines that compile what a scene's surfaces and lights need into its programs, and
/// leave the rest out (cl/surface.cl, cl/bsdf.cl, cl/integrator.cl).
fn surface_defines(features: SurfaceFeatures, kind: DeviceKind) -> Vec<String> {
    let mut defines = Vec::new();
    let mut define = |on: bool, name: &str| {
        if on {
            defines.push(name.to_string());
        }
    };
    define(features.masks, "ALPHA_MASKS");
    define(features.normals, "SHADING_NORMALS");
    define(features.textures, "TEXTURES");
    define(features.bsdfs(), "BSDFS");
    define(
        features.bsdfs(),
        &format!("BSDF_MODELS={}u", features.models),
    );
    define(features.bsdfs() && features.metallic, "METALLIC");
    define(features.emitters, "EMITTERS");
    define(features.environment, "ENVIRONMENT");
    define(features.punctual, "PUNCTUAL");
    define(features.bsdfs() || features.environment, "MIS");
    // The path loop traces a vertex's one light sample's shadow ray in its own turn
    // rather than inside the vertex (cl/integrator.cl), on SIMD devices in a turn after
    // every vertex, with or without a ray; CPUs skip the empty turns, which cost them 2-4%
    // (docs/bench/2026-12-05-deferred-shadow.md, docs/bench/2026-12-05-gpu-division.md).
    let deferred = features.emitters != features.environment && !features.punctual;
    define(deferred, "DEFERRED_SHADOW");
    define(deferred && kind != DeviceKind::Cpu, "LOCKSTEP_SHADOW");
    defines
}

/// The options a program of `kernels` takes on devices that take NVIDIA's (each followed by
/// a space): programs of sample kernels alone are capped at [`NV_SAMPLE_REGISTERS`], and
/// brute-force (`brute`) programs holding a sample kernel are built unoptimized. Optimized
/// by NVIDIA's compiler (driver 580.159.04, on an H100), the brute-force path program's
/// loop never ended, and once made to end it gave other samples than every layout's
/// program; unoptimized, it gives theirs to the bit. Whether the compiler is at fault or
/// exploits undefined behaviour that no other compiler does is not known: Oclgrind finds
/// none (docs/bench/2026-12-05-nvidia-brute-force.md). Brute force is the reference, not
/// the fast method.
fn nv_options(kernels: Kernels, brute: bool) -> String {
    let mut options = String::new();
    if kernels.only_sampling() {
        options.push_str(&format!("-cl-nv-maxrregcount={NV_SAMPLE_REGISTERS} "));
    }
    // Any program holding a sample kernel, also one with the tracing kernels beside it
    // (the library's Kernels::ALL, as the tests prepare).
    if brute && kernels.has_sampling() {
        options.push_str("-cl-nv-opt-level=0 ");
    }
    options
}

/// The defines every program takes on a device of `kind`: GPUs read the triangle test's
/// vertex coordinates one pick at a time (`AXIS_PICKS`), other devices permute a vertex by
/// two selects. Both give the same numbers; the selects ran 1.11-1.12x faster on Intel's CPU
/// runtime and cost an H200 1-4% (cl/intersect.cl, docs/bench/2026-12-06-axis-selects.md).
fn device_defines(kind: DeviceKind) -> Vec<String> {
    match kind {
        DeviceKind::Gpu => vec!["AXIS_PICKS".into()],
        DeviceKind::Cpu | DeviceKind::Accelerator | DeviceKind::Other => Vec::new(),
    }
}

/// The define with which camera rays' work-groups find their tile's entry node themselves.
const GROUP_ENTRIES: &str = "GROUP_ENTRIES";

/// Whether camera rays in `layout` on a device of `kind` find their tile's entry node in
/// their own work-group, its first work-item walking down while the others wait
/// (`GROUP_ENTRIES`, cl/trace.cl), rather than from a `tile_entries` pass before them. Both
/// give the same hits. On an H100 the work-groups' own walk made the binary layouts' camera
/// rays faster than the pass (`bin64` 5-14%, `bin32` level to 10%), and the wide layouts',
/// whose walks test four or eight boxes a node, level to 11% slower. On CPUs a
/// work-group's work-items run one after another, so the walk delays each of its rays: up
/// to 30% slower (docs/bench/2026-12-07-group-entries.md).
fn groups_find_entries(kind: DeviceKind, layout: Layout) -> bool {
    let binary = matches!(layout, Layout::Bin32 | Layout::Bin64);
    kind == DeviceKind::Gpu && binary
}

/// Whether a program of `kernels` on a device of `kind` asks for correctly rounded division
/// and square root, as the host computes them. Progressive samples are held to the host's
/// within a tolerance, not to the bit (tests/secondary.rs, tests/surfaces.rs), and on GPUs
/// the correctly rounded routines cost the path tracer up to 1.5x of its speed; the
/// tracing kernels keep them, as their hits must equal the host's (and on NVIDIA's GPUs
/// they ran faster with them): docs/bench/2026-12-05-gpu-division.md and
/// 2026-12-05-sample-rounding.md.
fn rounds_exactly(kernels: Kernels, kind: DeviceKind) -> bool {
    !(kernels.only_sampling() && kind == DeviceKind::Gpu)
}

/// Whether a program of `kernels` relaxes its shading's arithmetic (`RELAXED_SHADING`,
/// cl/sampling.cl: fused multiply-adds and the native sine and cosine from the sampling
/// on, the triangle test and traversal untouched), on every device. Only programs of
/// sample kernels, for the same reason as [`rounds_exactly`]: their samples are held to
/// the host's within a tolerance. The path tracer ran 1.11-1.30x as fast on PoCL (2
/// cores) and 1.02-1.08x on an H100, with image means equal to seven digits on PoCL
/// (docs/bench/2026-12-05-gpu-path-options.md).
fn relaxes_shading(kernels: Kernels) -> bool {
    kernels.only_sampling()
}

/// The defines of a program for a BVH in `layout`, with `stack_size` traversal stack
/// entries: the layout's own (its file refuses to compile without it), the stack's size,
/// and for the wide layouts the slots of a node.
fn layout_defines(layout: Layout, stack_size: u32) -> Vec<String> {
    use crate::bvh::wide::WideNode;
    let mut defines = vec![layout.define(), format!("STACK_SIZE={}", stack_size.max(1))];
    let width = match layout {
        Layout::Wide4 => Some(crate::bvh::wide4::Wide4Node::WIDTH),
        Layout::Wide8 => Some(crate::bvh::wide8::Wide8Node::WIDTH),
        Layout::Bin32 | Layout::Bin64 | Layout::Cwbvh => None,
    };
    if let Some(width) = width {
        defines.push(format!("WIDE_WIDTH={width}"));
    }
    defines
}

/// The files of a tracing program in order: for a BVH in `layout` (`None`: brute force),
/// with `sampling` the progressive shade modes too.
fn program_files(layout: Option<Layout>, sampling: bool) -> Vec<String> {
    let mut files: Vec<String> = [
        "common.cl",
        "intersect.cl",
        "camera.cl",
        "texture.cl",
        "surface.cl",
    ]
    .map(String::from)
    .to_vec();
    match layout {
        Some(layout) => {
            files.extend(["nodes.cl", "traverse.cl"].map(String::from));
            files.extend(layout_files(layout));
        }
        None => files.push("brute.cl".into()),
    }
    files.extend(["shade.cl", "trace.cl"].map(String::from));
    if sampling {
        files.extend(
            [
                "sampling.cl",
                "bsdf.cl",
                "environment.cl",
                "punctual.cl",
                "integrator.cl",
            ]
            .map(String::from),
        );
    }
    files
}

/// The files of the probe program: the shared structs, every node struct, the camera and
/// its samples, the probe.
const PROBE_FILES: [&str; 6] = [
    "common.cl",
    "texture.cl",
    "nodes.cl",
    "camera.cl",
    "sampling.cl",
    "probe.cl",
];

/// The source of a program: the constants header, then each file after a `#line` naming
/// it, so that a build log points into the file itself.
fn program_source(files: &[String]) -> String {
    let mut source = constants_header();
    for name in files {
        source.push_str(&format!("#line 1 \"{name}\"\n"));
        source.push_str(&file_text(name));
        source.push('\n');
    }
    source
}

/// Serialises program builds within the process. Intel's OpenCL CPU runtime (2026.2) hung
/// for good, a core busy in its LLVM's `StripDebugInfo`, when two threads of the test
/// binary built programs at once; one build at a time costs a renderer nothing (it builds
/// one program) and the tests little.
fn one_build_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static BUILDS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    BUILDS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Built programs by (build options, source).
pub(crate) type BuiltPrograms = std::collections::HashMap<(String, String), ocl::Program>;

/// A compiled tracing program and what it was compiled for: the BVH layout its kernels
/// traverse (`None`: every triangle), and which kernels it holds. A tracer refuses a
/// program compiled for another scene.
#[derive(Clone, Debug)]
pub struct Program {
    program: ocl::Program,
    layout: Option<Layout>,
    kernels: Kernels,
    features: SurfaceFeatures,
    group_entries: bool,
    cache: Option<CacheUse>,
}

impl Program {
    /// The BVH layout the kernels traverse; `None` for brute force.
    pub fn layout(&self) -> Option<Layout> {
        self.layout
    }

    /// What of a surface the kernels were compiled for.
    pub fn features(&self) -> SurfaceFeatures {
        self.features
    }

    /// The kernels the program holds.
    pub fn kernels(&self) -> Kernels {
        self.kernels
    }

    /// Whether its camera rays' work-groups find their tile's entry node themselves
    /// (`GROUP_ENTRIES`, cl/trace.cl), with no `tile_entries` pass before them.
    pub(crate) fn group_entries(&self) -> bool {
        self.group_entries
    }

    /// The OpenCL program.
    pub fn ocl(&self) -> &ocl::Program {
        &self.program
    }

    /// What the program cache did for it; `None` on a device without one.
    pub fn cache(&self) -> Option<&CacheUse> {
        self.cache.as_ref()
    }
}

impl ClDevice {
    /// Compiles `kernels` against a BVH in `layout` with a traversal stack of `stack_size`
    /// entries or, for `None`, against every triangle. `extra_options` go after cltrace's
    /// own build options (tests: `-cl-kernel-arg-info`).
    pub fn compile_program(
        &self,
        bvh: Option<(Layout, u32)>,
        kernels: Kernels,
        extra_options: &str,
    ) -> Result<Program> {
        self.compile_program_for(bvh, kernels, SurfaceFeatures::default(), extra_options)
    }

    /// [`ClDevice::compile_program`] for a scene whose surface has `features` (cut-out
    /// masks, vertex normals, scattering models).
    pub fn compile_program_for(
        &self,
        bvh: Option<(Layout, u32)>,
        kernels: Kernels,
        features: SurfaceFeatures,
        extra_options: &str,
    ) -> Result<Program> {
        let sampling = kernels.has_sampling();
        let layout = bvh.map(|(layout, _)| layout);
        let mut defines = match bvh {
            Some((layout, stack_size)) => layout_defines(layout, stack_size),
            None => Vec::new(),
        };
        if layout.is_some_and(|layout| groups_find_entries(self.info.kind, layout)) {
            defines.push(GROUP_ENTRIES.into());
        }
        defines.extend(surface_defines(features, self.info.kind));
        defines.extend(device_defines(self.info.kind));
        defines.extend(kernels.defines());
        if relaxes_shading(kernels) {
            defines.push("RELAXED_SHADING".into());
        }
        let label = match layout {
            Some(layout) => format!("{} ({})", kernels.names(), layout.name()),
            None => format!("{} (brute force)", kernels.names()),
        };
        let mut extra = String::new();
        if self.info.nv_compiler_options {
            extra.push_str(&nv_options(kernels, bvh.is_none()));
        }
        extra.push_str(extra_options);
        // Tests ask for the other devices' form through extra_options.
        let group_entries =
            defines.iter().any(|d| d == GROUP_ENTRIES) || extra_options.contains(GROUP_ENTRIES);
        let exact = rounds_exactly(kernels, self.info.kind);
        let options = self.build_options(&defines, extra.trim_end(), exact);
        let source = program_source(&program_files(layout, sampling));
        let Some(cache) = &self.program_cache else {
            let program = self.build_source(&label, &source, &options)?;
            return Ok(Program {
                program,
                layout,
                kernels,
                features,
                group_entries,
                cache: None,
            });
        };
        let entry = cache.entry(&self.info, &options, &source);
        let unusable = match entry.load() {
            Ok(Some(binary)) => match self.build_binary(&binary, &options) {
                Ok(program) => {
                    return Ok(Program {
                        program,
                        layout,
                        kernels,
                        features,
                        group_entries,
                        cache: Some(CacheUse::Hit(entry.path)),
                    });
                }
                Err(why) => Some(why),
            },
            Ok(None) => None,
            Err(why) => Some(why),
        };
        let program = self.build_source(&label, &source, &options)?;
        let stored = self.binary_of(&program).and_then(|b| entry.store(&b));
        let cache = match (stored, unusable) {
            (Err(why), _) => CacheUse::NotStored(why),
            (Ok(()), Some(why)) => CacheUse::Replaced(entry.path, why),
            (Ok(()), None) => CacheUse::Stored(entry.path),
        };
        Ok(Program {
            program,
            layout,
            kernels,
            features,
            group_entries,
            cache: Some(cache),
        })
    }

    /// A program from a binary this device compiled before; `Err` with the reason when
    /// the driver refuses it (a driver update it did not announce, a damaged binary).
    fn build_binary(&self, binary: &[u8], options: &str) -> Result<ocl::Program, String> {
        let _one_at_a_time = one_build_at_a_time();
        // By value: ocl-core passes the slice to OpenCL as an array of `cl_device_id`, so a
        // slice of references would hand it pointers to the wrappers (a driver crash).
        let device: ocl::core::DeviceId = *self.info.device.as_core();
        let program = ocl::core::create_program_with_binary(&self.context, &[device], &[binary])
            .map_err(|e| format!("the driver refused it: {}", first_line(&e.to_string())))?;
        let options = CString::new(options).expect("build options contain no NUL");
        let status = unsafe {
            ocl::core::ffi::clBuildProgram(
                program.as_ptr(),
                1,
                &device.as_ptr(),
                options.as_ptr(),
                None,
                std::ptr::null_mut(),
            )
        };
        crate::interrupt::reclaim_handlers();
        match status {
            0 => Ok(ocl::Program::from(program)),
            status => Err(format!("the driver refused it (OpenCL status {status})")),
        }
    }

    /// The device binary of a built program, to keep in the cache.
    fn binary_of(&self, program: &ocl::Program) -> Result<Vec<u8>, String> {
        match ocl::core::get_program_info(program, ocl::core::ProgramInfo::Binaries) {
            Ok(ocl::core::ProgramInfoResult::Binaries(mut binaries)) if binaries.len() == 1 => {
                let binary = binaries.remove(0);
                match binary.is_empty() {
                    true => Err("the driver gives no binary".into()),
                    false => Ok(binary),
                }
            }
            Ok(_) => Err("the driver gives no binary".into()),
            Err(e) => Err(format!("no binary: {}", first_line(&e.to_string()))),
        }
    }

    /// Compiles `probe.cl`, whose kernels report the shared structs' layout and the shared
    /// constants as this device sees them (tests/layout.rs).
    pub fn compile_probe(&self) -> Result<ocl::Program> {
        let files = PROBE_FILES.map(String::from);
        let options = self.build_options(&[], "", true);
        self.build_source("probe.cl", &program_source(&files), &options)
    }

    /// cltrace's build options with `-D` for each define, then `extra`, then
    /// `CLTRACE_BUILD_OPTIONS`. With `exact` the host and device must round identically,
    /// so division and square root are correctly rounded where the device offers it.
    fn build_options(&self, defines: &[String], extra: &str, exact: bool) -> String {
        let mut options = String::from("-cl-std=CL1.2");
        if exact && self.info.correctly_rounded_divide {
            options.push_str(" -cl-fp32-correctly-rounded-divide-sqrt");
        }
        for define in defines {
            options.push_str(&format!(" -D {define}"));
        }
        if !extra.is_empty() {
            options.push(' ');
            options.push_str(extra);
        }
        if let Ok(extra) = std::env::var(BUILD_OPTIONS_VAR) {
            options.push(' ');
            options.push_str(&extra);
        }
        options
    }

    /// Compiles arbitrary source; `name` labels errors. A failed build reports the device's
    /// build log. The same source with the same options is compiled once per opened device:
    /// not every driver keeps a kernel cache of its own (PoCL does, Intel's CPU runtime does
    /// not, and takes seconds a build), and the tests and `cltrace bench` build the same
    /// program many times.
    pub fn build_source(&self, name: &str, source: &str, options: &str) -> Result<ocl::Program> {
        let key = (options.to_string(), source.to_string());
        if let Some(program) = self.built_programs().get(&key) {
            return Ok(program.clone());
        }
        let program = self.build_uncached(name, source, options)?;
        self.built_programs().insert(key, program.clone());
        Ok(program)
    }

    fn built_programs(&self) -> std::sync::MutexGuard<'_, BuiltPrograms> {
        self.programs.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn build_uncached(&self, name: &str, source: &str, options: &str) -> Result<ocl::Program> {
        let _one_at_a_time = one_build_at_a_time();
        let fail = |e: ocl::core::Error| {
            Error::Device(format!(
                "cannot compile {name} for {}: {}",
                self.info.name,
                first_line(&e.to_string())
            ))
        };
        let source = CString::new(source)
            .map_err(|_| Error::Device(format!("{name} contains a NUL byte")))?;
        let options = CString::new(options).expect("build options contain no NUL");
        let program =
            ocl::core::create_program_with_source(&self.context, &[source]).map_err(fail)?;
        let status = unsafe {
            ocl::core::ffi::clBuildProgram(
                program.as_ptr(),
                1,
                &self.info.device.as_core().as_ptr(),
                options.as_ptr(),
                None,
                std::ptr::null_mut(),
            )
        };
        crate::interrupt::reclaim_handlers();
        let log = || match ocl::core::get_program_build_info(
            &program,
            self.info.device.as_core(),
            ocl::core::ProgramBuildInfo::BuildLog,
        ) {
            Ok(log) => log.to_string(),
            Err(e) => format!("(no build log: {e})"),
        };
        if status != 0 {
            let log = log();
            return Err(Error::Device(format!(
                "kernel {name} failed to build on {} (OpenCL status {status}); build log:\n{}",
                self.info.name,
                log.trim_end()
            )));
        }
        if std::env::var_os(BUILD_LOG_VAR).is_some() {
            crate::report::print_message(&format!(
                "build log of {name} ({options:?}):\n{}",
                log().trim_end()
            ));
        }
        Ok(ocl::Program::from(program))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_a_program_needs_is_embedded_and_every_embedded_file_is_used() {
        let mut used: Vec<String> = PROBE_FILES.map(String::from).to_vec();
        for sampling in [false, true] {
            used.extend(program_files(None, sampling));
            for layout in Layout::ALL {
                used.extend(program_files(Some(layout), sampling));
            }
        }
        for name in &used {
            assert!(FILES.iter().any(|(n, _)| n == name), "{name}");
        }
        for (name, _) in FILES {
            assert!(used.iter().any(|n| n == name), "{name} is in no program");
        }
    }

    /// Each layout's name is one file name and one define, and its file refuses to
    /// compile without that define.
    #[test]
    fn each_layout_has_its_file_and_define() {
        for layout in Layout::ALL {
            let own = format!("{}.cl", layout.name());
            assert_eq!(layout_files(layout)[0], own);
            let define = layout.define();
            let text = file_text(&own);
            assert!(
                text.contains(&format!("#ifndef {define}\n#error")),
                "{own} does not refuse to compile without {define}"
            );
            for (name, text) in FILES {
                if *name != own {
                    assert!(!text.contains(&define), "{name} mentions {define}");
                }
            }
        }
    }

    /// Only programs of sample kernels alone, and only on GPUs, give up correctly rounded
    /// division and square root: every program that traces closest hits keeps them.
    #[test]
    fn only_gpu_sample_programs_round_division_loosely() {
        use super::super::tracer::Kernel;
        let path = Kernels::NONE.with(Kernel::SamplePath);
        let samples = path.with(Kernel::SampleAo).with(Kernel::SampleShadow);
        assert!(!rounds_exactly(path, DeviceKind::Gpu));
        assert!(!rounds_exactly(samples, DeviceKind::Gpu));
        for kind in [DeviceKind::Cpu, DeviceKind::Accelerator, DeviceKind::Other] {
            assert!(rounds_exactly(path, kind), "{kind:?}");
        }
        for kind in [DeviceKind::Gpu, DeviceKind::Cpu] {
            for tracing in [Kernels::PRIMARY, Kernels::TRACING, Kernels::ALL] {
                assert!(rounds_exactly(tracing, kind), "{kind:?}");
            }
        }
    }

    /// On NVIDIA, sample programs are capped in registers, and brute-force programs with a
    /// sample kernel are built unoptimized; tracing programs take neither.
    #[test]
    fn nvidia_builds_brute_force_sample_programs_unoptimized() {
        use super::super::tracer::Kernel;
        let cap = format!("-cl-nv-maxrregcount={NV_SAMPLE_REGISTERS} ");
        for samples in [
            Kernels::NONE.with(Kernel::SamplePath),
            Kernels::NONE
                .with(Kernel::SampleAo)
                .with(Kernel::SampleShadow),
        ] {
            assert_eq!(nv_options(samples, false), cap);
            assert_eq!(
                nv_options(samples, true),
                format!("{cap}-cl-nv-opt-level=0 ")
            );
        }
        for tracing in [Kernels::PRIMARY, Kernels::TRACING] {
            for brute in [false, true] {
                assert_eq!(nv_options(tracing, brute), "");
            }
        }
        // Regression: a program of every kernel (the tests') held the brute-force path
        // kernel optimized, and the GPU's brute-force test still never ended.
        assert_eq!(nv_options(Kernels::ALL, false), "");
        assert_eq!(nv_options(Kernels::ALL, true), "-cl-nv-opt-level=0 ");
    }

    /// Every program of sample kernels alone relaxes its shading, on any device; no program
    /// that traces closest hits does.
    #[test]
    fn only_sample_programs_relax_their_shading() {
        use super::super::tracer::Kernel;
        let path = Kernels::NONE.with(Kernel::SamplePath);
        assert!(relaxes_shading(path));
        assert!(relaxes_shading(
            path.with(Kernel::SampleAo).with(Kernel::SampleShadow)
        ));
        for tracing in [Kernels::PRIMARY, Kernels::TRACING, Kernels::ALL] {
            assert!(!relaxes_shading(tracing));
        }
    }

    /// The path loop defers the shadow ray only where a vertex takes one light sample:
    /// emitters or an environment, not both, and no punctual lights; in lockstep turns on
    /// every device but CPUs.
    #[test]
    fn shadow_rays_are_deferred_where_a_vertex_takes_one_light_sample() {
        let one = |emitters, environment, punctual| SurfaceFeatures {
            emitters,
            environment,
            punctual,
            ..SurfaceFeatures::default()
        };
        for kind in [DeviceKind::Gpu, DeviceKind::Cpu, DeviceKind::Other] {
            let has = |f, name: &str| surface_defines(f, kind).contains(&name.into());
            let deferred = |f| has(f, "DEFERRED_SHADOW");
            assert!(deferred(one(true, false, false)) && deferred(one(false, true, false)));
            assert!(!deferred(one(true, true, false)) && !deferred(one(false, false, false)));
            assert!(!deferred(one(true, false, true)) && !deferred(one(false, true, true)));
            // Every vertex gets its shadow turn on SIMD devices; CPUs skip empty turns.
            for f in [one(true, false, false), one(false, true, false)] {
                assert_eq!(
                    has(f, "LOCKSTEP_SHADOW"),
                    kind != DeviceKind::Cpu,
                    "{kind:?}"
                );
            }
            assert!(!has(one(true, true, false), "LOCKSTEP_SHADOW"));
        }
    }

    /// GPUs' camera rays in the binary layouts find their tile entries in their
    /// work-groups; every other device and layout in a pass of its own.
    #[test]
    fn only_gpus_binary_layouts_find_tile_entries_in_their_work_groups() {
        for layout in Layout::ALL {
            for kind in [DeviceKind::Cpu, DeviceKind::Accelerator, DeviceKind::Other] {
                assert!(!groups_find_entries(kind, layout), "{kind:?} {layout:?}");
            }
            let gpu = groups_find_entries(DeviceKind::Gpu, layout);
            let binary = layout == Layout::Bin32 || layout == Layout::Bin64;
            assert_eq!(gpu, binary, "{layout:?}");
        }
    }

    /// GPUs alone take the triangle test's picks; every other device its selects.
    #[test]
    fn only_gpus_pick_the_triangle_tests_axes() {
        for kind in [
            DeviceKind::Gpu,
            DeviceKind::Cpu,
            DeviceKind::Accelerator,
            DeviceKind::Other,
        ] {
            let picks = device_defines(kind).contains(&"AXIS_PICKS".to_string());
            assert_eq!(picks, kind == DeviceKind::Gpu, "{kind:?}");
        }
    }

    /// The shared constants are defined by the host alone: no kernel file defines one of
    /// its own, and none dispatches on a layout number any more.
    #[test]
    fn no_kernel_file_defines_a_shared_constant() {
        let names: Vec<&str> = shared_constants().iter().map(|c| c.0).collect();
        for (file, text) in FILES {
            for line in text.lines() {
                let Some(rest) = line.trim_start().strip_prefix("#define ") else {
                    continue;
                };
                let defined = rest.split(|c: char| !c.is_ascii_alphanumeric() && c != '_');
                let defined = defined.into_iter().next().unwrap_or("");
                assert!(!names.contains(&defined), "{file} defines {defined}");
            }
            assert!(!text.contains("#if LAYOUT"), "{file} dispatches on LAYOUT");
        }
    }

    #[test]
    fn literals_keep_type_and_bits() {
        assert_eq!(Constant::U32(u32::MAX).literal(), "0xffffffffu");
        assert_eq!(Constant::U32(8).literal(), "8u");
        assert_eq!(Constant::I32(2).literal(), "2");
        assert_eq!(Constant::I32(-3).literal(), "(-3)");
        assert_eq!(Constant::F32(0.1).literal(), "0x1.99999ap-4f");
        assert_eq!(Constant::F32(1.0).literal(), "0x1.000000p+0f");
        assert_eq!(
            Constant::F32(1.0 + 3.0 * f32::EPSILON).literal(),
            "0x1.000006p+0f"
        );
        assert_eq!(Constant::F32(-2.5).literal(), "-0x1.400000p+1f");
        assert_eq!(Constant::F32(0.0).literal(), "0x0p+0f");
        assert_eq!(
            Constant::F32(f32::from_bits(1)).literal(),
            "0x0.000002p-126f"
        );
    }
}
