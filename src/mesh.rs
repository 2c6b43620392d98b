//! The triangle mesh every stage works on: one vertex list and one triangle list, with
//! triangle `i` being the i-th triangle of the input in file order.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::Aabb;

mod normals;
mod polygon;

pub use normals::DEFAULT_CREASE_ANGLE;

pub use polygon::{EAR_CLIP_BUDGET, Triangulation, triangulate_polygon};

/// Largest coordinate magnitude accepted. The watertight intersection multiplies three
/// coordinate differences together; with |x| <= 1e12 every such product stays finite in f32.
pub(crate) const MAX_COORDINATE: f32 = 1e12;

/// An indexed triangle mesh. Loaders and generators guarantee (through [`Mesh::check`])
/// that it has at least one triangle, that every index is in range and that every
/// vertex a triangle uses is finite and within `MAX_COORDINATE` (1e12 in magnitude).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The vertex positions in world space, indexed by [`Mesh::triangles`]. Vertices no
    /// triangle uses are allowed and ignored.
    pub positions: Vec<Vec3>,
    /// The triangles in input order, each as three indices into [`Mesh::positions`]; a
    /// triangle's position in this list is its primitive index in every later stage.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex shading normals, indexed like [`Mesh::positions`], or empty for none (the
    /// renderer then computes smooth normals with a crease angle). A zero normal means "use
    /// the triangle's own normal" at that corner.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, indexed like [`Mesh::positions`], or empty for none.
    /// As in OBJ and PLY, `(0, 0)` is the image's bottom-left corner and v grows upwards
    /// (the glTF loader flips its v to match).
    pub uvs: Vec<Vec2>,
    /// Per-vertex linear RGB colours multiplying the base colour, indexed like
    /// [`Mesh::positions`], or empty for none (white).
    pub colors: Vec<Vec3>,
}

impl Mesh {
    /// The mesh as given, unchecked: call [`Mesh::check`] before handing it on.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Mesh {
            positions,
            triangles,
            ..Mesh::default()
        }
    }

    /// The number of triangles, degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corners of triangle `i`.
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| self.positions[v as usize])
    }

    /// The box around every vertex a triangle uses (the "auto" camera frames this box).
    pub fn bounds(&self) -> Aabb {
        self.triangles
            .par_iter()
            .fold(
                || Aabb::EMPTY,
                |b, t| {
                    t.iter()
                        .fold(b, |b, &v| b.grown(self.positions[v as usize]))
                },
            )
            .reduce(|| Aabb::EMPTY, Aabb::union)
    }

    /// Triangles whose area is exactly zero. They are kept (their index still counts in the
    /// file order) but no ray ever hits them.
    pub fn degenerate_count(&self) -> usize {
        (0..self.triangles.len())
            .into_par_iter()
            .filter(|&i| {
                let [a, b, c] = self.corners(i);
                (b - a).cross(c - a) == Vec3::ZERO
            })
            .count()
    }

    /// Appends `other`'s triangles after this mesh's, keeping both orders. A vertex
    /// attribute only one side has is filled on the other with its "none" value: a zero
    /// normal (the triangle's own), texture coordinate (0, 0), white.
    pub fn append(&mut self, other: &Mesh) {
        let offset = self.positions.len() as u32;
        let (mine, theirs) = (self.positions.len(), other.positions.len());
        fn join<T: Copy>(a: &mut Vec<T>, b: &[T], mine: usize, theirs: usize, none: T) {
            if a.is_empty() && b.is_empty() {
                return;
            }
            a.resize(mine, none);
            if b.is_empty() {
                a.resize(mine + theirs, none);
            } else {
                a.extend_from_slice(b);
            }
        }
        join(&mut self.normals, &other.normals, mine, theirs, Vec3::ZERO);
        join(&mut self.uvs, &other.uvs, mine, theirs, Vec2::ZERO);
        join(&mut self.colors, &other.colors, mine, theirs, Vec3::ONE);
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + offset)));
    }

    /// The mesh moved by `transform` (an affine matrix): positions as points, normals by
    /// the inverse transpose and renormalised. A mirroring transform (negative determinant)
    /// also reverses each triangle's winding, so that the front face stays the front face.
    pub fn transformed(mut self, transform: Mat4) -> Mesh {
        for p in &mut self.positions {
            *p = transform.transform_point3(*p);
        }
        let linear = Mat3::from_mat4(transform);
        let normal_matrix = linear.inverse().transpose();
        for n in &mut self.normals {
            if *n != Vec3::ZERO {
                *n = (normal_matrix * *n).normalize_or_zero();
            }
        }
        if linear.determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
        self
    }

    /// Rejects what no renderer can use: no triangles, an index past the vertex list, a
    /// vertex that is NaN, infinite or beyond `MAX_COORDINATE` (1e12), more triangles than a
    /// `u32` index can name.
    pub fn check(&self, path: &Path) -> Result<()> {
        if self.triangles.is_empty() {
            return Err(Error::input(path, "the mesh has no triangles"));
        }
        if self.triangles.len() >= u32::MAX as usize {
            return Err(Error::input(
                path,
                format!(
                    "the mesh has {} triangles; at most {} are supported",
                    self.triangles.len(),
                    u32::MAX - 1
                ),
            ));
        }
        let n = self.positions.len();
        for (what, len) in [
            ("normals", self.normals.len()),
            ("texture coordinates", self.uvs.len()),
            ("colours", self.colors.len()),
        ] {
            if len != 0 && len != n {
                return Err(Error::input(
                    path,
                    format!("the mesh has {len} vertex {what} for {n} vertices"),
                ));
            }
        }
        for (i, tri) in self.triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(Error::input(
                    path,
                    format!("triangle {i} uses vertex {v}, but there are only {n} vertices"),
                ));
            }
            for &v in tri {
                if let Some(problem) = coordinate_problem(self.positions[v as usize]) {
                    return Err(Error::input(
                        path,
                        format!("triangle {i} has a vertex with {problem}"),
                    ));
                }
                let v = v as usize;
                let finite = self.normals.get(v).is_none_or(|n| n.is_finite())
                    && self.uvs.get(v).is_none_or(|t| t.is_finite())
                    && self.colors.get(v).is_none_or(|c| c.is_finite());
                if !finite {
                    return Err(Error::input(
                        path,
                        format!(
                            "triangle {i} has a vertex with a NaN or infinite normal, texture coordinate or colour"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// What is wrong with a vertex no renderer can use: a NaN or infinite coordinate, or one
/// beyond `MAX_COORDINATE`; `None` for a good vertex. The text completes "a vertex with ...".
pub(crate) fn coordinate_problem(p: Vec3) -> Option<String> {
    let xyz = p.to_array();
    if p.is_nan() {
        Some(format!("a NaN coordinate {xyz:?}"))
    } else if !p.is_finite() {
        Some(format!(
            "an infinite coordinate {xyz:?} (beyond the f32 range)"
        ))
    } else if p.abs().max_element() > MAX_COORDINATE {
        Some(format!("a coordinate beyond +-{MAX_COORDINATE:e}: {xyz:?}"))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE],
            vec![[0, 1, 2], [1, 3, 2]],
        )
    }

    #[test]
    fn append_offsets_indices() {
        let mut m = quad();
        m.append(&quad());
        assert_eq!(m.triangle_count(), 4);
        assert_eq!(m.triangles[2], [4, 5, 6]);
        assert_eq!(m.corners(3), quad().corners(1));
    }

    #[test]
    fn check_rejects_bad_meshes() {
        let p = Path::new("m.obj");
        assert!(quad().check(p).is_ok());
        assert!(Mesh::default().check(p).is_err());
        let mut bad = quad();
        bad.triangles[1][2] = 4;
        assert!(bad.check(p).unwrap_err().to_string().contains("vertex 4"));
        let mut nan = quad();
        nan.positions[3].y = f32::NAN;
        assert!(nan.check(p).unwrap_err().to_string().contains("NaN"));
    }

    #[test]
    fn degenerate_triangles_are_counted() {
        let mut m = quad();
        m.triangles.push([0, 0, 1]);
        m.positions.push(Vec3::new(2.0, 0.0, 0.0));
        m.triangles.push([0, 1, 4]); // collinear
        assert_eq!(m.degenerate_count(), 2);
    }
}
