//! Post-build optimization of the binary tree by node reinsertion (Bittner, Hapala, Havran,
//! "Fast Insertion-Based Optimization of Bounding Volume Hierarchies", CGF 2013).
//!
//! The leaves stay as built (the same triangles, the same boxes); only the topology above
//! them changes. One move takes an inner node `N` that wastes area, removes it together
//! with its parent `P` (`N`'s sibling takes `P`'s place), and reinserts `N`'s two children,
//! the larger first, each where it raises the tree's SAH cost least: as the sibling of some
//! node `Y`, under a new inner node (one of the freed `N`, `P`) that takes `Y`'s place. The
//! best `Y` is found by branch and bound from the root: placing `X` beside `Y` costs
//! `A(Y ∪ X)` plus the induced cost, the growth `A(a ∪ X) - A(a)` of every ancestor `a` of
//! `Y`; a subtree whose induced cost plus `A(X)` is no less than the best found so far
//! cannot hold a better place, and the queue visits subtrees in order of induced cost.
//! A place that would make the tree deeper than the limit is passed over, and a move that
//! does not lower the cost in total is undone, so the cost only ever falls.
//!
//! Each round ranks the inner nodes by inefficiency, `M = A(N)^3 / (min(A(L), A(R)) ·
//! (A(L) + A(R)))` (the paper's product of its "area", "min" and "sum" measures), and tries
//! to move the worst `BATCH_SHARE` (10%) of them, one by one, worst first. A node whose move
//! was undone is not tried again in the same pass (unless a kept move reuses it), so that
//! each round tries fresh nodes: ten rounds make a pass over the inner nodes, and then the
//! next pass begins. Rounds stop when the budget is spent or a round lowers the cost by
//! less than [`MIN_ROUND_GAIN`] (0.01%, about 0.1% per pass). The working tree is index-based (a node keeps its index; the freed
//! inner nodes are reused) and is laid out depth-first again at the end, the leaves'
//! triangle ranges copied in the new order.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::{Bvh, INTERSECTION_COST, MAX_DEPTH, TRAVERSAL_COST};
use crate::bvh::{Bin32Node, LEAF_FLAG};
use crate::geometry::Bounds;

/// Rounds stop once one lowers the SAH cost by less than this fraction of it.
pub const MIN_ROUND_GAIN: f64 = 0.0001;

/// The most rounds [`super::BuildOptions::optimize_rounds`] may ask for.
pub const MAX_ROUNDS: u32 = 1000;

/// The share of inner nodes a round tries to move (at least one).
pub(crate) const BATCH_SHARE: f64 = 0.1;

const NONE: u32 = u32::MAX;

/// What [`Bvh::optimize`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OptimizeReport {
    /// Rounds run (the last may have gained less than [`MIN_ROUND_GAIN`]).
    pub rounds: u32,
    /// Moves tried.
    pub attempts: u64,
    /// Moves kept: those that lowered the cost (the others were undone).
    pub moves: u64,
    /// SAH cost ([`super::BvhStats::sah_cost`]) of the tree as it came in.
    pub cost_before: f64,
    /// SAH cost of the optimized tree; never above `cost_before`.
    pub cost_after: f64,
}

impl Bvh {
    /// Lowers the tree's SAH cost by node reinsertion, for at most `rounds` rounds (0 does
    /// nothing), keeping every leaf as it is and the depth within `max_depth` (clamped to
    /// [`MAX_DEPTH`]; a tree already deeper keeps its own depth as the limit). The tree stays
    /// valid: depth-first, boxes tight, `prim_order` reordered to match the leaves; its cost
    /// never rises.
    pub fn optimize(&mut self, rounds: u32, max_depth: u32) -> OptimizeReport {
        let cost_before = self.stats().sah_cost;
        let mut report = OptimizeReport {
            cost_before,
            cost_after: cost_before,
            ..Default::default()
        };
        let limit = max_depth.min(MAX_DEPTH).max(self.depth);
        // A non-root inner node needs five nodes at least; boxes that are not finite (an
        // unchecked mesh) have no meaningful areas to trade.
        if rounds == 0 || self.nodes.len() < 5 || !self.nodes.iter().all(finite) {
            return report;
        }
        let mut tree = Tree::new(self, limit);
        let leaf_area = self
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| Bounds::new(n.min, n.max).half_area() as f64 * n.count() as f64)
            .sum::<f64>();
        // The cost as `BvhStats` weighs it; the leaves' part is fixed, and so is the root's box.
        let root_area = tree.nodes[tree.root as usize].area as f64;
        let cost = |tree: &Tree| {
            (TRAVERSAL_COST as f64 * tree.inner_area() + INTERSECTION_COST as f64 * leaf_area)
                / root_area
        };
        let batch = ((self.nodes.len() / 2) as f64 * BATCH_SHARE).ceil() as usize;
        let mut scratch = Scratch::default();
        let mut current = cost(&tree);
        for _ in 0..rounds {
            let (attempts, moves) = tree.round(batch.max(1), &mut scratch);
            if attempts == 0 {
                break;
            }
            report.rounds += 1;
            report.attempts += attempts;
            report.moves += moves;
            let next = cost(&tree);
            let gain = (current - next) / current;
            current = next;
            // A NaN gain (a zero-cost tree) also stops.
            if gain.is_nan() || gain < MIN_ROUND_GAIN {
                break;
            }
        }
        if report.moves == 0 {
            return report;
        }
        let optimized = tree.to_bvh(self);
        let after = optimized.stats().sah_cost;
        // Every kept move lowered the cost; should rounding in the areas say otherwise, the
        // built tree stays.
        if after <= cost_before {
            *self = optimized;
            report.cost_after = after;
        }
        report
    }
}

/// Asks for `node`'s cache line ahead of its use: the search is bound by memory latency.
#[inline(always)]
fn prefetch<T>(node: &T) {
    // SAFETY: a prefetch is only a hint: it never faults and changes no memory, and SSE
    // is part of every x86-64 target.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
            (node as *const T).cast(),
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = node;
}

fn finite(n: &Bin32Node) -> bool {
    n.min.iter().chain(&n.max).all(|v| v.is_finite())
}

/// A node of the working tree: what the search reads of it, in one 48-byte record.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Bounds,
    /// Half the box's surface area.
    area: f32,
    /// Nodes on the longest path down to a leaf (a leaf's is 1).
    height: u32,
    /// `[NONE, NONE]` for a leaf.
    child: [u32; 2],
}

/// The working tree. Leaves keep their indices in the built tree.
struct Tree {
    nodes: Vec<Node>,
    parent: Vec<u32>,
    /// Inner nodes whose move was tried and undone; rounds skip them.
    settled: Vec<bool>,
    root: u32,
    max_depth: u32,
}

/// A place to look at in the branch-and-bound search: a node, its depth, and the induced
/// cost of placing something inside its subtree.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    induced: f32,
    node: u32,
    depth: u32,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    /// Reversed, so that `BinaryHeap` pops the smallest induced cost first.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .induced
            .total_cmp(&self.induced)
            .then(other.node.cmp(&self.node))
    }
}

#[derive(Default)]
struct Scratch {
    heap: BinaryHeap<Candidate>,
    ranked: Vec<(f64, u32)>,
}

/// Where a removed node `N` and its parent `P` hung: enough to put them back.
struct Removal {
    n: u32,
    p: u32,
    /// `N`'s sibling, and `P`'s parent (or `NONE`).
    s: u32,
    g: u32,
    n_side: usize,
    p_side: usize,
    /// `N`'s children, in order.
    children: [u32; 2],
}

impl Tree {
    fn new(bvh: &Bvh, max_depth: u32) -> Tree {
        let count = bvh.nodes.len();
        let mut nodes: Vec<Node> = bvh
            .nodes
            .iter()
            .map(|n| Node {
                bounds: Bounds::new(n.min, n.max),
                area: 0.0,
                height: 1,
                child: [NONE, NONE],
            })
            .collect();
        let mut parent = vec![NONE; count];
        // Children come after their parent in depth-first order: fill in bottom-up, making
        // inner boxes exact unions of their children's.
        for i in (0..count).rev() {
            let n = &bvh.nodes[i];
            if !n.is_leaf() {
                let (l, r) = (n.left_or_first, n.right_or_count);
                parent[l as usize] = i as u32;
                parent[r as usize] = i as u32;
                let (a, b) = (nodes[l as usize], nodes[r as usize]);
                nodes[i].child = [l, r];
                nodes[i].bounds = a.bounds.union(b.bounds);
                nodes[i].height = 1 + a.height.max(b.height);
            }
            nodes[i].area = nodes[i].bounds.half_area();
        }
        Tree {
            nodes,
            parent,
            settled: vec![false; count],
            root: 0,
            max_depth,
        }
    }

    /// Sum of the inner nodes' half areas (between moves every node is in the tree).
    fn inner_area(&self) -> f64 {
        self.nodes
            .iter()
            .filter(|n| n.child[0] != NONE)
            .map(|n| n.area as f64)
            .sum()
    }

    /// Which child of `p` the node `c` is.
    #[inline]
    fn side(&self, p: u32, c: u32) -> usize {
        (self.nodes[p as usize].child[1] == c) as usize
    }

    /// Puts `new` where `old` hangs (under `old`'s parent, or as the root).
    fn replace(&mut self, old: u32, new: u32) {
        let g = self.parent[old as usize];
        if g == NONE {
            self.root = new;
        } else {
            let side = self.side(g, old);
            self.nodes[g as usize].child[side] = new;
        }
        self.parent[new as usize] = g;
    }

    /// Recomputes the box, area and height of inner node `i` from its children; returns
    /// whether anything changed.
    #[inline]
    fn recompute(&mut self, i: u32) -> bool {
        let [l, r] = self.nodes[i as usize].child;
        let (l, r) = (self.nodes[l as usize], self.nodes[r as usize]);
        let bounds = l.bounds.union(r.bounds);
        let height = 1 + l.height.max(r.height);
        let n = &mut self.nodes[i as usize];
        let changed = bounds != n.bounds || height != n.height;
        n.bounds = bounds;
        n.height = height;
        n.area = bounds.half_area();
        changed
    }

    /// Refits `i` and its ancestors, stopping where nothing changes. Returns the change in
    /// the sum of their areas.
    fn refit(&mut self, mut i: u32) -> f64 {
        let mut delta = 0.0;
        while i != NONE {
            let before = self.nodes[i as usize].area;
            if !self.recompute(i) {
                break;
            }
            delta += self.nodes[i as usize].area as f64 - before as f64;
            i = self.parent[i as usize];
        }
        delta
    }

    /// The inner nodes that may move and are not settled, with their inefficiency.
    fn rank(&self, ranked: &mut Vec<(f64, u32)>) {
        ranked.clear();
        for (i, n) in self.nodes.iter().enumerate() {
            // The root has no parent to remove with it (it can still move as a child).
            if n.child[0] == NONE || i as u32 == self.root || self.settled[i] {
                continue;
            }
            let [l, r] = n.child.map(|c| self.nodes[c as usize].area as f64);
            let a = n.area as f64;
            let m = if a > 0.0 {
                a * a * a / (l.min(r) * (l + r)).max(f64::MIN_POSITIVE)
            } else {
                0.0
            };
            ranked.push((m, i as u32));
        }
    }

    /// One round: ranks the inner nodes not yet settled by inefficiency and tries to move
    /// the `batch` worst. Returns the moves tried and kept.
    fn round(&mut self, batch: usize, scratch: &mut Scratch) -> (u64, u64) {
        let mut ranked = std::mem::take(&mut scratch.ranked);
        self.rank(&mut ranked);
        if ranked.len() < batch {
            // (Nearly) every node has been tried since its last change: start a new pass.
            self.settled.fill(false);
            self.rank(&mut ranked);
        }
        let worst_first = |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
        if batch < ranked.len() {
            ranked.select_nth_unstable_by(batch - 1, worst_first);
            ranked.truncate(batch);
        }
        ranked.sort_unstable_by(worst_first);
        let (mut attempts, mut moves) = (0, 0);
        for &(_, n) in &ranked {
            let p = self.parent[n as usize];
            if p == NONE {
                continue;
            }
            attempts += 1;
            if self.reinsert(n, &mut scratch.heap) {
                moves += 1;
                // Both now stand elsewhere, as new nodes.
                self.settled[p as usize] = false;
            } else {
                self.settled[n as usize] = true;
            }
        }
        scratch.ranked = ranked;
        (attempts, moves)
    }

    /// Removes inner node `n` (not the root) with its parent and reinserts its children at
    /// their best places; undoes it all unless the cost falls. Returns whether the move was
    /// kept.
    fn reinsert(&mut self, n: u32, heap: &mut BinaryHeap<Candidate>) -> bool {
        let p = self.parent[n as usize];
        let g = self.parent[p as usize];
        let n_side = self.side(p, n);
        let children = self.nodes[n as usize].child;
        let removal = Removal {
            n,
            p,
            s: self.nodes[p as usize].child[1 - n_side],
            g,
            n_side,
            p_side: if g == NONE { 0 } else { self.side(g, p) },
            children,
        };
        let mut delta = -(self.nodes[n as usize].area as f64 + self.nodes[p as usize].area as f64);
        self.replace(p, removal.s);
        delta += self.refit(g);

        let [a, b] = children;
        let (first, second) = if self.nodes[a as usize].area >= self.nodes[b as usize].area {
            (a, b)
        } else {
            (b, a)
        };
        let mut inserted = 0;
        for (x, z) in [(first, p), (second, n)] {
            let Some(y) = self.best_place(x, heap) else {
                break;
            };
            delta += self.insert(x, z, y);
            inserted += 1;
        }
        if inserted == 2 && delta < 0.0 {
            return true;
        }
        // Undo: take the inserted children out again, latest first, then restore N and P.
        for x in [second, first].into_iter().skip(2 - inserted) {
            let z = self.parent[x as usize];
            let y = self.nodes[z as usize].child[1 - self.side(z, x)];
            self.replace(z, y);
            let above = self.parent[y as usize];
            self.refit(above);
        }
        self.restore(&removal);
        false
    }

    /// Puts `N` and `P` back as they were.
    fn restore(&mut self, r: &Removal) {
        if r.g == NONE {
            self.root = r.p;
        } else {
            self.nodes[r.g as usize].child[r.p_side] = r.p;
        }
        self.parent[r.p as usize] = r.g;
        let mut p_children = [r.n; 2];
        p_children[1 - r.n_side] = r.s;
        self.nodes[r.p as usize].child = p_children;
        self.parent[r.s as usize] = r.p;
        self.parent[r.n as usize] = r.p;
        self.nodes[r.n as usize].child = r.children;
        for c in r.children {
            self.parent[c as usize] = r.n;
        }
        // N and P were reused, so their stored boxes are stale: recompute both outright.
        self.recompute(r.n);
        self.recompute(r.p);
        self.refit(r.g);
    }

    /// Hangs `x` beside `y` under the free inner node `z`, which takes `y`'s place. Returns
    /// the change in the sum of inner areas.
    fn insert(&mut self, x: u32, z: u32, y: u32) -> f64 {
        self.replace(y, z);
        self.nodes[z as usize].child = [y, x];
        self.parent[y as usize] = z;
        self.parent[x as usize] = z;
        self.recompute(z);
        let above = self.parent[z as usize];
        self.nodes[z as usize].area as f64 + self.refit(above)
    }

    /// The node beside which `x` (detached) costs least, within the depth limit: branch and
    /// bound over the tree, subtrees in order of induced cost.
    fn best_place(&self, x: u32, heap: &mut BinaryHeap<Candidate>) -> Option<u32> {
        let Node {
            bounds: bx,
            area: ax,
            height: hx,
            ..
        } = self.nodes[x as usize];
        let mut best_cost = f32::INFINITY;
        let mut best = None;
        heap.clear();
        heap.push(Candidate {
            induced: 0.0,
            node: self.root,
            depth: 1,
        });
        while let Some(c) = heap.pop() {
            // Every place left costs at least its induced cost plus x's own area.
            if c.induced + ax >= best_cost {
                break;
            }
            let y = &self.nodes[c.node as usize];
            let grown = y.bounds.union(bx).half_area();
            let cost = c.induced + grown;
            if cost < best_cost && c.depth + hx.max(y.height) <= self.max_depth {
                best_cost = cost;
                best = Some(c.node);
            }
            if y.child[0] != NONE {
                let induced = c.induced + (grown - y.area);
                if induced + ax < best_cost {
                    for node in y.child {
                        prefetch(&self.nodes[node as usize]);
                        heap.push(Candidate {
                            induced,
                            node,
                            depth: c.depth + 1,
                        });
                    }
                }
            }
        }
        best
    }

    /// Lays the tree out depth-first, the leaves (and their triangle ranges) copied from
    /// `built` in the new order.
    fn to_bvh(&self, built: &Bvh) -> Bvh {
        let mut nodes: Vec<Bin32Node> = Vec::with_capacity(built.nodes.len());
        let mut prim_order = Vec::with_capacity(built.prim_order.len());
        let mut depth = 0;
        // (node, the index of the parent whose right child it is or NONE, its depth)
        let mut stack = vec![(self.root, NONE, 1u32)];
        while let Some((i, right_of, d)) = stack.pop() {
            let index = nodes.len() as u32;
            if right_of != NONE {
                nodes[right_of as usize].right_or_count = index;
            }
            depth = depth.max(d);
            let n = &self.nodes[i as usize];
            if n.child[0] == NONE {
                let leaf = built.nodes[i as usize];
                let (first, count) = (leaf.left_or_first as usize, leaf.count() as usize);
                nodes.push(Bin32Node {
                    left_or_first: prim_order.len() as u32,
                    right_or_count: LEAF_FLAG | count as u32,
                    ..leaf
                });
                prim_order.extend_from_slice(&built.prim_order[first..first + count]);
            } else {
                nodes.push(Bin32Node {
                    min: n.bounds.min.to_array(),
                    left_or_first: index + 1,
                    max: n.bounds.max.to_array(),
                    right_or_count: 0,
                });
                stack.push((n.child[1], index, d + 1));
                stack.push((n.child[0], NONE, d + 1));
            }
        }
        Bvh {
            nodes,
            prim_order,
            depth,
        }
    }
}
