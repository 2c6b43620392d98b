//! Device layouts: the flat arrays the kernels read, as `#[repr(C)]` structs mirrored in
//! `cl/cltrace.h` (tests/layout.rs pins sizes and offsets on both sides).

use bytemuck::{Pod, Zeroable};

use crate::bvh::Bvh;
use crate::mesh::Mesh;

/// Marks a leaf in [`BvhNode::right_or_count`].
pub const LEAF_FLAG: u32 = 0x8000_0000;

/// A triangle as the intersectors read it: three corners, each padded to 16 bytes, and the
/// triangle's index in file order (`prim`), which is what hit records report.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub prim: u32,
    pub v1: [f32; 3],
    pub pad1: u32,
    pub v2: [f32; 3],
    pub pad2: u32,
}

impl Triangle {
    /// A stored triangle. One of zero area (its edges' cross product exactly zero, as
    /// [`Mesh::degenerate_count`] counts them) is stored with all three corners at `v0`:
    /// rounding could let the watertight test "hit" three distinct collinear points, but
    /// with coinciding corners every edge function is exactly zero, and such a triangle
    /// never hits anywhere.
    pub fn new(corners: [glam::Vec3; 3], prim: u32) -> Self {
        let [a, mut b, mut c] = corners;
        if (b - a).cross(c - a) == glam::Vec3::ZERO {
            (b, c) = (a, a);
        }
        Triangle {
            v0: a.to_array(),
            prim,
            v1: b.to_array(),
            pad1: 0,
            v2: c.to_array(),
            pad2: 0,
        }
    }
}

/// The mesh's triangles in the order given (file order for brute force, leaf order for a
/// BVH), each carrying its file-order index.
pub fn triangles_in_order(mesh: &Mesh, order: impl IntoIterator<Item = u32>) -> Vec<Triangle> {
    order
        .into_iter()
        .map(|prim| Triangle::new(mesh.corners(prim as usize), prim))
        .collect()
}

/// A 32-byte BVH node as in the thesis: bounds, then two u32. An inner node holds its
/// children's indices; a leaf holds its first triangle and `LEAF_FLAG | count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub right_or_count: u32,
}

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.right_or_count & LEAF_FLAG != 0
    }

    /// A leaf's triangle count.
    pub fn count(&self) -> u32 {
        self.right_or_count & !LEAF_FLAG
    }
}

/// The thesis's device layout: 32-byte nodes in depth-first order and the triangles
/// reordered into leaf order, so that a leaf's triangles are contiguous.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatBvh {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<Triangle>,
    /// Nodes on the longest root-to-leaf path; a traversal stack of `depth` entries suffices.
    pub depth: u32,
}

impl FlatBvh {
    pub fn new(bvh: Bvh, mesh: &Mesh) -> Self {
        FlatBvh {
            triangles: triangles_in_order(mesh, bvh.prim_order.iter().copied()),
            nodes: bvh.nodes,
            depth: bvh.depth,
        }
    }

    /// Bytes the device holds per triangle (nodes and triangles together).
    pub fn bytes_per_triangle(&self) -> f64 {
        (self.nodes.len() * size_of::<BvhNode>() + self.triangles.len() * size_of::<Triangle>())
            as f64
            / self.triangles.len() as f64
    }
}

macro_rules! ocl_prm {
    ($($t:ty),*) => {$(
        // SAFETY: plain-old-data with a fixed C layout, mirrored in cl/cltrace.h.
        unsafe impl ocl::OclPrm for $t {}
    )*};
}
ocl_prm!(Triangle, BvhNode);
