//! The device layouts `--layout` chooses among, and a built tree laid out in one of them
//! (node bytes, triangles, stack size). Each layout is its own module of `bvh/`, named as
//! the CLI, its node type and its kernel file name it.

use super::bin32::Bin32Bvh;
use super::{MAX_DEPTH, bin64, cwbvh, wide, wide4, wide8};
use crate::intersect::Triangle;

/// The device layouts `--layout` chooses among.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize, serde::Serialize,
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
    /// Every layout, the default first.
    pub const ALL: [Layout; 5] = [
        Layout::Bin32,
        Layout::Bin64,
        Layout::Wide4,
        Layout::Wide8,
        Layout::Cwbvh,
    ];

    /// The layout's name: on the command line (`--layout`), in the bench's method column
    /// (`cl-bvh:NAME`) and as its kernel file (`cl/NAME.cl`).
    pub fn name(self) -> &'static str {
        match self {
            Layout::Bin32 => "bin32",
            Layout::Bin64 => "bin64",
            Layout::Wide4 => "wide4",
            Layout::Wide8 => "wide8",
            Layout::Cwbvh => "cwbvh",
        }
    }

    /// One line on the layout, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            Layout::Bin32 => "The thesis's 32-byte binary node: a node's box is stored in the node",
            Layout::Bin64 => "Aila–Laine: 64-byte binary nodes holding both children's boxes",
            Layout::Wide4 => "4-wide nodes (128 bytes), collapsed from the binary tree",
            Layout::Wide8 => "8-wide nodes (256 bytes), collapsed from the binary tree",
            Layout::Cwbvh => {
                "Compressed 8-wide nodes (80 bytes, child boxes quantized to 8 bits; Ylitie et al. \
                 2017), leaves of at most 3 triangles"
            }
        }
    }

    /// The define its kernel program is built with, `LAYOUT_` and the name in capitals:
    /// the layout's kernel file, `cl/` and the name, refuses to compile without it.
    pub(crate) fn define(self) -> String {
        format!("LAYOUT_{}", self.name().to_ascii_uppercase())
    }

    /// The traversal stack entries a tree of this layout `depth` levels deep needs: the
    /// depth for binary layouts, (width - 1) per level of a wide tree, one per level of a
    /// compressed one (a node's unvisited children share one entry).
    pub fn stack_size(self, depth: u32) -> u32 {
        match self {
            Layout::Bin32 | Layout::Bin64 => depth,
            Layout::Wide4 => 3 * depth + 1,
            Layout::Wide8 => 7 * depth + 1,
            Layout::Cwbvh => depth + 1,
        }
    }

    /// The stack entries any tree of this layout needs ([`MAX_DEPTH`] levels): programs are
    /// compiled with it, so that they serve every scene of the layout and can compile
    /// before the tree is built. On the H200 and PoCL-16 it traced as fast as the tree's
    /// own size (docs/bench/2026-12-04-first-image.md).
    pub fn max_stack_size(self) -> u32 {
        self.stack_size(MAX_DEPTH)
    }
}

impl std::str::FromStr for Layout {
    type Err = String;

    /// The layout [`Layout::name`] names.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::error::by_name(s, &Layout::ALL, Layout::name, "layout")
    }
}

/// The nodes of a tree in one layout, kept in their own type (not copied into bytes: a
/// scene of hundreds of millions of triangles has gigabytes of them).
#[derive(Clone)]
pub(crate) enum Nodes {
    Bin32(Vec<super::Bin32Node>),
    Bin64(Vec<bin64::Bin64Node>),
    Wide4(Vec<wide4::Wide4Node>),
    Wide8(Vec<wide8::Wide8Node>),
    Cwbvh(Vec<cwbvh::CwbvhNode>),
}

impl Nodes {
    /// The nodes' bytes, as the kernels read them.
    pub(crate) fn bytes(&self) -> &[u8] {
        match self {
            Nodes::Bin32(n) => bytemuck::cast_slice(n),
            Nodes::Bin64(n) => bytemuck::cast_slice(n),
            Nodes::Wide4(n) => bytemuck::cast_slice(n),
            Nodes::Wide8(n) => bytemuck::cast_slice(n),
            Nodes::Cwbvh(n) => bytemuck::cast_slice(n),
        }
    }
}

impl PartialEq for Nodes {
    fn eq(&self, other: &Self) -> bool {
        self.bytes() == other.bytes()
    }
}

impl std::fmt::Debug for Nodes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} bytes of nodes", self.bytes().len())
    }
}

/// A BVH in one of the device layouts: node bytes, triangles in leaf order, and the
/// traversal stack the kernels need for it.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceLayout {
    pub(crate) layout: Layout,
    /// The nodes, as the kernels read them.
    pub(crate) nodes: Nodes,
    pub(crate) node_count: usize,
    pub(crate) triangles: Vec<Triangle>,
    /// Entries the traversal stack needs ([`Layout::stack_size`] of the tree's depth).
    pub stack_size: u32,
    /// The SAH cost of the tree as laid out (wide nodes count one traversal step each).
    pub(crate) sah_cost: f64,
}

impl DeviceLayout {
    /// Lays the thesis-layout tree out as `layout`; `sah_cost` is the binary tree's.
    pub fn new(mut flat: Bin32Bvh, layout: Layout, sah_cost: f64) -> Self {
        let depth = flat.depth.max(1);
        // The compressed layout reorders the triangles; the others keep the tree's order.
        let mut reordered = None;
        let (nodes, node_count, stack_size, sah_cost) = match layout {
            Layout::Bin64 => {
                let n = bin64::to_bvh64(&flat);
                let count = n.len();
                (Nodes::Bin64(n), count, layout.stack_size(depth), sah_cost)
            }
            Layout::Bin32 => {
                let count = flat.nodes.len();
                let nodes = Nodes::Bin32(std::mem::take(&mut flat.nodes));
                (nodes, count, layout.stack_size(depth), sah_cost)
            }
            Layout::Wide4 => {
                let c = wide::collapse::<wide4::Wide4Node>(&flat);
                let count = c.nodes.len();
                (
                    Nodes::Wide4(c.nodes),
                    count,
                    layout.stack_size(c.depth),
                    c.sah_cost,
                )
            }
            Layout::Wide8 => {
                let c = wide::collapse::<wide8::Wide8Node>(&flat);
                let count = c.nodes.len();
                (
                    Nodes::Wide8(c.nodes),
                    count,
                    layout.stack_size(c.depth),
                    c.sah_cost,
                )
            }
            Layout::Cwbvh => {
                let c = cwbvh::compress(&flat);
                reordered = Some(c.triangles);
                let count = c.nodes.len();
                (
                    Nodes::Cwbvh(c.nodes),
                    count,
                    layout.stack_size(c.depth),
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

    /// Bytes the device holds for the scene: nodes and triangles.
    pub(crate) fn device_bytes(&self) -> usize {
        self.nodes.bytes().len() + self.triangles.len() * size_of::<Triangle>()
    }

    /// Bytes the device holds per triangle (nodes and triangles together).
    pub(crate) fn bytes_per_triangle(&self) -> f64 {
        self.device_bytes() as f64 / self.triangles.len() as f64
    }
}
