//! Scene files of several meshes: each `[[mesh]]` lands where its transform puts it, in
//! file order, then the ground plane; a mirroring scale keeps the front faces; a material
//! override covers its own mesh only; the one-mesh form loads exactly as before; the
//! example scene renders; and a part's scene hash covers every mesh.

use std::path::{Path, PathBuf};

use cltrace::geometry::Aabb;
use cltrace::input::load_mesh_with_materials;
use cltrace::input::scene::{Ground, LoadedScene};
use cltrace::input::scene_file::SceneDescription;
use cltrace::mesh::Mesh;
use glam::Vec3;

use crate::common::command::{cltrace, run, succeeded, text};

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The scene `text`, its files taken from `scenes/`, loaded.
fn load(text: &str) -> LoadedScene {
    let path = scenes().join("test.toml");
    SceneDescription::parse(text, &path, &scenes())
        .unwrap()
        .meshes
        .load_with_materials()
        .unwrap()
}

/// The box around triangles `range` of `mesh`.
fn bounds_of(mesh: &Mesh, range: std::ops::Range<usize>) -> Aabb {
    Aabb::from_points(range.flat_map(|i| mesh.corners(i)))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn several_meshes_land_where_their_transforms_put_them_in_file_order() {
    let loaded = load(
        "[[mesh]]\ngenerator = { kind = \"cube\" }\ntranslate = [5, 0, 0]\n\
         [[mesh]]\ngenerator = { kind = \"cube\" }\nscale = [2, 1, 0.5]\ntranslate = [0, 10, 0]\n\
         [[mesh]]\nfile = \"room.obj\"\n",
    );
    let mesh = &loaded.file.mesh;
    let room = load_mesh_with_materials(&scenes().join("room.obj")).unwrap();
    let r = room.mesh.triangle_count();
    assert_eq!(mesh.triangle_count(), 12 + 12 + r);
    let first = bounds_of(mesh, 0..12);
    assert_eq!(
        (first.min, first.max),
        (Vec3::new(4.0, -1.0, -1.0), Vec3::new(6.0, 1.0, 1.0))
    );
    let second = bounds_of(mesh, 12..24);
    assert_eq!(
        (second.min, second.max),
        (Vec3::new(-2.0, 9.0, -0.5), Vec3::new(2.0, 11.0, 0.5))
    );
    // The room, untouched, comes third, triangle for triangle.
    for i in 0..r {
        assert_eq!(mesh.corners(24 + i), room.mesh.corners(i));
    }
    assert_eq!(loaded.bounds, mesh.bounds());
}

#[test]
fn rotations_turn_right_handed_about_x_then_y_then_z() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("t.obj"),
        "v 0 1 0\nv 0 0 1\nv 1 0 0\nf 1 2 3\n",
    )
    .unwrap();
    let corners = |rotate: &str| {
        let text = format!("[[mesh]]\nfile = \"t.obj\"\nrotate = {rotate}\n");
        let scene = SceneDescription::parse(&text, &dir.path().join("s.toml"), dir.path()).unwrap();
        scene.meshes.load().unwrap().corners(0)
    };
    // A quarter turn about y takes +z to +x and +x to -z; quarter turns are exact.
    assert_eq!(corners("[0, 90, 0]"), [Vec3::Y, Vec3::X, -Vec3::Z]);
    // About x first (+y to +z), then about y (+z to +x): the order matters.
    assert_eq!(corners("[90, 90, 0]"), [Vec3::X, -Vec3::Y, -Vec3::Z]);
    assert_eq!(corners("[0, 90, 90]"), [-Vec3::X, Vec3::Y, -Vec3::Z]);
    let [a, ..] = corners("[45, 0, 0]");
    assert!(close(a, Vec3::new(0.0, 1.0, 1.0).normalize()), "{a}");
}

#[test]
fn a_mirroring_scale_keeps_the_front_faces_outside() {
    for scale in ["1", "[-1, 1, 1]", "[1, -2, 1]", "-1", "[-1, -1, 1]"] {
        let loaded = load(&format!(
            "[[mesh]]\ngenerator = {{ kind = \"cube\" }}\nscale = {scale}\n"
        ));
        let mesh = &loaded.file.mesh;
        for i in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(i);
            let outward = (a + b + c) / 3.0;
            let normal = (b - a).cross(c - a);
            assert!(
                normal.dot(outward) > 0.0,
                "scale {scale}: triangle {i} faces in"
            );
        }
    }
}

#[test]
fn a_material_override_covers_its_own_mesh_only() {
    let loaded = load(
        "[[mesh]]\nfile = \"room.obj\"\n\
         [[mesh]]\nfile = \"room.obj\"\ntranslate = [10, 0, 0]\n\
         material = { albedo = [0.1, 0.2, 0.3], emission = [0, 0, 5] }\n\
         [[mesh]]\nfile = \"room.obj\"\ntranslate = [20, 0, 0]\n",
    );
    let room = load_mesh_with_materials(&scenes().join("room.obj")).unwrap();
    let r = room.mesh.triangle_count();
    let m = &loaded.file.materials;
    for i in 0..r {
        assert_eq!(m.of(i), room.materials.of(i), "first room, triangle {i}");
        assert_eq!(
            m.of(2 * r + i),
            room.materials.of(i),
            "third room, triangle {i}"
        );
        let overridden = m.of(r + i);
        assert_eq!(
            (overridden.albedo, overridden.emission),
            ([0.1, 0.2, 0.3], [0.0, 0.0, 5.0])
        );
    }
    assert!(
        (0..r).any(|i| room.materials.of(i).emits()),
        "room.obj has a light"
    );
}

#[test]
fn the_ground_comes_last_under_the_meshes_when_asked_for() {
    let meshes = "[[mesh]]\ngenerator = { kind = \"cube\" }\ntranslate = [3, 2, 1]\n\
                  [[mesh]]\ngenerator = { kind = \"sphere\", subdivisions = 1 }\n";
    let without = load(meshes);
    assert_eq!(without.file.mesh.triangle_count(), 12 + 80);
    let with = load(&format!("{meshes}[ground]\nalbedo = [0.2, 0.4, 0.6]\n"));
    let mesh = &with.file.mesh;
    let n = mesh.triangle_count();
    assert_eq!(n, 12 + 80 + 2);
    // The meshes' triangles are the same, and so is the box the camera frames.
    for i in 0..n - 2 {
        assert_eq!(mesh.corners(i), without.file.mesh.corners(i));
    }
    assert_eq!(with.bounds, without.bounds);
    let meshes_box = without.bounds;
    let ground = bounds_of(mesh, n - 2..n);
    assert_eq!(ground.min.y, ground.max.y);
    assert!(
        ground.max.y < meshes_box.min.y,
        "{ground:?} is not under {meshes_box:?}"
    );
    let radius = meshes_box.extent().length() / 2.0;
    assert!(meshes_box.min.y - ground.max.y <= 2.0 * Ground::GAP * radius);
    assert!(ground.min.x < meshes_box.min.x && ground.max.x > meshes_box.max.x);
    assert!(ground.min.z < meshes_box.min.z && ground.max.z > meshes_box.max.z);
    for i in n - 2..n {
        let [a, b, c] = mesh.corners(i);
        assert!((b - a).cross(c - a).y > 0.0, "the ground faces up");
        assert_eq!(with.file.materials.of(i).albedo, [0.2, 0.4, 0.6]);
    }
    // Height and size as given.
    let placed = load(&format!("{meshes}[ground]\nheight = -3\nsize = 8\n"));
    let ground = bounds_of(&placed.file.mesh, n - 2..n);
    assert_eq!(
        (ground.min.y, ground.extent().x, ground.extent().z),
        (-3.0, 8.0, 8.0)
    );
}

#[test]
fn the_one_mesh_form_loads_exactly_as_the_mesh_file_does() {
    let room = load_mesh_with_materials(&scenes().join("room.obj")).unwrap();
    for text in ["mesh = \"room.obj\"\n", "[[mesh]]\nfile = \"room.obj\"\n"] {
        let loaded = load(text);
        assert_eq!(loaded.file.mesh, room.mesh, "{text}");
        assert_eq!(loaded.file.materials, room.materials, "{text}");
        assert_eq!(loaded.bounds, room.mesh.bounds());
    }
    let scene = SceneDescription::named(Some(&scenes().join("room.toml"))).unwrap();
    assert_eq!(scene.meshes.name(), "room.obj");
    assert_eq!(scene.meshes.load().unwrap(), room.mesh);
}

/// The materials example holds every model it says it does, and renders.
#[test]
fn the_materials_example_scene_holds_glass_metals_and_plastic() {
    use cltrace::material::Bsdf;
    let scene = SceneDescription::named(Some(&scenes().join("materials.toml"))).unwrap();
    let loaded = scene.meshes.load_with_materials().unwrap();
    let models: Vec<Bsdf> = loaded
        .file
        .materials
        .list
        .iter()
        .map(|m| Bsdf::from_code(m.bsdf))
        .collect();
    for b in [
        Bsdf::Dielectric,
        Bsdf::Conductor,
        Bsdf::Plastic,
        Bsdf::Diffuse,
    ] {
        assert!(models.contains(&b), "{b:?} missing from {models:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(scenes().join("materials.toml"))
        .args([
            "--width", "32", "--height", "24", "--method", "cpu-bvh", "--spp", "2", "-q",
        ])
        .arg("-o")
        .arg(dir.path().join("materials.png"));
    succeeded(&run(cmd));
}

#[test]
fn the_example_scene_renders_and_animates() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("several.png");
    let json = dir.path().join("several.json");
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(scenes().join("several.toml"))
        .args([
            "--width", "64", "--height", "48", "--method", "cpu-bvh", "--spp", "2",
        ])
        .arg("-o")
        .arg(&png)
        .arg("--json")
        .arg(&json);
    let out = run(cmd);
    succeeded(&out);
    assert!(png.is_file());
    let summary = std::fs::read_to_string(&json).unwrap();
    assert!(
        summary.contains("room.obj + sphere(subdivisions=3) + cube + room.obj + ground"),
        "{summary}"
    );

    // Several meshes in an animated scene, through --frames.
    let scene = dir.path().join("turn.toml");
    let text = std::fs::read_to_string(scenes().join("several.toml")).unwrap();
    let text = text.replace("room.obj", &scenes().join("room.obj").display().to_string());
    std::fs::write(&scene, format!("{text}\n[camera.turntable]\nframes = 2\n")).unwrap();
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(&scene)
        .args([
            "--width", "16", "--height", "12", "--method", "cpu-bvh", "--shade", "lambert",
        ])
        .args(["--frames", "0..2", "-o"])
        .arg(dir.path().join("turn_%d.png"));
    succeeded(&run(cmd));
    assert!(dir.path().join("turn_0.png").is_file() && dir.path().join("turn_1.png").is_file());
}

/// Renders `scene` (text, written into `dir`) as a part of rows `rows` of a 16x8 image.
fn part(dir: &Path, name: &str, scene: &str, rows: &str) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, scene).unwrap();
    let exr = dir.join(format!("{name}.exr"));
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(&path)
        .args([
            "--width", "16", "--height", "8", "--method", "cpu-bvh", "--shade", "ao",
        ])
        .args(["--spp", "1", "--ao-samples", "1", "--region", rows, "-o"])
        .arg(&exr);
    succeeded(&run(cmd));
    exr
}

#[test]
fn parts_of_scenes_that_differ_in_a_later_mesh_do_not_merge() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |x: f32| {
        format!(
            "[[mesh]]\ngenerator = {{ kind = \"cube\" }}\n\
             [[mesh]]\ngenerator = {{ kind = \"cube\" }}\nscale = 0.5\ntranslate = [{x:?}, 1, 0]\n\
             [camera]\neye = [0, 0, 8]\nlook_at = [0, 0, 0]\n"
        )
    };
    let top = part(dir.path(), "top", &scene(1.0), "0,0,16,4");
    let bottom = part(dir.path(), "bottom", &scene(1.0), "0,4,16,8");
    let moved = part(dir.path(), "moved", &scene(1.5), "0,4,16,8");
    let merge = |parts: [&PathBuf; 2]| {
        let mut cmd = cltrace();
        cmd.arg("merge")
            .args(parts)
            .arg("-o")
            .arg(dir.path().join("merged.png"));
        run(cmd)
    };
    succeeded(&merge([&top, &bottom]));
    let refused = merge([&top, &moved]);
    assert_eq!(refused.status.code(), Some(2), "{}", text(&refused.stderr));
    assert!(
        text(&refused.stderr).contains("scene="),
        "{}",
        text(&refused.stderr)
    );
}
