//! Cameras: glTF conventions (looks down local −Z, +Y up, +X to image right; pixel (0, 0) is the
//! top-left pixel). A perspective camera's `yfov` is the vertical field of view for any aspect.

use glam::{Quat, Vec2, Vec3};

/// How a camera maps directions to the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A pinhole.
    Perspective {
        /// Vertical field of view in radians.
        yfov: f32,
    },
    /// Parallel rays.
    Orthographic {
        /// Half the view's width in world units.
        xmag: f32,
        /// Half its height.
        ymag: f32,
    },
}

/// A camera and the image it makes.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Its name in the scene (a glTF node's name, a USD prim path), as `--camera` takes it.
    pub name: String,
    /// The eye (world space).
    pub position: Vec3,
    /// Unit vectors: image right, image up, and the viewing direction.
    pub right: Vec3,
    /// See `right`.
    pub up: Vec3,
    /// See `right`.
    pub forward: Vec3,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// The largest image side any render takes (pixels).
    pub const MAX_SIDE: u32 = 16384;

    /// The image size (width, height) when neither the user nor the scene's render settings
    /// give one.
    pub const DEFAULT_SIZE: (u32, u32) = (512, 512);

    /// Refuse an image of `width` × `height` unless each side is from 1 to
    /// [`Camera::MAX_SIDE`], in one sentence.
    pub fn check_size(width: u32, height: u32) -> Result<(), String> {
        if (1..=Self::MAX_SIDE).contains(&width) && (1..=Self::MAX_SIDE).contains(&height) {
            Ok(())
        } else {
            Err(format!(
                "image size {width}x{height} must be between 1 and {} on each side",
                Self::MAX_SIDE
            ))
        }
    }

    /// A camera at `eye` looking at `target`, world +Y up (or +Z when looking along Y).
    pub fn look_at(
        name: &str,
        eye: Vec3,
        target: Vec3,
        yfov: f32,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = (target - eye).try_normalize()?;
        let world_up = if forward.y.abs() > 0.999 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let right = forward.cross(world_up).normalize();
        let up = right.cross(forward);
        Some(Camera {
            name: name.to_string(),
            position: eye,
            right,
            up,
            forward,
            projection: Projection::Perspective { yfov },
            width,
            height,
        })
    }

    /// A camera on +Z of a sphere (`center`, `radius`), looking at it, that frames it whole
    /// (40° vertical field of view).
    pub fn framing(center: Vec3, radius: f32, width: u32, height: u32) -> Option<Self> {
        let radius = radius.max(1e-6);
        let yfov = 40f32.to_radians();
        let aspect = (width as f32 / height as f32).min(1.0);
        let dist = 1.1 * radius / ((0.5 * yfov).tan() * aspect).atan().sin();
        Camera::look_at("auto", center + Vec3::Z * dist, center, yfov, width, height)
    }

    /// The point to orbit around: on the view axis, level with `centre` (the scene's), or
    /// one unit ahead where `centre` is behind the camera.
    pub(crate) fn orbit_target(&self, centre: Vec3) -> Vec3 {
        let reach = self.forward.dot(centre - self.position);
        self.position + self.forward * if reach > 0.0 { reach } else { 1.0 }
    }

    /// This camera turned around `target` by `yaw` about `up` and `pitch` about its right
    /// axis, still looking at `target` with `up` upwards; none where it would look along `up`.
    pub fn orbit(&self, target: Vec3, up: Vec3, yaw: f32, pitch: f32) -> Option<Camera> {
        let turn = Quat::from_axis_angle(up, yaw) * Quat::from_axis_angle(self.right, pitch);
        let eye = target + turn * (self.position - target);
        let forward = (target - eye).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        if forward.dot(up).abs() > 0.99 {
            return None;
        }
        Some(Camera {
            position: eye,
            right,
            up: right.cross(forward),
            forward,
            ..self.clone()
        })
    }

    /// The same camera rendering at another resolution.
    pub fn with_size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// OpenEXR's `worldToCamera`: row-major, for row vectors (p · M), into a camera space
    /// with x right, y up and the view along −z (Imath's convention).
    pub fn world_to_camera(&self) -> [f32; 16] {
        let e = self.position;
        let (x, y, z) = (self.right, self.up, -self.forward);
        [
            x.x,
            y.x,
            z.x,
            0.0, //
            x.y,
            y.y,
            z.y,
            0.0, //
            x.z,
            y.z,
            z.z,
            0.0, //
            -e.dot(x),
            -e.dot(y),
            -e.dot(z),
            1.0,
        ]
    }

    /// OpenEXR's `worldToNDC`, for row vectors: after the division by w, x and y run over
    /// [−1, 1] across the image's width and height (y up), as in [`Camera::generate_ray`];
    /// z/w is the reciprocal of the depth along the view (perspective) or the depth itself
    /// (orthographic).
    pub fn world_to_ndc(&self) -> [f32; 16] {
        let projection: [f32; 16] = match self.projection {
            Projection::Perspective { yfov } => {
                let t = (0.5 * yfov).tan();
                let aspect = self.width as f32 / self.height as f32;
                [
                    1.0 / (t * aspect),
                    0.0,
                    0.0,
                    0.0, //
                    0.0,
                    1.0 / t,
                    0.0,
                    0.0, //
                    0.0,
                    0.0,
                    0.0,
                    -1.0, //
                    0.0,
                    0.0,
                    1.0,
                    0.0,
                ]
            }
            Projection::Orthographic { xmag, ymag } => [
                1.0 / xmag,
                0.0,
                0.0,
                0.0, //
                0.0,
                1.0 / ymag,
                0.0,
                0.0, //
                0.0,
                0.0,
                -1.0,
                0.0, //
                0.0,
                0.0,
                0.0,
                1.0,
            ],
        };
        let a = glam::Mat4::from_cols_array(&self.world_to_camera());
        let b = glam::Mat4::from_cols_array(&projection);
        // Row-major arrays read as column-major are the transposes: (A·B)ᵀ = Bᵀ·Aᵀ.
        (b * a).to_cols_array()
    }

    /// Primary ray through film position `p` (in pixels, `[0, width) × [0, height)`):
    /// `(origin, unit direction)`.
    pub fn generate_ray(&self, p: Vec2) -> (Vec3, Vec3) {
        let aspect = self.width as f32 / self.height as f32;
        // Normalised device coordinates: x right, y up, in [-1, 1].
        let ndc = Vec2::new(
            2.0 * p.x / self.width as f32 - 1.0,
            1.0 - 2.0 * p.y / self.height as f32,
        );
        match self.projection {
            Projection::Perspective { yfov } => {
                let t = (0.5 * yfov).tan();
                let d = self.forward + self.right * (ndc.x * t * aspect) + self.up * (ndc.y * t);
                (self.position, d.normalize())
            }
            Projection::Orthographic { xmag, ymag } => {
                let o = self.position + self.right * (ndc.x * xmag) + self.up * (ndc.y * ymag);
                (o, self.forward)
            }
        }
    }
}

/// What a USD stage's `RenderSettings` prim (the first in the stage) and its first
/// `RenderProduct` ask of the image: the camera (a prim path, as [`Camera::name`]), the
/// resolution and the output's name. The product's own camera and resolution win over the
/// settings'. The command line takes each where its own option is not given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderProduct {
    /// The `RenderSettings` prim.
    pub settings: String,
    /// The camera prim it names, if any.
    pub camera: Option<String>,
    /// Its resolution (width, height), if it sets one.
    pub resolution: Option<(u32, u32)>,
    /// `productName`: the file the image goes to.
    pub name: Option<String>,
}
