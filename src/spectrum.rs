//! RGB radiometric quantities.
//!
//! The renderer works in linear RGB (Mitsuba's `*_rgb` variants): a radiance, a BSDF value and a
//! throughput are all `Rgb`, which is `glam::Vec3` under a name that says what it holds.

/// Linear RGB triple (radiance, reflectance, throughput).
pub type Rgb = glam::Vec3;

/// Largest component, the quantity Mitsuba uses for Russian roulette.
#[inline]
pub(crate) fn max_component(c: Rgb) -> f32 {
    c.x.max(c.y).max(c.z)
}

/// Rec. 709 luminance's weights of red, green and blue.
pub const LUMINANCE: [f32; 3] = [0.212_671, 0.715_160, 0.072_169];

/// Rec. 709 luminance.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    LUMINANCE[0] * c.x + LUMINANCE[1] * c.y + LUMINANCE[2] * c.z
}
