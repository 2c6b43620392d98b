//! Device layouts: the flat arrays the kernels read, as `#[repr(C)]` structs mirrored in
//! `cl/cltrace.h` (tests/layout.rs pins sizes and offsets on both sides). The thesis's
//! 32-byte binary layout ([`FlatBvh`]) is the builder's output and the reference; the
//! others are made from it: [`aila`] (both child boxes in the parent), [`wide`] (4- and
//! 8-wide nodes) and [`compressed`] (8-wide nodes with quantized boxes).

pub mod aila;
pub mod compressed;
pub mod wide;

use bytemuck::{Pod, Zeroable};

use crate::bvh::Bvh;
use crate::mesh::Mesh;

/// Marks a leaf in [`BvhNode::right_or_count`].
pub const LEAF_FLAG: u32 = 0x8000_0000;

/// A triangle as the intersectors read it: three corners, each padded to 16 bytes; the
/// padding holds the triangle's index in file order (`prim`, what hit records report) and
/// its material's index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub prim: u32,
    pub v1: [f32; 3],
    pub material: u32,
    pub v2: [f32; 3],
    pub pad: u32,
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
            material: 0,
            v2: c.to_array(),
            pad: 0,
        }
    }
}

/// Stores each triangle's material index (looked up by its file-order index).
pub fn assign_materials(triangles: &mut [Triangle], materials: &crate::material::Materials) {
    for t in triangles {
        t.material = materials.index_of(t.prim as usize);
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

/// The device layouts `--layout` chooses among.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    clap::ValueEnum,
    serde::Deserialize,
    serde::Serialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Layout {
    /// The thesis's 32-byte binary node: a node's box is stored in the node.
    #[default]
    Bin32,
    /// Aila–Laine: 64-byte binary nodes holding both children's boxes.
    Bin64,
    /// 4-wide nodes (128 bytes), collapsed from the binary tree.
    Wide4,
    /// 8-wide nodes (256 bytes), collapsed from the binary tree.
    Wide8,
    /// Compressed 8-wide nodes (80 bytes, child boxes quantized to 8 bits; Ylitie et al.
    /// 2017), leaves of at most 3 triangles.
    Cwbvh,
}

impl Layout {
    pub const ALL: [Layout; 5] = [
        Layout::Bin32,
        Layout::Bin64,
        Layout::Wide4,
        Layout::Wide8,
        Layout::Cwbvh,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Layout::Bin32 => "bin32",
            Layout::Bin64 => "bin64",
            Layout::Wide4 => "wide4",
            Layout::Wide8 => "wide8",
            Layout::Cwbvh => "cwbvh",
        }
    }

    /// The kernels' `LAYOUT` define.
    pub fn code(self) -> u32 {
        match self {
            Layout::Bin32 => 32,
            Layout::Bin64 => 64,
            Layout::Wide4 => 4,
            Layout::Wide8 => 8,
            Layout::Cwbvh => 80,
        }
    }
}

/// A BVH in one of the device layouts: node bytes, triangles in leaf order, and the
/// traversal stack the kernels need for it.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceLayout {
    pub layout: Layout,
    /// The nodes, as the kernels read them.
    pub nodes: Vec<u8>,
    pub node_count: usize,
    pub triangles: Vec<Triangle>,
    /// Entries the traversal stack needs: the depth for binary layouts, (width - 1) per
    /// level of a wide tree, one per level of a compressed one (a node's unvisited children
    /// share one entry).
    pub stack_size: u32,
    /// The SAH cost of the tree as laid out (wide nodes count one traversal step each).
    pub sah_cost: f64,
}

impl DeviceLayout {
    /// Lays the thesis-layout tree out as `layout`; `sah_cost` is the binary tree's.
    pub fn new(flat: FlatBvh, layout: Layout, sah_cost: f64) -> Self {
        let depth = flat.depth.max(1);
        // The compressed layout reorders the triangles; the others keep the tree's order.
        let mut reordered = None;
        let (nodes, node_count, stack_size, sah_cost) = match layout {
            Layout::Bin32 => (
                bytemuck::cast_slice(&flat.nodes).to_vec(),
                flat.nodes.len(),
                depth,
                sah_cost,
            ),
            Layout::Bin64 => {
                let n = aila::to_bvh64(&flat);
                (bytemuck::cast_slice(&n).to_vec(), n.len(), depth, sah_cost)
            }
            Layout::Wide4 => {
                let c = wide::collapse::<wide::Wide4Node>(&flat);
                (
                    bytemuck::cast_slice(&c.nodes).to_vec(),
                    c.nodes.len(),
                    3 * c.depth + 1,
                    c.sah_cost,
                )
            }
            Layout::Wide8 => {
                let c = wide::collapse::<wide::Wide8Node>(&flat);
                (
                    bytemuck::cast_slice(&c.nodes).to_vec(),
                    c.nodes.len(),
                    7 * c.depth + 1,
                    c.sah_cost,
                )
            }
            Layout::Cwbvh => {
                let c = compressed::compress(&flat);
                reordered = Some(c.triangles);
                (
                    bytemuck::cast_slice(&c.nodes).to_vec(),
                    c.nodes.len(),
                    c.depth + 1,
                    c.sah_cost,
                )
            }
        };
        DeviceLayout {
            layout,
            nodes,
            node_count,
            triangles: reordered.unwrap_or(flat.triangles),
            stack_size,
            sah_cost,
        }
    }

    /// Bytes the device holds per triangle (nodes and triangles together).
    pub fn bytes_per_triangle(&self) -> f64 {
        (self.nodes.len() + self.triangles.len() * size_of::<Triangle>()) as f64
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
