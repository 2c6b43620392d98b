//! `cltrace::input::load_mesh` against OBJ and PLY files written here, good and bad.

use std::io::Write;
use std::path::{Path, PathBuf};

use cltrace::input::{load_mesh, load_mesh_with_materials};
use cltrace::material::Material;
use cltrace::mesh::{Mesh, Triangulation, triangulate_polygon};
use glam::Vec3;

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn load(name: &str, bytes: impl AsRef<[u8]>) -> Mesh {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), name, bytes);
    match load_mesh(&path) {
        Ok(mesh) => mesh,
        Err(e) => panic!("{name} should load, got: {e}"),
    }
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Every triangle's corners, in order.
fn corners(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    (0..mesh.triangle_count())
        .map(|i| mesh.corners(i))
        .collect()
}

/// Checks the error for a file that must be refused and returns its message.
fn refused(path: &Path) -> String {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let err = match load_mesh(path) {
        Ok(mesh) => panic!(
            "{name} should be refused, but loaded {} triangles",
            mesh.triangle_count()
        ),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert_eq!(err.exit_code(), 2, "{name}: {msg}");
    assert!(
        msg.contains(&name),
        "{name}: message does not name the file: {msg}"
    );
    assert!(
        !msg.contains('\n'),
        "{name}: message is not one line: {msg:?}"
    );
    assert!(!msg.trim().is_empty());
    msg
}

/// Writes `bytes` as `name` and checks that loading it is refused.
fn refused_bytes(name: &str, bytes: impl AsRef<[u8]>) -> String {
    let dir = tempfile::tempdir().unwrap();
    refused(&write(dir.path(), name, bytes))
}

/// Like [`refused_bytes`], and the message must point at `name:line:`.
fn refused_at(name: &str, bytes: impl AsRef<[u8]>, line: usize) -> String {
    let msg = refused_bytes(name, bytes);
    assert!(
        msg.contains(&format!("{name}:{line}:")),
        "expected `{name}:{line}:` in: {msg}"
    );
    msg
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

// ---------------------------------------------------------------------------------------
// OBJ
// ---------------------------------------------------------------------------------------

const POLYGONS: &str = "\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 1.5 0
f 1 2 3
f 1 2 3 4
f 1 2 3 5 4
";

#[test]
fn obj_polygons_are_fan_triangulated() {
    let m = load("poly.obj", POLYGONS);
    let p = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(1.0, 1.0, 0.0),
        v(0.0, 1.0, 0.0),
        v(0.5, 1.5, 0.0),
    ];
    let tri = |a: usize, b: usize, c: usize| [p[a - 1], p[b - 1], p[c - 1]];
    assert_eq!(
        corners(&m),
        vec![
            tri(1, 2, 3),
            // the quad 1 2 3 4
            tri(1, 2, 3),
            tri(1, 3, 4),
            // the pentagon 1 2 3 5 4
            tri(1, 2, 3),
            tri(1, 3, 5),
            tri(1, 5, 4),
        ]
    );
    assert_eq!(m.degenerate_count(), 0);
}

/// The L of the tests below: the square [0, 2]², less the corner [1, 2]², from (2, 0)
/// counter-clockwise. Its fan from the first corner holds a triangle outside the L.
const L_SHAPE: [[f32; 2]; 6] = [[2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.], [0., 0.]];

/// Checks that `mesh`'s triangles cover the polygon `inside` describes and nothing else:
/// every triangle turns the polygon's way (+z) and has its centre inside, and their areas
/// add up to the polygon's `area`.
#[track_caller]
fn covers(mesh: &Mesh, area: f32, inside: impl Fn(Vec3) -> bool) {
    let mut sum = 0.0;
    for [a, b, c] in corners(mesh) {
        let normal = (b - a).cross(c - a);
        assert!(normal.z >= 0.0, "{a} {b} {c} is turned over");
        let centre = (a + b + c) / 3.0;
        assert!(
            normal == Vec3::ZERO || inside(centre),
            "{a} {b} {c} lies outside the polygon"
        );
        sum += normal.length() / 2.0;
    }
    assert!(
        (sum - area).abs() < 1e-5,
        "the triangles' area is {sum}, not {area}"
    );
}

/// Regression (issue 15): a concave polygon was fanned from its first corner, so the L
/// `f 1 2 3 4 5 6` became a triangle across its missing corner (and one overlapping it).
/// Polygons are cut by ear clipping now, in OBJ and in PLY alike.
#[test]
fn an_l_shaped_hexagon_was_fan_triangulated_wrongly() {
    let vertices: Vec<String> = L_SHAPE.iter().map(|[x, y]| format!("{x} {y} 0")).collect();
    let obj: String = vertices
        .iter()
        .map(|v| format!("v {v}\n"))
        .collect::<String>()
        + "f 1 2 3 4 5 6\n";
    let ply = ascii_ply(
        "property float x\nproperty float y\nproperty float z\n",
        "property list uchar int vertex_indices\n",
        &vertices.iter().map(String::as_str).collect::<Vec<_>>(),
        &["6 0 1 2 3 4 5"],
    );
    let in_l =
        |p: Vec3| p.x > 0.0 && p.y > 0.0 && ((p.x < 2.0 && p.y < 1.0) || (p.x < 1.0 && p.y < 2.0));
    for mesh in [load("l.obj", &obj), load("l.ply", &ply)] {
        assert_eq!(mesh.triangle_count(), 4);
        covers(&mesh, 3.0, in_l);
    }
}

/// A convex polygon with corners on its straight edges is still its fan from the first
/// corner (a zero-area triangle where the fan runs along an edge), as before ear clipping.
#[test]
fn convex_polygons_with_straight_edges_keep_their_fan() {
    let text = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 2 2 0\nv 0 2 0\nv 0 1 0\nf 1 2 3 4 5 6\n";
    let m = load("straight.obj", text);
    let p = |i: usize| {
        let [x, y] = [[0., 0.], [2., 0.], [2., 1.], [2., 2.], [0., 2.], [0., 1.]][i - 1];
        v(x, y, 0.0)
    };
    let fan: Vec<[Vec3; 3]> = (3..=6).map(|k| [p(1), p(k - 1), p(k)]).collect();
    assert_eq!(corners(&m), fan);
    assert_eq!(m.degenerate_count(), 1);
}

/// A polygon that crosses itself (ear clipping finds no ear in this pentagon) is fanned
/// from its first corner, and the file's warnings count it; simple ones are not counted.
#[test]
fn polygons_that_are_not_simple_are_fanned_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let text = "v 2 0 0\nv 1 2 0\nv 1 3 0\nv 2 2 0\nv 0 1 0\nf 1 2 3 4 5\nf 1 2 3 4\n";
    let obj = write(dir.path(), "crossed.obj", text);
    let ply = write(
        dir.path(),
        "crossed.ply",
        ascii_ply(
            "property float x\nproperty float y\nproperty float z\n",
            "property list uchar int vertex_indices\n",
            &["2 0 0", "1 2 0", "1 3 0", "2 2 0", "0 1 0"],
            &["5 0 1 2 3 4", "5 0 1 2 3 4", "3 0 1 2"],
        ),
    );
    for (path, count) in [(&obj, "1 polygon of"), (&ply, "2 polygons of")] {
        let file = load_mesh_with_materials(path).unwrap();
        let verb = if count.starts_with('1') { "is" } else { "are" };
        let want = format!(
            "{count} {} {verb} not simple: fan-triangulated",
            path.display()
        );
        assert_eq!(file.warnings, [want]);
        let first = file.mesh.triangles[..3].to_vec();
        let fan = [[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        assert_eq!(
            first
                .iter()
                .map(|t| t.map(|i| file.mesh.positions[i as usize]))
                .collect::<Vec<_>>(),
            fan.map(|t: [usize; 3]| t.map(|i| file.mesh.positions[i])),
        );
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

    /// Ear clipping covers a simple polygon exactly: star-shaped ones around the origin on
    /// a grid (so that corners on straight edges are exactly straight), in an axis plane,
    /// either way round and starting anywhere. `n - 2` triangles, none turned over, each
    /// with its centre inside, their areas adding up to the polygon's.
    #[test]
    fn ear_clipping_covers_star_shaped_polygons(
        points in proptest::collection::vec((-20i32..=20, -20i32..=20), 3..24),
        midpoints in proptest::collection::vec(proptest::bool::weighted(0.3), 24),
        start in 0usize..48,
        reversed: bool,
        plane in 0usize..3,
    ) {
        let polygon = star_polygon(&points, &midpoints);
        proptest::prop_assume!(polygon.len() >= 3);
        let mut polygon: Vec<[f64; 2]> = polygon;
        let len = polygon.len();
        polygon.rotate_left(start % len);
        if reversed {
            polygon.reverse();
        }
        let positions: Vec<Vec3> = polygon
            .iter()
            .map(|&[x, y]| {
                let mut p = [0.0; 3];
                p[plane] = x as f32;
                p[(plane + 1) % 3] = y as f32;
                p[(plane + 2) % 3] = 7.0;
                Vec3::from(p)
            })
            .collect();
        let corners: Vec<u32> = (0..positions.len() as u32).collect();
        let mut triangles = Vec::new();
        let how = triangulate_polygon(&positions, &corners, &mut triangles);
        proptest::prop_assert_eq!(how, Triangulation::Ears);
        proptest::prop_assert_eq!(triangles.len(), polygon.len() - 2);
        let signed = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
            ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2.0
        };
        let area: f64 = (1..polygon.len() - 1)
            .map(|k| signed(polygon[0], polygon[k], polygon[k + 1]))
            .sum();
        let mut sum = 0.0;
        for t in &triangles {
            let [a, b, c] = t.map(|i| polygon[i as usize]);
            let s = signed(a, b, c);
            proptest::prop_assert!(s * area >= 0.0, "{:?} is turned over", t);
            let centre = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
            proptest::prop_assert!(
                s == 0.0 || winding(&polygon, centre) != 0,
                "{:?} lies outside {:?}", t, polygon
            );
            sum += s.abs();
        }
        proptest::prop_assert!((sum - area.abs()).abs() < 1e-9, "{} != {}", sum, area);
    }

    /// A convex polygon's triangles are exactly its fan from the first corner, as before
    /// ear clipping: points on a circle, any start, either way round.
    #[test]
    fn convex_polygons_are_their_fan(
        angles in proptest::collection::btree_set(0u32..3600, 3..20),
        reversed: bool,
    ) {
        let mut positions: Vec<Vec3> = angles
            .iter()
            .map(|&a| {
                let a = (a as f32 / 10.0).to_radians();
                Vec3::new(a.cos(), 0.5, a.sin())
            })
            .collect();
        if reversed {
            positions.reverse();
        }
        let n = positions.len() as u32;
        let corners: Vec<u32> = (0..n).collect();
        let mut triangles = Vec::new();
        triangulate_polygon(&positions, &corners, &mut triangles);
        let fan: Vec<[u32; 3]> = (2..n).map(|k| [0, k - 1, k]).collect();
        proptest::prop_assert_eq!(triangles, fan);
    }
}

/// The grid points sorted by angle around the origin (one per angle), doubled, with the
/// midpoint of each edge where `midpoints` says: a polygon star-shaped around the origin,
/// or none (fewer than 3 corners, or an angle gap of half a turn or more).
fn star_polygon(points: &[(i32, i32)], midpoints: &[bool]) -> Vec<[f64; 2]> {
    let mut by_angle: Vec<(f64, [f64; 2])> = Vec::new();
    for &(x, y) in points {
        if (x, y) == (0, 0) {
            continue;
        }
        let angle = (y as f64).atan2(x as f64);
        if !by_angle.iter().any(|&(a, _)| a == angle) {
            by_angle.push((angle, [2.0 * x as f64, 2.0 * y as f64]));
        }
    }
    by_angle.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = by_angle.len();
    if n < 3 {
        return Vec::new();
    }
    let gap = |i: usize| {
        let next = by_angle[(i + 1) % n].0
            + if i + 1 == n {
                std::f64::consts::TAU
            } else {
                0.0
            };
        next - by_angle[i].0
    };
    if (0..n).any(|i| gap(i) >= std::f64::consts::PI - 1e-9) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b) = (by_angle[i].1, by_angle[(i + 1) % n].1);
        out.push(a);
        if midpoints[i % midpoints.len()] {
            // doubled coordinates: the midpoint is on the grid, exactly on the edge
            out.push([(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]);
        }
    }
    out
}

/// The winding number of `polygon` around `q`.
fn winding(polygon: &[[f64; 2]], q: [f64; 2]) -> i32 {
    let mut w = 0;
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let side = (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
        if a[1] <= q[1] && b[1] > q[1] && side > 0.0 {
            w += 1;
        } else if a[1] > q[1] && b[1] <= q[1] && side < 0.0 {
            w -= 1;
        }
    }
    w
}

#[test]
fn obj_groups_and_materials_merge_in_file_order() {
    let text = "\
mtllib no-such-file.mtl
o first
v 0 0 0
v 1 0 0
v 0 1 0
usemtl red
f 1 2 3
g second
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
usemtl blue
f 4 5 6 7
usemtl red
f 3 2 1
o third
v 0 0 2
v 2 0 2
v 0 2 2
f 8 9 10
g
f 10 4 1
usemtl green
f 9 5 2
";
    let m = load("groups.obj", text);
    let p = |i: usize| {
        [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(1.0, 1.0, 1.0),
            v(0.0, 1.0, 1.0),
            v(0.0, 0.0, 2.0),
            v(2.0, 0.0, 2.0),
            v(0.0, 2.0, 2.0),
        ][i - 1]
    };
    let tri = |a, b, c| [p(a), p(b), p(c)];
    let expected = [
        tri(1, 2, 3),
        tri(4, 5, 6),
        tri(4, 6, 7),
        tri(3, 2, 1),
        tri(8, 9, 10),
        tri(10, 4, 1),
        tri(9, 5, 2),
    ];
    assert_eq!(m.triangle_count(), expected.len());
    for (i, want) in expected.iter().enumerate() {
        assert_eq!(&m.corners(i), want, "triangle {i}");
    }
}

#[test]
fn obj_negative_indices_count_back_from_the_last_vertex() {
    let text = "\
v 0 0 0
v 1 0 0
v 0 1 0
f -3 -2 -1
v 5 5 5
f -4 -2 -1
f 1 -3 -1
";
    let m = load("rel.obj", text);
    let [a, b, c, d] = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(0.0, 1.0, 0.0),
        v(5.0, 5.0, 5.0),
    ];
    assert_eq!(corners(&m), vec![[a, b, c], [a, c, d], [a, b, d]]);
}

#[test]
fn obj_texture_and_normal_references_are_accepted() {
    let text = "\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vn 0 0 1
f 1/1/1 2/2/1 3/3/1
f 1//1 3//1 4//1
f 2/2 3/3 4/3
f -4/-3/-1 -3/-2/-1 -1/-1/-1
f 1/1/1 2/1/1 3/1/1 4/1/1
";
    let m = load("vtvn.obj", text);
    let [a, b, c, d] = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(1.0, 1.0, 0.0),
        v(0.0, 1.0, 0.0),
    ];
    assert_eq!(
        corners(&m),
        vec![
            [a, b, c],
            [a, c, d],
            [b, c, d],
            [a, b, d],
            [a, b, c],
            [a, c, d]
        ]
    );
}

#[test]
fn obj_weights_colours_and_material_lines() {
    // `w` divides; colours on some vertices only; materials that cannot be found, a
    // `usemtl` without a name and one written with a tab; malformed `vt`/`vn` lines that
    // cltrace never reads.
    let text = "\
mtllib nowhere.mtl
v 0 0 0 1 0 0
v 2 0 0 2
v 0 1 0
vt 0.5
vn 1 2
usemtl
usemtl\tred
f 1/1/1 2/1/1 3/1/1
";
    let m = load("extras.obj", text);
    assert_eq!(
        corners(&m),
        vec![[v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]]
    );
}

#[test]
fn obj_comments_blank_lines_and_odd_whitespace() {
    let text = "# a comment\n\n   \n#v 9 9 9\nv 0 0 0\n\tv\t1  0 0\n\n# another\nv 0 1 0   \n\
                vn 0 0 1\ns off\nf 1 2 3\n\n";
    let m = load("comments.obj", text);
    assert_eq!(m.triangle_count(), 1);
    assert_eq!(
        m.corners(0),
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    );
}

#[test]
fn obj_crlf_line_endings_give_the_same_mesh() {
    let lf = load("lf.obj", POLYGONS);
    let crlf = load("crlf.obj", POLYGONS.replace('\n', "\r\n"));
    assert_eq!(corners(&lf), corners(&crlf));
    assert_eq!(crlf.triangle_count(), 6);
}

#[test]
fn obj_utf8_byte_order_mark_is_skipped() {
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend_from_slice(POLYGONS.as_bytes());
    let m = load("bom.obj", &bytes);
    assert_eq!(corners(&m), corners(&load("poly.obj", POLYGONS)));
    // and line numbers still count from the first line
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend_from_slice(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    refused_at("bom-range.obj", &bytes, 4);
}

#[test]
fn obj_gzip_gives_the_same_mesh() {
    let plain = load("poly.obj", POLYGONS);
    let gz = load("poly.obj.gz", gzip(POLYGONS.as_bytes()));
    let upper = load("POLY.OBJ.GZ", gzip(POLYGONS.as_bytes()));
    assert_eq!(corners(&plain), corners(&gz));
    assert_eq!(corners(&plain), corners(&upper));
}

#[test]
fn zero_area_triangles_are_kept_and_counted() {
    let text = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 2 0 0
f 1 2 3
f 1 1 2
f 1 2 4
f 3 3 3
f 2 3 1
";
    let m = load("flat.obj", text);
    assert_eq!(m.triangle_count(), 5);
    assert_eq!(m.degenerate_count(), 3);
    // file order is kept around them
    assert_eq!(
        m.corners(4),
        [v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, 0.0)]
    );

    let ply = ascii_ply(
        "property float x\nproperty float y\nproperty float z\n",
        "property list uchar int vertex_indices\n",
        &["0 0 0", "1 0 0", "2 0 0"],
        &["3 0 1 2", "3 0 1 1"],
    );
    let m = load("flat.ply", ply);
    assert_eq!(m.triangle_count(), 2);
    assert_eq!(m.degenerate_count(), 2);
}

// ---------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------

/// The mesh every PLY test describes: five vertices, a triangle, a quad and a pentagon.
const PLY_POINTS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.5],
    [0.0, 1.0, -0.25],
    [0.5, 1.5, 2.0],
];
const PLY_FACES: [&[u32]; 3] = [&[0, 1, 2], &[0, 1, 2, 3], &[4, 3, 2, 1, 0]];

fn expected_ply_corners() -> Vec<[Vec3; 3]> {
    let p = |i: u32| Vec3::from(PLY_POINTS[i as usize]);
    let mut out = Vec::new();
    for f in PLY_FACES {
        for k in 2..f.len() {
            out.push([p(f[0]), p(f[k - 1]), p(f[k])]);
        }
    }
    assert_eq!(out.len(), 1 + 2 + 3);
    out
}

fn ascii_ply(vertex_props: &str, face_props: &str, vertices: &[&str], faces: &[&str]) -> String {
    format!(
        "ply\nformat ascii 1.0\ncomment made by a test\nelement vertex {}\n{vertex_props}\
         element face {}\n{face_props}end_header\n{}\n{}\n",
        vertices.len(),
        faces.len(),
        vertices.join("\n"),
        faces.join("\n")
    )
}

#[test]
fn ply_ascii_with_extra_properties_and_elements() {
    let mut text = String::from(
        "ply\nformat ascii 1.0\ncomment test\nobj_info nothing\nelement vertex 5\n\
         property float x\nproperty float nx\nproperty float y\nproperty float z\n\
         property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nelement edge 2\nproperty int vertex1\nproperty int vertex2\n\
         element face 3\nproperty uchar flags\nproperty list uchar int vertex_indices\n\
         property list uchar float texcoord\nelement material 1\nproperty float shininess\n\
         end_header\n",
    );
    for p in PLY_POINTS {
        text += &format!("{} 9 {} {} 0 0 1 255 128 0\n", p[0], p[1], p[2]);
    }
    text += "0 1\n1 2\n";
    for f in PLY_FACES {
        let idx: Vec<String> = f.iter().map(|i| i.to_string()).collect();
        text += &format!("7 {} {} 2 0.5 0.5\n", f.len(), idx.join(" "));
    }
    text += "0.25\n";
    let m = load("ascii.ply", &text);
    assert_eq!(corners(&m), expected_ply_corners());
    // gzip gives the same
    let gz = load("ascii.ply.gz", gzip(text.as_bytes()));
    assert_eq!(corners(&gz), expected_ply_corners());
}

/// A binary PLY written byte by byte: `double` coordinates or `float`, the face list
/// count as `count_type` (uchar or int), indices as `int` or `uint`, an `edge` element
/// between the vertices and the faces and extra vertex properties.
fn binary_ply(big_endian: bool, double: bool, count_type: &str, index_type: &str) -> Vec<u8> {
    let coord = if double { "double" } else { "float" };
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply\nformat {format} 1.0\nelement vertex 5\nproperty {coord} x\nproperty {coord} y\n\
         property {coord} z\nproperty float nx\nproperty uchar red\nelement edge 1\n\
         property int vertex1\nproperty int vertex2\nelement face 3\n\
         property list {count_type} {index_type} vertex_indices\nproperty short tag\nend_header\n"
    );
    let mut out = header.into_bytes();
    macro_rules! put {
        ($v:expr) => {
            if big_endian {
                out.extend_from_slice(&$v.to_be_bytes())
            } else {
                out.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    for p in PLY_POINTS {
        for c in p {
            if double {
                put!(c as f64);
            } else {
                put!(c);
            }
        }
        put!(0.5f32); // nx
        out.push(200); // red
    }
    put!(0i32); // edge
    put!(4i32);
    for f in PLY_FACES {
        match count_type {
            "uchar" => out.push(f.len() as u8),
            "int" => put!(f.len() as i32),
            "ushort" => put!(f.len() as u16),
            other => panic!("{other}"),
        }
        for &i in f {
            match index_type {
                "int" => put!(i as i32),
                "uint" => put!(i),
                "ushort" => put!(i as u16),
                other => panic!("{other}"),
            }
        }
        put!(-3i16); // tag
    }
    out
}

#[test]
fn ply_binary_little_endian() {
    for (double, count, index) in [
        (false, "uchar", "int"),
        (true, "int", "uint"),
        (true, "uchar", "ushort"),
        (false, "ushort", "uint"),
    ] {
        let m = load("le.ply", binary_ply(false, double, count, index));
        assert_eq!(
            corners(&m),
            expected_ply_corners(),
            "double {double}, list {count} {index}"
        );
    }
}

#[test]
fn ply_binary_big_endian() {
    for (double, count, index) in [
        (false, "uchar", "int"),
        (true, "int", "int"),
        (false, "int", "uint"),
    ] {
        let m = load("be.ply", binary_ply(true, double, count, index));
        assert_eq!(
            corners(&m),
            expected_ply_corners(),
            "double {double}, list {count} {index}"
        );
    }
}

#[test]
fn ply_binary_gzip() {
    let bytes = binary_ply(false, true, "uchar", "int");
    let m = load("le.ply.gz", gzip(&bytes));
    assert_eq!(corners(&m), expected_ply_corners());
}

#[test]
fn ply_ascii_with_crlf_line_endings() {
    let text = ascii_ply(
        "property float x\nproperty float y\nproperty float z\n",
        "property list uchar int vertex_indices\n",
        &["0 0 0", "1 0 0", "1 1 0", "0 1 0"],
        &["4 0 1 2 3"],
    );
    let m = load("crlf.ply", text.replace('\n', "\r\n"));
    assert_eq!(
        corners(&m),
        vec![
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0)],
            [v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0)],
        ]
    );
}

#[test]
fn ply_vertex_index_spelling_is_accepted() {
    let ply = ascii_ply(
        "property double x\nproperty double y\nproperty double z\n",
        "property list int uint vertex_index\n",
        &["0 0 0", "1 0 0", "0 1 0"],
        &["3 0 1 2"],
    );
    let m = load("vi.ply", ply);
    assert_eq!(m.triangle_count(), 1);
    assert_eq!(
        m.corners(0),
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    );
}

// ---------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn missing_files_and_directories_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let msg = refused(&dir.path().join("nothing-here.obj"));
    assert!(msg.contains("no such file"), "{msg}");
    let sub = dir.path().join("folder.obj");
    std::fs::create_dir(&sub).unwrap();
    let msg = refused(&sub);
    assert!(msg.contains("directory"), "{msg}");
    let sub = dir.path().join("folder.ply.gz");
    std::fs::create_dir(&sub).unwrap();
    refused(&sub);
}

#[test]
fn unknown_extensions_are_refused() {
    let msg = refused_bytes("model.stl", "solid x\nendsolid x\n");
    assert!(msg.contains(".obj"), "{msg}");
    refused_bytes("model.gz", gzip(TRIANGLE.as_bytes()));
    refused_bytes("model", TRIANGLE);
    refused_bytes("model.obj.zip", TRIANGLE);
}

#[test]
fn empty_files_and_files_without_triangles_are_refused() {
    for name in ["empty.obj", "empty.ply", "empty.obj.gz", "empty.ply.gz"] {
        refused_bytes(name, "");
    }
    refused_bytes("emptygz.obj.gz", gzip(b""));
    let msg = refused_bytes("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    assert!(msg.contains("no triangles"), "{msg}");
    // lines and points are not triangles
    refused_bytes(
        "lines.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 3\nf 1 2\n",
    );
    let msg = refused_bytes(
        "points.ply",
        ascii_ply(
            "property float x\nproperty float y\nproperty float z\n",
            "property list uchar int vertex_indices\n",
            &["0 0 0", "1 0 0", "0 1 0"],
            &[],
        ),
    );
    assert!(msg.contains("no triangles"), "{msg}");
}

#[test]
fn obj_bad_indices_name_the_line() {
    let m = refused_at(
        "range.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
        5,
    );
    assert!(m.contains('4'), "{m}");
    let m = refused_at("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4);
    assert!(m.contains('0'), "{m}");
    refused_at("behind.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf -4 -2 -1\n", 5);
    refused_at("word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", 4);
    refused_at(
        "huge.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n",
        4,
    );
    // in a later group, with a CRLF file
    refused_at(
        "crlf.obj",
        "o a\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\ng b\r\nf 1/1/1 2 9\r\n",
        7,
    );
}

#[test]
fn obj_bad_texture_and_normal_references_do_not_panic() {
    // cltrace reads only positions: the references must not crash the loader, whether it
    // accepts them or refuses them cleanly.
    let dir = tempfile::tempdir().unwrap();
    for (i, text) in [
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/0 2/0 3/0\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//0 2//0 3//0\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/-5/-5 2/-5/-5 3/-5/-5\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/7 2/7 3/7\n",
    ]
    .iter()
    .enumerate()
    {
        let path = write(dir.path(), &format!("ref{i}.obj"), text);
        match load_mesh(&path) {
            Ok(m) => assert_eq!(m.triangle_count(), 1),
            Err(_) => {
                refused(&path);
            }
        }
    }
}

#[test]
fn obj_bad_coordinates_name_the_line() {
    let m = refused_at("two.obj", "v 0 0 0\nv 1 two 3\nv 0 1 0\nf 1 2 3\n", 2);
    assert!(m.contains("vertex"), "{m}");
    refused_at("short.obj", "v 0 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n", 3);
    let m = refused_at("nan.obj", "v 0 0 0\n\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", 3);
    assert!(m.contains("NaN"), "{m}");
    let m = refused_at("inf.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", 2);
    assert!(m.contains("inf"), "{m}");
    refused_at("neginf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n", 3);
    let m = refused_at("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1e20 0\nf 1 2 3\n", 3);
    assert!(m.contains("1e12"), "{m}");
    // the w component divides, and can overflow too
    refused_at("w.obj", "v 0 0 0\nv 1 0 0\nv 0 1e11 0 1e-5\nf 1 2 3\n", 3);
    refused_bytes("w0.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0 0\nf 1 2 3\n");
    // the same vertex in a gzip file
    refused_at(
        "nan.obj.gz",
        gzip(b"v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n"),
        2,
    );
}

#[test]
fn bad_vertices_that_no_triangle_uses_are_harmless() {
    let m = load(
        "unused.obj",
        "v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 4\n",
    );
    assert_eq!(m.triangle_count(), 1);
    assert_eq!(
        m.corners(0),
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    );
}

#[test]
fn files_that_are_not_utf8_text_are_refused() {
    // invalid UTF-8 on line 2
    refused_at("latin1.obj", b"v 0 0 0\nv 1 \xe9 0\nv 0 1 0\nf 1 2 3\n", 2);
    // UTF-16 with a byte order mark
    let utf16: Vec<u8> = std::iter::once(0xFEFFu16)
        .chain(TRIANGLE.encode_utf16())
        .flat_map(|u| u.to_le_bytes())
        .collect();
    refused_bytes("utf16.obj", &utf16);
    // UTF-16 without one (every other byte is NUL)
    let utf16: Vec<u8> = TRIANGLE
        .encode_utf16()
        .flat_map(|u| u.to_le_bytes())
        .collect();
    refused_bytes("utf16-nobom.obj", &utf16);
    // binary garbage
    let garbage: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    refused_bytes("garbage.obj", &garbage);
    refused_bytes("garbage.ply", &garbage);
    refused_bytes("garbage.obj.gz", &garbage);
    let mut ply_garbage = b"ply\n".to_vec();
    ply_garbage.extend_from_slice(&garbage);
    refused_bytes("garbage2.ply", &ply_garbage);
}

#[test]
fn truncated_and_fake_gzip_files_are_refused() {
    let whole = gzip(POLYGONS.repeat(50).as_bytes());
    let msg = refused_bytes("cut.obj.gz", &whole[..whole.len() / 2]);
    assert!(msg.contains("gzip"), "{msg}");
    // a gzip stream without its trailer
    refused_bytes("trailer.obj.gz", &whole[..whole.len() - 4]);
    let msg = refused_bytes("plain.obj.gz", POLYGONS);
    assert!(msg.contains("gzip"), "{msg}");
    refused_bytes("plain.ply.gz", binary_ply(false, false, "uchar", "int"));
}

#[test]
fn ply_truncated_binary_body() {
    let whole = binary_ply(false, false, "uchar", "int");
    let header_len = whole
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    // cut inside the vertices, inside the edges, inside the faces, one byte short
    for cut in [
        header_len + 7,
        header_len + 5 * 17 + 3,
        whole.len() - 9,
        whole.len() - 1,
    ] {
        let msg = refused_bytes("cut.ply", &whole[..cut]);
        // the body is not text: no line number may be claimed for it
        assert!(msg.contains("cut.ply: "), "{msg}");
        assert!(!msg.contains("Line"), "{msg}");
    }
    let whole = binary_ply(true, true, "int", "int");
    refused_bytes("cut-be.ply", &whole[..whole.len() - 3]);
    // an ASCII body that ends early
    let text = ascii_ply(
        "property float x\nproperty float y\nproperty float z\n",
        "property list uchar int vertex_indices\n",
        &["0 0 0", "1 0 0", "0 1 0"],
        &["3 0 1 2"],
    );
    let cut = text.replace("3 0 1 2\n", "");
    refused_bytes("cut-ascii.ply", &cut);
}

#[test]
fn ply_bad_headers() {
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let good_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                       property float y\nproperty float z\nelement face 1\n\
                       property list uchar int vertex_indices\nend_header\n";
    // the control: this one loads
    assert_eq!(
        load("good.ply", format!("{good_header}{body}")).triangle_count(),
        1
    );

    let cases = [
        // not a PLY at all
        (
            "magic.ply",
            "plx\nformat ascii 1.0\nend_header\n".to_string(),
        ),
        // an unknown line in the header, at line 4
        (
            "keyword.ply",
            good_header.replace("property float x\n", "propertee float x\n"),
        ),
        // an unknown type
        (
            "type.ply",
            good_header.replace("property float y", "property quad y"),
        ),
        // no end_header
        ("open.ply", good_header.replace("end_header\n", "")),
        // no format line
        ("format.ply", good_header.replace("format ascii 1.0\n", "")),
        // an unknown format
        (
            "enc.ply",
            good_header.replace("format ascii 1.0", "format binary_middle_endian 1.0"),
        ),
        // a property before any element
        (
            "orphan.ply",
            good_header.replace("format ascii 1.0\n", "format ascii 1.0\nproperty float w\n"),
        ),
        // a vertex without z
        ("noz.ply", good_header.replace("property float z\n", "")),
        // a face element without vertex_indices
        (
            "noidx.ply",
            good_header.replace("vertex_indices", "vertex_colours"),
        ),
        // indices as a float list
        (
            "floatidx.ply",
            good_header.replace(
                "list uchar int vertex_indices",
                "list uchar float vertex_indices",
            ),
        ),
    ];
    for (name, header) in cases {
        refused_bytes(name, format!("{header}{body}"));
    }
    refused_at(
        "keyword2.ply",
        format!(
            "{}{body}",
            good_header.replace("property float x\n", "propertee float x\n")
        ),
        4,
    );
}

#[test]
fn ply_bad_bodies() {
    let header = |n_faces: usize, index: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face {n_faces}\nproperty list uchar {index} vertex_indices\n\
             end_header\n"
        )
    };
    let vertices = "0 0 0\n1 0 0\n0 1 0\n";
    let m = refused_bytes(
        "past.ply",
        format!("{}{vertices}3 0 1 2\n3 0 1 3\n", header(2, "int")),
    );
    assert!(m.contains('3'), "{m}");
    let m = refused_bytes(
        "negative.ply",
        format!("{}{vertices}3 0 -1 2\n", header(1, "int")),
    );
    assert!(m.contains("-1"), "{m}");
    refused_bytes(
        "quadpast.ply",
        format!("{}{vertices}4 0 1 2 7\n", header(1, "uint")),
    );
    // an unparsable coordinate, on line 11
    let m = refused_at(
        "two.ply",
        format!("{}0 0 0\n1 two 0\n0 1 0\n3 0 1 2\n", header(1, "int")),
        11,
    );
    assert!(m.contains("two"), "{m}");
    // a list shorter than its count
    refused_bytes(
        "shortlist.ply",
        format!("{}{vertices}4 0 1 2\n", header(1, "int")),
    );
    // NaN, infinite and huge coordinates
    refused_bytes(
        "nan.ply",
        format!("{}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", header(1, "int")),
    );
    refused_bytes(
        "inf.ply",
        format!("{}0 0 0\n1e39 0 0\n0 1 0\n3 0 1 2\n", header(1, "int")),
    );
    let m = refused_bytes(
        "far.ply",
        format!("{}0 0 0\n1e20 0 0\n0 1 0\n3 0 1 2\n", header(1, "int")),
    );
    assert!(m.contains("1e12"), "{m}");
    // a binary negative index
    let mut bytes = binary_ply(false, false, "uchar", "int");
    let n = bytes.len();
    // the last face's last index (before the 2-byte tag) becomes -1
    bytes[n - 6..n - 2].copy_from_slice(&(-1i32).to_le_bytes());
    let m = refused_bytes("negative-bin.ply", &bytes);
    assert!(m.contains("-1"), "{m}");
}

#[test]
fn ply_counts_far_beyond_the_data() {
    // Header counts and list lengths are not trusted for allocation: these fail at the end
    // of the data, quickly and without running out of memory.
    let text = "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n\
                property float y\nproperty float z\nelement face 1\n\
                property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n";
    refused_bytes("many.ply", text);
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                      property float y\nproperty float z\nelement face 1\n\
                      property list uint int vertex_indices\nend_header\n"
        .to_vec();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    bytes.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    for i in [0i32, 1, 2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    refused_bytes("longlist.ply", &bytes);
}

#[test]
fn ply_without_faces() {
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let m = refused_bytes("noface.ply", text);
    assert!(m.contains("face") || m.contains("triangles"), "{m}");
    let text = "ply\nformat ascii 1.0\nelement face 1\n\
                property list uchar int vertex_indices\nend_header\n3 0 1 2\n";
    refused_bytes("novertex.ply", text);
}

/// Materials from the MTL file beside the OBJ: `Kd` and `Ke` per triangle in file order,
/// the `Ka` above 1 convention for lights, grey for triangles without a (known) material.
#[test]
fn obj_materials_come_from_the_mtl_file() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "my colours.mtl",
        "newmtl red\nKd 1 0 0\n\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 4 3 2\n\nnewmtl old_lamp\nKa 20 20 20\nKd 1 1 1\n",
    );
    let obj = write(
        dir.path(),
        "lit.obj",
        "mtllib my colours.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl\tred\nf 1 2 3\n\
         usemtl lamp\nf 1 2 3 \nusemtl nowhere\nf 1 2 3\n usemtl old_lamp\nf 1 2 3\n",
    );
    let file = load_mesh_with_materials(&obj).unwrap();
    assert_eq!(file.warnings, Vec::<String>::new());
    assert_eq!(file.mesh.triangle_count(), 5);
    let m = &file.materials;
    let albedo = |i| m.of(i).albedo;
    let emission = |i| m.of(i).emission;
    assert_eq!(albedo(0), Material::default().albedo, "before any usemtl");
    assert_eq!((albedo(1), emission(1)), ([1.0, 0.0, 0.0], [0.0; 3]));
    assert_eq!((albedo(2), emission(2)), ([0.5; 3], [4.0, 3.0, 2.0]));
    assert_eq!(albedo(3), Material::default().albedo, "unknown material");
    assert_eq!((albedo(4), emission(4)), ([1.0; 3], [20.0; 3]));
    // Without materials asked for, the same file loads to the same triangles.
    assert_eq!(corners(&load_mesh(&obj).unwrap()), corners(&file.mesh));
}

/// The scattering model of each MTL material, as the table in docs/rendering.md maps it.
#[test]
fn mtl_illum_ks_ns_ni_tf_pr_and_pm_choose_the_scattering_model() {
    use cltrace::material::Bsdf;
    let library = "newmtl matte\nKd 0.5 0.5 0.5\nKs 0 0 0\nillum 2\n\
                   newmtl glossy\nKd 0.2 0.3 0.8\nKs 0.5 0.5 0.5\nNs 250\nillum 2\n\
                   newmtl chrome\nKd 0.9 0.9 0.9\nillum 3\n\
                   newmtl brushed\nKd 0.9 0.9 0.9\nNs 90\nillum 5\n\
                   newmtl glass\nNi 1.45\nTf 0.9 1 0.9\nillum 7\n\
                   newmtl exported_glass\nNi 1.000000\nillum 4\n\
                   newmtl window\nKd 0.4 0.6 0.6\nKs 0.5 0.5 0.5\nd 0.006\nillum 2\n\
                   newmtl sheet\nillum 9\n\
                   newmtl pbr\nKd 0.8 0.5 0.2\nPr 0.35\nPm 0.8\n\
                   newmtl faded\nTr 0.5\n";
    let list = cltrace::input::parse_material_library(library.as_bytes()).unwrap();
    let by_name = |i: usize| (Bsdf::from_code(list[i].bsdf), list[i]);
    let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
    let (b, m) = by_name(0);
    assert_eq!(b, Bsdf::Diffuse, "Ks 0 under illum 2 is matte");
    assert_eq!(m.roughness, 1.0);
    let (b, m) = by_name(1);
    assert_eq!(b, Bsdf::Plastic);
    assert_eq!(m.specular, [0.5; 3], "Ks tints the coating");
    assert!(close(m.roughness, 1.0 - 0.25f32.sqrt()), "{}", m.roughness);
    assert_eq!(
        (by_name(2).0, by_name(2).1.roughness),
        (Bsdf::Conductor, 0.0)
    );
    let (b, m) = by_name(3);
    assert_eq!(b, Bsdf::Conductor);
    assert!(close(m.roughness, 1.0 - 0.09f32.sqrt()));
    assert_eq!(
        m.eta, [0.0; 3],
        "a colour's Schlick Fresnel, as glTF metals"
    );
    let (b, m) = by_name(4);
    assert_eq!(
        (b, m.ior, m.specular, m.roughness),
        (Bsdf::Dielectric, 1.45, [0.9, 1.0, 0.9], 0.0)
    );
    assert_eq!(
        (by_name(5).0, by_name(5).1.ior),
        (Bsdf::Dielectric, 1.5),
        "Ni 1 is unset"
    );
    assert_eq!(by_name(6).0, Bsdf::ThinDielectric, "d below 1");
    assert_eq!(by_name(7).0, Bsdf::ThinDielectric);
    let (b, m) = by_name(8);
    assert_eq!((b, m.roughness, m.metallic), (Bsdf::Plastic, 0.35, 0.8));
    assert_eq!(by_name(9).0, Bsdf::ThinDielectric, "Tr above 0");
}

/// Regression: a folder without a mesh extension was refused as an "unknown mesh format";
/// it is named a directory, with or without one.
#[test]
fn a_folder_as_the_mesh_was_an_unknown_format() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["scans", "scans.obj", "scans.ply.gz"] {
        let folder = dir.path().join(name);
        std::fs::create_dir(&folder).unwrap();
        let e = load_mesh(&folder).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("is a directory"), "{e}");
    }
}

/// Regression: an MTL colour with fewer than three numbers (`Kd 0.5`, legal MTL: `g` and
/// `b` default to `r`) panicked inside tobj; now it is that grey, and an empty `Kd` line
/// is ignored.
#[test]
fn mtl_colours_with_fewer_than_three_numbers_panicked() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "short.mtl",
        "newmtl grey\nKd 0.5\nKe 2 3\n\nnewmtl bare\nKd\nKs\r\nKa 0.1\r\n",
    );
    let obj = write(
        dir.path(),
        "short.obj",
        "mtllib short.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\nusemtl bare\nf 1 2 3\n",
    );
    let file = load_mesh_with_materials(&obj).unwrap();
    assert_eq!(file.warnings, Vec::<String>::new());
    let m = &file.materials;
    assert_eq!(
        (m.of(0).albedo, m.of(0).emission),
        ([0.5; 3], [2.0, 3.0, 2.0])
    );
    assert_eq!(
        m.of(1).albedo,
        Material::default().albedo,
        "an empty Kd is no colour"
    );
}

/// A missing or broken MTL file leaves the mesh grey with a warning naming the file.
#[test]
fn obj_without_its_mtl_file_is_grey_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let text = "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    let obj = write(dir.path(), "grey.obj", text);
    let file = load_mesh_with_materials(&obj).unwrap();
    let [warning] = &file.warnings[..] else {
        panic!("not one warning: {:?}", file.warnings)
    };
    let tried = std::path::absolute(dir.path().join("gone.mtl")).unwrap();
    assert!(
        warning.contains("grey.obj") && warning.contains(&tried.display().to_string()),
        "{warning}"
    );
    assert_eq!(file.materials.of(0), &Material::default());

    write(dir.path(), "gone.mtl", "newmtl red\nKd one two three\n");
    let file = load_mesh_with_materials(&obj).unwrap();
    assert_eq!(file.warnings.len(), 1, "a broken MTL file warns");
    assert_eq!(file.materials.of(0), &Material::default());
}

/// The Cornell box lights itself: its light is an emitter, its walls are not.
#[test]
fn cornell_box_has_its_light() {
    let Some(path) = crate::common::shared_scene("cornell_box.obj") else {
        return;
    };
    let file = load_mesh_with_materials(&path).unwrap();
    assert_eq!(file.warnings, Vec::<String>::new());
    let emitting = (0..file.mesh.triangle_count())
        .filter(|&i| file.materials.of(i).emits())
        .count();
    assert_eq!(emitting, 2, "the light is one quad");
    let red = (0..file.mesh.triangle_count())
        .filter(|&i| file.materials.of(i).albedo == [1.0, 0.0, 0.0])
        .count();
    assert!(red > 0, "the red wall");
}
