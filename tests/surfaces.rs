//! What a hit looks like (issue 16): shading normals from the file or computed with a crease
//! angle, textures (base colour, cut-out masks, normal maps), vertex colours. Every layout's
//! kernels, and brute force, give what the host reference gives: the single-hit shade modes
//! to the bit, the progressive ones within the stated tolerance. The meshes and textures are
//! written by the tests.

use std::path::{Path, PathBuf};

use crate::common::command::{cltrace, run, succeeded, text};

/// The layouts of `cl-bvh`, each compared with the host: every layout's traversal (with
/// its cut-out masks) meets camera rays.
const EVERY_LAYOUT: &[&str] = &["bin32", "bin64", "wide4", "wide8", "cwbvh"];

/// The layouts the progressive modes are compared on: what happens at a hit is the same
/// code in every layout, and each compile of the progressive kernels costs PoCL seconds.
/// The GPU's and the CPU's default layouts.
const SOME_LAYOUTS: &[&str] = &["bin64", "wide8"];

/// A UV sphere of radius 1 about the origin: `rings` x `segments` quads, with `vn` lines
/// (the exact sphere normals) when `normals`, and `vt` lines (longitude, latitude) when
/// `uvs`.
fn uv_sphere(rings: u32, segments: u32, normals: bool, uvs: bool) -> String {
    let mut obj = String::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let p = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
            if normals {
                obj += &format!("vn {} {} {}\n", p[0], p[1], p[2]);
            }
            if uvs {
                obj += &format!(
                    "vt {} {}\n",
                    s as f32 / segments as f32,
                    1.0 - r as f32 / rings as f32
                );
            }
        }
    }
    let index = |r: u32, s: u32| r * (segments + 1) + s + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (
                index(r, s),
                index(r + 1, s),
                index(r + 1, s + 1),
                index(r, s + 1),
            );
            let corner = |i: u32| match (normals, uvs) {
                (true, true) => format!("{i}/{i}/{i}"),
                (true, false) => format!("{i}//{i}"),
                (false, true) => format!("{i}/{i}"),
                (false, false) => format!("{i}"),
            };
            obj += &format!(
                "f {} {} {} {}\n",
                corner(a),
                corner(d),
                corner(c),
                corner(b)
            );
        }
    }
    obj
}

/// An 8x8 checkerboard PNG, `dark` and `light` RGBA squares, `cells` per side.
fn checker_png(path: &Path, cells: u32, dark: [u8; 4], light: [u8; 4]) {
    let size = 8 * cells;
    let img = image::RgbaImage::from_fn(size, size, |x, y| {
        image::Rgba(if (x / 8 + y / 8) % 2 == 0 {
            dark
        } else {
            light
        })
    });
    img.save(path).unwrap();
}

/// A unit quad in the z = 0 plane facing +z with texture coordinates over [0, 1]^2, and
/// behind it a larger wall tilted away (so its normal shades differently), with material
/// `quad` for the quad (from `scene.mtl`) and none for the wall.
fn quad_and_wall(dir: &Path, mtl: &str) -> PathBuf {
    std::fs::write(dir.join("scene.mtl"), mtl).unwrap();
    let obj = "mtllib scene.mtl\n\
        v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
        v -3 -3 -2\nv 3 -3 -1\nv 3 3 -1\nv -3 3 -2\n\
        usemtl quad\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n\
        usemtl wall\nf 5 6 7\nf 5 7 8\n";
    let path = dir.join("scene.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// `cltrace render MESH -o OUT` looking at the origin from +z, with `args`.
fn render(mesh: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(mesh)
        .arg("-o")
        .arg(out)
        .args(["--eye", "0.3,0.4,3.5", "--look-at", "0,0,0", "--fov", "50"])
        .args(["--width", "48", "--height", "40"])
        .args(args);
    run(cmd)
}

fn pixels(path: &Path) -> Vec<[u8; 4]> {
    image::open(path)
        .unwrap()
        .to_rgba8()
        .pixels()
        .map(|p| p.0)
        .collect()
}

/// Renders `mesh` with `args` on the host (cpu-bvh) and with brute force and `layouts` on
/// the device; calls `same` with the host's and each device's pixels.
fn host_and_devices(
    dir: &Path,
    mesh: &Path,
    args: &[&str],
    layouts: &[&str],
    same: impl Fn(&str, &[[u8; 4]], &[[u8; 4]]),
) -> Vec<[u8; 4]> {
    let host = dir.join("host.png");
    let out = render(mesh, &host, &[args, &["--method", "cpu-bvh"]].concat());
    succeeded(&out);
    let host = pixels(&host);
    let mut kernels: Vec<Vec<&str>> = vec![vec!["--method", "cl-brute"]];
    kernels.extend(
        layouts
            .iter()
            .map(|l| vec!["--method", "cl-bvh", "--layout", *l]),
    );
    for k in kernels {
        let file = dir.join(format!("{}.png", k.join("_")));
        let out = render(mesh, &file, &[args, &k].concat());
        succeeded(&out);
        same(&k.join(" "), &host, &pixels(&file));
    }
    host
}

#[track_caller]
fn equal(what: &str, host: &[[u8; 4]], device: &[[u8; 4]]) {
    let differ = host.iter().zip(device).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{what}: {differ} pixels differ from the host");
}

/// Progressive modes: the host and the device draw the same random numbers and mirror each
/// operation, but built-in functions (log2 of the mip level, normalize, dot) may differ by
/// an ulp, so each 8-bit channel may differ by 2, and on average by under 0.05.
#[track_caller]
fn close(what: &str, host: &[[u8; 4]], device: &[[u8; 4]]) {
    let diffs: Vec<i32> = host
        .iter()
        .zip(device)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] as i32 - b[c] as i32).abs()))
        .collect();
    let max = diffs.iter().max().copied().unwrap_or(0);
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    assert!(max <= 2 && mean < 0.05, "{what}: max {max}, mean {mean}");
}

/// The largest step in colour between neighbouring pixels of the middle row, both on the
/// sphere: a faceted sphere jumps at every facet edge, a smooth one changes gradually.
fn largest_step_in_middle_row(p: &[[u8; 4]]) -> i32 {
    let row = &p[20 * 48..21 * 48];
    let sum = |q: &[u8; 4]| q[..3].iter().map(|&c| c as i32).sum::<i32>();
    row.windows(2)
        .filter(|w| sum(&w[0]) > 0 && sum(&w[1]) > 0)
        .map(|w| (sum(&w[0]) - sum(&w[1])).abs())
        .max()
        .unwrap_or(0)
}

#[test]
fn smooth_normals_from_the_file_or_the_crease_angle_match_the_host_on_every_layout() {
    let dir = tempfile::tempdir().unwrap();
    let with = dir.path().join("with_vn.obj");
    let without = dir.path().join("without_vn.obj");
    std::fs::write(&with, uv_sphere(8, 12, true, false)).unwrap();
    std::fs::write(&without, uv_sphere(8, 12, false, false)).unwrap();
    for shade in ["normal", "lambert"] {
        let from_file =
            host_and_devices(dir.path(), &with, &["--shade", shade], EVERY_LAYOUT, equal);
        let computed = host_and_devices(
            dir.path(),
            &without,
            &["--shade", shade],
            EVERY_LAYOUT,
            equal,
        );
        let faceted = host_and_devices(
            dir.path(),
            &without,
            &["--shade", shade, "--crease-angle", "0"],
            EVERY_LAYOUT,
            equal,
        );
        let (a, b, c) = (
            largest_step_in_middle_row(&from_file),
            largest_step_in_middle_row(&computed),
            largest_step_in_middle_row(&faceted),
        );
        assert!(
            2 * a < c && 2 * b < c,
            "{shade}: smooth {a} and {b}, faceted {c}"
        );
    }
    // The crease angle is a scene key too, and its range is checked.
    let out = render(
        &without,
        &dir.path().join("x.png"),
        &["--crease-angle", "200"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("--crease-angle 200"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn smooth_spheres_path_trace_as_the_host_does() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = dir.path().join("sphere.obj");
    std::fs::write(&sphere, uv_sphere(6, 8, false, false)).unwrap();
    for shade in ["ao", "shadow", "path"] {
        host_and_devices(
            dir.path(),
            &sphere,
            &["--shade", shade, "--spp", "2"],
            SOME_LAYOUTS,
            close,
        );
    }
}

#[test]
fn a_base_colour_texture_is_read_filtered_and_matches_the_host() {
    let dir = tempfile::tempdir().unwrap();
    checker_png(
        &dir.path().join("checker.png"),
        4,
        [255, 0, 0, 255],
        [0, 0, 255, 255],
    );
    let mesh = quad_and_wall(
        dir.path(),
        "newmtl quad\nKd 1 1 1\nmap_Kd checker.png\nnewmtl wall\nKd 0.5 0.5 0.5\n",
    );
    let args = ["--shade", "shadow", "--spp", "2", "--light", "sun:0,0,1"];
    let host = host_and_devices(dir.path(), &mesh, &args, SOME_LAYOUTS, close);
    // The quad shows both squares' colours: red ones and blue ones.
    let red = host.iter().filter(|p| p[0] > 100 && p[2] < 40).count();
    let blue = host.iter().filter(|p| p[2] > 100 && p[0] < 40).count();
    assert!(red > 100 && blue > 100, "red {red}, blue {blue}");
}

/// A quad cut out in a checker (`map_d`) in front of a wall.
fn cut_out_quad_and_wall() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    checker_png(
        &dir.path().join("mask.png"),
        4,
        [255, 255, 255, 0],
        [255, 255, 255, 255],
    );
    let mesh = quad_and_wall(
        dir.path(),
        "newmtl quad\nKd 0.8 0.8 0.8\nmap_d mask.png\nnewmtl wall\nKd 0.5 0.5 0.5\n",
    );
    (dir, mesh)
}

#[test]
fn cut_out_masks_let_camera_rays_through_their_holes_on_every_layout() {
    let (dir, mesh) = cut_out_quad_and_wall();
    // Camera rays: the wall shows through the holes (its normal has another colour).
    let host = host_and_devices(
        dir.path(),
        &mesh,
        &["--shade", "normal"],
        EVERY_LAYOUT,
        equal,
    );
    let quad_colour = [128, 128, 255, 255];
    let on_quad = host.iter().filter(|p| **p == quad_colour).count();
    assert!(on_quad > 100, "{on_quad} pixels show the quad");
    let through = host
        .iter()
        .filter(|p| **p != quad_colour && p[..3] != [0, 0, 0])
        .count();
    assert!(
        through > 100,
        "{through} pixels show the wall through the holes"
    );
}

/// The shadow and bounce rays of [`cut_out_masks_let_camera_rays_through_their_holes_on_every_layout`]'s
/// scene (a test of its own, so that the two halves' program compiles run side by side).
#[test]
fn cut_out_masks_let_shadow_and_bounce_rays_through_their_holes() {
    let (dir, mesh) = cut_out_quad_and_wall();
    // The sun casts the checker's shadow on the wall.
    for shade in ["shadow", "path"] {
        host_and_devices(
            dir.path(),
            &mesh,
            &["--shade", shade, "--spp", "2", "--light", "sun:0.2,0.1,1"],
            SOME_LAYOUTS,
            close,
        );
    }
}

#[test]
fn a_normal_map_bends_the_shading_normal_as_on_the_host() {
    let dir = tempfile::tempdir().unwrap();
    // Every texel leans the normal towards +u (the tangent, +x on this quad).
    let lean = [218, 128, 218, 255];
    checker_png(&dir.path().join("normal.png"), 1, lean, lean);
    let mtl =
        |map: &str| format!("newmtl quad\nKd 0.8 0.8 0.8\n{map}\nnewmtl wall\nKd 0.5 0.5 0.5\n");
    // A low sun from +x: the leaning surface faces it more, and is brighter.
    let args = ["--shade", "shadow", "--spp", "1", "--light", "sun:1,0,0.3"];
    let flat = quad_and_wall(dir.path(), &mtl(""));
    let flat = host_and_devices(dir.path(), &flat, &args, SOME_LAYOUTS, close)[20 * 48 + 24];
    let mapped = quad_and_wall(dir.path(), &mtl("norm normal.png"));
    let mapped = host_and_devices(dir.path(), &mapped, &args, SOME_LAYOUTS, close)[20 * 48 + 24];
    assert!(
        mapped[0] as i32 > flat[0] as i32 + 20,
        "flat {flat:?}, mapped {mapped:?}"
    );
    // The single-hit modes show the interpolated vertex normal: the quad's own here.
    let normal = host_and_devices(
        dir.path(),
        &quad_and_wall(dir.path(), &mtl("norm normal.png")),
        &["--shade", "normal"],
        EVERY_LAYOUT,
        equal,
    );
    assert_eq!(normal[20 * 48 + 24], [128, 128, 255, 255]);
}

#[test]
fn ply_vertex_colours_colour_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("red.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n\
         -2 -2 0 255 0 0\n2 -2 0 255 0 0\n0 2 0 255 0 0\n3 0 1 2\n",
    )
    .unwrap();
    let args = ["--shade", "shadow", "--spp", "1", "--light", "sun:0,0,1"];
    let host = host_and_devices(dir.path(), &ply, &args, SOME_LAYOUTS, close);
    let centre = host[20 * 48 + 24];
    assert!(
        centre[0] > 150 && centre[1] < 30 && centre[2] < 30,
        "{centre:?}"
    );
}

#[test]
fn a_missing_texture_is_a_warning_and_a_grey_surface_and_a_corrupt_one_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = quad_and_wall(
        dir.path(),
        "newmtl quad\nKd 1 0 0\nmap_Kd gone.png\nnewmtl wall\nKd 0.5 0.5 0.5\n",
    );
    let png = dir.path().join("out.png");
    let out = render(
        &mesh,
        &png,
        &["--shade", "shadow", "--spp", "1", "--light", "sun:0,0,1"],
    );
    succeeded(&out);
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("warning") && stderr.contains("gone.png") && stderr.contains("grey"),
        "{stderr}"
    );
    let centre = pixels(&png)[20 * 48 + 24];
    assert!(
        centre[0] == centre[1] && centre[1] == centre[2],
        "grey, not red: {centre:?}"
    );

    std::fs::write(dir.path().join("gone.png"), b"\x89PNG\r\n\x1a\nbroken").unwrap();
    let out = render(&mesh, &dir.path().join("bad.png"), &[]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("gone.png"), "{stderr}");
    assert!(!dir.path().join("bad.png").exists());
}
