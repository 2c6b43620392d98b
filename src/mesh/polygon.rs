//! Polygons cut into triangles by ear clipping, in the polygon's own plane.
//!
//! The loaders of every polygonal format (OBJ faces, PLY faces) call
//! [`triangulate_polygon`], so a polygon becomes the same triangles whichever file it
//! came from.

use glam::{DVec2, DVec3, Vec3};

/// How [`triangulate_polygon`] cut a polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Triangulation {
    /// By ear clipping: the triangles cover the polygon exactly, without overlap. A convex
    /// polygon gives the fan from its first corner, `(0, 1, 2), (0, 2, 3), ...`.
    Ears,
    /// Fanned from its first corner because it has no area to cut (fewer than three
    /// corners, all of them on a line, or a coordinate that is not finite): its
    /// triangles have no area either.
    Flat,
    /// Fanned from its first corner because ear clipping found no ear: the polygon is not
    /// simple (it crosses itself), so no triangles cover it exactly.
    NotSimple,
    /// Fanned from its first corner because ear clipping would have taken more than
    /// [`EAR_CLIP_BUDGET`] vertex tests (a polygon of many thousands of reflex corners).
    TooCostly,
}

/// The most point-in-triangle tests ear clipping spends on one polygon. Ear clipping is
/// quadratic to cubic in the corners; this bounds the time a hostile file can cost
/// (about a second) while real polygons, even with thousands of corners, stay far below.
pub const EAR_CLIP_BUDGET: u64 = 1 << 28;

/// Cuts the polygon `corners` (indices into `positions`, in order around it) into
/// `corners.len() - 2` triangles appended to `out`, each with the polygon's winding.
///
/// The polygon is projected onto the plane of its Newell normal and cut by ear clipping:
/// concave polygons come out right, a corner on a straight edge becomes a triangle of
/// zero area, and a convex polygon gives the same fan from its first corner that a fan
/// triangulation would. What cannot be cut (see [`Triangulation`]) is fanned from the
/// first corner, as a fan triangulation would. Fewer than three corners give nothing.
///
/// Every index in `corners` must be in range of `positions`.
pub fn triangulate_polygon(
    positions: &[Vec3],
    corners: &[u32],
    out: &mut Vec<[u32; 3]>,
) -> Triangulation {
    let n = corners.len();
    if n < 3 {
        return Triangulation::Flat;
    }
    if n == 3 {
        out.push([corners[0], corners[1], corners[2]]);
        return Triangulation::Ears;
    }
    let points: Vec<DVec3> = corners
        .iter()
        .map(|&i| positions[i as usize].as_dvec3())
        .collect();
    let Some(flat) = project(&points) else {
        fan(corners, out);
        return Triangulation::Flat;
    };
    let start = out.len();
    let outcome = clip_ears(&flat, corners, out);
    if outcome != Triangulation::Ears {
        // Half a cut is worse than a plain fan: start again from the first corner.
        out.truncate(start);
        fan(corners, out);
    }
    outcome
}

/// The fan from the first corner: `(0, k - 1, k)` for `k` in `2..n`.
fn fan(corners: &[u32], out: &mut Vec<[u32; 3]>) {
    out.extend((2..corners.len()).map(|k| [corners[0], corners[k - 1], corners[k]]));
}

/// The polygon in 2D, counter-clockwise: its points with the coordinate along the Newell
/// normal's largest component dropped. `None` when the normal is zero or not finite.
fn project(points: &[DVec3]) -> Option<Vec<DVec2>> {
    let mut normal = DVec3::ZERO;
    for (i, p) in points.iter().enumerate() {
        let q = points[(i + 1) % points.len()];
        normal += DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    if !normal.is_finite() || normal == DVec3::ZERO {
        return None;
    }
    let axis = normal.abs().max_position();
    // The two kept axes in cyclic order (y z, z x, x y) see the polygon counter-clockwise
    // when the dropped component is positive; a negative one mirrors them.
    let sign = normal[axis].signum();
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    Some(
        points
            .iter()
            .map(|p| DVec2::new(p[u] * sign, p[v]))
            .collect(),
    )
}

/// Twice the signed area of the triangle `a b c`: positive when it turns left.
fn turn(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Ear clipping of a counter-clockwise polygon, appending triangles of `corners` to `out`.
/// The walk starts at the second corner and stays put after each cut, which makes a convex
/// polygon's ears exactly the fan from the first corner.
fn clip_ears(p: &[DVec2], corners: &[u32], out: &mut Vec<[u32; 3]>) -> Triangulation {
    let n = p.len();
    let mut next: Vec<usize> = (1..=n).map(|i| i % n).collect();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut removed = vec![false; n];
    let convex =
        |prev: &[usize], next: &[usize], i: usize| turn(p[prev[i]], p[i], p[next[i]]) > 0.0;
    // Only a corner that is not convex can lie inside an ear of a simple polygon, so only
    // those are tested against each candidate ear.
    let mut concave: Vec<usize> = (0..n).filter(|&i| !convex(&prev, &next, i)).collect();
    let mut listed = vec![false; n];
    for &i in &concave {
        listed[i] = true;
    }
    let mut budget = EAR_CLIP_BUDGET;
    let mut left = n;
    let mut cur = 1;
    let mut misses = 0;
    while left > 3 {
        let (a, c) = (prev[cur], next[cur]);
        let t = turn(p[a], p[cur], p[c]);
        // A corner on a line with its neighbours is cut off as a triangle of zero area:
        // that changes nothing about what is left.
        let ear = t == 0.0
            || (t > 0.0 && {
                let tests = concave.len() as u64;
                if tests > budget {
                    return Triangulation::TooCostly;
                }
                budget -= tests;
                !concave.iter().any(|&j| {
                    let flat = turn(p[prev[j]], p[j], p[next[j]]) == 0.0;
                    !removed[j] && blocks(p[j], flat, [p[a], p[cur], p[c]])
                })
            });
        if !ear {
            cur = c;
            misses += 1;
            if misses >= left {
                return Triangulation::NotSimple;
            }
            continue;
        }
        out.push([corners[a], corners[cur], corners[c]]);
        removed[cur] = true;
        next[a] = c;
        prev[c] = a;
        left -= 1;
        misses = 0;
        // The cut changes the angles at its two neighbours only.
        for k in [a, c] {
            if !listed[k] && !convex(&prev, &next, k) {
                listed[k] = true;
                concave.push(k);
            }
        }
        concave.retain(|&j| {
            let keep = !removed[j] && !convex(&prev, &next, j);
            listed[j] = keep;
            keep
        });
        cur = c;
    }
    out.push([corners[prev[cur]], corners[cur], corners[next[cur]]]);
    Triangulation::Ears
}

/// Whether the corner `q`, not convex, keeps the counter-clockwise triangle `t` from
/// being an ear: it lies inside it, or for a reflex corner on its border too (a reflex
/// corner on the cut would pinch what is left into two parts, and the next ear could be
/// taken on the outside). A corner on a straight edge may touch the border (a convex
/// polygon's fan runs along its straight edges), and a corner at the same place as one of
/// the triangle's is no obstacle.
fn blocks(q: DVec2, flat: bool, t: [DVec2; 3]) -> bool {
    if t.contains(&q) {
        return false;
    }
    let [a, b, c] = t;
    let sides = [turn(a, b, q), turn(b, c, q), turn(c, a, q)];
    match flat {
        true => sides.iter().all(|&s| s > 0.0),
        false => sides.iter().all(|&s| s >= 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cut(points: &[[f32; 3]]) -> (Vec<[u32; 3]>, Triangulation) {
        let positions: Vec<Vec3> = points.iter().map(|&p| Vec3::from(p)).collect();
        let corners: Vec<u32> = (0..points.len() as u32).collect();
        let mut out = Vec::new();
        let how = triangulate_polygon(&positions, &corners, &mut out);
        (out, how)
    }

    #[test]
    fn a_convex_quad_is_the_fan() {
        let (t, how) = cut(&[[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]);
        assert_eq!(how, Triangulation::Ears);
        assert_eq!(t, [[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn flat_polygons_are_fanned() {
        let (t, how) = cut(&[[0., 0., 0.], [1., 0., 0.], [2., 0., 0.], [3., 0., 0.]]);
        assert_eq!(how, Triangulation::Flat);
        assert_eq!(t, [[0, 1, 2], [0, 2, 3]]);
        let (t, how) = cut(&[[0., 0., 0.], [1., 0., 0.]]);
        assert_eq!((t.len(), how), (0, Triangulation::Flat));
        let (_, how) = cut(&[[0., 0., 0.], [1., f32::NAN, 0.], [1., 1., 0.], [0., 1., 0.]]);
        assert_eq!(how, Triangulation::Flat);
    }
}
