//! The previewer's Vulkan objects, owned in one place: every object is registered the moment
//! it is created and destroyed, children first, when its [`Objects`] is dropped, so that no
//! error path leaks one (the validation layer reports leaks). Every object gets a name.

use super::device::{check, Gpu, VulkanError};
use ash::vk;
use std::ffi::c_void;
use std::sync::Arc;

/// A Vulkan object that [`Objects`] destroys.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Owned {
    Memory(vk::DeviceMemory),
    Buffer(vk::Buffer),
    Image(vk::Image),
    View(vk::ImageView),
    Sampler(vk::Sampler),
    RenderPass(vk::RenderPass),
    Framebuffer(vk::Framebuffer),
    Shader(vk::ShaderModule),
    SetLayout(vk::DescriptorSetLayout),
    DescriptorPool(vk::DescriptorPool),
    PipelineLayout(vk::PipelineLayout),
    Pipeline(vk::Pipeline),
    CommandPool(vk::CommandPool),
    Fence(vk::Fence),
}

/// A host-visible, coherent buffer, mapped for its lifetime.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Buffer {
    pub handle: vk::Buffer,
    memory: vk::DeviceMemory,
    pub size: u64,
    mapped: *mut c_void,
}

impl Buffer {
    /// Copy `data` to the start of the buffer (at most its size).
    pub fn write<T: bytemuck::Pod>(&self, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let n = bytes.len().min(self.size as usize);
        // SAFETY: `mapped` points to `size` bytes of host-coherent memory that only this
        // thread touches while no submitted command reads it (callers wait for the fence).
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), self.mapped as *mut u8, n) };
    }

    /// The first `n` values of type `T` in the buffer (fewer if it is smaller).
    pub fn read<T: bytemuck::Pod>(&self, n: usize) -> Vec<T> {
        let n = n.min(self.size as usize / std::mem::size_of::<T>());
        let mut out = vec![T::zeroed(); n];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        // SAFETY: as in `write`; the GPU's writes are complete (the caller waited).
        unsafe {
            std::ptr::copy_nonoverlapping(self.mapped as *const u8, bytes.as_mut_ptr(), bytes.len())
        };
        out
    }
}

/// A device-local 2D image with one view.
#[derive(Clone, Copy, Debug)]
pub struct Image {
    pub handle: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
}

/// The owner of a set of Vulkan objects of one device.
pub(crate) struct Objects {
    pub gpu: Arc<Gpu>,
    owned: Vec<Owned>,
}

impl Objects {
    pub fn new(gpu: Arc<Gpu>) -> Objects {
        Objects {
            gpu,
            owned: Vec::new(),
        }
    }

    pub fn device(&self) -> &ash::Device {
        &self.gpu.device
    }

    fn keep(&mut self, o: Owned) {
        self.owned.push(o);
    }

    /// Name `handle` (see [`Gpu::name`]).
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) -> Result<(), VulkanError> {
        self.gpu.name(handle, &format!("wpbgi {name}"))
    }

    fn memory_type(&self, bits: u32, want: vk::MemoryPropertyFlags) -> Option<u32> {
        // SAFETY: a plain query of the physical device.
        let props = unsafe {
            self.gpu
                .instance
                .get_physical_device_memory_properties(self.gpu.physical)
        };
        (0..props.memory_type_count).find(|&i| {
            bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(want)
        })
    }

    fn allocate(
        &mut self,
        name: &str,
        req: vk::MemoryRequirements,
        want: vk::MemoryPropertyFlags,
    ) -> Result<vk::DeviceMemory, VulkanError> {
        let index = self
            .memory_type(req.memory_type_bits, want)
            .or_else(|| self.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty()))
            .ok_or(VulkanError::Call {
                call: "vkAllocateMemory (no memory type fits)",
                result: vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            })?;
        let info = vk::MemoryAllocateInfo::default()
            .allocation_size(req.size)
            .memory_type_index(index);
        // SAFETY: a valid allocate info for this device.
        let memory = check("vkAllocateMemory", unsafe {
            self.device().allocate_memory(&info, None)
        })?;
        self.keep(Owned::Memory(memory));
        self.name(memory, &format!("{name} memory"))?;
        Ok(memory)
    }

    /// A host-visible, coherent buffer of `size` bytes (at least 16).
    pub fn buffer(
        &mut self,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer, VulkanError> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: a valid create info for this device.
        let handle = check("vkCreateBuffer", unsafe {
            self.device().create_buffer(&info, None)
        })?;
        self.keep(Owned::Buffer(handle));
        self.name(handle, name)?;
        // SAFETY: the buffer is this device's.
        let req = unsafe { self.device().get_buffer_memory_requirements(handle) };
        let memory = self.allocate(
            name,
            req,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
        )?;
        // SAFETY: fresh memory of a fitting type, bound once, then mapped whole.
        let mapped = unsafe {
            check(
                "vkBindBufferMemory",
                self.device().bind_buffer_memory(handle, memory, 0),
            )?;
            check(
                "vkMapMemory",
                self.device()
                    .map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()),
            )?
        };
        Ok(Buffer {
            handle,
            memory,
            size,
            mapped,
        })
    }

    /// A device-local image of `width` × `height` with a view of `aspect`.
    pub fn image(
        &mut self,
        name: &str,
        (width, height): (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
    ) -> Result<Image, VulkanError> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info for this device.
        let handle = check("vkCreateImage", unsafe {
            self.device().create_image(&info, None)
        })?;
        self.keep(Owned::Image(handle));
        self.name(handle, name)?;
        // SAFETY: the image is this device's.
        let req = unsafe { self.device().get_image_memory_requirements(handle) };
        let memory = self.allocate(name, req, vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
        // SAFETY: fresh memory of a fitting type, bound once.
        check("vkBindImageMemory", unsafe {
            self.device().bind_image_memory(handle, memory, 0)
        })?;
        let view = self.view(name, handle, format, aspect)?;
        Ok(Image {
            handle,
            view,
            format,
        })
    }

    /// A 2D view of all of `image`.
    pub fn view(
        &mut self,
        name: &str,
        image: vk::Image,
        format: vk::Format,
        aspect: vk::ImageAspectFlags,
    ) -> Result<vk::ImageView, VulkanError> {
        let info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(whole(aspect));
        // SAFETY: a valid create info for an image of this device.
        let view = check("vkCreateImageView", unsafe {
            self.device().create_image_view(&info, None)
        })?;
        self.keep(Owned::View(view));
        self.name(view, &format!("{name} view"))?;
        Ok(view)
    }

    /// Destroy `buffer` now (a buffer that is outgrown).
    pub(crate) fn release_buffer(&mut self, buffer: Buffer) {
        for o in [Owned::Buffer(buffer.handle), Owned::Memory(buffer.memory)] {
            if let Some(i) = self.owned.iter().position(|&x| x == o) {
                self.owned.remove(i);
                // SAFETY: the object is ours and no pending command uses it (callers wait).
                unsafe { destroy(self.device(), o) };
            }
        }
    }
}

/// Register-and-name wrappers for the objects that need no memory.
macro_rules! owned_creator {
    ($fn:ident, $info:ty, $handle:ty, $variant:ident, $create:ident, $call:literal) => {
        impl Objects {
            pub fn $fn(&mut self, name: &str, info: &$info) -> Result<$handle, VulkanError> {
                // SAFETY: `info` is a valid create info for this device; the caller keeps
                // what it points to alive through the call.
                let h = check($call, unsafe { self.gpu.device.$create(info, None) })?;
                self.keep(Owned::$variant(h));
                self.name(h, name)?;
                Ok(h)
            }
        }
    };
}

owned_creator!(
    sampler,
    vk::SamplerCreateInfo<'_>,
    vk::Sampler,
    Sampler,
    create_sampler,
    "vkCreateSampler"
);
owned_creator!(
    render_pass,
    vk::RenderPassCreateInfo<'_>,
    vk::RenderPass,
    RenderPass,
    create_render_pass,
    "vkCreateRenderPass"
);
owned_creator!(
    framebuffer,
    vk::FramebufferCreateInfo<'_>,
    vk::Framebuffer,
    Framebuffer,
    create_framebuffer,
    "vkCreateFramebuffer"
);
owned_creator!(
    shader,
    vk::ShaderModuleCreateInfo<'_>,
    vk::ShaderModule,
    Shader,
    create_shader_module,
    "vkCreateShaderModule"
);
owned_creator!(
    set_layout,
    vk::DescriptorSetLayoutCreateInfo<'_>,
    vk::DescriptorSetLayout,
    SetLayout,
    create_descriptor_set_layout,
    "vkCreateDescriptorSetLayout"
);
owned_creator!(
    descriptor_pool,
    vk::DescriptorPoolCreateInfo<'_>,
    vk::DescriptorPool,
    DescriptorPool,
    create_descriptor_pool,
    "vkCreateDescriptorPool"
);
owned_creator!(
    pipeline_layout,
    vk::PipelineLayoutCreateInfo<'_>,
    vk::PipelineLayout,
    PipelineLayout,
    create_pipeline_layout,
    "vkCreatePipelineLayout"
);
owned_creator!(
    command_pool,
    vk::CommandPoolCreateInfo<'_>,
    vk::CommandPool,
    CommandPool,
    create_command_pool,
    "vkCreateCommandPool"
);
owned_creator!(
    fence,
    vk::FenceCreateInfo<'_>,
    vk::Fence,
    Fence,
    create_fence,
    "vkCreateFence"
);

impl Objects {
    /// A graphics pipeline.
    pub fn pipeline(
        &mut self,
        name: &str,
        info: &vk::GraphicsPipelineCreateInfo<'_>,
    ) -> Result<vk::Pipeline, VulkanError> {
        // SAFETY: `info` is a valid create info whose pointers outlive the call.
        let p = unsafe {
            self.gpu.device.create_graphics_pipelines(
                vk::PipelineCache::null(),
                std::slice::from_ref(info),
                None,
            )
        }
        .map_err(|(_, result)| VulkanError::Call {
            call: "vkCreateGraphicsPipelines",
            result,
        })?;
        let p = p[0];
        self.keep(Owned::Pipeline(p));
        self.name(p, name)?;
        Ok(p)
    }
}

/// All of an image's one mip level and layer.
pub fn whole(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// Destroy one object.
///
/// # Safety
/// The object belongs to `device`, and nothing uses it any more.
unsafe fn destroy(device: &ash::Device, o: Owned) {
    // SAFETY: the caller's contract.
    unsafe {
        match o {
            Owned::Memory(h) => device.free_memory(h, None),
            Owned::Buffer(h) => device.destroy_buffer(h, None),
            Owned::Image(h) => device.destroy_image(h, None),
            Owned::View(h) => device.destroy_image_view(h, None),
            Owned::Sampler(h) => device.destroy_sampler(h, None),
            Owned::RenderPass(h) => device.destroy_render_pass(h, None),
            Owned::Framebuffer(h) => device.destroy_framebuffer(h, None),
            Owned::Shader(h) => device.destroy_shader_module(h, None),
            Owned::SetLayout(h) => device.destroy_descriptor_set_layout(h, None),
            Owned::DescriptorPool(h) => device.destroy_descriptor_pool(h, None),
            Owned::PipelineLayout(h) => device.destroy_pipeline_layout(h, None),
            Owned::Pipeline(h) => device.destroy_pipeline(h, None),
            Owned::CommandPool(h) => device.destroy_command_pool(h, None),
            Owned::Fence(h) => device.destroy_fence(h, None),
        }
    }
}

impl Drop for Objects {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait, and every object is destroyed once, in
        // the reverse of its creation (views before images, buffers before their memory...).
        unsafe {
            let _ = self.gpu.device.device_wait_idle();
            for &o in self.owned.iter().rev() {
                destroy(&self.gpu.device, o);
            }
        }
    }
}
