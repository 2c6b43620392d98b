//! Materials: a diffuse albedo and an emitted radiance per triangle, from an OBJ's MTL file
//! (`Kd`, `Ke`) or the defaults. Geometry stays in [`crate::mesh::Mesh`]; this is how it looks.

use bytemuck::{Pod, Zeroable};

use crate::intersect::Triangle;

/// The albedo of triangles without a material: a mid grey.
pub(crate) const DEFAULT_ALBEDO: [f32; 3] = [0.7, 0.7, 0.7];

/// A diffuse (Lambertian) material, as the kernels read it (`Material` in cl/common.cl).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Diffuse reflectance per channel, in [0, 1].
    pub albedo: [f32; 3],
    /// Padding of `albedo` to 16 bytes (one vector load); always 0.
    pub pad0: f32,
    /// Emitted radiance per channel (0 for surfaces that do not glow).
    pub emission: [f32; 3],
    /// Padding of `emission` to 16 bytes (one vector load); always 0.
    pub pad1: f32,
}

impl Material {
    /// A surface that reflects `albedo` and emits nothing.
    pub fn diffuse(albedo: [f32; 3]) -> Self {
        Material {
            albedo,
            pad0: 0.0,
            emission: [0.0; 3],
            pad1: 0.0,
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
}

impl Default for Material {
    fn default() -> Self {
        Material::diffuse(DEFAULT_ALBEDO)
    }
}

/// The materials of a mesh: a list, and each triangle's index into it (file order).
#[derive(Clone, Debug, PartialEq)]
pub struct Materials {
    /// The materials triangles refer to by index; never empty as the loaders make it.
    /// `list[0]` is what a triangle not covered by `per_triangle` uses.
    pub list: Vec<Material>,
    /// `per_triangle[i]` is triangle i's material; empty means every triangle uses `list[0]`.
    pub per_triangle: Vec<u32>,
}

impl Default for Materials {
    fn default() -> Self {
        Materials::uniform(Material::default())
    }
}

impl Materials {
    /// Stores each triangle's material index (looked up by its file-order index).
    pub(crate) fn assign(&self, triangles: &mut [Triangle]) {
        for t in triangles {
            t.material = self.index_of(t.prim as usize);
        }
    }

    /// One material for every triangle.
    pub fn uniform(material: Material) -> Self {
        Materials {
            list: vec![material],
            per_triangle: Vec::new(),
        }
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
}
