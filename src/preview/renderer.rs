//! The previewer's frame (docs/design.md §8, docs/method.md §9), three render passes:
//!
//! 1. **G-buffer**: the scene's meshes into position, geometric normal and emitted radiance
//!    (float images), depth tested.
//! 2. **Splats**: each cut node ([`super::cut::Splat`]) as a square facing the eye that covers
//!    its footprint sphere; per pixel, radiance cache splatting's weight against the G-buffer's
//!    point, and `(w L, w)` added into one float image. Without a scene, or to show surfels,
//!    depth-tested discs instead (the point-cloud view).
//! 3. **Resolve**: `emission × E + splats × Σ w L / Σ w` per pixel, into the output image.
//!
//! Blending adds in primitive order (Vulkan guarantees it), so a frame is the same on every
//! run on one device.

use super::cut::Splat;
use super::device::{check, Gpu, VulkanError};
use super::objects::{Buffer, Objects};
use super::pipelines::{
    descriptor_set, float4_features, pipeline, pipeline_layout, render_pass, write_descriptors,
    PipelineDesc, COLOR, DEPTH, FLOAT4,
};
use super::transfer;
use super::view::{FrameUniforms, View};
use crate::image::Image as RgbImage;
use crate::scene::Scene;
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// What a frame draws of the cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Weight of the emitters drawn from the G-buffer.
    pub emission: f32,
    /// Weight of the splatted (or disc) radiance.
    pub splats: f32,
    /// Depth-tested discs instead of weighted splats.
    pub discs: bool,
}

/// The scene's triangles for the G-buffer pass: one draw per mesh.
struct Geometry {
    vertices: Buffer,
    indices: Buffer,
    /// Per mesh: first index, index count, emission of its front and back faces.
    draws: Vec<(u32, u32, [f32; 8])>,
}

/// The pipelines of the three passes.
struct Pipelines {
    gbuffer: vk::Pipeline,
    splat: vk::Pipeline,
    disk: vk::Pipeline,
    resolve: vk::Pipeline,
}

/// Draws preview frames of one size, headless: each frame ends in a float image that is
/// read back.
pub struct Renderer {
    objects: Objects,
    size: (u32, u32),
    /// The G-buffer's position, normal and emission images, and the output image (the
    /// others live in `objects` only).
    gbuffer: [vk::Image; 3],
    output: vk::Image,
    passes: [vk::RenderPass; 3],
    framebuffers: [vk::Framebuffer; 3],
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
    pipelines: Pipelines,
    uniforms: Buffer,
    instances: Buffer,
    readback: Buffer,
    /// Whether the float output can be blitted with linear filtering (to scale it up).
    blit_linear: bool,
    geometry: Option<Geometry>,
    command: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Renderer {
    /// A renderer of `size` frames on `gpu`, with `scene`'s meshes for the G-buffer (none: the
    /// point-cloud view only).
    pub fn new(
        gpu: Arc<Gpu>,
        size: (u32, u32),
        scene: Option<&Scene>,
    ) -> Result<Renderer, VulkanError> {
        let mut o = Objects::new(gpu);
        let sampled = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let gbuffer = [
            o.image("G-buffer position", size, FLOAT4, sampled, COLOR)?,
            o.image("G-buffer normal", size, FLOAT4, sampled, COLOR)?,
            o.image("G-buffer emission", size, FLOAT4, sampled, COLOR)?,
        ];
        let depth = o.image(
            "depth",
            size,
            DEPTH,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            vk::ImageAspectFlags::DEPTH,
        )?;
        // Splat weights reach W_MAX = 1e4 and radiance 1e6, far past half floats: the
        // accumulation needs 32-bit float blending (lavapipe and desktop GPUs have it).
        let features = float4_features(&o);
        if !features.contains(vk::FormatFeatureFlags::COLOR_ATTACHMENT_BLEND) {
            return Err(VulkanError::Call {
                call: "vkGetPhysicalDeviceFormatProperties (the device cannot blend 32-bit float images)",
                result: vk::Result::ERROR_FORMAT_NOT_SUPPORTED,
            });
        }
        let accum = o.image("splat accumulation", size, FLOAT4, sampled, COLOR)?;
        let output = o.image(
            "output",
            size,
            FLOAT4,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            COLOR,
        )?;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let passes = [
            render_pass(&mut o, "G-buffer pass", &[FLOAT4; 3], read, true)?,
            render_pass(&mut o, "splat pass", &[accum.format], read, true)?,
            render_pass(
                &mut o,
                "resolve pass",
                &[FLOAT4],
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                false,
            )?,
        ];
        let fb = |o: &mut Objects, name: &str, pass, views: &[vk::ImageView]| {
            let info = vk::FramebufferCreateInfo::default()
                .render_pass(pass)
                .attachments(views)
                .width(size.0)
                .height(size.1)
                .layers(1);
            o.framebuffer(name, &info)
        };
        let framebuffers = [
            fb(
                &mut o,
                "G-buffer framebuffer",
                passes[0],
                &[
                    gbuffer[0].view,
                    gbuffer[1].view,
                    gbuffer[2].view,
                    depth.view,
                ],
            )?,
            fb(
                &mut o,
                "splat framebuffer",
                passes[1],
                &[accum.view, depth.view],
            )?,
            fb(&mut o, "resolve framebuffer", passes[2], &[output.view])?,
        ];
        let (layout, set_layout) = pipeline_layout(&mut o)?;
        let set = descriptor_set(&mut o, set_layout)?;
        let pipelines = Pipelines {
            gbuffer: pipeline(&mut o, &PipelineDesc::GBUFFER, layout, passes[0])?,
            splat: pipeline(&mut o, &PipelineDesc::SPLAT, layout, passes[1])?,
            disk: pipeline(&mut o, &PipelineDesc::DISK, layout, passes[1])?,
            resolve: pipeline(&mut o, &PipelineDesc::RESOLVE, layout, passes[2])?,
        };
        let uniforms = o.buffer(
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let instances = o.buffer("splats", 1 << 16, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let readback = o.buffer(
            "readback",
            size.0 as u64 * size.1 as u64 * 16,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let sampler = o.sampler(
            "nearest sampler",
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::NEAREST)
                .min_filter(vk::Filter::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE),
        )?;
        let views = [
            gbuffer[0].view,
            gbuffer[1].view,
            gbuffer[2].view,
            accum.view,
        ];
        write_descriptors(&o, set, &uniforms, views, sampler);
        let geometry = scene.map(|s| upload_geometry(&mut o, s)).transpose()?;
        let pool = o.command_pool(
            "command pool",
            &vk::CommandPoolCreateInfo::default()
                .queue_family_index(o.gpu.queue_family)
                .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
        )?;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: a valid allocate info; the buffer is freed with its pool.
        let command = check("vkAllocateCommandBuffers", unsafe {
            o.device().allocate_command_buffers(&info)
        })?[0];
        o.name(command, "frame commands")?;
        let fence = o.fence("frame fence", &vk::FenceCreateInfo::default())?;
        let blit_linear = features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        Ok(Renderer {
            objects: o,
            size,
            gbuffer: gbuffer.map(|i| i.handle),
            output: output.handle,
            passes,
            framebuffers,
            layout,
            set,
            pipelines,
            uniforms,
            instances,
            readback,
            blit_linear,
            geometry,
            command,
            fence,
        })
    }

    /// The device it draws with.
    pub fn gpu(&self) -> &Gpu {
        &self.objects.gpu
    }

    /// The size of its frames.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The same, shared.
    pub(crate) fn gpu_arc(&self) -> Arc<Gpu> {
        self.objects.gpu.clone()
    }

    /// Draw one frame of `splats` seen from `view` and return it (linear float RGB).
    pub fn render(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
    ) -> Result<RgbImage, VulkanError> {
        self.draw(view, splats, settings, None, |r, d, cmd| {
            // SAFETY: the output is in the transfer layout after the resolve pass, and the
            // readback buffer holds a float4 image of the renderer's size.
            unsafe {
                transfer::record_readback(d, cmd, (r.output, r.size), r.readback.handle, None)
            };
        })?;
        Ok(RgbImage {
            width: self.size.0,
            height: self.size.1,
            pixels: self.read_pixels(|p| Vec3::new(p[0], p[1], p[2])),
        })
    }

    /// Draw one frame into a window's swapchain image (blitted from the float output, which
    /// converts it to the image's format). With `target.screenshot`, the swapchain image is
    /// also read back: its bytes, 4 per pixel in its format, row-major from the top (only when
    /// the frame has the image's size, which the readback buffer holds).
    pub fn present(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
        target: &PresentTarget,
    ) -> Result<Option<Vec<u8>>, VulkanError> {
        let screenshot = target.screenshot && target.size == self.size;
        let semaphores = Some((target.acquired, target.rendered));
        self.draw(view, splats, settings, semaphores, |r, d, cmd| {
            let readback = screenshot.then_some(r.readback.handle);
            let image = (target.image, target.size);
            // SAFETY: the submit waits for the image's acquisition at the transfer stage; a
            // screenshot's image has the renderer's size, 4 bytes a pixel (the readback buffer
            // holds 16).
            unsafe {
                transfer::record_present(d, cmd, (r.output, r.size), image, readback, r.blit_linear)
            };
        })?;
        Ok(screenshot.then(|| {
            let n = self.size.0 as usize * self.size.1 as usize;
            self.readback
                .read::<[u8; 4]>(n)
                .into_iter()
                .flatten()
                .collect()
        }))
    }

    /// Upload and record the three passes, then `finish` (what happens to the output), and
    /// submit with `semaphores` (see [`Renderer::submit`]).
    fn draw(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
        semaphores: Option<(vk::Semaphore, vk::Semaphore)>,
        finish: impl FnOnce(&Self, &ash::Device, vk::CommandBuffer),
    ) -> Result<(), VulkanError> {
        self.upload(view, splats, settings)?;
        let cmd = self.command;
        self.submit(
            |r, d| {
                r.record_passes(d, cmd, splats.len() as u32, settings);
                finish(r, d, cmd);
            },
            semaphores,
        )
    }

    /// Write the frame's uniforms and splats.
    fn upload(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
    ) -> Result<(), VulkanError> {
        self.uniforms.write(std::slice::from_ref(
            &view.uniforms(settings.emission, settings.splats),
        ));
        let bytes = std::mem::size_of_val(splats) as u64;
        if bytes > self.instances.size {
            let old = self.instances;
            self.objects.release_buffer(old);
            self.instances = self.objects.buffer(
                "splats",
                bytes.next_power_of_two(),
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?;
        }
        self.instances.write(splats);
        Ok(())
    }

    /// The G-buffer of the last frame, row-major from the top: positions (w = 1 where a mesh
    /// covers the pixel), geometric normals and emission. What a CPU implementation of the
    /// splat and resolve passes needs.
    pub fn gbuffer(&mut self) -> Result<[Vec<[f32; 4]>; 3], VulkanError> {
        let mut out = Vec::new();
        for i in 0..3 {
            let image = self.gbuffer[i];
            let cmd = self.command;
            let layout = Some(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            // SAFETY: after a frame the G-buffer images are in `layout`, read by shaders; the
            // readback buffer holds one of them.
            let record = |r: &Self, d: &ash::Device| unsafe {
                transfer::record_readback(d, cmd, (image, r.size), r.readback.handle, layout)
            };
            self.submit(record, None)?;
            out.push(self.read_pixels(|p| p));
        }
        let emission = out.pop().unwrap_or_default();
        let normals = out.pop().unwrap_or_default();
        let positions = out.pop().unwrap_or_default();
        Ok([positions, normals, emission])
    }

    /// The readback buffer's pixels, each turned into a `T` by `f`.
    fn read_pixels<T>(&self, f: impl Fn([f32; 4]) -> T) -> Vec<T> {
        let n = self.size.0 as usize * self.size.1 as usize;
        self.readback
            .read::<[f32; 4]>(n)
            .into_iter()
            .map(f)
            .collect()
    }

    /// Record with `record`, submit (waiting for and signalling `semaphores`' first and
    /// second, if given), and wait for the GPU.
    fn submit(
        &self,
        record: impl FnOnce(&Self, &ash::Device),
        semaphores: Option<(vk::Semaphore, vk::Semaphore)>,
    ) -> Result<(), VulkanError> {
        let d = self.objects.device();
        let cmd = self.command;
        // SAFETY: the command buffer is ours and not pending (every submit waits); the queue
        // is used from this thread only.
        unsafe {
            check(
                "vkResetCommandBuffer",
                d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()),
            )?;
            check(
                "vkBeginCommandBuffer",
                d.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                ),
            )?;
            record(self, d);
            check("vkEndCommandBuffer", d.end_command_buffer(cmd))?;
            let waits: Vec<vk::Semaphore> = semaphores.iter().map(|s| s.0).collect();
            let signals: Vec<vk::Semaphore> = semaphores.iter().map(|s| s.1).collect();
            let stages = vec![vk::PipelineStageFlags::TRANSFER; waits.len()];
            let submit = vk::SubmitInfo::default()
                .command_buffers(std::slice::from_ref(&cmd))
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages)
                .signal_semaphores(&signals);
            check(
                "vkQueueSubmit",
                d.queue_submit(self.objects.gpu.queue, &[submit], self.fence),
            )?;
            check(
                "vkWaitForFences",
                d.wait_for_fences(&[self.fence], true, u64::MAX),
            )?;
            check("vkResetFences", d.reset_fences(&[self.fence]))?;
        }
        Ok(())
    }

    /// The three passes into the output image.
    fn record_passes(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        splats: u32,
        s: FrameSettings,
    ) {
        let (w, h) = self.size;
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: w as f32,
            height: h as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let zero = vk::ClearValue {
            color: vk::ClearColorValue { float32: [0.0; 4] },
        };
        // Reversed depth (see `view.rs`): the far plane is 0.
        let far = vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 0.0,
                stencil: 0,
            },
        };
        let begin = |pass: usize, clears: &[vk::ClearValue]| {
            let info = vk::RenderPassBeginInfo::default()
                .render_pass(self.passes[pass])
                .framebuffer(self.framebuffers[pass])
                .render_area(area)
                .clear_values(clears);
            // SAFETY: recording into our command buffer with our objects.
            unsafe {
                d.cmd_begin_render_pass(cmd, &info, vk::SubpassContents::INLINE);
                d.cmd_set_viewport(cmd, 0, &[viewport]);
                d.cmd_set_scissor(cmd, 0, &[area]);
            }
        };
        let bind = |pipeline| {
            // SAFETY: recording into our command buffer with our objects.
            unsafe {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
                let graphics = vk::PipelineBindPoint::GRAPHICS;
                d.cmd_bind_descriptor_sets(cmd, graphics, self.layout, 0, &[self.set], &[]);
            }
        };
        // SAFETY: as above; every bound object lives as long as the renderer.
        unsafe {
            begin(0, &[zero, zero, zero, far]);
            if let Some(g) = &self.geometry {
                bind(self.pipelines.gbuffer);
                d.cmd_bind_vertex_buffers(cmd, 0, &[g.vertices.handle], &[0]);
                d.cmd_bind_index_buffer(cmd, g.indices.handle, 0, vk::IndexType::UINT32);
                for (first, count, emission) in &g.draws {
                    d.cmd_push_constants(
                        cmd,
                        self.layout,
                        vk::ShaderStageFlags::FRAGMENT,
                        0,
                        bytemuck::cast_slice(emission),
                    );
                    d.cmd_draw_indexed(cmd, *count, 1, *first, 0, 0);
                }
            }
            d.cmd_end_render_pass(cmd);
            begin(1, &[zero, far]);
            if splats > 0 {
                let p = if s.discs {
                    self.pipelines.disk
                } else {
                    self.pipelines.splat
                };
                bind(p);
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.instances.handle], &[0]);
                d.cmd_draw(cmd, 4, splats, 0, 0);
            }
            d.cmd_end_render_pass(cmd);
            begin(2, &[zero]);
            bind(self.pipelines.resolve);
            d.cmd_draw(cmd, 3, 1, 0, 0);
            d.cmd_end_render_pass(cmd);
        }
    }
}

/// The scene's meshes in one vertex and one index buffer, with each mesh's emission.
fn upload_geometry(o: &mut Objects, scene: &Scene) -> Result<Geometry, VulkanError> {
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut draws = Vec::new();
    for m in &scene.meshes {
        let base = vertices.len() as u32;
        let first = indices.len() as u32;
        vertices.extend(m.positions.iter().map(|p| p.to_array()));
        indices.extend(m.triangles.iter().flatten().map(|&i| base + i));
        // Emission textures are left out: the preview shows each emitter's factor.
        let material = scene.materials.get(m.material);
        let emitted = |front| {
            material
                .map(|mat| mat.emission_at(&scene.textures, glam::Vec2::ZERO, front))
                .unwrap_or(Vec3::ZERO)
        };
        let (f, b) = (emitted(true), emitted(false));
        draws.push((
            first,
            indices.len() as u32 - first,
            [f.x, f.y, f.z, 0.0, b.x, b.y, b.z, 0.0],
        ));
    }
    let vb = o.buffer(
        "scene vertices",
        std::mem::size_of_val(vertices.as_slice()) as u64,
        vk::BufferUsageFlags::VERTEX_BUFFER,
    )?;
    vb.write(&vertices);
    let ib = o.buffer(
        "scene indices",
        std::mem::size_of_val(indices.as_slice()) as u64,
        vk::BufferUsageFlags::INDEX_BUFFER,
    )?;
    ib.write(&indices);
    Ok(Geometry {
        vertices: vb,
        indices: ib,
        draws,
    })
}

/// A swapchain image to draw a frame into.
pub struct PresentTarget {
    /// The image.
    pub image: vk::Image,
    /// Signalled when the image is acquired; the frame waits for it.
    pub acquired: vk::Semaphore,
    /// Signalled when the frame is drawn; presentation waits for it.
    pub rendered: vk::Semaphore,
    /// Its size (the blit scales the frame up to it).
    pub size: (u32, u32),
    /// Read the image back after drawing (only when the frame has the image's size).
    pub screenshot: bool,
}
