//! Camera animation: the keyframes of a scene file (`[[camera.keyframe]]`), interpolated
//! linearly per value by frame number, or a turntable (`[camera.turntable]`) that turns the
//! camera about an axis through the point it looks at. `cltrace render --frames` renders
//! frames of it; without `--frames`, a render takes frame 0's camera.

use glam::{DVec3, Vec3};
use serde::Deserialize;

use crate::camera::{Camera, CameraSettings};
use crate::error::Result;
use crate::geometry::Aabb;

/// One camera key: the values it gives at its frame. Each value is interpolated between
/// the keys that give it, so a key may give some and leave the rest to the others.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Keyframe {
    /// The frame this key is at.
    pub(crate) frame: u32,
    pub(crate) eye: Option<[f32; 3]>,
    pub(crate) look_at: Option<[f32; 3]>,
    pub(crate) up: Option<[f32; 3]>,
    /// Vertical field of view, degrees.
    pub(crate) fov: Option<f32>,
}

/// A turn of the camera (eye and up) about an axis through its look-at point.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Turntable {
    /// Frames the turn of `degrees` takes: frame `frames` is turned by `degrees`.
    pub(crate) frames: u32,
    /// The axis, any length; `None`: the camera's up (so up stays as it is).
    pub(crate) axis: Option<[f32; 3]>,
    /// The angle of the whole turn, right-handed about the axis (negative: the other way).
    #[serde(default = "full_turn")]
    pub(crate) degrees: f32,
}

fn full_turn() -> f32 {
    360.0
}

/// A checked camera animation: keyframes in increasing frame order, or a turntable.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Animation(Motion);

#[derive(Clone, Debug, PartialEq)]
enum Motion {
    Keyframes(Vec<Keyframe>),
    Turntable(Turntable),
}

impl Animation {
    /// Keyframes, checked: at least one, frames strictly increasing, each giving a value,
    /// every value finite and the field of view in range. A bad key is named by its index.
    pub(crate) fn keyframes(keys: Vec<Keyframe>) -> std::result::Result<Self, (usize, String)> {
        if keys.is_empty() {
            return Err((0, "no keyframes: give [[camera.keyframe]] tables".into()));
        }
        for (i, key) in keys.iter().enumerate() {
            let f = key.frame;
            let at = |message: String| (i, format!("keyframe at frame {f}: {message}"));
            if i > 0 && f <= keys[i - 1].frame {
                return Err(at(format!(
                    "it comes after the keyframe at frame {}: keyframes must be in increasing \
                     frame order, each frame once",
                    keys[i - 1].frame
                )));
            }
            if key.eye.is_none() && key.look_at.is_none() && key.up.is_none() && key.fov.is_none() {
                return Err(at("it sets nothing: give eye, look_at, up or fov".into()));
            }
            for (name, v) in [("eye", key.eye), ("look_at", key.look_at), ("up", key.up)] {
                if v.is_some_and(|v| !v.iter().all(|c| c.is_finite())) {
                    return Err(at(format!("{name} must be three finite numbers")));
                }
            }
            crate::camera::check_settings(&CameraSettings {
                fov: key.fov,
                ..Default::default()
            })
            .map_err(|e| at(e.to_string()))?;
        }
        Ok(Animation(Motion::Keyframes(keys)))
    }

    /// A turntable, checked: at least one frame, a finite angle, a finite axis that is not
    /// zero.
    pub(crate) fn turntable(t: Turntable) -> std::result::Result<Self, String> {
        if t.frames == 0 {
            return Err("turntable frames = 0: the turn needs 1 frame or more".into());
        }
        if !t.degrees.is_finite() {
            return Err(format!(
                "turntable degrees = {}: give a finite angle",
                t.degrees
            ));
        }
        if let Some(axis) = t.axis {
            let a = Vec3::from(axis);
            if !a.is_finite() || a == Vec3::ZERO {
                return Err(format!(
                    "turntable axis {axis:?}: give three finite numbers, not all zero"
                ));
            }
        }
        Ok(Animation(Motion::Turntable(t)))
    }

    /// The camera settings of `frame`: the command line's `flags` over the animation over
    /// the scene's `[camera]` table. Keyframes give the values they key (a flag still wins,
    /// as over any scene setting); a turntable turns the camera that `flags`, the scene
    /// and the auto framing of `bounds` give together, so it can fail as that camera does.
    pub(crate) fn settings_at(
        &self,
        frame: u32,
        flags: &CameraSettings,
        scene: &CameraSettings,
        bounds: &Aabb,
    ) -> Result<CameraSettings> {
        match &self.0 {
            Motion::Keyframes(keys) => Ok(flags.over(keyed(keys, frame).over(*scene))),
            Motion::Turntable(t) => {
                let base = flags.over(*scene);
                let start = Camera::from_settings(&base, bounds)?;
                Ok(turned(t, frame, &start, &base))
            }
        }
    }
}

/// The values the keys give at `frame`; `None` for a value no key gives.
fn keyed(keys: &[Keyframe], frame: u32) -> CameraSettings {
    CameraSettings {
        eye: track(keys, frame, |k| k.eye),
        look_at: track(keys, frame, |k| k.look_at),
        up: track(keys, frame, |k| k.up),
        fov: track(keys, frame, |k| k.fov.map(|f| [f])).map(|[f]| f),
        ..Default::default()
    }
}

/// One value at `frame`, from the keys that give it (in increasing frame order): a key's
/// own value at its frame, linear between two keys, held before the first and after the
/// last.
fn track<const N: usize>(
    keys: &[Keyframe],
    frame: u32,
    value: impl Fn(&Keyframe) -> Option<[f32; N]>,
) -> Option<[f32; N]> {
    let mut before: Option<(u32, [f32; N])> = None;
    for key in keys {
        let Some(v) = value(key) else { continue };
        if key.frame == frame {
            return Some(v);
        }
        if key.frame < frame {
            before = Some((key.frame, v));
            continue;
        }
        let Some((f0, v0)) = before else {
            return Some(v);
        };
        // In f64, so that long gaps between keys lose nothing to the frame arithmetic.
        let t = (frame - f0) as f64 / (key.frame - f0) as f64;
        return Some(std::array::from_fn(|c| {
            let (a, b) = (v0[c] as f64, v[c] as f64);
            (a + (b - a) * t) as f32
        }));
    }
    before.map(|(_, v)| v)
}

/// `start` turned for `frame`: eye (and up, when the axis is not up itself) by
/// `degrees · frame / frames` about the axis through the look-at point. The projection
/// and lens stay those of `base`, the settings `start` was made from, except that an
/// orthographic height is `start`'s, so that an auto-fitted one does not change from
/// frame to frame.
fn turned(t: &Turntable, frame: u32, start: &Camera, base: &CameraSettings) -> CameraSettings {
    let settings = |eye: Vec3, up: Vec3| CameraSettings {
        eye: Some(eye.to_array()),
        look_at: Some(start.look_at.to_array()),
        up: Some(up.to_array()),
        fov: Some(start.fov),
        width: Some(start.width),
        height: Some(start.height),
        projection: Some(start.projection),
        ortho_height: (start.projection == crate::camera::Projection::Orthographic)
            .then_some(start.ortho_height),
        ..*base
    };
    // Whole turns are taken off first, so that frame `frames` of a full turn is exactly
    // frame 0, not its rounded rotation by 2π.
    let degrees = (t.degrees as f64 * frame as f64 / t.frames as f64).rem_euclid(360.0);
    if degrees == 0.0 {
        return settings(start.eye, start.up);
    }
    let axis = t
        .axis
        .map(Vec3::from)
        .unwrap_or(start.up)
        .as_dvec3()
        .normalize();
    let (sin, cos) = degrees.to_radians().sin_cos();
    // Rodrigues' rotation formula.
    let rotate = |v: DVec3| v * cos + axis.cross(v) * sin + axis * axis.dot(v) * (1.0 - cos);
    let centre = start.look_at.as_dvec3();
    let eye = (centre + rotate(start.eye.as_dvec3() - centre)).as_vec3();
    let up = match t.axis {
        None => start.up,
        Some(_) => rotate(start.up.as_dvec3()).as_vec3(),
    };
    settings(eye, up)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(frame: u32) -> Keyframe {
        Keyframe {
            frame,
            ..Default::default()
        }
    }

    /// Eye keys at frames 10 and 20 ([0, 0, 4] to [2, 4, 8]); fov only at frame 20.
    fn two_keys() -> Animation {
        Animation::keyframes(vec![
            Keyframe {
                eye: Some([0.0, 0.0, 4.0]),
                ..key(10)
            },
            Keyframe {
                eye: Some([2.0, 4.0, 8.0]),
                fov: Some(30.0),
                ..key(20)
            },
        ])
        .unwrap()
    }

    fn unit_box() -> Aabb {
        Aabb::from_points([Vec3::splat(-1.0), Vec3::splat(1.0)])
    }

    fn at(a: &Animation, frame: u32) -> CameraSettings {
        a.settings_at(
            frame,
            &CameraSettings::default(),
            &CameraSettings::default(),
            &unit_box(),
        )
        .unwrap()
    }

    #[test]
    fn keyframes_are_met_at_their_frames_and_interpolated_between() {
        let a = two_keys();
        assert_eq!(at(&a, 10).eye, Some([0.0, 0.0, 4.0]));
        assert_eq!(at(&a, 20).eye, Some([2.0, 4.0, 8.0]));
        assert_eq!(at(&a, 15).eye, Some([1.0, 2.0, 6.0]));
        let e = at(&a, 11).eye.unwrap();
        assert!(
            (Vec3::from(e) - Vec3::new(0.2, 0.4, 4.4)).length() < 1e-6,
            "{e:?}"
        );
    }

    #[test]
    fn keyframes_hold_before_the_first_and_after_the_last() {
        let a = two_keys();
        assert_eq!(at(&a, 0).eye, Some([0.0, 0.0, 4.0]));
        assert_eq!(at(&a, 9).eye, Some([0.0, 0.0, 4.0]));
        assert_eq!(at(&a, 21).eye, Some([2.0, 4.0, 8.0]));
        assert_eq!(at(&a, u32::MAX).eye, Some([2.0, 4.0, 8.0]));
    }

    #[test]
    fn each_value_follows_only_the_keys_that_give_it() {
        let a = two_keys();
        // fov is keyed once: held everywhere, even where the eye moves.
        assert_eq!(at(&a, 0).fov, Some(30.0));
        assert_eq!(at(&a, 15).fov, Some(30.0));
        // No key gives look_at or up: the scene's value, else the auto framing's.
        assert_eq!(at(&a, 15).look_at, None);
        let scene = CameraSettings {
            look_at: Some([0.0, 1.0, 0.0]),
            eye: Some([9.0, 9.0, 9.0]),
            width: Some(64),
            ..Default::default()
        };
        let s = a
            .settings_at(15, &CameraSettings::default(), &scene, &unit_box())
            .unwrap();
        assert_eq!(s.look_at, Some([0.0, 1.0, 0.0]));
        assert_eq!(s.width, Some(64));
        // A keyed value beats the scene's, and a flag beats the key.
        assert_eq!(s.eye, Some([1.0, 2.0, 6.0]));
        let flags = CameraSettings {
            eye: Some([5.0, 5.0, 5.0]),
            ..Default::default()
        };
        let s = a.settings_at(15, &flags, &scene, &unit_box()).unwrap();
        assert_eq!(s.eye, Some([5.0, 5.0, 5.0]));
        assert_eq!(s.fov, Some(30.0));
    }

    #[test]
    fn a_value_keyed_by_the_middle_key_alone_interpolates_across_the_others() {
        let a = Animation::keyframes(vec![
            Keyframe {
                fov: Some(40.0),
                ..key(0)
            },
            Keyframe {
                eye: Some([0.0, 0.0, 5.0]),
                ..key(5)
            },
            Keyframe {
                fov: Some(60.0),
                ..key(10)
            },
        ])
        .unwrap();
        assert_eq!(at(&a, 5).fov, Some(50.0));
        assert_eq!(at(&a, 0).eye, Some([0.0, 0.0, 5.0]));
    }

    #[test]
    fn bad_keyframes_are_refused_naming_the_key() {
        let err = |keys: Vec<Keyframe>| Animation::keyframes(keys).unwrap_err();
        let eye = |frame| Keyframe {
            eye: Some([0.0, 0.0, 1.0]),
            ..key(frame)
        };
        let (i, m) = err(vec![eye(5), eye(8), eye(3)]);
        assert_eq!(i, 2);
        assert!(m.contains("frame 3") && m.contains("increasing"), "{m}");
        let (i, m) = err(vec![eye(5), eye(5)]);
        assert_eq!(i, 1);
        assert!(m.contains("increasing"), "{m}");
        let (i, m) = err(vec![eye(0), key(4)]);
        assert_eq!(i, 1);
        assert!(m.contains("sets nothing"), "{m}");
        let (_, m) = err(vec![Keyframe {
            fov: Some(180.0),
            ..key(0)
        }]);
        assert!(m.contains("field of view"), "{m}");
        let (_, m) = err(vec![Keyframe {
            up: Some([0.0, f32::NAN, 0.0]),
            ..key(0)
        }]);
        assert!(m.contains("up must be three finite numbers"), "{m}");
        assert!(err(vec![]).1.contains("no keyframes"));
        assert!(Animation::keyframes(vec![eye(0), eye(1), eye(7)]).is_ok());
    }

    fn turntable(frames: u32, degrees: f32, axis: Option<[f32; 3]>) -> Animation {
        Animation::turntable(Turntable {
            frames,
            axis,
            degrees,
        })
        .unwrap()
    }

    /// The eye [0, 2, 4] looking at [0, 1, 0], as the scene's camera.
    fn scene() -> CameraSettings {
        CameraSettings {
            eye: Some([0.0, 2.0, 4.0]),
            look_at: Some([0.0, 1.0, 0.0]),
            ..Default::default()
        }
    }

    fn turned_at(a: &Animation, frame: u32) -> CameraSettings {
        a.settings_at(frame, &CameraSettings::default(), &scene(), &unit_box())
            .unwrap()
    }

    fn close(a: [f32; 3], b: [f32; 3]) -> bool {
        (Vec3::from(a) - Vec3::from(b)).length() < 1e-5
    }

    #[test]
    fn a_turntable_starts_at_the_camera_and_a_full_turn_ends_there_exactly() {
        let a = turntable(120, 360.0, None);
        let start = turned_at(&a, 0);
        assert_eq!(start.eye, Some([0.0, 2.0, 4.0]));
        assert_eq!(start.look_at, Some([0.0, 1.0, 0.0]));
        assert_eq!(start.up, Some([0.0, 1.0, 0.0]));
        assert_eq!(turned_at(&a, 120), start);
        assert_eq!(turned_at(&a, 240), start);
        assert_ne!(turned_at(&a, 1), start);
    }

    #[test]
    fn a_turntable_turns_right_handed_about_up_through_the_look_at_point() {
        let a = turntable(4, 360.0, None);
        // A quarter turn about +y takes +z to +x; the height and distance stay.
        let quarter = turned_at(&a, 1);
        assert!(close(quarter.eye.unwrap(), [4.0, 2.0, 0.0]), "{quarter:?}");
        assert!(close(turned_at(&a, 2).eye.unwrap(), [0.0, 2.0, -4.0]));
        assert_eq!(quarter.up, Some([0.0, 1.0, 0.0]));
        assert_eq!(quarter.look_at, Some([0.0, 1.0, 0.0]));
        // Negative degrees turn the other way; part turns reach their angle at `frames`.
        let back = turntable(2, -90.0, None);
        assert!(close(turned_at(&back, 2).eye.unwrap(), [-4.0, 2.0, 0.0]));
        assert!(close(
            turned_at(&back, 1).eye.unwrap(),
            [-4.0 * 0.5f32.sqrt(), 2.0, 4.0 * 0.5f32.sqrt()]
        ));
    }

    #[test]
    fn a_turntable_about_another_axis_turns_up_with_the_eye() {
        // A quarter turn about +z: the eye [0, 2, 4] around [0, 1, 0] goes to [-1, 1, 4],
        // and up +y to -x.
        let a = turntable(1, 90.0, Some([0.0, 0.0, 3.0]));
        let s = turned_at(&a, 1);
        assert!(close(s.eye.unwrap(), [-1.0, 1.0, 4.0]), "{s:?}");
        assert!(close(s.up.unwrap(), [-1.0, 0.0, 0.0]), "{s:?}");
    }

    #[test]
    fn a_turntable_starts_from_the_auto_framing_and_the_flags() {
        let a = turntable(4, 360.0, None);
        let none = CameraSettings::default();
        let auto = Camera::from_settings(&none, &unit_box()).unwrap();
        let s = a.settings_at(0, &none, &none, &unit_box()).unwrap();
        assert_eq!(s.eye, Some(auto.eye.to_array()));
        assert_eq!(s.look_at, Some(auto.look_at.to_array()));
        assert_eq!(s.fov, Some(auto.fov));
        // A flag's eye is where the turn starts.
        let flags = CameraSettings {
            eye: Some([0.0, 1.0, 7.0]),
            fov: Some(30.0),
            ..Default::default()
        };
        let s = a.settings_at(1, &flags, &scene(), &unit_box()).unwrap();
        assert!(close(s.eye.unwrap(), [7.0, 1.0, 0.0]), "{s:?}");
        assert_eq!(s.fov, Some(30.0));
        // A camera that cannot be is the frame's error.
        let flags = CameraSettings {
            eye: Some([0.0, 1.0, 0.0]),
            ..Default::default()
        };
        let e = a.settings_at(1, &flags, &scene(), &unit_box()).unwrap_err();
        assert!(e.to_string().contains("equals look-at"), "{e}");
    }

    #[test]
    fn bad_turntables_are_refused() {
        let err = |frames, degrees, axis| {
            Animation::turntable(Turntable {
                frames,
                axis,
                degrees,
            })
            .unwrap_err()
        };
        assert!(err(0, 360.0, None).contains("frames = 0"));
        assert!(err(10, f32::INFINITY, None).contains("finite angle"));
        assert!(err(10, 360.0, Some([0.0; 3])).contains("not all zero"));
        assert!(err(10, 360.0, Some([f32::NAN, 1.0, 0.0])).contains("finite"));
    }
}
