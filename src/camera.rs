//! The camera: settings, the two framings of a mesh (the "auto" three-quarter view for
//! people, and the benchmark protocol's straight-on view, `../shared/BENCHMARK.md`, outside
//! the repository), perspective or orthographic projection, a thin lens, validation, and
//! the exact f32 arithmetic that turns a pixel into a ray on the host and in every kernel.

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
/// The auto view's azimuth, degrees: from the front (+z for up +y) towards the right (+x).
pub const AUTO_AZIMUTH: f64 = 40.0;
/// The auto view's elevation above the horizontal plane, degrees.
pub const AUTO_ELEVATION: f64 = 30.0;
/// Share of each half of the image the auto view leaves free around the mesh's box.
pub const AUTO_MARGIN: f64 = 0.05;

/// Which framing fills in what the settings leave out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    /// A three-quarter view from the front-right and above, fitted to the mesh's box.
    Auto,
    /// The benchmark protocol's view: along -z at the bounding sphere (what `bench` and
    /// `tune` use, so that their figures stay comparable).
    Bench,
}

impl View {
    /// Every view.
    pub const ALL: [View; 2] = [View::Auto, View::Bench];

    /// The view's name: `--camera` and the scene key `view`.
    pub fn name(self) -> &'static str {
        match self {
            View::Auto => "auto",
            View::Bench => "bench",
        }
    }

    /// One line on the view, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            View::Auto => {
                "From the front-right and above (40° round, 30° up), the mesh's box fitted \
                 to the image with a 5% margin"
            }
            View::Bench => {
                "The benchmark's view: straight along -z at the mesh's bounding sphere (as \
                 `bench` and `tune` render)"
            }
        }
    }
}

impl std::str::FromStr for View {
    type Err = String;

    /// The view [`View::name`] names.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        crate::error::by_name(s, &View::ALL, View::name, "camera view")
    }
}

/// How rays leave the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Projection {
    /// All rays leave the eye, one through each pixel (the field of view applies).
    #[default]
    Perspective,
    /// Parallel rays along the view direction, one from each pixel of an image plane
    /// through the eye (its height is `ortho_height`; the field of view does not apply).
    Orthographic,
}

impl Projection {
    /// Every projection.
    pub const ALL: [Projection; 2] = [Projection::Perspective, Projection::Orthographic];

    /// The projection's name: `--projection` and the scene key `projection`.
    pub fn name(self) -> &'static str {
        match self {
            Projection::Perspective => "perspective",
            Projection::Orthographic => "orthographic",
        }
    }

    /// One line on the projection, for `--help`.
    pub fn about(self) -> &'static str {
        match self {
            Projection::Perspective => "Rays from the eye through each pixel (`--fov`)",
            Projection::Orthographic => {
                "Parallel rays from an image plane through the eye (`--ortho-height`)"
            }
        }
    }
}

impl std::str::FromStr for Projection {
    type Err = String;

    /// The projection [`Projection::name`] names.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        crate::error::by_name(s, &Projection::ALL, Projection::name, "projection")
    }
}

/// Camera settings; `None` means "not said here" (a later layer or the framing decides).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSettings {
    /// The framing that fills in eye and look-at where they are not given; default auto.
    pub view: Option<View>,
    /// Eye position in world space; auto: see [`View`].
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
    /// Perspective (default) or orthographic.
    pub projection: Option<Projection>,
    /// Height of an orthographic camera's image plane, in scene units, above 0; auto:
    /// the mesh's box fitted with the auto margin.
    pub ortho_height: Option<f32>,
    /// Diameter of the thin lens, in scene units, 0 or more; default 0, a pinhole.
    pub aperture: Option<f32>,
    /// Distance from the eye, along the view direction, of the plane in focus, above 0;
    /// default: the look-at point's distance.
    pub focus_distance: Option<f32>,
    /// A point to focus on: sets the focus distance to its distance along the view
    /// direction. Give it or `focus_distance`, not both.
    pub focus_on: Option<[f32; 3]>,
}

impl CameraSettings {
    /// Each setting from `self` where given, else from `base`. The focus is one setting:
    /// a `focus_distance` here beats a `focus_on` in `base`, and the other way round.
    pub(crate) fn over(self, base: CameraSettings) -> CameraSettings {
        let (focus_distance, focus_on) = if self.focus_distance.is_some() || self.focus_on.is_some()
        {
            (self.focus_distance, self.focus_on)
        } else {
            (base.focus_distance, base.focus_on)
        };
        CameraSettings {
            view: self.view.or(base.view),
            eye: self.eye.or(base.eye),
            look_at: self.look_at.or(base.look_at),
            up: self.up.or(base.up),
            fov: self.fov.or(base.fov),
            width: self.width.or(base.width),
            height: self.height.or(base.height),
            projection: self.projection.or(base.projection),
            ortho_height: self.ortho_height.or(base.ortho_height),
            aperture: self.aperture.or(base.aperture),
            focus_distance,
            focus_on,
        }
    }
}

/// A camera: eye, the point it looks at, an up hint, a vertical field of view or an
/// orthographic image height, and a thin lens (closed by default: a pinhole).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub(crate) eye: Vec3,
    pub(crate) look_at: Vec3,
    pub(crate) up: Vec3,
    /// Vertical field of view in degrees, in (0, 180) (perspective only).
    pub(crate) fov: f32,
    /// Image width in pixels (1 to 16384).
    pub width: u32,
    /// Image height in pixels (1 to 16384).
    pub height: u32,
    pub(crate) projection: Projection,
    /// Height of the orthographic image plane, scene units (orthographic only).
    pub(crate) ortho_height: f32,
    /// Diameter of the lens, scene units; 0: a pinhole.
    pub(crate) aperture: f32,
    /// Distance of the plane in focus along the view direction (with a lens only).
    pub(crate) focus_distance: f32,
}

impl Camera {
    /// The benchmark protocol's framing, which `bench` and `tune` render: with centre `c`
    /// and radius `r` (half the diagonal) of `bounds`, the eye sits at
    /// `c + (0, 0, r / sin(fov / 2))`, looks at `c`, up is +y, fov 45°, a pinhole.
    pub fn bench(bounds: &Aabb, width: u32, height: u32) -> Result<Camera> {
        Camera::from_settings(
            &CameraSettings {
                view: Some(View::Bench),
                width: Some(width),
                height: Some(height),
                ..Default::default()
            },
            bounds,
        )
    }

    /// Fills what `settings` leaves out from the view of `bounds` that `settings.view`
    /// names (default [`View::Auto`]), then validates. A given eye is kept; a given look-at
    /// point replaces the box's centre, and the eye is fitted around it; a given fov or
    /// up is fitted with.
    pub fn from_settings(settings: &CameraSettings, bounds: &Aabb) -> Result<Camera> {
        check_settings(settings)?;
        let fov = settings.fov.unwrap_or(AUTO_FOV);
        let width = settings.width.unwrap_or(DEFAULT_WIDTH);
        let height = settings.height.unwrap_or(DEFAULT_HEIGHT);
        let up = settings.up.map(Vec3::from).unwrap_or(Vec3::Y);
        let look_at = settings.look_at.map(Vec3::from).unwrap_or(bounds.center());
        let eye = match (settings.eye, settings.view.unwrap_or(View::Auto)) {
            (Some(eye), _) => Vec3::from(eye),
            (None, View::Bench) => bench_eye(bounds, look_at, fov),
            (None, View::Auto) => auto_eye(bounds, look_at, up, fov, width, height),
        };
        let mut camera = Camera {
            eye,
            look_at,
            up,
            fov,
            width,
            height,
            projection: settings.projection.unwrap_or_default(),
            ortho_height: 1.0,
            aperture: settings.aperture.unwrap_or(0.0),
            focus_distance: 1.0,
        };
        camera.validate_view()?;
        if camera.projection == Projection::Orthographic {
            camera.ortho_height = match settings.ortho_height {
                Some(h) => h,
                None => camera.fitted_ortho_height(bounds),
            };
        }
        camera.focus_distance = match (settings.focus_distance, settings.focus_on) {
            (Some(d), _) => d,
            (None, Some(p)) => {
                let f = (Vec3::from(p).as_dvec3() - camera.eye.as_dvec3()).dot(camera.forward());
                if !(f > 0.0 && f.is_finite()) {
                    return Err(Error::Invalid(format!(
                        "focus_on {p:?} is not in front of the camera at {:?} (its distance \
                         along the view is {f}): focus on a point the camera looks towards",
                        camera.eye.to_array()
                    )));
                }
                f as f32
            }
            (None, None) => (camera.look_at - camera.eye).length(),
        };
        camera.validate()?;
        Ok(camera)
    }

    /// The unit view direction, in f64.
    fn forward(&self) -> DVec3 {
        (self.look_at.as_dvec3() - self.eye.as_dvec3()).normalize()
    }

    /// The height of an orthographic image plane that holds the 8 corners of `bounds`
    /// with the auto margin, seen along this camera's view.
    fn fitted_ortho_height(&self, bounds: &Aabb) -> f32 {
        let forward = self.forward();
        let right = forward.cross(self.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let aspect = self.width as f64 / self.height as f64;
        let axis = self.eye.as_dvec3();
        let half = corners(bounds)
            .map(|p| {
                let q = p - axis;
                q.dot(up).abs().max(q.dot(right).abs() / aspect)
            })
            .fold(0.0, f64::max);
        let h = 2.0 * half / (1.0 - AUTO_MARGIN);
        if h > 0.0 && h.is_finite() {
            h as f32
        } else {
            2.0 // a mesh in one point still gets a view
        }
    }

    /// Refuses eye, look-at and up that give no view direction or no image orientation.
    fn validate_view(&self) -> Result<()> {
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

    /// Refuses cameras that cannot make an image.
    pub(crate) fn validate(&self) -> Result<()> {
        check_resolution(self.width, self.height)?;
        check_fov(self.fov)?;
        self.validate_view()?;
        check_aperture(self.aperture)?;
        check_focus_distance(self.focus_distance)?;
        if self.projection == Projection::Orthographic {
            check_ortho_height(self.ortho_height)?;
        }
        Ok(())
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The point looked at.
    pub fn look_at(&self) -> Vec3 {
        self.look_at
    }

    /// The up hint.
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Vertical field of view, degrees (perspective only).
    pub fn fov(&self) -> f32 {
        self.fov
    }

    /// Perspective or orthographic.
    pub fn projection(&self) -> Projection {
        self.projection
    }

    /// Height of the orthographic image plane, scene units (orthographic only).
    pub fn ortho_height(&self) -> f32 {
        self.ortho_height
    }

    /// Lens diameter, scene units; 0 for a pinhole.
    pub fn aperture(&self) -> f32 {
        self.aperture
    }

    /// Distance of the plane in focus along the view direction.
    pub fn focus_distance(&self) -> f32 {
        self.focus_distance
    }

    /// How the camera differs from a perspective pinhole, for the logs and a part's
    /// settings: empty for a perspective pinhole (so their lines stay as they were).
    pub(crate) fn lens_description(&self) -> String {
        let mut s = String::new();
        if self.projection == Projection::Orthographic {
            s.push_str(&format!(" orthographic height {:?}", self.ortho_height));
        }
        if self.aperture > 0.0 {
            s.push_str(&format!(
                " aperture {:?} focus {:?}",
                self.aperture, self.focus_distance
            ));
        }
        s
    }

    /// The f32 ray basis the host and the kernels share.
    pub fn pinhole(&self) -> Pinhole {
        let eye = self.eye.as_dvec3();
        let forward = (self.look_at.as_dvec3() - eye).normalize();
        let right = forward.cross(self.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let f4 = |v: DVec3, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        let (w, h) = (self.width as f64, self.height as f64);
        let (p0, du, dv, orthographic) = match self.projection {
            Projection::Perspective => {
                // The image plane at distance 1: directions with forward component 1.
                let half_h = ((self.fov as f64).to_radians() * 0.5).tan();
                let half_w = half_h * w / h;
                let p0 = forward - right * half_w + up * half_h;
                (
                    p0,
                    right * (2.0 * half_w / w),
                    -up * (2.0 * half_h / h),
                    0.0,
                )
            }
            Projection::Orthographic => {
                // The image plane through the eye: offsets of the rays' origins.
                let half_h = self.ortho_height as f64 * 0.5;
                let half_w = half_h * w / h;
                let p0 = -right * half_w + up * half_h;
                (
                    p0,
                    right * (2.0 * half_w / w),
                    -up * (2.0 * half_h / h),
                    1.0,
                )
            }
        };
        let radius = self.aperture as f64 * 0.5;
        let (lens_u, lens_v, focus) = if radius > 0.0 {
            (right * radius, up * radius, self.focus_distance)
        } else {
            (DVec3::ZERO, DVec3::ZERO, 0.0)
        };
        Pinhole {
            eye: f4(eye, 0.0),
            p0: f4(p0, 0.0),
            du: f4(du, 0.0),
            dv: f4(dv, 0.0),
            forward: f4(forward, orthographic),
            lens_u: f4(lens_u, focus),
            lens_v: f4(lens_v, 0.0),
        }
    }
}

/// The 8 corners of `b`, in f64.
fn corners(b: &Aabb) -> impl Iterator<Item = DVec3> {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    (0..8).map(move |i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Half the diagonal of `bounds`, or 1 for a mesh in one point.
fn radius(bounds: &Aabb) -> f32 {
    let radius = bounds.extent().length() * 0.5;
    if radius.is_nan() || radius <= 0.0 {
        1.0 // a mesh in one point still gets a view
    } else {
        radius
    }
}

/// The benchmark protocol's eye: on +z from `look_at`, far enough that the bounding
/// sphere fits the field of view. In f32, as it always was, so that `bench` and `tune`
/// keep their figures comparable.
fn bench_eye(bounds: &Aabb, look_at: Vec3, fov: f32) -> Vec3 {
    let distance = radius(bounds) / (fov.to_radians() * 0.5).sin();
    look_at + Vec3::new(0.0, 0.0, distance)
}

/// The auto view's eye: from `look_at`, [`AUTO_AZIMUTH`] round from the front towards
/// the right and [`AUTO_ELEVATION`] up (both about `up`), as close as lets the 8 corners
/// of `bounds` project inside the image less [`AUTO_MARGIN`] on both axes, and strictly in
/// front of every corner, so never inside the box (the box lies in the open half-space
/// ahead of such an eye). The corners fit, not the bounding sphere, so that flat or long
/// meshes fill the image instead of sitting small in its middle.
fn auto_eye(bounds: &Aabb, look_at: Vec3, up: Vec3, fov: f32, width: u32, height: u32) -> Vec3 {
    let u = up.as_dvec3().normalize();
    // The front: +z for a y-up scene; -y (as in Blender) when up is along z.
    let reject = |v: DVec3| v - u * u.dot(v);
    let mut front = reject(DVec3::Z);
    if front.length() < 1e-3 {
        front = reject(DVec3::NEG_Y);
    }
    let front = front.normalize();
    let side = u.cross(front);
    let (az, el) = (AUTO_AZIMUTH.to_radians(), AUTO_ELEVATION.to_radians());
    let back = (front * az.cos() + side * az.sin()) * el.cos() + u * el.sin();
    // The basis Camera::pinhole will build for this eye.
    let forward = -back;
    let right = forward.cross(u).normalize();
    let image_up = right.cross(forward);
    let tan_y = ((fov as f64).to_radians() * 0.5).tan() * (1.0 - AUTO_MARGIN);
    let tan_x = tan_y * width as f64 / height as f64;
    let centre = look_at.as_dvec3();
    let (mut distance, mut nearest) = (0.0f64, f64::NEG_INFINITY);
    for p in corners(bounds) {
        let q = p - centre;
        let z = q.dot(back);
        distance = distance
            .max(z + q.dot(right).abs() / tan_x)
            .max(z + q.dot(image_up).abs() / tan_y);
        nearest = nearest.max(z);
    }
    let r = radius(bounds) as f64;
    let extent = bounds.extent().length();
    if extent.is_nan() || extent <= 0.0 {
        // A mesh in one point: far enough to see a sphere of radius 1 round it.
        distance = r / ((fov as f64).to_radians() * 0.5).sin();
    }
    // Back off until the eye, rounded to f32, is outside the box and ahead of it.
    let mut gap = 1e-3 * r;
    for _ in 0..64 {
        let d = distance.max(nearest + gap);
        let eye = (centre + back * d).as_vec3();
        let outside = (0..3).any(|k| eye[k] < bounds.min[k] || eye[k] > bounds.max[k]);
        if outside || !eye.is_finite() {
            return eye;
        }
        gap *= 2.0;
    }
    (centre + back * distance.max(nearest + gap)).as_vec3()
}

/// Checks what can be checked before the mesh is known: resolution, field of view,
/// up, the lens and the orthographic height, and an eye on the look-at point.
pub fn check_settings(s: &CameraSettings) -> Result<()> {
    check_resolution(
        s.width.unwrap_or(DEFAULT_WIDTH),
        s.height.unwrap_or(DEFAULT_HEIGHT),
    )?;
    if let Some(fov) = s.fov {
        check_fov(fov)?;
    }
    if let Some(up) = s.up
        && !(Vec3::from(up).is_finite() && Vec3::from(up) != Vec3::ZERO)
    {
        return Err(Error::Invalid(format!(
            "camera up {up:?} is zero or not finite: give a direction"
        )));
    }
    if let (Some(eye), Some(look_at)) = (s.eye, s.look_at)
        && eye == look_at
    {
        return Err(Error::Invalid(format!(
            "camera eye {eye:?} equals look-at {look_at:?}: there is no view direction"
        )));
    }
    if let Some(a) = s.aperture {
        check_aperture(a)?;
    }
    if let Some(d) = s.focus_distance {
        check_focus_distance(d)?;
    }
    if let Some(p) = s.focus_on
        && !Vec3::from(p).is_finite()
    {
        return Err(Error::Invalid(format!(
            "focus_on {p:?} must be three finite numbers"
        )));
    }
    if s.focus_distance.is_some() && s.focus_on.is_some() {
        return Err(Error::Invalid(
            "give focus_distance or focus_on, not both: each sets the distance in focus".into(),
        ));
    }
    if let Some(h) = s.ortho_height {
        check_ortho_height(h)?;
    }
    Ok(())
}

fn check_resolution(width: u32, height: u32) -> Result<()> {
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 || v > MAX_RESOLUTION {
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

fn check_aperture(a: f32) -> Result<()> {
    if !(a >= 0.0 && a.is_finite()) {
        return Err(Error::Invalid(format!(
            "aperture {a} is out of range: it is the lens diameter in scene units, 0 (a \
             pinhole) or more"
        )));
    }
    Ok(())
}

fn check_focus_distance(d: f32) -> Result<()> {
    if !(d > 0.0 && d.is_finite()) {
        return Err(Error::Invalid(format!(
            "focus distance {d} is out of range: it must be a finite distance above 0, in \
             scene units"
        )));
    }
    Ok(())
}

fn check_ortho_height(h: f32) -> Result<()> {
    if !(h > 0.0 && h.is_finite()) {
        return Err(Error::Invalid(format!(
            "orthographic height {h} is out of range: it must be a finite height above 0, \
             in scene units"
        )));
    }
    Ok(())
}

/// The camera as kernels see it (`CAMERA_PARAMS` in `cl/camera.cl`, which mirrors these
/// methods operation for operation). At image position `(fx, fy)`, in pixels, the point
/// `pix = p0 + fx * du + fy * dv` is, for a perspective camera, the ray's direction
/// (unnormalised, forward component 1) from `eye`; for an orthographic one
/// (`forward.w` = 1), the ray leaves `eye + pix` along `forward`. A thin lens is open when
/// `lens_u.w`, the focus distance, is above 0: `lens_u` and `lens_v` are the lens radius
/// along the image's right and up.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Pinhole {
    pub(crate) eye: [f32; 4],
    pub(crate) p0: [f32; 4],
    pub(crate) du: [f32; 4],
    pub(crate) dv: [f32; 4],
    pub(crate) forward: [f32; 4],
    pub(crate) lens_u: [f32; 4],
    pub(crate) lens_v: [f32; 4],
}

impl Pinhole {
    /// The primary ray through the centre of pixel `(x, y)`, the lens ignored.
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        self.ray_at(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The ray through image position `(fx, fy)` in pixels, the lens ignored. No fused
    /// multiply-adds, in the same order as the kernel, so both produce the same bits.
    pub fn ray_at(&self, fx: f32, fy: f32) -> Ray {
        let pix = |k: usize| (self.p0[k] + fx * self.du[k]) + fy * self.dv[k];
        let p = Vec3::new(pix(0), pix(1), pix(2));
        let eye = Vec3::from_slice(&self.eye[..3]);
        if self.is_orthographic() {
            Ray::new(eye + p, Vec3::from_slice(&self.forward[..3]))
        } else {
            Ray::new(eye, p)
        }
    }

    /// Whether rays leave from the image plane, all in one direction, rather than from the
    /// eye.
    pub fn is_orthographic(&self) -> bool {
        self.forward[3] != 0.0
    }

    /// Whether the thin lens is open (rays need a lens sample).
    pub fn has_lens(&self) -> bool {
        self.lens_u[3] != 0.0
    }

    /// The ray through image position `(fx, fy)` from the lens point `(a, b)` of the
    /// unit disk: it leaves the lens there and passes where the pinhole ray meets the
    /// plane in focus, so that everything on that plane stays sharp. Without a lens, the
    /// pinhole ray.
    pub fn lens_ray(&self, fx: f32, fy: f32, (a, b): (f32, f32)) -> Ray {
        let ray = self.ray_at(fx, fy);
        if !self.has_lens() {
            return ray;
        }
        let off = |k: usize| self.lens_u[k] * a + self.lens_v[k] * b;
        let off = Vec3::new(off(0), off(1), off(2));
        Ray::new(ray.origin + off, ray.dir * self.lens_u[3] - off)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::from_points([Vec3::splat(-1.0), Vec3::splat(1.0)])
    }

    #[test]
    fn the_bench_view_follows_the_benchmark_protocol() {
        let b = Aabb::from_points([Vec3::new(0.0, 2.0, 0.0), Vec3::new(2.0, 4.0, 2.0)]);
        let c = Camera::bench(&b, 640, 480).unwrap();
        let r = 3f32.sqrt();
        let expected = Vec3::new(1.0, 3.0, 1.0 + r / 22.5f32.to_radians().sin());
        assert!((c.eye - expected).length() < 1e-5);
        assert_eq!(c.look_at, Vec3::new(1.0, 3.0, 1.0));
        assert_eq!(c.fov, 45.0);
    }

    #[test]
    fn centre_pixel_looks_at_the_target_and_corners_span_the_fov() {
        let c = Camera::bench(&unit_box(), 101, 51).unwrap();
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
    fn impossible_lenses_and_projections_are_refused() {
        let b = unit_box();
        let bad = |s: CameraSettings| Camera::from_settings(&s, &b).unwrap_err().to_string();
        let lens = |aperture, focus_distance| CameraSettings {
            aperture: Some(aperture),
            focus_distance,
            ..Default::default()
        };
        assert!(bad(lens(-0.1, None)).contains("aperture"));
        assert!(bad(lens(f32::NAN, None)).contains("aperture"));
        assert!(bad(lens(f32::INFINITY, None)).contains("aperture"));
        for d in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(bad(lens(0.1, Some(d))).contains("focus distance"), "{d}");
        }
        for h in [0.0, -1.0, f32::NAN] {
            let s = CameraSettings {
                projection: Some(Projection::Orthographic),
                ortho_height: Some(h),
                ..Default::default()
            };
            assert!(bad(s).contains("orthographic height"), "{h}");
        }
        assert!(
            bad(CameraSettings {
                focus_distance: Some(1.0),
                focus_on: Some([0.0; 3]),
                ..Default::default()
            })
            .contains("not both")
        );
        assert!(
            bad(CameraSettings {
                eye: Some([0.0, 0.0, 5.0]),
                look_at: Some([0.0; 3]),
                focus_on: Some([0.0, 0.0, 6.0]),
                ..Default::default()
            })
            .contains("not in front")
        );
        assert!(
            bad(CameraSettings {
                up: Some([0.0; 3]),
                ..Default::default()
            })
            .contains("up")
        );
    }

    #[test]
    fn the_focus_is_one_setting_across_layers() {
        let flags = CameraSettings {
            focus_distance: Some(2.0),
            ..Default::default()
        };
        let scene = CameraSettings {
            focus_on: Some([1.0, 2.0, 3.0]),
            aperture: Some(0.5),
            ..Default::default()
        };
        let s = flags.over(scene);
        assert_eq!((s.focus_distance, s.focus_on), (Some(2.0), None));
        assert_eq!(s.aperture, Some(0.5));
        let s = CameraSettings::default().over(scene);
        assert_eq!(
            (s.focus_distance, s.focus_on),
            (None, Some([1.0, 2.0, 3.0]))
        );
    }

    #[test]
    fn names_read_back() {
        for v in View::ALL {
            assert_eq!(v.name().parse::<View>(), Ok(v));
        }
        for p in Projection::ALL {
            assert_eq!(p.name().parse::<Projection>(), Ok(p));
        }
        assert!("top".parse::<View>().unwrap_err().contains("auto, bench"));
    }

    #[test]
    fn a_mesh_in_one_point_still_gets_a_camera() {
        let b = Aabb::from_points([Vec3::ONE]);
        for view in View::ALL {
            for projection in Projection::ALL {
                let s = CameraSettings {
                    view: Some(view),
                    projection: Some(projection),
                    ..Default::default()
                };
                let c = Camera::from_settings(&s, &b).unwrap();
                assert_ne!(c.eye, Vec3::ONE);
            }
        }
    }
}
