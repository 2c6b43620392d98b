//! The OpenCL renderer: uploads the scene, launches the tracing kernels over bands of rows
//! (each launch bounded in time, the band height adapted from the launches before), and
//! reads each band back from pitched device images.

use std::time::Instant;

use ocl::enums::ProfilingInfo;
use ocl::prm::{Float2, Float4, Long4};

use super::{ClDevice, DeviceKind, PitchedBuffer, Program};
use crate::bvh::{Bin32Bvh, DeviceLayout, Layout};
use crate::camera::Pinhole;
use crate::error::{Error, Result};
use crate::geometry::Ray;
use crate::intersect::Triangle;
use crate::light::Lights;
use crate::material::Material;
use crate::material::surface::{Surface, SurfaceFeatures};
use crate::material::texture::TextureInfo;
use crate::render::integrator::{Accumulation, Emitters, Light, Lighting, Region, SampleSettings};
use crate::render::{Frame, Hit, ShadeParams};
use crate::report::Progress;

/// Default bound on one kernel launch, in milliseconds of device time.
pub(crate) const LAUNCH_TARGET_MS: f64 = 100.0;

/// The bit a BVH kernel sets in the scene's status flag when a traversal overflowed its
/// stack (`STATUS_STACK_OVERFLOW` in the kernels).
pub const STATUS_STACK_OVERFLOW: u32 = 1;

/// The kernels of a tracing program: `trace_primary`, `trace_primary_general` and
/// `trace_rays` of cl/trace.cl, and the progressive shade modes of cl/integrator.cl.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// `trace_primary`: one primary ray per pixel of a band of rows, hit and colour, from
    /// a perspective camera.
    TracePrimary,
    /// `trace_primary_general`: `trace_primary` for any camera, with barycentrics when
    /// they are asked for (the general code slows PoCL's `trace_primary` even unused).
    TracePrimaryGeneral,
    /// `trace_rays`: a list of arbitrary rays, closest or any hit (the diffuse rays).
    TraceRays,
    /// `sample_ao`: ambient occlusion samples of each pixel of a band.
    SampleAo,
    /// `sample_shadow`: samples of each pixel of a band under one light, with hard shadows.
    SampleShadow,
    /// `sample_path`: path-traced samples of each pixel of a band.
    SamplePath,
}

impl Kernel {
    /// Every kernel, the closest-hit ones first.
    pub const ALL: [Kernel; 6] = [
        Kernel::TracePrimary,
        Kernel::TracePrimaryGeneral,
        Kernel::TraceRays,
        Kernel::SampleAo,
        Kernel::SampleShadow,
        Kernel::SamplePath,
    ];

    /// The kernel's name in its `cl/` file.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::TracePrimary => "trace_primary",
            Kernel::TracePrimaryGeneral => "trace_primary_general",
            Kernel::TraceRays => "trace_rays",
            Kernel::SampleAo => "sample_ao",
            Kernel::SampleShadow => "sample_shadow",
            Kernel::SamplePath => "sample_path",
        }
    }

    /// Whether the kernel is one of the progressive shade modes (cl/integrator.cl).
    pub(crate) fn is_sampling(self) -> bool {
        matches!(
            self,
            Kernel::SampleAo | Kernel::SampleShadow | Kernel::SamplePath
        )
    }

    /// The progressive kernel of a shade mode; `None` for the single-hit modes.
    pub fn sampling(shade: crate::render::Shade) -> Option<Kernel> {
        use crate::render::Shade;
        match shade {
            Shade::Ao => Some(Kernel::SampleAo),
            Shade::Shadow => Some(Kernel::SampleShadow),
            Shade::Path => Some(Kernel::SamplePath),
            _ => None,
        }
    }

    /// The kernel's parameters in order, as the host binds them: the scene's (`bvh`: those
    /// of a BVH program, else those of brute force), then the kernel's own.
    /// tests/layout.rs compares them with the device compiler's.
    pub fn parameters(self, bvh: bool) -> Vec<&'static str> {
        let scene = if bvh {
            [BvhSceneParams::NAMES, SurfaceParams::NAMES].concat()
        } else {
            [BruteSceneParams::NAMES, SurfaceParams::NAMES].concat()
        };
        let own = match self {
            Kernel::TracePrimary | Kernel::TracePrimaryGeneral => {
                [BandParams::NAMES, PrimaryParams::NAMES].concat()
            }
            Kernel::TraceRays => TraceRaysParams::NAMES.to_vec(),
            Kernel::SampleAo | Kernel::SampleShadow | Kernel::SamplePath => {
                [LightParams::NAMES, BandParams::NAMES, SampleParams::NAMES].concat()
            }
        };
        [scene, own].concat()
    }
}

/// The kernels one program holds (each kernel of the `cl/` files is compiled only where its
/// `KERNEL_<NAME>` is defined). A run compiles those it uses: on the H200 a cold compile of
/// every kernel with the dragon's path tracer took 4.2-5.2 s, `trace_primary` and
/// `sample_path` alone 1.8-2.1 s (docs/bench/2026-12-04-first-image.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Kernels(u8);

impl Kernels {
    /// No kernel: what [`Kernels::with`] adds to.
    pub const NONE: Kernels = Kernels(0);
    /// `trace_primary` alone.
    pub const PRIMARY: Kernels = Kernels::NONE.with(Kernel::TracePrimary);
    /// The closest-hit kernels: both primary-ray kernels and `trace_rays`.
    pub const TRACING: Kernels = Kernels::PRIMARY
        .with(Kernel::TracePrimaryGeneral)
        .with(Kernel::TraceRays);
    /// Every kernel.
    pub const ALL: Kernels = Kernels::TRACING
        .with(Kernel::SampleAo)
        .with(Kernel::SampleShadow)
        .with(Kernel::SamplePath);

    /// These and `kernel`.
    pub const fn with(self, kernel: Kernel) -> Kernels {
        Kernels(self.0 | 1 << kernel as u8)
    }

    /// These and `kernel` if there is one.
    pub fn with_some(self, kernel: Option<Kernel>) -> Kernels {
        kernel.map_or(self, |k| self.with(k))
    }

    /// Whether `kernel` is one of these.
    pub fn contains(self, kernel: Kernel) -> bool {
        self.0 & 1 << kernel as u8 != 0
    }

    /// Whether a progressive shade mode's kernel is among these (the program then needs
    /// cl/integrator.cl and the files it uses).
    pub fn has_sampling(self) -> bool {
        self.iter().any(Kernel::is_sampling)
    }

    /// Whether every one of these (at least one) is a progressive shade mode's kernel.
    pub(crate) fn only_sampling(self) -> bool {
        self.has_sampling() && self.iter().all(Kernel::is_sampling)
    }

    /// The kernels, in [`Kernel::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = Kernel> {
        Kernel::ALL.into_iter().filter(move |&k| self.contains(k))
    }

    /// The kernels' names, comma-separated.
    pub(crate) fn names(self) -> String {
        self.iter().map(Kernel::name).collect::<Vec<_>>().join(", ")
    }

    /// The kernels' build defines: `KERNEL_` and the kernel's name in capitals.
    pub(crate) fn defines(self) -> Vec<String> {
        self.iter()
            .map(|k| format!("KERNEL_{}", k.name().to_uppercase()))
            .collect()
    }
}

impl Default for Kernels {
    /// The closest-hit kernels.
    fn default() -> Self {
        Kernels::TRACING
    }
}

/// The parameters of a kernel (or the scene's, which lead every kernel's) as a struct
/// whose fields are named and ordered as the kernel's parameters are: `bind` adds them to a
/// kernel builder under their names, `set` sets them by name on a built kernel.
macro_rules! kernel_params {
    ($(#[$doc:meta])* struct $name:ident { $($field:ident: $ty:ty,)* }) => {
        kernel_params! { @define $(#[$doc])* struct $name[] { $($field: $ty,)* } }
    };
    ($(#[$doc:meta])* struct $name:ident<$a:lifetime> { $($field:ident: $ty:ty,)* }) => {
        kernel_params! { @define $(#[$doc])* struct $name[$a] { $($field: $ty,)* } }
    };
    (@define $(#[$doc:meta])* struct $name:ident[$($a:lifetime)?] { $($field:ident: $ty:ty,)* }) => {
        $(#[$doc])*
        #[derive(Clone, Copy)]
        struct $name$(<$a>)? {
            $($field: $ty,)*
        }

        impl$(<$a>)? $name$(<$a>)? {
            const NAMES: &'static [&'static str] = &[$(stringify!($field)),*];

            fn bind<'b>(&self, builder: &mut ocl::builders::KernelBuilder<'b>)
            $(where
                $a: 'b,)?
            {
                $(builder.arg_named(stringify!($field), self.$field);)*
            }

            // The scene's parameters are bound once and never set again.
            #[allow(dead_code)]
            fn set(&self, kernel: &ocl::Kernel) -> std::result::Result<(), ocl::Error> {
                $(kernel.set_arg(stringify!($field), self.$field)?;)*
                Ok(())
            }
        }
    };
}

kernel_params! {
    /// `SCENE_PARAMS` of a BVH program (cl/bin32.cl and the other layouts' files), before
    /// the surface's.
    struct BvhSceneParams<'a> {
        nodes: &'a ocl::Buffer<u8>,
        tris: &'a ocl::Buffer<Triangle>,
        status: &'a ocl::Buffer<u32>,
    }
}

kernel_params! {
    /// `SCENE_PARAMS` of a brute-force program (cl/brute.cl), before the surface's.
    struct BruteSceneParams<'a> {
        tris: &'a ocl::Buffer<Triangle>,
        tri_count: u32,
    }
}

kernel_params! {
    /// `SURFACE_PARAMS` (cl/surface.cl), the end of every program's `SCENE_PARAMS`.
    struct SurfaceParams<'a> {
        materials: &'a ocl::Buffer<Material>,
        corners: &'a ocl::Buffer<u32>,
        normals: &'a ocl::Buffer<f32>,
        uvs: &'a ocl::Buffer<f32>,
        vertex_colors: &'a ocl::Buffer<f32>,
        textures: &'a ocl::Buffer<TextureInfo>,
        texels: &'a ocl::Buffer<u16>,
        surface_flags: u32,
    }
}

kernel_params! {
    /// `CAMERA_BAND_PARAMS` (cl/camera.cl), which every image kernel takes: the camera
    /// ([`Pinhole`]'s fields: eye, pixel grid, projection and lens), the image width, and
    /// the band of rows `[row0, row_end)` one launch covers (its images' row 0 is image
    /// row `row0`).
    #[derive(Default)]
    struct BandParams {
        eye: Float4,
        p0: Float4,
        du: Float4,
        dv: Float4,
        forward: Float4,
        lens_u: Float4,
        lens_v: Float4,
        width: u32,
        row0: u32,
        row_end: u32,
    }
}

impl BandParams {
    /// The band parameters of `camera` for a `width`-pixel image, before any band is set.
    fn new(camera: &Pinhole, width: u32) -> Self {
        let f4 = |v: [f32; 4]| Float4::new(v[0], v[1], v[2], v[3]);
        BandParams {
            eye: f4(camera.eye),
            p0: f4(camera.p0),
            du: f4(camera.du),
            dv: f4(camera.dv),
            forward: f4(camera.forward),
            lens_u: f4(camera.lens_u),
            lens_v: f4(camera.lens_v),
            width,
            row0: 0,
            row_end: 0,
        }
    }
}

/// A sample kernel ready to launch, with its accumulation images.
struct SampleSetup {
    kernel: ocl::Kernel,
    accum: PitchedBuffer<Long4>,
    rays: ocl::Buffer<u32>,
    band: BandParams,
    values: SampleValues,
    name: &'static str,
}

/// Sums of a region kept on the device between units ([`ClTracer::begin_samples`]).
pub(crate) struct SampleSession {
    setup: SampleSetup,
    width: u32,
    region: Region,
    /// The region's rows whose sums have been cleared, which are the rows a unit touched:
    /// rows are cleared when first touched and only those are read back, so a device that
    /// takes one small unit of a frame pays for that unit, not for the whole frame.
    cleared: Vec<bool>,
}

/// The values of `SampleParams` that stay the same from launch to launch.
#[derive(Clone, Copy)]
struct SampleValues {
    offset: f32,
    seed: u32,
    ao_samples: u32,
    ao_distance: f32,
    light: Float4,
    max_bounces: u32,
    col0: u32,
    col_end: u32,
}

impl SampleValues {
    fn params<'a>(
        &self,
        samples: std::ops::Range<u32>,
        accum: &'a PitchedBuffer<Long4>,
        rays: &'a ocl::Buffer<u32>,
    ) -> SampleParams<'a> {
        SampleParams {
            offset: self.offset,
            seed: self.seed,
            sample: samples.start,
            sample_count: samples.len() as u32,
            ao_samples: self.ao_samples,
            ao_distance: self.ao_distance,
            light: self.light,
            max_bounces: self.max_bounces,
            accum: &accum.buffer,
            rays,
            accum_pitch: accum.pitch as u32,
            col0: self.col0,
            col_end: self.col_end,
        }
    }
}

kernel_params! {
    /// `trace_primary` (cl/trace.cl) after the scene's and the band's parameters.
    #[derive(Default)]
    struct PrimaryParams<'a> {
        shade: i32,
        near: f32,
        far: f32,
        hits: Option<&'a ocl::Buffer<Hit>>,
        hit_pitch: u32,
        colors: Option<&'a ocl::Buffer<u32>>,
        color_pitch: u32,
        barycentrics: Option<&'a ocl::Buffer<Float2>>,
        barycentric_pitch: u32,
        entries: Option<&'a ocl::Buffer<u32>>,
    }
}

kernel_params! {
    /// `tile_entries` (cl/trace.cl) after the scene's and the band's parameters: the
    /// entry node of each work-group of `trace_primary`'s launch over the band.
    #[derive(Default)]
    struct TileEntriesParams<'a> {
        tile_width: u32,
        tile_height: u32,
        tiles_x: u32,
        tiles: u32,
        entries: Option<&'a ocl::Buffer<u32>>,
    }
}

/// The parameters of `tile_entries` (cl/trace.cl), which a BVH program compiles beside
/// `trace_primary`, as the host binds them, as [`Kernel::parameters`] lists a kernel's.
pub fn tile_entries_parameters() -> Vec<&'static str> {
    [
        BvhSceneParams::NAMES,
        SurfaceParams::NAMES,
        BandParams::NAMES,
        TileEntriesParams::NAMES,
    ]
    .concat()
}

kernel_params! {
    /// `trace_rays` (cl/trace.cl) after the scene's parameters.
    struct TraceRaysParams<'a> {
        rays: &'a ocl::Buffer<Float4>,
        count: u32,
        any_hit: i32,
        hits: &'a ocl::Buffer<Hit>,
    }
}

kernel_params! {
    /// `LIGHT_PARAMS` (cl/integrator.cl): the emitting triangles, with the cumulative
    /// distribution of their power; the environment (cl/environment.cl); the punctual
    /// lights (cl/punctual.cl).
    struct LightParams<'a> {
        emitters: &'a ocl::Buffer<u32>,
        emitter_cdf: &'a ocl::Buffer<f32>,
        emitter_count: u32,
        emitter_power: f32,
        env_texels: &'a ocl::Buffer<Float4>,
        env_marginal: &'a ocl::Buffer<f32>,
        env_conditional: &'a ocl::Buffer<f32>,
        env_width: u32,
        env_height: u32,
        env_rotation: Float2,
        punctual: &'a ocl::Buffer<Float4>,
        punctual_count: u32,
    }
}

kernel_params! {
    /// The rest of `SAMPLE_PARAMS` (cl/integrator.cl), after the scene's, the lights' and
    /// the band's: the sample and the shade mode's settings, and the accumulation images.
    struct SampleParams<'a> {
        offset: f32,
        seed: u32,
        sample: u32,
        sample_count: u32,
        ao_samples: u32,
        ao_distance: f32,
        light: Float4,
        max_bounces: u32,
        accum: &'a ocl::Buffer<Long4>,
        rays: &'a ocl::Buffer<u32>,
        accum_pitch: u32,
        col0: u32,
        col_end: u32,
    }
}

/// What one render on the device cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeviceTimes {
    /// Sum of the kernel launches' device time (profiling events).
    pub(crate) kernel_ms: f64,
    /// Host wall time of the rectangular reads.
    pub(crate) read_back_ms: f64,
    /// Kernel launches the render took: one per band of rows, one for a list of rays.
    pub launches: u32,
}

/// The scene on the device: what every kernel's leading `SCENE_PARAMS` receive.
struct Scene {
    /// Every triangle: in file order for brute force, in leaf order under a BVH.
    triangles: ocl::Buffer<Triangle>,
    count: u32,
    bvh: Option<DeviceBvh>,
    surface: DeviceSurface,
}

/// The surface's buffers (`SURFACE_PARAMS`); an empty array of the host's is one zero here,
/// since buffers cannot be empty.
struct DeviceSurface {
    materials: ocl::Buffer<Material>,
    corners: ocl::Buffer<u32>,
    normals: ocl::Buffer<f32>,
    uvs: ocl::Buffer<f32>,
    colors: ocl::Buffer<f32>,
    textures: ocl::Buffer<TextureInfo>,
    texels: ocl::Buffer<u16>,
    flags: u32,
}

impl DeviceSurface {
    fn upload(device: &ClDevice, surface: &Surface) -> Result<Self> {
        fn some<T: Clone + Default>(v: &[T]) -> Vec<T> {
            if v.is_empty() {
                vec![T::default()]
            } else {
                v.to_vec()
            }
        }
        let materials = match surface.materials.is_empty() {
            true => vec![Material::default()],
            false => surface.materials.clone(),
        };
        let doing = "uploading the surface data";
        Ok(DeviceSurface {
            materials: upload(device, &materials, "uploading materials")?,
            corners: upload(device, &some(&surface.corners), doing)?,
            normals: upload(device, &some(&surface.normals), doing)?,
            uvs: upload(device, &some(&surface.uvs), doing)?,
            colors: upload(device, &some(&surface.colors), doing)?,
            textures: upload(device, &some(&surface.textures.infos), "uploading textures")?,
            texels: upload(
                device,
                &some(&surface.textures.texels),
                "uploading textures",
            )?,
            flags: surface.flags,
        })
    }

    fn params(&self) -> SurfaceParams<'_> {
        SurfaceParams {
            materials: &self.materials,
            corners: &self.corners,
            normals: &self.normals,
            uvs: &self.uvs,
            vertex_colors: &self.colors,
            textures: &self.textures,
            texels: &self.texels,
            surface_flags: self.flags,
        }
    }
}

/// The BVH's nodes (in whichever layout the program was compiled for) and the kernels'
/// error flags (bit 0: a stack overflowed).
struct DeviceBvh {
    nodes: ocl::Buffer<u8>,
    status: ocl::Buffer<u32>,
}

/// What the shade modes read besides the scene (`LIGHT_PARAMS` in cl/integrator.cl); an
/// absent light is one zero element, since buffers cannot be empty.
struct DeviceLights {
    emitters: ocl::Buffer<u32>,
    cdf: ocl::Buffer<f32>,
    count: u32,
    power: f32,
    env_texels: ocl::Buffer<Float4>,
    env_marginal: ocl::Buffer<f32>,
    env_conditional: ocl::Buffer<f32>,
    env_size: [u32; 2],
    env_rotation: [f32; 2],
    punctual: ocl::Buffer<Float4>,
    punctual_count: u32,
}

impl DeviceLights {
    fn params(&self) -> LightParams<'_> {
        LightParams {
            emitters: &self.emitters,
            emitter_cdf: &self.cdf,
            emitter_count: self.count,
            emitter_power: self.power,
            env_texels: &self.env_texels,
            env_marginal: &self.env_marginal,
            env_conditional: &self.env_conditional,
            env_width: self.env_size[0],
            env_height: self.env_size[1],
            env_rotation: Float2::new(self.env_rotation[0], self.env_rotation[1]),
            punctual: &self.punctual,
            punctual_count: self.punctual_count,
        }
    }
}

/// The kernels compiled for one device with their scene uploaded, ready to trace.
pub struct ClTracer<'d> {
    device: &'d ClDevice,
    /// The kernels, compiled for this tracer's scene.
    program: Program,
    scene: Scene,
    lights: Option<DeviceLights>,
    /// `trace_primary` and, where the program holds them, `trace_primary_general` and (in a
    /// BVH program) `tile_entries`, bound to the scene.
    primary: [Option<ocl::Kernel>; 3],
    bands: BandPlanner,
    sample_bands: BandPlanner,
    /// The most bytes one output image may take: the device's largest allocation and an
    /// eighth of its memory, or less when set (images larger go band by band).
    image_budget: u64,
    /// Work-group shape of the image kernels (its product for the ray-buffer kernel).
    local: [usize; 2],
}

/// Sizes bands of rows so that each launch takes about [`LAUNCH_TARGET_MS`].
struct BandPlanner {
    /// Pixels per millisecond seen so far.
    rate: Option<f64>,
    /// Pixels of the first band when nothing has been measured yet.
    first_band_pixels: usize,
}

impl BandPlanner {
    fn next_rows(&self, width: usize, remaining: usize) -> usize {
        let pixels = match self.rate {
            Some(rate) => (rate * LAUNCH_TARGET_MS) as usize,
            None => self.first_band_pixels,
        };
        (pixels / width).clamp(1, remaining)
    }

    /// How many of `remaining` samples one launch over `pixels` pixels takes: as many as
    /// fit the target, at least one.
    fn next_samples(&self, pixels: usize, remaining: u32) -> u32 {
        let fit = match self.rate {
            Some(rate) => (rate * LAUNCH_TARGET_MS / pixels.max(1) as f64) as u32,
            None => 1,
        };
        fit.clamp(1, remaining.max(1))
    }

    fn learn(&mut self, pixels: usize, ms: f64) {
        // Launches too short to time say little; never grow more than 8x at a step.
        let measured = pixels as f64 / ms.max(0.01);
        self.rate = Some(match self.rate {
            Some(old) => measured.min(old * 8.0),
            None => measured,
        });
    }
}

impl<'d> ClTracer<'d> {
    /// Compiles the kernels against a plain triangle list (brute force).
    pub fn compile_brute(device: &'d ClDevice) -> Result<Program> {
        Self::compile(device, None, Kernels::TRACING)
    }

    /// Compiles the kernels against a thesis-layout BVH, with a traversal stack as deep as
    /// the tree.
    pub fn compile_bvh(device: &'d ClDevice, depth: u32) -> Result<Program> {
        Self::compile(device, Some((Layout::Bin32, depth)), Kernels::TRACING)
    }

    /// Compiles `kernels` against a BVH in `layout` with a traversal stack of `stack_size`
    /// entries or, for `None`, against every triangle.
    pub fn compile(
        device: &'d ClDevice,
        bvh: Option<(Layout, u32)>,
        kernels: Kernels,
    ) -> Result<Program> {
        device.compile_program(bvh, kernels, "")
    }

    /// [`ClTracer::compile`] for a scene whose surface has `features`.
    pub fn compile_for(
        device: &'d ClDevice,
        bvh: Option<(Layout, u32)>,
        kernels: Kernels,
        features: SurfaceFeatures,
    ) -> Result<Program> {
        device.compile_program_for(bvh, kernels, features, "")
    }

    /// Uploads the triangles (in file order) for the brute-force kernels.
    pub fn brute(device: &'d ClDevice, program: &Program, triangles: &[Triangle]) -> Result<Self> {
        check_program(program, None)?;
        check_scene_memory(device, &[("triangles", size_of_val(triangles) as u64)])?;
        let scene = Scene {
            triangles: upload(device, triangles, "uploading triangles")?,
            count: triangles.len() as u32,
            bvh: None,
            surface: DeviceSurface::upload(device, &Surface::default())?,
        };
        // About 16 million ray/triangle tests in the first launch.
        Self::new(
            device,
            program,
            scene,
            (1usize << 24) / triangles.len().max(1),
        )
    }

    /// Uploads a thesis-layout BVH for kernels compiled with [`ClTracer::compile_bvh`].
    pub fn bvh(device: &'d ClDevice, program: &Program, bvh: &Bin32Bvh) -> Result<Self> {
        check_program(program, Some(Layout::Bin32))?;
        Self::with_nodes(
            device,
            program,
            bytemuck::cast_slice(&bvh.nodes),
            &bvh.triangles,
        )
    }

    /// Uploads a BVH in any layout, for kernels compiled with its layout and stack size.
    pub fn with_layout(
        device: &'d ClDevice,
        program: &Program,
        layout: &DeviceLayout,
    ) -> Result<Self> {
        check_program(program, Some(layout.layout))?;
        Self::with_nodes(device, program, layout.nodes.bytes(), &layout.triangles)
    }

    /// What the program cache did for this tracer's program; `None` without a cache.
    pub fn program_cache(&self) -> Option<&super::CacheUse> {
        self.program.cache()
    }

    /// The BVH's node layout, `None` for brute force.
    pub fn layout(&self) -> Option<Layout> {
        self.program.layout()
    }

    fn with_nodes(
        device: &'d ClDevice,
        program: &Program,
        nodes: &[u8],
        triangles: &[Triangle],
    ) -> Result<Self> {
        check_scene_memory(
            device,
            &[
                ("triangles", size_of_val(triangles) as u64),
                ("BVH nodes", nodes.len() as u64),
            ],
        )?;
        let status = ocl::Buffer::<u32>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_READ_WRITE)
            .len(1)
            .build()
            .map_err(|e| device.error("allocating the status flag", e))?;
        let scene = Scene {
            triangles: upload(device, triangles, "uploading triangles")?,
            count: triangles.len() as u32,
            bvh: Some(DeviceBvh {
                nodes: upload(device, nodes, "uploading BVH nodes")?,
                status,
            }),
            surface: DeviceSurface::upload(device, &Surface::default())?,
        };
        Self::new(device, program, scene, 1 << 16)
    }

    fn new(
        device: &'d ClDevice,
        program: &Program,
        scene: Scene,
        first_band_pixels: usize,
    ) -> Result<Self> {
        let primary = primary_kernels(device, program, &scene)?;
        Ok(ClTracer {
            device,
            program: program.clone(),
            scene,
            lights: None,
            primary,
            bands: BandPlanner {
                rate: None,
                first_band_pixels,
            },
            sample_bands: BandPlanner {
                rate: None,
                first_band_pixels: first_band_pixels / 8,
            },
            image_budget: device
                .info
                .max_allocation
                .min(device.info.global_memory / 8),
            local: default_work_group(device),
        })
    }

    /// The work-group shape (pixels across, down) the kernels launch with.
    pub(crate) fn work_group(&self) -> [usize; 2] {
        self.local
    }

    /// Sets the work-group shape (pixels across, down) of the kernels; `cltrace tune` finds
    /// the best one per device. Shapes the device cannot run are refused.
    pub(crate) fn set_work_group(&mut self, local: [usize; 2]) -> Result<()> {
        let size = local[0] * local[1];
        if size == 0 || size > self.device.info.max_work_group_size {
            return Err(Error::Invalid(format!(
                "work-group {}x{} does not fit {} (at most {} work-items)",
                local[0], local[1], self.device.info.name, self.device.info.max_work_group_size
            )));
        }
        self.local = local;
        Ok(())
    }

    /// Caps the bytes of one output image below what the device allows, so that frames
    /// are rendered and read back in bands of rows that fit (what a device with a small
    /// largest allocation does anyway).
    pub fn limit_image_bytes(&mut self, bytes: u64) {
        self.image_budget = self.image_budget.min(bytes.max(1));
    }

    /// Uploads the emitters (indices into this tracer's triangle order) and the other
    /// lights, which the shade modes need, after checking that the program was compiled
    /// for those lights and that they fit in the device's memory.
    pub(crate) fn set_lights(&mut self, emitters: &Emitters, lights: &Lights) -> Result<()> {
        let device = self.device;
        let has = self.program.features();
        if (lights.environment.is_some() && !has.environment)
            || (!lights.punctual.is_empty() && !has.punctual)
            || (!emitters.is_empty() && !has.emitters)
        {
            return Err(Error::Invalid(format!(
                "the program was compiled for {has:?}, not for this scene's lights"
            )));
        }
        check_scene_memory(device, &[("the lights", lights.bytes())])?;
        // Buffers cannot be empty: a lone zero stands in for "none".
        let (list, cdf) = if emitters.is_empty() {
            (vec![0u32], vec![1.0f32])
        } else {
            (emitters.triangles.clone(), emitters.cdf.clone())
        };
        let f4 = |v: &[f32; 4]| Float4::new(v[0], v[1], v[2], v[3]);
        let doing = "uploading the environment";
        let (env_texels, env_marginal, env_conditional, env_size, env_rotation) =
            match &lights.environment {
                Some(env) => (
                    upload(
                        device,
                        &env.texels.iter().map(f4).collect::<Vec<_>>(),
                        doing,
                    )?,
                    upload(device, &env.marginal, doing)?,
                    upload(device, &env.conditional, doing)?,
                    [env.width, env.height],
                    env.rotation,
                ),
                None => (
                    upload(device, &[Float4::zero()], doing)?,
                    upload(device, &[1.0f32], doing)?,
                    upload(device, &[1.0f32], doing)?,
                    [1, 1],
                    [1.0, 0.0],
                ),
            };
        let mut punctual: Vec<Float4> = lights.packed().iter().flatten().map(f4).collect();
        if punctual.is_empty() {
            punctual.push(Float4::zero());
        }
        self.lights = Some(DeviceLights {
            emitters: upload(device, &list, "uploading emitters")?,
            cdf: upload(device, &cdf, "uploading emitters")?,
            count: emitters.triangles.len() as u32,
            power: emitters.total_power,
            env_texels,
            env_marginal,
            env_conditional,
            env_size,
            env_rotation,
            punctual: upload(device, &punctual, "uploading the punctual lights")?,
            punctual_count: lights.punctual.len() as u32,
        });
        Ok(())
    }

    /// Uploads the surface (materials, vertex data, textures) the kernels shade with,
    /// within the device's memory, after checking that it fits and that the program was
    /// compiled for what the surface has ([`Surface::features`]).
    pub(crate) fn set_surface(&mut self, surface: &Surface) -> Result<()> {
        let device = self.device;
        let (needs, has) = (surface.features(), self.program.features());
        // Textures and scattering models are read by the progressive kernels alone.
        let kernels = self.program.kernels();
        if (needs.masks && !has.masks)
            || (needs.normals && !has.normals)
            || (kernels.has_sampling() && needs.textures && !has.textures)
            || (kernels.contains(Kernel::SamplePath) && !has.holds_models_of(&needs))
        {
            return Err(Error::Invalid(format!(
                "the program was compiled for a surface with {has:?}, this one has {needs:?}"
            )));
        }
        let textures = surface.textures.bytes();
        check_scene_memory(
            device,
            &[
                (
                    "triangles",
                    self.scene.count as u64 * size_of::<Triangle>() as u64,
                ),
                ("surface data", surface.bytes() - textures),
                ("textures", textures),
            ],
        )?;
        self.scene.surface = DeviceSurface::upload(device, surface)?;
        self.primary = primary_kernels(device, &self.program, &self.scene)?;
        Ok(())
    }

    /// Adds the samples `samples` of every pixel of `accumulation`'s region to it, with the kernels of
    /// cl/integrator.cl (the program must have been compiled with sampling). Launches cover bands
    /// of rows, each about `LAUNCH_TARGET_MS` (100 ms); a whole sample of the image is taken before
    /// the next one where the accumulation image fits on the device, so that stopping early
    /// (`stop` set, checked between launches) leaves every pixel with nearly the same number
    /// of samples. `on_sample` is called after each finished sample with the number of
    /// samples done and the rays traced so far, once the first sample's are counted
    /// (estimated from them until the last sample's read-back counts them all).
    #[allow(clippy::too_many_arguments)]
    pub fn render_samples(
        &mut self,
        camera: &Pinhole,
        settings: &SampleSettings,
        samples: std::ops::Range<u32>,
        accumulation: &mut Accumulation,
        stop: &std::sync::atomic::AtomicBool,
        on_sample: &mut dyn FnMut(u32, Option<u64>),
    ) -> Result<DeviceTimes> {
        use std::sync::atomic::Ordering;
        let device = self.device;
        let (width, region) = (accumulation.width, accumulation.region);
        let (w, h) = (region.width() as usize, region.height() as usize);
        let (x0, y0) = (region.x0 as usize, region.y0 as usize);
        // 32 bytes of radiance sums and 4 of ray count a pixel.
        let capacity = capacity::<Long4>(device, self.image_budget, w, h);
        let SampleSetup {
            kernel,
            accum,
            rays,
            mut band,
            values,
            name,
        } = self.sample_setup(camera, settings, width, region, capacity)?;
        let pitch = accum.pitch;
        let mut params = values.params(0..1, &accum, &rays);
        let set = |band: &BandParams, params: &SampleParams| {
            band.set(&kernel)
                .and_then(|()| params.set(&kernel))
                .map_err(|e| device.error(&format!("setting the arguments of {name}"), e))
        };

        self.scene.clear_status(device)?;
        let local = self.local;
        let mut times = DeviceTimes::default();
        // The host's copy of the ray counts: the first sample's (FirstCounts), then each
        // group's, read back with its sums.
        let mut counts: Vec<u32> = Vec::new();
        let mut first_counts: Option<FirstCounts> = None;
        let counts_error = |e| device.error("reading the ray counts back", e);
        // The host's side of the read-back, made ready on other cores while the launches
        // after the first sample wait on the device (ReadBack).
        let background = device.info.kind != DeviceKind::Cpu;
        let mut read_back: Option<ReadBack> = None;
        let outcome = (|| {
            let mut group0 = 0usize;
            'groups: while group0 < h {
                let group_rows = capacity.min(h - group0);
                clear_rows(device, &accum, &rays, 0..accum.height)?;
                // The accumulation image's row 0 is the group's first row; bands run inside it.
                band.row0 = (y0 + group0) as u32;
                let mut stopped = false;
                let mut rays_per_sample = None;
                let mut done = 0;
                'samples: while done < samples.len() as u32 {
                    // Where one sample of the group takes less than a launch's target, a launch
                    // takes several: fewer launches, and the kernel's work-items start their
                    // next path as soon as one ends. The first takes one, to count its rays.
                    let whole = self.sample_bands.next_rows(w, group_rows) == group_rows;
                    let take = match done > 0 && whole {
                        true => self
                            .sample_bands
                            .next_samples(w * group_rows, samples.len() as u32 - done),
                        false => 1,
                    };
                    let first = samples.start + done;
                    params.sample = first;
                    params.sample_count = take;
                    let mut row = group0;
                    while row < group0 + group_rows {
                        let rows = self.sample_bands.next_rows(w, group0 + group_rows - row);
                        band.row_end = (y0 + row + rows) as u32;
                        set(&band, &params)?;
                        let ms = launch_rect(device, &kernel, local, [x0, y0 + row], [w, rows])?;
                        times.kernel_ms += ms;
                        times.launches += 1;
                        self.sample_bands.learn(rows * w * take as usize, ms);
                        row += rows;
                        if stop.load(Ordering::Relaxed) {
                            stopped = true;
                            break 'samples;
                        }
                    }
                    if group_rows == h {
                        if rays_per_sample.is_none() {
                            first_counts = match first_counts.take() {
                                None if done == 0 => Some(
                                    FirstCounts::start(device, &rays, pitch * group_rows)
                                        .map_err(counts_error)?,
                                ),
                                Some(first) if first.is_finished() => {
                                    let (read, n) = first.finish().map_err(counts_error)?;
                                    counts = read;
                                    rays_per_sample = Some(n);
                                    None
                                }
                                pending => pending,
                            };
                        }
                        on_sample(
                            done + take,
                            rays_per_sample.map(|n| n * (done + take) as u64),
                        );
                    }
                    if read_back.is_none() {
                        read_back = Some(ReadBack::prepare(
                            &mut accumulation.pixels,
                            w * capacity,
                            background,
                        ));
                    }
                    done += take;
                }
                let start = Instant::now();
                let host = read_back
                    .get_or_insert_with(|| {
                        ReadBack::prepare(&mut accumulation.pixels, w * capacity, false)
                    })
                    .ready(&mut accumulation.pixels);
                accum.read_rows(device, group_rows, host)?;
                if let Some(first) = first_counts.take() {
                    // Its buffer is the one to read into.
                    counts = first.finish().map_err(counts_error)?.0;
                }
                if counts.len() < pitch * group_rows {
                    counts = filled(0u32, pitch * capacity);
                }
                rays.read(&mut counts[..pitch * group_rows])
                    .enq()
                    .map_err(counts_error)?;
                times.read_back_ms += start.elapsed().as_secs_f64() * 1e3;
                // On every core: a 4K frame's sums are 265 MB.
                use rayon::prelude::*;
                accumulation.pixels[group0 * w..(group0 + group_rows) * w]
                    .par_chunks_mut(w)
                    .zip(host.par_chunks(w))
                    .for_each(|(out, sums)| {
                        for (o, v) in out.iter_mut().zip(sums) {
                            for c in 0..4 {
                                o[c] += v[c];
                            }
                        }
                    });
                let group_rays = (0..group_rows)
                    .into_par_iter()
                    .map(|y| row_sums(&counts, pitch, w, y..y + 1))
                    .sum::<u64>();
                accumulation.rays += group_rays;
                if group_rows == h {
                    on_sample(done, Some(group_rays));
                }
                self.scene.check_status(device)?;
                group0 += group_rows;
                if stopped {
                    break 'groups;
                }
            }
            Ok(times)
        })();
        // An error before the first read-back leaves the accumulation its sums.
        if let Some(read_back) = read_back.as_mut() {
            read_back.ready(&mut accumulation.pixels);
        }
        outcome
    }

    /// The sample kernel of `settings`' mode, created with its arguments bound, and an
    /// accumulation image of `rows` rows for `region` of an image `width` pixels wide.
    fn sample_setup(
        &mut self,
        camera: &Pinhole,
        settings: &SampleSettings,
        width: u32,
        region: Region,
        rows: usize,
    ) -> Result<SampleSetup> {
        let device = self.device;
        let w = region.width() as usize;
        let kernel = match settings.lighting {
            Lighting::Ao { .. } => Kernel::SampleAo,
            Lighting::Shadow { .. } => Kernel::SampleShadow,
            Lighting::Path { .. } => Kernel::SamplePath,
        };
        require_kernel(&self.program, kernel)?;
        let name = kernel.name();
        if self.lights.is_none() {
            self.set_lights(&Emitters::default(), &Lights::default())?;
        }
        let lights = self.lights.as_ref().expect("set above");
        let accum = PitchedBuffer::<Long4>::read_write(device, w, rows)?;
        let rays = ocl::Buffer::<u32>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_READ_WRITE)
            .len(accum.pitch * rows)
            .build()
            .map_err(|e| device.error("allocating the ray counts", e))?;
        let (ao_samples, ao_distance, light, max_bounces) = match settings.lighting {
            Lighting::Ao { samples, distance } => (samples, distance, Float4::zero(), 0),
            Lighting::Shadow { light } => {
                let l = match light {
                    Light::Directional(d) => Float4::new(d.x, d.y, d.z, 0.0),
                    Light::Point(p) => Float4::new(p.x, p.y, p.z, 1.0),
                };
                (0, 0.0, l, 0)
            }
            Lighting::Path { max_bounces } => (0, 0.0, Float4::zero(), max_bounces),
        };
        let values = SampleValues {
            offset: settings.offset,
            seed: settings.seed,
            ao_samples,
            ao_distance,
            light,
            max_bounces,
            col0: region.x0,
            col_end: region.x1,
        };
        let light_params = lights.params();
        // The band (row0, row_end) and the sample change from launch to launch.
        let band = BandParams::new(camera, width);
        let mut builder = kernel_builder(device, &self.program, kernel, &self.scene)?;
        light_params.bind(&mut builder);
        band.bind(&mut builder);
        values.params(0..1, &accum, &rays).bind(&mut builder);
        let kernel = builder
            .build()
            .map_err(|e| device.error(&format!("creating the {name} kernel"), e))?;
        Ok(SampleSetup {
            kernel,
            accum,
            rays,
            band,
            values,
            name,
        })
    }

    /// Starts sums of `region` (of an image `width` pixels wide) that stay on the device
    /// while [`ClTracer::add_samples`] adds units of rows and samples to them, read back once
    /// by [`ClTracer::finish_samples`]: how one device of several takes its share of a
    /// frame. `None` where the region's sums do not fit in one device image.
    pub(crate) fn begin_samples(
        &mut self,
        camera: &Pinhole,
        settings: &SampleSettings,
        width: u32,
        region: Region,
    ) -> Result<Option<SampleSession>> {
        let (w, h) = (region.width() as usize, region.height() as usize);
        if capacity::<Long4>(self.device, self.image_budget, w, h) < h {
            return Ok(None);
        }
        let mut setup = self.sample_setup(camera, settings, width, region, h)?;
        // The accumulation image's row 0 is the region's first row.
        setup.band.row0 = region.y0;
        self.scene.clear_status(self.device)?;
        Ok(Some(SampleSession {
            setup,
            width,
            region,
            cleared: vec![false; h],
        }))
    }

    /// Adds the samples `samples` of the rows `rows` (image rows inside the session's
    /// region) to the session's sums; `stop` is checked after each launch. Returns the
    /// kernels' device time, ms.
    pub(crate) fn add_samples(
        &mut self,
        session: &mut SampleSession,
        rows: std::ops::Range<u32>,
        samples: std::ops::Range<u32>,
        stop: &std::sync::atomic::AtomicBool,
    ) -> Result<f64> {
        let device = self.device;
        let y0 = session.region.y0;
        // Clear the runs of rows not touched before.
        let mut row = rows.start;
        while row < rows.end {
            let first = (row - y0) as usize;
            let run = session.cleared[first..(rows.end - y0) as usize]
                .iter()
                .take_while(|&&c| c == session.cleared[first])
                .count();
            if !session.cleared[first] {
                clear_rows(
                    device,
                    &session.setup.accum,
                    &session.setup.rays,
                    first..first + run,
                )?;
                session.cleared[first..first + run].fill(true);
            }
            row += run as u32;
        }
        let SampleSetup {
            kernel,
            accum,
            rays,
            band,
            values,
            name,
        } = &mut session.setup;
        let x0 = session.region.x0 as usize;
        let w = session.region.width() as usize;
        band.row_end = rows.end;
        // Launches are queued one ahead of the one waited for, so that the device never
        // idles while the host (perhaps slowed by a busy CPU device beside it) comes back
        // to queue the next: arguments set after a launch is queued do not change it.
        // A launch takes as many samples as fit its target (`render_samples`).
        let mut in_flight = std::collections::VecDeque::new();
        let mut ms = 0.0;
        let pixels = w * rows.len();
        let mut next = samples.start;
        while next < samples.end {
            let take = self.sample_bands.next_samples(pixels, samples.end - next);
            band.set(kernel)
                .and_then(|()| values.params(next..next + take, accum, rays).set(kernel))
                .map_err(|e| device.error(&format!("setting the arguments of {name}"), e))?;
            next += take;
            let origin = [x0, rows.start as usize];
            let event = queue_rect(device, kernel, self.local, origin, [w, rows.len()])?;
            in_flight.push_back((event, pixels * take as usize));
            if in_flight.len() > 1 {
                let (event, work) = in_flight.pop_front().expect("two in flight");
                let launch_ms = wait_ms(device, &event)?;
                self.sample_bands.learn(work, launch_ms);
                ms += launch_ms;
                if stop.load(std::sync::atomic::Ordering::Relaxed) {
                    break;
                }
            }
        }
        for (event, work) in in_flight {
            let launch_ms = wait_ms(device, &event)?;
            self.sample_bands.learn(work, launch_ms);
            ms += launch_ms;
        }
        Ok(ms)
    }

    /// The session's sums of the rows its units touched, read back, and its rays; `None`
    /// when it took no unit.
    pub(crate) fn finish_samples(
        &mut self,
        session: SampleSession,
    ) -> Result<Option<Accumulation>> {
        let device = self.device;
        let cleared = &session.cleared;
        let (Some(first), Some(last)) = (
            cleared.iter().position(|&c| c),
            cleared.iter().rposition(|&c| c),
        ) else {
            return Ok(None);
        };
        let w = session.region.width() as usize;
        let h = last + 1 - first;
        let setup = &session.setup;
        let pitch = setup.accum.pitch;
        let region = Region {
            y0: session.region.y0 + first as u32,
            y1: session.region.y0 + last as u32 + 1,
            ..session.region
        };
        let mut acc = Accumulation::of_region(session.width, region.y1, region);
        // Straight into the accumulation: no copy of hundreds of megabytes on the host. Its
        // pages are touched first on every core: a driver's copy would fault them in one
        // by one.
        {
            use rayon::prelude::*;
            acc.pixels
                .par_chunks_mut(1 << 14)
                .for_each(|c| c.fill([0; 4]));
        }
        setup
            .accum
            .read_row_range(device, first..last + 1, long4s(&mut acc.pixels))?;
        let mut counts = vec![0u32; pitch * h];
        setup
            .rays
            .cmd()
            .read(&mut counts)
            .offset(pitch * first)
            .enq()
            .map_err(|e| device.error("reading the ray counts back", e))?;
        self.scene.check_status(device)?;
        // Rows between touched ones that no unit touched were never cleared: they add nothing.
        for (y, out) in acc.pixels.chunks_mut(w).enumerate() {
            match cleared[first + y] {
                true => acc.rays += row_sums(&counts, pitch, w, y..y + 1),
                false => out.fill([0; 4]),
            }
        }
        Ok(Some(acc))
    }

    /// Renders one frame. `progress` shows a bar on stderr when the render looks long.
    pub fn render(
        &mut self,
        camera: &Pinhole,
        width: u32,
        height: u32,
        shade: &ShadeParams,
        progress: bool,
    ) -> Result<(Frame, DeviceTimes)> {
        let device = self.device;
        let (w, h) = (width as usize, height as usize);
        let band_capacity = capacity::<Hit>(device, self.image_budget, w, h);
        let hits = PitchedBuffer::<Hit>::new(device, w, band_capacity)?;
        let colors = match shade.colors {
            true => Some(PitchedBuffer::<u32>::new(device, w, band_capacity)?),
            false => None,
        };
        let barycentrics = match shade.barycentrics {
            true => Some(PitchedBuffer::<Float2>::new(device, w, band_capacity)?),
            false => None,
        };

        let general = shade.barycentrics || camera.is_orthographic();
        let (kernel, k) = match general {
            false => (Kernel::TracePrimary, &self.primary[0]),
            true => (Kernel::TracePrimaryGeneral, &self.primary[1]),
        };
        require_kernel(&self.program, kernel)?;
        let k = k.as_ref().expect("the program's primary kernels are built");
        // The band (row0, row_end) changes from launch to launch.
        let mut band = BandParams::new(camera, width);
        let local = self.local;
        // Perspective camera rays start from their tile's entry node (cl/trace.cl), found by
        // a pass of its own unless their work-groups find it themselves.
        let pass = !general && !self.program.group_entries();
        let entries = match self.primary[2].as_ref().filter(|_| pass) {
            Some(kernel) => {
                let tiles = self.tiles(w, band_capacity).1;
                Some((kernel, entries_buffer(device, tiles)?))
            }
            None => None,
        };
        let params = PrimaryParams {
            entries: entries.as_ref().map(|(_, buffer)| buffer),
            shade: shade.shade.code(),
            near: shade.near,
            far: shade.far,
            hits: Some(&hits.buffer),
            hit_pitch: hits.pitch as u32,
            colors: colors.as_ref().map(|c| &c.buffer),
            color_pitch: colors.as_ref().map_or(0, |c| c.pitch as u32),
            barycentrics: barycentrics.as_ref().map(|b| &b.buffer),
            barycentric_pitch: barycentrics.as_ref().map_or(0, |b| b.pitch as u32),
        };
        self.scene.clear_status(device)?;

        let mut frame = Frame::new(width, height);
        let mut bary = vec![Float2::zero(); if barycentrics.is_some() { w * h } else { 0 }];
        let mut times = DeviceTimes::default();
        let mut bar: Option<Progress> = None;
        let mut y0 = 0usize;
        while y0 < h {
            // Interrupted, the frame would miss rows: stop at this band, with the error.
            crate::interrupt::check()?;
            let rows = self.bands.next_rows(w, h - y0).min(band_capacity);
            // Work-items past the band (the global size is rounded up) return at once.
            band.row0 = y0 as u32;
            band.row_end = (y0 + rows) as u32;
            band.set(k).and_then(|()| params.set(k)).map_err(|e| {
                device.error(&format!("setting the arguments of {}", kernel.name()), e)
            })?;
            let entries_done = match &entries {
                Some((kernel, buffer)) => {
                    Some(self.queue_tile_entries(kernel, &band, buffer, w, rows)?)
                }
                None => None,
            };
            // Both count as the frame's kernel time.
            let mut ms = launch_rows(device, k, local, w, y0, rows)?;
            if let Some(done) = &entries_done {
                ms += wait_ms(device, done)?;
            }
            times.kernel_ms += ms;
            times.launches += 1;
            self.bands.learn(rows * w, ms);

            let start = Instant::now();
            hits.read_rows(device, rows, &mut frame.hits[y0 * w..])?;
            if let Some(c) = &colors {
                c.read_rows(device, rows, &mut frame.colors[y0 * w..])?;
            }
            if let Some(b) = &barycentrics {
                b.read_rows(device, rows, &mut bary[y0 * w..])?;
            }
            times.read_back_ms += start.elapsed().as_secs_f64() * 1e3;

            y0 += rows;
            if progress && bar.is_none() && y0 < h {
                // Show a bar only when the remaining work looks longer than a second.
                let remaining_ms =
                    (h - y0) as f64 * w as f64 / self.bands.rate.unwrap_or(f64::INFINITY);
                if remaining_ms > 1000.0 {
                    let what = format!("tracing on {}", device.info.name);
                    bar = Some(Progress::new(true, what, h as u64, "rows"));
                }
            }
            if let Some(b) = &bar {
                b.set_position(y0 as u64);
            }
        }
        if let Some(b) = bar {
            b.finish();
        }
        self.scene.check_status(device)?;
        frame.barycentrics = bary.iter().map(|b| [b[0], b[1]]).collect();
        Ok((frame, times))
    }

    /// The work-groups of an image kernel's launch over `rows` rows of a `width`-pixel
    /// image (the tiles `tile_entries` finds an entry node for): per row, and in all.
    fn tiles(&self, width: usize, rows: usize) -> (usize, usize) {
        let tiles_x = width.div_ceil(self.local[0]);
        (tiles_x, tiles_x * rows.div_ceil(self.local[1]))
    }

    /// Enqueues `tile_entries` over the band `band` sets, `rows` rows of a `width`-pixel
    /// image: the entry node of each work-group of `trace_primary` there, into `entries`.
    fn queue_tile_entries(
        &self,
        kernel: &ocl::Kernel,
        band: &BandParams,
        entries: &ocl::Buffer<u32>,
        width: usize,
        rows: usize,
    ) -> Result<ocl::Event> {
        let (device, local) = (self.device, self.local);
        let (tiles_x, tiles) = self.tiles(width, rows);
        let params = TileEntriesParams {
            tile_width: local[0] as u32,
            tile_height: local[1] as u32,
            tiles_x: tiles_x as u32,
            tiles: tiles as u32,
            entries: Some(entries),
        };
        band.set(kernel)
            .and_then(|()| params.set(kernel))
            .map_err(|e| device.error("setting the arguments of tile_entries", e))?;
        let group = local[0] * local[1];
        let cmd = kernel
            .cmd()
            .global_work_size(tiles.div_ceil(group) * group)
            .local_work_size(group);
        queue_kernel(device, cmd)
    }

    /// The node of the BVH each work-group of a perspective camera's primary rays starts
    /// from, work-groups in row-major order over the whole image (as one band):
    /// [`crate::render::MISS`] where none of its rays can hit anything.
    /// `None` for brute force or a program without `trace_primary`. For tests and tools:
    /// [`ClTracer::render`] finds them itself.
    pub fn tile_entries(
        &mut self,
        camera: &Pinhole,
        width: u32,
        height: u32,
    ) -> Result<Option<Vec<u32>>> {
        let device = self.device;
        let Some(kernel) = &self.primary[2] else {
            return Ok(None);
        };
        let mut band = BandParams::new(camera, width);
        band.row_end = height;
        let (w, h) = (width as usize, height as usize);
        let tiles = self.tiles(w, h).1;
        let entries = entries_buffer(device, tiles)?;
        wait_ms(
            device,
            &self.queue_tile_entries(kernel, &band, &entries, w, h)?,
        )?;
        let mut out = vec![0u32; tiles];
        entries
            .read(&mut out)
            .enq()
            .map_err(|e| device.error("reading the tile entries back", e))?;
        Ok(Some(out))
    }

    /// Traces arbitrary rays: the closest hit of each in `(0, t_max)`, or with `any_hit`
    /// any hit there. Hits name triangles in file order; `t` is the distance along the ray.
    pub fn trace_rays(&mut self, rays: &[Ray], t_max: f32, any_hit: bool) -> Result<Vec<Hit>> {
        Ok(self.trace_rays_timed(rays, t_max, any_hit)?.0)
    }

    /// [`ClTracer::trace_rays`] with the kernel's device time and the read-back's wall time
    /// (the upload of the rays is in neither).
    pub(crate) fn trace_rays_timed(
        &mut self,
        rays: &[Ray],
        t_max: f32,
        any_hit: bool,
    ) -> Result<(Vec<Hit>, DeviceTimes)> {
        let device = self.device;
        if rays.is_empty() {
            return Ok((Vec::new(), DeviceTimes::default()));
        }
        let packed: Vec<Float4> = rays
            .iter()
            .flat_map(|r| {
                [
                    Float4::new(r.origin.x, r.origin.y, r.origin.z, t_max),
                    Float4::new(r.dir.x, r.dir.y, r.dir.z, 0.0),
                ]
            })
            .collect();
        let input = upload(device, &packed, "uploading rays")?;
        let output = ocl::Buffer::<Hit>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_WRITE_ONLY)
            .len(rays.len())
            .build()
            .map_err(|e| device.error("allocating the hit buffer", e))?;
        let kernel = Kernel::TraceRays;
        let params = TraceRaysParams {
            rays: &input,
            count: rays.len() as u32,
            any_hit: any_hit as i32,
            hits: &output,
        };
        let mut builder = kernel_builder(device, &self.program, kernel, &self.scene)?;
        params.bind(&mut builder);
        let local = self.local[0] * self.local[1];
        builder
            .global_work_size(rays.len().div_ceil(local) * local)
            .local_work_size(local);
        let kernel = builder
            .build()
            .map_err(|e| device.error(&format!("creating the {} kernel", kernel.name()), e))?;
        self.scene.clear_status(device)?;
        let kernel_ms = launch(device, kernel.cmd())?;
        let start = Instant::now();
        let mut hits = vec![Hit::NONE; rays.len()];
        output
            .read(&mut hits)
            .enq()
            .map_err(|e| device.error("reading hits back", e))?;
        let times = DeviceTimes {
            kernel_ms,
            read_back_ms: start.elapsed().as_secs_f64() * 1e3,
            launches: 1,
        };
        self.scene.check_status(device)?;
        Ok((hits, times))
    }
}

impl Scene {
    fn clear_status(&self, device: &ClDevice) -> Result<()> {
        if let Some(DeviceBvh { status, .. }) = &self.bvh {
            status
                .write(&[0u32][..])
                .enq()
                .map_err(|e| device.error("clearing the status flag", e))?;
        }
        Ok(())
    }

    /// Refuses the result of kernels that raised an error flag.
    fn check_status(&self, device: &ClDevice) -> Result<()> {
        if let Some(DeviceBvh { status, .. }) = &self.bvh {
            let mut flags = [0u32];
            status
                .read(&mut flags[..])
                .enq()
                .map_err(|e| device.error("reading the kernel's status", e))?;
            if flags[0] != 0 {
                return Err(Error::Device(format!(
                    "the BVH kernel on {} overflowed its traversal stack (status {:#x}): the image would be wrong, so none was written",
                    device.info.name, flags[0]
                )));
            }
        }
        Ok(())
    }
}

/// Refuses a program compiled for another scene than the tracer's: a BVH in `layout`, or
/// for `None` every triangle.
fn check_program(program: &Program, layout: Option<Layout>) -> Result<()> {
    if program.layout() == layout {
        return Ok(());
    }
    let scene = |layout: Option<Layout>| match layout {
        Some(layout) => format!("a BVH in the {} layout", layout.name()),
        None => "brute force".to_string(),
    };
    Err(Error::Invalid(format!(
        "the kernels were compiled for {}, but the tracer is for {}",
        scene(program.layout()),
        scene(layout)
    )))
}

/// Refuses a kernel the program was compiled without.
fn require_kernel(program: &Program, kernel: Kernel) -> Result<()> {
    if !program.kernels().contains(kernel) {
        return Err(Error::Invalid(format!(
            "the {} kernel is not in this program: it was compiled with {} only",
            kernel.name(),
            program.kernels().names()
        )));
    }
    Ok(())
}

/// `trace_primary` and `trace_primary_general` for `scene` where the program holds them, and
/// with the first in a BVH program `tile_entries`, the frame's values to be set by
/// [`ClTracer::render`].
fn primary_kernels(
    device: &ClDevice,
    program: &Program,
    scene: &Scene,
) -> Result<[Option<ocl::Kernel>; 3]> {
    let build = |kernel: Kernel| {
        if !program.kernels().contains(kernel) {
            return Ok(None);
        }
        let mut builder = kernel_builder(device, program, kernel, scene)?;
        BandParams::default().bind(&mut builder);
        PrimaryParams::default().bind(&mut builder);
        builder
            .build()
            .map(Some)
            .map_err(|e| device.error(&format!("creating the {} kernel", kernel.name()), e))
    };
    let entries = match scene.bvh.is_some() && program.kernels().contains(Kernel::TracePrimary) {
        true => {
            let mut builder = scene_kernel_builder(device, program, "tile_entries", scene);
            BandParams::default().bind(&mut builder);
            TileEntriesParams::default().bind(&mut builder);
            let kernel = builder
                .build()
                .map_err(|e| device.error("creating the tile_entries kernel", e))?;
            Some(kernel)
        }
        false => None,
    };
    Ok([
        build(Kernel::TracePrimary)?,
        build(Kernel::TracePrimaryGeneral)?,
        entries,
    ])
}

/// A builder of `kernel` of `program` with the scene's parameters bound (by name).
fn kernel_builder<'b>(
    device: &ClDevice,
    program: &'b Program,
    kernel: Kernel,
    scene: &'b Scene,
) -> Result<ocl::builders::KernelBuilder<'b>> {
    require_kernel(program, kernel)?;
    Ok(scene_kernel_builder(device, program, kernel.name(), scene))
}

/// A builder of the kernel `name` of `program` with the scene's parameters bound.
fn scene_kernel_builder<'b>(
    device: &ClDevice,
    program: &'b Program,
    name: &str,
    scene: &'b Scene,
) -> ocl::builders::KernelBuilder<'b> {
    let mut builder = ocl::Kernel::builder();
    builder
        .program(program.ocl())
        .name(name)
        .queue(device.queue.clone());
    match &scene.bvh {
        None => BruteSceneParams {
            tris: &scene.triangles,
            tri_count: scene.count,
        }
        .bind(&mut builder),
        Some(bvh) => BvhSceneParams {
            nodes: &bvh.nodes,
            tris: &scene.triangles,
            status: &bvh.status,
        }
        .bind(&mut builder),
    }
    scene.surface.params().bind(&mut builder);
    builder
}

/// A device buffer for the entry nodes of `tiles` tiles.
fn entries_buffer(device: &ClDevice, tiles: usize) -> Result<ocl::Buffer<u32>> {
    ocl::Buffer::<u32>::builder()
        .queue(device.queue.clone())
        .len(tiles)
        .build()
        .map_err(|e| device.error("allocating the tile entries", e))
}

/// The rays counted in `rows` of a pitched image of counts `width` wide.
fn row_sums(counts: &[u32], pitch: usize, width: usize, rows: std::ops::Range<usize>) -> u64 {
    rows.map(|y| {
        counts[y * pitch..y * pitch + width]
            .iter()
            .map(|&c| c as u64)
            .sum::<u64>()
    })
    .sum()
}

/// The first sample's ray counts, read while the launches with the rest of the samples run:
/// copied on the device after the first sample, then read on a queue of their own by a
/// thread, into a buffer it makes. They give the progress bar its rate. Read in line, they
/// left the device idle while they crossed and the host made their buffer: reading them so
/// made an H200's 1080p path renders 1.00-1.02x as fast (docs/bench/2026-12-07-tile-order.md).
struct FirstCounts(std::thread::JoinHandle<std::result::Result<(Vec<u32>, u64), ocl::Error>>);

impl FirstCounts {
    /// Starts reading the first `len` counts of `rays` as the commands queued so far leave
    /// them.
    fn start(
        device: &ClDevice,
        rays: &ocl::Buffer<u32>,
        len: usize,
    ) -> std::result::Result<FirstCounts, ocl::Error> {
        let copy = ocl::Buffer::<u32>::builder()
            .queue(device.queue.clone())
            .len(len)
            .build()?;
        let mut copied = ocl::Event::empty();
        rays.copy(&copy, Some(0), Some(len))
            .enew(&mut copied)
            .enq()?;
        // The other queue's read waits on the copy: it must reach the device even if no
        // command after it does (an error ending the render).
        device.queue.flush()?;
        let (context, id) = (device.context.clone(), device.info.device);
        Ok(FirstCounts(std::thread::spawn(move || {
            use rayon::prelude::*;
            let queue = ocl::Queue::new(&context, id, None)?;
            let mut counts = filled(0u32, len);
            copy.read(&mut counts).queue(&queue).ewait(&copied).enq()?;
            let n = counts.par_iter().map(|&c| c as u64).sum();
            Ok((counts, n))
        })))
    }

    fn is_finished(&self) -> bool {
        self.0.is_finished()
    }

    /// The counts and their sum.
    fn finish(self) -> std::result::Result<(Vec<u32>, u64), ocl::Error> {
        self.0.join().expect("reading the counts does not panic")
    }
}

/// What the host needs to take a frame's sums back: a zeroed buffer to read them into, and
/// the pages of the accumulation they are added to, faulted in. A GPU's host makes them
/// ready on its cores while the device samples; made before the launches instead, they
/// left an H100 idle for milliseconds at 1080p (66 MB of sums), and made during the first
/// sample they slowed its ray-count read (docs/bench/2026-12-07-host-sums.md). A CPU
/// device's cores are the host's, busy with the launches: there the buffer is made at
/// once, as are small ones.
struct ReadBack {
    /// The thread making the buffer and the pages ready, with the accumulation's pixels.
    preparing: Option<std::thread::JoinHandle<Prepared>>,
    host: Vec<Long4>,
}

/// The accumulation's pixels, and the buffer to read sums into.
type Prepared = (Vec<[i64; 4]>, Vec<Long4>);

impl ReadBack {
    /// Starts making ready a buffer of `len` sums and, in the background, the
    /// accumulation's `pixels`, which [`ReadBack::ready`] gives back.
    fn prepare(pixels: &mut Vec<[i64; 4]>, len: usize, background: bool) -> ReadBack {
        // Below this many sums a thread costs more than it saves.
        if !background || len < 1 << 16 {
            return ReadBack {
                preparing: None,
                host: filled(Long4::zero(), len),
            };
        }
        let mut pixels = std::mem::take(pixels);
        let preparing = std::thread::spawn(move || {
            use rayon::prelude::*;
            // One write a page (4 KiB: 128 pixels) faults it in; the values stay.
            pixels
                .par_chunks_mut(128)
                .for_each(|page| page[0] = std::hint::black_box(page[0]));
            (pixels, filled(Long4::zero(), len))
        });
        ReadBack {
            preparing: Some(preparing),
            host: Vec::new(),
        }
    }

    /// The buffer to read into, once ready; the accumulation's pixels back in `pixels`.
    fn ready(&mut self, pixels: &mut Vec<[i64; 4]>) -> &mut [Long4] {
        if let Some(thread) = self.preparing.take() {
            let (made, host) = thread
                .join()
                .expect("the read-back's preparation does not panic");
            *pixels = made;
            self.host = host;
        }
        &mut self.host
    }
}

/// `len` copies of `value`, written on every core: one thread faulting in the pages of a 4K
/// frame's 265 MB of sums takes tens of milliseconds, and on the GPU machines' virtual
/// hosts one faulting in a 1080p frame's 8 MB of ray counts took 8 ms.
fn filled<T: ocl::OclPrm + Send + Sync>(value: T, len: usize) -> Vec<T> {
    use rayon::prelude::*;
    let mut v = Vec::with_capacity(len);
    v.par_extend(rayon::iter::repeat_n(value, len));
    v
}

/// Sums as the host keeps them, as the device's `long4`s, to read into.
fn long4s(pixels: &mut [[i64; 4]]) -> &mut [Long4] {
    // ocl's Long4 is a newtype of [i64; 4]: same size, no stricter alignment.
    const _: () = assert!(size_of::<Long4>() == size_of::<[i64; 4]>());
    const _: () = assert!(align_of::<Long4>() <= align_of::<[i64; 4]>());
    // SAFETY: as above, and every bit pattern is a valid value of both.
    unsafe { std::slice::from_raw_parts_mut(pixels.as_mut_ptr().cast::<Long4>(), pixels.len()) }
}

/// Zeroes the sums and ray counts of `rows` (rows of the accumulation image).
fn clear_rows(
    device: &ClDevice,
    accum: &PitchedBuffer<Long4>,
    rays: &ocl::Buffer<u32>,
    rows: std::ops::Range<usize>,
) -> Result<()> {
    let (offset, len) = (rows.start * accum.pitch, rows.len() * accum.pitch);
    accum
        .buffer
        .cmd()
        .fill(Long4::zero(), Some(len))
        .offset(offset)
        .enq()
        .map_err(|e| device.error("clearing the accumulation image", e))?;
    rays.cmd()
        .fill(0u32, Some(len))
        .offset(offset)
        .enq()
        .map_err(|e| device.error("clearing the ray counts", e))
}

/// Launches an image kernel over rows `y0 .. y0 + rows` of a `width`-pixel image, the
/// global size rounded up to whole work-groups; returns its device time in ms.
fn launch_rows(
    device: &ClDevice,
    kernel: &ocl::Kernel,
    local: [usize; 2],
    width: usize,
    y0: usize,
    rows: usize,
) -> Result<f64> {
    launch_rect(device, kernel, local, [0, y0], [width, rows])
}

/// Launches `kernel` over the `size` pixels from `origin` (the global offset), the global
/// size rounded up to whole work-groups: the kernels return at once past the rectangle.
fn launch_rect(
    device: &ClDevice,
    kernel: &ocl::Kernel,
    local: [usize; 2],
    origin: [usize; 2],
    size: [usize; 2],
) -> Result<f64> {
    wait_ms(device, &queue_rect(device, kernel, local, origin, size)?)
}

/// Enqueues a kernel, waits for it, and returns its device time in milliseconds.
fn launch(device: &ClDevice, cmd: ocl::builders::KernelCmd) -> Result<f64> {
    wait_ms(device, &queue_kernel(device, cmd)?)
}

/// [`launch_rect`] without the wait: the launch's event.
fn queue_rect(
    device: &ClDevice,
    kernel: &ocl::Kernel,
    local: [usize; 2],
    origin: [usize; 2],
    size: [usize; 2],
) -> Result<ocl::Event> {
    let global = [
        size[0].div_ceil(local[0]) * local[0],
        size[1].div_ceil(local[1]) * local[1],
    ];
    queue_kernel(
        device,
        kernel
            .cmd()
            .global_work_offset(origin)
            .global_work_size(global)
            .local_work_size(local),
    )
}

fn queue_kernel(device: &ClDevice, cmd: ocl::builders::KernelCmd) -> Result<ocl::Event> {
    let mut event = ocl::Event::empty();
    unsafe {
        cmd.enew(&mut event)
            .enq()
            .map_err(|e| device.error("launching the kernel", e))?;
    }
    Ok(event)
}

/// Waits for a launch to end; its device time, ms.
fn wait_ms(device: &ClDevice, event: &ocl::Event) -> Result<f64> {
    event
        .wait_for()
        .map_err(|e| device.error("running the kernel", e.into()))?;
    event_ms(event).map_err(|e| device.error("reading the kernel's profiling times", e))
}

fn upload<T: ocl::OclPrm>(device: &ClDevice, data: &[T], doing: &str) -> Result<ocl::Buffer<T>> {
    if size_of_val(data) <= STAGING_BYTES {
        return ocl::Buffer::<T>::builder()
            .queue(device.queue.clone())
            .flags(ocl::flags::MEM_READ_ONLY | ocl::flags::MEM_COPY_HOST_PTR)
            .len(data.len())
            .copy_host_slice(data)
            .build()
            .map_err(|e| device.error(doing, e));
    }
    let err = |e| device.error(doing, e);
    let buffer = ocl::Buffer::<T>::builder()
        .queue(device.queue.clone())
        .flags(ocl::flags::MEM_READ_ONLY)
        .len(data.len())
        .build()
        .map_err(err)?;
    let per = STAGING_BYTES / size_of::<T>();
    let staging = ocl::Buffer::<T>::builder()
        .queue(device.queue.clone())
        .flags(ocl::flags::MEM_ALLOC_HOST_PTR | ocl::flags::MEM_READ_WRITE)
        .len(per)
        .build()
        .map_err(err)?;
    for (k, chunk) in data.chunks(per).enumerate() {
        // Mapping waits for the last chunk's copy out of the staging buffer (one queue, in
        // order); the chunk is then copied in on every core.
        // SAFETY: the mapping is only written through, and unmapped before the copy reads it.
        let mut map =
            unsafe { staging.map().write_invalidate().len(chunk.len()).enq() }.map_err(err)?;
        use rayon::prelude::*;
        map.par_chunks_mut(1 << 16)
            .zip(chunk.par_chunks(1 << 16))
            .for_each(|(to, from)| to.copy_from_slice(from));
        map.unmap().enq().map_err(err)?;
        staging
            .copy(&buffer, Some(k * per), Some(chunk.len()))
            .enq()
            .map_err(err)?;
    }
    device.queue.finish().map_err(err)?;
    Ok(buffer)
}

/// Buffers larger than this go to the device in chunks through pinned (page-locked) host
/// memory, filled on every core: NVIDIA's driver copied pageable memory at 1.6 GB/s, an
/// 8 GB scene in 5 s.
const STAGING_BYTES: usize = 64 << 20;

/// Checks, before anything is uploaded, that each of the scene's buffers fits in one device
/// allocation and that together (with a row of output) they fit in the device's memory.
fn check_scene_memory(device: &ClDevice, buffers: &[(&str, u64)]) -> Result<()> {
    let info = &device.info;
    let mib = |b: u64| b.div_ceil(1 << 20);
    let total: u64 = buffers.iter().map(|b| b.1).sum();
    let largest = buffers
        .iter()
        .max_by_key(|b| b.1)
        .copied()
        .unwrap_or(("", 0));
    let parts: Vec<String> = buffers
        .iter()
        .map(|(n, b)| format!("{n} {} MiB", mib(*b)))
        .collect();
    if largest.1 > info.max_allocation || total + (1 << 20) > info.global_memory {
        return Err(Error::Device(format!(
            "the scene needs {} MiB on {} ({}), but the device has {} MiB of global memory and allocates at most {} MiB at once",
            mib(total),
            info.name,
            parts.join(", "),
            mib(info.global_memory),
            mib(info.max_allocation)
        )));
    }
    Ok(())
}

/// Rows of a `width`-wide pitched image of `T` that fit in `budget` bytes: the whole
/// frame where they all fit, at least one.
fn capacity<T: ocl::OclPrm>(device: &ClDevice, budget: u64, width: usize, height: usize) -> usize {
    let row_bytes = PitchedBuffer::<T>::pitch_bytes_for(device, width) as u64;
    ((budget / row_bytes) as usize).clamp(1, height)
}

/// The work-group shape before tuning: pixel tiles keep neighbouring rays together. On
/// GPUs 16 x 8 (a warp two rows of 16): on the H200 it traces primary rays 3-8% and paths
/// 2-3% faster than 8 x 8, diffuse batches 1% slower (docs/bench/2026-12-05-h200.md).
/// Other devices keep 8 x 8, unmeasured against it (`cltrace tune` finds each one's).
fn default_work_group(device: &ClDevice) -> [usize; 2] {
    default_shape(device.info.kind, device.info.max_work_group_size)
}

/// [`default_work_group`] of a device of `kind` that runs at most `most` work-items a group.
fn default_shape(kind: DeviceKind, most: usize) -> [usize; 2] {
    match kind {
        DeviceKind::Gpu if most >= 128 => [16, 8],
        _ if most >= 64 => [8, 8],
        _ => [1, 1],
    }
}

fn event_ms(event: &ocl::Event) -> std::result::Result<f64, ocl::Error> {
    let start = event.profiling_info(ProfilingInfo::Start)?.time()?;
    let end = event.profiling_info(ProfilingInfo::End)?.time()?;
    Ok(end.saturating_sub(start) as f64 * 1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_launch_takes_as_many_samples_as_fit_its_target_and_at_least_one() {
        let mut planner = BandPlanner {
            rate: None,
            first_band_pixels: 1000,
        };
        // Nothing measured: one sample.
        assert_eq!(planner.next_samples(100, 64), 1);
        // 10 pixel samples a millisecond: 1,000 in a launch's target, 10 samples of 100.
        planner.learn(1000, 100.0);
        assert_eq!(planner.next_samples(100, 64), 10);
        assert_eq!(planner.next_samples(100, 4), 4);
        // One sample of a larger region is over the target: still one.
        assert_eq!(planner.next_samples(5000, 64), 1);
        assert_eq!(planner.next_samples(100, 0), 1);
    }

    #[test]
    fn gpus_default_to_16_by_8_work_groups_other_devices_to_8_by_8_where_they_fit() {
        assert_eq!(default_shape(DeviceKind::Gpu, 1024), [16, 8]);
        assert_eq!(default_shape(DeviceKind::Gpu, 128), [16, 8]);
        assert_eq!(default_shape(DeviceKind::Gpu, 64), [8, 8]);
        assert_eq!(default_shape(DeviceKind::Cpu, 4096), [8, 8]);
        assert_eq!(default_shape(DeviceKind::Accelerator, 256), [8, 8]);
        assert_eq!(default_shape(DeviceKind::Cpu, 32), [1, 1]);
    }

    #[test]
    fn a_read_back_made_in_the_background_gives_the_sums_back_unchanged() {
        for (len, background) in [(1 << 17, true), (1 << 17, false), (10, true)] {
            let sums: Vec<[i64; 4]> = (0..len as i64).map(|i| [i, -i, 2 * i, 1]).collect();
            let mut pixels = sums.clone();
            let mut read_back = ReadBack::prepare(&mut pixels, len + 3, background);
            let host = read_back.ready(&mut pixels);
            assert_eq!(host.len(), len + 3);
            assert!(host.iter().all(|v| *v == Long4::zero()));
            assert!(pixels == sums, "{len} sums, background {background}");
            // Ready again: the same buffer, the pixels left alone.
            assert_eq!(read_back.ready(&mut pixels).len(), len + 3);
            assert!(pixels == sums);
        }
    }

    #[test]
    fn only_programs_of_sample_kernels_alone_count_as_sampling() {
        assert!(Kernels::NONE.with(Kernel::SamplePath).only_sampling());
        assert!(!Kernels::ALL.only_sampling());
        assert!(!Kernels::PRIMARY.only_sampling());
        assert!(!Kernels::NONE.only_sampling());
    }
}
