//! Materials: how each triangle looks, from an OBJ's MTL file, a glTF file's PBR materials
//! or the defaults, and the textures they read ([`texture`]). Geometry stays in
//! [`crate::mesh::Mesh`]; this is how it looks.

use bytemuck::{Pod, Zeroable};

use crate::intersect::Triangle;

pub mod surface;
pub mod texture;

pub use texture::{Texture, Wrap};

/// A material's texture slot that holds no texture.
pub const NO_TEXTURE: i32 = -1;

/// The albedo of triangles without a material: a mid grey.
pub(crate) const DEFAULT_ALBEDO: [f32; 3] = [0.7, 0.7, 0.7];

/// A material as the kernels read it (`Material` in cl/common.cl): seven 16-byte rows.
/// Texture slots are indices into [`Materials::textures`], or [`NO_TEXTURE`]. How it
/// scatters light is [`Material::bsdf`], one of [`Bsdf`]'s models (src/render/bsdf.rs and
/// cl/bsdf.cl), blended with a metal by [`Material::metallic`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Diffuse reflectance (base colour) per channel, in [0, 1]; multiplies the base
    /// colour texture and the vertex colours.
    pub albedo: [f32; 3],
    /// Base colour texture (sRGB in the file, linear as stored), or [`NO_TEXTURE`].
    pub base_texture: i32,
    /// Emitted radiance per channel (0 for surfaces that do not glow); multiplies the
    /// emission texture.
    pub emission: [f32; 3],
    /// Emission texture, or [`NO_TEXTURE`].
    pub emission_texture: i32,
    /// Metalness in [0, 1] (glTF's `metallicFactor`; 0 from MTL files).
    pub metallic: f32,
    /// Perceptual roughness in [0, 1] (glTF's `roughnessFactor`; 1 from MTL files).
    pub roughness: f32,
    /// glTF's metallic-roughness texture (roughness in green, metalness in blue), or
    /// [`NO_TEXTURE`].
    pub metallic_roughness_texture: i32,
    /// Tangent-space normal map (OpenGL convention: +y up, as glTF and most MTL files), or
    /// [`NO_TEXTURE`].
    pub normal_texture: i32,
    /// Scale of the normal map's x and y (glTF's `normalTexture.scale`; 1 otherwise).
    pub normal_scale: f32,
    /// Cut-out mask: where this texture's alpha is below `alpha_cutoff` the surface is not
    /// there (no hit for any ray), or [`NO_TEXTURE`] for an opaque surface.
    pub alpha_texture: i32,
    /// The alpha below which a masked surface is a hole (0.5 from MTL files; glTF's
    /// `alphaCutoff`, divided by the base colour factor's alpha).
    pub alpha_cutoff: f32,
    /// Ambient occlusion texture (red channel), or [`NO_TEXTURE`].
    pub occlusion_texture: i32,
    /// A tint of the specular part: the conductor's reflectance, the plastic's coating
    /// reflection, the dielectrics' transmission (MTL `Ks` or `Tf`); 1 leaves it untinted.
    pub specular: [f32; 3],
    /// The scattering model: a [`Bsdf`] code.
    pub bsdf: u32,
    /// A conductor's complex index of refraction, real part per channel; all 0 reflects
    /// with Schlick's Fresnel from the base colour (times `specular`) as glTF's metals do.
    pub eta: [f32; 3],
    /// The index of refraction of a dielectric, or of a plastic's coating (inside over
    /// outside, the side the winding's normal points to being outside).
    pub ior: f32,
    /// A conductor's complex index of refraction, imaginary part (absorption) per channel.
    pub k: [f32; 3],
    /// Keeps the rows whole; 0.
    pub reserved: u32,
}

/// Metals by name, for [`Material::eta`] and [`Material::k`]: complex indices of refraction
/// at about 650, 550 and 450 nm (red, green, blue), from measured data (Johnson and
/// Christy 1972; Rakic et al. 1998) as renderers commonly tabulate them.
pub const CONDUCTORS: [(&str, [f32; 3], [f32; 3]); 6] = [
    ("gold", [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
    ("silver", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
    ("copper", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
    ("aluminium", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("iron", [2.911, 2.950, 2.585], [3.089, 2.932, 2.767]),
    ("chromium", [3.105, 3.186, 2.315], [3.323, 3.320, 3.139]),
];

/// The scattering models ([`Material::bsdf`]); src/render/bsdf.rs is the host's version of
/// cl/bsdf.cl, which evaluates and samples them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Bsdf {
    /// Lambertian: the base colour over pi.
    Diffuse,
    /// A metal: GGX microfacets (smooth below a roughness of about 0.03) with a conductor's
    /// Fresnel reflectance.
    Conductor,
    /// Glass and water: GGX microfacets that reflect or refract, with Fresnel and total
    /// internal reflection; smooth below a roughness of about 0.03.
    Dielectric,
    /// A window pane: a smooth dielectric sheet of no thickness, reflecting and passing
    /// light straight through (its inner reflections summed).
    ThinDielectric,
    /// A diffuse base under a GGX dielectric coating.
    Plastic,
}

impl Bsdf {
    /// Every model, in code order.
    pub const ALL: [Bsdf; 5] = [
        Bsdf::Diffuse,
        Bsdf::Conductor,
        Bsdf::Dielectric,
        Bsdf::ThinDielectric,
        Bsdf::Plastic,
    ];

    /// Its [`Material::bsdf`] code (`BSDF_*` in the kernels).
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// The model of a code; diffuse for an unknown one.
    pub fn from_code(code: u32) -> Bsdf {
        Bsdf::ALL
            .get(code as usize)
            .copied()
            .unwrap_or(Bsdf::Diffuse)
    }

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Bsdf::Diffuse => "diffuse",
            Bsdf::Conductor => "conductor",
            Bsdf::Dielectric => "dielectric",
            Bsdf::ThinDielectric => "thin-dielectric",
            Bsdf::Plastic => "plastic",
        }
    }
}

impl Material {
    /// A surface that reflects `albedo` and emits nothing.
    pub fn diffuse(albedo: [f32; 3]) -> Self {
        Material {
            albedo,
            base_texture: NO_TEXTURE,
            emission: [0.0; 3],
            emission_texture: NO_TEXTURE,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: NO_TEXTURE,
            normal_texture: NO_TEXTURE,
            normal_scale: 1.0,
            alpha_texture: NO_TEXTURE,
            alpha_cutoff: 0.5,
            occlusion_texture: NO_TEXTURE,
            specular: [1.0; 3],
            bsdf: Bsdf::Diffuse.code(),
            eta: [0.0; 3],
            ior: 1.5,
            k: [0.0; 3],
            reserved: 0,
        }
    }

    /// A material of model `bsdf` with base colour `albedo` and perceptual roughness
    /// `roughness` (0 smooth, 1 rough), the rest as [`Material::diffuse`]'s.
    pub fn with_bsdf(bsdf: Bsdf, albedo: [f32; 3], roughness: f32) -> Self {
        Material {
            bsdf: bsdf.code(),
            roughness,
            ..Material::diffuse(albedo)
        }
    }

    /// A surface that reflects `albedo` and emits `emission` (radiance per channel, >= 0).
    pub fn emitting(albedo: [f32; 3], emission: [f32; 3]) -> Self {
        Material {
            emission,
            ..Material::diffuse(albedo)
        }
    }

    /// Whether any channel of the emission is positive: triangles with this material are
    /// lights.
    pub fn emits(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0)
    }

    /// Whether the material has holes: rays pass where its mask's alpha is below the
    /// cutoff.
    pub fn is_masked(&self) -> bool {
        self.alpha_texture != NO_TEXTURE
    }

    /// Whether the material reads a texture while shading (base colour, emission,
    /// metalness and roughness, or a normal map; the occlusion map is not read by the
    /// kernels, the cut-out mask is [`Material::is_masked`]).
    pub fn shades_with_textures(&self) -> bool {
        [
            self.base_texture,
            self.emission_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
        ]
        .iter()
        .any(|&t| t != NO_TEXTURE)
    }

    /// Every texture slot, for renumbering.
    fn texture_slots(&mut self) -> [&mut i32; 6] {
        [
            &mut self.base_texture,
            &mut self.emission_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.alpha_texture,
            &mut self.occlusion_texture,
        ]
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::diffuse(DEFAULT_ALBEDO)
    }
}

/// The materials of a mesh: a list, each triangle's index into it (file order), and the
/// textures the materials name.
#[derive(Clone, Debug, PartialEq)]
pub struct Materials {
    /// The materials triangles refer to by index; never empty as the loaders make it.
    /// `list[0]` is what a triangle not covered by `per_triangle` uses.
    pub list: Vec<Material>,
    /// `per_triangle[i]` is triangle i's material; empty means every triangle uses `list[0]`.
    pub per_triangle: Vec<u32>,
    /// The textures [`Material`]'s slots index.
    pub textures: Vec<Texture>,
}

impl Default for Materials {
    fn default() -> Self {
        Materials::uniform(Material::default())
    }
}

impl Materials {
    /// Stores each triangle's material index (looked up by its file-order index), and
    /// marks the triangles of masked materials, and the emitters when `two_sided_lights`.
    pub(crate) fn assign(&self, triangles: &mut [Triangle], two_sided_lights: bool) {
        use crate::intersect::{TRIANGLE_MASKED, TRIANGLE_TWO_SIDED};
        use rayon::prelude::*;
        triangles.par_iter_mut().with_min_len(4096).for_each(|t| {
            t.material = self.index_of(t.prim as usize);
            let m = &self.list[t.material as usize];
            t.flags = 0;
            if m.is_masked() {
                t.flags |= TRIANGLE_MASKED;
            }
            if two_sided_lights && m.emits() {
                t.flags |= TRIANGLE_TWO_SIDED;
            }
        });
    }

    /// One material for every triangle.
    pub fn uniform(material: Material) -> Self {
        Materials {
            list: vec![material],
            per_triangle: Vec::new(),
            textures: Vec::new(),
        }
    }

    /// Appends the materials of `other_triangles` more triangles (the mesh appended after
    /// `own_triangles` of this list's), renumbering their material and texture indices.
    pub fn append(&mut self, own_triangles: usize, other: &Materials, other_triangles: usize) {
        let material_offset = self.list.len() as u32;
        let texture_offset = self.textures.len() as i32;
        let mut per_triangle: Vec<u32> = (0..own_triangles).map(|i| self.index_of(i)).collect();
        per_triangle.extend((0..other_triangles).map(|i| other.index_of(i) + material_offset));
        self.per_triangle = per_triangle;
        self.list.extend(other.list.iter().map(|m| {
            let mut m = *m;
            for slot in m.texture_slots() {
                if *slot != NO_TEXTURE {
                    *slot += texture_offset;
                }
            }
            m
        }));
        self.textures.extend_from_slice(&other.textures);
    }

    /// Whether any material in the list has a cut-out mask.
    pub fn has_masks(&self) -> bool {
        self.list.iter().any(Material::is_masked)
    }

    /// Triangle `i`'s material index.
    pub(crate) fn index_of(&self, triangle: usize) -> u32 {
        self.per_triangle.get(triangle).copied().unwrap_or(0)
    }

    /// Triangle `triangle`'s material (by file-order index).
    pub fn of(&self, triangle: usize) -> &Material {
        &self.list[self.index_of(triangle) as usize]
    }

    /// Whether any material in the list emits, whether or not a triangle uses it.
    pub fn has_emitters(&self) -> bool {
        self.list.iter().any(Material::emits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_materials_cover_every_triangle() {
        let m = Materials::uniform(Material::emitting([0.5; 3], [1.0, 0.0, 0.0]));
        assert_eq!(m.index_of(12345), 0);
        assert!(m.of(7).emits());
        assert!(m.has_emitters());
        assert!(!Materials::default().has_emitters());
    }

    #[test]
    fn appending_renumbers_materials_and_textures() {
        let mut a = Materials::uniform(Material::diffuse([0.1; 3]));
        a.textures.push(Texture::solid([1.0; 4]));
        a.list[0].base_texture = 0;
        let mut b = Materials::uniform(Material::diffuse([0.2; 3]));
        b.list.push(Material {
            normal_texture: 0,
            ..Material::diffuse([0.3; 3])
        });
        b.per_triangle = vec![1, 0];
        b.textures.push(Texture::solid([0.5; 4]));
        a.append(2, &b, 3);
        assert_eq!(a.per_triangle, vec![0, 0, 2, 1, 1]);
        assert_eq!(a.list[2].normal_texture, 1);
        assert_eq!(a.list[0].base_texture, 0);
        assert_eq!(a.list[1].base_texture, NO_TEXTURE);
        assert_eq!(a.textures.len(), 2);
    }
}
