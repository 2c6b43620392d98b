//! glTF 2.0 in: `.gltf` (JSON with its buffers and images in files or data URIs) and `.glb`
//! (one binary file). Every triangle primitive of the default scene goes through the node
//! hierarchy's transforms into one triangle list (instances flattened), with its PBR
//! metallic-roughness material and textures, and the first perspective camera.
//!
//! The `gltf` crate parses and validates the JSON (index references in range, required
//! extensions known); everything after that reads its plain JSON structures, not the
//! crate's wrappers (some unwrap where a hostile file can make them panic), and resolves
//! buffers, accessors and images itself with bounds checked before any allocation.

use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use super::MeshFile;
use super::texture::{ColorSpace, decode_texture};
use crate::camera::CameraSettings;
use crate::error::{Error, Result};
use crate::material::{Material, Materials, NO_TEXTURE, Texture, Wrap};
use crate::mesh::Mesh;

/// The most triangles, and the most vertices, a glTF file may hold once its instances are
/// flattened: a few nodes naming one large mesh many times could otherwise ask for more
/// memory than any machine has. Real scenes of this size are beyond one device anyway.
pub const MAX_TRIANGLES: u64 = 1 << 28;

/// The largest image file read (a texture's pixels are bounded by
/// [`super::texture::MAX_TEXTURE_SIZE`] once decoded; this bounds the read itself).
const MAX_IMAGE_BYTES: u64 = 1 << 30;

/// Parses a glTF or GLB file's bytes. `folder` is where its relative URIs point; `None`
/// (no file system, for fuzzing) makes any external file an error. With `read_materials`
/// off only the geometry is read: no materials, no images.
pub(super) fn parse(
    path: &Path,
    bytes: &[u8],
    folder: Option<&Path>,
    read_materials: bool,
) -> Result<MeshFile> {
    let bytes = glb_extent(path, bytes)?;
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| describe(path, e))?;
    let blob = gltf.blob.clone();
    let root = gltf.document.into_json();
    validate(path, &root)?;
    let mut file = Reader {
        path,
        folder,
        root: &root,
        blob,
        buffers: HashMap::new(),
        warnings: Vec::new(),
        notes: Vec::new(),
    };
    file.read(read_materials)
}

/// The crate's validation (every index in range, enumerations known, required extensions
/// read), which everything after relies on, less one rule: an accessor for POSITION
/// without `min` and `max` (which cltrace does not need, and some exporters leave out).
fn validate(path: &Path, root: &json::Root) -> Result<()> {
    use json::validation::{Error as Invalid, Validate};
    // The crate's check of a primitive's POSITION bounds indexes the accessors unchecked
    // (gltf-json 1.4.1 panics on a POSITION index out of range): check it first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions));
            if let Some(a) = position.filter(|a| a.value() >= root.accessors.len()) {
                return Err(Error::input(
                    path,
                    format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes[\"POSITION\"] \
                         = {}: Index out of bounds",
                        a.value()
                    ),
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(
        root,
        json::Path::new,
        &mut |at: &dyn Fn() -> json::Path, e| {
            let at = at();
            let bound = at.as_str().ends_with(".min") || at.as_str().ends_with(".max");
            if !(bound && e == Invalid::Missing) {
                errors.push((at, e));
            }
        },
    );
    match errors.is_empty() {
        true => Ok(()),
        false => Err(describe(path, gltf::Error::Validation(errors))),
    }
}

/// The size of a GLB file's header: magic, version and the file's length, 4 bytes each.
const GLB_HEADER: usize = 12;

/// A GLB file's bytes up to the length its header gives, which the format makes the file's
/// length; other bytes (a `.gltf`'s JSON) as they are. gltf 1.4.1 subtracts the header's
/// size from that length unchecked (a panic where overflow is checked, found by fuzzing)
/// and reads chunks past it, refusing files with bytes after the GLB (gltf-rs/gltf#475).
fn glb_extent<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a [u8]> {
    if bytes.len() < GLB_HEADER || !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    let length = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize;
    if length < GLB_HEADER {
        return Err(Error::input(
            path,
            format!(
                "not a valid GLB file: its header gives a length of {length} bytes, shorter than the {GLB_HEADER}-byte header"
            ),
        ));
    }
    if length > bytes.len() {
        return Err(Error::input(
            path,
            format!(
                "not a valid GLB file: its header gives a length of {length} bytes, but the file holds {} (cut short?)",
                bytes.len()
            ),
        ));
    }
    Ok(&bytes[..length])
}

/// One line for the crate's error: what failed to parse, or the first invalid item.
fn describe(path: &Path, e: gltf::Error) -> Error {
    let message = match e {
        gltf::Error::Validation(errors) => {
            let more = match errors.len() {
                0 | 1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            match errors.first() {
                Some((at, json::validation::Error::Unsupported)) => {
                    format!("needs {at}, an extension cltrace does not read{more}")
                }
                Some((at, error)) => format!("invalid glTF: {at}: {error}{more}"),
                None => "invalid glTF".to_string(),
            }
        }
        gltf::Error::Binary(e) => format!("not a valid GLB file: {e}"),
        gltf::Error::Deserialize(e) => format!("not valid glTF JSON: {e}"),
        e => format!("cannot read the glTF: {e}"),
    };
    Error::input(path, super::clean_line(&message))
}

/// The file being read, with the buffers resolved so far.
struct Reader<'a> {
    path: &'a Path,
    folder: Option<&'a Path>,
    root: &'a json::Root,
    /// A GLB file's binary chunk, the buffer without a URI.
    blob: Option<Vec<u8>>,
    /// Buffers read, by index (each cut to its `byteLength`).
    buffers: HashMap<usize, Vec<u8>>,
    warnings: Vec<String>,
    notes: Vec<String>,
}

/// One mesh primitive placed in the world.
struct Placed {
    mesh: usize,
    transform: Mat4,
}

/// Where a URI's bytes are.
enum Fetched {
    Bytes(Vec<u8>),
    /// The file named does not exist: why, as a line.
    Missing(String),
}

impl Reader<'_> {
    fn err(&self, message: impl Into<String>) -> Error {
        Error::input(self.path, super::clean_line(&message.into()))
    }

    fn read(&mut self, read_materials: bool) -> Result<MeshFile> {
        let (instances, camera_node) = self.instances()?;
        self.check_size(&instances)?;
        let mut mesh = Mesh::default();
        let mut per_triangle: Vec<u32> = Vec::new();
        let mut skipped_modes = 0usize;
        let mut other_uvs = false;
        for placed in &instances {
            let m = &self.root.meshes[placed.mesh];
            for (p, primitive) in m.primitives.iter().enumerate() {
                let what = format!("mesh {} primitive {p}", placed.mesh);
                let Some(mut part) = self.primitive(primitive, &what, &mut skipped_modes)? else {
                    continue;
                };
                other_uvs |= primitive
                    .attributes
                    .keys()
                    .any(|k| matches!(k, Checked::Valid(Semantic::TexCoords(i)) if *i > 0));
                let linear = Mat3::from_mat4(placed.transform);
                let det = linear.determinant();
                if det == 0.0 || !det.is_finite() {
                    // A flattening scale (often used to hide a node) has no normal matrix.
                    part.normals.clear();
                }
                let part = part.transformed(placed.transform);
                let material = primitive.material.map_or(0, |m| m.value() as u32 + 1);
                per_triangle.extend(std::iter::repeat_n(material, part.triangles.len()));
                mesh.append(&part);
            }
        }
        if skipped_modes > 0 {
            self.notes.push(format!(
                "{}: {skipped_modes} point or line primitives are not drawn",
                self.path.display()
            ));
        }
        if other_uvs {
            self.notes.push(format!(
                "{}: only TEXCOORD_0 is read; textures that name another set use it",
                self.path.display()
            ));
        }
        self.unused_notes();
        if mesh.triangles.is_empty() && skipped_modes > 0 {
            return Err(self.err(format!(
                "the mesh has no triangles, only {skipped_modes} point or line primitives"
            )));
        }
        mesh.check(self.path)?;
        let materials = match read_materials {
            true => {
                let mut materials = self.materials()?;
                if materials.list.len() > 1 {
                    materials.per_triangle = per_triangle;
                }
                materials
            }
            false => Materials::default(),
        };
        let camera = match camera_node {
            Some((index, transform)) => self.camera(index, transform, &mesh),
            None => None,
        };
        Ok(MeshFile {
            mesh,
            materials,
            warnings: std::mem::take(&mut self.warnings),
            notes: std::mem::take(&mut self.notes),
            camera,
        })
    }

    /// Every mesh instance of the scene drawn, with its world transform, and the first
    /// perspective camera's index and world transform (the lowest camera index a node of
    /// the scene uses, at the first such node).
    #[allow(clippy::type_complexity)]
    fn instances(&mut self) -> Result<(Vec<Placed>, Option<(usize, Mat4)>)> {
        let root = self.root;
        let scene = match root.scene {
            Some(s) => Some(s.value()),
            None if !root.scenes.is_empty() => Some(0),
            None => None,
        };
        let Some(scene) = scene else {
            // No scene: every mesh once, where it was modelled.
            self.notes.push(format!(
                "{}: the file has no scene: every mesh is drawn once, untransformed",
                self.path.display()
            ));
            let all = (0..root.meshes.len()).map(|mesh| Placed {
                mesh,
                transform: Mat4::IDENTITY,
            });
            return Ok((all.collect(), None));
        };
        let mut seen = vec![false; root.nodes.len()];
        let mut stack: Vec<(usize, Mat4)> = root.scenes[scene]
            .nodes
            .iter()
            .rev()
            .map(|n| (n.value(), Mat4::IDENTITY))
            .collect();
        let mut placed = Vec::new();
        let mut camera: Option<(usize, Mat4)> = None;
        while let Some((index, parent)) = stack.pop() {
            // glTF nodes form trees: a node met twice is in a cycle or has two parents,
            // and following it could go on for ever or multiply without bound.
            if std::mem::replace(&mut seen[index], true) {
                return Err(self.err(format!(
                    "node {index} is reached twice from scene {scene} (a cycle, or two \
                     parents): glTF nodes must form trees"
                )));
            }
            let node = &root.nodes[index];
            let world = parent * self.local_transform(index, node)?;
            if let Some(mesh) = node.mesh {
                placed.push(Placed {
                    mesh: mesh.value(),
                    transform: world,
                });
            }
            if let Some(c) = node.camera {
                let c = c.value();
                let perspective = root.cameras[c].perspective.is_some()
                    && matches!(
                        root.cameras[c].type_,
                        Checked::Valid(json::camera::Type::Perspective)
                    );
                if perspective && camera.is_none_or(|(best, _)| c < best) {
                    camera = Some((c, world));
                }
            }
            for child in node.children.iter().flatten().rev() {
                stack.push((child.value(), world));
            }
        }
        if root.nodes.iter().any(|n| n.skin.is_some()) || !root.animations.is_empty() {
            self.notes.push(format!(
                "{}: skins and animations are not applied (the rest pose is drawn)",
                self.path.display()
            ));
        }
        Ok((placed, camera))
    }

    /// A node's transform relative to its parent: its matrix, or translation, rotation and
    /// scale.
    fn local_transform(&self, index: usize, node: &json::Node) -> Result<Mat4> {
        let m = match node.matrix {
            Some(m) => Mat4::from_cols_array(&m),
            None => {
                let t = Vec3::from(node.translation.unwrap_or([0.0; 3]));
                let s = Vec3::from(node.scale.unwrap_or([1.0; 3]));
                let [x, y, z, w] = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
                let q = Quat::from_xyzw(x, y, z, w);
                if !q.is_finite() || q.length() < 1e-6 {
                    return Err(self.err(format!(
                        "node {index} has a rotation {:?} that is not a unit quaternion",
                        [x, y, z, w]
                    )));
                }
                Mat4::from_scale_rotation_translation(s, q.normalize(), t)
            }
        };
        if !m.is_finite() {
            return Err(self.err(format!("node {index} has a transform that is not finite")));
        }
        Ok(m)
    }

    /// Refuses a scene whose flattened instances exceed [`MAX_TRIANGLES`] triangles or
    /// vertices, counted from the accessors before anything is read.
    fn check_size(&self, instances: &[Placed]) -> Result<()> {
        let root = self.root;
        let (mut triangles, mut vertices) = (0u64, 0u64);
        for placed in instances {
            for p in &root.meshes[placed.mesh].primitives {
                let Some(position) = p.attributes.get(&Checked::Valid(Semantic::Positions)) else {
                    continue;
                };
                let n = root.accessors[position.value()].count.0;
                let corners = p.indices.map_or(n, |i| root.accessors[i.value()].count.0);
                vertices = vertices.saturating_add(n);
                triangles = triangles.saturating_add(match p.mode {
                    Checked::Valid(Mode::Triangles) => corners / 3,
                    Checked::Valid(Mode::TriangleStrip | Mode::TriangleFan) => {
                        corners.saturating_sub(2)
                    }
                    _ => 0,
                });
            }
        }
        for (count, what) in [(triangles, "triangles"), (vertices, "vertices")] {
            if count > MAX_TRIANGLES {
                return Err(self.err(format!(
                    "the scene holds {count} {what} once its instances are flattened; at most \
                     {MAX_TRIANGLES} are supported"
                )));
            }
        }
        Ok(())
    }

    /// One primitive as a mesh in its own space, or `None` for one that draws no triangles
    /// (points, lines, or no positions).
    fn primitive(
        &mut self,
        p: &json::mesh::Primitive,
        what: &str,
        skipped_modes: &mut usize,
    ) -> Result<Option<Mesh>> {
        let mode = match p.mode {
            Checked::Valid(mode) => mode,
            Checked::Invalid => return Err(self.err(format!("{what} has an invalid mode"))),
        };
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            *skipped_modes += 1;
            return Ok(None);
        }
        let attribute = |s: Semantic| p.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let Some(position) = attribute(Semantic::Positions) else {
            self.notes.push(format!(
                "{}: {what} has no POSITION and is not drawn",
                self.path.display()
            ));
            return Ok(None);
        };
        let positions: Vec<Vec3> = self
            .floats(position, &[Type::Vec3], "POSITION")?
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .collect();
        let n = positions.len();
        let same_count = |reader: &Self, len: usize, name: &str| {
            if len == n {
                Ok(())
            } else {
                Err(reader.err(format!(
                    "{what}: {name} has {len} elements for {n} positions"
                )))
            }
        };
        let mut mesh = Mesh::new(positions, Vec::new());
        if let Some(a) = attribute(Semantic::Normals) {
            mesh.normals = self
                .floats(a, &[Type::Vec3], "NORMAL")?
                .chunks_exact(3)
                .map(Vec3::from_slice)
                .collect();
            same_count(self, mesh.normals.len(), "NORMAL")?;
        }
        if let Some(a) = attribute(Semantic::TexCoords(0)) {
            // glTF's v grows downwards from the image's top; cltrace's upwards.
            mesh.uvs = self
                .floats(a, &[Type::Vec2], "TEXCOORD_0")?
                .chunks_exact(2)
                .map(|uv| Vec2::new(uv[0], 1.0 - uv[1]))
                .collect();
            same_count(self, mesh.uvs.len(), "TEXCOORD_0")?;
        }
        if let Some(a) = attribute(Semantic::Colors(0)) {
            let width = self.components(a, &[Type::Vec3, Type::Vec4], "COLOR_0")?;
            mesh.colors = self
                .floats(a, &[Type::Vec3, Type::Vec4], "COLOR_0")?
                .chunks_exact(width)
                .map(|c| Vec3::from_slice(c).clamp(Vec3::ZERO, Vec3::ONE))
                .collect();
            same_count(self, mesh.colors.len(), "COLOR_0")?;
        }
        let corners: Vec<u32> = match p.indices {
            Some(i) => {
                let indices = self.indices(i.value())?;
                if let Some(&bad) = indices.iter().find(|&&v| v as usize >= n) {
                    return Err(self.err(format!(
                        "{what} uses vertex {bad}, but it has only {n} vertices"
                    )));
                }
                indices
            }
            None => (0..n as u32).collect(),
        };
        mesh.triangles = match mode {
            Mode::TriangleStrip => (0..corners.len().saturating_sub(2))
                .map(|i| {
                    // Every other triangle turns round, to keep the winding.
                    let (b, c) = if i % 2 == 0 { (1, 2) } else { (2, 1) };
                    [corners[i], corners[i + b], corners[i + c]]
                })
                .collect(),
            Mode::TriangleFan => (0..corners.len().saturating_sub(2))
                .map(|i| [corners[i + 1], corners[i + 2], corners[0]])
                .collect(),
            _ => corners
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        };
        Ok(Some(mesh))
    }

    /// How many components accessor `index`'s elements have, checked to be one of `types`.
    fn components(&self, index: usize, types: &[Type], what: &str) -> Result<usize> {
        let a = &self.root.accessors[index];
        match a.type_ {
            Checked::Valid(t) if types.contains(&t) => Ok(t.multiplicity()),
            _ => Err(self.err(format!(
                "accessor {index} ({what}) has type {}, expected {}",
                match a.type_ {
                    Checked::Valid(t) => format!("{t:?}").to_uppercase(),
                    Checked::Invalid => "invalid".into(),
                },
                types
                    .iter()
                    .map(|t| format!("{t:?}").to_uppercase())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ))),
        }
    }

    /// Accessor `index`'s components as floats (normalised integers mapped to [0, 1] or
    /// [-1, 1]), element after element.
    fn floats(&mut self, index: usize, types: &[Type], what: &str) -> Result<Vec<f32>> {
        let width = self.components(index, types, what)?;
        let a = &self.root.accessors[index];
        let normalized = a.normalized;
        let kind = self.component_type(index)?;
        self.elements(index, width, kind.size(), |bytes| {
            let v = match kind {
                ComponentType::F32 => f32::from_le_bytes(bytes.try_into().unwrap()),
                ComponentType::U8 => norm(bytes[0] as f32, 255.0, normalized),
                ComponentType::I8 => norm(bytes[0] as i8 as f32, 127.0, normalized),
                ComponentType::U16 => norm(
                    u16::from_le_bytes([bytes[0], bytes[1]]) as f32,
                    65535.0,
                    normalized,
                ),
                ComponentType::I16 => norm(
                    i16::from_le_bytes([bytes[0], bytes[1]]) as f32,
                    32767.0,
                    normalized,
                ),
                ComponentType::U32 => u32::from_le_bytes(bytes.try_into().unwrap()) as f32,
            };
            Ok(v)
        })
    }

    /// Accessor `index` as vertex indices: unsigned integer scalars.
    fn indices(&mut self, index: usize) -> Result<Vec<u32>> {
        self.components(index, &[Type::Scalar], "indices")?;
        let kind = self.component_type(index)?;
        if !matches!(
            kind,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        ) {
            return Err(self.err(format!(
                "accessor {index} (indices) has component type {kind:?}, expected an unsigned \
                 integer"
            )));
        }
        self.elements(index, 1, kind.size(), |b| {
            Ok(match b.len() {
                1 => b[0] as u32,
                2 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes(b.try_into().unwrap()),
            })
        })
    }

    fn component_type(&self, index: usize) -> Result<ComponentType> {
        match self.root.accessors[index].component_type {
            Checked::Valid(t) => Ok(t.0),
            Checked::Invalid => {
                Err(self.err(format!("accessor {index} has an invalid component type")))
            }
        }
    }

    /// Every component of accessor `index` (`width` components of `size` bytes an element)
    /// through `read`, after checking that the elements lie within the buffer view and the
    /// view within its buffer.
    fn elements<T>(
        &mut self,
        index: usize,
        width: usize,
        size: usize,
        read: impl Fn(&[u8]) -> Result<T>,
    ) -> Result<Vec<T>> {
        let root = self.root;
        let a = &root.accessors[index];
        if a.sparse.is_some() {
            return Err(self.err(format!(
                "accessor {index} is sparse, which cltrace does not read"
            )));
        }
        let Some(view_index) = a.buffer_view else {
            return Err(self.err(format!("accessor {index} has no bufferView")));
        };
        let view = &root.buffer_views[view_index.value()];
        let buffer = self.buffer(view.buffer.value())?;
        let buffer = &self.buffers[&buffer];
        let view_offset = view.byte_offset.map_or(0, |o| o.0);
        let view_length = view.byte_length.0;
        if view_offset
            .checked_add(view_length)
            .is_none_or(|end| end > buffer.len() as u64)
        {
            return Err(self.err(format!(
                "bufferView {} (bytes {view_offset} to {view_offset} + {view_length}) lies \
                 outside buffer {} of {} bytes",
                view_index.value(),
                view.buffer.value(),
                buffer.len()
            )));
        }
        let view_bytes = &buffer[view_offset as usize..(view_offset + view_length) as usize];
        let element = (width * size) as u64;
        let stride = view.byte_stride.map_or(element, |s| s.0 as u64);
        if stride < element {
            return Err(self.err(format!(
                "bufferView {} has a byteStride of {stride}, less than accessor {index}'s \
                 {element}-byte elements",
                view_index.value()
            )));
        }
        let offset = a.byte_offset.map_or(0, |o| o.0);
        let count = a.count.0;
        let end = match count {
            0 => Some(offset),
            _ => (count - 1)
                .checked_mul(stride)
                .and_then(|s| s.checked_add(offset))
                .and_then(|s| s.checked_add(element)),
        };
        if end.is_none_or(|end| end > view_length) {
            return Err(self.err(format!(
                "accessor {index} ({count} elements of {element} bytes from byte {offset}, \
                 stride {stride}) runs past the end of bufferView {} ({view_length} bytes)",
                view_index.value()
            )));
        }
        let mut out = Vec::with_capacity(count as usize * width);
        for e in 0..count {
            let start = (offset + e * stride) as usize;
            for c in 0..width {
                let at = start + c * size;
                out.push(read(&view_bytes[at..at + size])?);
            }
        }
        Ok(out)
    }

    /// Reads buffer `index` (its first `byteLength` bytes) into `self.buffers` on first
    /// use, and returns the key it is under there.
    fn buffer(&mut self, index: usize) -> Result<usize> {
        if !self.buffers.contains_key(&index) {
            let b = &self.root.buffers[index];
            let length = b.byte_length.0;
            let bytes = match &b.uri {
                None => match &self.blob {
                    Some(blob) => blob.clone(),
                    None => {
                        return Err(self.err(format!(
                            "buffer {index} has no uri and the file has no binary chunk"
                        )));
                    }
                },
                Some(uri) => match self.fetch(uri, &format!("buffer {index}"), length)? {
                    Fetched::Bytes(bytes) => bytes,
                    Fetched::Missing(why) => return Err(self.err(why)),
                },
            };
            if (bytes.len() as u64) < length {
                return Err(self.err(format!(
                    "buffer {index} holds {} bytes, but its byteLength is {length}",
                    bytes.len()
                )));
            }
            let mut bytes = bytes;
            bytes.truncate(length as usize);
            self.buffers.insert(index, bytes);
        }
        Ok(index)
    }

    /// A URI's bytes, at most `limit` of them (more are not needed): a base64 data URI
    /// decoded, or a file relative to the glTF file's folder.
    fn fetch(&self, uri: &str, what: &str, limit: u64) -> Result<Fetched> {
        if let Some(data) = uri.strip_prefix("data:") {
            let Some((header, payload)) = data.split_once(',') else {
                return Err(self.err(format!("{what}: a data URI without a comma")));
            };
            if !header.ends_with(";base64") {
                return Err(self.err(format!(
                    "{what}: a data URI that is not base64 ({}), which cltrace does not read",
                    super::quoted(header)
                )));
            }
            let bytes = base64::decode(payload.trim_end_matches('='))
                .or_else(|_| base64::decode(payload))
                .map_err(|e| self.err(format!("{what}: its base64 data URI is corrupt: {e}")))?;
            return Ok(Fetched::Bytes(bytes));
        }
        if has_scheme(uri) {
            return Err(self.err(format!(
                "{what}: URI {} is neither a relative file name nor a data URI",
                super::quoted(uri)
            )));
        }
        let name = percent_decode(uri)
            .ok_or_else(|| self.err(format!("{what}: URI {} is malformed", super::quoted(uri))))?;
        let Some(folder) = self.folder else {
            return Err(self.err(format!(
                "{what} is the external file {}, which is not read here",
                super::quoted(&name)
            )));
        };
        let file: PathBuf = folder.join(&name);
        let opened = std::fs::File::open(&file).and_then(|f| {
            if f.metadata()?.is_dir() {
                return Err(std::io::Error::other("is a directory"));
            }
            let mut bytes = Vec::new();
            f.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
            Ok(bytes)
        });
        match opened {
            Ok(bytes) => Ok(Fetched::Bytes(bytes)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Fetched::Missing(format!(
                "{what}: cannot open {} (no such file)",
                file.display()
            ))),
            Err(e) => Err(self.err(format!(
                "{what}: cannot read {} ({})",
                file.display(),
                super::io_reason(&e)
            ))),
        }
    }

    /// The materials: the default grey first (for primitives without one), then the
    /// file's in order, with their textures decoded.
    fn materials(&mut self) -> Result<Materials> {
        let root = self.root;
        let mut out = Materials::default();
        let mut cache: HashMap<(usize, bool, [u32; 2]), i32> = HashMap::new();
        let mut missing = std::collections::HashSet::new();
        let mut blended = 0usize;
        let mut transformed = false;
        let mut occlusion_strength = false;
        for (i, m) in root.materials.iter().enumerate() {
            let pbr = &m.pbr_metallic_roughness;
            let [r, g, b, alpha] = pbr.base_color_factor.0.map(unit);
            let strength = m
                .extensions
                .as_ref()
                .and_then(|e| e.emissive_strength.as_ref())
                .map_or(1.0, |s| s.emissive_strength.0);
            let strength = if strength.is_finite() && strength > 0.0 {
                strength
            } else {
                0.0
            };
            let emission = m.emissive_factor.0.map(|e| unit(e) * strength);
            // glTF's metallic-roughness model: a dielectric of index 1.5 over the base
            // colour (cltrace's plastic) blended with a metal of the base colour.
            let mut material = Material {
                metallic: unit(pbr.metallic_factor.0),
                roughness: unit(pbr.roughness_factor.0),
                bsdf: crate::material::Bsdf::Plastic.code(),
                ..Material::emitting([r, g, b], emission)
            };
            let infos = [
                pbr.base_color_texture.as_ref().map(|t| t.index),
                m.emissive_texture.as_ref().map(|t| t.index),
                pbr.metallic_roughness_texture.as_ref().map(|t| t.index),
                m.normal_texture.as_ref().map(|t| t.index),
                m.occlusion_texture.as_ref().map(|t| t.index),
            ];
            let spaces = [true, true, false, false, false];
            let mut slots = [NO_TEXTURE; 5];
            for ((info, srgb), slot) in infos.iter().zip(spaces).zip(&mut slots) {
                if let Some(t) = info {
                    *slot = self.texture(t.value(), srgb, &mut out, &mut cache, &mut missing)?;
                }
            }
            transformed |= [
                pbr.base_color_texture.as_ref(),
                m.emissive_texture.as_ref(),
                pbr.metallic_roughness_texture.as_ref(),
            ]
            .into_iter()
            .flatten()
            .any(|t| {
                t.extensions
                    .as_ref()
                    .is_some_and(|e| e.texture_transform.is_some())
            });
            [
                material.base_texture,
                material.emission_texture,
                material.metallic_roughness_texture,
                material.normal_texture,
                material.occlusion_texture,
            ] = slots;
            if let Some(n) = &m.normal_texture {
                material.normal_scale = if n.scale.is_finite() { n.scale } else { 1.0 };
            }
            occlusion_strength |= m
                .occlusion_texture
                .as_ref()
                .is_some_and(|o| o.strength.0 != 1.0);
            let mode = match m.alpha_mode {
                Checked::Valid(mode) => mode,
                Checked::Invalid => json::material::AlphaMode::Opaque,
            };
            let cutoff = match mode {
                json::material::AlphaMode::Opaque => None,
                json::material::AlphaMode::Mask => {
                    Some(m.alpha_cutoff.map_or(0.5, |c| c.0).max(0.0))
                }
                json::material::AlphaMode::Blend => {
                    blended += 1;
                    // Blending is not drawn; a texture's alpha still cuts leaves and
                    // fences out, at half, where a uniform alpha would hide the surface.
                    (material.base_texture != NO_TEXTURE).then_some(0.5)
                }
            };
            if let Some(cutoff) = cutoff {
                // texel alpha * factor alpha < cutoff, without the product.
                material.alpha_cutoff = if alpha > 0.0 {
                    (cutoff / alpha).min(f32::MAX)
                } else {
                    f32::MAX
                };
                material.alpha_texture = match material.base_texture {
                    NO_TEXTURE => {
                        out.textures.push(Texture {
                            name: format!("glTF material {i}'s alpha"),
                            ..Texture::solid([1.0; 4])
                        });
                        out.textures.len() as i32 - 1
                    }
                    base => base,
                };
            }
            out.list.push(material);
        }
        let path = self.path.display();
        if blended > 0 {
            self.notes.push(format!(
                "{path}: {blended} materials blend (alphaMode BLEND): drawn opaque, or cut out \
                 at alpha 0.5 where a base colour texture gives the alpha"
            ));
        }
        if transformed {
            self.notes.push(format!(
                "{path}: texture transforms (KHR_texture_transform) are not applied"
            ));
        }
        if occlusion_strength {
            self.notes.push(format!(
                "{path}: occlusion strengths other than 1 are read as 1"
            ));
        }
        Ok(out)
    }

    /// The texture slot for glTF texture `index` read as sRGB colour or linear data,
    /// decoded on first use; [`NO_TEXTURE`] with a warning (once per image) for an image
    /// file that does not exist.
    fn texture(
        &mut self,
        index: usize,
        srgb: bool,
        out: &mut Materials,
        cache: &mut HashMap<(usize, bool, [u32; 2]), i32>,
        missing: &mut std::collections::HashSet<usize>,
    ) -> Result<i32> {
        let root = self.root;
        let t = &root.textures[index];
        let image = t.source.value();
        let wrap = match t.sampler {
            Some(s) => {
                let s = &root.samplers[s.value()];
                [wrap_of(s.wrap_s), wrap_of(s.wrap_t)]
            }
            None => [Wrap::Repeat; 2],
        };
        if let Some(&slot) = cache.get(&(image, srgb, wrap.map(Wrap::code))) {
            return Ok(slot);
        }
        if missing.contains(&image) {
            return Ok(NO_TEXTURE);
        }
        let img = &root.images[image];
        let what = format!("image {image}");
        let (bytes, name) = match (&img.uri, img.buffer_view) {
            (Some(uri), _) => {
                let name = match uri.starts_with("data:") {
                    true => format!("{}: {what}", self.path.display()),
                    false => format!("{}: {what} ({})", self.path.display(), uri),
                };
                match self.fetch(uri, &what, MAX_IMAGE_BYTES)? {
                    Fetched::Bytes(bytes) => (bytes, name),
                    Fetched::Missing(why) => {
                        self.warnings.push(format!(
                            "{}: {why}; the textures it holds are left out",
                            self.path.display()
                        ));
                        missing.insert(image);
                        return Ok(NO_TEXTURE);
                    }
                }
            }
            (None, Some(view)) => {
                let view = &root.buffer_views[view.value()];
                let (offset, length) = (view.byte_offset.map_or(0, |o| o.0), view.byte_length.0);
                let buffer = self.buffer(view.buffer.value())?;
                let buffer = &self.buffers[&buffer];
                let Some(bytes) = offset
                    .checked_add(length)
                    .filter(|&end| end <= buffer.len() as u64)
                    .map(|end| buffer[offset as usize..end as usize].to_vec())
                else {
                    return Err(self.err(format!("{what}'s bufferView lies outside its buffer")));
                };
                (bytes, format!("{}: {what}", self.path.display()))
            }
            (None, None) => {
                return Err(self.err(format!("{what} has neither a uri nor a bufferView")));
            }
        };
        if bytes.len() as u64 > MAX_IMAGE_BYTES {
            return Err(self.err(format!(
                "{what} is larger than {MAX_IMAGE_BYTES} bytes: refused"
            )));
        }
        let space = if srgb {
            ColorSpace::Srgb
        } else {
            ColorSpace::Linear
        };
        let mut texture = decode_texture(self.path, &bytes, space, wrap).map_err(|e| match e {
            Error::Input { message, .. } => self.err(format!("{what}: {message}")),
            e => e,
        })?;
        texture.name = name;
        out.textures.push(texture);
        let slot = out.textures.len() as i32 - 1;
        cache.insert((image, srgb, wrap.map(Wrap::code)), slot);
        Ok(slot)
    }

    /// The camera settings of perspective camera `index` seen from world transform `m`:
    /// glTF cameras look down their -z with +y up. `None`, with a warning, for one whose
    /// transform or field of view cltrace cannot use.
    fn camera(&mut self, index: usize, m: Mat4, mesh: &Mesh) -> Option<CameraSettings> {
        let perspective = self.root.cameras[index].perspective.as_ref()?;
        let eye = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = m.transform_vector3(Vec3::Y).normalize_or_zero();
        let fov = perspective.yfov.to_degrees();
        let usable = eye.is_finite()
            && forward != Vec3::ZERO
            && up != Vec3::ZERO
            && forward.cross(up).length() > 1e-3
            && fov > 0.0
            && fov < 180.0;
        if !usable {
            self.warnings.push(format!(
                "{}: camera {index} has a transform or field of view cltrace cannot use \
                 (yfov {}); it is ignored",
                self.path.display(),
                perspective.yfov
            ));
            return None;
        }
        // The look-at point only gives the direction: put it level with the scene's centre.
        let bounds = mesh.bounds();
        let centre = (bounds.min + bounds.max) * 0.5;
        let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-3);
        let ahead = (centre - eye).dot(forward).max(radius);
        if perspective.aspect_ratio.is_some() {
            self.notes.push(format!(
                "{}: camera {index}'s aspect ratio is not used (--width and --height are)",
                self.path.display()
            ));
        }
        Some(CameraSettings {
            eye: Some(eye.to_array()),
            look_at: Some((eye + forward * ahead).to_array()),
            up: Some(up.to_array()),
            fov: Some(fov),
            ..CameraSettings::default()
        })
    }

    /// Notes for what the file holds that is not read at all.
    fn unused_notes(&mut self) {
        let root = self.root;
        let morphs = root
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .any(|p| p.targets.is_some());
        if morphs {
            self.notes.push(format!(
                "{}: morph targets are not applied",
                self.path.display()
            ));
        }
    }
}

/// `v` mapped to [0, 1] or [-1, 1] when `normalized`, as glTF maps integers.
fn norm(v: f32, max: f32, normalized: bool) -> f32 {
    if normalized { (v / max).max(-1.0) } else { v }
}

/// A factor clamped to [0, 1] (the JSON can give any number).
fn unit(v: f32) -> f32 {
    if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

fn wrap_of(mode: Checked<json::texture::WrappingMode>) -> Wrap {
    match mode {
        Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::Clamp,
        Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::Mirror,
        _ => Wrap::Repeat,
    }
}

/// Whether a URI starts with a scheme (`http:`, `file:`): letters, digits, `+-.` and a
/// colon, at least two characters before it so that a Windows drive letter is a path.
fn has_scheme(uri: &str) -> bool {
    match uri.split_once(':') {
        Some((scheme, _)) => {
            scheme.len() > 1
                && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
                && scheme
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        }
        None => false,
    }
}

/// A URI's `%XX` escapes decoded; `None` for a bad escape or a result that is not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_told_apart_and_decoded() {
        assert!(has_scheme("http://example.com/a.bin"));
        assert!(has_scheme("file:///a.bin"));
        assert!(!has_scheme("C:/models/a.bin"));
        assert!(!has_scheme("a.bin"));
        assert_eq!(
            percent_decode("my%20mesh.bin").as_deref(),
            Some("my mesh.bin")
        );
        assert_eq!(percent_decode("bad%2"), None);
        assert_eq!(percent_decode("bad%zz"), None);
    }
}
