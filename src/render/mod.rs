//! Rendering: one frame of per-pixel closest hits and colours, by brute force or through
//! a BVH, on the CPU or on an OpenCL device. Every method fills the same [`Frame`].

pub mod bsdf;
pub mod cpu;
pub mod integrator;
pub mod sampling;
mod shade;

pub use shade::{ShadeParams, tone_map};

use bytemuck::{Pod, Zeroable};
use serde::Deserialize;

/// How rays find their closest hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Every ray against every triangle, on the host (rayon over rows).
    CpuBrute,
    /// BVH traversal on the host (rayon over rows).
    CpuBvh,
    /// Every ray against every triangle, in an OpenCL kernel.
    ClBrute,
    /// BVH traversal in an OpenCL kernel.
    ClBvh,
}

impl Method {
    /// Every method, host ones first.
    pub const ALL: [Method; 4] = [
        Method::CpuBrute,
        Method::CpuBvh,
        Method::ClBrute,
        Method::ClBvh,
    ];

    /// The method's name: on the command line (`--method`), in scene files and in the
    /// bench's tables.
    pub fn name(self) -> &'static str {
        match self {
            Method::CpuBrute => "cpu-brute",
            Method::CpuBvh => "cpu-bvh",
            Method::ClBrute => "cl-brute",
            Method::ClBvh => "cl-bvh",
        }
    }

    /// One line on the method, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            Method::CpuBrute => "Every ray against every triangle, on the host (rayon over rows)",
            Method::CpuBvh => "BVH traversal on the host (rayon over rows)",
            Method::ClBrute => "Every ray against every triangle, in an OpenCL kernel",
            Method::ClBvh => "BVH traversal in an OpenCL kernel",
        }
    }

    pub(crate) fn uses_opencl(self) -> bool {
        matches!(self, Method::ClBrute | Method::ClBvh)
    }

    pub(crate) fn uses_bvh(self) -> bool {
        matches!(self, Method::CpuBvh | Method::ClBvh)
    }
}

/// How a hit becomes a colour. Misses are black.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shade {
    /// The geometric normal (by winding), mapped from [-1, 1] to [0, 1] per channel.
    Normal,
    /// Distance: white at the nearest point of the scene's bounding sphere, black at the farthest.
    Depth,
    /// A two-sided headlight: |cos| between the geometric normal and the ray.
    Lambert,
    /// Ambient occlusion: the unoccluded share of cosine-weighted rays (`--ao-samples`,
    /// `--ao-distance`).
    Ao,
    /// The albedo under one light (`--light`) with hard shadows.
    Shadow,
    /// Path tracing through the materials' scattering models: light from emitting
    /// materials, or a sky where there are none.
    Path,
}

impl std::str::FromStr for Method {
    type Err = String;

    /// The method [`Method::name`] names.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::error::by_name(s, &Method::ALL, Method::name, "method")
    }
}

impl Shade {
    /// Every mode, the single-hit ones first.
    pub const ALL: [Shade; 6] = [
        Shade::Normal,
        Shade::Depth,
        Shade::Lambert,
        Shade::Ao,
        Shade::Shadow,
        Shade::Path,
    ];

    /// The number the primary-ray kernel uses (`SHADE_*`, written in front of every program
    /// by src/device/program.rs and read by cl/shade.cl); the progressive
    /// modes shade their own samples and are given Lambert for the primary pass.
    pub fn code(self) -> i32 {
        match self {
            Shade::Normal => 0,
            Shade::Depth => 1,
            Shade::Lambert | Shade::Ao | Shade::Shadow | Shade::Path => 2,
        }
    }

    /// The mode's name: on the command line (`--shade`) and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Shade::Normal => "normal",
            Shade::Depth => "depth",
            Shade::Lambert => "lambert",
            Shade::Ao => "ao",
            Shade::Shadow => "shadow",
            Shade::Path => "path",
        }
    }

    /// One line on the mode, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            Shade::Normal => {
                "The geometric normal (by winding), mapped from [-1, 1] to [0, 1] per channel"
            }
            Shade::Depth => {
                "Distance: white at the nearest point of the scene's bounding sphere, black at \
                 the farthest"
            }
            Shade::Lambert => {
                "A two-sided headlight: |cos| between the geometric normal and the ray"
            }
            Shade::Ao => {
                "Ambient occlusion: the unoccluded share of cosine-weighted rays (`--ao-samples`, \
                 `--ao-distance`)"
            }
            Shade::Shadow => "The albedo under one light (`--light`) with hard shadows",
            Shade::Path => {
                "Path tracing through metals, glass and plastics: light from emitting materials, or a sky where there are none"
            }
        }
    }
}

impl std::str::FromStr for Shade {
    type Err = String;

    /// The mode [`Shade::name`] names.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::error::by_name(s, &Shade::ALL, Shade::name, "shade mode")
    }
}

/// Marks a miss in [`Hit::prim`].
pub const MISS: u32 = u32::MAX;

/// One pixel's closest hit, as the kernels write it and `--hits` stores it: the triangle's
/// index in file order ([`MISS`] for none) and the distance from the eye (+inf for a miss).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Hit {
    /// The triangle's index in file order, or [`MISS`].
    pub prim: u32,
    /// Distance from the ray's origin (the eye, for primary rays) to the hit, in world
    /// units whatever the direction's length; +inf for a miss.
    pub t: f32,
}

impl Hit {
    pub(crate) const NONE: Hit = Hit {
        prim: MISS,
        t: f32::INFINITY,
    };

    /// Whether the ray hit nothing.
    pub fn is_miss(&self) -> bool {
        self.prim == MISS
    }
}

/// A rendered frame: per-pixel hits and RGBA8 colours (packed little-endian in a u32),
/// row-major, `y` down.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One closest hit per pixel.
    pub hits: Vec<Hit>,
    /// One RGBA8 colour per pixel, red in the low byte.
    pub colors: Vec<u32>,
    /// Where the frame was asked for them ([`ShadeParams::with_barycentrics`]), one per
    /// pixel: the hit's barycentric weights of its triangle's vertices 1 and 2 (vertex 0's
    /// is 1 minus their sum), `[0, 0]` for a miss; otherwise empty.
    pub barycentrics: Vec<[f32; 2]>,
    /// Linear radiance per pixel, for the progressive shade modes (the colours are then its
    /// tone-mapped form).
    pub(crate) radiance: Option<Vec<[f32; 3]>>,
}

impl Frame {
    pub(crate) fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            hits: vec![Hit::NONE; n],
            colors: vec![0; n],
            barycentrics: Vec::new(),
            radiance: None,
        }
    }

    /// The hit of pixel (x, y); panics outside the frame.
    pub fn hit(&self, x: u32, y: u32) -> Hit {
        self.hits[(y * self.width + x) as usize]
    }

    /// The colours as an RGB image.
    pub(crate) fn to_rgb_image(&self) -> image::RgbImage {
        let bytes = self
            .colors
            .iter()
            .flat_map(|c| {
                let [r, g, b, _] = c.to_le_bytes();
                [r, g, b]
            })
            .collect();
        image::RgbImage::from_raw(self.width, self.height, bytes).expect("frame size matches")
    }
}
