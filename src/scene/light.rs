//! Punctual lights (KHR_lights_punctual). Units follow Mitsuba's `point` emitter: a point or
//! spot light's `intensity × color` is its radiant intensity (W/sr), a directional light's is the
//! irradiance it delivers (W/m²) on a surface facing it.

use crate::spectrum::Rgb;
use glam::Vec3;

/// What shape of light a punctual light sends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// The same intensity every way.
    Point,
    /// A cone with a smooth edge.
    Spot {
        /// Cosine of the inner cone angle (full intensity inside).
        cos_inner: f32,
        /// Cosine of the outer cone angle (nothing outside).
        cos_outer: f32,
    },
    /// Parallel light from infinitely far.
    Directional,
}

/// A light of no extent (KHR_lights_punctual; UsdLux's distant lights).
#[derive(Clone, Debug, PartialEq)]
pub struct PunctualLight {
    /// Its name in the scene (the node's or prim's).
    pub name: String,
    /// Point, spot or directional.
    pub kind: LightKind,
    /// Where it is (unused for directional lights).
    pub position: Vec3,
    /// Unit direction the light shines towards (the node's −Z axis).
    pub direction: Vec3,
    /// `intensity × color`: radiant intensity (W/sr), or irradiance (W/m²) for a directional
    /// light.
    pub intensity: Rgb,
}

impl PunctualLight {
    /// Angular falloff of a spot light for emission direction `w` (glTF's smooth falloff).
    pub(crate) fn falloff(&self, w: Vec3) -> f32 {
        match self.kind {
            LightKind::Spot {
                cos_inner,
                cos_outer,
            } => {
                let c = w.dot(self.direction);
                let t = ((c - cos_outer) / (cos_inner - cos_outer).max(1e-6)).clamp(0.0, 1.0);
                t * t
            }
            _ => 1.0,
        }
    }
}
