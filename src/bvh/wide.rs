//! What the wide layouts ([`super::wide4`], [`super::wide8`]) share: the binary tree
//! collapsed into nodes of up to 4 or 8 children, their boxes stored axis by axis so that
//! one vector operation tests a plane of every child (`cl/wide.cl`).
//!
//! The collapse is greedy by surface area: a node starts with its two children and, while
//! it has room, replaces its largest inner child by that child's own children. Leaves stay
//! as they are.

use super::bin32::{Bin32Bvh, Bin32Node};
use glam::Vec3;

use super::SahCost;
use crate::geometry::surface_area_f64;

/// Marks an unused child slot in a wide node's `count`.
pub const EMPTY_SLOT: u32 = u32::MAX;

macro_rules! wide_node {
    ($name:ident, $n:literal) => {
        /// A wide node: the children's boxes plane by plane, then their references. A child
        /// with `count` 0 is an inner node (`child` indexes the node array), with `count > 0`
        /// a leaf of `count` triangles from `child`, with `EMPTY_SLOT` (`u32::MAX`) unused.
        /// Mirrored by the struct of its name in cl/nodes.cl; cl/wide.cl traverses it.
        #[repr(C)]
        #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
        pub struct $name {
            /// Per slot: the low x plane of the child's box (0 in an unused slot).
            pub min_x: [f32; $n],
            /// Per slot: the high x plane of the child's box.
            pub max_x: [f32; $n],
            /// Per slot: the low y plane of the child's box.
            pub min_y: [f32; $n],
            /// Per slot: the high y plane of the child's box.
            pub max_y: [f32; $n],
            /// Per slot: the low z plane of the child's box.
            pub min_z: [f32; $n],
            /// Per slot: the high z plane of the child's box.
            pub max_z: [f32; $n],
            /// Per slot: an inner child's index in the node array, or a leaf's first
            /// triangle in the leaf-order triangle list ([`super::Bin32Bvh::triangles`]).
            pub child: [u32; $n],
            /// Per slot: 0 for an inner child, the triangle count (at least 1) for a leaf,
            /// `EMPTY_SLOT` (`u32::MAX`) for an unused slot, which the kernel skips.
            pub count: [u32; $n],
        }

        impl Default for $name {
            fn default() -> Self {
                $name {
                    min_x: [0.0; $n],
                    max_x: [0.0; $n],
                    min_y: [0.0; $n],
                    max_y: [0.0; $n],
                    min_z: [0.0; $n],
                    max_z: [0.0; $n],
                    child: [0; $n],
                    count: [super::wide::EMPTY_SLOT; $n],
                }
            }
        }

        impl super::wide::WideNode for $name {
            const WIDTH: usize = $n;
            fn set(&mut self, slot: usize, b: &super::bin32::Bin32Node, child: u32, count: u32) {
                self.min_x[slot] = b.min[0];
                self.max_x[slot] = b.max[0];
                self.min_y[slot] = b.min[1];
                self.max_y[slot] = b.max[1];
                self.min_z[slot] = b.min[2];
                self.max_z[slot] = b.max[2];
                self.child[slot] = child;
                self.count[slot] = count;
            }
        }
    };
}

pub(super) use wide_node;

/// What the collapse needs of a wide node type.
pub(crate) trait WideNode: Default + Copy {
    const WIDTH: usize;
    /// Puts the child with box `b` in `slot`.
    fn set(&mut self, slot: usize, b: &Bin32Node, child: u32, count: u32);
}

/// A collapsed tree: nodes depth-first (root first), its depth in wide nodes, and its SAH
/// cost under the same constants as the binary tree's (a wide node's visit costs one
/// traversal step, whatever its width).
pub(crate) struct Collapsed<N> {
    pub(crate) nodes: Vec<N>,
    pub(crate) depth: u32,
    pub(crate) sah_cost: f64,
}

/// Fills a wide node greedily by surface area: while `children` has fewer than `width`
/// entries, its largest inner node is replaced, in place, by that node's two children
/// (`split` gives them, `None` for a leaf).
pub(super) fn open_largest(
    children: &mut Vec<usize>,
    width: usize,
    split: impl Fn(usize) -> Option<[usize; 2]>,
    area: impl Fn(usize) -> f64,
) {
    while children.len() < width {
        let Some((k, _)) = children
            .iter()
            .enumerate()
            .filter(|(_, c)| split(**c).is_some())
            .max_by(|a, b| area(*a.1).total_cmp(&area(*b.1)))
        else {
            break;
        };
        let pair = split(children[k]).expect("an inner node splits");
        children.splice(k..=k, pair);
    }
}

/// Collapses the thesis-layout tree into nodes of up to `N::WIDTH` children.
pub(crate) fn collapse<N: WideNode>(flat: &Bin32Bvh) -> Collapsed<N> {
    let nodes = &flat.nodes;
    let area = |n: &Bin32Node| surface_area_f64(Vec3::from(n.min), Vec3::from(n.max));
    let mut out: Vec<N> = Vec::new();
    let mut cost = SahCost::default();
    let mut depth = 0;
    // (binary node, depth) of wide nodes still to fill, and where each is to be written.
    let mut stack = vec![(0usize, 1u32, None::<(usize, usize)>)];
    while let Some((root, d, parent)) = stack.pop() {
        let index = out.len();
        out.push(N::default());
        if let Some((p, slot)) = parent {
            let b = &nodes[root];
            out[p].set(slot, b, index as u32, 0);
        }
        depth = depth.max(d);
        cost.add_inner(area(&nodes[root]));
        let mut children: Vec<usize> = if nodes[root].is_leaf() {
            vec![root]
        } else {
            vec![
                nodes[root].left_or_first as usize,
                nodes[root].right_or_count as usize,
            ]
        };
        open_largest(
            &mut children,
            N::WIDTH,
            |c| {
                let n = &nodes[c];
                (!n.is_leaf()).then_some([n.left_or_first as usize, n.right_or_count as usize])
            },
            |c| area(&nodes[c]),
        );
        // Inner children are visited last-pushed-first: push in reverse to keep order.
        for (slot, &c) in children.iter().enumerate().rev() {
            let n = &nodes[c];
            if n.is_leaf() {
                out[index].set(slot, n, n.left_or_first, n.count());
                cost.add_leaf(area(n), n.count());
            } else {
                stack.push((c, d + 1, Some((index, slot))));
            }
        }
    }
    let root_area = area(&nodes[0]);
    Collapsed {
        nodes: out,
        depth,
        sah_cost: cost.relative_to(root_area).unwrap_or(0.0),
    }
}
