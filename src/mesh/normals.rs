//! Smooth vertex normals for meshes that come without them: each triangle corner gets the
//! angle-weighted mean of the normals of the triangles around its position whose normals
//! lie within the crease angle of its own, so that curved surfaces shade smoothly and
//! edges sharper than the crease stay sharp. A position whose corners end up with
//! different normals is split into one vertex per normal.

use std::collections::HashMap;

use glam::Vec3;

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
            .map(|i| {
                let [a, b, c] = self.corners(i);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        // Corners grouped by exact position: files often repeat a vertex per face.
        let mut around: HashMap<[u32; 3], Vec<(u32, u8)>> = HashMap::new();
        for (i, tri) in self.triangles.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                if !has(v) {
                    let key = self.positions[v as usize].to_array().map(f32::to_bits);
                    around.entry(key).or_default().push((i as u32, k as u8));
                }
            }
        }
        let angle = |i: u32, k: u8| {
            let p = self.corners(i as usize);
            let k = k as usize;
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            e1.angle_between(e2)
        };
        let mut corner_normal: HashMap<(u32, u8), Vec3> = HashMap::new();
        for corners in around.values() {
            let weighted: Vec<Vec3> = corners
                .iter()
                .map(|&(i, k)| {
                    let w = angle(i, k);
                    faces[i as usize] * if w.is_finite() { w } else { 0.0 }
                })
                .collect();
            for &(i, k) in corners {
                let own = faces[i as usize];
                let n = if corners.len() > MAX_PAIRWISE {
                    weighted.iter().sum::<Vec3>()
                } else {
                    corners
                        .iter()
                        .zip(&weighted)
                        .filter(|((other, _), _)| faces[*other as usize].dot(own) >= cos_crease)
                        .map(|(_, w)| *w)
                        .sum::<Vec3>()
                };
                corner_normal.insert((i, k), n.normalize_or_zero());
            }
        }
        self.split_by_normal(&corner_normal);
    }

    /// Renumbers vertices so that each corner in `normals` has its own normal: corners of
    /// one vertex with equal normals share a vertex, others get copies.
    fn split_by_normal(&mut self, normals: &HashMap<(u32, u8), Vec3>) {
        let n = self.positions.len();
        if self.normals.is_empty() {
            self.normals = vec![Vec3::ZERO; n];
        }
        let mut copies: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
        let mut first_use = vec![true; n];
        for i in 0..self.triangles.len() {
            for k in 0..3 {
                let Some(&normal) = normals.get(&(i as u32, k as u8)) else {
                    continue;
                };
                let v = self.triangles[i][k];
                let key = (v, normal.to_array().map(f32::to_bits));
                let index = *copies.entry(key).or_insert_with(|| {
                    if std::mem::take(&mut first_use[v as usize]) {
                        self.normals[v as usize] = normal;
                        v
                    } else {
                        let copy = self.positions.len() as u32;
                        self.positions.push(self.positions[v as usize]);
                        self.normals.push(normal);
                        if !self.uvs.is_empty() {
                            self.uvs.push(self.uvs[v as usize]);
                        }
                        if !self.colors.is_empty() {
                            self.colors.push(self.colors[v as usize]);
                        }
                        copy
                    }
                });
                self.triangles[i][k] = index;
            }
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
