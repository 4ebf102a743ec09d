//! The camera as the previewer's shaders see it: the per-frame uniforms (`frame.glsl`) and the
//! frustum that culls the cut (docs/design.md §8).
//!
//! Clip space is Vulkan's: x right, y down, with depth reversed (1 at the near plane, 0 at the
//! far one), which float depth resolves evenly over the range: with the usual mapping, a
//! light 1 mm under a ceiling fought with it 4 m away. Pixel (x, y)'s centre is the film
//! point (x + 0.5, y + 0.5) of [`Camera::generate_ray`], so the preview and the final render
//! see the same rays.

use crate::scene::{Camera, Projection};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

/// `frame.glsl`'s `Frame` block (std140: every member a vec4 or a column-major mat4).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct FrameUniforms {
    /// World to clip space.
    pub view_proj: [[f32; 4]; 4],
    /// The eye (w = 1).
    pub eye: [f32; 4],
    /// The camera's right, up and forward unit vectors (w = 0).
    pub right: [f32; 4],
    /// See `right`.
    pub up: [f32; 4],
    /// See `right`.
    pub forward: [f32; 4],
    /// Emission scale, splat scale, [`W_MIN`], [`W_MAX`].
    pub params: [f32; 4],
}

/// The splat weight's threshold: Gautron et al.'s w > 1, i.e. ‖p − p_k‖ < R where normals
/// agree (docs/method.md §9). The shader subtracts it, so that a splat's weight falls to zero at its rim
/// and pixels do not pop where a footprint ends.
pub const W_MIN: f32 = 1.0;

/// The weight's cap: a pixel at a node's centre would weigh infinitely.
pub const W_MAX: f32 = 1e4;

/// A camera for the previewer, with the depth range of what it looks at.
#[derive(Clone, Debug)]
pub struct View {
    /// The camera.
    pub camera: Camera,
    /// The near and far depth of what it looks at.
    pub near: f32,
    /// See `near`.
    pub far: f32,
}

impl View {
    /// `camera` looking at a scene inside the box `bounds`: the depth range covers the box.
    pub fn new(camera: Camera, bounds: (Vec3, Vec3)) -> View {
        let (lo, hi) = bounds;
        let far = (0..8)
            .map(|i| {
                let corner = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                camera.forward.dot(corner - camera.position)
            })
            .fold(0.0f32, f32::max);
        let far = if far.is_finite() && far > 0.0 {
            far * 1.01
        } else {
            1.0
        };
        View {
            camera,
            near: far * 1e-4,
            far,
        }
    }

    /// Whether the camera is a pinhole (not orthographic).
    pub(crate) fn is_perspective(&self) -> bool {
        matches!(self.camera.projection, Projection::Perspective { .. })
    }

    /// World to clip space.
    pub(crate) fn view_proj(&self) -> Mat4 {
        let c = &self.camera;
        let aspect = c.width as f32 / c.height as f32;
        let row = |axis: Vec3, scale: f32, offset: f32| {
            (axis * scale).extend(-(axis * scale).dot(c.position) + offset)
        };
        let rows = match c.projection {
            Projection::Perspective { yfov } => {
                let t = (0.5 * yfov).tan();
                // Reversed depth: near → 1, far → 0.
                let a = self.near / (self.far - self.near);
                [
                    row(c.right, 1.0 / (t * aspect), 0.0),
                    row(c.up, -1.0 / t, 0.0),
                    row(c.forward, -a, a * self.far),
                    row(c.forward, 1.0, 0.0),
                ]
            }
            Projection::Orthographic { xmag, ymag } => {
                let depth = 1.0 / (self.far - self.near);
                [
                    row(c.right, 1.0 / xmag, 0.0),
                    row(c.up, -1.0 / ymag, 0.0),
                    row(c.forward, -depth, self.far * depth),
                    Vec4::W,
                ]
            }
        };
        Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose()
    }

    /// The uniforms of a frame that shows `emission` times the emitters and `splats` times
    /// the splatted radiance.
    pub(crate) fn uniforms(&self, emission: f32, splats: f32) -> FrameUniforms {
        let c = &self.camera;
        FrameUniforms {
            view_proj: self.view_proj().to_cols_array_2d(),
            eye: c
                .position
                .extend(if self.is_perspective() { 1.0 } else { 0.0 })
                .to_array(),
            right: c.right.extend(0.0).to_array(),
            up: c.up.extend(0.0).to_array(),
            forward: c.forward.extend(0.0).to_array(),
            params: [emission, splats, W_MIN, W_MAX],
        }
    }

    /// The unit direction from `p` towards the eye.
    pub(crate) fn towards_eye(&self, p: Vec3) -> Vec3 {
        if self.is_perspective() {
            (self.camera.position - p).normalize_or(-self.camera.forward)
        } else {
            -self.camera.forward
        }
    }

    /// How many pixels the diameter of a sphere (`centre`, `radius`) covers on screen, at
    /// most; infinite when the eye is inside it.
    pub(crate) fn pixels_across(&self, centre: Vec3, radius: f32) -> f32 {
        let c = &self.camera;
        match c.projection {
            Projection::Perspective { yfov } => {
                let d = (centre - c.position).length() - radius;
                if d <= 0.0 {
                    return f32::INFINITY;
                }
                let focal = 0.5 * c.height as f32 / (0.5 * yfov).tan();
                2.0 * radius * focal / d
            }
            Projection::Orthographic { ymag, .. } => radius * c.height as f32 / ymag,
        }
    }

    /// Whether a sphere lies wholly outside the view frustum's sides or behind the eye.
    pub(crate) fn culls(&self, centre: Vec3, radius: f32) -> bool {
        let c = &self.camera;
        let v = centre - c.position;
        let (x, y, z) = (c.right.dot(v), c.up.dot(v), c.forward.dot(v));
        match c.projection {
            Projection::Perspective { yfov } => {
                let t = (0.5 * yfov).tan();
                let ta = t * c.width as f32 / c.height as f32;
                // Each side plane through the eye, outward normal (±1, 0, −t·a) normalised.
                let side = |u: f32, slope: f32| (u - slope * z) / (1.0 + slope * slope).sqrt();
                z < -radius
                    || side(x, ta) > radius
                    || side(-x, ta) > radius
                    || side(y, t) > radius
                    || side(-y, t) > radius
            }
            Projection::Orthographic { xmag, ymag } => {
                z < -radius || x.abs() > xmag + radius || y.abs() > ymag + radius
            }
        }
    }
}
