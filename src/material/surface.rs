//! What a hit looks like, on the host: the mirror of cl/surface.cl, operation for
//! operation. [`Surface`] holds what the kernels' `SURFACE_PARAMS` receive: the
//! materials, each triangle's corners as indices into the vertex normals, texture
//! coordinates and colours, and the textures' mip chains.

use glam::{Vec2, Vec3};

use super::texture::DeviceTextures;
use super::{Material, Materials, NO_TEXTURE};
use crate::intersect::{TRIANGLE_MASKED, TRIANGLE_TWO_SIDED, Triangle, WatertightRay};
use crate::mesh::Mesh;

/// [`Surface::flags`] bit: the vertices have normals.
pub const SURFACE_NORMALS: u32 = 1;

/// What a surface asks of the kernels beyond plain hits, compiled in only for scenes that
/// have it: each costs registers wherever it is compiled in (the interpolated normal of
/// primary rays took the wide layouts' kernel from 56 to 64 registers on the H200, and 12%
/// of its speed, whether a scene had normals or not).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfaceFeatures {
    /// Cut-out masks: the traversals look each hit's mask up (`ALPHA_MASKS`,
    /// cl/traverse.cl).
    pub masks: bool,
    /// Vertex normals: primary rays shade with the interpolated normal (`SHADING_NORMALS`,
    /// cl/surface.cl).
    pub normals: bool,
    /// Textures read while shading (`TEXTURES`, cl/surface.cl): without, the progressive
    /// modes hold no texture lookups, which are much of their code and so of their
    /// compile time (docs/bench/2026-12-04-first-image.md).
    pub textures: bool,
    /// The scattering models the materials use, a bit per [`Bsdf`](crate::material::Bsdf)
    /// code (`BSDF_MODELS`, cl/bsdf.cl): a program with [`SurfaceFeatures::bsdfs`] holds
    /// these alone.
    pub models: u32,
    /// Whether a material has metalness (`METALLIC`, cl/bsdf.cl).
    pub metallic: bool,
    /// Whether a material emits (`EMITTERS`, cl/integrator.cl): without, the path tracer
    /// holds no light sampling of emitters, whose code (a second traversal among it) costs
    /// compile time and registers in scenes lit by the sky alone.
    pub emitters: bool,
    /// An environment light (`ENVIRONMENT`, cl/environment.cl), which also turns on the
    /// weighing of light and BSDF samples (`MIS`); not the surface's, but compiled in the
    /// same way. [`Surface::features`] leaves it off; the renderer sets it from the scene's
    /// lights.
    pub environment: bool,
    /// Point, spot or directional lights (`PUNCTUAL`, cl/punctual.cl); set as `environment`.
    pub punctual: bool,
}
impl SurfaceFeatures {
    /// The features of a surface with `materials` and, or without, vertex normals (the
    /// environment and punctual lights left off).
    fn of(materials: &[Material], normals: bool) -> SurfaceFeatures {
        let models = materials
            .iter()
            .fold(0, |bits, m| bits | 1u32.checked_shl(m.bsdf).unwrap_or(0));
        let metallic = materials.iter().any(|m| m.metallic > 0.0);
        SurfaceFeatures {
            masks: materials.iter().any(Material::is_masked),
            normals,
            textures: materials.iter().any(Material::shades_with_textures),
            models,
            metallic,
            emitters: materials.iter().any(Material::emits),
            environment: false,
            punctual: false,
        }
    }

    /// Materials other than Lambertian: the path tracer holds the scattering models of
    /// cl/bsdf.cl and weighs light and BSDF samples (`BSDFS`, cl/integrator.cl). Without
    /// them it reaches emitters by light samples alone and keeps the diffuse path
    /// tracer's speed (the models cost the H200 23% a ray: docs/bench/2026-12-03-bsdfs.md).
    pub fn bsdfs(&self) -> bool {
        self.metallic || self.models & !(1 << crate::material::Bsdf::Diffuse.code()) != 0
    }

    /// Whether a path-tracing program compiled for these features holds every scattering
    /// model a surface with `needs` uses: none where all of its materials are Lambertian,
    /// else the models (and metalness) among the program's. A program without a model
    /// would shade its materials as something else, silently.
    pub fn holds_models_of(&self, needs: &SurfaceFeatures) -> bool {
        !needs.bsdfs()
            || (self.bsdfs()
                && needs.models & !self.models == 0
                && (!needs.metallic || self.metallic))
    }

    /// The features of the [`Surface`] made of `mesh` and `materials` once smooth normals
    /// are filled in with `crease_degrees` ([`Mesh::fill_normals`]), known before they are
    /// computed: the kernels can compile meanwhile.
    pub fn before_normals(mesh: &Mesh, materials: &Materials, crease_degrees: f32) -> Self {
        let normals = !mesh.normals.is_empty() || crease_degrees > 0.0;
        SurfaceFeatures::of(&materials.list, normals)
    }
}

/// The parts of `items` one after the other (millions of them: on every core).
fn flat<T: Sync, C: Copy + Default + Send + Sync, const N: usize>(
    items: &[T],
    parts: impl Fn(&T) -> [C; N] + Sync,
) -> Vec<C> {
    use rayon::prelude::*;
    let mut out = vec![C::default(); N * items.len()];
    out.par_chunks_mut(N)
        .zip(items.par_iter())
        .with_min_len(4096)
        .for_each(|(o, i)| o.copy_from_slice(&parts(i)));
    out
}

/// [`Surface::flags`] bit: the vertices have texture coordinates.
pub const SURFACE_UVS: u32 = 2;
/// [`Surface::flags`] bit: the vertices have colours.
pub const SURFACE_COLORS: u32 = 4;

/// How much wider a ray cone grows per unit of distance after a diffuse bounce, in
/// radians: what a bounce ray sees is blurred by the bounce anyway, and reading coarse mip
/// levels there saves texture traffic without a visible change.
pub const BOUNCE_CONE_SPREAD: f32 = 0.1;

/// The shading data of a scene, as the kernels read it (`SURFACE_PARAMS`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    /// The materials, indexed by [`Triangle::material`].
    pub materials: Vec<Material>,
    /// `corners[3 prim + k]`: corner k of triangle `prim` (file order), indexing the
    /// vertex arrays; empty when the mesh has no vertex attributes.
    pub corners: Vec<u32>,
    /// Vertex normals, three floats each, or empty.
    pub normals: Vec<f32>,
    /// Texture coordinates, two floats each, or empty.
    pub uvs: Vec<f32>,
    /// Vertex colours, three floats each, or empty.
    pub colors: Vec<f32>,
    /// The textures' mip chains.
    pub textures: DeviceTextures,
    /// Which vertex arrays exist: [`SURFACE_NORMALS`], [`SURFACE_UVS`], [`SURFACE_COLORS`].
    pub flags: u32,
}

/// What the integrator needs of a hit (`SurfacePoint` in cl/surface.cl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Where rays leave from: off the surface on the ray's side.
    pub origin: Vec3,
    /// Where rays that pass through the surface (refraction) leave from: off the plain
    /// hit point on the far side, not lifted onto the curved surface as `origin` may be
    /// (whence a refracted ray would meet its own triangle again).
    pub through: Vec3,
    /// The unit geometric normal on the ray's side.
    pub ng: Vec3,
    /// The unit shading normal on the ray's side.
    pub ns: Vec3,
    /// The unit shading normal as the mesh orients it.
    pub normal: Vec3,
    /// Base colour: factor, texture and vertex colour.
    pub albedo: Vec3,
    /// Emitted radiance: factor and texture.
    pub emission: Vec3,
    /// Perceptual roughness: factor and texture (glTF's green channel).
    pub roughness: f32,
    /// Metalness: factor and texture (glTF's blue channel).
    pub metallic: f32,
    /// Whether the ray hit the side the winding's normal points to.
    pub front_face: bool,
}

fn dot3(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

fn cross3(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

fn length3(a: Vec3) -> f32 {
    (a.x * a.x + a.y * a.y + a.z * a.z).sqrt()
}

fn lerp3<T>(a: T, b: T, c: T, w: [f32; 3]) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    a * w[0] + b * w[1] + c * w[2]
}

impl Surface {
    /// The shading data of `mesh` with `materials`.
    pub fn new(mesh: &Mesh, materials: &Materials) -> Surface {
        let flags = [
            (!mesh.normals.is_empty(), SURFACE_NORMALS),
            (!mesh.uvs.is_empty(), SURFACE_UVS),
            (!mesh.colors.is_empty(), SURFACE_COLORS),
        ]
        .into_iter()
        .filter_map(|(has, bit)| has.then_some(bit))
        .fold(0, |a, b| a | b);
        Surface {
            materials: materials.list.clone(),
            corners: match flags {
                0 => Vec::new(),
                _ => flat(&mesh.triangles, |t| *t),
            },
            normals: flat(&mesh.normals, |n| n.to_array()),
            uvs: flat(&mesh.uvs, |t| t.to_array()),
            colors: flat(&mesh.colors, |c| c.to_array()),
            textures: DeviceTextures::new(&materials.textures),
            flags,
        }
    }

    /// Whether any material has a cut-out mask: its programs test masks in the traversal.
    pub fn has_masks(&self) -> bool {
        self.materials.iter().any(Material::is_masked)
    }

    /// What of this surface the kernels must be compiled for.
    pub fn features(&self) -> SurfaceFeatures {
        SurfaceFeatures::of(&self.materials, self.flags & SURFACE_NORMALS != 0)
    }

    /// Bytes the kernels' surface buffers take on the device.
    pub fn bytes(&self) -> u64 {
        (size_of_val(self.materials.as_slice())
            + 4 * (self.corners.len() + self.normals.len() + self.uvs.len() + self.colors.len()))
            as u64
            + self.textures.bytes()
    }

    fn corner_indices(&self, prim: u32) -> [usize; 3] {
        let i = 3 * prim as usize;
        [0, 1, 2].map(|k| self.corners[i + k] as usize)
    }

    fn vec3(list: &[f32], i: usize) -> Vec3 {
        Vec3::from_slice(&list[3 * i..3 * i + 3])
    }

    fn vec2(list: &[f32], i: usize) -> Vec2 {
        Vec2::from_slice(&list[2 * i..2 * i + 2])
    }

    /// `surface_uv` in cl/surface.cl.
    pub fn uv(&self, prim: u32, w: [f32; 3]) -> Vec2 {
        if self.flags & SURFACE_UVS == 0 {
            return Vec2::ZERO;
        }
        let [i0, i1, i2] = self.corner_indices(prim);
        let t = |i| Self::vec2(&self.uvs, i);
        lerp3(t(i0), t(i1), t(i2), w)
    }

    /// `mask_keeps` in cl/surface.cl: whether a hit on `tri` by `ray` counts.
    pub fn mask_keeps(&self, tri: &Triangle, ray: &WatertightRay) -> bool {
        if tri.flags & TRIANGLE_MASKED == 0 {
            return true;
        }
        let m = &self.materials[tri.material as usize];
        let uv = self.uv(tri.prim, ray.barycentrics(tri));
        self.textures.sample(m.alpha_texture, uv.to_array(), 0.0)[3] >= m.alpha_cutoff
    }

    /// `sample_footprint` in cl/surface.cl.
    fn footprint(&self, index: i32, uv: Vec2, lod_base: f32) -> Vec3 {
        let t = &self.textures.infos[index as usize];
        let lod = lod_base + 0.5 * (t.width as f32 * t.height as f32).log2();
        Vec3::from_slice(&self.textures.sample(index, uv.to_array(), lod)[..3])
    }

    /// `surface_point` in cl/surface.cl: the surface at the hit of the ray `(org, dir)` on
    /// `tri` at ray parameter `t`, the ray cone `cone_width` wide there, rays leaving
    /// `offset` off it along the geometric normal.
    pub fn point(
        &self,
        tri: &Triangle,
        (org, dir): (Vec3, Vec3),
        t: f32,
        offset: f32,
        cone_width: f32,
    ) -> SurfacePoint {
        let default = Material::default();
        // A surface without materials (frames of geometry alone) shades with the default.
        let m = self
            .materials
            .get(tri.material as usize)
            .unwrap_or(&default);
        let (v0, v1, v2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
        let (e1, e2) = (v1 - v0, v2 - v0);
        let cross_e = cross3(e1, e2);
        let area2 = length3(cross_e);
        let front = cross_e / area2;
        let back = dot3(front, dir) > 0.0;
        let ng = if back { -front } else { front };
        let mut albedo = Vec3::from(m.albedo);
        // An emitter shines from its front face only, unless two-sided.
        let shines = !back || tri.flags & TRIANGLE_TWO_SIDED != 0;
        let mut emission = if shines {
            Vec3::from(m.emission)
        } else {
            Vec3::ZERO
        };
        let (mut roughness, mut metallic) = (m.roughness, m.metallic);
        if self.flags == 0 {
            let p = org + dir * t;
            return SurfacePoint {
                origin: p + ng * offset,
                through: p - ng * offset,
                ng,
                ns: ng,
                normal: front,
                albedo,
                emission,
                roughness,
                metallic,
                front_face: !back,
            };
        }
        let w = WatertightRay::new(&crate::geometry::Ray::new(org, dir)).barycentrics(tri);
        let [i0, i1, i2] = self.corner_indices(tri.prim);
        let mut n = front;
        let mut smooth = false;
        let (mut n0, mut n1, mut n2) = (front, front, front);
        if self.flags & SURFACE_NORMALS != 0 {
            let nv = |i| Self::vec3(&self.normals, i);
            (n0, n1, n2) = (nv(i0), nv(i1), nv(i2));
            smooth = dot3(n0, n0) > 0.0 && dot3(n1, n1) > 0.0 && dot3(n2, n2) > 0.0;
            if smooth {
                let mixed = lerp3(n0, n1, n2, w);
                let len = length3(mixed);
                smooth = len > 0.0;
                if smooth {
                    n = mixed / len;
                }
            }
        }
        if self.flags & SURFACE_UVS != 0 {
            let tv = |i| Self::vec2(&self.uvs, i);
            let (t0, t1, t2) = (tv(i0), tv(i1), tv(i2));
            let uv = lerp3(t0, t1, t2, w);
            let (d1, d2) = (t1 - t0, t2 - t0);
            let uv_det = d1.x * d2.y - d1.y * d2.x;
            let cos_view = dot3(front, dir).abs() / length3(dir);
            let lod_base =
                (cone_width / cos_view.max(1e-4)).log2() + 0.5 * (uv_det.abs() / area2).log2();
            if m.normal_texture != NO_TEXTURE && uv_det != 0.0 {
                let tangent = (e1 * d2.y - e2 * d1.y) / uv_det;
                let bitangent = (e2 * d1.x - e1 * d2.x) / uv_det;
                let mut tn = self.footprint(m.normal_texture, uv, lod_base) * 2.0 - Vec3::ONE;
                tn.x *= m.normal_scale;
                tn.y *= m.normal_scale;
                let tt = tangent - n * dot3(n, tangent);
                let tt_len = length3(tt);
                if tt_len > 0.0 {
                    let tt = tt / tt_len;
                    let mut bt = cross3(n, tt);
                    if dot3(bt, bitangent) < 0.0 {
                        bt = -bt;
                    }
                    let mapped = tt * tn.x + bt * tn.y + n * tn.z;
                    let mapped_len = length3(mapped);
                    if mapped_len > 0.0 {
                        n = mapped / mapped_len;
                    }
                }
            }
            if m.base_texture != NO_TEXTURE {
                albedo *= self.footprint(m.base_texture, uv, lod_base);
            }
            if m.emission_texture != NO_TEXTURE && shines {
                emission *= self.footprint(m.emission_texture, uv, lod_base);
            }
            if m.metallic_roughness_texture != NO_TEXTURE {
                let mr = self.footprint(m.metallic_roughness_texture, uv, lod_base);
                roughness *= mr.y;
                metallic *= mr.z;
            }
        }
        if self.flags & SURFACE_COLORS != 0 {
            let c = |i| Self::vec3(&self.colors, i);
            albedo *= lerp3(c(i0), c(i1), c(i2), w);
        }
        let ns = if dot3(n, ng) < 0.0 { -n } else { n };
        let mut p = lerp3(v0, v1, v2, w);
        let through = p - ng * offset;
        if smooth {
            // Hanika 2021, "Hacking the shadow terminator": see cl/surface.cl.
            let flip = if back { -1.0 } else { 1.0 };
            let (m0, m1, m2) = (n0 * flip, n1 * flip, n2 * flip);
            let d0 = dot3(p - v0, m0).min(0.0);
            let d1 = dot3(p - v1, m1).min(0.0);
            let d2 = dot3(p - v2, m2).min(0.0);
            p -= m0 * (d0 * w[0]) + m1 * (d1 * w[1]) + m2 * (d2 * w[2]);
        }
        SurfacePoint {
            origin: p + ng * offset,
            through,
            ng,
            ns,
            normal: n,
            albedo,
            emission,
            roughness,
            metallic,
            front_face: !back,
        }
    }

    /// Triangle `tri`'s material; the default for a surface without materials.
    pub fn material(&self, tri: &Triangle) -> Material {
        self.materials
            .get(tri.material as usize)
            .copied()
            .unwrap_or_default()
    }

    /// `shading_normal` in cl/surface.cl: the unit shading normal at a primary hit for the
    /// single-hit shade modes, the vertex normals interpolated (no normal map).
    pub fn shading_normal(&self, tri: &Triangle, (org, dir): (Vec3, Vec3)) -> Vec3 {
        let v0 = Vec3::from(tri.v0);
        let cross_e = cross3(Vec3::from(tri.v1) - v0, Vec3::from(tri.v2) - v0);
        let front = cross_e / length3(cross_e);
        if self.flags & SURFACE_NORMALS == 0 {
            return front;
        }
        let w = WatertightRay::new(&crate::geometry::Ray::new(org, dir)).barycentrics(tri);
        let [i0, i1, i2] = self.corner_indices(tri.prim);
        let nv = |i| Self::vec3(&self.normals, i);
        let (n0, n1, n2) = (nv(i0), nv(i1), nv(i2));
        if !(dot3(n0, n0) > 0.0 && dot3(n1, n1) > 0.0 && dot3(n2, n2) > 0.0) {
            return front;
        }
        let mixed = lerp3(n0, n1, n2, w);
        let len = length3(mixed);
        if len > 0.0 { mixed / len } else { front }
    }

    /// `emitted` in cl/integrator.cl: the radiance emitter `e` sends from its point with
    /// barycentrics `(w0, w1, 1 - w0 - w1)`.
    pub fn emitted(&self, e: &Triangle, w0: f32, w1: f32) -> Vec3 {
        let m = &self.materials[e.material as usize];
        let mut le = Vec3::from(m.emission);
        if m.emission_texture != NO_TEXTURE && self.flags & SURFACE_UVS != 0 {
            let uv = self.uv(e.prim, [w0, w1, 1.0 - w0 - w1]);
            le *= Vec3::from_slice(
                &self.textures.sample(m.emission_texture, uv.to_array(), 0.0)[..3],
            );
        }
        le
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intersect::triangles_in_order;

    #[test]
    fn the_features_name_the_models_the_materials_use() {
        use crate::material::Bsdf;
        let bit = |b: Bsdf| 1u32 << b.code();
        let lambert = SurfaceFeatures::of(&[Material::diffuse([0.5; 3])], false);
        assert_eq!(
            (lambert.bsdfs(), lambert.models, lambert.metallic),
            (false, bit(Bsdf::Diffuse), false)
        );
        let gold = Material::with_bsdf(Bsdf::Conductor, [1.0; 3], 0.5);
        let room = SurfaceFeatures::of(&[Material::diffuse([0.5; 3]), gold], false);
        assert!(room.bsdfs() && !room.metallic);
        assert_eq!(room.models, bit(Bsdf::Diffuse) | bit(Bsdf::Conductor));
        // Metalness on a Lambertian base needs the models' code too.
        let metal = Material {
            metallic: 0.5,
            ..Material::diffuse([0.5; 3])
        };
        let metallic = SurfaceFeatures::of(&[metal], false);
        assert!(metallic.bsdfs() && metallic.metallic);
        assert_eq!(metallic.models, bit(Bsdf::Diffuse));
        // Emitters: any material with emission, whatever its model.
        assert!(!lambert.emitters && !room.emitters);
        let lamp = Material {
            emission: [0.0, 0.0, 4.0],
            ..Material::diffuse([0.5; 3])
        };
        assert!(SurfaceFeatures::of(&[Material::diffuse([0.5; 3]), lamp], false).emitters);
        // Textures: a shading texture in any slot; a cut-out mask alone is `masks`.
        assert!(!lambert.textures && !room.textures);
        for slot in 0..5 {
            let mut m = Material::diffuse([0.5; 3]);
            *[
                &mut m.base_texture,
                &mut m.emission_texture,
                &mut m.metallic_roughness_texture,
                &mut m.normal_texture,
                &mut m.alpha_texture,
            ][slot] = 0;
            let f = SurfaceFeatures::of(&[m], false);
            assert_eq!((f.textures, f.masks), (slot < 4, slot == 4), "slot {slot}");
        }
    }

    #[test]
    fn a_program_holds_the_models_of_a_surface_only_with_each_of_them() {
        use crate::material::Bsdf;
        let of = |m: &[Material]| SurfaceFeatures::of(m, false);
        let lambert = of(&[Material::diffuse([0.5; 3])]);
        let gold = of(&[Material::with_bsdf(Bsdf::Conductor, [1.0; 3], 0.5)]);
        let glass = of(&[Material::with_bsdf(Bsdf::Dielectric, [1.0; 3], 0.0)]);
        let both = of(&[
            Material::with_bsdf(Bsdf::Conductor, [1.0; 3], 0.5),
            Material::with_bsdf(Bsdf::Dielectric, [1.0; 3], 0.0),
        ]);
        let metal = of(&[Material {
            metallic: 1.0,
            ..Material::diffuse([0.5; 3])
        }]);
        // Lambertian surfaces need nothing; the defaults' program holds no model.
        for program in [
            SurfaceFeatures::default(),
            lambert,
            gold,
            glass,
            both,
            metal,
        ] {
            assert!(program.holds_models_of(&lambert));
        }
        assert!(!SurfaceFeatures::default().holds_models_of(&gold));
        assert!(!lambert.holds_models_of(&gold));
        assert!(gold.holds_models_of(&gold) && both.holds_models_of(&gold));
        assert!(!glass.holds_models_of(&gold) && !gold.holds_models_of(&both));
        assert!(!lambert.holds_models_of(&metal) && !gold.holds_models_of(&metal));
        assert!(metal.holds_models_of(&metal));
    }

    /// One facet of a coarse unit sphere, its vertex normals the sphere's.
    fn facet() -> (Mesh, Surface, Triangle) {
        let corners = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.8, 0.0, 0.6),
            Vec3::new(0.0, 0.8, 0.6),
        ];
        let mut mesh = Mesh::new(corners.to_vec(), vec![[0, 1, 2]]);
        mesh.normals = corners.to_vec();
        let surface = Surface::new(&mesh, &Materials::default());
        let tri = triangles_in_order(&mesh, [0])[0];
        (mesh, surface, tri)
    }

    /// The shadow-terminator fix lifts a point of a coarse smooth facet off the facet,
    /// outwards, to about where the curved surface its normals describe would be (the
    /// blended tangent planes overshoot the sphere a little on so coarse a facet, as in
    /// Hanika's paper), and only where normals are given.
    #[test]
    fn points_on_a_coarse_sphere_are_lifted_towards_it() {
        let (_, surface, tri) = facet();
        let centroid = Vec3::new(0.8, 0.8, 2.2) / 3.0;
        let eye = Vec3::new(0.0, 0.0, 5.0);
        let dir = (centroid - eye) * 0.5;
        let t = 2.0;
        let p = surface.point(&tri, (eye, dir), t, 0.0, 0.0);
        let before = centroid.length();
        let after = p.origin.length();
        assert!(before < 0.85, "{before}");
        assert!(
            after > before + 0.05 && after < 1.1 && (p.origin - centroid).dot(p.ng) > 0.0,
            "{before} -> {after}"
        );
        // the shading normal is the sphere's there, the geometric one the facet's
        assert!((p.ns - centroid.normalize()).length() < 0.05, "{}", p.ns);
        assert!(p.ng.dot(p.ns) > 0.9);
        // without normals the point stays on the facet
        let mut flat = surface.clone();
        flat.flags = 0;
        let q = flat.point(&tri, (eye, dir), t, 0.0, 0.0);
        assert!((q.origin - centroid).length() < 1e-5);
        assert_eq!(q.ns, q.ng);
    }

    /// Seen from behind, both normals turn to the viewer and the point is not lifted
    /// outwards (away from the viewer).
    #[test]
    fn hits_from_behind_turn_the_normals_to_the_ray() {
        let (_, surface, tri) = facet();
        let centroid = Vec3::new(0.8, 0.8, 2.2) / 3.0;
        let dir = centroid;
        let p = surface.point(&tri, (Vec3::ZERO, dir), 1.0, 0.0, 0.0);
        assert!(p.ng.dot(dir) < 0.0 && p.ns.dot(dir) < 0.0);
        assert!(p.origin.length() <= centroid.length() + 1e-6);
    }
}
