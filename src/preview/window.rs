//! The windowed preview (docs/design.md §8): winit 0.30 and ash-window, an orbit camera, and the
//! cut refined while the camera rests.
//!
//! - Left drag orbits the camera around its target, right or middle drag pans, the wheel
//!   zooms; keys 1–5 (or t, i, d, s, c) switch what is shown, r returns to the start, Esc or
//!   q quits.
//! - The first frame after the camera moves is drawn at half the size (scaled up by the
//!   blit) with a cut [`MOVING_COARSENESS`] times coarser than asked; at rest the frames are
//!   full size and the cut halves every frame down to the asked bound.
//! - The title shows what is shown, the frame time and the cut's size.
//! - e starts an edit of the scene in the `--set` syntax, typed into the title; Enter hands it
//!   to the caller's relighter, which returns the edited scene and its cache, and the window
//!   goes on with them (Esc drops the edit). The window does not relight itself: that is the
//!   bake's work, which the preview does not import.
//! - A scripted run (`frames`) orbits once around the target and ends where it started, then
//!   refines, optionally reads the swapchain image back as a screenshot, and exits: what the
//!   tests run under Xvfb.

use super::device::Gpu;
use super::renderer::PresentTarget;
use super::swapchain::Swapchain;
use super::{Preview, PreviewError, Show};
use crate::cache::store::BakedCache;
use crate::scene::{Camera, Scene};
use ash::vk;
use glam::Vec3;
use std::path::PathBuf;
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

/// How much coarser the cut is while the camera moves.
pub const MOVING_COARSENESS: f32 = 8.0;

/// What a windowed run does.
#[derive(Clone, Debug)]
pub struct WindowSettings {
    /// What the splats show (the cache's light, or a diagnostic).
    pub show: Show,
    /// The cut's target: the largest a node may look on screen, in pixels.
    pub cut_pixels: f32,
    /// A scripted run of this many frames (then refinement), instead of an interactive one.
    pub frames: Option<u32>,
    /// Read the last frame back from the swapchain into this PNG.
    pub screenshot: Option<PathBuf>,
    /// Run under the Vulkan validation layer and collect its messages.
    pub validate: bool,
    /// A scripted run applies this edit before its first frame, as typing it would.
    pub edit: Option<String>,
}

/// What the window calls to apply an edit the user typed: given the scene and cache it shows
/// and the edit (`--set` syntax), the edited scene and its cache, or why not in one sentence.
pub type Relighter<'a> =
    &'a mut dyn FnMut(&Scene, &BakedCache, &str) -> Result<(Scene, BakedCache), String>;

/// What a windowed run did.
#[derive(Clone, Debug, Default)]
pub struct WindowReport {
    /// The device's name.
    pub device: String,
    /// Frames drawn.
    pub frames: u32,
    /// Splats in the last frame's cut.
    pub last_cut_size: usize,
    /// Seconds the last cut took on the CPU.
    pub last_cut_seconds: f64,
    /// Seconds the last frame took to draw.
    pub last_draw_seconds: f64,
    /// The validation layer's messages (with `validate`).
    pub validation: Vec<String>,
}

/// Open a window on the cache (and its scene) seen by `camera`, whose size is the window's,
/// and run until it is closed or the script ends. With a scene, `relighter` applies the edits
/// typed into the window (key e).
pub fn run_window<'a>(
    cache: &'a BakedCache,
    scene: Option<&'a Scene>,
    camera: Camera,
    settings: &WindowSettings,
    relighter: Option<Relighter<'a>>,
) -> Result<WindowReport, PreviewError> {
    let event_loop = EventLoop::new().map_err(|e| PreviewError::Window(e.to_string()))?;
    let bounds = super::bounds(cache, scene);
    let target = camera.orbit_target(0.5 * (bounds.0 + bounds.1));
    let mut app = App {
        cache,
        scene,
        settings: settings.clone(),
        show: settings.show,
        home: (camera.clone(), target),
        camera,
        target,
        cut_now: settings.cut_pixels * MOVING_COARSENESS,
        running: None,
        drag: None,
        cursor: (0.0, 0.0),
        report: WindowReport::default(),
        error: None,
        relighter,
        relit: None,
        editing: None,
        notice: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| PreviewError::Window(e.to_string()))?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if let Some(r) = &app.running {
        app.report.validation = r.gpu.validation_messages();
    }
    Ok(app.report)
}

/// The Vulkan side of an open window. Fields drop in order: the swapchain (and its surface)
/// before the window.
struct Running {
    swapchain: Swapchain,
    preview: Preview,
    gpu: Arc<Gpu>,
    window: Window,
}

struct App<'a> {
    cache: &'a BakedCache,
    scene: Option<&'a Scene>,
    /// Applies typed edits (see [`Relighter`]).
    relighter: Option<Relighter<'a>>,
    /// The edited scene and its cache, once an edit was applied: shown instead of the
    /// originals.
    relit: Option<(Scene, BakedCache)>,
    /// The edit being typed.
    editing: Option<String>,
    /// What the last edit did, for the title.
    notice: Option<String>,
    settings: WindowSettings,
    show: Show,
    /// The starting camera and orbit target.
    home: (Camera, Vec3),
    camera: Camera,
    target: Vec3,
    /// The cut's bound for the next frame.
    cut_now: f32,
    running: Option<Running>,
    drag: Option<MouseButton>,
    cursor: (f64, f64),
    report: WindowReport,
    error: Option<PreviewError>,
}

impl App<'_> {
    /// The scene and cache shown: the last edit's, else the originals.
    fn shown(&self) -> (Option<&Scene>, &BakedCache) {
        match &self.relit {
            Some((scene, cache)) => (Some(scene), cache),
            None => (self.scene, self.cache),
        }
    }

    /// Apply `edit` through the relighter and show its scene and cache; a refusal goes to the
    /// title (and, in a scripted run, ends it with the error).
    fn apply_edit(&mut self, edit: &str) -> Result<(), PreviewError> {
        let Some(relight) = self.relighter.take() else {
            return Err(PreviewError::Window(
                "this window cannot apply edits".into(),
            ));
        };
        let result = match self.shown() {
            (Some(scene), cache) => relight(scene, cache, edit),
            (None, _) => Err("an edit needs the scene (--scene)".to_string()),
        };
        self.relighter = Some(relight);
        match result {
            Ok(relit) => {
                if let Some(r) = self.running.as_mut() {
                    r.preview =
                        Preview::new(r.gpu.clone(), &relit.1, Some(&relit.0), r.swapchain.extent)?;
                }
                self.relit = Some(relit);
                self.notice = Some(format!("applied {edit}"));
            }
            Err(why) if self.settings.frames.is_some() => return Err(PreviewError::Window(why)),
            Err(why) => self.notice = Some(why),
        }
        self.moved();
        Ok(())
    }

    /// The title while an edit is typed.
    fn show_editing(&self) {
        if let (Some(r), Some(text)) = (&self.running, &self.editing) {
            r.window
                .set_title(&format!("edit: {text}_   (Enter: apply, Esc: cancel)"));
        }
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), PreviewError> {
        let size = PhysicalSize::new(self.camera.width, self.camera.height);
        let window = event_loop
            .create_window(
                Window::default_attributes()
                    .with_title("wpbgi preview")
                    .with_inner_size(size)
                    .with_resizable(self.settings.frames.is_none()),
            )
            .map_err(|e| PreviewError::Window(e.to_string()))?;
        let handle_error = |e: winit::raw_window_handle::HandleError| {
            PreviewError::Window(format!("the window has no handle: {e}"))
        };
        let display = window.display_handle().map_err(handle_error)?.as_raw();
        let window_handle = window.window_handle().map_err(handle_error)?.as_raw();
        let gpu = Arc::new(Gpu::for_window(self.settings.validate, display)?);
        let inner = window.inner_size();
        let swapchain = Swapchain::new(
            gpu.clone(),
            display,
            window_handle,
            (inner.width.max(1), inner.height.max(1)),
        )?;
        if self.settings.screenshot.is_some() && !swapchain.readable {
            return Err(PreviewError::Window(
                "this window's images cannot be read back for a screenshot".into(),
            ));
        }
        self.camera = self
            .camera
            .clone()
            .with_size(swapchain.extent.0, swapchain.extent.1);
        let (scene, cache) = self.shown();
        let preview = Preview::new(gpu.clone(), cache, scene, swapchain.extent)?;
        self.report.device = gpu.name.clone();
        self.running = Some(Running {
            swapchain,
            preview,
            gpu,
            window,
        });
        if let Some(edit) = self.settings.edit.clone() {
            self.apply_edit(&edit)?;
        }
        Ok(())
    }

    /// Draw and present one frame; with `screenshot`, write it out. Returns whether a frame
    /// was presented.
    fn draw(&mut self, screenshot: bool) -> Result<bool, PreviewError> {
        let Some(r) = self.running.as_mut() else {
            return Ok(false);
        };
        let t = std::time::Instant::now();
        // The first frame after a move is drawn at half the size (a quarter of the fragments)
        // with a cut as coarse on screen; refining frames at full size.
        let moving = self.cut_now >= MOVING_COARSENESS * self.settings.cut_pixels;
        let (camera, cut) = if moving {
            let (w, h) = r.preview.reduced_size();
            let scale = h as f32 / self.camera.height as f32;
            (self.camera.clone().with_size(w, h), self.cut_now * scale)
        } else {
            (self.camera.clone(), self.cut_now)
        };
        let (view, splats, settings) = r.preview.prepare(&camera, self.show, cut);
        let cut_seconds = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let Some(index) = r.swapchain.acquire()? else {
            self.resize()?;
            return Ok(false);
        };
        let target = PresentTarget {
            image: r.swapchain.images[index as usize],
            acquired: r.swapchain.acquired,
            rendered: r.swapchain.rendered[index as usize],
            size: r.swapchain.extent,
            screenshot,
        };
        let pixels = r.preview.present(&view, &splats, settings, &target)?;
        let fits = r.swapchain.present(index)?;
        let draw_seconds = t.elapsed().as_secs_f64();
        self.report.frames += 1;
        self.report.last_cut_size = splats.len();
        self.report.last_cut_seconds = cut_seconds;
        self.report.last_draw_seconds = draw_seconds;
        if self.editing.is_none() {
            r.window.set_title(&format!(
                "wpbgi preview: {:?}, {:.0} ms, cut of {} nodes ({} px{}){}",
                self.show,
                1e3 * (cut_seconds + draw_seconds),
                splats.len(),
                self.cut_now,
                if moving { ", half size" } else { "" },
                self.notice
                    .as_ref()
                    .map_or(String::new(), |n| format!("; {n}"))
            ));
        }
        if let (Some(bytes), Some(path)) = (pixels, &self.settings.screenshot) {
            let bgr = matches!(
                r.swapchain.format,
                vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM
            );
            let rgb: Vec<u8> = bytes
                .chunks_exact(4)
                .flat_map(|p| {
                    if bgr {
                        [p[2], p[1], p[0]]
                    } else {
                        [p[0], p[1], p[2]]
                    }
                })
                .collect();
            let (w, h) = r.swapchain.extent;
            crate::image::write_png_rgb8(path, w, h, &rgb)
                .map_err(|e| PreviewError::Window(e.to_string()))?;
        }
        if !fits {
            self.resize()?;
        }
        Ok(true)
    }

    /// Fit the swapchain and the frames to the window.
    fn resize(&mut self) -> Result<(), PreviewError> {
        let Some(r) = self.running.as_mut() else {
            return Ok(());
        };
        let size = r.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        r.swapchain.recreate((size.width, size.height))?;
        let (w, h) = r.swapchain.extent;
        let scene = match &self.relit {
            Some((scene, _)) => Some(scene),
            None => self.scene,
        };
        r.preview.resize((w, h), scene)?;
        self.camera = self.camera.clone().with_size(w, h);
        self.home.0 = self.home.0.clone().with_size(w, h);
        Ok(())
    }

    /// The camera moved: coarsen the cut and draw again.
    fn moved(&mut self) {
        self.cut_now = self.settings.cut_pixels * MOVING_COARSENESS;
        if let Some(r) = &self.running {
            r.window.request_redraw();
        }
    }

    /// One step of a scripted run; false when it is over.
    fn script_step(&mut self) -> Result<bool, PreviewError> {
        let Some(total) = self.settings.frames else {
            return Ok(true);
        };
        let done = self.report.frames;
        if done + 1 < total {
            // Around the target in `total - 1` steps; the last frame is the start exactly.
            let angle = std::f32::consts::TAU * (done + 1) as f32 / (total - 1).max(1) as f32;
            let (home, target) = self.home.clone();
            self.camera = if done + 2 == total {
                home
            } else {
                home.orbit(target, home.up, angle, 0.0).unwrap_or(home)
            };
            self.cut_now = self.settings.cut_pixels * MOVING_COARSENESS;
            return Ok(true);
        }
        if self.cut_now > self.settings.cut_pixels {
            return Ok(true);
        }
        // The last, refined frame: take the screenshot from it.
        self.draw(self.settings.screenshot.is_some())?;
        Ok(false)
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        if let Err(e) = self.open(event_loop) {
            self.error = Some(e);
            event_loop.exit();
            return;
        }
        event_loop.set_control_flow(ControlFlow::Wait);
        if let Some(r) = &self.running {
            r.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let result = self.handle(event_loop, event);
        if let Err(e) = result {
            self.error = Some(e);
            event_loop.exit();
        }
    }
}

impl App<'_> {
    fn handle(
        &mut self,
        event_loop: &ActiveEventLoop,
        event: WindowEvent,
    ) -> Result<(), PreviewError> {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => {
                self.resize()?;
                self.moved();
            }
            WindowEvent::RedrawRequested => {
                // A scripted run's step sets the camera of the frame drawn below (and the next
                // frame is requested at once), or takes the last frame and ends.
                if self.settings.frames.is_some() && !self.script_step()? {
                    event_loop.exit();
                    return Ok(());
                }
                self.draw(false)?;
                let rest = self.settings.cut_pixels;
                let refining = self.cut_now > rest;
                self.cut_now = (0.5 * self.cut_now).max(rest);
                if refining || self.settings.frames.is_some() {
                    if let Some(r) = &self.running {
                        r.window.request_redraw();
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = (
                    (position.x - self.cursor.0) as f32,
                    (position.y - self.cursor.1) as f32,
                );
                self.cursor = (position.x, position.y);
                if self.settings.frames.is_none() {
                    if let Some(button) = self.drag {
                        self.drag_by(button, dx, dy);
                    }
                }
            }
            WindowEvent::MouseWheel { delta, .. } if self.settings.frames.is_none() => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                let offset = self.camera.position - self.target;
                let scaled = offset * 0.9f32.powf(steps);
                if scaled.length() > 1e-6 {
                    self.camera.position = self.target + scaled;
                    self.moved();
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && self.settings.frames.is_none()
                    && self.editing.is_some() =>
            {
                match event.logical_key.as_ref() {
                    Key::Named(NamedKey::Escape) => self.editing = None,
                    Key::Named(NamedKey::Enter) => {
                        let edit = self.editing.take().unwrap_or_default();
                        self.apply_edit(edit.trim())?;
                    }
                    Key::Named(NamedKey::Backspace) => {
                        if let Some(text) = self.editing.as_mut() {
                            text.pop();
                        }
                    }
                    _ => {
                        if let (Some(text), Some(typed)) = (self.editing.as_mut(), &event.text) {
                            text.push_str(typed);
                        }
                    }
                }
                self.show_editing();
                if self.editing.is_none() {
                    self.moved();
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed && self.settings.frames.is_none() =>
            {
                let show = match event.logical_key.as_ref() {
                    Key::Character("e") if self.relighter.is_some() && self.scene.is_some() => {
                        self.editing = Some(String::new());
                        self.show_editing();
                        return Ok(());
                    }
                    Key::Named(NamedKey::Escape) => {
                        event_loop.exit();
                        return Ok(());
                    }
                    Key::Character("q") => {
                        event_loop.exit();
                        return Ok(());
                    }
                    Key::Character("r") => {
                        (self.camera, self.target) = self.home.clone();
                        self.moved();
                        return Ok(());
                    }
                    Key::Character("1" | "t") => Show::Total,
                    Key::Character("2" | "i") => Show::Indirect,
                    Key::Character("3" | "d") => Show::Direct,
                    Key::Character("4" | "s") => Show::Surfels,
                    Key::Character("5" | "c") => Show::Cut,
                    _ => return Ok(()),
                };
                self.show = show;
                self.moved();
            }
            _ => {}
        }
        Ok(())
    }

    /// Orbit (left button) or pan (others) by a cursor move of (`dx`, `dy`) pixels.
    fn drag_by(&mut self, button: MouseButton, dx: f32, dy: f32) {
        let c = &self.camera;
        if button == MouseButton::Left {
            let up = self.home.0.up;
            if let Some(moved) = c.orbit(self.target, up, -0.01 * dx, -0.01 * dy) {
                self.camera = moved;
            }
        } else {
            // One pixel moves the target's plane by one pixel.
            let distance = (c.position - self.target).length();
            let per_pixel = match c.projection {
                crate::scene::Projection::Perspective { yfov } => {
                    2.0 * distance * (0.5 * yfov).tan() / c.height as f32
                }
                crate::scene::Projection::Orthographic { ymag, .. } => 2.0 * ymag / c.height as f32,
            };
            let shift = (c.right * -dx + c.up * dy) * per_pixel;
            self.camera.position += shift;
            self.target += shift;
        }
        self.moved();
    }
}
