//! Procedural meshes: the built-in default scene (a sphereflake on a landscape) and the
//! simple shapes the tests and benchmarks use. Every generator is deterministic, so a
//! generator name and its parameters identify a mesh exactly.

use std::collections::HashMap;
use std::f32::consts::TAU;

use glam::{Mat3, Vec3};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::material::{Material, Materials};
use crate::mesh::Mesh;

/// A built-in mesh and its parameters, as written in a scene file's `[generator]` table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Generator {
    /// Haines' sphereflake (each sphere carries nine spheres a third its size) standing on
    /// a noise-displaced landscape: the default scene.
    Sphereflake {
        /// Recursion levels below the main sphere (0 to 5).
        #[serde(default = "default_levels")]
        levels: u32,
        /// Icosphere subdivisions of the smallest spheres (0 to 6): 20 * 4^n triangles
        /// each; every generation up gets one more, so large spheres stay round.
        #[serde(default = "default_subdivisions")]
        subdivisions: u32,
        /// Landscape cells along each side (0 for no ground, at most 4096).
        #[serde(default = "default_ground")]
        ground: u32,
    },
    /// A unit icosphere.
    Sphere {
        /// Subdivisions of the icosahedron (0 to 10): 20 * 4^n triangles; default 2.
        #[serde(default = "default_subdivisions")]
        subdivisions: u32,
    },
    /// The cube [-1, 1]^3, 12 triangles.
    Cube {},
    /// `count` concentric cubes, each turned a little against the last.
    NestedBoxes {
        /// Number of cubes (1 to 1000000), the k-th of half-size k / count; default 8.
        #[serde(default = "default_boxes")]
        count: u32,
    },
    /// `triangles` random triangles of random size in the unit cube.
    Soup {
        /// Number of triangles (1 to 2^31, as the host's memory allows); required.
        triangles: u32,
        /// Seed of the random placement; each seed gives its own soup, always the same one
        /// (default 0).
        #[serde(default)]
        seed: u64,
    },
    /// A noise-displaced height field of `resolution` x `resolution` cells.
    Landscape {
        /// Cells along each side of [-1, 1]^2 in x and z (1 to 32767: two triangles a cell,
        /// as many as the host's memory allows); required.
        resolution: u32,
        /// Seed of the noise: each seed its own mesh, always the same one (default 0).
        #[serde(default)]
        seed: u64,
    },
    /// The landscape tilted up by 60 degrees about x, so that a camera on the +z axis (the
    /// auto framing) looks down onto it: the scaling benchmark's mesh.
    Hillside {
        /// Cells along each side, as for [`Generator::Landscape`] (1 to 32767); required.
        resolution: u32,
        /// Seed of the noise: each seed its own mesh, always the same one (default 0).
        #[serde(default)]
        seed: u64,
    },
}

fn default_levels() -> u32 {
    3
}
fn default_subdivisions() -> u32 {
    2
}
fn default_ground() -> u32 {
    160
}
fn default_boxes() -> u32 {
    8
}

/// The most triangles a generator makes: triangle indices are 32-bit, and the top bit is
/// kept clear. Below that, the host's memory decides ([`HOST_BYTES_PER_TRIANGLE`]), and the
/// device's is checked before the upload.
const MAX_TRIANGLES: u64 = 1 << 31;

/// Host memory a generated triangle takes at the peak of a render (the mesh, its smooth
/// normals, the build's boxes and tree, the layout), with some room: on the H200 host a
/// hillside of 100 million triangles peaked at 28.0 GiB resident (300 bytes a triangle),
/// one of 300 million at 85.4 GiB (306); with `--crease-angle 0`, 17.0 GiB for 100 million.
const HOST_BYTES_PER_TRIANGLE: u64 = 320;

/// The most cells along a side of the landscape and the hillside: `2 r^2` triangles stay
/// under [`MAX_TRIANGLES`].
pub(crate) const MAX_RESOLUTION: u32 = 32767;

impl Generator {
    /// The default scene's mesh.
    pub(crate) fn default_scene() -> Self {
        Generator::Sphereflake {
            levels: default_levels(),
            subdivisions: default_subdivisions(),
            ground: default_ground(),
        }
    }

    /// A name with every parameter, e.g. `sphereflake(levels=3,subdivisions=2,ground=160)`,
    /// so that benchmark rows say exactly which mesh they measured.
    pub fn name(&self) -> String {
        match self {
            Generator::Sphereflake {
                levels,
                subdivisions,
                ground,
            } => {
                format!("sphereflake(levels={levels},subdivisions={subdivisions},ground={ground})")
            }
            Generator::Sphere { subdivisions } => format!("sphere(subdivisions={subdivisions})"),
            Generator::Cube {} => "cube".to_string(),
            Generator::NestedBoxes { count } => format!("nested-boxes(count={count})"),
            Generator::Soup { triangles, seed } => {
                format!("soup(triangles={triangles},seed={seed})")
            }
            Generator::Landscape { resolution, seed } => {
                format!("landscape(resolution={resolution},seed={seed})")
            }
            Generator::Hillside { resolution, seed } => {
                format!("hillside(resolution={resolution},seed={seed})")
            }
        }
    }

    /// The number of triangles [`Generator::generate`] will make.
    pub fn triangle_count(&self) -> u64 {
        let sphere = |s: u32| 20u64 * 4u64.saturating_pow(s);
        match *self {
            Generator::Sphereflake {
                levels,
                subdivisions,
                ground,
            } => {
                let spheres: u64 = (0..=levels)
                    .map(|l| 9u64.saturating_pow(l) * sphere(subdivisions + levels - l))
                    .sum();
                spheres + 2 * ground as u64 * ground as u64
            }
            Generator::Sphere { subdivisions } => sphere(subdivisions),
            Generator::Cube {} => 12,
            Generator::NestedBoxes { count } => 12 * count as u64,
            Generator::Soup { triangles, .. } => triangles as u64,
            Generator::Landscape { resolution, .. } | Generator::Hillside { resolution, .. } => {
                2 * resolution as u64 * resolution as u64
            }
        }
    }

    /// Builds the mesh, or says which parameter is out of range.
    pub fn generate(&self) -> Result<Mesh> {
        self.check()?;
        Ok(match *self {
            Generator::Sphereflake {
                levels,
                subdivisions,
                ground,
            } => sphereflake(levels, subdivisions, ground),
            Generator::Sphere { subdivisions } => icosphere(subdivisions),
            Generator::Cube {} => cube(Mat3::IDENTITY, 1.0),
            Generator::NestedBoxes { count } => nested_boxes(count),
            Generator::Soup { triangles, seed } => soup(triangles, seed),
            Generator::Landscape { resolution, seed } => {
                landscape(resolution, 1.0, 0.15, seed, Vec3::ZERO)
            }
            Generator::Hillside { resolution, seed } => {
                let mut mesh = landscape(resolution, 1.0, 0.15, seed, Vec3::ZERO);
                let tilt = Mat3::from_rotation_x(60f32.to_radians());
                use rayon::prelude::*;
                mesh.positions.par_iter_mut().for_each(|p| *p = tilt * *p);
                mesh
            }
        })
    }

    /// The materials of the generated mesh: the sphereflake's spheres a light grey over a
    /// darker, warmer ground; every other generator grey.
    pub(crate) fn materials(&self, mesh: &Mesh) -> Materials {
        match *self {
            Generator::Sphereflake { ground, .. } if ground > 0 => {
                let spheres = mesh.triangle_count() - 2 * ground as usize * ground as usize;
                Materials {
                    list: vec![
                        Material::diffuse([0.8, 0.8, 0.8]),
                        Material::diffuse([0.45, 0.4, 0.33]),
                    ],
                    per_triangle: (0..mesh.triangle_count())
                        .map(|i| (i >= spheres) as u32)
                        .collect(),
                    textures: Vec::new(),
                }
            }
            _ => Materials::default(),
        }
    }

    /// Checks the parameters: every one in range, and no more triangles than the host's
    /// memory can take.
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str, range: &str| {
            Err(Error::Invalid(format!(
                "generator {}: {what} must be {range}",
                self.name()
            )))
        };
        match *self {
            Generator::Sphereflake { levels, .. } if levels > 5 => {
                return bad("levels", "at most 5");
            }
            Generator::Sphereflake {
                levels,
                subdivisions,
                ..
            } if subdivisions + levels > 9 => {
                return bad("subdivisions + levels", "at most 9");
            }
            Generator::Sphereflake { ground, .. } if ground > 4096 => {
                return bad("ground", "at most 4096");
            }
            Generator::Sphere { subdivisions } if subdivisions > 10 => {
                return bad("subdivisions", "at most 10");
            }
            Generator::NestedBoxes { count } if count == 0 || count > 1_000_000 => {
                return bad("count", "between 1 and 1000000");
            }
            Generator::Soup { triangles: 0, .. } => {
                return bad("triangles", "at least 1");
            }
            Generator::Landscape { resolution, .. } | Generator::Hillside { resolution, .. }
                if resolution == 0 || resolution > MAX_RESOLUTION =>
            {
                return bad("resolution", &format!("between 1 and {MAX_RESOLUTION}"));
            }
            _ => {}
        }
        if self.triangle_count() > MAX_TRIANGLES {
            return Err(Error::Invalid(format!(
                "generator {} would make {} triangles; the limit is {MAX_TRIANGLES}",
                self.name(),
                self.triangle_count()
            )));
        }
        let needs = self.triangle_count() * HOST_BYTES_PER_TRIANGLE;
        if let Some(available) = available_memory()
            && needs > available
        {
            let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
            return Err(Error::Invalid(format!(
                "generator {} would make {} triangles, which take about {:.0} GiB of memory \
                 to render; this machine has {:.1} GiB available",
                self.name(),
                self.triangle_count(),
                gib(needs),
                gib(available)
            )));
        }
        Ok(())
    }
}

/// The memory the system says it can give without swapping (Linux's `MemAvailable`), in
/// bytes; `None` where it does not say.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The sphereflake: a unit sphere at the origin, `levels` generations of children, and a
/// landscape below it.
fn sphereflake(levels: u32, subdivisions: u32, ground: u32) -> Mesh {
    // One unit sphere per generation: generation g (0 = the main sphere) gets
    // `subdivisions + levels - g` subdivisions.
    let units: Vec<Mesh> = (0..=levels)
        .map(|g| icosphere(subdivisions + levels - g))
        .collect();
    let mut mesh = Mesh::default();
    let mut add_sphere = |center: Vec3, radius: f32, generation: u32| {
        let mut s = units[generation as usize].clone();
        for p in &mut s.positions {
            *p = center + *p * radius;
        }
        mesh.append(&s);
    };
    flake(&mut add_sphere, Vec3::ZERO, 1.0, Vec3::Y, 0, levels);
    if ground > 0 {
        mesh.append(&landscape(ground, 4.0, 0.25, 7, Vec3::new(0.0, -1.05, 0.0)));
    }
    mesh
}

/// One sphere and, recursively, its nine children: six around its equator and three
/// above, each a third of its size and touching it, all turned to face away from it.
fn flake(
    add: &mut impl FnMut(Vec3, f32, u32),
    center: Vec3,
    radius: f32,
    axis: Vec3,
    generation: u32,
    levels: u32,
) {
    add(center, radius, generation);
    if generation == levels {
        return;
    }
    let (u, v) = axis.any_orthonormal_pair();
    let child = radius / 3.0;
    let directions = (0..6)
        .map(|k| (90f32.to_radians(), k as f32 * TAU / 6.0))
        .chain((0..3).map(|k| (35f32.to_radians(), TAU / 12.0 + k as f32 * TAU / 3.0)));
    for (polar, azimuth) in directions {
        let d = axis * polar.cos() + (u * azimuth.cos() + v * azimuth.sin()) * polar.sin();
        flake(
            add,
            center + d * (radius + child),
            child,
            d,
            generation + 1,
            levels,
        );
    }
}

/// The unit icosphere: an icosahedron with each face split in four `subdivisions` times.
fn icosphere(subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = ((positions[a as usize] + positions[b as usize]) * 0.5).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    Mesh::new(positions, triangles)
}

/// The cube [-half, half]^3 turned by `rotation`, two triangles a face, wound outwards.
fn cube(rotation: Mat3, half: f32) -> Mesh {
    let positions = (0..8)
        .map(|i| {
            let corner = Vec3::new(
                if i & 1 == 0 { -half } else { half },
                if i & 2 == 0 { -half } else { half },
                if i & 4 == 0 { -half } else { half },
            );
            rotation * corner
        })
        .collect();
    let quads = [
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh::new(positions, triangles)
}

fn nested_boxes(count: u32) -> Mesh {
    let mut mesh = Mesh::default();
    for k in 0..count {
        let turn = Mat3::from_rotation_y(k as f32 * 0.13) * Mat3::from_rotation_x(k as f32 * 0.07);
        mesh.append(&cube(turn, (k + 1) as f32 / count as f32));
    }
    mesh
}

fn soup(count: u32, seed: u64) -> Mesh {
    let mut rng = SplitMix64(seed);
    let mut mesh = Mesh::default();
    for _ in 0..count {
        let center = Vec3::new(rng.unit(), rng.unit(), rng.unit());
        // Sizes from tiny to a third of the cube, log-uniformly, as in real scenes.
        let size = 0.002 * 150f32.powf(rng.unit());
        let base = mesh.positions.len() as u32;
        for _ in 0..3 {
            let offset = Vec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5;
            mesh.positions.push(center + offset * size);
        }
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    mesh
}

/// A height field over [-half, half]^2 around `center`, displaced by fractal value noise of
/// the given amplitude.
fn landscape(cells: u32, half: f32, amplitude: f32, seed: u64, center: Vec3) -> Mesh {
    use rayon::prelude::*;
    let n = cells as usize + 1;
    // Row by row on every core: hundreds of millions of triangles take seconds on one.
    let mut positions = vec![Vec3::ZERO; n * n];
    positions
        .par_chunks_mut(n)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, p) in row.iter_mut().enumerate() {
                let x = -half + 2.0 * half * i as f32 / cells as f32;
                let z = -half + 2.0 * half * j as f32 / cells as f32;
                let h = fractal_noise(x / half * 3.0, z / half * 3.0, seed) * amplitude;
                *p = center + Vec3::new(x, h, z);
            }
        });
    let cells = cells as usize;
    let mut triangles = vec![[0u32; 3]; 2 * cells * cells];
    triangles
        .par_chunks_mut(2 * cells)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, pair) in row.chunks_exact_mut(2).enumerate() {
                let a = (j * n + i) as u32;
                let b = a + 1;
                let c = a + n as u32;
                let d = c + 1;
                pair[0] = [a, c, b];
                pair[1] = [b, c, d];
            }
        });
    Mesh::new(positions, triangles)
}

/// Four octaves of smoothly interpolated lattice noise in [-1, 1].
fn fractal_noise(x: f32, z: f32, seed: u64) -> f32 {
    let mut sum = 0.0;
    let mut scale = 1.0;
    let mut weight = 0.5;
    for octave in 0..4 {
        sum += weight * value_noise(x * scale, z * scale, seed.wrapping_add(octave));
        scale *= 2.0;
        weight *= 0.5;
    }
    sum / 0.9375
}

fn value_noise(x: f32, z: f32, seed: u64) -> f32 {
    let (x0, z0) = (x.floor(), z.floor());
    let (fx, fz) = (x - x0, z - z0);
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let lattice = |i: f32, j: f32| {
        let key = (i as i64 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (j as i64 as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ seed;
        SplitMix64(key).unit() * 2.0 - 1.0
    };
    let (sx, sz) = (smooth(fx), smooth(fz));
    let top = lattice(x0, z0) * (1.0 - sx) + lattice(x0 + 1.0, z0) * sx;
    let bottom = lattice(x0, z0 + 1.0) * (1.0 - sx) + lattice(x0 + 1.0, z0 + 1.0) * sx;
    top * (1.0 - sz) + bottom * sz
}

/// SplitMix64: a tiny, fixed random number generator, so generated meshes never change
/// with a dependency's version.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn counts_match_the_prediction() {
        for g in [
            Generator::Sphereflake {
                levels: 1,
                subdivisions: 1,
                ground: 4,
            },
            Generator::Sphere { subdivisions: 3 },
            Generator::Cube {},
            Generator::NestedBoxes { count: 3 },
            Generator::Soup {
                triangles: 100,
                seed: 1,
            },
            Generator::Landscape {
                resolution: 5,
                seed: 2,
            },
            Generator::Hillside {
                resolution: 3,
                seed: 2,
            },
        ] {
            let mesh = g.generate().unwrap();
            assert_eq!(
                mesh.triangle_count() as u64,
                g.triangle_count(),
                "{}",
                g.name()
            );
            mesh.check(Path::new("generated")).unwrap();
        }
    }

    #[test]
    fn default_scene_is_big_enough() {
        let g = Generator::default_scene();
        assert!(g.triangle_count() >= 200_000, "{}", g.triangle_count());
    }

    #[test]
    fn generators_are_deterministic() {
        let g = Generator::Soup {
            triangles: 50,
            seed: 9,
        };
        assert_eq!(g.generate().unwrap(), g.generate().unwrap());
    }

    #[test]
    fn out_of_range_parameters_are_refused() {
        assert!(
            Generator::Soup {
                triangles: 0,
                seed: 0
            }
            .generate()
            .is_err()
        );
        assert!(
            Generator::Sphereflake {
                levels: 6,
                subdivisions: 2,
                ground: 0
            }
            .generate()
            .is_err()
        );
        let hillside = |resolution| Generator::Hillside {
            resolution,
            seed: 0,
        };
        let err = hillside(32768).check().unwrap_err().to_string();
        assert!(err.contains("between 1 and 32767"), "{err}");
        // 2.1 billion triangles: more than the index limit allows is refused by that, fewer
        // by the memory they would take on any machine these tests run on.
        let err = Generator::Soup {
            triangles: u32::MAX,
            seed: 0,
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(err.contains("the limit is 2147483648"), "{err}");
        let err = hillside(32767).check().unwrap_err().to_string();
        assert!(err.contains("GiB of memory to render"), "{err}");
    }

    #[test]
    fn cube_faces_point_outwards() {
        let m = cube(Mat3::IDENTITY, 1.0);
        for i in 0..m.triangle_count() {
            let [a, b, c] = m.corners(i);
            let n = (b - a).cross(c - a);
            assert!(n.dot((a + b + c) / 3.0) > 0.0, "face {i} points inwards");
        }
    }
}
