//! The lights of a scene besides its emitting triangles (which are materials: see
//! [`crate::material`]): an environment at infinity ([`environment`]: an image, a
//! constant colour, or the sun and sky of [`sky`] baked into one) and lights without area
//! ([`punctual`]: point, spot, directional). The path tracer samples each kind on every
//! bounce: one point of the emitting triangles (chosen by power), one direction of the
//! environment, and every punctual light.

pub mod environment;
pub mod punctual;
pub mod sky;

pub use environment::Environment;
pub use punctual::Punctual;

/// What lights a scene beyond its emitters; without any of it (and without emitters) the
/// path tracer's rays that leave the scene see the default sky.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lights {
    /// Light from every direction at infinity, if any.
    pub environment: Option<Environment>,
    /// Point, spot and directional lights.
    pub punctual: Vec<Punctual>,
}

impl Lights {
    /// Whether the scene has any of these lights: then the default sky is off.
    pub fn any(&self) -> bool {
        self.environment.is_some() || !self.punctual.is_empty()
    }

    /// Bytes the lights take on the device.
    pub fn bytes(&self) -> u64 {
        self.environment.as_ref().map_or(0, Environment::bytes) + 64 * self.punctual.len() as u64
    }

    /// The punctual lights as the kernels read them, four float4 each.
    pub fn packed(&self) -> Vec<[[f32; 4]; 4]> {
        self.punctual.iter().map(Punctual::pack).collect()
    }
}
