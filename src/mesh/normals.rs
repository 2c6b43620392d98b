//! Smooth vertex normals for meshes that come without them: each triangle corner gets the
//! angle-weighted mean of the normals of the triangles around its position whose normals
//! lie within the crease angle of its own, so that curved surfaces shade smoothly and
//! edges sharper than the crease stay sharp. A position whose corners end up with
//! different normals is split into one vertex per normal.

use glam::Vec3;
use rayon::prelude::*;

use super::Mesh;

/// The crease angle of meshes without normals when nothing else is said, in degrees:
/// curved surfaces tessellated as coarsely as a 20-sided sphere (42 degrees between
/// neighbouring faces) still shade round, while boxes, rooms and architecture (90-degree
/// edges) keep their edges.
pub const DEFAULT_CREASE_ANGLE: f32 = 60.0;

/// Corners around one position at most compared pairwise; a position shared by more (a
/// fan's hub) gets the plain mean of them, keeping the cost linear.
const MAX_PAIRWISE: usize = 256;

impl Mesh {
    /// Gives every corner without a normal (a mesh without normals, or a zero normal where
    /// the file gave none) a smooth one with `crease_degrees` (0: none are computed and the
    /// mesh stays faceted). Corners with normals keep theirs. Triangles keep their order
    /// and corners their positions; vertices may be split or renumbered.
    pub fn fill_normals(&mut self, crease_degrees: f32) {
        if crease_degrees <= 0.0 || crease_degrees.is_nan() {
            return;
        }
        let has = |v: u32| {
            self.normals
                .get(v as usize)
                .is_some_and(|n| *n != Vec3::ZERO)
        };
        if self.triangles.iter().flatten().all(|&v| has(v)) {
            return;
        }
        let cos_crease = crease_degrees.min(180.0).to_radians().cos();
        let faces: Vec<Vec3> = (0..self.triangles.len())
            .into_par_iter()
            .map(|i| {
                let [a, b, c] = self.corners(i);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        // Corners (3 triangle + k) without a normal, grouped by exact position: files often
        // repeat a vertex per face. Sorting, not hashing: millions of corners sort fast.
        let key = |c: u32| {
            let v = self.triangles[c as usize / 3][c as usize % 3];
            self.positions[v as usize].to_array().map(f32::to_bits)
        };
        let mut corners: Vec<u32> = (0..3 * self.triangles.len() as u32)
            .filter(|&c| !has(self.triangles[c as usize / 3][c as usize % 3]))
            .collect();
        corners.par_sort_unstable_by_key(|&c| key(c));
        let angle = |c: u32| {
            let p = self.corners(c as usize / 3);
            let k = c as usize % 3;
            let w = (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]);
            if w.is_finite() { w } else { 0.0 }
        };
        let groups: Vec<&[u32]> = corners.chunk_by(|&a, &b| key(a) == key(b)).collect();
        let faces = &faces;
        let normals: Vec<(u32, Vec3)> = groups
            .par_iter()
            .flat_map_iter(|group| {
                let weighted: Vec<Vec3> = group
                    .iter()
                    .map(|&c| faces[c as usize / 3] * angle(c))
                    .collect();
                let all: Vec3 = weighted.iter().sum();
                group.iter().map(move |&c| {
                    let own = faces[c as usize / 3];
                    let n = if group.len() > MAX_PAIRWISE {
                        all
                    } else {
                        group
                            .iter()
                            .zip(&weighted)
                            .filter(|(other, _)| faces[**other as usize / 3].dot(own) >= cos_crease)
                            .map(|(_, w)| *w)
                            .sum::<Vec3>()
                    };
                    (c, n.normalize_or_zero())
                })
            })
            .collect();
        self.split_by_normal(normals);
    }

    /// Gives each corner (3 triangle + k) in `normals` its normal: corners of one vertex
    /// with equal normals share it, others get copies of the vertex.
    fn split_by_normal(&mut self, mut normals: Vec<(u32, Vec3)>) {
        let n = self.positions.len();
        if self.normals.is_empty() {
            self.normals = vec![Vec3::ZERO; n];
        }
        let vertex = |c: u32| self.triangles[c as usize / 3][c as usize % 3];
        // By vertex, then normal, then corner: equal (vertex, normal) runs share a vertex,
        // and the first run of each vertex keeps its number.
        normals.par_sort_unstable_by_key(|&(c, n)| (vertex(c), n.to_array().map(f32::to_bits), c));
        let mut last: Option<(u32, [u32; 3])> = None;
        let mut index = 0;
        for (c, normal) in normals {
            let v = self.triangles[c as usize / 3][c as usize % 3];
            let bits = normal.to_array().map(f32::to_bits);
            match last {
                Some((lv, lb)) if lv == v && lb == bits => {}
                Some((lv, _)) if lv == v => {
                    index = self.positions.len() as u32;
                    self.positions.push(self.positions[v as usize]);
                    self.normals.push(normal);
                    if !self.uvs.is_empty() {
                        self.uvs.push(self.uvs[v as usize]);
                    }
                    if !self.colors.is_empty() {
                        self.colors.push(self.colors[v as usize]);
                    }
                }
                _ => {
                    index = v;
                    self.normals[v as usize] = normal;
                }
            }
            last = Some((v, bits));
            self.triangles[c as usize / 3][c as usize % 3] = index;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube of 12 triangles sharing 8 vertices, faces outwards.
    fn cube() -> Mesh {
        let p = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh::new(p, t)
    }

    #[test]
    fn a_cube_keeps_its_edges_and_its_faces_are_flat() {
        let mut m = cube();
        m.fill_normals(DEFAULT_CREASE_ANGLE);
        assert_eq!(
            m.positions.len(),
            24,
            "each corner of the cube is split three ways"
        );
        for (i, tri) in m.triangles.iter().enumerate() {
            let [a, b, c] = m.corners(i);
            let face = (b - a).cross(c - a).normalize();
            for &v in tri {
                assert!((m.normals[v as usize] - face).length() < 1e-6);
            }
        }
        // the same corners, in the same triangle order
        let before = cube();
        for i in 0..12 {
            assert_eq!(m.corners(i), before.corners(i));
        }
    }

    #[test]
    fn past_the_crease_angle_a_cube_corner_is_averaged() {
        let mut m = cube();
        m.fill_normals(100.0);
        assert_eq!(m.positions.len(), 8);
        let n = m.normals[7];
        assert!((n - Vec3::ONE.normalize()).length() < 1e-5, "{n}");
    }

    #[test]
    fn zero_crease_angle_leaves_the_mesh_faceted_and_given_normals_stay() {
        let mut m = cube();
        m.fill_normals(0.0);
        assert!(m.normals.is_empty());
        let mut m = cube();
        m.normals = vec![Vec3::Y; 8];
        m.fill_normals(60.0);
        assert_eq!(m.normals, vec![Vec3::Y; 8]);
    }

    #[test]
    fn repeated_vertices_are_smoothed_as_one() {
        // two triangles folded 30 degrees along x, sharing no vertex indices
        let s = 30f32.to_radians();
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::ZERO,
            Vec3::new(0.0, -s.sin(), s.cos()),
            Vec3::X,
        ];
        let mut m = Mesh::new(p, vec![[0, 1, 2], [3, 4, 5]]);
        m.fill_normals(60.0);
        let n0 = m.normals[m.triangles[0][0] as usize];
        let n1 = m.normals[m.triangles[1][0] as usize];
        assert!((n0 - n1).length() < 1e-6, "{n0} {n1}");
        assert!(n0.y > 0.9 && n0.z > 0.1, "between both faces: {n0}");
    }
}
