//! The Vulkan previewer (docs/design.md §8, docs/method.md §9): the cache splatted with ash, headless and in
//! a window.
//!
//! - [`device`]: the Vulkan device (lavapipe where there is no GPU).
//! - [`cut`]: the view-dependent cut of the surfel tree, and each node's radiance towards the
//!   eye.
//! - [`view`]: the camera as the shaders see it.
//! - [`renderer`]: the G-buffer, splat and resolve passes.
//! - [`window`]: the windowed mode (winit, ash-window) with an orbit camera.
//!
//! [`Preview`] ties them together: a cache (and optionally its scene) on a device, a frame per
//! camera.

pub mod cut;
pub mod device;
mod objects;
mod pipelines;
pub mod renderer;
mod swapchain;
mod transfer;
pub mod view;
pub mod window;

use crate::cache::store::BakedCache;
use crate::cache::CacheError;
use crate::gather::senders::Senders;
use crate::image::Image;
use crate::scene::{Camera, Scene};
use cut::{splats, view_cut, Colouring, Footprint, Splat};
use device::{Gpu, VulkanError};
use glam::Vec3;
use renderer::{FrameSettings, Renderer};
use std::sync::Arc;
use view::View;

/// What went wrong previewing a cache.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// The Vulkan device or a call to it.
    #[error(transparent)]
    Vulkan(#[from] VulkanError),
    /// The cache previewed.
    #[error(transparent)]
    Cache(#[from] CacheError),
    /// The window system (the message it gave).
    #[error("the preview window failed: {0}")]
    Window(String),
}

/// What a preview frame shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Show {
    /// Emitters, and the light the surfaces reflect splatted from the cache.
    Total,
    /// The reflected light only: everything the cache holds but emission. The cache does not
    /// keep the first bounce apart from the others, so direct light that surfaces reflect is
    /// part of it.
    Indirect,
    /// The emitters only, as the eye sees them.
    Direct,
    /// The surfels (cut nodes) as depth-tested discs of their outgoing radiance.
    Surfels,
    /// Each cut node in its own colour.
    Cut,
}

/// The default screen-space bound of the cut: nodes spanning at most this many pixels.
pub const DEFAULT_CUT_PIXELS: f32 = 2.0;

/// The box a preview looks into: the scene's, or without one the cache's surfels'.
pub fn bounds(cache: &BakedCache, scene: Option<&Scene>) -> (Vec3, Vec3) {
    match scene {
        Some(s) => s.bounds(),
        None => cache
            .surfels
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s.p.into()), hi.max(s.p.into()))
            }),
    }
}

/// A camera that frames `bounds` (none for an empty box).
pub fn framing_camera(bounds: (Vec3, Vec3), width: u32, height: u32) -> Option<Camera> {
    let (lo, hi) = bounds;
    lo.cmple(hi).all().then_some(())?;
    Camera::framing(0.5 * (lo + hi), 0.5 * (hi - lo).length(), width, height)
}

/// One drawn frame.
pub struct Frame {
    /// The frame read back.
    pub image: Image,
    /// Nodes in the cut (splats drawn).
    pub cut_size: usize,
    /// Seconds spent on the cut and its radiance (CPU), and drawing (GPU, with the readback).
    pub cut_seconds: f64,
    /// See `cut_seconds`.
    pub draw_seconds: f64,
}

/// A cache on a device, ready to draw frames.
pub struct Preview {
    senders: Senders,
    /// Per node: the mean disc radius of the surfels below.
    disc_radius: Vec<f32>,
    renderer: Renderer,
    /// The same at half the size, for frames while the camera moves.
    reduced: Renderer,
    has_scene: bool,
    bounds: (Vec3, Vec3),
}

impl Preview {
    /// Load `cache` (and `scene`'s meshes, whose G-buffer the splats land on; without them,
    /// the point-cloud view) onto `gpu` for frames of `size`.
    pub fn new(
        gpu: Arc<Gpu>,
        cache: &BakedCache,
        scene: Option<&Scene>,
        size: (u32, u32),
    ) -> Result<Preview, PreviewError> {
        let senders = Senders::from_cache(cache)?;
        let bounds = bounds(cache, scene);
        let disc_radius = cache
            .nodes
            .iter()
            .map(|n| (n.node.area / (n.node.count.max(1) as f32 * std::f32::consts::PI)).sqrt())
            .collect();
        Ok(Preview {
            senders,
            disc_radius,
            reduced: Renderer::new(gpu.clone(), reduced_size(size), scene)?,
            renderer: Renderer::new(gpu, size, scene)?,
            has_scene: scene.is_some(),
            bounds,
        })
    }

    /// The splats and pass settings of a frame: the cut for `camera` at `cut_pixels`, each
    /// node coloured for `show`.
    pub fn prepare(
        &self,
        camera: &Camera,
        show: Show,
        cut_pixels: f32,
    ) -> (View, Vec<Splat>, FrameSettings) {
        let view = View::new(camera.clone(), self.bounds);
        // The cut shows as discs: splats would blend neighbouring nodes' colours.
        let discs = !self.has_scene || matches!(show, Show::Surfels | Show::Cut);
        let (colouring, emission, splatted) = match (show, discs) {
            (Show::Direct, true) => (Colouring::Emitted, 0.0, 1.0),
            (Show::Direct, false) => (Colouring::Reflected, 1.0, 0.0),
            (Show::Indirect, _) => (Colouring::Reflected, 0.0, 1.0),
            (Show::Cut, _) => (Colouring::NodeId, 0.0, 1.0),
            (_, true) => (Colouring::Outgoing, 0.0, 1.0),
            (_, false) => (Colouring::Reflected, 1.0, 1.0),
        };
        let cut = if splatted > 0.0 {
            view_cut(&self.senders, &view, cut_pixels)
        } else {
            vec![]
        };
        let footprint = if discs {
            Footprint::Disc
        } else {
            Footprint::Splat
        };
        let splats = splats(
            &self.senders,
            &view,
            &cut,
            colouring,
            footprint,
            &self.disc_radius,
        );
        let settings = FrameSettings {
            emission,
            splats: splatted,
            discs,
        };
        (view, splats, settings)
    }

    /// Draw prepared splats, at the reduced size if `view`'s camera has it (see
    /// [`Preview::reduced_size`]).
    pub fn draw(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
    ) -> Result<Image, VulkanError> {
        self.renderer_for(view).render(view, splats, settings)
    }

    /// The size of frames drawn while the camera moves: half the size in each direction, a
    /// quarter of the fragments (lavapipe's cost is in the fragments, see docs/preview.md).
    pub fn reduced_size(&self) -> (u32, u32) {
        self.reduced.size()
    }

    fn renderer_for(&mut self, view: &View) -> &mut Renderer {
        let size = (view.camera.width, view.camera.height);
        if size == self.reduced.size() && size != self.renderer.size() {
            &mut self.reduced
        } else {
            &mut self.renderer
        }
    }

    /// Prepare and draw one frame.
    pub fn frame(
        &mut self,
        camera: &Camera,
        show: Show,
        cut_pixels: f32,
    ) -> Result<Frame, VulkanError> {
        let t = std::time::Instant::now();
        let (view, splats, settings) = self.prepare(camera, show, cut_pixels);
        let cut_seconds = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let image = self.draw(&view, &splats, settings)?;
        Ok(Frame {
            image,
            cut_size: splats.len(),
            cut_seconds,
            draw_seconds: t.elapsed().as_secs_f64(),
        })
    }

    /// The last frame's G-buffer (see [`Renderer::gbuffer`]).
    pub fn gbuffer(&mut self) -> Result<[Vec<[f32; 4]>; 3], VulkanError> {
        self.renderer.gbuffer()
    }

    /// The device it draws with.
    pub fn gpu(&self) -> &Gpu {
        self.renderer.gpu()
    }

    /// Draw prepared splats into a window's swapchain image (see [`Renderer::present`]), at
    /// the reduced size if `view`'s camera has it (scaled up by the blit).
    pub fn present(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
        target: &renderer::PresentTarget,
    ) -> Result<Option<Vec<u8>>, VulkanError> {
        self.renderer_for(view)
            .present(view, splats, settings, target)
    }

    /// Draw frames of another size from now on.
    pub(crate) fn resize(
        &mut self,
        size: (u32, u32),
        scene: Option<&Scene>,
    ) -> Result<(), VulkanError> {
        let gpu = self.renderer.gpu_arc();
        self.reduced = Renderer::new(gpu.clone(), reduced_size(size), scene)?;
        self.renderer = Renderer::new(gpu, size, scene)?;
        Ok(())
    }
}

/// Half of `size`, rounded up.
fn reduced_size((w, h): (u32, u32)) -> (u32, u32) {
    (w.div_ceil(2), h.div_ceil(2))
}
