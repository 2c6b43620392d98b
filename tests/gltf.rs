//! glTF 2.0 input against small `.gltf` and `.glb` files written here (JSON with base64
//! data-URI or `.bin` buffers, PNG textures made with the `image` crate), good and bad, and
//! the shared Suzanne model where it is present.

use std::path::{Path, PathBuf};

use cltrace::input::{MeshFile, load_mesh_with_materials, parse_gltf_bytes};
use cltrace::material::{NO_TEXTURE, Wrap};
use glam::{Mat4, Quat, Vec2, Vec3};
use serde_json::{Value, json};

use crate::common::command::{cltrace, run, succeeded, text};
use crate::common::shared_scene;

/// A glTF file being put together: one binary buffer and the views and accessors into it.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;

impl Gltf {
    /// An accessor of `count` elements of `kind` over `bytes`, in a view of its own.
    fn accessor(&mut self, bytes: &[u8], kind: &str, component: u32, count: usize) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        let mut a = json!({
            "bufferView": self.views.len() - 1, "componentType": component,
            "count": count, "type": kind
        });
        if component != FLOAT {
            a["normalized"] = json!(kind != "SCALAR");
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn vec3(&mut self, points: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = points
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        self.accessor(&bytes, "VEC3", FLOAT, points.len())
    }

    fn vec2(&mut self, points: &[[f32; 2]]) -> usize {
        let bytes: Vec<u8> = points
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        self.accessor(&bytes, "VEC2", FLOAT, points.len())
    }

    fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        self.accessor(&bytes, "SCALAR", UNSIGNED_SHORT, indices.len())
    }

    /// The document: `rest` (meshes, nodes, scenes, ...) with the asset, the accessors,
    /// the views and the buffer, given by `uri` (`None`: a GLB's binary chunk).
    fn document(&self, mut rest: Value, uri: Option<String>) -> Value {
        rest["asset"] = json!({"version": "2.0"});
        rest["accessors"] = json!(self.accessors);
        rest["bufferViews"] = json!(self.views);
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        rest["buffers"] = json!([buffer]);
        rest
    }

    /// The JSON of a `.gltf` with the buffer in a data URI.
    fn embedded(&self, rest: Value) -> Vec<u8> {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::encode(&self.bin)
        );
        self.document(rest, Some(uri)).to_string().into_bytes()
    }

    /// A `.glb`: header, JSON chunk, binary chunk.
    fn glb(&self, rest: Value) -> Vec<u8> {
        let json = self.document(rest, None).to_string().into_bytes();
        glb_bytes(json, Some(self.bin.clone()))
    }
}

/// A GLB file of a JSON chunk and, if given, a binary chunk, each padded to 4 bytes.
fn glb_bytes(mut json: Vec<u8>, bin: Option<Vec<u8>>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut chunks = Vec::new();
    chunks.extend_from_slice(&(json.len() as u32).to_le_bytes());
    chunks.extend_from_slice(b"JSON");
    chunks.extend_from_slice(&json);
    if let Some(mut bin) = bin {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        chunks.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        chunks.extend_from_slice(b"BIN\0");
        chunks.extend_from_slice(&bin);
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + chunks.len()) as u32).to_le_bytes());
    out.extend_from_slice(&chunks);
    out
}

/// A PNG of `pixels` (RGBA, rows from the top), `width` wide.
fn png(pixels: &[[u8; 4]], width: u32) -> Vec<u8> {
    let height = pixels.len() as u32 / width;
    let img = image::RgbaImage::from_raw(width, height, pixels.concat()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!("data:{mime};base64,{}", base64::encode(bytes))
}

/// One triangle (corners 0, x, y) with indices, as mesh 0's only primitive.
fn triangle(g: &mut Gltf, material: Option<usize>) -> Value {
    let position = g.vec3(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let indices = g.indices(&[0, 1, 2]);
    let mut primitive = json!({"attributes": {"POSITION": position}, "indices": indices});
    if let Some(m) = material {
        primitive["material"] = json!(m);
    }
    json!([{"primitives": [primitive]}])
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn load(path: &Path) -> MeshFile {
    load_mesh_with_materials(path).unwrap_or_else(|e| panic!("{} should load: {e}", path.display()))
}

/// The error for a file that must be refused: one line, naming the file, exit status 2.
fn refused(path: &Path) -> String {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let err = match load_mesh_with_materials(path) {
        Ok(f) => panic!(
            "{name} should be refused, but loaded {} triangles",
            f.mesh.triangle_count()
        ),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert_eq!(err.exit_code(), 2, "{msg}");
    assert!(
        msg.contains(&name),
        "the message does not name {name}: {msg}"
    );
    assert!(!msg.contains('\n'), "not one line: {msg:?}");
    msg
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn node_transforms_are_applied_through_the_hierarchy() {
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, None);
    // Parent: translate and scale; child: rotate 90 degrees about z; a sibling by matrix.
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let matrix = Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0));
    let rest = json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0], "children": [1]},
            {"rotation": q.to_array(), "mesh": 0},
            {"matrix": matrix.to_cols_array(), "mesh": 0}
        ],
        "meshes": meshes
    });
    let dir = tempfile::tempdir().unwrap();
    let file = load(&write(dir.path(), "tree.gltf", g.embedded(rest)));
    let mesh = &file.mesh;
    assert_eq!(mesh.triangle_count(), 2);
    let parent = Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::IDENTITY,
        Vec3::new(10.0, 0.0, 0.0),
    );
    let child = parent * Mat4::from_quat(q);
    let local = [Vec3::ZERO, Vec3::X, Vec3::Y];
    for (c, p) in mesh.corners(0).iter().zip(local) {
        assert!(close(*c, child.transform_point3(p)), "{c} vs {p}");
    }
    assert!(close(mesh.corners(0)[1], Vec3::new(10.0, 2.0, 0.0)));
    for (c, p) in mesh.corners(1).iter().zip(local) {
        assert!(close(*c, matrix.transform_point3(p)), "{c} vs {p}");
    }
    assert!(file.camera.is_none());
}

#[test]
fn a_mesh_used_by_two_nodes_is_drawn_twice_and_a_glb_reads_the_same() {
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, None);
    let rest = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [0.0, 0.0, 5.0]}],
        "meshes": meshes
    });
    let dir = tempfile::tempdir().unwrap();
    let gltf = load(&write(dir.path(), "twice.gltf", g.embedded(rest.clone())));
    assert_eq!(gltf.mesh.triangle_count(), 2);
    assert!(close(gltf.mesh.corners(1)[0], Vec3::new(0.0, 0.0, 5.0)));
    let glb = load(&write(dir.path(), "twice.GLB", g.glb(rest.clone())));
    assert_eq!(glb.mesh, gltf.mesh);
    // The same file with the buffer beside it.
    std::fs::write(dir.path().join("twice data.bin"), &g.bin).unwrap();
    let doc = g.document(rest, Some("twice%20data.bin".into()));
    let external = load(&write(dir.path(), "external.gltf", doc.to_string()));
    assert_eq!(external.mesh, gltf.mesh);
    // Without a file system the external buffer cannot be read: a clear error.
    let e = parse_gltf_bytes(Path::new("external.gltf"), doc.to_string().as_bytes())
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.starts_with("external.gltf:") && e.contains("twice data.bin"),
        "{e}"
    );
}

/// Bytes after the length a GLB's header gives are not the file's. gltf 1.4.1 read them as
/// a binary chunk where the GLB has none (its buffer in a data URI) and refused the file
/// (gltf-rs/gltf#475).
#[test]
fn a_glb_followed_by_other_bytes_was_refused() {
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, None);
    let rest = json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": meshes});
    let dir = tempfile::tempdir().unwrap();
    let json = g.embedded(rest);
    let gltf = load(&write(dir.path(), "triangle.gltf", &json));
    let mut json_only = glb_bytes(json, None);
    let plain = load(&write(dir.path(), "json_only.glb", &json_only));
    assert_eq!(plain.mesh, gltf.mesh);
    json_only.extend_from_slice(&[0xFF; 5]);
    let padded = load(&write(dir.path(), "padded.glb", &json_only));
    assert_eq!(padded.mesh, gltf.mesh);
}

#[test]
fn strips_fans_and_unindexed_primitives_become_triangles() {
    let mut g = Gltf::default();
    let quad = g.vec3(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let strip = g.indices(&[0, 1, 2, 3]);
    let fan = g.indices(&[0, 1, 3, 2]);
    let rest = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": quad}, "indices": strip, "mode": 5},
            {"attributes": {"POSITION": quad}, "indices": fan, "mode": 6},
            {"attributes": {"POSITION": quad}, "mode": 4},
            {"attributes": {"POSITION": quad}, "mode": 1}
        ]}]
    });
    let dir = tempfile::tempdir().unwrap();
    let file = load(&write(dir.path(), "modes.gltf", g.embedded(rest)));
    let t = &file.mesh.triangles;
    // Strip: (0 1 2), then (1 3 2) to keep the winding; fan: (1 3 0), (3 2 0); the
    // unindexed triangle list: (0 1 2) with the fourth vertex left over; lines skipped.
    assert_eq!(t, &[[0, 1, 2], [1, 3, 2], [5, 7, 4], [7, 6, 4], [8, 9, 10]]);
    for i in 0..4 {
        let [a, b, c] = file.mesh.corners(i);
        assert!((b - a).cross(c - a).z > 0.0, "triangle {i} faces +z");
    }
    assert!(
        file.notes.iter().any(|n| n.contains("point or line")),
        "{:?}",
        file.notes
    );
}

#[test]
fn materials_factors_textures_and_attributes_are_read() {
    let mut g = Gltf::default();
    let position = g.vec3(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let normal = g.vec3(&[[0.0, 0.0, 1.0]; 3]);
    let uv = g.vec2(&[[0.0, 0.0], [1.0, 0.25], [0.0, 1.0]]);
    let color = g.accessor(
        &[255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255],
        "VEC4",
        UNSIGNED_BYTE,
        3,
    );
    let indices = g.indices(&[0, 1, 2]);
    let other = g.vec3(&[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]);
    let base = png(&[[255, 0, 0, 255], [0, 0, 255, 128]], 2);
    let data = png(&[[0, 128, 255, 255]], 1);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("mr.png"), &data).unwrap();
    let rest = json!({
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv,
                            "COLOR_0": color},
             "indices": indices, "material": 0},
            {"attributes": {"POSITION": other}, "material": 1},
            {"attributes": {"POSITION": other}}
        ]}],
        "materials": [
            {"pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1.0, 0.5],
                "baseColorTexture": {"index": 0},
                "metallicFactor": 0.75, "roughnessFactor": 0.125,
                "metallicRoughnessTexture": {"index": 1}},
             "normalTexture": {"index": 1, "scale": 0.5},
             "occlusionTexture": {"index": 1},
             "emissiveFactor": [1.0, 0.5, 0.0],
             "emissiveTexture": {"index": 0},
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
             "alphaMode": "MASK", "alphaCutoff": 0.25},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.4, 1.0]}}
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648}],
        "images": [{"uri": data_uri("image/png", &base)}, {"uri": "mr.png"}]
    });
    let file = load(&write(dir.path(), "materials.gltf", g.embedded(rest)));
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);
    let (mesh, m) = (&file.mesh, &file.materials);
    assert_eq!(mesh.triangle_count(), 3);
    // v is flipped: glTF's v grows downwards.
    assert_eq!(
        &mesh.uvs[..3],
        &[
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 0.75),
            Vec2::new(0.0, 0.0)
        ]
    );
    assert_eq!(mesh.colors[0], Vec3::X);
    assert_eq!(mesh.colors[4], Vec3::ONE, "no COLOR_0: white");
    assert_eq!(mesh.normals[1], Vec3::Z);
    assert_eq!(mesh.normals[4], Vec3::ZERO, "no NORMAL: the triangle's own");
    // list[0] is the default grey; the file's materials follow.
    assert_eq!(m.per_triangle, vec![1, 2, 0]);
    assert_eq!(m.list[0], cltrace::material::Material::default());
    let a = &m.list[1];
    assert_eq!(a.albedo, [0.5, 0.25, 1.0]);
    assert_eq!((a.metallic, a.roughness), (0.75, 0.125));
    assert_eq!(
        (cltrace::material::Bsdf::from_code(a.bsdf), a.ior),
        (cltrace::material::Bsdf::Plastic, 1.5),
        "glTF's dielectric base: a coating of index 1.5, blended with a metal"
    );
    assert_eq!(a.emission, [4.0, 2.0, 0.0]);
    assert_eq!(a.normal_scale, 0.5);
    assert_eq!(a.alpha_texture, a.base_texture);
    assert_eq!(a.alpha_cutoff, 0.5, "alphaCutoff / the factor's alpha");
    assert_eq!(
        a.emission_texture, a.base_texture,
        "the same sRGB decode is shared"
    );
    assert_eq!(a.metallic_roughness_texture, a.normal_texture);
    assert_eq!(a.occlusion_texture, a.normal_texture);
    assert_ne!(a.base_texture, a.normal_texture);
    let base = &m.textures[a.base_texture as usize];
    assert_eq!((base.width, base.height), (2, 1));
    assert_eq!(base.wrap, [Wrap::Clamp, Wrap::Mirror]);
    assert_eq!(base.texels[0], [1.0, 0.0, 0.0, 1.0]);
    assert!((base.texels[1][3] - 128.0 / 255.0).abs() < 1e-6);
    let data = &m.textures[a.normal_texture as usize];
    assert_eq!(data.wrap, [Wrap::Repeat; 2]);
    assert!(
        (data.texels[0][1] - 128.0 / 255.0).abs() < 1e-6,
        "linear, not sRGB-decoded"
    );
    assert_eq!(m.list[2].albedo, [0.2, 0.3, 0.4]);
    assert_eq!(m.list[2].base_texture, NO_TEXTURE);
    assert!(!m.list[2].is_masked());
}

#[test]
fn a_missing_texture_is_a_warning_and_an_untextured_surface() {
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, Some(0));
    let rest = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": meshes,
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "gone.png"}]
    });
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "missing.gltf", g.embedded(rest));
    let file = load(&path);
    assert_eq!(file.materials.list[1].base_texture, NO_TEXTURE);
    assert!(file.materials.textures.is_empty());
    assert_eq!(file.warnings.len(), 1, "{:?}", file.warnings);
    assert!(file.warnings[0].contains("gone.png"), "{:?}", file.warnings);
    // The binary renders it, saying so.
    let out = run({
        let mut c = cltrace();
        c.arg("render")
            .arg(&path)
            .arg("-o")
            .arg(dir.path().join("m.png"));
        c.args(["--width", "16", "--height", "12", "--method", "cpu-bvh"]);
        c
    });
    succeeded(&out);
    let said = text(&out.stdout) + &text(&out.stderr);
    assert!(
        said.contains("warning:") && said.contains("gone.png"),
        "{said}"
    );
}

#[test]
fn the_first_perspective_camera_is_the_default_camera() {
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, None);
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let rest = json!({
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0},
            {"camera": 1, "translation": [0.0, 0.0, 9.0]},
            {"camera": 2, "translation": [5.0, 0.25, 0.0], "rotation": turn.to_array()}
        ],
        "meshes": meshes,
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}},
            {"type": "orthographic", "orthographic":
                {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}},
            {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}
        ]
    });
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "camera.gltf", g.embedded(rest));
    let file = load(&path);
    // Camera 0 is used by no node, camera 1 is orthographic: camera 2, looking down -x.
    let c = file.camera.expect("a camera");
    assert_eq!(c.fov, Some(0.5f32.to_degrees()));
    let eye = Vec3::from(c.eye.unwrap());
    assert!(close(eye, Vec3::new(5.0, 0.25, 0.0)), "{eye}");
    let forward = (Vec3::from(c.look_at.unwrap()) - eye).normalize();
    assert!(close(forward, -Vec3::X), "{forward}");
    assert!(close(Vec3::from(c.up.unwrap()), Vec3::Y));
    assert_eq!((c.width, c.height), (None, None));

    // The render uses it unless the flags place the camera.
    let render = |extra: &[&str]| {
        let mut c = cltrace();
        c.arg("render")
            .arg(&path)
            .arg("-o")
            .arg(dir.path().join("c.png"));
        c.args([
            "--width", "16", "--height", "12", "--method", "cpu-bvh", "-v",
        ]);
        c.args(extra);
        let out = run(c);
        succeeded(&out);
        text(&out.stdout) + &text(&out.stderr)
    };
    let said = render(&[]);
    let line = said.lines().find(|l| l.starts_with("camera: eye")).unwrap();
    assert!(line.contains("eye [5.0, 0.25, 0.0]"), "{line}");
    assert!(
        line.contains(&format!("fov {}", 0.5f32.to_degrees())),
        "{line}"
    );
    let said = render(&["--fov", "30"]);
    let line = said.lines().find(|l| l.starts_with("camera: eye")).unwrap();
    assert!(!line.contains("eye [5.0"), "flags give the camera: {line}");
}

#[test]
fn bad_gltf_is_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut g = Gltf::default();
    let meshes = triangle(&mut g, Some(0));
    let base = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": meshes.clone(),
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "corrupt.png"}]
    });
    let mut corrupt = png(&[[9, 9, 9, 255]; 64], 8);
    corrupt.truncate(corrupt.len() / 2);
    std::fs::write(d.join("corrupt.png"), &corrupt).unwrap();
    let e = refused(&write(d, "corrupt_texture.gltf", g.embedded(base.clone())));
    assert!(e.contains("image 0") && e.contains("decode"), "{e}");

    let e = refused(&write(d, "not_json.gltf", "{\"asset\": "));
    assert!(e.contains("JSON"), "{e}");
    let e = refused(&write(d, "truncated.glb", &g.glb(base.clone())[..40]));
    assert!(e.contains("GLB") && e.contains("cut short"), "{e}");
    // A header whose length is shorter than the header: gltf 1.4.1 subtracted it unchecked.
    let mut short = g.glb(base.clone());
    short[8..12].copy_from_slice(&4u32.to_le_bytes());
    let e = refused(&write(d, "short_header.glb", short));
    assert!(e.contains("length of 4 bytes"), "{e}");

    // A buffer file that is not there, and one shorter than it says.
    let doc = g.document(base.clone(), Some("nowhere.bin".into()));
    let e = refused(&write(d, "missing_bin.gltf", doc.to_string()));
    assert!(
        e.contains("nowhere.bin") && e.contains("no such file"),
        "{e}"
    );
    std::fs::write(d.join("short.bin"), &g.bin[..10]).unwrap();
    let doc = g.document(base.clone(), Some("short.bin".into()));
    let e = refused(&write(d, "short_bin.gltf", doc.to_string()));
    assert!(e.contains("byteLength"), "{e}");
    let doc = g.document(
        base.clone(),
        Some("data:application/octet-stream;base64,@@@".into()),
    );
    let e = refused(&write(d, "bad_base64.gltf", doc.to_string()));
    assert!(e.contains("base64"), "{e}");
    let doc = g.document(base.clone(), Some("https://example.com/a.bin".into()));
    let e = refused(&write(d, "remote.gltf", doc.to_string()));
    assert!(e.contains("relative"), "{e}");

    // An accessor past its view, an index past the vertices, an accessor that is not there.
    let mut far: Value = serde_json::from_slice(&g.embedded(base.clone())).unwrap();
    far["accessors"][0]["count"] = json!(100);
    let e = refused(&write(d, "accessor_past_view.gltf", far.to_string()));
    assert!(e.contains("accessor 0") && e.contains("runs past"), "{e}");
    // A huge count is refused before anything is allocated.
    far["accessors"][0]["count"] = json!(1_000_000_000_000u64);
    let e = refused(&write(d, "huge_count.gltf", far.to_string()));
    assert!(e.contains("at most"), "{e}");
    let mut bad_index = Gltf::default();
    let position = bad_index.vec3(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let indices = bad_index.indices(&[0, 1, 7]);
    let rest = json!({
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": position}, "indices": indices}]}]
    });
    let e = refused(&write(
        d,
        "index_out_of_range.gltf",
        bad_index.embedded(rest),
    ));
    assert!(e.contains("vertex 7"), "{e}");
    let mut dangling = base.clone();
    dangling["meshes"][0]["primitives"][0]["indices"] = json!(42);
    let e = refused(&write(d, "dangling.gltf", g.embedded(dangling)));
    assert!(e.contains("invalid glTF"), "{e}");

    // A node cycle, and a node with two parents.
    let mut cycle = base.clone();
    cycle["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    let e = refused(&write(d, "cycle.gltf", g.embedded(cycle)));
    assert!(e.contains("trees"), "{e}");
    // No triangles at all.
    let mut none = base;
    none["scenes"] = json!([{"nodes": []}]);
    let e = refused(&write(d, "nothing.gltf", g.embedded(none)));
    assert!(e.contains("no triangles"), "{e}");

    // Through the binary: exit status 2 and one line.
    let out = run({
        let mut c = cltrace();
        c.arg("render")
            .arg(d.join("cycle.gltf"))
            .arg("-o")
            .arg(d.join("x.png"));
        c.args(["--method", "cpu-bvh"]);
        c
    });
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error:") && stderr.contains("cycle.gltf"),
        "{stderr}"
    );
}

#[test]
fn suzanne_loads_and_renders() {
    let Some(dir) = shared_scene("suzanne_gltf") else {
        return;
    };
    let path = dir.join("Suzanne.gltf");
    let file = load(&path);
    assert_eq!(file.mesh.triangle_count(), 3936);
    assert_eq!(file.mesh.normals.len(), file.mesh.positions.len());
    assert_eq!(file.mesh.uvs.len(), file.mesh.positions.len());
    let m = &file.materials;
    assert_eq!(m.textures.len(), 2, "base colour and metallic-roughness");
    assert!(m.list.iter().any(|x| x.base_texture != NO_TEXTURE));
    let out_dir = tempfile::tempdir().unwrap();
    let out = run({
        let mut c = cltrace();
        c.arg("render")
            .arg(&path)
            .arg("-o")
            .arg(out_dir.path().join("s.png"));
        c.args(["--width", "64", "--height", "48", "--method", "cpu-bvh"]);
        c
    });
    succeeded(&out);
    assert!(out_dir.path().join("s.png").is_file());
}
