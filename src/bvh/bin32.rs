//! `bin32`, the thesis's layout: 32-byte binary nodes in depth-first order, each holding
//! its own box, and the triangles reordered into leaf order. The builders produce it
//! directly; every other layout is made from it. Also the host's traversal of it,
//! mirroring `trace` in `cl/bin32.cl` step for step: a per-ray stack, nearer child first,
//! boxes farther than the closest hit so far skipped.

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use super::{Bvh, MAX_DEPTH};
use crate::geometry::Ray;
use crate::intersect::{ClosestHit, RayBox, Triangle, WatertightRay, triangles_in_order};
use crate::mesh::Mesh;

/// Marks a leaf in [`Bin32Node::right_or_count`].
pub const LEAF_FLAG: u32 = 0x8000_0000;

/// A 32-byte BVH node as in the thesis: bounds, then two u32. An inner node holds its
/// children's indices; a leaf holds its first triangle and `LEAF_FLAG | count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Bin32Node {
    /// The lowest corner of the node's box (a leaf's: tight around its triangles).
    pub min: [f32; 3],
    /// Inner node: the left child's index, always the next node (depth-first order).
    /// Leaf: the index of its first triangle in [`Bin32Bvh::triangles`].
    pub left_or_first: u32,
    /// The highest corner of the node's box.
    pub max: [f32; 3],
    /// Inner node: the right child's index (below [`LEAF_FLAG`]). Leaf: `LEAF_FLAG` ORed
    /// with its triangle count (at least 1).
    pub right_or_count: u32,
}

impl Bin32Node {
    /// Whether the node is a leaf: [`LEAF_FLAG`] is set in `right_or_count`.
    pub fn is_leaf(&self) -> bool {
        self.right_or_count & LEAF_FLAG != 0
    }

    /// A leaf's triangle count.
    pub fn count(&self) -> u32 {
        self.right_or_count & !LEAF_FLAG
    }

    /// The entry distance into the node's box if the ray meets it before `t_max`.
    #[inline]
    pub(crate) fn hit(&self, ray: &RayBox, t_max: f32) -> Option<f32> {
        ray.hit(&self.min, &self.max, t_max)
    }
}

/// The thesis's device layout: 32-byte nodes in depth-first order and the triangles
/// reordered into leaf order, so that a leaf's triangles are contiguous.
#[derive(Clone, Debug, PartialEq)]
pub struct Bin32Bvh {
    pub(crate) nodes: Vec<Bin32Node>,
    /// The mesh's triangles in leaf order, each carrying its file-order index: a leaf's
    /// `left_or_first` and every hit index into this list.
    pub triangles: Vec<Triangle>,
    /// Nodes on the longest root-to-leaf path; a traversal stack of `depth` entries suffices.
    pub depth: u32,
}

impl Bin32Bvh {
    /// Lays `bvh` out for the device: its nodes as built, and `mesh`'s triangles copied in
    /// the order of [`Bvh::prim_order`] (materials all 0 until assigned).
    pub fn new(bvh: Bvh, mesh: &Mesh) -> Self {
        Bin32Bvh {
            triangles: triangles_in_order(mesh, bvh.prim_order.par_iter().copied()),
            nodes: bvh.nodes,
            depth: bvh.depth,
        }
    }
}

impl ClosestHit for Bin32Bvh {
    fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    fn trace_filtered(
        &self,
        ray: &Ray,
        t_max: f32,
        any_hit: bool,
        keeps: &dyn Fn(usize, &WatertightRay) -> bool,
    ) -> Option<(usize, f32)> {
        let tri_ray = WatertightRay::new(ray);
        let box_ray = RayBox::new(ray);
        let mut t = t_max;
        let mut best = None;
        let mut stack = [(0u32, 0f32); MAX_DEPTH as usize];
        let mut sp = 0;
        self.nodes[0].hit(&box_ray, t)?;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.is_leaf() {
                let first = n.left_or_first as usize;
                for i in first..first + n.count() as usize {
                    if let Some(h) = tri_ray
                        .intersect_stored(&self.triangles[i], t)
                        .filter(|_| keeps(i, &tri_ray))
                    {
                        t = h;
                        best = Some((i, h));
                        if any_hit {
                            return best;
                        }
                    }
                }
            } else {
                let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
                match (
                    self.nodes[l].hit(&box_ray, t),
                    self.nodes[r].hit(&box_ray, t),
                ) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tr < tl { (r, l, tl) } else { (l, r, tr) };
                        stack[sp] = (far as u32, t_far);
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node still nearer than the closest hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let (next, entry) = stack[sp];
                if entry <= t {
                    node = next as usize;
                    break;
                }
            }
        }
    }
}
