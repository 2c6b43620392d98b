//! A scene's geometry put together: its meshes, each loaded, moved by its transform and
//! given its material override, then the ground plane, in that order (the triangle order
//! the hit records' primitive indices follow). The scene file's syntax is
//! [`super::scene_file`]'s.

use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec3};

use crate::error::{Error, Result};
use crate::geometry::Aabb;
use crate::input::MeshFile;
use crate::input::scene_file::MeshSource;
use crate::material::{Material, Materials};
use crate::mesh::Mesh;

/// One mesh of a scene: where it comes from and how it is placed.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedMesh {
    /// The file or generator.
    pub source: MeshSource,
    /// The transform from the mesh's coordinates to the scene's, or `None` to keep them as
    /// they are (bit for bit: an identity matrix would still turn -0 into +0).
    pub transform: Option<Mat4>,
    /// A material for every triangle of this mesh instead of its own, or `None`.
    pub material: Option<Material>,
    /// The line of the scene file that placed it (its `[[mesh]]` table), for errors; `None`
    /// for the one-mesh forms, whose errors stay the mesh file's own.
    pub(crate) line: Option<usize>,
}

impl PlacedMesh {
    /// A mesh as it is, with its own materials.
    pub fn plain(source: MeshSource) -> Self {
        PlacedMesh {
            source,
            transform: None,
            material: None,
            line: None,
        }
    }
}

/// The ground plane a scene asks for: a square at `y = height`, facing up (+y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    /// Its diffuse albedo.
    pub albedo: [f32; 3],
    /// Its height, or `None` for just under the meshes ([`Ground::GAP`]).
    pub height: Option<f32>,
    /// Its side, or `None` for [`Ground::SIZE`] times the meshes' bounding radius.
    pub size: Option<f32>,
}

impl Ground {
    /// The default albedo: darker than the meshes' default grey (0.7), so that they stand
    /// out against it.
    pub const ALBEDO: [f32; 3] = [0.5, 0.5, 0.5];
    /// The default side in bounding radii of the meshes: far enough that shadows and the
    /// light it bounces stay on it, near enough that the float precision at its edges
    /// stays far below the rays' offset (1e-4 radii).
    pub const SIZE: f32 = 20.0;
    /// The default gap below the meshes' lowest point, in bounding radii: so that the
    /// ground never coincides with a floor the meshes have (coplanar surfaces would fight
    /// over every ray), while staying ten times the rays' offset.
    pub const GAP: f32 = 1e-3;

    /// The two triangles under `bounds` (the meshes' box), counter-clockwise seen from above.
    fn mesh(&self, bounds: &Aabb) -> Mesh {
        let radius = bounds.extent().length() * 0.5;
        let radius = if radius > 0.0 { radius } else { 1.0 };
        let height = self.height.unwrap_or(bounds.min.y - Ground::GAP * radius);
        let half = self.size.unwrap_or(Ground::SIZE * radius) * 0.5;
        let c = bounds.center();
        let (x0, x1, z0, z1) = (c.x - half, c.x + half, c.z - half, c.z + half);
        Mesh::new(
            vec![
                Vec3::new(x0, height, z0),
                Vec3::new(x0, height, z1),
                Vec3::new(x1, height, z1),
                Vec3::new(x1, height, z0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }
}

/// Everything a scene's geometry is made of: its meshes in file order, then the ground
/// plane if it asks for one.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMeshes {
    /// The meshes, at least one.
    pub meshes: Vec<PlacedMesh>,
    /// The ground plane, if asked for.
    pub ground: Option<Ground>,
    /// The scene file, for errors that name a line of it.
    pub(crate) scene: PathBuf,
}

/// A scene's geometry loaded: every mesh's triangles and materials, then the ground's.
pub struct LoadedScene {
    /// The triangles, materials, warnings and notes of every mesh, in order.
    pub file: MeshFile,
    /// The box around the meshes, without the ground: what the auto framing, the depth
    /// shading and the default reach of ambient occlusion measure, so that a ground plane
    /// changes none of them.
    pub bounds: Aabb,
}

impl From<MeshSource> for SceneMeshes {
    fn from(source: MeshSource) -> Self {
        SceneMeshes {
            meshes: vec![PlacedMesh::plain(source)],
            ground: None,
            scene: PathBuf::new(),
        }
    }
}

impl SceneMeshes {
    /// The geometry alone, as [`SceneMeshes::load_with_materials`] puts it together.
    pub fn load(&self) -> Result<Mesh> {
        Ok(self.load_with_materials()?.file.mesh)
    }

    /// Every mesh loaded, transformed and given its material override, then the ground.
    /// A mesh named twice is loaded once.
    pub fn load_with_materials(&self) -> Result<LoadedScene> {
        let mut loaded: Vec<(usize, Mesh, Materials)> = Vec::new();
        let mut warnings = Vec::new();
        let mut notes = Vec::new();
        let mut file_camera = None;
        for (i, placed) in self.meshes.iter().enumerate() {
            let earlier = self.meshes[..i]
                .iter()
                .position(|p| p.source == placed.source)
                .and_then(|first| loaded.iter().find(|(j, ..)| *j == first));
            let (mesh, materials) = match earlier {
                Some((_, mesh, materials)) => (mesh.clone(), materials.clone()),
                None => {
                    let file =
                        placed
                            .source
                            .load_with_materials()
                            .map_err(|e| match placed.line {
                                Some(line) => Error::input_at(&self.scene, line, e.to_string()),
                                None => e,
                            })?;
                    warnings.extend(file.warnings);
                    notes.extend(file.notes);
                    if i == 0 {
                        file_camera = file.camera;
                    }
                    (file.mesh, file.materials)
                }
            };
            loaded.push((i, mesh, materials));
        }
        let mut parts = Vec::with_capacity(loaded.len());
        for ((_, mesh, materials), placed) in loaded.into_iter().zip(&self.meshes) {
            parts.push(self.place(placed, mesh, materials)?);
        }
        let bounds = parts
            .iter()
            .map(|(m, _)| m.bounds())
            .fold(Aabb::EMPTY, |b, m| b.grown(m.min).grown(m.max));
        if let Some(ground) = &self.ground {
            let mesh = ground.mesh(&bounds);
            self.check_placed(&mesh, "the ground", None)?;
            parts.push((mesh, Materials::uniform(Material::diffuse(ground.albedo))));
        }
        let several = parts.len() > 1;
        let mut parts = parts.into_iter();
        let (mut mesh, mut materials) = parts.next().expect("a scene has a mesh");
        for (m, mat) in parts {
            materials.append(mesh.triangle_count(), &mat, m.triangle_count());
            mesh.append(&m);
        }
        if several {
            // Only the total can be too large: each part passed its check.
            mesh.check(&self.scene)?;
        }
        Ok(LoadedScene {
            file: MeshFile {
                mesh,
                materials,
                warnings,
                notes,
                // A file's own camera (glTF) frames that file as it stands: a scene of
                // one mesh, not moved.
                camera: match self.meshes.as_slice() {
                    [only] if only.transform.is_none() => file_camera,
                    _ => None,
                },
            },
            bounds,
        })
    }

    /// One mesh moved by its transform and given its material.
    fn place(
        &self,
        placed: &PlacedMesh,
        mut mesh: Mesh,
        materials: Materials,
    ) -> Result<(Mesh, Materials)> {
        if let Some(transform) = placed.transform {
            mesh = mesh.transformed(transform);
            let what = format!("{} after its transform", placed.source.name());
            self.check_placed(&mesh, &what, placed.line)?;
        }
        let materials = match placed.material {
            Some(material) => {
                // The override is the whole look: vertex colours would tint it.
                mesh.colors.clear();
                Materials::uniform(material)
            }
            None => materials,
        };
        Ok((mesh, materials))
    }

    /// The checks a loader makes, for geometry the scene file moved or made: a transform
    /// can carry vertices past the coordinate limit.
    fn check_placed(&self, mesh: &Mesh, what: &str, line: Option<usize>) -> Result<()> {
        mesh.check(Path::new(what)).map_err(|e| {
            let message = match e {
                Error::Input { path, message, .. } => format!("{}: {message}", path.display()),
                e => e.to_string(),
            };
            match line {
                Some(line) => Error::input_at(&self.scene, line, message),
                None => Error::input(&self.scene, message),
            }
        })
    }

    /// The geometry's name for reports: the mesh's name alone, or every mesh's joined by
    /// `+`, ending in `ground` where there is one.
    pub fn name(&self) -> String {
        let mut names: Vec<String> = self.meshes.iter().map(|m| m.source.name()).collect();
        if self.ground.is_some() {
            names.push("ground".into());
        }
        names.join(" + ")
    }
}

/// The transform of a `[[mesh]]` table: scaled, then turned about x, then y, then z (each
/// right-handed: counter-clockwise looking down the axis towards the origin), then moved.
/// Angles are in degrees; whole quarter turns are exact.
pub(crate) fn transform(translate: Vec3, rotate_degrees: Vec3, scale: Vec3) -> Mat4 {
    let [x, y, z] = rotate_degrees.to_array().map(sin_cos_degrees);
    let about_x = Mat3::from_cols(Vec3::X, Vec3::new(0.0, x.1, x.0), Vec3::new(0.0, -x.0, x.1));
    let about_y = Mat3::from_cols(Vec3::new(y.1, 0.0, -y.0), Vec3::Y, Vec3::new(y.0, 0.0, y.1));
    let about_z = Mat3::from_cols(Vec3::new(z.1, z.0, 0.0), Vec3::new(-z.0, z.1, 0.0), Vec3::Z);
    let linear = about_z * about_y * about_x * Mat3::from_diagonal(scale);
    Mat4::from_translation(translate) * Mat4::from_mat3(linear)
}

/// The sine and cosine of an angle in degrees, exact at whole quarter turns (where the
/// radian form would leave a cosine of -4e-8 instead of 0).
fn sin_cos_degrees(degrees: f32) -> (f32, f32) {
    let d = (degrees as f64).rem_euclid(360.0);
    if d == 0.0 {
        (0.0, 1.0)
    } else if d == 90.0 {
        (1.0, 0.0)
    } else if d == 180.0 {
        (0.0, -1.0)
    } else if d == 270.0 {
        (-1.0, 0.0)
    } else {
        let (s, c) = d.to_radians().sin_cos();
        (s as f32, c as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_are_right_handed_in_x_y_z_order() {
        let t =
            |r: [f32; 3], p: Vec3| transform(Vec3::ZERO, r.into(), Vec3::ONE).transform_point3(p);
        assert_eq!(t([90.0, 0.0, 0.0], Vec3::Y), Vec3::Z);
        assert_eq!(t([0.0, 90.0, 0.0], Vec3::Z), Vec3::X);
        assert_eq!(t([0.0, 0.0, 90.0], Vec3::X), Vec3::Y);
        // About x first (y to z), then about y (z to x).
        assert_eq!(t([90.0, 90.0, 0.0], Vec3::Y), Vec3::X);
        assert_eq!(t([0.0, -90.0, 0.0], Vec3::Z), -Vec3::X);
        assert_eq!(t([0.0, 450.0, 0.0], Vec3::Z), Vec3::X);
        let half = t([0.0, 0.0, 45.0], Vec3::X);
        assert!((half - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn scale_then_rotate_then_translate() {
        let m = transform(
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 90.0),
            Vec3::new(2.0, 1.0, 1.0),
        );
        // x scaled to 2, turned onto y, moved by 10 in x.
        assert_eq!(m.transform_point3(Vec3::X), Vec3::new(10.0, 2.0, 0.0));
    }

    #[test]
    fn the_ground_faces_up_under_the_bounds() {
        let bounds = Aabb::from_points([Vec3::new(-1.0, 2.0, -1.0), Vec3::new(3.0, 4.0, 1.0)]);
        let ground = Ground {
            albedo: Ground::ALBEDO,
            height: None,
            size: None,
        };
        let mesh = ground.mesh(&bounds);
        for i in 0..2 {
            let [a, b, c] = mesh.corners(i);
            assert!((b - a).cross(c - a).y > 0.0);
        }
        let g = mesh.bounds();
        assert!(g.max.y < 2.0 && g.max.y > 1.99);
        assert_eq!(g.center().x, 1.0);
        let radius = bounds.extent().length() * 0.5;
        assert!((g.extent().x - Ground::SIZE * radius).abs() < 1e-3);
    }
}
