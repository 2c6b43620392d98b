//! The bounding volume hierarchy: top-down SAH builders (binned, and an exact full sweep
//! as the quality reference), post-build optimization, tree statistics, and the device
//! layouts with their host traversals.
//!
//! The builders produce the thesis's layout directly: 32-byte [`Bin32Node`]s in depth-first
//! order (a node's left child is the next node), leaves holding ranges of
//! [`Bvh::prim_order`]. The other layouts ([`bin64`], [`wide4`], [`wide8`], [`cwbvh`]) are
//! made from that tree; [`layout`] names them and lays a tree out in one.

pub mod bin32;
pub mod bin64;
mod build;
pub mod cwbvh;
pub mod layout;
pub mod optimize;
mod stats;
pub mod wide;
pub mod wide4;
pub mod wide8;

pub use bin32::{Bin32Bvh, Bin32Node, LEAF_FLAG};
pub use layout::{DeviceLayout, Layout};
pub use stats::BvhStats;

use serde::Deserialize;

use crate::mesh::Mesh;

/// No tree is deeper than this (nodes on the longest root-to-leaf path). Builders switch
/// to median splits where the SAH would go deeper, so traversal stacks stay bounded.
pub const MAX_DEPTH: u32 = 64;

/// SAH cost of visiting a node (testing its children's boxes), relative to one
/// ray/triangle test. Both are 1: the box pair and the watertight triangle test cost
/// about the same on the devices measured.
pub(crate) const TRAVERSAL_COST: f32 = 1.0;
/// SAH cost of one ray/triangle test.
pub(crate) const INTERSECTION_COST: f32 = 1.0;

/// The SAH cost of a tree as it is summed: each node's surface area weighted by what a
/// visit costs, relative to the root's area (the chance a ray meeting the root meets it).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SahCost(f64);

impl SahCost {
    /// A node visit: its children's boxes are tested.
    pub(crate) fn add_inner(&mut self, area: f64) {
        self.0 += TRAVERSAL_COST as f64 * area;
    }

    /// A leaf of `count` triangles, each tested.
    pub(crate) fn add_leaf(&mut self, area: f64, count: u32) {
        self.0 += INTERSECTION_COST as f64 * area * count as f64;
    }

    /// Adds the nodes another sum covers.
    pub(crate) fn add(&mut self, other: SahCost) {
        self.0 += other.0;
    }

    /// The cost relative to the root's area; `None` where the root has none (every
    /// triangle in one point or line).
    pub(crate) fn relative_to(self, root_area: f64) -> Option<f64> {
        (root_area > 0.0).then(|| self.0 / root_area)
    }
}

/// Which builder makes the tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Builder {
    /// The exact sweep for scenes of up to [`SWEEP_UP_TO`] triangles, binned above: on
    /// small scenes of large triangles the bins miss the best planes (compare.py's spheres
    /// path-trace 2-8% faster on an H100 swept: docs/bench/2026-12-05-auto-builder.md),
    /// and sweeping them takes milliseconds.
    #[default]
    Auto,
    /// Binned SAH over centroids on all three axes (Wald 2007), parallel: fast.
    Binned,
    /// Exact SAH over every centroid-sorted split on all three axes: slow, the reference.
    Sweep,
}

/// The most triangles [`Builder::Auto`] sweeps: about 10 ms on 2 cores.
pub const SWEEP_UP_TO: usize = 16_384;

impl Builder {
    /// Every builder, the default first.
    pub const ALL: [Builder; 3] = [Builder::Auto, Builder::Binned, Builder::Sweep];

    /// The builder that builds a scene of `triangles`: [`Builder::Auto`] picks one.
    pub fn for_triangles(self, triangles: usize) -> Builder {
        match self {
            Builder::Auto if triangles <= SWEEP_UP_TO => Builder::Sweep,
            Builder::Auto => Builder::Binned,
            builder => builder,
        }
    }

    /// The builder's name on the command line (`--builder`), which [`str::parse`] reads
    /// back.
    pub fn name(self) -> &'static str {
        match self {
            Builder::Auto => "auto",
            Builder::Binned => "binned",
            Builder::Sweep => "sweep",
        }
    }

    /// One line on the builder, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            Builder::Auto => "The exact sweep up to 16,384 triangles (milliseconds), binned above",
            Builder::Binned => {
                "Binned SAH over centroids on all three axes (Wald 2007), parallel: fast"
            }
            Builder::Sweep => {
                "Exact SAH over every centroid-sorted split on all three axes: slow, the reference"
            }
        }
    }
}

impl std::str::FromStr for Builder {
    type Err = String;

    /// The builder [`Builder::name`] names.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::error::by_name(s, &Builder::ALL, Builder::name, "builder")
    }
}

/// How to build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Which builder makes the tree.
    pub builder: Builder,
    /// Bins per axis for the binned builder (2 to 64).
    pub bins: u32,
    /// Largest leaf (1 to 255). Bigger nodes are always split; smaller ones become
    /// leaves where that costs less under the SAH.
    pub max_leaf_size: u32,
    /// Deepest tree allowed (2 to [`MAX_DEPTH`]). Where the SAH would go deeper the builder
    /// switches to median splits in time; a node at this depth is a leaf, whatever its size.
    pub max_depth: u32,
    /// Rounds of post-build optimization by node reinsertion (0 to
    /// [`optimize::MAX_ROUNDS`]; 0, the default, is off): each moves the worst-placed
    /// inner nodes to where they cost least, lowering the SAH cost; rounds stop early once
    /// one gains less than [`optimize::MIN_ROUND_GAIN`].
    pub optimize_rounds: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            builder: Builder::Auto,
            bins: 32,
            max_leaf_size: 8,
            max_depth: MAX_DEPTH,
            optimize_rounds: 0,
        }
    }
}

impl BuildOptions {
    /// Checks every option is in its range, naming the flag that is not.
    pub fn check(&self) -> crate::Result<()> {
        if !(2..=build::MAX_BINS as u32).contains(&self.bins) {
            return Err(crate::Error::Invalid(format!(
                "--bins {} is out of range: use 2 to {}",
                self.bins,
                build::MAX_BINS
            )));
        }
        if !(1..=255).contains(&self.max_leaf_size) {
            return Err(crate::Error::Invalid(format!(
                "--max-leaf-size {} is out of range: use 1 to 255",
                self.max_leaf_size
            )));
        }
        if !(2..=MAX_DEPTH).contains(&self.max_depth) {
            return Err(crate::Error::Invalid(format!(
                "maximum depth {} is out of range: use 2 to {MAX_DEPTH}",
                self.max_depth
            )));
        }
        if self.optimize_rounds > optimize::MAX_ROUNDS {
            return Err(crate::Error::Invalid(format!(
                "--optimize {} is out of range: use 0 to {}",
                self.optimize_rounds,
                optimize::MAX_ROUNDS
            )));
        }
        Ok(())
    }
}

/// A built BVH: nodes in depth-first order (root first) and the leaf order of triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    /// The nodes, root first; a leaf's `left_or_first` indexes [`Bvh::prim_order`].
    pub nodes: Vec<Bin32Node>,
    /// `prim_order[i]` is the mesh triangle at position `i` of the leaves' ranges.
    pub prim_order: Vec<u32>,
    /// Nodes on the longest root-to-leaf path (a lone leaf has depth 1).
    pub depth: u32,
}

impl Bvh {
    /// Builds a BVH over the mesh's triangles with rayon's threads. The mesh is meant to
    /// have passed [`Mesh::check`]; any other (NaN coordinates, say) still builds a valid
    /// tree, of no particular quality, without panicking.
    pub fn build(mesh: &Mesh, options: &BuildOptions) -> Bvh {
        let mut bvh = build::build(mesh, options);
        if options.optimize_rounds > 0 {
            bvh.optimize(options.optimize_rounds, options.max_depth);
        }
        bvh
    }

    /// The tree's summary numbers (SAH cost, depth, leaf sizes).
    pub fn stats(&self) -> BvhStats {
        BvhStats::of(self)
    }
}
