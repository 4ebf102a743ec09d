//! The previewer's fixed state: render passes, the descriptor layout every pass shares, and
//! the pipelines of the G-buffer, splat, disc and resolve passes, built from the SPIR-V that
//! `build.rs` compiled with naga.

use super::cut::Splat;
use super::device::{check, VulkanError};
use super::objects::{Buffer, Objects};
use ash::vk;

/// The SPIR-V that `build.rs` compiled.
mod spirv {
    macro_rules! shader {
        ($name:literal) => {
            include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv"))
        };
    }
    pub(crate) const GBUFFER_VERT: &[u8] = shader!("gbuffer.vert");
    pub(crate) const GBUFFER_FRAG: &[u8] = shader!("gbuffer.frag");
    pub(crate) const SPLAT_VERT: &[u8] = shader!("splat.vert");
    pub(crate) const SPLAT_FRAG: &[u8] = shader!("splat.frag");
    pub(crate) const DISK_VERT: &[u8] = shader!("disk.vert");
    pub(crate) const DISK_FRAG: &[u8] = shader!("disk.frag");
    pub(crate) const RESOLVE_VERT: &[u8] = shader!("resolve.vert");
    pub(crate) const RESOLVE_FRAG: &[u8] = shader!("resolve.frag");
}

/// The G-buffer's, the accumulation's and the output's format.
pub(crate) const FLOAT4: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub(crate) const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
pub(crate) const COLOR: vk::ImageAspectFlags = vk::ImageAspectFlags::COLOR;

/// What the device can do with [`FLOAT4`] images (optimal tiling).
pub(crate) fn float4_features(o: &Objects) -> vk::FormatFeatureFlags {
    // SAFETY: a plain query of the physical device.
    unsafe {
        o.gpu
            .instance
            .get_physical_device_format_properties(o.gpu.physical, FLOAT4)
    }
    .optimal_tiling_features
}

/// A one-subpass render pass over colour attachments of `formats` (cleared; left in
/// `final_layout`) and, with `depth`, a depth attachment. Its dependencies order it after the
/// previous pass's reads and writes and before the next pass's reads and the copies.
pub(crate) fn render_pass(
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
pub(crate) fn pipeline_layout(
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

pub(crate) fn descriptor_set(
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

/// Point `set` at the frame's uniforms, the G-buffer's three images and the accumulation
/// (`images`, in binding order) and the sampler.
pub(crate) fn write_descriptors(
    o: &Objects,
    set: vk::DescriptorSet,
    uniforms: &Buffer,
    images: [vk::ImageView; 4],
    sampler: vk::Sampler,
) {
    let buffer = [vk::DescriptorBufferInfo {
        buffer: uniforms.handle,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let images: Vec<[vk::DescriptorImageInfo; 1]> = images
        .iter()
        .map(|&view| {
            [vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: view,
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
pub(crate) struct PipelineDesc {
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
    pub(crate) const GBUFFER: PipelineDesc = PipelineDesc {
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
    pub(crate) const SPLAT: PipelineDesc = PipelineDesc {
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
    pub(crate) const DISK: PipelineDesc = PipelineDesc {
        name: "disc pipeline",
        vertex: spirv::DISK_VERT,
        fragment: spirv::DISK_FRAG,
        depth_test: true,
        blend_add: false,
        ..PipelineDesc::SPLAT
    };
    pub(crate) const RESOLVE: PipelineDesc = PipelineDesc {
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

pub fn pipeline(
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
        .depth_compare_op(vk::CompareOp::GREATER);
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
