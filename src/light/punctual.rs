//! Lights without area, which only light samples can reach: point, spot and directional
//! lights, with Mitsuba 3's parameters (`point`, `spot`, `directional`). The mirror of
//! cl/punctual.cl, which reads each light as the four float4 of [`Punctual::pack`].

use glam::Vec3;

/// [`Punctual::pack`]'s kind code (the first float4's w) of a directional light.
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// Kind code of a point light.
pub const LIGHT_POINT: u32 = 1;
/// Kind code of a spot light.
pub const LIGHT_SPOT: u32 = 2;

/// A light without area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Punctual {
    /// Light from one point, the same in every direction: radiant intensity (W/sr).
    Point {
        /// Where it is.
        position: Vec3,
        /// Radiant intensity, per channel.
        intensity: Vec3,
    },
    /// A point light whose light fills a cone: full within `beam` of the axis, falling
    /// linearly in angle to nothing at `cutoff` (Mitsuba's `spot`).
    Spot {
        /// Where it is.
        position: Vec3,
        /// Where its axis points (unit).
        direction: Vec3,
        /// Radiant intensity on the axis, per channel.
        intensity: Vec3,
        /// Angle off the axis where the light ends, radians (0 to π/2).
        cutoff: f32,
        /// Angle within which it is full, radians (0 to `cutoff`).
        beam: f32,
    },
    /// Parallel light from infinitely far away, as the sun's.
    Directional {
        /// The way its light travels (unit).
        direction: Vec3,
        /// Irradiance on a surface facing it, per channel.
        irradiance: Vec3,
    },
}

impl Punctual {
    /// The four float4 the kernels read: position (or the direction of travel) and kind;
    /// intensity (or irradiance) and cos cutoff; the spot's axis and cos beam; the cutoff
    /// angle and the inverse of the falloff band's width, radians.
    pub fn pack(&self) -> [[f32; 4]; 4] {
        match *self {
            Punctual::Point {
                position: p,
                intensity: i,
            } => [
                [p.x, p.y, p.z, LIGHT_POINT as f32],
                [i.x, i.y, i.z, -1.0],
                [0.0, 0.0, 1.0, -1.0],
                [0.0; 4],
            ],
            Punctual::Spot {
                position: p,
                direction: a,
                intensity: i,
                cutoff,
                beam,
            } => {
                let band = cutoff - beam;
                let inv = if band > 0.0 { 1.0 / band } else { 0.0 };
                [
                    [p.x, p.y, p.z, LIGHT_SPOT as f32],
                    [i.x, i.y, i.z, cutoff.cos()],
                    [a.x, a.y, a.z, beam.cos()],
                    [cutoff, inv, 0.0, 0.0],
                ]
            }
            Punctual::Directional {
                direction: d,
                irradiance: e,
            } => [
                [d.x, d.y, d.z, LIGHT_DIRECTIONAL as f32],
                [e.x, e.y, e.z, -1.0],
                [0.0, 0.0, 1.0, -1.0],
                [0.0; 4],
            ],
        }
    }
}

/// `punctual_incident` in cl/punctual.cl: for the packed light `l` and a point `x`, the
/// unit direction towards the light, how far it is (infinite for a directional light)
/// and the irradiance it brings to a surface facing it there.
pub fn incident(l: &[[f32; 4]; 4], x: Vec3) -> (Vec3, f32, Vec3) {
    let [p, i, a, c] = l;
    let power = Vec3::new(i[0], i[1], i[2]);
    let at = Vec3::new(p[0], p[1], p[2]);
    let kind = p[3] as u32;
    if kind == LIGHT_DIRECTIONAL {
        return (-at, f32::INFINITY, power);
    }
    let w = at - x;
    let d2 = w.length_squared();
    let dist = d2.sqrt();
    let dir = w / dist;
    let mut falloff = 1.0;
    if kind == LIGHT_SPOT {
        let cos = -(dir.x * a[0] + dir.y * a[1] + dir.z * a[2]);
        falloff = if cos <= i[3] {
            0.0
        } else if cos >= a[3] {
            1.0
        } else {
            (c[0] - cos.min(1.0).acos()) * c[1]
        };
    }
    (dir, dist, power * (falloff / d2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_is_full_in_its_beam_falls_linearly_in_angle_and_ends_at_its_cutoff() {
        let spot = Punctual::Spot {
            position: Vec3::new(0.0, 2.0, 0.0),
            direction: -Vec3::Y,
            intensity: Vec3::splat(8.0),
            cutoff: 30f32.to_radians(),
            beam: 20f32.to_radians(),
        }
        .pack();
        let at = |deg: f32| {
            let x = Vec3::new(2.0 * deg.to_radians().tan(), 0.0, 0.0);
            let (dir, dist, e) = incident(&spot, x);
            assert!((dir - (Vec3::new(0.0, 2.0, 0.0) - x).normalize()).length() < 1e-6);
            e.x * dist * dist / 8.0
        };
        assert!((at(0.0) - 1.0).abs() < 1e-6);
        assert!((at(19.0) - 1.0).abs() < 1e-6);
        assert!((at(25.0) - 0.5).abs() < 1e-3, "{}", at(25.0));
        assert!((at(27.5) - 0.25).abs() < 1e-3, "{}", at(27.5));
        assert_eq!(at(31.0), 0.0);
    }

    #[test]
    fn points_fall_off_with_the_square_of_distance_and_suns_do_not() {
        let point = Punctual::Point {
            position: Vec3::new(1.0, 3.0, 0.0),
            intensity: Vec3::new(9.0, 18.0, 27.0),
        }
        .pack();
        let (dir, dist, e) = incident(&point, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!((dir, dist), (Vec3::Y, 3.0));
        assert!((e - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
        let sun = Punctual::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::splat(2.0),
        }
        .pack();
        let (dir, dist, e) = incident(&sun, Vec3::new(5.0, 1.0, 7.0));
        assert_eq!((dir, dist, e), (Vec3::Y, f32::INFINITY, Vec3::splat(2.0)));
    }
}
