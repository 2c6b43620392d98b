//! Top-down SAH construction.
//!
//! Each node's triangles are split in two by a plane chosen under the surface area
//! heuristic: binned over centroids on all three axes (Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", 2007), or by an exact sweep over every
//! centroid-sorted position. Large nodes bin and partition in parallel, and subtrees build
//! in parallel.
//!
//! Each triangle is kept as a 32-byte record, its box with its mesh index, in one of two
//! buffers of the mesh's size. A node owns the same range of both: its triangles sit in
//! one, and a split writes the two children into the other (a stable, out-of-place
//! partition: one read and one write per triangle, where an in-place one reads and writes
//! two), so each level of the tree alternates buffers. A leaf writes its mesh indices to
//! [`Bvh::prim_order`]. Centroids are kept doubled (`min + max`): only their order and the
//! boxes around them matter, and the halving would cost a multiply per triangle at every
//! level.
//!
//! Nodes are stored in depth-first order as they are made. Large nodes split and hand
//! their two halves to parallel tasks; each task writes its subtree into its own compact
//! vector, and one pass at the end lays the tasks' vectors out behind the few shared top
//! nodes, shifting child indices, into the two triangle buffers (records of the node's
//! size, and at most `2n - 1` nodes for `n` triangles), so that the nodes need no memory of
//! their own: on a virtual machine a page's first touch costs over a microsecond.

use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::{BuildOptions, Builder, Bvh, INTERSECTION_COST, TRAVERSAL_COST};
use crate::bvh::{Bin32Node, LEAF_FLAG};
use crate::geometry::Bounds;
use crate::mesh::Mesh;

/// Nodes with more triangles than this build their two subtrees in parallel.
const PARALLEL_SUBTREES: usize = 1 << 14;
/// Nodes with more triangles than this bin and partition in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;
/// Triangles per chunk of the parallel passes.
const CHUNK: usize = 1 << 14;
/// The most bins per axis [`BuildOptions::bins`] may ask for (a power of two).
pub(super) const MAX_BINS: usize = 64;

/// A box as the node that holds it.
trait NodeBox {
    fn node(&self, left_or_first: u32, right_or_count: u32) -> Bin32Node;
}

impl NodeBox for Bounds {
    fn node(&self, left_or_first: u32, right_or_count: u32) -> Bin32Node {
        Bin32Node {
            min: self.min.to_array(),
            left_or_first,
            max: self.max.to_array(),
            right_or_count,
        }
    }
}

/// A triangle as the builder moves it: a record in the shape of a [`Bin32Node`], its box
/// with its mesh index in `left_or_first` (`right_or_count` is zero).
type Prim = Bin32Node;

/// The triangle with mesh index `id` and box `b`.
fn prim(b: &Bounds, id: u32) -> Prim {
    b.node(id, 0)
}

/// The triangle's box corners as two SIMD vectors of four lanes: the mesh index rides
/// along in the fourth lane of `min`, and 0.0 in that of `max`.
#[inline(always)]
fn lanes_of(p: &Prim) -> (Vec4, Vec4) {
    let [min, max]: [[f32; 4]; 2] = bytemuck::cast(*p);
    (Vec4::from_array(min), Vec4::from_array(max))
}

/// The triangle's box (box arithmetic ignores the fourth lanes).
#[inline(always)]
fn bounds_of(p: &Prim) -> Bounds {
    let (min, max) = lanes_of(p);
    Bounds {
        min: Vec3A::from_vec4(min),
        max: Vec3A::from_vec4(max),
    }
}

/// Twice the box's centroid, `min + max`: what the builder bins and sorts by.
#[inline(always)]
fn centroid2(b: &Bounds) -> Vec3A {
    b.min + b.max
}

/// A node's box and the box of its triangles' doubled centroids.
type Side = (Bounds, Bounds);

fn union_sides(a: Side, b: Side) -> Side {
    (a.0.union(b.0), a.1.union(b.1))
}

/// The triangles of one node where they are now, and the same range of the other buffer,
/// where a split writes the children.
struct Prims<'a> {
    prims: &'a mut [Prim],
    spare: &'a mut [Prim],
    /// The node's range of [`Bvh::prim_order`], which its leaves fill in.
    order: &'a mut [u32],
    /// Position of `prims[0]` in the whole leaf order.
    first: u32,
}

impl<'a> Prims<'a> {
    fn len(&self) -> usize {
        self.prims.len()
    }

    /// The two children, once a split has written the node's triangles to the spare
    /// buffer with the left child's in `[0, mid)`: each child's triangles are in its part
    /// of the spare buffer, and its part of the current one is its spare.
    fn children(self, mid: usize) -> (Prims<'a>, Prims<'a>) {
        let (lp, rp) = self.spare.split_at_mut(mid);
        let (ls, rs) = self.prims.split_at_mut(mid);
        let (lo, ro) = self.order.split_at_mut(mid);
        (
            Prims {
                prims: lp,
                spare: ls,
                order: lo,
                first: self.first,
            },
            Prims {
                prims: rp,
                spare: rs,
                order: ro,
                first: self.first + mid as u32,
            },
        )
    }

    /// Makes the triangles a leaf: writes their mesh indices to the leaf order.
    fn settle(self) {
        for (o, p) in self.order.iter_mut().zip(self.prims.iter()) {
            *o = p.left_or_first;
        }
    }

    /// Writes the triangles to the spare buffer in a new order: position `i` takes what
    /// is at `order[i]`.
    fn gather(&mut self, order: impl IntoIterator<Item = u32>) {
        for (p, i) in self.spare.iter_mut().zip(order) {
            *p = self.prims[i as usize];
        }
    }
}

/// The outcome of looking for a split.
enum Split {
    /// Make a leaf: cheaper than any split (only offered when the node may be a leaf).
    Leaf,
    /// The triangles are in the spare buffer, `[0, mid)` going left, with the children's
    /// boxes and centroid boxes.
    At { mid: usize, left: Side, right: Side },
    /// No plane separates the centroids: split by count instead.
    None,
}

struct Ctx {
    options: BuildOptions,
}

/// Working memory reused from node to node (one per thread of the build), so that the
/// millions of small nodes allocate nothing.
struct Scratch {
    bins: BinTable,
    order: Vec<u32>,
    keys: Vec<u64>,
    right_area: Vec<f32>,
}

impl Scratch {
    fn new(bins: usize) -> Self {
        Scratch {
            bins: BinTable::new(bins),
            order: Vec::new(),
            keys: Vec::new(),
            right_area: Vec::new(),
        }
    }
}

pub(super) fn build(mesh: &Mesh, options: &BuildOptions) -> Bvh {
    let n = mesh.triangle_count();
    assert!(n > 0, "a checked mesh has triangles");
    // Both triangle buffers in one allocation, which holds the nodes in the end. Written in
    // parallel from the start: zeroed memory would come from the system untouched only the
    // first time, and be cleared by one thread after that.
    let mut work: Vec<Prim> = Vec::with_capacity(2 * n);
    work.par_extend((0..n).into_par_iter().map(|t| {
        let [a, b, c] = mesh.corners(t).map(Vec3A::from);
        let b = Bounds {
            min: a.min(b).min(c),
            max: a.max(b).max(c),
        };
        prim(&b, t as u32)
    }));
    work.par_extend(rayon::iter::repeat_n(Prim::default(), n));
    let mut order: Vec<u32> = Vec::with_capacity(n);
    order.par_extend(rayon::iter::repeat_n(0, n));
    let (prims, spare) = work.split_at_mut(n);
    // The root's box and centroid box.
    let empty = (Bounds::EMPTY, Bounds::EMPTY);
    let bounds = prims
        .par_chunks(CHUNK)
        .map(side_bounds)
        .reduce(|| empty, union_sides);
    let prims = Prims {
        prims,
        spare,
        order: &mut order,
        first: 0,
    };
    let ctx = Ctx { options: *options };
    let (tree, depth) = ctx.top(prims, bounds, 1, &mut Scratch::new(options.bins as usize));
    // A binary tree over at most n leaves has at most 2n - 1 nodes.
    work.truncate(tree.node_count());
    tree.lay_out(&mut work, 0);
    // Returns the triangle buffers' tail to the system (glibc shrinks in place).
    work.shrink_to_fit();
    Bvh {
        nodes: work,
        prim_order: order,
        depth,
    }
}

/// The tree as the parallel build leaves it: shared top nodes over tasks' subtrees.
enum Subtree {
    /// A task's subtree, compact and depth-first, child indices counted from its start.
    Nodes(Vec<Bin32Node>),
    /// A top node (its child indices not yet known), its two halves, and its node count.
    Split(Bin32Node, Box<(Subtree, Subtree)>, usize),
}

impl Subtree {
    fn split(node: Bin32Node, left: Subtree, right: Subtree) -> Self {
        let count = 1 + left.node_count() + right.node_count();
        Subtree::Split(node, Box::new((left, right)), count)
    }

    fn node_count(&self) -> usize {
        match self {
            Subtree::Nodes(v) => v.len(),
            Subtree::Split(.., count) => *count,
        }
    }

    /// Writes the subtree depth-first into `out` (exactly its size), whose first node has
    /// global index `offset`; the halves of top nodes are written in parallel.
    fn lay_out(self, out: &mut [Bin32Node], offset: u32) {
        match self {
            Subtree::Nodes(v) => {
                for (slot, mut node) in out.iter_mut().zip(v) {
                    if !node.is_leaf() {
                        node.left_or_first += offset;
                        node.right_or_count += offset;
                    }
                    *slot = node;
                }
            }
            Subtree::Split(mut node, halves, _) => {
                let (left, right) = *halves;
                let left_count = left.node_count();
                node.left_or_first = offset + 1;
                node.right_or_count = offset + 1 + left_count as u32;
                out[0] = node;
                let (lo, ro) = out[1..].split_at_mut(left_count);
                rayon::join(
                    || left.lay_out(lo, offset + 1),
                    || right.lay_out(ro, offset + 1 + left_count as u32),
                );
            }
        }
    }
}

impl Ctx {
    /// Builds the subtree over `prims` at `depth` (the root is 1), in parallel while it is
    /// large. Returns it and its deepest level.
    fn top(
        &self,
        mut prims: Prims,
        bounds: Side,
        depth: u32,
        scratch: &mut Scratch,
    ) -> (Subtree, u32) {
        if prims.len() <= PARALLEL_SUBTREES {
            let mut nodes = Vec::with_capacity(2 * prims.len());
            let depth = self.node(prims, bounds, depth, &mut nodes, scratch);
            return (Subtree::Nodes(nodes), depth);
        }
        let Some((mid, left, right)) = self.split(&mut prims, bounds, depth, scratch) else {
            let leaf = bounds.0.node(prims.first, LEAF_FLAG | prims.len() as u32);
            prims.settle();
            return (Subtree::Nodes(vec![leaf]), depth);
        };
        let (lp, rp) = prims.children(mid);
        let ((l, dl), (r, dr)) = rayon::join(
            || self.top(lp, left, depth + 1, scratch),
            || {
                self.top(
                    rp,
                    right,
                    depth + 1,
                    &mut Scratch::new(self.options.bins as usize),
                )
            },
        );
        (Subtree::split(bounds.0.node(0, 0), l, r), dl.max(dr))
    }

    /// Builds the subtree over `prims` at `depth` onto the end of `out`, depth-first with
    /// indices counted from `out`'s start. Returns the subtree's deepest level.
    fn node(
        &self,
        mut prims: Prims,
        bounds: Side,
        depth: u32,
        out: &mut Vec<Bin32Node>,
        scratch: &mut Scratch,
    ) -> u32 {
        let index = out.len();
        match self.split(&mut prims, bounds, depth, scratch) {
            None => {
                out.push(bounds.0.node(prims.first, LEAF_FLAG | prims.len() as u32));
                prims.settle();
                depth
            }
            Some((mid, left, right)) => {
                out.push(bounds.0.node(index as u32 + 1, 0));
                let (lp, rp) = prims.children(mid);
                let dl = self.node(lp, left, depth + 1, out, scratch);
                out[index].right_or_count = out.len() as u32;
                let dr = self.node(rp, right, depth + 1, out, scratch);
                dl.max(dr)
            }
        }
    }

    /// Decides a node: `None` for a leaf, else the split position with both children's
    /// boxes and centroid boxes, the triangles written to the spare buffer in the
    /// children's order.
    fn split(
        &self,
        prims: &mut Prims,
        (bounds, centroids): Side,
        depth: u32,
        scratch: &mut Scratch,
    ) -> Option<(usize, Side, Side)> {
        let n = prims.len();
        let max_leaf = self.options.max_leaf_size as usize;
        let max_depth = self.options.max_depth;
        if n == 1 || depth >= max_depth {
            return None;
        }
        // Median splits from depth d reach leaves by d + ceil(log2(n / max_leaf)): switch to
        // them while that still fits under the maximum depth.
        let balanced_depth = depth + n.div_ceil(max_leaf).next_power_of_two().trailing_zeros();
        let split = if balanced_depth + 1 >= max_depth {
            Split::None
        } else {
            match self.options.builder {
                Builder::Binned if n > SMALL => {
                    self.binned_split(prims, bounds, centroids, n <= max_leaf, &mut scratch.bins)
                }
                _ if n <= SMALL => small_sweep_split(prims, bounds, n <= max_leaf),
                _ => sweep_split(prims, bounds, n <= max_leaf, scratch),
            }
        };
        match split {
            Split::Leaf => None,
            Split::At { mid, left, right } => {
                debug_assert!(mid > 0 && mid < n, "a split leaves both sides triangles");
                Some((mid, left, right))
            }
            Split::None if n <= max_leaf => None,
            Split::None => Some(median_split(prims, centroids)),
        }
    }

    /// Bins the centroids on all three axes, picks the cheapest plane between bins, and
    /// partitions the triangles into the spare buffer.
    fn binned_split(
        &self,
        prims: &mut Prims,
        bounds: Bounds,
        centroids: Bounds,
        may_be_leaf: bool,
        table: &mut BinTable,
    ) -> Split {
        // Small nodes use fewer bins: a few triangles gain nothing from many planes.
        let bins = (self.options.bins as usize).min((prims.len() / 4).max(8));
        let grid = Grid::new(centroids, bins);
        if prims.len() > PARALLEL_BINNING {
            return parallel_binned_split(prims, bounds, &grid, may_be_leaf);
        }
        table.add(prims.prims, &grid);
        let Some(plane) = table.best_plane(&grid) else {
            return Split::None;
        };
        if may_be_leaf && leaf_is_cheaper(prims.len(), bounds.half_area(), plane.cost) {
            return Split::Leaf;
        }
        let (left_box, right_box) = table.side_boxes(&plane);
        let (lc, rc) = partition(&grid, &plane, prims.prims, prims.spare);
        Split::At {
            mid: plane.left_count,
            left: (left_box, lc),
            right: (right_box, rc),
        }
    }
}

/// [`Ctx::binned_split`] for a large node: each chunk of triangles is binned by a task of
/// its own, and then partitioned by one, straight to its place on each side (the chunk's
/// bins say how many of its triangles go left).
fn parallel_binned_split(
    prims: &mut Prims,
    bounds: Bounds,
    grid: &Grid,
    may_be_leaf: bool,
) -> Split {
    let tables: Vec<BinTable> = prims
        .prims
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut t = BinTable::new(grid.bins);
            t.add(chunk, grid);
            t
        })
        .collect();
    let mut total = BinTable::new(grid.bins);
    for t in &tables {
        total.merge(t);
    }
    let Some(plane) = total.best_plane(grid) else {
        return Split::None;
    };
    if may_be_leaf && leaf_is_cheaper(prims.len(), bounds.half_area(), plane.cost) {
        return Split::Leaf;
    }
    let (left_box, right_box) = total.side_boxes(&plane);
    let (mut left, mut right) = prims.spare.split_at_mut(plane.left_count);
    let mut jobs = Vec::with_capacity(tables.len());
    for (src, t) in prims.prims.chunks(CHUNK).zip(&tables) {
        let l = t.count_left_of(&plane);
        let (l_j, l_rest) = std::mem::take(&mut left).split_at_mut(l);
        let (r_j, r_rest) = std::mem::take(&mut right).split_at_mut(src.len() - l);
        (left, right) = (l_rest, r_rest);
        jobs.push((src, l_j, r_j));
    }
    let empty = (Bounds::EMPTY, Bounds::EMPTY);
    let (lc, rc) = jobs
        .into_par_iter()
        .map(|(src, l, r)| partition_sides(grid, &plane, src, l, r))
        .reduce(|| empty, union_sides);
    Split::At {
        mid: plane.left_count,
        left: (left_box, lc),
        right: (right_box, rc),
    }
}

/// Where doubled centroids fall among a node's bins on each axis.
struct Grid {
    /// The low corner of the centroid box.
    origin: Vec3A,
    /// Bins per unit length on each axis; zero on an axis with no extent to bin.
    scale: Vec3A,
    /// The last bin's index in every lane.
    last: Vec3A,
    bins: usize,
}

impl Grid {
    fn new(centroids: Bounds, bins: usize) -> Grid {
        let extent = centroids.max - centroids.min;
        // Slightly under `bins / extent`, so the largest centroid still lands in the last
        // bin. An extent so thin that the scale overflows counts as flat.
        let scale = Vec3A::splat(bins as f32 * (1.0 - 1e-6)) / extent;
        let usable = extent.cmpgt(Vec3A::ZERO) & scale.is_finite_mask();
        Grid {
            origin: centroids.min,
            scale: Vec3A::select(usable, scale, Vec3A::ZERO),
            last: Vec3A::splat((bins - 1) as f32),
            bins,
        }
    }

    /// Whether the axis has bins to choose between.
    fn usable(&self, axis: usize) -> bool {
        self.scale[axis] > 0.0
    }

    /// The doubled centroid's position in bin units on each axis, in `[0, bins - 1]`
    /// (the clamp only matters for an unchecked mesh: it takes NaN to 0); the bin is its
    /// integer part.
    #[inline(always)]
    fn position(&self, c2: Vec3A) -> Vec3A {
        ((c2 - self.origin) * self.scale)
            .max(Vec3A::ZERO)
            .min(self.last)
    }

    /// The bin on each axis of the doubled centroid in the first three lanes of `c2`.
    #[inline(always)]
    fn bins_of(&self, c2: Vec4) -> [u32; 4] {
        let p = self.position(Vec3A::from_vec4(c2));
        // One truncating conversion for all lanes; `as` would convert, and saturate, each.
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::_mm_cvttps_epi32;
            // SAFETY: SSE2 is part of every x86-64 target, and the conversion touches no
            // memory.
            bytemuck::cast(unsafe { _mm_cvttps_epi32(p.into()) })
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            [p.x as u32, p.y as u32, p.z as u32, 0]
        }
    }
}

/// A candidate split plane between bins.
struct Plane {
    /// `sum of half-area * count` over both sides.
    cost: f32,
    axis: usize,
    /// The first bin on the right.
    bin: usize,
    /// Triangles on the left.
    left_count: usize,
}

/// Moves the triangles to the spare buffer, the plane's left side first, keeping their
/// order (without branches: data-dependent branches mispredict half the time near the
/// root). Returns both sides' centroid boxes.
fn partition(grid: &Grid, plane: &Plane, src: &[Prim], dst: &mut [Prim]) -> (Bounds, Bounds) {
    #[inline(always)]
    fn go<const AXIS: usize>(
        grid: &Grid,
        plane: &Plane,
        src: &[Prim],
        dst: &mut [Prim],
    ) -> (Bounds, Bounds) {
        // floor(p) < bin exactly when p < bin, p being the same position the binning
        // truncated: the sides hold what the bins counted.
        let split = Vec3A::splat(plane.bin as f32);
        let (mut lc, mut rc) = (Bounds::EMPTY, Bounds::EMPTY);
        let (mut l, mut r) = (0, plane.left_count);
        for p in src {
            let c = centroid2(&bounds_of(p));
            let left = SideMask::below::<AXIS>(grid.position(c), split);
            let is_left = left.is_set();
            dst[if is_left { l } else { r }] = *p;
            l += is_left as usize;
            r += !is_left as usize;
            left.grow(&mut lc, &mut rc, c);
        }
        (lc, rc)
    }
    match plane.axis {
        0 => go::<0>(grid, plane, src, dst),
        1 => go::<1>(grid, plane, src, dst),
        _ => go::<2>(grid, plane, src, dst),
    }
}

/// Which side of the plane a triangle goes to, in every lane of a SIMD mask: the
/// partition steers its centroid into one side's box without a branch.
#[derive(Clone, Copy)]
struct SideMask(
    #[cfg(target_arch = "x86_64")] std::arch::x86_64::__m128,
    #[cfg(not(target_arch = "x86_64"))] bool,
);

#[cfg(target_arch = "x86_64")]
impl SideMask {
    /// Set where lane `AXIS` of `p` is below that of `split`.
    #[inline(always)]
    fn below<const AXIS: usize>(p: Vec3A, split: Vec3A) -> SideMask {
        use std::arch::x86_64::{_mm_cmplt_ps, _mm_shuffle_ps};
        // SAFETY (this block and the others in this impl): SSE2 is part of every x86-64
        // target, and these touch no memory.
        unsafe {
            let m = _mm_cmplt_ps(p.into(), split.into());
            SideMask(match AXIS {
                0 => _mm_shuffle_ps::<0x00>(m, m),
                1 => _mm_shuffle_ps::<0x55>(m, m),
                _ => _mm_shuffle_ps::<0xaa>(m, m),
            })
        }
    }

    #[inline(always)]
    fn is_set(self) -> bool {
        use std::arch::x86_64::_mm_movemask_ps;
        unsafe { _mm_movemask_ps(self.0) & 1 != 0 }
    }

    /// Grows `left` by `c` where the mask is set, `right` where it is clear. SSE's min and
    /// max return their second operand where the first is NaN, so `c` with every bit set
    /// (a NaN) in the lanes of the other side leaves that side's box as it is.
    #[inline(always)]
    fn grow(self, left: &mut Bounds, right: &mut Bounds, c: Vec3A) {
        use std::arch::x86_64::{
            __m128, _mm_andnot_ps, _mm_cmpeq_ps, _mm_max_ps, _mm_min_ps, _mm_or_ps,
        };
        unsafe {
            let c: __m128 = c.into();
            let m = self.0;
            let ones = _mm_cmpeq_ps(m, m);
            let for_left = _mm_or_ps(c, _mm_andnot_ps(m, ones));
            let for_right = _mm_or_ps(c, m);
            left.min = _mm_min_ps(for_left, left.min.into()).into();
            left.max = _mm_max_ps(for_left, left.max.into()).into();
            right.min = _mm_min_ps(for_right, right.min.into()).into();
            right.max = _mm_max_ps(for_right, right.max.into()).into();
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl SideMask {
    #[inline(always)]
    fn below<const AXIS: usize>(p: Vec3A, split: Vec3A) -> SideMask {
        SideMask(p[AXIS] < split[AXIS])
    }

    #[inline(always)]
    fn is_set(self) -> bool {
        self.0
    }

    #[inline(always)]
    fn grow(self, left: &mut Bounds, right: &mut Bounds, c: Vec3A) {
        if self.0 { left.grow(c) } else { right.grow(c) }
    }
}

/// [`partition`] of one chunk of a large node, its left side to `left` and its right
/// side to `right` (separate slices, as the chunks' sides interleave).
fn partition_sides(
    grid: &Grid,
    plane: &Plane,
    src: &[Prim],
    left: &mut [Prim],
    right: &mut [Prim],
) -> (Bounds, Bounds) {
    #[inline(always)]
    fn go<const AXIS: usize>(
        grid: &Grid,
        plane: &Plane,
        src: &[Prim],
        left: &mut [Prim],
        right: &mut [Prim],
    ) -> (Bounds, Bounds) {
        let split = plane.bin as f32;
        let (mut lc, mut rc) = (Bounds::EMPTY, Bounds::EMPTY);
        let (mut l, mut r) = (0, 0);
        for p in src {
            let c = centroid2(&bounds_of(p));
            // Near the root the sides come in long runs (a mesh's neighbouring triangles
            // are near each other), so this branch predicts well.
            if grid.position(c)[AXIS] < split {
                left[l] = *p;
                l += 1;
                lc.grow(c);
            } else {
                right[r] = *p;
                r += 1;
                rc.grow(c);
            }
        }
        (lc, rc)
    }
    match plane.axis {
        0 => go::<0>(grid, plane, src, left, right),
        1 => go::<1>(grid, plane, src, left, right),
        _ => go::<2>(grid, plane, src, left, right),
    }
}

/// Whether keeping `n` triangles in a leaf costs no more than splitting them, given the
/// split's `sum of half-area * count` over both children and the node's half-area.
fn leaf_is_cheaper(n: usize, half_area: f32, split: f32) -> bool {
    INTERSECTION_COST * n as f32 * half_area
        <= TRAVERSAL_COST * half_area + INTERSECTION_COST * split
}

/// A bin while triangles are added: the box of those whose centroid falls in it, with
/// their count in the fourth lane of `max`. A triangle's `max` has 0.0 in that lane (its
/// record's `right_or_count` is zero), so the maximum keeps the count and adding
/// [`Vec4::W`] counts the triangle: a bin takes a triangle in one update of two vectors.
#[derive(Clone, Copy)]
struct Bin {
    min: Vec4,
    max: Vec4,
}

impl Bin {
    const EMPTY: Bin = Bin {
        min: Vec4::INFINITY,
        max: Vec4::new(f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0),
    };

    #[inline(always)]
    fn add(&mut self, (min, max): (Vec4, Vec4)) {
        self.min = self.min.min(min);
        self.max = self.max.max(max) + Vec4::W;
    }

    /// The bin's box and count with another bin's.
    fn with(self, other: Bin) -> (Bounds, u32) {
        let b = Bounds {
            min: Vec3A::from_vec4(self.min.min(other.min)),
            max: Vec3A::from_vec4(self.max.max(other.max)),
        };
        (b, (self.max.w + other.max.w) as u32)
    }
}

/// Per-axis bins: the box of the triangles whose centroid falls in each bin, and their
/// count; `bins` of the allocated [`MAX_BINS`] are in use. Bin indices are masked to
/// `MAX_BINS - 1` (a no-op, as they are below `bins`), so indexing needs no bounds checks.
struct BinTable {
    bins: usize,
    /// Two sets of bins for adding triangles, even ones to the first, odd ones to the
    /// second (see [`BinTable::add`]); their counts stay exact in f32 up to 2^24, far more
    /// than a table ever takes.
    adding: Box<[[[Bin; MAX_BINS]; 3]; 2]>,
    /// The result: each bin's box and count.
    boxes: Box<[[Bounds; MAX_BINS]; 3]>,
    counts: Box<[[u32; MAX_BINS]; 3]>,
    /// Sweep workspace: area of the bins right of each plane.
    right_area: Box<[f32; MAX_BINS]>,
}

impl BinTable {
    fn new(bins: usize) -> Self {
        BinTable {
            bins,
            adding: Box::new([[[Bin::EMPTY; MAX_BINS]; 3]; 2]),
            boxes: Box::new([[Bounds::EMPTY; MAX_BINS]; 3]),
            counts: Box::new([[0; MAX_BINS]; 3]),
            right_area: Box::new([0.0; MAX_BINS]),
        }
    }

    /// Bins every triangle on all three axes into the first `bins` bins of each axis,
    /// replacing what the table held. Neighbouring triangles of a mesh tend to fall in the
    /// same bins, which would chain every update to the one before through memory; even
    /// and odd triangles go to separate bin sets, merged at the end, so that two updates
    /// are always in flight.
    #[inline]
    fn add(&mut self, prims: &[Prim], grid: &Grid) {
        let bins = grid.bins;
        self.bins = bins;
        for set in self.adding.iter_mut() {
            for axis in set.iter_mut() {
                axis[..bins].fill(Bin::EMPTY);
            }
        }
        #[inline(always)]
        fn put(set: &mut [[Bin; MAX_BINS]; 3], lanes: (Vec4, Vec4), k: [u32; 4]) {
            for axis in 0..3 {
                set[axis][k[axis] as usize & (MAX_BINS - 1)].add(lanes);
            }
        }
        let [even, odd] = &mut *self.adding;
        let mut pairs = prims.chunks_exact(2);
        for pair in &mut pairs {
            let (l0, l1) = (lanes_of(&pair[0]), lanes_of(&pair[1]));
            let (k0, k1) = (grid.bins_of(l0.0 + l0.1), grid.bins_of(l1.0 + l1.1));
            put(even, l0, k0);
            put(odd, l1, k1);
        }
        for p in pairs.remainder() {
            let l = lanes_of(p);
            put(even, l, grid.bins_of(l.0 + l.1));
        }
        for axis in 0..3 {
            for k in 0..bins {
                (self.boxes[axis][k], self.counts[axis][k]) = even[axis][k].with(odd[axis][k]);
            }
        }
    }

    /// Adds another table's bins to these.
    fn merge(&mut self, other: &BinTable) {
        for axis in 0..3 {
            for k in 0..self.bins {
                self.boxes[axis][k] = self.boxes[axis][k].union(other.boxes[axis][k]);
                self.counts[axis][k] += other.counts[axis][k];
            }
        }
    }

    /// The cheapest plane between bins on the grid's usable axes, if any leaves both
    /// sides triangles. For each axis, the planes are swept right-to-left for the areas
    /// right of them, then left-to-right to price each.
    fn best_plane(&mut self, grid: &Grid) -> Option<Plane> {
        let bins = self.bins;
        let mut best: Option<Plane> = None;
        for axis in 0..3 {
            if !grid.usable(axis) {
                continue;
            }
            let boxes = &self.boxes[axis][..bins];
            let counts = &self.counts[axis][..bins];
            let right_area = &mut self.right_area[..bins];
            let mut acc = Bounds::EMPTY;
            for k in (1..bins).rev() {
                acc = acc.union(boxes[k]);
                right_area[k] = acc.half_area();
            }
            let total: u32 = counts.iter().sum();
            let mut left = Bounds::EMPTY;
            let mut left_count = 0u32;
            for k in 1..bins {
                left = left.union(boxes[k - 1]);
                left_count += counts[k - 1];
                let right_count = total - left_count;
                if left_count == 0 || right_count == 0 {
                    continue;
                }
                let cost =
                    left.half_area() * left_count as f32 + right_area[k] * right_count as f32;
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Plane {
                        cost,
                        axis,
                        bin: k,
                        left_count: left_count as usize,
                    });
                }
            }
        }
        best
    }

    /// The boxes of the triangles on each side of the plane.
    fn side_boxes(&self, plane: &Plane) -> (Bounds, Bounds) {
        let boxes = &self.boxes[plane.axis][..self.bins];
        let union = |b: &[Bounds]| b.iter().fold(Bounds::EMPTY, |a, b| a.union(*b));
        (union(&boxes[..plane.bin]), union(&boxes[plane.bin..]))
    }

    /// How many of the binned triangles lie left of the plane.
    fn count_left_of(&self, plane: &Plane) -> usize {
        self.counts[plane.axis][..plane.bin]
            .iter()
            .map(|&c| c as usize)
            .sum()
    }
}

/// The exact SAH split: for each axis, sort by centroid and price every position.
fn sweep_split(
    prims: &mut Prims,
    bounds: Bounds,
    may_be_leaf: bool,
    scratch: &mut Scratch,
) -> Split {
    let n = prims.len();
    let mut order = std::mem::take(&mut scratch.order);
    let mut keys = std::mem::take(&mut scratch.keys);
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, left count)
    let right_area = &mut scratch.right_area;
    right_area.clear();
    right_area.resize(n, 0.0);
    // Sorts by (centroid, index) packed in one integer: the f32 bits made monotonic above,
    // the index below, so that ties break the same way every time.
    let sort_by_axis = |order: &mut Vec<u32>, keys: &mut Vec<u64>, axis: usize, prims: &[Prim]| {
        keys.clear();
        keys.extend(
            prims
                .iter()
                .enumerate()
                .map(|(i, p)| sort_key(bounds_of(p).centroid()[axis], i)),
        );
        keys.sort_unstable();
        order.clear();
        order.extend(keys.iter().map(|&k| k as u32));
    };
    for axis in 0..3 {
        sort_by_axis(&mut order, &mut keys, axis, prims.prims);
        sweep_costs(
            n,
            |k| bounds_of(&prims.prims[order[k] as usize]),
            right_area,
            |cost, k| {
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            },
        );
    }
    let (cost, axis, mid) = best.expect("n >= 2 gives a split position");
    let leaf = may_be_leaf && leaf_is_cheaper(n, bounds.half_area(), cost);
    if !leaf {
        if axis != 2 {
            sort_by_axis(&mut order, &mut keys, axis, prims.prims);
        }
        prims.gather(order.iter().copied());
    }
    scratch.order = order;
    scratch.keys = keys;
    if leaf {
        return Split::Leaf;
    }
    Split::At {
        mid,
        left: side_bounds(&prims.spare[..mid]),
        right: side_bounds(&prims.spare[mid..]),
    }
}

/// The SAH cost of every split position `k` (1 to `n - 1`) of the boxes in sweep order,
/// the first `k` to the left: each handed to `keep` in order of `k`. `right_area` is
/// scratch of at least `n` entries.
#[inline(always)]
fn sweep_costs(
    n: usize,
    box_at: impl Fn(usize) -> Bounds,
    right_area: &mut [f32],
    mut keep: impl FnMut(f32, usize),
) {
    let mut acc = Bounds::EMPTY;
    for k in (1..n).rev() {
        acc = acc.union(box_at(k));
        right_area[k] = acc.half_area();
    }
    let mut left = Bounds::EMPTY;
    for (k, &right) in right_area[..n].iter().enumerate().skip(1) {
        left = left.union(box_at(k - 1));
        keep(left.half_area() * k as f32 + right * (n - k) as f32, k);
    }
}

/// Nodes this small take the exact sweep on the stack, without allocation or indirection.
const SMALL: usize = 8;

/// The sorting key of a centroid coordinate: its f32 bits made monotonic, above the
/// triangle's position, so that ties break by position (as [`sweep_split`] breaks them).
#[inline(always)]
fn sort_key(coordinate: f32, position: usize) -> u64 {
    let bits = coordinate.to_bits();
    let ordered = if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    };
    (ordered as u64) << 32 | position as u64
}

/// Sorts `keys` with a fixed sorting network (Knuth's 5 comparators for 4 keys, 19 for 8),
/// branch-free: the comparisons of a few centroids mispredict as often as not, which cost
/// an insertion sort more than its work.
#[inline(always)]
fn sort_small(keys: &mut [u64; SMALL], n: usize) {
    const FOUR: [(usize, usize); 5] = [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)];
    const EIGHT: [(usize, usize); 19] = [
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (2, 4),
        (3, 5),
        (1, 4),
        (3, 6),
        (1, 2),
        (3, 4),
        (5, 6),
    ];
    let network: &[(usize, usize)] = if n <= 4 { &FOUR } else { &EIGHT };
    for &(i, j) in network {
        let (a, b) = (keys[i], keys[j]);
        keys[i] = a.min(b);
        keys[j] = a.max(b);
    }
}

/// [`sweep_split`] for at most [`SMALL`] triangles: sorting networks over a few centroids
/// on the stack. Same splits, same tie-breaking (by position), a fraction of the work.
fn small_sweep_split(prims: &mut Prims, bounds: Bounds, may_be_leaf: bool) -> Split {
    let n = prims.len();
    debug_assert!((2..=SMALL).contains(&n));
    if n == 2 {
        // One way to split two triangles, whatever the axis: no sorting needed.
        let (a, b) = (bounds_of(&prims.prims[0]), bounds_of(&prims.prims[1]));
        if may_be_leaf && leaf_is_cheaper(2, bounds.half_area(), a.half_area() + b.half_area()) {
            return Split::Leaf;
        }
        prims.gather([0, 1]);
        let one = |p: Bounds| {
            let c = centroid2(&p);
            (p, Bounds { min: c, max: c })
        };
        return Split::At {
            mid: 1,
            left: one(a),
            right: one(b),
        };
    }
    let mut boxes = [Bounds::EMPTY; SMALL];
    for (b, p) in boxes.iter_mut().zip(prims.prims.iter()) {
        *b = bounds_of(p);
    }
    // Padding keys sort last and are never swept.
    let mut keys = [[u64::MAX; SMALL]; 3];
    for (i, b) in boxes[..n].iter().enumerate() {
        let c = b.centroid();
        for (axis, keys) in keys.iter_mut().enumerate() {
            keys[i] = sort_key(c[axis], i);
        }
    }
    // (cost, axis, left count): a valid split even should every cost be NaN.
    let mut best = (f32::INFINITY, 0, 1);
    for (axis, keys) in keys.iter_mut().enumerate() {
        sort_small(keys, n);
        let mut right_area = [0.0f32; SMALL];
        sweep_costs(
            n,
            |k| boxes[keys[k] as usize & (SMALL - 1)],
            &mut right_area,
            |cost, k| {
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            },
        );
    }
    let (cost, axis, mid) = best;
    if may_be_leaf && leaf_is_cheaper(n, bounds.half_area(), cost) {
        return Split::Leaf;
    }
    prims.gather(keys[axis][..n].iter().map(|&k| k as u32));
    Split::At {
        mid,
        left: side_bounds(&prims.spare[..mid]),
        right: side_bounds(&prims.spare[mid..]),
    }
}

/// Splits at the middle by count, ordered along the centroids' widest axis: the fallback
/// when centroids coincide, and the way to keep depth bounded.
fn median_split(prims: &mut Prims, centroids: Bounds) -> (usize, Side, Side) {
    let n = prims.len();
    let mid = n / 2;
    let extent = centroids.max - centroids.min;
    let mut order: Vec<u32> = (0..n as u32).collect();
    if extent.max_element() > 0.0 {
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        order.select_nth_unstable_by(mid, |&a, &b| {
            let (ca, cb) = (
                bounds_of(&prims.prims[a as usize]).centroid()[axis],
                bounds_of(&prims.prims[b as usize]).centroid()[axis],
            );
            ca.total_cmp(&cb)
        });
    }
    prims.gather(order);
    (
        mid,
        side_bounds(&prims.spare[..mid]),
        side_bounds(&prims.spare[mid..]),
    )
}

/// The box and doubled-centroid box of some triangles.
fn side_bounds(prims: &[Prim]) -> Side {
    prims
        .iter()
        .fold((Bounds::EMPTY, Bounds::EMPTY), |(b, mut c), p| {
            let p = bounds_of(p);
            c.grow(centroid2(&p));
            (b.union(p), c)
        })
}
