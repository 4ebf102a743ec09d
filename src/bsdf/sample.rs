//! What every BSDF model returns and takes besides directions: the sampled direction with its
//! weight ([`BsdfSample`]), the lobe it came from, and the transport mode (radiance or
//! importance), which changes refraction only.

use crate::spectrum::Rgb;
use glam::Vec3;

/// What is being transported along the path (affects refraction only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TransportMode {
    /// Paths traced from the camera (the usual case).
    #[default]
    Radiance,
    /// Paths traced from the lights.
    Importance,
}

/// Which lobe a sample came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    /// Reflected to the side of `wi`.
    Reflection,
    /// Transmitted to the other side.
    Transmission,
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The sampled direction, in the local frame.
    pub wo: Vec3,
    /// Solid-angle density, lobe selection included.
    pub pdf: f32,
    /// Relative index of refraction crossed (1 for reflection).
    pub eta: f32,
    /// Which lobe it came from.
    pub lobe: Lobe,
    /// `eval / pdf`.
    pub weight: Rgb,
}
