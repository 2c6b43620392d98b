//! Compressed wide BVH (Ylitie, Karras, Laine, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs", HPG 2017): 8-wide nodes of 80 bytes whose child boxes are
//! quantized to 8 bits per plane against a per-node grid, a third of [`super::wide`]'s
//! 256-byte node. Fewer bytes per visit is what incoherent rays on a GPU need.
//!
//! A node's inner children are stored contiguously from `child_base`, in slot order, so one
//! index and an 8-bit mask find them all; its leaf children's triangles are contiguous from
//! `triangle_base`, at most 3 per child and 24 per node. Children are placed in slots by the
//! direction they lie in from the node's centre, so that visiting slots in the order of a
//! ray's direction signs is roughly front to back.
//!
//! The quantized boxes are conservative as the kernel computes them: the host checks every
//! plane with the device's own f32 arithmetic (`origin + q * scale`, each rounded once), so
//! a dequantized box never cuts into the box it stands for.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::Bin32Bvh;
use super::SahCost;
use crate::geometry::surface_area_f64;
use crate::intersect::Triangle;

/// Triangles a leaf child holds at most (the metadata's unary count has 3 bits).
pub(crate) const MAX_LEAF_TRIANGLES: usize = 3;
/// The low 5 bits of an inner child's metadata byte are 24 + its slot; a leaf's are the
/// offset of its first triangle from `triangle_base`, below 24.
const INNER_META: u8 = 0b001_11000;

/// An 80-byte compressed 8-wide node. Child `k`'s box on axis `a` is
/// `origin[a] + lo_a[k] * 2^(exponent[a] - 127)` to the same with `hi_a[k]`.
/// Mirrors `CwbvhNode` in cl/nodes.cl; cl/cwbvh.cl traverses it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CwbvhNode {
    /// The grid's origin: the node's box minimum.
    pub origin: [f32; 3],
    /// The grid's spacing per axis as a biased power-of-two exponent (an f32's exponent).
    pub exponent: [u8; 3],
    /// Bit k set: slot k holds an inner node.
    pub inner_mask: u8,
    /// Index of the first inner child node.
    pub child_base: u32,
    /// Index of the first triangle of the leaf children.
    pub triangle_base: u32,
    /// Per slot: 0 for empty; an inner child `0b001_11000 | slot`; a leaf of n triangles
    /// `(2^n - 1) << 5 | offset` (offset from `triangle_base`, below 24).
    pub meta: [u8; 8],
    /// Per slot: the child box's low x plane in grid steps from `origin[0]`, rounded down
    /// so that it lies at or below the true box under the kernel's f32 arithmetic (0 for
    /// an empty slot).
    pub lo_x: [u8; 8],
    /// Per slot: the low y plane, as `lo_x`.
    pub lo_y: [u8; 8],
    /// Per slot: the low z plane, as `lo_x`.
    pub lo_z: [u8; 8],
    /// Per slot: the child box's high x plane in grid steps from `origin[0]`, rounded up
    /// so that it lies at or above the true box (0 for an empty slot).
    pub hi_x: [u8; 8],
    /// Per slot: the high y plane, as `hi_x`.
    pub hi_y: [u8; 8],
    /// Per slot: the high z plane, as `hi_x`.
    pub hi_z: [u8; 8],
}

/// The host mirror of the kernel's box test and slot decoding, which the unit tests hold
/// the quantization to.
#[cfg(test)]
impl CwbvhNode {
    /// The grid spacing on `axis`, as the kernel computes it.
    pub(crate) fn scale(&self, axis: usize) -> f32 {
        f32::from_bits((self.exponent[axis] as u32) << 23)
    }

    /// Slot `k`'s box, dequantized with the kernel's arithmetic.
    pub(crate) fn child_box(&self, k: usize) -> (Vec3, Vec3) {
        let deq = |axis: usize, q: u8| self.origin[axis] + q as f32 * self.scale(axis);
        (
            Vec3::new(
                deq(0, self.lo_x[k]),
                deq(1, self.lo_y[k]),
                deq(2, self.lo_z[k]),
            ),
            Vec3::new(
                deq(0, self.hi_x[k]),
                deq(1, self.hi_y[k]),
                deq(2, self.hi_z[k]),
            ),
        )
    }

    /// The kernel's box test of slot `k` (the traversal loop of cl/cwbvh.cl), operation for
    /// operation: plane q of an axis lies at `q * a + b` along the ray, one fused
    /// multiply-add, with the near planes moved nearer and the far ones farther by a bound
    /// on that form's rounding error. True when the ray may meet the box in `[0, t_max]`.
    pub(crate) fn fused_box_test(&self, k: usize, org: Vec3, inv: Vec3, t_max: f32) -> bool {
        let planes = [
            (self.lo_x[k], self.hi_x[k]),
            (self.lo_y[k], self.hi_y[k]),
            (self.lo_z[k], self.hi_z[k]),
        ];
        let (mut near, mut far) = (0.0f32, t_max);
        for (axis, (lo, hi)) in planes.into_iter().enumerate() {
            let a = self.scale(axis) * inv[axis];
            let b = (self.origin[axis] - org[axis]) * inv[axis];
            let err = (255.0 * a.abs() + b.abs()) * (8.0 * f32::EPSILON) + f32::MIN_POSITIVE;
            let (q_near, q_far) = if inv[axis].is_sign_negative() {
                (hi, lo)
            } else {
                (lo, hi)
            };
            // f32::max and min skip a NaN, as the kernel's fmax and fmin do.
            near = near.max((q_near as f32).mul_add(a, b - err));
            far = far.min((q_far as f32).mul_add(a, b + err));
        }
        near <= far
    }

    /// What slot `k` holds.
    pub(crate) fn child(&self, k: usize) -> Child {
        let meta = self.meta[k];
        if meta == 0 {
            Child::Empty
        } else if meta & INNER_META == INNER_META {
            let before = (self.inner_mask as u32 & ((1u32 << k) - 1)).count_ones();
            Child::Node(self.child_base + before)
        } else {
            Child::Leaf {
                first: self.triangle_base + (meta & 0x1F) as u32,
                count: (meta >> 5).count_ones(),
            }
        }
    }
}

/// A slot's content.
#[cfg(test)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Child {
    Empty,
    Node(u32),
    Leaf { first: u32, count: u32 },
}

/// A compressed tree: nodes (root first), triangles in the order its leaves reference them,
/// its depth in nodes and its SAH cost (one traversal step per wide node).
pub(crate) struct Compressed {
    pub(crate) nodes: Vec<CwbvhNode>,
    pub(crate) triangles: Vec<Triangle>,
    pub(crate) depth: u32,
    pub(crate) sah_cost: f64,
}

/// A binary node of the tree being collapsed: the builder's nodes, with leaves of more than
/// [`MAX_LEAF_TRIANGLES`] split into small subtrees of tight boxes.
#[derive(Clone, Copy)]
struct Binary {
    lo: Vec3,
    hi: Vec3,
    /// Inner: children's indices; leaf: first triangle (into the flat tree's) and count.
    a: u32,
    b: u32,
    leaf: bool,
}

impl Binary {
    fn area(&self) -> f64 {
        surface_area_f64(self.lo, self.hi)
    }

    fn centre(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }
}

/// Rebuilds a thesis-layout tree as a compressed 8-wide tree.
pub(crate) fn compress(flat: &Bin32Bvh) -> Compressed {
    let tree = small_leaves(flat);
    let mut nodes = vec![CwbvhNode::default()];
    let mut triangles = Vec::with_capacity(flat.triangles.len());
    let mut cost = SahCost::default();
    let mut depth = 0;
    // (binary node, its wide node's index, depth), filled depth-first.
    let mut todo = vec![(0usize, 0usize, 1u32)];
    while let Some((root, index, d)) = todo.pop() {
        depth = depth.max(d);
        cost.add_inner(tree[root].area());
        let children = slots(&tree, open(&tree, root), tree[root].centre());
        let mut node = CwbvhNode {
            child_base: nodes.len() as u32,
            triangle_base: triangles.len() as u32,
            ..Default::default()
        };
        for (k, child) in children.iter().enumerate() {
            let Some(c) = *child else { continue };
            let n = &tree[c];
            if n.leaf {
                let offset = triangles.len() as u32 - node.triangle_base;
                node.meta[k] = (((1u32 << n.b) - 1) << 5 | offset) as u8;
                triangles.extend_from_slice(&flat.triangles[n.a as usize..(n.a + n.b) as usize]);
                cost.add_leaf(n.area(), n.b);
            } else {
                node.meta[k] = INNER_META | k as u8;
                node.inner_mask |= 1 << k;
            }
        }
        quantize(&mut node, &tree, &children);
        // Inner children take consecutive indices in slot order.
        let mut next = nodes.len();
        for c in children.iter().flatten().filter(|c| !tree[**c].leaf) {
            todo.push((*c, next, d + 1));
            next += 1;
        }
        nodes.resize(next, CwbvhNode::default());
        nodes[index] = node;
    }
    let root_area = tree[0].area();
    Compressed {
        nodes,
        triangles,
        depth,
        sah_cost: cost.relative_to(root_area).unwrap_or(0.0),
    }
}

/// The flat tree as [`Binary`] nodes (root first), every leaf of more than
/// [`MAX_LEAF_TRIANGLES`] triangles split in halves of its range until none is.
fn small_leaves(flat: &Bin32Bvh) -> Vec<Binary> {
    let mut out: Vec<Binary> = Vec::with_capacity(flat.nodes.len() * 2);
    // (flat node or a leaf's range, where to link it), depth-first.
    enum Todo {
        Node(usize),
        Range(u32, u32),
    }
    let mut todo = vec![(Todo::Node(0), None::<(usize, bool)>)];
    while let Some((item, parent)) = todo.pop() {
        let index = out.len() as u32;
        if let Some((p, right)) = parent {
            if right {
                out[p].b = index;
            } else {
                out[p].a = index;
            }
        }
        let (first, count) = match item {
            Todo::Node(i) => {
                let n = &flat.nodes[i];
                if !n.is_leaf() {
                    out.push(Binary {
                        lo: Vec3::from(n.min),
                        hi: Vec3::from(n.max),
                        a: 0,
                        b: 0,
                        leaf: false,
                    });
                    let at = index as usize;
                    todo.push((Todo::Node(n.right_or_count as usize), Some((at, true))));
                    todo.push((Todo::Node(n.left_or_first as usize), Some((at, false))));
                    continue;
                }
                (n.left_or_first, n.count())
            }
            Todo::Range(first, count) => (first, count),
        };
        let (lo, hi) = range_bounds(&flat.triangles[first as usize..(first + count) as usize]);
        if count as usize <= MAX_LEAF_TRIANGLES {
            out.push(Binary {
                lo,
                hi,
                a: first,
                b: count,
                leaf: true,
            });
        } else {
            out.push(Binary {
                lo,
                hi,
                a: 0,
                b: 0,
                leaf: false,
            });
            let half = count / 2;
            let at = index as usize;
            todo.push((Todo::Range(first + half, count - half), Some((at, true))));
            todo.push((Todo::Range(first, half), Some((at, false))));
        }
    }
    out
}

fn range_bounds(triangles: &[Triangle]) -> (Vec3, Vec3) {
    let mut lo = Vec3::INFINITY;
    let mut hi = Vec3::NEG_INFINITY;
    for t in triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(Vec3::from(v));
            hi = hi.max(Vec3::from(v));
        }
    }
    (lo, hi)
}

/// The up to 8 nodes a wide node over `root` holds: its children, with the largest inner
/// one opened while there is room (as [`super::wide::collapse`] does). A leaf root is its
/// own only child.
fn open(tree: &[Binary], root: usize) -> Vec<usize> {
    if tree[root].leaf {
        return vec![root];
    }
    let mut children = vec![tree[root].a as usize, tree[root].b as usize];
    super::wide::open_largest(
        &mut children,
        8,
        |c| (!tree[c].leaf).then_some([tree[c].a as usize, tree[c].b as usize]),
        |c| tree[c].area(),
    );
    children
}

/// Places children in slots: slot s (bits: x, y, z, most significant first) wants the child
/// lying furthest towards the corner whose set bits are the box's maximum side, so that a
/// ray entering from corner c meets slot c's child first. Greedy by the strongest pull.
fn slots(tree: &[Binary], children: Vec<usize>, centre: Vec3) -> [Option<usize>; 8] {
    let corner = |s: usize| {
        Vec3::new(
            if s & 4 != 0 { 1.0 } else { -1.0 },
            if s & 2 != 0 { 1.0 } else { -1.0 },
            if s & 1 != 0 { 1.0 } else { -1.0 },
        )
    };
    let mut pairs = [(f32::MIN, 0usize, 0usize); 64];
    let mut len = 0;
    for (i, &c) in children.iter().enumerate() {
        let offset = tree[c].centre() - centre;
        for s in 0..8 {
            // A NaN pull (no finite centre) sorts last, never panics.
            let pull = offset.dot(corner(s));
            pairs[len] = (if pull.is_nan() { f32::MIN } else { pull }, i, s);
            len += 1;
        }
    }
    let pairs = &mut pairs[..len];
    pairs.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut out = [None; 8];
    let mut placed = [false; 8];
    for &mut (_, i, s) in pairs {
        if !placed[i] && out[s].is_none() {
            out[s] = Some(children[i]);
            placed[i] = true;
        }
    }
    out
}

/// Sets the node's grid and its children's quantized boxes, each plane checked to contain
/// the child's true box under the kernel's f32 arithmetic.
fn quantize(node: &mut CwbvhNode, tree: &[Binary], children: &[Option<usize>; 8]) {
    let present: Vec<(usize, &Binary)> = children
        .iter()
        .enumerate()
        .filter_map(|(k, c)| c.map(|c| (k, &tree[c])))
        .collect();
    let lo = present
        .iter()
        .fold(Vec3::INFINITY, |acc, (_, n)| acc.min(n.lo));
    let hi = present
        .iter()
        .fold(Vec3::NEG_INFINITY, |acc, (_, n)| acc.max(n.hi));
    node.origin = lo.to_array();
    for axis in 0..3 {
        let origin = lo[axis];
        let extent = (hi[axis] - origin) as f64;
        // The smallest power of two that spans the extent in 255 steps, then larger ones
        // until every plane fits after the f32 check.
        let first = if extent > 0.0 && extent.is_finite() {
            ((extent / 255.0).log2().ceil() as i32 + 127).clamp(1, 254)
        } else {
            1
        };
        'exponent: for e in first..=254 {
            let scale = f32::from_bits((e as u32) << 23);
            let deq = |q: u32| origin + q as f32 * scale;
            // Written so that a NaN counts as not (yet) outside the box.
            let below = |q: u32, l: f32| deq(q) < l;
            let above = |q: u32, h: f32| deq(q) > h;
            let mut q_lo = [0u8; 8];
            let mut q_hi = [0u8; 8];
            for (k, n) in &present {
                let (l, h) = (n.lo[axis], n.hi[axis]);
                // Strictly beyond the box after rounding means beyond it before rounding
                // too (rounding is monotonic), so the plane holds both for the kernel's
                // rounded dequantization and for its fused q * a + b form. The grid's own
                // origin (q = 0) is exact.
                let mut a = (((l - origin) as f64 / scale as f64).floor().max(0.0) as u32).min(255);
                while a > 0 && !below(a, l) {
                    a -= 1;
                }
                let mut b = (((h - origin) as f64 / scale as f64).ceil().max(0.0) as u32).min(255);
                while b < 255 && !above(b, h) {
                    b += 1;
                }
                if !above(b, h) && e < 254 {
                    continue 'exponent;
                }
                q_lo[*k] = a as u8;
                q_hi[*k] = b as u8;
            }
            node.exponent[axis] = e as u8;
            let (l, h) = match axis {
                0 => (&mut node.lo_x, &mut node.hi_x),
                1 => (&mut node.lo_y, &mut node.hi_y),
                _ => (&mut node.lo_z, &mut node.hi_z),
            };
            *l = q_lo;
            *h = q_hi;
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{BuildOptions, Bvh};
    use crate::input::generate::Generator;
    use crate::mesh::Mesh;

    /// Every triangle is referenced exactly once and lies inside every box on its path
    /// (their intersection is carried down), every node is reached once.
    fn check(c: &Compressed, flat: &Bin32Bvh) {
        let mut seen = vec![0u32; c.triangles.len()];
        let all = (Vec3::NEG_INFINITY, Vec3::INFINITY);
        let mut todo = vec![(0u32, all)];
        let mut visited = 0;
        while let Some((i, (plo, phi))) = todo.pop() {
            visited += 1;
            let node = &c.nodes[i as usize];
            for k in 0..8 {
                let (lo, hi) = node.child_box(k);
                let (lo, hi) = (lo.max(plo), hi.min(phi));
                match node.child(k) {
                    Child::Empty => {}
                    Child::Node(n) => todo.push((n, (lo, hi))),
                    Child::Leaf { first, count } => {
                        assert!((1..=3).contains(&count));
                        let range = first as usize..(first + count) as usize;
                        for t in &c.triangles[range.clone()] {
                            for v in [t.v0, t.v1, t.v2].map(Vec3::from) {
                                assert!(
                                    v.cmpge(lo).all() && v.cmple(hi).all(),
                                    "{v} outside {lo}..{hi}"
                                );
                            }
                        }
                        for s in &mut seen[range] {
                            *s += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(visited, c.nodes.len(), "every node is reached once");
        assert!(
            seen.iter().all(|&s| s == 1),
            "every triangle referenced once"
        );
        let mut prims: Vec<u32> = c.triangles.iter().map(|t| t.prim).collect();
        prims.sort_unstable();
        let mut expected: Vec<u32> = flat.triangles.iter().map(|t| t.prim).collect();
        expected.sort_unstable();
        assert_eq!(prims, expected);
    }

    fn flat(mesh: &Mesh, max_leaf_size: u32) -> Bin32Bvh {
        let options = BuildOptions {
            max_leaf_size,
            ..Default::default()
        };
        Bin32Bvh::new(Bvh::build(mesh, &options), mesh)
    }

    #[test]
    fn boxes_contain_their_triangles_and_every_triangle_is_reached_once() {
        let mesh = Generator::Sphereflake {
            levels: 1,
            subdivisions: 1,
            ground: 8,
        }
        .generate()
        .unwrap();
        for max_leaf_size in [1, 3, 8, 40] {
            let flat = flat(&mesh, max_leaf_size);
            let c = compress(&flat);
            check(&c, &flat);
            assert!(c.depth >= 2 && c.sah_cost > 0.0);
        }
    }

    /// Rays aimed at the corners, edges and faces of random quantized boxes, wherever they
    /// start: whenever exact arithmetic (f64, far finer than the f32 rounding in question)
    /// says a ray meets the box, the kernel's fused test must say so too.
    #[test]
    fn the_fused_box_test_never_misses_a_box_the_ray_meets() {
        use proptest::prelude::*;
        use proptest::test_runner::{Config, TestRunner};
        let mut runner = TestRunner::new(Config {
            cases: 20_000,
            failure_persistence: None,
            ..Config::default()
        });
        let coordinate = prop_oneof![-1e3f32..1e3, -1e6f32..1e6, -1.0f32..1.0];
        let case = (
            [coordinate.clone(), coordinate.clone(), coordinate.clone()],
            [100u8..150, 100u8..150, 100u8..150],
            [
                (0u8..=255, 0u8..=255),
                (0u8..=255, 0u8..=255),
                (0u8..=255, 0u8..=255),
            ],
            [coordinate.clone(), coordinate.clone(), coordinate],
            [0u8..4, 0u8..4, 0u8..4],
            [0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0],
        );
        runner
            .run(&case, |(origin, exponent, q, org, aim, inside)| {
                let mut node = CwbvhNode {
                    origin,
                    exponent,
                    ..Default::default()
                };
                let mut target = [0.0f32; 3];
                for axis in 0..3 {
                    let (lo, hi) = (q[axis].0.min(q[axis].1), q[axis].0.max(q[axis].1));
                    let (l, h) = match axis {
                        0 => (&mut node.lo_x, &mut node.hi_x),
                        1 => (&mut node.lo_y, &mut node.hi_y),
                        _ => (&mut node.lo_z, &mut node.hi_z),
                    };
                    (l[0], h[0]) = (lo, hi);
                    let plane = |q: u8| origin[axis] + q as f32 * node.scale(axis);
                    // On the lo plane, the hi plane, or between them.
                    target[axis] = match aim[axis] {
                        0 => plane(lo),
                        1 => plane(hi),
                        _ => plane(lo) + (plane(hi) - plane(lo)) * inside[axis],
                    };
                }
                let org = Vec3::from(org);
                let dir = Vec3::from(target) - org;
                let inv = dir.recip();
                // The exact planes: origin + q * scale, in f64.
                let (mut near, mut far) = (0.0f64, f64::INFINITY);
                for axis in 0..3 {
                    let scale = node.scale(axis) as f64;
                    let p = |q: u8| origin[axis] as f64 + q as f64 * scale;
                    let (lo, hi) = (p(q[axis].0.min(q[axis].1)), p(q[axis].0.max(q[axis].1)));
                    let (o, d) = (org[axis] as f64, dir[axis] as f64);
                    if d == 0.0 {
                        if o < lo || o > hi {
                            near = f64::INFINITY;
                        }
                        continue;
                    }
                    let (t0, t1) = ((lo - o) / d, (hi - o) / d);
                    near = near.max(t0.min(t1));
                    far = far.min(t0.max(t1));
                }
                // A margin of 1e-12 keeps the f64 reference's own rounding out of it.
                if near <= far * (1.0 - 1e-12) {
                    prop_assert!(
                        node.fused_box_test(0, org, inv, f32::INFINITY),
                        "missed: org {org}, dir {dir}, exact entry {near}, exit {far}"
                    );
                }
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn a_single_triangle_is_a_root_with_one_leaf() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
        let flat = flat(&mesh, 8);
        let c = compress(&flat);
        check(&c, &flat);
        assert_eq!(c.nodes.len(), 1);
        assert_eq!(
            (0..8)
                .filter(|&k| c.nodes[0].child(k) != Child::Empty)
                .count(),
            1
        );
    }

    #[test]
    fn quantization_is_conservative_for_awkward_coordinates() {
        // Far from the origin, tiny next to large boxes: where (x - origin) / scale rounded
        // in f64 alone would put planes inside the boxes.
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..300u32 {
            let f = i as f32;
            let base = Vec3::new(1.0e5 + f * 0.37, -3.3e4 - f * 1e-3, 7.0 + f * 11.0);
            let size = if i % 7 == 0 { 50.0 } else { 1e-3 };
            positions.extend([
                base,
                base + Vec3::X * size,
                base + Vec3::new(0.0, size, 3.0),
            ]);
            triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = Mesh::new(positions, triangles);
        for max_leaf_size in [1, 8] {
            let flat = flat(&mesh, max_leaf_size);
            check(&compress(&flat), &flat);
        }
    }
}
