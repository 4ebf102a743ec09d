//! The previewer's frame (DESIGN.md §8, spec §9), three render passes:
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
use super::objects::{whole, Buffer, Image, Objects};
use super::view::{FrameUniforms, View};
use crate::image::Image as RgbImage;
use crate::scene::Scene;
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// The SPIR-V that `build.rs` compiled.
mod spirv {
    macro_rules! shader {
        ($name:literal) => {
            include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv"))
        };
    }
    pub const GBUFFER_VERT: &[u8] = shader!("gbuffer.vert");
    pub const GBUFFER_FRAG: &[u8] = shader!("gbuffer.frag");
    pub const SPLAT_VERT: &[u8] = shader!("splat.vert");
    pub const SPLAT_FRAG: &[u8] = shader!("splat.frag");
    pub const DISK_VERT: &[u8] = shader!("disk.vert");
    pub const DISK_FRAG: &[u8] = shader!("disk.frag");
    pub const RESOLVE_VERT: &[u8] = shader!("resolve.vert");
    pub const RESOLVE_FRAG: &[u8] = shader!("resolve.frag");
}

const FLOAT4: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
const COLOR: vk::ImageAspectFlags = vk::ImageAspectFlags::COLOR;

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

/// The images one frame renders through.
struct Targets {
    gbuffer: [Image; 3],
    accum: Image,
    output: Image,
}

/// Draws preview frames of one size, headless: each frame ends in a float image that is
/// read back.
pub struct Renderer {
    objects: Objects,
    size: (u32, u32),
    targets: Targets,
    passes: [vk::RenderPass; 3],
    framebuffers: [vk::Framebuffer; 3],
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
    pipelines: Pipelines,
    uniforms: Buffer,
    instances: Buffer,
    readback: Buffer,
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
        let accum = o.image(
            "splat accumulation",
            size,
            accumulation_format(&o),
            sampled,
            COLOR,
        )?;
        let output = o.image(
            "output",
            size,
            FLOAT4,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            COLOR,
        )?;
        let targets = Targets {
            gbuffer,
            accum,
            output,
        };
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
        write_descriptors(&o, set, &uniforms, &targets, sampler);
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
        Ok(Renderer {
            objects: o,
            size,
            targets,
            passes,
            framebuffers,
            layout,
            set,
            pipelines,
            uniforms,
            instances,
            readback,
            geometry,
            command,
            fence,
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.objects.gpu
    }

    pub fn gpu_arc(&self) -> Arc<Gpu> {
        self.objects.gpu.clone()
    }

    /// Draw one frame of `splats` seen from `view` and return it (linear float RGB).
    pub fn render(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
    ) -> Result<RgbImage, VulkanError> {
        self.upload(view, splats, settings)?;
        let cmd = self.command;
        self.submit(
            |r, d| {
                r.record_passes(d, cmd, splats.len() as u32, settings);
                r.record_copy(d, cmd, r.targets.output.handle, None);
            },
            None,
        )?;
        Ok(RgbImage {
            width: self.size.0,
            height: self.size.1,
            pixels: self.read_pixels(|p| Vec3::new(p[0], p[1], p[2])),
        })
    }

    /// Draw one frame into a window's swapchain image (blitted from the float output, which
    /// converts it to the image's format). With `target.screenshot`, the swapchain image is
    /// also read back: its bytes, 4 per pixel in its format, row-major from the top.
    pub fn present(
        &mut self,
        view: &View,
        splats: &[Splat],
        settings: FrameSettings,
        target: &PresentTarget,
    ) -> Result<Option<Vec<u8>>, VulkanError> {
        self.upload(view, splats, settings)?;
        let cmd = self.command;
        self.submit(
            |r, d| {
                r.record_passes(d, cmd, splats.len() as u32, settings);
                r.record_blit(d, cmd, target);
            },
            Some((target.acquired, target.rendered)),
        )?;
        Ok(target.screenshot.then(|| {
            let n = self.size.0 as usize * self.size.1 as usize;
            self.readback
                .read::<[u8; 4]>(n)
                .into_iter()
                .flatten()
                .collect()
        }))
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
            let image = self.targets.gbuffer[i].handle;
            let cmd = self.command;
            let layout = Some(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            self.submit(|r, d| r.record_copy(d, cmd, image, layout), None)?;
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
        let far = vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
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
        // SAFETY: as above; every bound object lives as long as the renderer.
        unsafe {
            begin(0, &[zero, zero, zero, far]);
            if let Some(g) = &self.geometry {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipelines.gbuffer);
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layout,
                    0,
                    &[self.set],
                    &[],
                );
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
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, p);
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layout,
                    0,
                    &[self.set],
                    &[],
                );
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.instances.handle], &[0]);
                d.cmd_draw(cmd, 4, splats, 0, 0);
            }
            d.cmd_end_render_pass(cmd);
            begin(2, &[zero]);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipelines.resolve);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[self.set],
                &[],
            );
            d.cmd_draw(cmd, 3, 1, 0, 0);
            d.cmd_end_render_pass(cmd);
        }
    }

    /// Copy `image` into the readback buffer. It is in TRANSFER_SRC_OPTIMAL, or in `layout`
    /// (then it is moved to the transfer layout and back).
    fn record_copy(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        image: vk::Image,
        layout: Option<vk::ImageLayout>,
    ) {
        let (w, h) = self.size;
        let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        let barrier = |from, to, src_access, dst_access| {
            vk::ImageMemoryBarrier::default()
                .old_layout(from)
                .new_layout(to)
                .src_access_mask(src_access)
                .dst_access_mask(dst_access)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(whole(COLOR))
        };
        let stages = vk::PipelineStageFlags::ALL_COMMANDS;
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth: 1,
            });
        // SAFETY: recording into our command buffer; the image and buffer are ours and big
        // enough (the readback buffer holds one float4 image of the renderer's size).
        unsafe {
            if let Some(l) = layout {
                let b = barrier(
                    l,
                    src,
                    vk::AccessFlags::SHADER_READ,
                    vk::AccessFlags::TRANSFER_READ,
                );
                d.cmd_pipeline_barrier(
                    cmd,
                    stages,
                    stages,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &[b],
                );
            }
            d.cmd_copy_image_to_buffer(cmd, image, src, self.readback.handle, &[region]);
            let to_host = vk::BufferMemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(self.readback.handle)
                .size(vk::WHOLE_SIZE);
            let back = layout.map(|l| {
                barrier(
                    src,
                    l,
                    vk::AccessFlags::TRANSFER_READ,
                    vk::AccessFlags::SHADER_READ,
                )
            });
            d.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST | stages,
                vk::DependencyFlags::empty(),
                &[],
                &[to_host],
                back.as_slice(),
            );
        }
    }
}

/// RGBA32F where the device blends it (lavapipe and desktop GPUs), else RGBA16F.
fn accumulation_format(o: &Objects) -> vk::Format {
    // SAFETY: a plain query of the physical device.
    let props = unsafe {
        o.gpu
            .instance
            .get_physical_device_format_properties(o.gpu.physical, FLOAT4)
    };
    if props
        .optimal_tiling_features
        .contains(vk::FormatFeatureFlags::COLOR_ATTACHMENT_BLEND)
    {
        FLOAT4
    } else {
        vk::Format::R16G16B16A16_SFLOAT
    }
}

/// A one-subpass render pass over colour attachments of `formats` (cleared; left in
/// `final_layout`) and, with `depth`, a depth attachment. Its dependencies order it after the
/// previous pass's reads and writes and before the next pass's reads and the copies.
fn render_pass(
    o: &mut Objects,
    name: &str,
    formats: &[vk::Format],
    final_layout: vk::ImageLayout,
    depth: bool,
) -> Result<vk::RenderPass, VulkanError> {
    let mut attachments: Vec<vk::AttachmentDescription> = formats
        .iter()
        .map(|&f| {
            vk::AttachmentDescription::default()
                .format(f)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(final_layout)
        })
        .collect();
    let colour_refs: Vec<vk::AttachmentReference> = (0..formats.len() as u32)
        .map(|i| vk::AttachmentReference {
            attachment: i,
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        })
        .collect();
    let depth_ref = vk::AttachmentReference {
        attachment: formats.len() as u32,
        layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    };
    let mut subpass = vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour_refs);
    if depth {
        attachments.push(
            vk::AttachmentDescription::default()
                .format(DEPTH)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
        );
        subpass = subpass.depth_stencil_attachment(&depth_ref);
    }
    let attach_stages = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
        | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
    let attach_writes =
        vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE;
    let readers = vk::PipelineStageFlags::FRAGMENT_SHADER | vk::PipelineStageFlags::TRANSFER;
    let reads = vk::AccessFlags::SHADER_READ | vk::AccessFlags::TRANSFER_READ;
    let dependencies = [
        vk::SubpassDependency::default()
            .src_subpass(vk::SUBPASS_EXTERNAL)
            .dst_subpass(0)
            .src_stage_mask(readers | attach_stages)
            .src_access_mask(attach_writes)
            .dst_stage_mask(attach_stages | vk::PipelineStageFlags::FRAGMENT_SHADER)
            .dst_access_mask(attach_writes | vk::AccessFlags::SHADER_READ),
        vk::SubpassDependency::default()
            .src_subpass(0)
            .dst_subpass(vk::SUBPASS_EXTERNAL)
            .src_stage_mask(attach_stages)
            .src_access_mask(attach_writes)
            .dst_stage_mask(readers | attach_stages)
            .dst_access_mask(reads | attach_writes),
    ];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(std::slice::from_ref(&subpass))
        .dependencies(&dependencies);
    o.render_pass(name, &info)
}

/// Binding 0: the frame's uniforms; 1–3: the G-buffer's position, normal and emission; 4: the
/// splat accumulation; 5: a nearest sampler. Push constants: a mesh's emission (32 bytes).
fn pipeline_layout(
    o: &mut Objects,
) -> Result<(vk::PipelineLayout, vk::DescriptorSetLayout), VulkanError> {
    let fragment = vk::ShaderStageFlags::FRAGMENT;
    let binding = |b: u32, ty, stages| {
        vk::DescriptorSetLayoutBinding::default()
            .binding(b)
            .descriptor_type(ty)
            .descriptor_count(1)
            .stage_flags(stages)
    };
    let bindings = [
        binding(
            0,
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::ShaderStageFlags::VERTEX | fragment,
        ),
        binding(1, vk::DescriptorType::SAMPLED_IMAGE, fragment),
        binding(2, vk::DescriptorType::SAMPLED_IMAGE, fragment),
        binding(3, vk::DescriptorType::SAMPLED_IMAGE, fragment),
        binding(4, vk::DescriptorType::SAMPLED_IMAGE, fragment),
        binding(5, vk::DescriptorType::SAMPLER, fragment),
    ];
    let set_layout = o.set_layout(
        "frame descriptor layout",
        &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
    )?;
    let push = vk::PushConstantRange {
        stage_flags: fragment,
        offset: 0,
        size: 32,
    };
    let layout = o.pipeline_layout(
        "frame pipeline layout",
        &vk::PipelineLayoutCreateInfo::default()
            .set_layouts(std::slice::from_ref(&set_layout))
            .push_constant_ranges(std::slice::from_ref(&push)),
    )?;
    Ok((layout, set_layout))
}

fn descriptor_set(
    o: &mut Objects,
    layout: vk::DescriptorSetLayout,
) -> Result<vk::DescriptorSet, VulkanError> {
    let sizes = [
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::UNIFORM_BUFFER,
            descriptor_count: 1,
        },
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::SAMPLED_IMAGE,
            descriptor_count: 4,
        },
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::SAMPLER,
            descriptor_count: 1,
        },
    ];
    let pool = o.descriptor_pool(
        "descriptor pool",
        &vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes),
    )?;
    let info = vk::DescriptorSetAllocateInfo::default()
        .descriptor_pool(pool)
        .set_layouts(std::slice::from_ref(&layout));
    // SAFETY: a valid allocate info; the set is freed with its pool.
    let set = check("vkAllocateDescriptorSets", unsafe {
        o.device().allocate_descriptor_sets(&info)
    })?[0];
    o.name(set, "frame descriptors")?;
    Ok(set)
}

fn write_descriptors(
    o: &Objects,
    set: vk::DescriptorSet,
    uniforms: &Buffer,
    t: &Targets,
    sampler: vk::Sampler,
) {
    let buffer = [vk::DescriptorBufferInfo {
        buffer: uniforms.handle,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let images: Vec<[vk::DescriptorImageInfo; 1]> =
        [t.gbuffer[0], t.gbuffer[1], t.gbuffer[2], t.accum]
            .iter()
            .map(|i| {
                [vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: i.view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }]
            })
            .collect();
    let samplers = [vk::DescriptorImageInfo {
        sampler,
        image_view: vk::ImageView::null(),
        image_layout: vk::ImageLayout::UNDEFINED,
    }];
    let mut writes = vec![vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(0)
        .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
        .buffer_info(&buffer)];
    for (i, info) in images.iter().enumerate() {
        writes.push(
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1 + i as u32)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(info),
        );
    }
    writes.push(
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(5)
            .descriptor_type(vk::DescriptorType::SAMPLER)
            .image_info(&samplers),
    );
    // SAFETY: the writes name live objects of this device; the set is not in use.
    unsafe { o.device().update_descriptor_sets(&writes, &[]) };
}

/// How one pipeline is built.
struct PipelineDesc {
    name: &'static str,
    vertex: &'static [u8],
    fragment: &'static [u8],
    /// Vertex stride and whether the vertex buffer is per instance (0: none).
    stride: u32,
    per_instance: bool,
    strip: bool,
    depth_test: bool,
    blend_add: bool,
    colour_targets: u32,
}

impl PipelineDesc {
    const GBUFFER: PipelineDesc = PipelineDesc {
        name: "G-buffer pipeline",
        vertex: spirv::GBUFFER_VERT,
        fragment: spirv::GBUFFER_FRAG,
        stride: 12,
        per_instance: false,
        strip: false,
        depth_test: true,
        blend_add: false,
        colour_targets: 3,
    };
    const SPLAT: PipelineDesc = PipelineDesc {
        name: "splat pipeline",
        vertex: spirv::SPLAT_VERT,
        fragment: spirv::SPLAT_FRAG,
        stride: std::mem::size_of::<Splat>() as u32,
        per_instance: true,
        strip: true,
        depth_test: false,
        blend_add: true,
        colour_targets: 1,
    };
    const DISK: PipelineDesc = PipelineDesc {
        name: "disc pipeline",
        vertex: spirv::DISK_VERT,
        fragment: spirv::DISK_FRAG,
        depth_test: true,
        blend_add: false,
        ..PipelineDesc::SPLAT
    };
    const RESOLVE: PipelineDesc = PipelineDesc {
        name: "resolve pipeline",
        vertex: spirv::RESOLVE_VERT,
        fragment: spirv::RESOLVE_FRAG,
        stride: 0,
        per_instance: false,
        strip: false,
        depth_test: false,
        blend_add: false,
        colour_targets: 1,
    };
}

fn shader(o: &mut Objects, name: &str, spirv: &[u8]) -> Result<vk::ShaderModule, VulkanError> {
    let words =
        ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|_| VulkanError::Call {
            call: "reading SPIR-V",
            result: vk::Result::ERROR_INVALID_SHADER_NV,
        })?;
    o.shader(name, &vk::ShaderModuleCreateInfo::default().code(&words))
}

fn pipeline(
    o: &mut Objects,
    desc: &PipelineDesc,
    layout: vk::PipelineLayout,
    pass: vk::RenderPass,
) -> Result<vk::Pipeline, VulkanError> {
    let vs = shader(o, &format!("{} vertex shader", desc.name), desc.vertex)?;
    let fs = shader(o, &format!("{} fragment shader", desc.name), desc.fragment)?;
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vs)
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fs)
            .name(c"main"),
    ];
    let bindings = [vk::VertexInputBindingDescription {
        binding: 0,
        stride: desc.stride,
        input_rate: if desc.per_instance {
            vk::VertexInputRate::INSTANCE
        } else {
            vk::VertexInputRate::VERTEX
        },
    }];
    let attributes: Vec<vk::VertexInputAttributeDescription> = if desc.per_instance {
        (0..3)
            .map(|i| vk::VertexInputAttributeDescription {
                location: i,
                binding: 0,
                format: FLOAT4,
                offset: 16 * i,
            })
            .collect()
    } else if desc.stride > 0 {
        vec![vk::VertexInputAttributeDescription {
            location: 0,
            binding: 0,
            format: vk::Format::R32G32B32_SFLOAT,
            offset: 0,
        }]
    } else {
        vec![]
    };
    let vertex_input = if desc.stride > 0 {
        vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes)
    } else {
        vk::PipelineVertexInputStateCreateInfo::default()
    };
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(if desc.strip {
        vk::PrimitiveTopology::TRIANGLE_STRIP
    } else {
        vk::PrimitiveTopology::TRIANGLE_LIST
    });
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    // glTF's front faces are counter-clockwise, and the projection keeps the image upright.
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth_test)
        .depth_write_enable(desc.depth_test)
        .depth_compare_op(vk::CompareOp::LESS);
    let blend = vk::PipelineColorBlendAttachmentState {
        blend_enable: desc.blend_add.into(),
        src_color_blend_factor: vk::BlendFactor::ONE,
        dst_color_blend_factor: vk::BlendFactor::ONE,
        color_blend_op: vk::BlendOp::ADD,
        src_alpha_blend_factor: vk::BlendFactor::ONE,
        dst_alpha_blend_factor: vk::BlendFactor::ONE,
        alpha_blend_op: vk::BlendOp::ADD,
        color_write_mask: vk::ColorComponentFlags::RGBA,
    };
    let blends = vec![blend; desc.colour_targets as usize];
    let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .color_blend_state(&blending)
        .dynamic_state(&dynamic)
        .layout(layout)
        .render_pass(pass)
        .subpass(0);
    if pass_has_depth(desc) {
        info = info.depth_stencil_state(&depth);
    }
    o.pipeline(desc.name, &info)
}

/// Whether the pipeline's pass has a depth attachment (all but the resolve pass).
fn pass_has_depth(desc: &PipelineDesc) -> bool {
    desc.stride > 0
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

impl Renderer {
    /// Blit the output into `target`'s swapchain image (and read it back for a screenshot),
    /// leaving it ready to present.
    fn record_blit(&self, d: &ash::Device, cmd: vk::CommandBuffer, target: &PresentTarget) {
        let (w, h) = self.size;
        let image = target.image;
        let barrier = |from, to, src_access, dst_access| {
            vk::ImageMemoryBarrier::default()
                .old_layout(from)
                .new_layout(to)
                .src_access_mask(src_access)
                .dst_access_mask(dst_access)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(whole(COLOR))
        };
        let transfer = vk::PipelineStageFlags::TRANSFER;
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let corner = vk::Offset3D {
            x: w as i32,
            y: h as i32,
            z: 1,
        };
        let blit = vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), corner],
            dst_subresource: layers,
            dst_offsets: [vk::Offset3D::default(), corner],
        };
        let (dst, src, present) = (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::ImageLayout::PRESENT_SRC_KHR,
        );
        let none = vk::AccessFlags::empty();
        let flags = vk::DependencyFlags::empty();
        let write = vk::AccessFlags::TRANSFER_WRITE;
        // SAFETY: recording into our command buffer; the swapchain image was acquired (the
        // submit waits for it at the transfer stage) and has the output's size.
        unsafe {
            let to_dst = barrier(vk::ImageLayout::UNDEFINED, dst, none, write);
            d.cmd_pipeline_barrier(cmd, transfer, transfer, flags, &[], &[], &[to_dst]);
            d.cmd_blit_image(
                cmd,
                self.targets.output.handle,
                src,
                image,
                dst,
                &[blit],
                vk::Filter::NEAREST,
            );
            let mut last = (dst, write);
            if target.screenshot {
                let read = vk::AccessFlags::TRANSFER_READ;
                let to_src = barrier(dst, src, write, read);
                d.cmd_pipeline_barrier(cmd, transfer, transfer, flags, &[], &[], &[to_src]);
                let region = vk::BufferImageCopy::default()
                    .image_subresource(layers)
                    .image_extent(vk::Extent3D {
                        width: w,
                        height: h,
                        depth: 1,
                    });
                d.cmd_copy_image_to_buffer(cmd, image, src, self.readback.handle, &[region]);
                let to_host = vk::BufferMemoryBarrier::default()
                    .src_access_mask(write)
                    .dst_access_mask(vk::AccessFlags::HOST_READ)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .buffer(self.readback.handle)
                    .size(vk::WHOLE_SIZE);
                let host = vk::PipelineStageFlags::HOST;
                d.cmd_pipeline_barrier(cmd, transfer, host, flags, &[], &[to_host], &[]);
                last = (src, read);
            }
            let to_present = barrier(last.0, present, last.1, none);
            let bottom = vk::PipelineStageFlags::BOTTOM_OF_PIPE;
            d.cmd_pipeline_barrier(cmd, transfer, bottom, flags, &[], &[], &[to_present]);
        }
    }
}

/// A swapchain image to draw a frame into.
pub struct PresentTarget {
    pub image: vk::Image,
    /// Signalled when the image is acquired; the frame waits for it.
    pub acquired: vk::Semaphore,
    /// Signalled when the frame is drawn; presentation waits for it.
    pub rendered: vk::Semaphore,
    /// Read the image back after drawing.
    pub screenshot: bool,
}
