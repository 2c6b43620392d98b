//! The pinhole camera: settings, the "auto" framing of the benchmark protocol
//! (`../shared/BENCHMARK.md`, outside the repository), validation, and the exact f32
//! arithmetic that turns a pixel into a ray on the host and in every kernel.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::geometry::{Aabb, Ray};

/// Largest width or height accepted.
pub const MAX_RESOLUTION: u32 = 16384;
/// Field of view of the auto framing, degrees.
pub const AUTO_FOV: f32 = 45.0;
/// Width in pixels when neither the scene nor the flags give one.
pub const DEFAULT_WIDTH: u32 = 1280;
/// Height in pixels when neither the scene nor the flags give one.
pub const DEFAULT_HEIGHT: u32 = 720;

/// Camera settings; `None` means "not said here" (a later layer or the auto framing decides).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSettings {
    /// Eye position in world space; auto: on +z from the look-at point, far enough back
    /// that the mesh's bounding sphere fits the field of view.
    pub eye: Option<[f32; 3]>,
    /// The point the camera looks at, in world space; auto: the centre of the mesh's box.
    pub look_at: Option<[f32; 3]>,
    /// Up hint, any length but not parallel to the view direction; auto: +y.
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees, in (0, 180); auto: 45.
    pub fov: Option<f32>,
    /// Image width in pixels (1 to 16384); default 1280.
    pub width: Option<u32>,
    /// Image height in pixels (1 to 16384); default 720.
    pub height: Option<u32>,
}

impl CameraSettings {
    /// Each setting from `self` where given, else from `base`.
    pub(crate) fn over(self, base: CameraSettings) -> CameraSettings {
        CameraSettings {
            eye: self.eye.or(base.eye),
            look_at: self.look_at.or(base.look_at),
            up: self.up.or(base.up),
            fov: self.fov.or(base.fov),
            width: self.width.or(base.width),
            height: self.height.or(base.height),
        }
    }
}

/// A pinhole camera: eye, the point it looks at, an up hint and a vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub(crate) eye: Vec3,
    pub(crate) look_at: Vec3,
    pub(crate) up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub(crate) fov: f32,
    /// Image width in pixels (1 to 16384).
    pub width: u32,
    /// Image height in pixels (1 to 16384).
    pub height: u32,
}

impl Camera {
    /// The "auto" framing: with centre `c` and radius `r` (half the diagonal) of `bounds`,
    /// the eye sits at `c + (0, 0, r / sin(fov / 2))`, looks at `c`, up is +y, fov 45°.
    pub fn auto(bounds: &Aabb, width: u32, height: u32) -> Result<Camera> {
        Camera::from_settings(
            &CameraSettings {
                width: Some(width),
                height: Some(height),
                ..Default::default()
            },
            bounds,
        )
    }

    /// Fills what `settings` leaves out from the auto framing of `bounds`, then validates.
    /// A given look-at point replaces the centre; a given fov moves the auto eye so that
    /// the bounding sphere still fits.
    pub fn from_settings(settings: &CameraSettings, bounds: &Aabb) -> Result<Camera> {
        check_resolution(settings)?;
        let fov = settings.fov.unwrap_or(AUTO_FOV);
        check_fov(fov)?;
        let center = bounds.center();
        let mut radius = bounds.extent().length() * 0.5;
        if radius.is_nan() || radius <= 0.0 {
            radius = 1.0; // a mesh in one point still gets a view
        }
        let look_at = settings.look_at.map(Vec3::from).unwrap_or(center);
        let distance = radius / (fov.to_radians() * 0.5).sin();
        let camera = Camera {
            eye: settings
                .eye
                .map(Vec3::from)
                .unwrap_or(look_at + Vec3::new(0.0, 0.0, distance)),
            look_at,
            up: settings.up.map(Vec3::from).unwrap_or(Vec3::Y),
            fov,
            width: settings.width.unwrap_or(DEFAULT_WIDTH),
            height: settings.height.unwrap_or(DEFAULT_HEIGHT),
        };
        camera.validate()?;
        Ok(camera)
    }

    /// Refuses cameras that cannot make an image.
    pub(crate) fn validate(&self) -> Result<()> {
        check_resolution(&CameraSettings {
            width: Some(self.width),
            height: Some(self.height),
            ..Default::default()
        })?;
        check_fov(self.fov)?;
        if !(self.eye.is_finite() && self.look_at.is_finite() && self.up.is_finite()) {
            return Err(Error::Invalid(
                "camera eye, look-at and up must be finite numbers".into(),
            ));
        }
        let forward = self.look_at.as_dvec3() - self.eye.as_dvec3();
        if forward.length() <= 1e-12 * (1.0 + self.eye.as_dvec3().length()) {
            return Err(Error::Invalid(format!(
                "camera eye {:?} equals look-at {:?}: there is no view direction",
                self.eye.to_array(),
                self.look_at.to_array()
            )));
        }
        let up = self.up.as_dvec3();
        if up.length() == 0.0 || forward.normalize().cross(up.normalize()).length() < 1e-6 {
            return Err(Error::Invalid(format!(
                "camera up {:?} is parallel to the view direction (or zero); choose another up",
                self.up.to_array()
            )));
        }
        Ok(())
    }

    /// The f32 ray basis the host and the kernels share.
    pub fn pinhole(&self) -> Pinhole {
        let eye = self.eye.as_dvec3();
        let forward = (self.look_at.as_dvec3() - eye).normalize();
        let right = forward.cross(self.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let half_h = ((self.fov as f64).to_radians() * 0.5).tan();
        let half_w = half_h * self.width as f64 / self.height as f64;
        let p0 = forward - right * half_w + up * half_h;
        let du = right * (2.0 * half_w / self.width as f64);
        let dv = -up * (2.0 * half_h / self.height as f64);
        let f4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        Pinhole {
            eye: f4(eye),
            p0: f4(p0),
            du: f4(du),
            dv: f4(dv),
        }
    }
}

/// Checks what can be checked before the mesh is known: resolution and field of view.
pub fn check_settings(s: &CameraSettings) -> Result<()> {
    check_resolution(s)?;
    if let Some(fov) = s.fov {
        check_fov(fov)?;
    }
    Ok(())
}

fn check_resolution(s: &CameraSettings) -> Result<()> {
    for (name, value) in [("width", s.width), ("height", s.height)] {
        if let Some(v) = value
            && (v == 0 || v > MAX_RESOLUTION)
        {
            return Err(Error::Invalid(format!(
                "image {name} {v} is out of range: it must be between 1 and {MAX_RESOLUTION}"
            )));
        }
    }
    Ok(())
}

fn check_fov(fov: f32) -> Result<()> {
    if !(fov > 0.0 && fov < 180.0) {
        return Err(Error::Invalid(format!(
            "field of view {fov} is out of range: it must be strictly between 0 and 180 degrees"
        )));
    }
    Ok(())
}

/// The camera as kernels see it: pixel `(x, y)`'s ray leaves `eye` in direction
/// `p0 + (x + 0.5) * du + (y + 0.5) * dv`, unnormalised. `p0` points at the image plane's
/// top-left corner at distance 1; `du` steps one pixel right, `dv` one pixel down.
/// Mirrored by `camera_ray` in `cl/camera.cl`, operation for operation.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Pinhole {
    pub(crate) eye: [f32; 4],
    pub(crate) p0: [f32; 4],
    pub(crate) du: [f32; 4],
    pub(crate) dv: [f32; 4],
}

impl Pinhole {
    /// The primary ray through the centre of pixel `(x, y)`. No fused multiply-adds, in the
    /// same order as the kernel, so both produce the same bits.
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        let fx = x as f32 + 0.5;
        let fy = y as f32 + 0.5;
        let d = |k: usize| (self.p0[k] + fx * self.du[k]) + fy * self.dv[k];
        Ray::new(
            Vec3::new(self.eye[0], self.eye[1], self.eye[2]),
            Vec3::new(d(0), d(1), d(2)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::from_points([Vec3::splat(-1.0), Vec3::splat(1.0)])
    }

    #[test]
    fn auto_framing_follows_the_benchmark_protocol() {
        let b = Aabb::from_points([Vec3::new(0.0, 2.0, 0.0), Vec3::new(2.0, 4.0, 2.0)]);
        let c = Camera::auto(&b, 640, 480).unwrap();
        let r = 3f32.sqrt();
        let expected = Vec3::new(1.0, 3.0, 1.0 + r / 22.5f32.to_radians().sin());
        assert!((c.eye - expected).length() < 1e-5);
        assert_eq!(c.look_at, Vec3::new(1.0, 3.0, 1.0));
        assert_eq!(c.fov, 45.0);
    }

    #[test]
    fn centre_pixel_looks_at_the_target_and_corners_span_the_fov() {
        let c = Camera::auto(&unit_box(), 101, 51).unwrap();
        let p = c.pinhole();
        let centre = p.ray(50, 25).dir.normalize();
        assert!((centre - Vec3::NEG_Z).length() < 1e-6);
        // Top edge of the image plane at half-height tan(22.5°), x to the right, y down.
        let top_left = p.ray(0, 0).dir;
        assert!(top_left.x < 0.0 && top_left.y > 0.0);
        let edge = Vec3::from_slice(&p.p0[..3]);
        assert!((edge.y - 22.5f32.to_radians().tan()).abs() < 1e-6);
        assert!((edge.x + 22.5f32.to_radians().tan() * 101.0 / 51.0).abs() < 1e-5);
    }

    #[test]
    fn invalid_cameras_are_refused() {
        let b = unit_box();
        let bad = |s: CameraSettings| Camera::from_settings(&s, &b).unwrap_err().to_string();
        assert!(
            bad(CameraSettings {
                width: Some(0),
                ..Default::default()
            })
            .contains("width")
        );
        assert!(
            bad(CameraSettings {
                height: Some(16385),
                ..Default::default()
            })
            .contains("height")
        );
        assert!(
            bad(CameraSettings {
                fov: Some(180.0),
                ..Default::default()
            })
            .contains("field of view")
        );
        assert!(
            bad(CameraSettings {
                fov: Some(0.0),
                ..Default::default()
            })
            .contains("field of view")
        );
        assert!(
            bad(CameraSettings {
                fov: Some(f32::NAN),
                ..Default::default()
            })
            .contains("field of view")
        );
        assert!(
            bad(CameraSettings {
                eye: Some([1.0, 2.0, 3.0]),
                look_at: Some([1.0, 2.0, 3.0]),
                ..Default::default()
            })
            .contains("equals look-at")
        );
        assert!(
            bad(CameraSettings {
                eye: Some([0.0, 5.0, 0.0]),
                look_at: Some([0.0, 0.0, 0.0]),
                ..Default::default()
            })
            .contains("parallel")
        );
        assert!(
            Camera::from_settings(
                &CameraSettings {
                    width: Some(16384),
                    ..Default::default()
                },
                &b
            )
            .is_ok()
        );
    }

    #[test]
    fn a_mesh_in_one_point_still_gets_a_camera() {
        let b = Aabb::from_points([Vec3::ONE]);
        assert!(Camera::from_settings(&CameraSettings::default(), &b).is_ok());
    }
}
