//! Textures as the renderer keeps them: linear RGBA texels in rows, the first row the
//! image's top, with a wrap mode per axis. Files become textures in `crate::input`
//! (`input/texture.rs`); this module knows nothing of files.

/// What a texture coordinate outside [0, 1] reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The texture tiles the plane (OBJ's and glTF's default).
    #[default]
    Repeat,
    /// The edge texels extend outwards (MTL `-clamp on`, glTF `CLAMP_TO_EDGE`).
    Clamp,
    /// Every other tile is mirrored (glTF `MIRRORED_REPEAT`).
    Mirror,
}

impl Wrap {
    /// The code the kernels read (`WRAP_*` in the generated constants).
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::Clamp => 1,
            Wrap::Mirror => 2,
        }
    }
}

/// A texture: `width * height` linear RGBA texels, row by row from the image's top row.
/// Colour textures (base colour, emission) were sRGB in their file and are stored linear;
/// data textures (normals, masks, metallic-roughness, occlusion) are stored as read.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages: a file name or "glTF image 3".
    pub name: String,
    /// Width in texels, at least 1.
    pub width: u32,
    /// Height in texels, at least 1.
    pub height: u32,
    /// The texels, `width * height` of them, row-major from the top row.
    pub texels: Vec<[f32; 4]>,
    /// Wrap mode along u (across a row) and along v (down the columns).
    pub wrap: [Wrap; 2],
}

impl Texture {
    /// A 1x1 texture of one value: what a missing texture file becomes (grey), and tests.
    pub fn solid(value: [f32; 4]) -> Texture {
        Texture {
            name: "solid".into(),
            width: 1,
            height: 1,
            texels: vec![value],
            wrap: [Wrap::Repeat; 2],
        }
    }
}
