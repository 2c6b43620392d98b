//! The bodies of cltrace's fuzz targets, one public function per target. The targets in
//! `fuzz_targets/` only call them, and `tests/fuzz_regressions.rs` includes this file as a
//! module, so that a regression input takes exactly the path it took under the fuzzer.
//!
//! Each function panics where an invariant breaks. Bad input must come back as an `Err`:
//! one line (no control characters), naming the file, exit code 2.

use std::path::Path;

use cltrace::brute::BruteForce;
use cltrace::bvh::Bin32Bvh;
use cltrace::bvh::{BuildOptions, Builder, Bvh, MAX_DEPTH};
use cltrace::camera::Camera;
use cltrace::geometry::{Aabb, Ray};
use cltrace::input::scene_file::{MeshSource, SceneDescription};
use cltrace::input::{MeshFormat, parse_mesh_bytes};
use cltrace::intersect::ClosestHit;
use cltrace::intersect::WatertightRay;
use cltrace::intersect::triangles_in_order;
use cltrace::mesh::Mesh;
use glam::{DVec3, Vec3};

/// Checks the error bad input gets: one line without control characters, starting with
/// the file's name, and the "bad input" exit code.
pub fn check_input_error(path: &Path, err: &cltrace::Error) {
    let msg = err.to_string();
    assert!(
        !msg.chars().any(char::is_control),
        "the error is not one clean line: {msg:?}"
    );
    assert!(
        msg.starts_with(&path.display().to_string()),
        "the error does not name {}: {msg}",
        path.display()
    );
    assert_eq!(err.exit_code(), 2, "bad input exits with 2: {msg}");
}

/// Parses `data` as the mesh file `name` (its extension picks the format) on the loaders'
/// path; a mesh that comes back must pass [`Mesh::check`], an error must be clean.
pub fn mesh_bytes(name: &str, data: &[u8]) -> cltrace::Result<Mesh> {
    let path = Path::new(name);
    let (format, gzip) = MeshFormat::from_path(path).expect("a mesh file name");
    let result = parse_mesh_bytes(path, format, gzip, data);
    match &result {
        Ok(mesh) => {
            if let Err(e) = mesh.check(path) {
                panic!("a loaded mesh fails its check: {e}");
            }
        }
        Err(e) => check_input_error(path, e),
    }
    result
}

/// Target `obj`: the bytes as a Wavefront OBJ file.
pub fn obj(data: &[u8]) -> cltrace::Result<Mesh> {
    mesh_bytes("fuzz.obj", data)
}

/// Target `ply`: the bytes as a Stanford PLY file (ASCII or binary, as its header says).
pub fn ply(data: &[u8]) -> cltrace::Result<Mesh> {
    mesh_bytes("fuzz.ply", data)
}

/// Target `mtl`: the bytes as an MTL material library. Every material read must have an
/// albedo in [0, 1] and a finite, non-negative emission; a refusal is fine (the loader
/// turns it into a warning).
pub fn mtl(data: &[u8]) -> Option<Vec<cltrace::material::Material>> {
    let materials = cltrace::input::parse_material_library(data).ok()?;
    for m in &materials {
        let (albedo, emission) = (m.albedo, m.emission);
        assert!(
            albedo.iter().all(|c| (0.0..=1.0).contains(c)),
            "albedo out of [0, 1]: {albedo:?}"
        );
        assert!(
            emission.iter().all(|c| c.is_finite() && *c >= 0.0),
            "emission not finite and non-negative: {emission:?}"
        );
    }
    Some(materials)
}

/// Generated meshes up to this size are made and checked by the `scene` target.
const MAX_GENERATED: u64 = 20_000;

/// Target `scene`: the bytes (lossily UTF-8) as a scene file. A scene that parses must name
/// a mesh file under its folder or a generator whose parameters are in range (small ones
/// are generated and must pass [`Mesh::check`]); its camera settings must give a camera or
/// a clean error, and a camera must give finite rays.
pub fn scene(data: &[u8]) -> cltrace::Result<SceneDescription> {
    let path = Path::new("fuzz.toml");
    let base = Path::new("scenes");
    let text = String::from_utf8_lossy(data);
    let result = SceneDescription::parse(&text, path, base);
    let scene = match &result {
        Ok(scene) => scene,
        Err(e) => {
            check_input_error(path, e);
            return result;
        }
    };
    let mut bounds = Aabb::from_points([Vec3::splat(-1.0), Vec3::splat(1.0)]);
    let mut triangles = 0;
    for placed in &scene.meshes.meshes {
        if let Some(t) = placed.transform {
            let det = glam::Mat3::from_mat4(t).determinant();
            assert!(det.is_normal(), "a singular transform {t:?}");
        }
        match &placed.source {
            MeshSource::File(file) => assert!(file.starts_with(base), "{}", file.display()),
            MeshSource::Generator(g) => {
                if let Err(e) = g.check() {
                    panic!("a parsed scene has a bad generator: {e}");
                }
                triangles += g.triangle_count();
            }
        }
    }
    // Generators only: a file would be read from the disk.
    let generated = scene
        .meshes
        .meshes
        .iter()
        .all(|m| matches!(m.source, MeshSource::Generator(_)));
    if generated && triangles <= MAX_GENERATED {
        match scene.meshes.load_with_materials() {
            Ok(loaded) => {
                let mesh = &loaded.file.mesh;
                if let Err(e) = mesh.check(path) {
                    panic!("{} makes a bad mesh: {e}", scene.meshes.name());
                }
                let ground = 2 * scene.meshes.ground.is_some() as u64;
                assert_eq!(mesh.triangle_count() as u64, triangles + ground);
                bounds = loaded.bounds;
            }
            // A transform may carry a generated mesh past the coordinate limit.
            Err(e) => check_input_error(path, &e),
        }
    }
    if let Err(e) = cltrace::camera::check_settings(&scene.camera) {
        panic!("a parsed scene has bad camera settings: {e}");
    }
    if let Ok(camera) = Camera::from_settings(&scene.camera, &bounds) {
        let pinhole = camera.pinhole();
        for (x, y) in [(0, 0), (camera.width - 1, camera.height - 1)] {
            let ray = pinhole.ray(x, y);
            assert!(
                ray.origin.is_finite() && ray.dir.is_finite() && ray.dir != Vec3::ZERO,
                "camera {camera:?} gives the ray {ray:?}"
            );
        }
    }
    result
}

// ---------------------------------------------------------------------------------------
// Triangle soups for the BVH targets
// ---------------------------------------------------------------------------------------

/// Coordinates a tag byte `01xx_nnnn` selects: everything the f32 range holds that could
/// upset a builder or a traversal.
const SPECIAL: [f32; 16] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1e38,
    -1e38,
    1e-40, // denormal
    -1e-40,
    f32::MIN_POSITIVE,
    -0.0,
    1e12, // the largest coordinate Mesh::check accepts
    -1e12,
    1.000_000_1e12, // just beyond it
    f32::MAX,
    1e-45, // the smallest denormal
    3.0e6,
    -7.5e11,
];

/// Reads the fuzzer's bytes; past the end every byte reads as 0.
struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// One coordinate, from a tag byte: `00nnnnnn` a point of a coarse grid (shared
    /// coordinates, axis-aligned and coincident triangles), `01..nnnn` a [`SPECIAL`] value,
    /// `101nnnnn` a few ulps above 1, `100nnnnn` tiny multiples of 1e-30, `11......` the
    /// next four bytes as raw f32 bits.
    fn coordinate(&mut self) -> f32 {
        let tag = self.byte();
        let n = (tag & 63) as f32;
        match tag >> 6 {
            0 => n * 0.25 - 8.0,
            1 => SPECIAL[(tag & 15) as usize],
            2 if tag & 32 != 0 => 1.0 + (tag & 31) as f32 * f32::EPSILON,
            2 => (tag & 31) as f32 * 1e-30,
            _ => f32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()]),
        }
    }
}

/// A triangle soup and rays to trace through it, decoded from the fuzzer's bytes.
pub struct Soup {
    pub mesh: Mesh,
    /// Rays with their `t_max`.
    pub rays: Vec<(Ray, f32)>,
    /// The depth limit of the last build option.
    pub max_depth: u32,
}

/// Layout: vertex count (1 + b % 128), triangle count (1 + b), depth limit byte, then
/// the vertices' coordinates ([`Input::coordinate`]), the triangles' indices (a byte each,
/// modulo the vertex count), and three bytes per ray: origin, triangle, point on it.
/// `normalize`: ray directions as unit vectors (the checked pipeline's rays are sane);
/// otherwise raw differences, NaN and all.
pub fn decode_soup(data: &[u8], normalize: bool) -> Soup {
    let mut input = Input(data);
    let nv = 1 + input.byte() as usize % 128;
    let nt = 1 + input.byte() as usize;
    let max_depth = 2 + input.byte() as u32 % (MAX_DEPTH - 1);
    let positions: Vec<Vec3> = (0..nv)
        .map(|_| {
            let x = input.coordinate();
            let y = input.coordinate();
            let z = input.coordinate();
            Vec3::new(x, y, z)
        })
        .collect();
    let triangles: Vec<[u32; 3]> = (0..nt)
        .map(|_| [0; 3].map(|_| (input.byte() as usize % nv) as u32))
        .collect();
    let mesh = Mesh::new(positions, triangles);

    let bounds = mesh.bounds();
    let center = bounds.center();
    let radius = (bounds.extent().length() * 0.5).max(1.0);
    let outside = [
        center + Vec3::new(0.0, 0.0, 2.0) * radius,
        center + Vec3::new(-2.1, 0.3, 0.2) * radius,
        center + Vec3::new(1.3, 1.7, -1.1) * radius,
        center,
    ];
    let corner = |k: usize| mesh.corners(k / 3 % nt)[k % 3];
    let point_on = |tri: usize, sel: u8| {
        let [a, b, c] = mesh.corners(tri % nt);
        match sel % 8 {
            0 => a,
            1 => b,
            2 => c,
            3 => (a + b) * 0.5,
            4 => (b + c) * 0.5,
            5 => (c + a) * 0.5,
            6 => (a + b + c) / 3.0,
            _ => {
                let (u, v) = ((sel >> 3 & 3) as f32 / 4.0, (sel >> 5) as f32 / 8.0);
                a + (b - a) * u + (c - a) * v * (1.0 - u)
            }
        }
    };
    let mut rays = Vec::new();
    let ray_to = |origin: Vec3, target: Vec3, t_sel: u8| {
        let dir = if normalize {
            let d = target.as_dvec3() - origin.as_dvec3();
            let d = d / d.length();
            if !d.is_finite() || d == DVec3::ZERO {
                return None;
            }
            d.as_vec3()
        } else {
            target - origin
        };
        let ray = Ray::new(origin, dir);
        let to_target = (target - origin).length() / dir.length();
        let t_max = match t_sel % 4 {
            0 => to_target,
            1 => to_target * 0.5,
            _ => f32::INFINITY,
        };
        Some((ray, t_max))
    };
    if input.is_empty() {
        // No ray bytes: the centroid and an edge midpoint of each triangle from outside.
        for tri in 0..nt.min(32) {
            rays.extend(ray_to(outside[0], point_on(tri, 6), 2));
            rays.extend(ray_to(outside[1], point_on(tri, 3 + tri as u8 % 3), 2));
        }
    }
    while !input.is_empty() && rays.len() < 256 {
        let (o, tri, sel) = (input.byte(), input.byte() as usize, input.byte());
        let target = point_on(tri, sel);
        let origin = if o & 0x80 != 0 {
            // Exactly along an axis, from outside the bounds.
            let mut axis = Vec3::ZERO;
            axis[(o & 3) as usize % 3] = if o & 4 != 0 { 1.0 } else { -1.0 };
            target - axis * (3.0 * radius)
        } else if (o as usize) < outside.len() {
            outside[o as usize]
        } else {
            corner(o as usize - outside.len())
        };
        rays.extend(ray_to(origin, target, o >> 3));
    }
    Soup {
        mesh,
        rays,
        max_depth,
    }
}

/// The build settings every soup is built with: both builders, few and many bins, leaves
/// of one to the most allowed, and a depth limit from the input.
pub fn build_options(max_depth: u32) -> Vec<BuildOptions> {
    // From the defaults, so that options added later keep their default.
    let with = |mut options: BuildOptions, builder, bins, max_leaf_size, max_depth| {
        options.builder = builder;
        options.bins = bins;
        options.max_leaf_size = max_leaf_size;
        options.max_depth = max_depth;
        options
    };
    let o = |builder, bins, max_leaf_size, max_depth| {
        with(
            BuildOptions::default(),
            builder,
            bins,
            max_leaf_size,
            max_depth,
        )
    };
    vec![
        BuildOptions::default(),
        o(Builder::Binned, 2, 1, MAX_DEPTH),
        o(Builder::Sweep, 32, 1, MAX_DEPTH),
        o(Builder::Binned, 64, 255, MAX_DEPTH),
        o(Builder::Binned, 7, 3, max_depth),
        o(Builder::Sweep, 32, 2, max_depth),
    ]
}

/// Relative distance within which two different triangles hit by one ray count as a tie
/// (as in tests/common).
pub const TIE: f32 = 1e-5;

/// Target `bvh`: the real pipeline. A soup that fails [`Mesh::check`] stops there (the
/// loaders refuse it); one that passes must build a valid tree with every option, whose
/// closest hits and any-hits agree with brute force: the same triangle at the same
/// distance, or a tie within rounding ([`TIE`]): another triangle as near, or a miss where
/// brute force hits as far as `t_max`; or brute force reports a "hit" outside the
/// triangle's own box (the test's distance on a sliver seen edge-on), which the BVH, culling
/// by boxes, may skip. Returns whether the soup passed the check.
pub fn bvh(data: &[u8]) -> bool {
    let soup = decode_soup(data, true);
    let mesh = &soup.mesh;
    if mesh.check(Path::new("fuzz")).is_err() {
        return false;
    }
    let n = mesh.triangle_count();
    let brute = BruteForce {
        triangles: triangles_in_order(mesh, 0..n as u32),
    };
    for options in build_options(soup.max_depth) {
        options.check().expect("valid build options");
        let bvh = Bvh::build(mesh, &options);
        if let Err(e) = bvh.check(mesh) {
            panic!("{options:?}: invalid tree: {e}");
        }
        assert!(bvh.depth <= options.max_depth, "{options:?}: too deep");
        let flat = Bin32Bvh::new(bvh, mesh);
        for (k, (ray, t_max)) in soup.rays.iter().enumerate() {
            let expected = brute.closest_hit(ray, *t_max);
            let got = flat.closest_hit(ray, *t_max);
            // A hit within rounding of `t_max` is a tie with the end of the ray: the box
            // test compares its own rounded entry distance with `t_max`, and may cull it.
            let at_the_end = expected.is_some_and(|(_, s)| s >= *t_max * (1.0 - TIE));
            // The watertight test's distance can be off by far more than rounding on
            // slivers seen edge-on (its edge functions cancel); a "hit" outside the
            // triangle's own box is one no BVH can be asked to find, as it culls by boxes.
            let impossible = expected.is_some_and(|(i, s)| {
                let tri = &brute.triangles[i];
                s < box_entry(ray, [tri.v0, tri.v1, tri.v2]) * (1.0 - TIE as f64) as f32
            });
            match (expected, got) {
                (None, None) => {}
                (Some(_), None) if at_the_end || impossible => {}
                (Some((i, s)), Some((j, t))) => {
                    let (a, b) = (brute.triangles[i].prim, flat.triangles[j].prim);
                    // The same triangle at the same distance (the same test on the same
                    // data), or a tie: two triangles within rounding of each other (which
                    // one wins depends on the order they are tested in, as `t < t_max`
                    // is compared in the test's scaled space), the BVH's really hit there.
                    let own = WatertightRay::new(ray).intersect_stored(&flat.triangles[j], *t_max);
                    let tie = (s - t).abs() <= TIE * s.abs().max(t.abs()) && own == Some(t);
                    assert!(
                        (a == b && s == t) || (a != b && (tie || impossible)),
                        "{options:?}, ray {k} {ray:?} (t_max {t_max}): brute force hits \
                         triangle {a} at {s}, the BVH triangle {b} at {t}"
                    );
                }
                _ => panic!(
                    "{options:?}, ray {k} {ray:?} (t_max {t_max}): brute force {expected:?}, \
                     BVH {got:?}"
                ),
            }
            assert!(
                flat.occluded(ray, *t_max) == expected.is_some() || at_the_end || impossible,
                "{options:?}, ray {k} {ray:?} (t_max {t_max}): any-hit differs from {expected:?}"
            );
        }
    }
    true
}

/// Where the ray enters the box around `corners`, in f64 (+inf if it misses it): a lower
/// bound for the distance of any true hit on the triangle.
pub fn box_entry(ray: &Ray, corners: [[f32; 3]; 3]) -> f32 {
    let box_ = Aabb::from_points(corners.map(Vec3::from));
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (lo, hi) = (box_.min.as_dvec3(), box_.max.as_dvec3());
    let (mut near, mut far) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return f32::INFINITY;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    if near <= far {
        near as f32
    } else {
        f32::INFINITY
    }
}

/// Checks what keeps a traversal in bounds whatever the coordinates: depth-first children
/// inside the node list, leaves inside the triangle list, every triangle in exactly one
/// leaf, the depth as recorded and within `max_depth`. (Not the boxes: NaN has none.)
pub fn check_structure(bvh: &Bvh, n: usize, max_depth: u32) -> Result<(), String> {
    if bvh.prim_order.len() != n {
        return Err(format!("{} of {n} triangles ordered", bvh.prim_order.len()));
    }
    let mut seen = vec![false; n];
    let (mut visited, mut deepest) = (0, 0);
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, depth)) = stack.pop() {
        visited += 1;
        deepest = deepest.max(depth);
        let node = bvh.nodes.get(i).ok_or(format!("node {i} out of range"))?;
        if node.is_leaf() {
            let (first, count) = (node.left_or_first as usize, node.count() as usize);
            if count == 0 || first + count > n {
                return Err(format!("leaf {i}: range {first}+{count} of {n}"));
            }
            for &p in &bvh.prim_order[first..first + count] {
                if p as usize >= n || std::mem::replace(&mut seen[p as usize], true) {
                    return Err(format!("triangle {p} missing or twice"));
                }
            }
        } else {
            let (l, r) = (node.left_or_first as usize, node.right_or_count as usize);
            if l != i + 1 || r <= l || r >= bvh.nodes.len() {
                return Err(format!("node {i}: children {l}, {r}"));
            }
            stack.push((l, depth + 1));
            stack.push((r, depth + 1));
        }
    }
    if seen.iter().any(|s| !s) || visited != bvh.nodes.len() {
        return Err("unreachable nodes or triangles".into());
    }
    if deepest != bvh.depth || deepest > max_depth {
        return Err(format!(
            "depth {deepest}, recorded {}, limit {max_depth}",
            bvh.depth
        ));
    }
    Ok(())
}

/// Target `bvh_raw`: the builder without the check, NaN, infinities and all, straight into
/// [`Bvh::build`] and a traversal. Nothing may panic or hang; the tree may be of any
/// quality but must be structurally sound ([`check_structure`]), so that a traversal stays
/// in bounds. Returns the number of hits found, to keep the traversals from being optimised
/// away.
pub fn bvh_raw(data: &[u8]) -> usize {
    let soup = decode_soup(data, false);
    let mesh = &soup.mesh;
    let n = mesh.triangle_count();
    let brute = BruteForce {
        triangles: triangles_in_order(mesh, 0..n as u32),
    };
    let _ = mesh.degenerate_count();
    let mut hits = 0;
    for options in build_options(soup.max_depth) {
        let bvh = Bvh::build(mesh, &options);
        if let Err(e) = check_structure(&bvh, n, options.max_depth) {
            panic!("{options:?}: broken tree: {e}");
        }
        let _ = bvh.check(mesh);
        let _ = bvh.stats();
        let flat = Bin32Bvh::new(bvh, mesh);
        for (ray, t_max) in &soup.rays {
            for any_hit in [false, true] {
                if let Some((i, _)) = flat.trace(ray, *t_max, any_hit) {
                    assert!(i < n);
                    hits += 1;
                }
            }
        }
    }
    for (ray, t_max) in &soup.rays {
        hits += brute.closest_hit(ray, *t_max).is_some() as usize;
    }
    hits
}

/// Target `gltf`: the bytes as a glTF file (a `.glb` when they start with its magic), with
/// its materials and the textures in data URIs or the binary chunk. A file that loads must
/// pass the mesh check, give every triangle a material and every texture slot a texture.
pub fn gltf(data: &[u8]) -> cltrace::Result<cltrace::input::MeshFile> {
    let path = Path::new("fuzz.gltf");
    let result = cltrace::input::parse_gltf_bytes(path, data);
    match &result {
        Ok(file) => {
            if let Err(e) = file.mesh.check(path) {
                panic!("a loaded mesh fails its check: {e}");
            }
            let m = &file.materials;
            assert!(
                m.per_triangle.is_empty() || m.per_triangle.len() == file.mesh.triangle_count(),
                "{} material indices for {} triangles",
                m.per_triangle.len(),
                file.mesh.triangle_count()
            );
            assert!(m.per_triangle.iter().all(|&i| (i as usize) < m.list.len()));
            for material in &m.list {
                let slots = [
                    material.base_texture,
                    material.emission_texture,
                    material.metallic_roughness_texture,
                    material.normal_texture,
                    material.alpha_texture,
                    material.occlusion_texture,
                ];
                for slot in slots {
                    assert!(
                        slot == cltrace::material::NO_TEXTURE
                            || (0..m.textures.len() as i32).contains(&slot),
                        "texture slot {slot} of {} textures",
                        m.textures.len()
                    );
                }
                assert!(material.albedo.iter().all(|c| (0.0..=1.0).contains(c)));
                assert!(material.emission.iter().all(|e| e.is_finite() && *e >= 0.0));
            }
            if let Some(c) = &file.camera {
                let fov = c.fov.expect("a file's camera has a field of view");
                assert!(fov > 0.0 && fov < 180.0, "fov {fov}");
            }
        }
        Err(e) => check_input_error(path, e),
    }
    result
}

/// Target `texture`: the bytes as an image file decoded to a texture. One that decodes has
/// `width * height` finite texels; an error is clean.
pub fn texture(data: &[u8]) -> cltrace::Result<cltrace::material::Texture> {
    use cltrace::input::texture::{ColorSpace, decode_texture};
    let path = Path::new("fuzz.png");
    let result = decode_texture(path, data, ColorSpace::Srgb, [Default::default(); 2]);
    match &result {
        Ok(t) => {
            assert_eq!(t.texels.len(), t.width as usize * t.height as usize);
            assert!(t.texels.iter().flatten().all(|v| v.is_finite()));
        }
        Err(e) => check_input_error(path, e),
    }
    result
}
