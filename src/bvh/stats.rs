//! What a BVH looks like: sizes, depth, leaf sizes, SAH cost, and a structural check.

use glam::Vec3;

use super::{Bvh, MAX_DEPTH, SahCost};
use crate::bvh::Bin32Node;
use crate::geometry::Aabb;
use crate::mesh::Mesh;

/// Summary numbers of a BVH.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhStats {
    pub(crate) triangles: usize,
    pub(crate) nodes: usize,
    pub(crate) leaves: usize,
    pub(crate) depth: u32,
    pub(crate) mean_leaf_size: f64,
    pub(crate) max_leaf_size: u32,
    /// `(C_trav * sum over inner nodes of A(n) + C_isect * sum over leaves of A(l) * N(l)) / A(root)`,
    /// with A the surface area: the expected cost of a random ray that hits the root box.
    pub sah_cost: f64,
}

fn node_box(n: &Bin32Node) -> Aabb {
    Aabb {
        min: Vec3::from(n.min),
        max: Vec3::from(n.max),
    }
}

impl BvhStats {
    pub(crate) fn of(bvh: &Bvh) -> Self {
        use rayon::prelude::*;
        // Chunks summed on every core, then in order: the same sums on every run, and a
        // hundred million nodes in a fraction of a second.
        let chunks: Vec<(usize, u64, u32, SahCost)> = bvh
            .nodes
            .par_chunks(1 << 16)
            .map(|chunk| {
                let (mut leaves, mut leaf_prims, mut max_leaf) = (0, 0u64, 0);
                let mut cost = SahCost::default();
                for n in chunk {
                    let area = node_box(n).surface_area() as f64;
                    if n.is_leaf() {
                        leaves += 1;
                        leaf_prims += n.count() as u64;
                        max_leaf = max_leaf.max(n.count());
                        cost.add_leaf(area, n.count());
                    } else {
                        cost.add_inner(area);
                    }
                }
                (leaves, leaf_prims, max_leaf, cost)
            })
            .collect();
        let (mut leaves, mut leaf_prims, mut max_leaf) = (0, 0u64, 0);
        let mut cost = SahCost::default();
        for (l, p, m, c) in chunks {
            (leaves, leaf_prims, max_leaf) = (leaves + l, leaf_prims + p, max_leaf.max(m));
            cost.add(c);
        }
        let root_area = node_box(&bvh.nodes[0]).surface_area() as f64;
        BvhStats {
            triangles: bvh.prim_order.len(),
            nodes: bvh.nodes.len(),
            leaves,
            depth: bvh.depth,
            mean_leaf_size: leaf_prims as f64 / leaves.max(1) as f64,
            max_leaf_size: max_leaf,
            // A tree whose root box has no area (all triangles in one point or line) costs
            // what its leaves cost.
            sah_cost: cost
                .relative_to(root_area)
                .unwrap_or(leaf_prims as f64 / leaves.max(1) as f64),
        }
    }
}

impl Bvh {
    /// Checks the tree's invariants against its mesh: depth-first order, every triangle in
    /// exactly one leaf, every child box inside its parent's, every leaf box around its
    /// triangles, the depth as recorded and within [`MAX_DEPTH`]. The error says what broke.
    pub fn check(&self, mesh: &Mesh) -> Result<(), String> {
        let n = mesh.triangle_count();
        if self.prim_order.len() != n {
            return Err(format!(
                "{} triangles in the leaf order, {n} in the mesh",
                self.prim_order.len()
            ));
        }
        let mut seen = vec![false; n];
        let mut covered = 0usize;
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1u32)];
        let mut visited = 0;
        while let Some((i, depth)) = stack.pop() {
            visited += 1;
            deepest = deepest.max(depth);
            let node = self
                .nodes
                .get(i)
                .ok_or(format!("node index {i} out of range"))?;
            let b = node_box(node);
            if node.is_leaf() {
                let (first, count) = (node.left_or_first as usize, node.count() as usize);
                if count == 0 || first + count > n || node.left_or_first as usize != first {
                    return Err(format!("leaf {i} has range {first}+{count} of {n}"));
                }
                for &prim in &self.prim_order[first..first + count] {
                    let p = prim as usize;
                    if p >= n || std::mem::replace(&mut seen[p], true) {
                        return Err(format!("triangle {prim} is missing or in two leaves"));
                    }
                    let tri = Aabb::from_points(mesh.corners(p));
                    if !b.contains(&tri) {
                        return Err(format!("leaf {i}'s box does not hold triangle {prim}"));
                    }
                }
                covered += count;
            } else {
                let (l, r) = (node.left_or_first as usize, node.right_or_count as usize);
                if l != i + 1 || r <= l || r >= self.nodes.len() {
                    return Err(format!("node {i} has children {l}, {r}: not depth-first"));
                }
                for c in [l, r] {
                    if !b.contains(&node_box(&self.nodes[c])) {
                        return Err(format!("child {c}'s box is not inside its parent {i}'s"));
                    }
                    stack.push((c, depth + 1));
                }
            }
        }
        if covered != n {
            return Err(format!("leaves cover {covered} triangles of {n}"));
        }
        if visited != self.nodes.len() {
            return Err(format!(
                "{} nodes stored, {visited} reachable",
                self.nodes.len()
            ));
        }
        if deepest != self.depth || deepest > MAX_DEPTH {
            return Err(format!(
                "depth is {deepest}, recorded {}, limit {MAX_DEPTH}",
                self.depth
            ));
        }
        Ok(())
    }
}
