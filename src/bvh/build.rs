//! Top-down SAH construction.
//!
//! Each node's triangles are split in two by a plane chosen under the surface area
//! heuristic: binned over centroids on all three axes (Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", 2007), or by an exact sweep over every
//! centroid-sorted position. Large nodes bin in parallel, the largest partition in
//! parallel, and subtrees build in parallel.
//!
//! Each triangle moves through the build as one 32-byte record, its box stored as minimum
//! and negated maximum (so that the union of two boxes is one `min` of each half) with its
//! mesh index in the spare lane: a swap moves one record, and binning one update per axis.
//!
//! Nodes are stored in depth-first order as they are made. Large nodes split and hand
//! their two halves to parallel tasks; each task writes its subtree into its own compact
//! vector, and one pass at the end lays the tasks' vectors out behind the few shared top
//! nodes, shifting child indices. Memory is touched once per node: on a virtual machine a
//! fresh page costs microseconds, so untouched slack is worth more than it seems.

use glam::{BVec4A, UVec4, Vec3A, Vec4};
use rayon::prelude::*;

use super::{BuildOptions, Builder, Bvh, INTERSECTION_COST, TRAVERSAL_COST};
use crate::bvh::{Bin32Node, LEAF_FLAG};
use crate::geometry::Bounds;
use crate::mesh::Mesh;

/// Nodes with more triangles than this build their two subtrees in parallel.
const PARALLEL_SUBTREES: usize = 1 << 14;
/// Nodes with more triangles than this bin in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;
/// Nodes with more triangles than this partition in parallel chunks: near the root,
/// where too few subtrees run at once to keep every core busy (the dragon's root, 871,414
/// triangles, partitioned on both of 2 cores builds it 3% sooner than on one).
const PARALLEL_PARTITION: usize = 1 << 19;
/// The most bins per axis [`BuildOptions::bins`] may ask for (a power of two).
pub(super) const MAX_BINS: usize = 64;

/// A box as its minimum and negated maximum, each in a 4-lane vector whose fourth lane is
/// spare: the union of two boxes is then one `min` per half.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
struct Aabb {
    lo: Vec4,
    hi: Vec4,
}

/// A triangle as the build moves it: its box, with its mesh index in the fourth lane of
/// `lo` (the index's bits XOR [`ID_BITS`], which makes them an ordinary float for any mesh
/// under a billion triangles: arithmetic on a subnormal lane is many times slower).
type Prim = Aabb;

/// See [`Prim`].
const ID_BITS: u32 = 0x4000_0000;

impl Aabb {
    /// The empty box: its union with any box is that box.
    const EMPTY: Aabb = Aabb {
        lo: Vec4::INFINITY,
        hi: Vec4::INFINITY,
    };

    /// Triangle `id`, whose box is `b`.
    fn prim(b: Bounds, id: u32) -> Prim {
        Aabb {
            lo: b.min.extend(f32::from_bits(id ^ ID_BITS)),
            hi: (-b.max).extend(0.0),
        }
    }

    /// The mesh index of a [`Prim`].
    fn id(&self) -> u32 {
        self.lo.w.to_bits() ^ ID_BITS
    }

    #[inline(always)]
    fn union(self, o: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(o.lo),
            hi: self.hi.min(o.hi),
        }
    }

    /// The box of point `p` (its first three lanes).
    #[inline(always)]
    fn point(p: Vec4) -> Aabb {
        Aabb { lo: p, hi: -p }
    }

    /// Half the surface area, as [`Bounds::half_area`].
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = (-self.hi - self.lo).max(Vec4::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The centre in the first three lanes: `(min + max) / 2`, exactly.
    #[inline(always)]
    fn centroid(&self) -> Vec4 {
        (self.lo - self.hi) * 0.5
    }

    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    fn max(&self) -> Vec3A {
        -Vec3A::from_vec4(self.hi)
    }

    /// The box as the node that holds it.
    fn node(&self, left_or_first: u32, right_or_count: u32) -> Bin32Node {
        Bin32Node {
            min: self.min().to_array(),
            left_or_first,
            max: self.max().to_array(),
            right_or_count,
        }
    }
}

/// The triangles of one node.
struct Prims<'a> {
    prims: &'a mut [Prim],
    /// Position of `prims[0]` in the whole leaf order.
    first: u32,
}

impl Prims<'_> {
    fn len(&self) -> usize {
        self.prims.len()
    }

    fn split_at(self, mid: usize) -> (Self, Self) {
        let (l, r) = self.prims.split_at_mut(mid);
        (
            Prims {
                prims: l,
                first: self.first,
            },
            Prims {
                prims: r,
                first: self.first + mid as u32,
            },
        )
    }

    /// Box and centroid box of all the triangles.
    fn bounds(&self) -> Side {
        if self.len() > PARALLEL_BINNING {
            self.prims
                .par_chunks(1 << 14)
                .map(side_bounds)
                .reduce(|| EMPTY_SIDE, |(a, b), (c, d)| (a.union(c), b.union(d)))
        } else {
            side_bounds(self.prims)
        }
    }
}

/// A child's box, and a box that holds its triangles' centroids: the grid its binning
/// spans. The exact centroid box where a side's triangles are gathered anyway; below a
/// binned split, the child's box clipped to its parent's centroid box (see
/// [`Ctx::binned_split`]).
type Side = (Aabb, Aabb);

const EMPTY_SIDE: Side = (Aabb::EMPTY, Aabb::EMPTY);

/// The outcome of looking for a split.
enum Split {
    /// Make a leaf: cheaper than any split (only offered when the node may be a leaf).
    Leaf,
    /// Triangles `[0, mid)` go left, with the children's boxes and centroid boxes.
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
    prims: Vec<Prim>,
}

impl Scratch {
    fn new(bins: usize) -> Self {
        Scratch {
            bins: BinTable::new(bins),
            order: Vec::new(),
            keys: Vec::new(),
            right_area: Vec::new(),
            prims: Vec::new(),
        }
    }
}

pub(super) fn build(mesh: &Mesh, options: &BuildOptions) -> Bvh {
    let n = mesh.triangle_count();
    assert!(n > 0, "a checked mesh has triangles");
    // From the index and position arrays directly: through `Mesh::corners` (inlined or
    // not) the dragon's records took 9 ms instead of 3.4.
    let positions = &mesh.positions;
    let mut records: Vec<Prim> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(i, corners)| {
            let [a, b, c] = corners.map(|v| Vec3A::from(positions[v as usize]));
            let bounds = Bounds {
                min: a.min(b).min(c),
                max: a.max(b).max(c),
            };
            Aabb::prim(bounds, i as u32)
        })
        .collect();
    let prims = Prims {
        prims: &mut records,
        first: 0,
    };
    let bounds = prims.bounds();
    let ctx = Ctx {
        options: BuildOptions {
            builder: options.builder.for_triangles(n),
            ..*options
        },
    };
    let (tree, depth) = ctx.top(prims, bounds, 1, &mut Scratch::new(options.bins as usize));
    // Zeroed memory comes from the system untouched, so the pages are first touched (and
    // paid for) by the parallel writers, not here.
    let mut nodes: Vec<Bin32Node> = bytemuck::zeroed_vec(tree.node_count());
    tree.lay_out(&mut nodes, 0);
    Bvh {
        nodes,
        prim_order: records
            .par_iter()
            .with_min_len(4096)
            .map(Prim::id)
            .collect(),
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
            return (Subtree::Nodes(vec![leaf]), depth);
        };
        let (lp, rp) = prims.split_at(mid);
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
                depth
            }
            Some((mid, left, right)) => {
                out.push(bounds.0.node(index as u32 + 1, 0));
                let (lp, rp) = prims.split_at(mid);
                let dl = self.node(lp, left, depth + 1, out, scratch);
                out[index].right_or_count = out.len() as u32;
                let dr = self.node(rp, right, depth + 1, out, scratch);
                dl.max(dr)
            }
        }
    }

    /// Decides a node: `None` for a leaf, else the split position with both children's
    /// boxes and centroid boxes (the triangles reordered to match).
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
                // `Auto` was resolved in `build`.
                Builder::Binned | Builder::Auto if n > SMALL => {
                    self.binned_split(prims, bounds, centroids, n <= max_leaf, &mut scratch.bins)
                }
                _ if n <= SMALL => small_sweep_split(prims, bounds, n <= max_leaf),
                _ => sweep_split(prims, bounds, n <= max_leaf, scratch),
            }
        };
        match split {
            Split::Leaf => None,
            // Both sides hold triangles for any checked mesh; should NaNs have slipped in,
            // fall back rather than recurse on an empty side.
            Split::At { mid, left, right } if mid > 0 && mid < n => Some((mid, left, right)),
            Split::At { .. } => Some(median_split(prims, centroids, scratch)),
            Split::None if n <= max_leaf => None,
            Split::None => Some(median_split(prims, centroids, scratch)),
        }
    }

    /// Bins the centroids on all three axes, picks the cheapest plane between bins, and
    /// partitions the triangles in place.
    fn binned_split(
        &self,
        prims: &mut Prims,
        bounds: Aabb,
        centroids: Aabb,
        may_be_leaf: bool,
        table: &mut BinTable,
    ) -> Split {
        // Small nodes use fewer bins: a few triangles gain nothing from many planes.
        let bins = (self.options.bins as usize).min((prims.len() / 4).max(8));
        table.reset(bins);
        let cmin = centroids.lo;
        let extent = -centroids.hi - cmin;
        // Slightly under `bins / extent`, so the largest centroid still lands in the last
        // bin. An extent so thin that the scale overflows counts as flat. The spare lane
        // counts as flat too.
        let scale = Vec4::splat(bins as f32 * (1.0 - 1e-6)) / extent;
        let usable = extent.cmpgt(Vec4::ZERO)
            & scale.is_finite_mask()
            & BVec4A::new(true, true, true, false);
        let scale = Vec4::select(usable, scale, Vec4::ZERO);
        let last = Vec4::splat((bins - 1) as f32);
        // By value, so that the loop keeps them in registers.
        let bin_of = move |p: &Prim| bin_indices(((p.centroid() - cmin) * scale).min(last));

        if prims.len() > PARALLEL_BINNING {
            *table = prims
                .prims
                .par_chunks(1 << 14)
                .map(|chunk| {
                    let mut t = BinTable::new(bins);
                    t.add(chunk, &bin_of);
                    t
                })
                .reduce(|| BinTable::new(bins), BinTable::merged);
        } else {
            table.add(prims.prims, &bin_of);
        }

        let best = table.cheapest_plane(usable, prims.len());
        let Some((cost, axis, split_bin)) = best else {
            return Split::None;
        };
        if may_be_leaf && leaf_is_cheaper(prims.len(), bounds.half_area(), cost) {
            return Split::Leaf;
        }

        // Partition: bin < split_bin goes left. The children's boxes come from the bins.
        let boxes = table.axis(axis);
        let left_box = boxes[..split_bin]
            .iter()
            .fold(Aabb::EMPTY, |a, b| a.union(*b));
        let right_box = boxes[split_bin..]
            .iter()
            .fold(Aabb::EMPTY, |a, b| a.union(*b));
        // floor(f) < split_bin exactly when f < split_bin, f being the same lane product the
        // binning floored.
        let plane = split_bin as f32;
        let goes_left = |c: Vec4| ((c - cmin) * scale)[axis] < plane;
        let mid = match (prims.len() > PARALLEL_PARTITION, axis) {
            (true, _) => parallel_partition(prims.prims, goes_left),
            (false, 0) => partition(prims.prims, |c| ((c - cmin) * scale).x < plane),
            (false, 1) => partition(prims.prims, |c| ((c - cmin) * scale).y < plane),
            (false, _) => partition(prims.prims, |c| ((c - cmin) * scale).z < plane),
        };
        // Each child bins over its box clipped to this node's centroid box: it holds every
        // centroid of that side (a centroid lies in its triangle's box), so no index
        // leaves the grid. A pass over each side for its exact centroid box cost 5% of the
        // build and bought 0.1-0.2% of SAH cost on the bunny and the dragon
        // (docs/bench/2026-12-05-bvh-build.md).
        let grid = |b: Aabb| Aabb {
            lo: b.lo.max(centroids.lo),
            hi: b.hi.max(centroids.hi),
        };
        Split::At {
            mid,
            left: (left_box, grid(left_box)),
            right: (right_box, grid(right_box)),
        }
    }
}

/// The bin indices of a centroid's grid coordinates `k` (in `[0, bins)` for a checked mesh),
/// truncated in one vector conversion. An unchecked mesh's NaN or negative coordinates give
/// indices that [`BinTable`] masks into its allocated bins.
#[inline(always)]
fn bin_indices(k: Vec4) -> [u32; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttps_epi32, _mm_storeu_si128};
        let mut lanes = [0u32; 4];
        // SAFETY: SSE2 is part of x86_64; the store writes 16 bytes into 16 bytes.
        unsafe { _mm_storeu_si128(lanes.as_mut_ptr().cast(), _mm_cvttps_epi32(k.into())) };
        [lanes[0], lanes[1], lanes[2]]
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [k.x as u32, k.y as u32, k.z as u32]
    }
}

/// Moves the triangles whose centroid `goes_left` to the front, without branches
/// (Lomuto's scheme with an unconditional swap: data-dependent branches mispredict half
/// the time near the root). Returns the left count.
#[inline]
fn partition(prims: &mut [Prim], goes_left: impl Fn(Vec4) -> bool) -> usize {
    let mut left = 0;
    for i in 0..prims.len() {
        let p = prims[i];
        let is_left = goes_left(p.centroid());
        prims[i] = prims[left];
        prims[left] = p;
        left += is_left as usize;
    }
    left
}

/// [`partition`] for a large node, on every core: each chunk partitions itself in place,
/// and then the right-side triangles in front of the split point trade places with the
/// left-side ones behind it, pair by pair in order, in pieces of a chunk's size. Near the
/// root a sequential partition of every triangle would leave all but a few cores idle.
fn parallel_partition(prims: &mut [Prim], goes_left: impl Fn(Vec4) -> bool + Sync) -> usize {
    const CHUNK: usize = 1 << 14;
    let n = prims.len();
    let parts: Vec<usize> = prims
        .par_chunks_mut(CHUNK)
        .map(|chunk| partition(chunk, &goes_left))
        .collect();
    let left: usize = parts.iter().sum();
    // Triangles on the wrong side of `left`: chunks' right parts before it, their left
    // parts after it. There are as many of one as of the other.
    let (mut wrong_right, mut wrong_left) = (Vec::new(), Vec::new());
    for (k, &count) in parts.iter().enumerate() {
        let (start, end) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
        let mid = start + count;
        if mid < left {
            wrong_right.push(mid..end.min(left));
        }
        if mid > left {
            wrong_left.push(start.max(left)..mid);
        }
    }
    // Pair them in order, in pieces of at most a chunk.
    let (mut a_pieces, mut b_pieces) = (Vec::new(), Vec::new());
    let (mut a, mut b) = (wrong_right.into_iter(), wrong_left.into_iter());
    let (mut ra, mut rb) = (a.next(), b.next());
    while let (Some(x), Some(y)) = (ra.as_mut(), rb.as_mut()) {
        let len = x.len().min(y.len()).min(CHUNK);
        a_pieces.push(x.start..x.start + len);
        b_pieces.push(y.start..y.start + len);
        x.start += len;
        y.start += len;
        if x.start == x.end {
            ra = a.next();
        }
        if y.start == y.end {
            rb = b.next();
        }
    }
    debug_assert!(ra.is_none() && rb.is_none(), "as many wrong on each side");
    let (front, back) = prims.split_at_mut(left);
    carve(front, &a_pieces, 0)
        .zip(carve(back, &b_pieces, left))
        .collect::<Vec<_>>()
        .into_par_iter()
        .for_each(|(f, b)| f.swap_with_slice(b));
    left
}

/// The slices of `items` (whose first element has index `offset`) at `ranges`, which are
/// in increasing order and do not overlap.
fn carve<'a, T>(
    mut items: &'a mut [T],
    ranges: &[std::ops::Range<usize>],
    mut offset: usize,
) -> impl Iterator<Item = &'a mut [T]> {
    let mut pieces = Vec::with_capacity(ranges.len());
    for r in ranges {
        let (_, rest) = std::mem::take(&mut items).split_at_mut(r.start - offset);
        let (piece, rest) = rest.split_at_mut(r.len());
        pieces.push(piece);
        items = rest;
        offset = r.end;
    }
    pieces.into_iter()
}

/// Whether keeping `n` triangles in a leaf costs no more than splitting them, given the
/// split's `sum of half-area * count` over both children and the node's half-area.
fn leaf_is_cheaper(n: usize, half_area: f32, split: f32) -> bool {
    INTERSECTION_COST * n as f32 * half_area
        <= TRAVERSAL_COST * half_area + INTERSECTION_COST * split
}

/// Per-axis bins: the box of the triangles whose centroid falls in each bin, and their
/// count; `bins` of the allocated [`MAX_BINS`] are in use. Bin indices are masked to
/// `MAX_BINS - 1` (a no-op, as they are below `bins`), so indexing needs no bounds checks.
struct BinTable {
    bins: usize,
    boxes: Box<[[Aabb; MAX_BINS]; 3]>,
    /// Per bin, its count on each axis (lanes x, y, z).
    counts: Box<[UVec4; MAX_BINS]>,
    /// A second set of bins for every other triangle (see [`BinTable::add`]).
    odd_boxes: Box<[[Aabb; MAX_BINS]; 3]>,
    odd_counts: Box<[UVec4; MAX_BINS]>,
    /// Sweep workspace: half-area of the bins right of each plane, per axis (lanes x, y, z).
    right_area: Box<[Vec4; MAX_BINS]>,
}

impl BinTable {
    fn new(bins: usize) -> Self {
        let mut t = BinTable {
            bins,
            boxes: Box::new([[Aabb::EMPTY; MAX_BINS]; 3]),
            counts: Box::new([UVec4::ZERO; MAX_BINS]),
            odd_boxes: Box::new([[Aabb::EMPTY; MAX_BINS]; 3]),
            odd_counts: Box::new([UVec4::ZERO; MAX_BINS]),
            right_area: Box::new([Vec4::ZERO; MAX_BINS]),
        };
        t.reset(bins);
        t
    }

    /// Empties the first `bins` bins of each axis and uses only those (the odd set is
    /// emptied by [`BinTable::add`] where it is used).
    fn reset(&mut self, bins: usize) {
        self.bins = bins;
        self.counts[..bins].fill(UVec4::ZERO);
        for axis in 0..3 {
            self.boxes[axis][..bins].fill(Aabb::EMPTY);
        }
    }

    /// Bins every triangle on all three axes. Neighbouring triangles of a mesh tend to fall
    /// in the same bins, which would chain every update to the one before through memory;
    /// even and odd triangles go to separate bin sets, merged at the end, so that two
    /// updates are always in flight. A node of one block's triangles or fewer uses one set:
    /// there emptying and merging the second cost more than the chain (the dragon's build
    /// 3% faster).
    #[inline]
    fn add(&mut self, prims: &[Prim], bin_of: &impl Fn(&Prim) -> [u32; 3]) {
        let bins = self.bins;
        #[inline(always)]
        fn put(
            boxes: &mut [[Aabb; MAX_BINS]; 3],
            counts: &mut [UVec4; MAX_BINS],
            p: &Prim,
            k: [u32; 3],
        ) {
            for axis in 0..3 {
                let k = k[axis] as usize & (MAX_BINS - 1);
                boxes[axis][k] = boxes[axis][k].union(*p);
                counts[k][axis] += 1;
            }
        }
        // The bin indices of a block first, then its updates: each index waits on a load
        // and a chain of arithmetic, which would otherwise stall the updates behind it.
        const BLOCK: usize = 32;
        let mut ks = [[0u32; 3]; BLOCK];
        if prims.len() <= BLOCK {
            // One block, one set.
            for (k, p) in ks.iter_mut().zip(prims) {
                *k = bin_of(p);
            }
            for (p, k) in prims.iter().zip(ks) {
                put(&mut self.boxes, &mut self.counts, p, k);
            }
            return;
        }
        self.odd_counts[..bins].fill(UVec4::ZERO);
        for axis in 0..3 {
            self.odd_boxes[axis][..bins].fill(Aabb::EMPTY);
        }
        for block in prims.chunks(BLOCK) {
            for (k, p) in ks.iter_mut().zip(block) {
                *k = bin_of(p);
            }
            let mut pairs = block.chunks_exact(2).zip(ks.chunks_exact(2));
            for (pair, k) in &mut pairs {
                put(&mut self.boxes, &mut self.counts, &pair[0], k[0]);
                put(&mut self.odd_boxes, &mut self.odd_counts, &pair[1], k[1]);
            }
            if block.len() % 2 == 1 {
                let last = block.len() - 1;
                put(&mut self.boxes, &mut self.counts, &block[last], ks[last]);
            }
        }
        for axis in 0..3 {
            for k in 0..self.bins {
                self.boxes[axis][k] = self.boxes[axis][k].union(self.odd_boxes[axis][k]);
            }
        }
        for k in 0..self.bins {
            self.counts[k] += self.odd_counts[k];
        }
    }

    fn merged(mut self, other: BinTable) -> BinTable {
        for axis in 0..3 {
            for k in 0..self.bins {
                self.boxes[axis][k] = self.boxes[axis][k].union(other.boxes[axis][k]);
            }
        }
        for k in 0..self.bins {
            self.counts[k] += other.counts[k];
        }
        self
    }

    fn axis(&self, axis: usize) -> &[Aabb] {
        &self.boxes[axis][..self.bins]
    }

    /// The cheapest plane between bins under the SAH over all three axes, swept together
    /// (one axis a lane), on the axes `usable` allows: `(sum of half-area * count over both
    /// sides, axis, first bin on the right)`, the lowest axis and bin among equal costs, or
    /// `None` if no plane has triangles on both sides. `n` is the node's triangle count.
    fn cheapest_plane(&mut self, usable: BVec4A, n: usize) -> Option<(f32, usize, usize)> {
        let bins = self.bins;
        let [bx, by, bz] = &*self.boxes;
        // Right to left: the half-areas of the bins right of each plane.
        let mut acc = [Aabb::EMPTY; 3];
        for k in (1..bins).rev() {
            acc = [
                acc[0].union(bx[k]),
                acc[1].union(by[k]),
                acc[2].union(bz[k]),
            ];
            self.right_area[k] = half_areas(&acc);
        }
        // Left to right: price each plane.
        let total = UVec4::splat(n as u32);
        let mut left = [Aabb::EMPTY; 3];
        let mut left_count = UVec4::ZERO;
        // Per axis, the first plane with triangles on both sides, then any cheaper one (as a
        // loop over the axes' planes in order would keep them); bin 0 marks none yet.
        let (mut best_cost, mut best_bin) = (Vec4::ZERO, Vec4::ZERO);
        for k in 1..bins {
            left = [
                left[0].union(bx[k - 1]),
                left[1].union(by[k - 1]),
                left[2].union(bz[k - 1]),
            ];
            left_count += self.counts[k - 1];
            let (lc, rc) = (left_count.as_vec4(), (total - left_count).as_vec4());
            let cost = half_areas(&left) * lc + self.right_area[k] * rc;
            let found = best_bin.cmpgt(Vec4::ZERO);
            let better = usable
                & lc.cmpgt(Vec4::ZERO)
                & rc.cmpgt(Vec4::ZERO)
                & (cost.cmplt(best_cost) | !found);
            best_cost = Vec4::select(better, cost, best_cost);
            best_bin = Vec4::select(better, Vec4::splat(k as f32), best_bin);
        }
        let found = best_bin.cmpgt(Vec4::ZERO);
        let mut best: Option<usize> = None;
        for axis in (0..3).filter(|&a| found.test(a)) {
            if best.is_none_or(|b| best_cost[axis] < best_cost[b]) {
                best = Some(axis);
            }
        }
        best.map(|axis| (best_cost[axis], axis, best_bin[axis] as usize))
    }
}

/// The half-areas of three boxes, one a lane ([`Aabb::half_area`] of each, in the same
/// operations).
#[inline(always)]
fn half_areas(b: &[Aabb; 3]) -> Vec4 {
    let e = b.map(|b| (-b.hi - b.lo).max(Vec4::ZERO));
    let x = Vec4::new(e[0].x, e[1].x, e[2].x, 0.0);
    let y = Vec4::new(e[0].y, e[1].y, e[2].y, 0.0);
    let z = Vec4::new(e[0].z, e[1].z, e[2].z, 0.0);
    x * y + y * z + z * x
}

/// The exact SAH split: for each axis, sort by centroid and price every position.
fn sweep_split(prims: &mut Prims, bounds: Aabb, may_be_leaf: bool, scratch: &mut Scratch) -> Split {
    let n = prims.len();
    let mut order = std::mem::take(&mut scratch.order);
    let mut keys = std::mem::take(&mut scratch.keys);
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, left count)
    let right_area = &mut scratch.right_area;
    right_area.clear();
    right_area.resize(n, 0.0);
    // Sorts by (centroid, index) packed in one integer: the f32 bits made monotonic above,
    // the index below, so that ties break the same way every time.
    let sort_by_axis = |order: &mut Vec<u32>, keys: &mut Vec<u64>, axis: usize, boxes: &[Prim]| {
        keys.clear();
        keys.extend(boxes.iter().enumerate().map(|(i, b)| {
            let bits = b.centroid()[axis].to_bits();
            let ordered = if bits >> 31 == 1 {
                !bits
            } else {
                bits | 1 << 31
            };
            (ordered as u64) << 32 | i as u64
        }));
        keys.sort_unstable();
        order.clear();
        order.extend(keys.iter().map(|&k| k as u32));
    };
    for axis in 0..3 {
        sort_by_axis(&mut order, &mut keys, axis, prims.prims);
        sweep_costs(
            n,
            |k| prims.prims[order[k] as usize],
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
        apply_order(prims, &order, scratch);
    }
    scratch.order = order;
    scratch.keys = keys;
    if leaf {
        return Split::Leaf;
    }
    let (l, r) = (
        side_bounds(&prims.prims[..mid]),
        side_bounds(&prims.prims[mid..]),
    );
    Split::At {
        mid,
        left: l,
        right: r,
    }
}

/// The SAH cost of every split position `k` (1 to `n - 1`) of the boxes in sweep order,
/// the first `k` to the left: each handed to `keep` in order of `k`. `right_area` is
/// scratch of at least `n` entries.
#[inline(always)]
fn sweep_costs(
    n: usize,
    box_at: impl Fn(usize) -> Aabb,
    right_area: &mut [f32],
    mut keep: impl FnMut(f32, usize),
) {
    let mut acc = Aabb::EMPTY;
    for k in (1..n).rev() {
        acc = acc.union(box_at(k));
        right_area[k] = acc.half_area();
    }
    let mut left = Aabb::EMPTY;
    for (k, &right) in right_area[..n].iter().enumerate().skip(1) {
        left = left.union(box_at(k - 1));
        keep(left.half_area() * k as f32 + right * (n - k) as f32, k);
    }
}

/// Nodes this small take the exact sweep on the stack, without allocation or indirection.
const SMALL: usize = 4;

/// [`sweep_split`] for at most [`SMALL`] triangles: insertion sorts of a few centroids on the
/// stack. Same splits, same tie-breaking (by position), a fraction of the work.
fn small_sweep_split(prims: &mut Prims, bounds: Aabb, may_be_leaf: bool) -> Split {
    let n = prims.len();
    debug_assert!((2..=SMALL).contains(&n));
    if n == 2 {
        // One way to split two triangles, whatever the axis: no sorting needed.
        let (a, b) = (prims.prims[0], prims.prims[1]);
        if may_be_leaf && leaf_is_cheaper(2, bounds.half_area(), a.half_area() + b.half_area()) {
            return Split::Leaf;
        }
        let one = |p: Prim| side_bounds(&[p]);
        return Split::At {
            mid: 1,
            left: one(a),
            right: one(b),
        };
    }
    let mut keys = [[0.0f32; SMALL]; 3];
    for (i, b) in prims.prims.iter().enumerate() {
        let c = b.centroid();
        keys[0][i] = c.x;
        keys[1][i] = c.y;
        keys[2][i] = c.z;
    }
    let mut best: Option<(f32, usize)> = None;
    let mut best_order = [0u8; SMALL];
    for key in &keys {
        let mut order = [0u8; SMALL];
        for i in 0..n {
            // Stable insertion: equal keys keep their positions, as the index tie-break does.
            let mut j = i;
            while j > 0 && key[order[j - 1] as usize] > key[i] {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = i as u8;
        }
        let mut right_area = [0.0f32; SMALL];
        sweep_costs(
            n,
            |k| prims.prims[order[k] as usize],
            &mut right_area,
            |cost, k| {
                if best.is_none_or(|(c, _)| cost < c) {
                    best = Some((cost, k));
                    best_order = order;
                }
            },
        );
    }
    let (cost, mid) = best.expect("n >= 2 gives a split position");
    if may_be_leaf && leaf_is_cheaper(n, bounds.half_area(), cost) {
        return Split::Leaf;
    }
    // Permute in place, cycle by cycle: position i takes what was at best_order[i].
    let mut done = 0u32;
    for start in 0..n {
        if done & (1 << start) != 0 {
            continue;
        }
        let first = prims.prims[start];
        let mut i = start;
        loop {
            done |= 1 << i;
            let from = best_order[i] as usize;
            if from == start {
                prims.prims[i] = first;
                break;
            }
            prims.prims[i] = prims.prims[from];
            i = from;
        }
    }
    Split::At {
        mid,
        left: side_bounds(&prims.prims[..mid]),
        right: side_bounds(&prims.prims[mid..]),
    }
}

/// Splits at the middle by count, ordered along the centroids' widest axis: the fallback
/// when centroids coincide, and the way to keep depth bounded.
fn median_split(prims: &mut Prims, centroids: Aabb, scratch: &mut Scratch) -> (usize, Side, Side) {
    let n = prims.len();
    let mid = n / 2;
    let extent = centroids.max() - centroids.min();
    if extent.max_element() > 0.0 {
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.select_nth_unstable_by(mid, |&a, &b| {
            let (ca, cb) = (
                prims.prims[a as usize].centroid()[axis],
                prims.prims[b as usize].centroid()[axis],
            );
            ca.total_cmp(&cb)
        });
        apply_order(prims, &order, scratch);
    }
    (
        mid,
        side_bounds(&prims.prims[..mid]),
        side_bounds(&prims.prims[mid..]),
    )
}

/// The box and the centroid box of `prims`.
fn side_bounds(prims: &[Prim]) -> Side {
    prims.iter().fold(EMPTY_SIDE, |(b, c), p| {
        (b.union(*p), c.union(Aabb::point(p.centroid())))
    })
}

/// Permutes the triangles so that position `i` holds what was at `order[i]`.
fn apply_order(prims: &mut Prims, order: &[u32], scratch: &mut Scratch) {
    scratch.prims.clear();
    scratch
        .prims
        .extend(order.iter().map(|&i| prims.prims[i as usize]));
    prims.prims.copy_from_slice(&scratch.prims);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit boxes at pseudo-random places along x, triangle `i` at position `i`.
    fn scattered(n: usize) -> Vec<Prim> {
        (0..n as u64)
            .map(|i| {
                let x = (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32;
                Aabb::prim(Bounds::new([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0]), i as u32)
            })
            .collect()
    }

    #[test]
    fn a_record_keeps_its_box_and_mesh_index() {
        let b = Bounds::new([-1.5, 2.0, 0.25], [3.0, 2.5, 8.0]);
        for id in [0, 1, 12_345, (1 << 23) - 1, 1 << 23, 999_999_999, u32::MAX] {
            let p = Aabb::prim(b, id);
            assert_eq!(p.id(), id);
            assert_eq!((p.min(), p.max()), (b.min, b.max));
            assert_eq!(p.half_area(), b.half_area());
            assert_eq!(Vec3A::from_vec4(p.centroid()), (b.min + b.max) * 0.5);
        }
        // Meshes under a billion triangles keep their indices out of the subnormal range.
        for id in [0, 1 << 20, 999_999_999] {
            assert!(Aabb::prim(b, id).lo.w.is_normal(), "{id}");
        }
    }

    #[test]
    fn the_parallel_partition_is_a_partition_with_the_sequential_ones_sides() {
        // Sizes around the chunk size, so that misplaced runs start and end mid-chunk.
        for n in [1, 5000, (1 << 14) + 1, 3 * (1 << 14) - 7, 200_000] {
            for threshold in [0.0, 0.3, 0.5, 0.97, 2.0] {
                let mut prims = scattered(n);
                let mut seq = prims.clone();
                let cut = threshold * (1 << 24) as f32;
                let goes_left = |c: Vec4| c.x < cut;
                let left = parallel_partition(&mut prims, goes_left);
                assert_eq!(left, partition(&mut seq, goes_left), "{n}, {threshold}");
                let left_of = |p: &Prim| goes_left(p.centroid());
                assert!(prims[..left].iter().all(left_of), "{n}, {threshold}");
                assert!(!prims[left..].iter().any(left_of), "{n}, {threshold}");
                // Every triangle is still there once, with its own box.
                let original = scattered(n);
                assert!(prims.iter().all(|p| original[p.id() as usize] == *p));
                let mut ids: Vec<u32> = prims.iter().map(Prim::id).collect();
                ids.sort_unstable();
                assert!(ids.iter().enumerate().all(|(k, &i)| k as u32 == i));
            }
        }
    }

    /// The plane a loop over each axis's planes in turn keeps: the first with triangles on
    /// both sides, then only a strictly cheaper one, later axes only if strictly cheaper.
    fn cheapest_plane_axis_by_axis(t: &BinTable, usable: BVec4A) -> Option<(f32, usize, usize)> {
        let mut best: Option<(f32, usize, usize)> = None;
        let total: u32 = t.counts[..t.bins].iter().map(|c| c.x).sum();
        for axis in (0..3).filter(|&a| usable.test(a)) {
            for k in 1..t.bins {
                let left = t.boxes[axis][..k]
                    .iter()
                    .fold(Aabb::EMPTY, |a, b| a.union(*b));
                let right = t.boxes[axis][k..]
                    .iter()
                    .fold(Aabb::EMPTY, |a, b| a.union(*b));
                let lc: u32 = t.counts[..k].iter().map(|c| c[axis]).sum();
                let rc = total - lc;
                if lc == 0 || rc == 0 {
                    continue;
                }
                let cost = left.half_area() * lc as f32 + right.half_area() * rc as f32;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
        best
    }

    #[test]
    fn the_three_axis_sweep_picks_the_plane_an_axis_by_axis_sweep_picks() {
        let mut seed = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move |m: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % m
        };
        for case in 0..2000 {
            let bins = 2 + next(31) as usize;
            let mut t = BinTable::new(bins);
            // Few distinct coordinates and counts, so that equal costs and empty bins occur.
            let n = 1 + next(40) as u32;
            for _ in 0..n {
                let a = Vec3A::from([0, 1, 2].map(|_| next(4) as f32));
                let b = Vec3A::from([0, 1, 2].map(|_| next(4) as f32));
                let prim = Aabb::prim(
                    Bounds {
                        min: a.min(b),
                        max: a.max(b),
                    },
                    0,
                );
                for axis in 0..3 {
                    let k = next(bins as u64) as usize;
                    t.boxes[axis][k] = t.boxes[axis][k].union(prim);
                    t.counts[k][axis] += 1;
                }
            }
            let usable = BVec4A::new(next(5) > 0, next(5) > 0, next(5) > 0, false);
            let expected = cheapest_plane_axis_by_axis(&t, usable);
            assert_eq!(
                t.cheapest_plane(usable, n as usize),
                expected,
                "case {case}"
            );
        }
    }

    /// Splits `prims` with the binned builder's plane search down to small nodes, checking
    /// at every node that each side's grid holds the centroids of its triangles and its box
    /// their boxes.
    fn split_checking_grids(ctx: &Ctx, prims: &mut [Prim], (bounds, grid): Side, depth: u32) {
        let n = prims.len();
        let inside = |b: &Aabb, p: &Prim| {
            let c = p.centroid();
            (b.lo.cmple(c) & (-b.hi).cmpge(c)).bitmask() & 7 == 7
        };
        assert!(prims.iter().all(|p| inside(&grid, p)), "depth {depth}");
        assert!(
            prims.iter().all(|p| bounds.union(*p) == bounds),
            "depth {depth}"
        );
        if n <= SMALL {
            return;
        }
        let mut table = BinTable::new(32);
        let mut node = Prims { prims, first: 0 };
        if let Split::At { mid, left, right } =
            ctx.binned_split(&mut node, bounds, grid, false, &mut table)
        {
            let (l, r) = prims.split_at_mut(mid);
            split_checking_grids(ctx, l, left, depth + 1);
            split_checking_grids(ctx, r, right, depth + 1);
        }
    }

    #[test]
    fn a_binned_split_leaves_each_childs_centroids_inside_its_grid() {
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let ctx = Ctx {
            options: BuildOptions::default(),
        };
        // Boxes of every size from points to half the scene, some flat on an axis, so that
        // clipped grids are loose on some axes and tight on others.
        for case in 0..20 {
            let mut prims: Vec<Prim> = (0..3000)
                .map(|i| {
                    let a = Vec3A::new(next(), next(), next()) * 100.0;
                    let size = Vec3A::new(next(), next(), next()) * 50.0 * next().powi(4);
                    let flat = Vec3A::select(
                        glam::BVec3A::new(i % 7 == 0, false, false),
                        Vec3A::ZERO,
                        size,
                    );
                    Aabb::prim(
                        Bounds {
                            min: a,
                            max: a + flat,
                        },
                        i,
                    )
                })
                .collect();
            let side = side_bounds(&prims);
            split_checking_grids(&ctx, &mut prims, side, case);
        }
    }
}
