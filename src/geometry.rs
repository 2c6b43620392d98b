//! Rays and axis-aligned boxes, the two shapes every stage speaks.

use glam::{Vec3, Vec3A};

/// A ray `origin + t * dir`. `dir` need not be unit length: primary rays keep the
/// unnormalised pixel direction so that the host and the device compute identical bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts, in world space (`t = 0`).
    pub origin: Vec3,
    /// The direction, not necessarily unit length; `t` is measured in multiples of it.
    pub dir: Vec3,
}

impl Ray {
    /// The ray from `origin` along `dir`, taken as given (not normalised).
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir }
    }

    pub(crate) fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// An axis-aligned bounding box. The empty box has `min = +inf`, `max = -inf`, so that
/// growing it by any point gives that point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lowest corner: the smallest x, y and z inside the box (`+inf` when empty).
    pub min: Vec3,
    /// The highest corner: the largest x, y and z inside the box (`-inf` when empty).
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub(crate) const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding every point; the empty box for no points.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grown(p))
    }

    /// The smallest box holding both (either may be empty).
    pub(crate) fn union(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub(crate) fn grown(self, p: Vec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// The size along each axis, `max - min`; zero for an empty box.
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The midpoint of `min` and `max`; NaN for an empty box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area; zero for an empty box, so that empty bins cost nothing in the SAH.
    pub(crate) fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Whether `other` lies inside this box (boundaries included).
    pub(crate) fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.min.cmple(other.min).all() && other.max.cmple(self.max).all())
    }
}

/// The builders' box: an [`Aabb`] in SIMD lanes (the fourth lane unused), with the half
/// surface area the SAH compares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub(crate) min: Vec3A,
    pub(crate) max: Vec3A,
}

impl Bounds {
    /// The box `[min, max]`.
    pub(crate) fn new(min: [f32; 3], max: [f32; 3]) -> Bounds {
        Bounds {
            min: Vec3A::from(min),
            max: Vec3A::from(max),
        }
    }

    /// The smallest box holding both.
    #[inline]
    pub(crate) fn union(self, o: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Half the surface area, negative extents counting as zero: the SAH only compares
    /// areas, so the factor 2 is dropped.
    #[inline]
    pub(crate) fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// The surface area of the box `[min, max]` in f64 (extents subtracted in f32, negative
/// ones counting as zero), as the SAH costs of the collapsed trees sum it.
pub(crate) fn surface_area_f64(min: Vec3, max: Vec3) -> f64 {
    let e = (max - min).max(Vec3::ZERO).as_dvec3();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_box_grows_to_a_point_and_has_no_area() {
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let b = Aabb::EMPTY.grown(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(b.min, b.max);
        assert_eq!(b.surface_area(), 0.0);
    }

    #[test]
    fn unit_cube_area_and_axis() {
        let b = Aabb::from_points([Vec3::ZERO, Vec3::new(1.0, 1.0, 2.0)]);
        assert_eq!(b.surface_area(), 10.0);
        assert!(b.contains(&Aabb::from_points([Vec3::splat(0.5)])));
        assert!(!b.contains(&Aabb::from_points([Vec3::splat(1.5)])));
    }
}
