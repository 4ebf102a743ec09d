//! Punctual lights (KHR_lights_punctual). Units follow Mitsuba's `point` emitter: a point or
//! spot light's `intensity × color` is its radiant intensity (W/sr), a directional light's is the
//! irradiance it delivers (W/m²) on a surface facing it.

use crate::spectrum::Rgb;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cosines of the inner and outer cone angles.
    Spot {
        cos_inner: f32,
        cos_outer: f32,
    },
    Directional,
}

#[derive(Clone, Debug, PartialEq)]
pub struct PunctualLight {
    pub name: String,
    pub kind: LightKind,
    pub position: Vec3,
    /// Unit direction the light shines towards (the node's −Z axis).
    pub direction: Vec3,
    pub intensity: Rgb,
}

impl PunctualLight {
    /// Angular falloff of a spot light for emission direction `w` (glTF's smooth falloff).
    pub fn falloff(&self, w: Vec3) -> f32 {
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
