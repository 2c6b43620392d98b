//! The Aila–Laine binary layout ("Understanding the Efficiency of Ray Traversal on GPUs",
//! 2009): each node holds both of its children's boxes, so that one 64-byte fetch tests two
//! children, where the thesis's 32-byte node needs its two children fetched.

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use super::{Bin32Bvh, Bin32Node};

/// A 64-byte node: both children's boxes, then their references. A child with `count` 0 is
/// an inner node (`child` indexes the node array); with `count > 0` it is a leaf of `count`
/// triangles from `child`. Mirrors `Bin64Node` in cl/nodes.cl; cl/bin64.cl traverses it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Bin64Node {
    /// Left child: min.x, max.x, min.y, max.y.
    pub left_xy: [f32; 4],
    /// Right child: min.x, max.x, min.y, max.y.
    pub right_xy: [f32; 4],
    /// min.z, max.z of the left child, then of the right.
    pub z: [f32; 4],
    /// Left child, right child, left count, right count.
    pub refs: [u32; 4],
}

/// Rebuilds a thesis-layout tree in the Aila–Laine layout, depth-first. A tree that is a
/// single leaf gets a root whose two children are that same leaf.
pub(crate) fn to_bvh64(flat: &Bin32Bvh) -> Vec<Bin64Node> {
    let nodes = &flat.nodes;
    let root = &nodes[0];
    if root.is_leaf() {
        return vec![pair(root, root, 0, 0)];
    }
    // Inner nodes keep their depth-first order; number them: a count of the inner nodes
    // before each chunk, then each chunk on its own core.
    const CHUNK: usize = 1 << 16;
    let mut before: Vec<u32> = nodes
        .par_chunks(CHUNK)
        .map(|c| c.iter().filter(|n| !n.is_leaf()).count() as u32)
        .collect();
    let mut sum = 0;
    for b in &mut before {
        (*b, sum) = (sum, sum + *b);
    }
    // Untouched zeroed pages, filled on every core: a single-threaded fill, or a filtered
    // collect into one vector, takes seconds for a hundred million triangles.
    let mut index: Vec<u32> = bytemuck::zeroed_vec(nodes.len());
    index
        .par_chunks_mut(CHUNK)
        .zip(nodes.par_chunks(CHUNK))
        .zip(before.par_iter())
        .for_each(|((index, nodes), &first)| {
            let mut count = first;
            for (i, n) in index.iter_mut().zip(nodes) {
                *i = match n.is_leaf() {
                    true => u32::MAX,
                    false => {
                        count += 1;
                        count - 1
                    }
                };
            }
        });
    let reference = |i: usize| {
        let n = &nodes[i];
        if n.is_leaf() {
            (n.left_or_first, n.count())
        } else {
            (index[i], 0)
        }
    };
    // Each chunk of binary nodes writes its inner nodes to its own run of the output.
    let mut out: Vec<Bin64Node> = bytemuck::zeroed_vec(sum as usize);
    let mut runs = Vec::with_capacity(before.len());
    let mut rest = out.as_mut_slice();
    for (k, &first) in before.iter().enumerate() {
        let next = before.get(k + 1).copied().unwrap_or(sum);
        let (run, tail) = std::mem::take(&mut rest).split_at_mut((next - first) as usize);
        runs.push(run);
        rest = tail;
    }
    runs.into_par_iter()
        .zip(nodes.par_chunks(CHUNK))
        .for_each(|(run, chunk)| {
            let inner = chunk.iter().filter(|n| !n.is_leaf());
            for (slot, n) in run.iter_mut().zip(inner) {
                let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
                let (lref, lcount) = reference(l);
                let (rref, rcount) = reference(r);
                *slot = pair(&nodes[l], &nodes[r], lref, rref);
                slot.refs[2] = lcount;
                slot.refs[3] = rcount;
            }
        });
    out
}

fn pair(l: &Bin32Node, r: &Bin32Node, lref: u32, rref: u32) -> Bin64Node {
    let leaf_count = |n: &Bin32Node| if n.is_leaf() { n.count() } else { 0 };
    Bin64Node {
        left_xy: [l.min[0], l.max[0], l.min[1], l.max[1]],
        right_xy: [r.min[0], r.max[0], r.min[1], r.max[1]],
        z: [l.min[2], l.max[2], r.min[2], r.max[2]],
        refs: [
            if l.is_leaf() { l.left_or_first } else { lref },
            if r.is_leaf() { r.left_or_first } else { rref },
            leaf_count(l),
            leaf_count(r),
        ],
    }
}
