//! A window's surface and swapchain (docs/design.md §8's windowed mode): images the frame is
//! blitted into, acquired and presented in turn.

use super::device::{check, Gpu, VulkanError};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use std::sync::Arc;

/// The swapchain of one window.
pub(crate) struct Swapchain {
    gpu: Arc<Gpu>,
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    handle: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub format: vk::Format,
    pub extent: (u32, u32),
    /// Whether the images can be read back (for screenshots).
    pub readable: bool,
    /// Signalled when an image is acquired (one frame is in flight at a time).
    pub acquired: vk::Semaphore,
    /// Per image: signalled when its frame is drawn (an image is not acquired again before
    /// its presentation waited).
    pub rendered: Vec<vk::Semaphore>,
}

impl Swapchain {
    /// A surface on the window and a swapchain of `size` (or the surface's own extent).
    pub fn new(
        gpu: Arc<Gpu>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        size: (u32, u32),
    ) -> Result<Swapchain, VulkanError> {
        // SAFETY: the handles are a live window's; the surface is destroyed (in `drop`)
        // before the caller drops the window.
        let surface = check("vkCreate*SurfaceKHR", unsafe {
            ash_window::create_surface(gpu.entry(), &gpu.instance, display, window, None)
        })?;
        let surface_fn = ash::khr::surface::Instance::new(gpu.entry(), &gpu.instance);
        let swapchain_fn = ash::khr::swapchain::Device::new(&gpu.instance, &gpu.device);
        let semaphore = || {
            // SAFETY: a plain create call on our device.
            check("vkCreateSemaphore", unsafe {
                gpu.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            })
        };
        let acquired = semaphore()?;
        let mut sc = Swapchain {
            gpu: gpu.clone(),
            surface_fn,
            swapchain_fn,
            surface,
            handle: vk::SwapchainKHR::null(),
            images: vec![],
            format: vk::Format::UNDEFINED,
            extent: size,
            readable: false,
            acquired,
            rendered: vec![],
        };
        // SAFETY: a plain query.
        let supported = check("vkGetPhysicalDeviceSurfaceSupportKHR", unsafe {
            sc.surface_fn.get_physical_device_surface_support(
                gpu.physical,
                gpu.queue_family,
                surface,
            )
        })?;
        if !supported {
            return Err(VulkanError::Call {
                call: "vkGetPhysicalDeviceSurfaceSupportKHR (the device cannot present to this window)",
                result: vk::Result::ERROR_SURFACE_LOST_KHR,
            });
        }
        sc.recreate(size)?;
        Ok(sc)
    }

    /// Build the swapchain anew for a window of `size` (after a resize).
    pub(crate) fn recreate(&mut self, size: (u32, u32)) -> Result<(), VulkanError> {
        let gpu = &self.gpu;
        // SAFETY: plain queries of a live surface.
        let (caps, formats) = unsafe {
            (
                check(
                    "vkGetPhysicalDeviceSurfaceCapabilitiesKHR",
                    self.surface_fn
                        .get_physical_device_surface_capabilities(gpu.physical, self.surface),
                )?,
                check(
                    "vkGetPhysicalDeviceSurfaceFormatsKHR",
                    self.surface_fn
                        .get_physical_device_surface_formats(gpu.physical, self.surface),
                )?,
            )
        };
        // An sRGB format, so that the blit from the linear float output encodes it.
        let format = formats
            .iter()
            .find(|f| {
                matches!(
                    f.format,
                    vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
                ) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .or(formats.first())
            .copied()
            .ok_or(VulkanError::Call {
                call: "vkGetPhysicalDeviceSurfaceFormatsKHR (no format)",
                result: vk::Result::ERROR_FORMAT_NOT_SUPPORTED,
            })?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size
                    .0
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size
                    .1
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        self.readable = caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST;
        if self.readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let old = self.handle;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: the device is idle (no frame in flight: every frame waits for its fence),
        // and the old swapchain is retired into the new one, then destroyed.
        unsafe {
            let _ = gpu.device.device_wait_idle();
            self.handle = check(
                "vkCreateSwapchainKHR",
                self.swapchain_fn.create_swapchain(&info, None),
            )?;
            if old != vk::SwapchainKHR::null() {
                self.swapchain_fn.destroy_swapchain(old, None);
            }
            self.images = check(
                "vkGetSwapchainImagesKHR",
                self.swapchain_fn.get_swapchain_images(self.handle),
            )?;
            while self.rendered.len() < self.images.len() {
                let s = check(
                    "vkCreateSemaphore",
                    gpu.device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None),
                )?;
                self.rendered.push(s);
            }
        }
        for (i, &image) in self.images.iter().enumerate() {
            gpu.name(image, &format!("wpbgi swapchain image {i}"))?;
        }
        self.format = format.format;
        self.extent = (extent.width, extent.height);
        Ok(())
    }

    /// The next image to draw into; `None` when the swapchain no longer fits the window
    /// (recreate it).
    pub(crate) fn acquire(&self) -> Result<Option<u32>, VulkanError> {
        // SAFETY: the swapchain and semaphore are ours; the semaphore has no pending signal
        // (the previous frame's submit waited for it, and that submit completed).
        match unsafe {
            self.swapchain_fn.acquire_next_image(
                self.handle,
                u64::MAX,
                self.acquired,
                vk::Fence::null(),
            )
        } {
            Ok((i, _)) => Ok(Some(i)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(result) => Err(VulkanError::Call {
                call: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Present image `index` once its frame is drawn; `false` when the swapchain no longer
    /// fits the window.
    pub fn present(&self, index: u32) -> Result<bool, VulkanError> {
        let waits = [self.rendered[index as usize]];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(std::slice::from_ref(&self.handle))
            .image_indices(std::slice::from_ref(&index));
        // SAFETY: the image was acquired and its frame submitted, signalling `waits`.
        match unsafe { self.swapchain_fn.queue_present(self.gpu.queue, &info) } {
            Ok(suboptimal) => Ok(!suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(result) => Err(VulkanError::Call {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: the device is idle; everything here is ours and destroyed once, the
        // swapchain before its surface.
        unsafe {
            let _ = self.gpu.device.device_wait_idle();
            for &s in self.rendered.iter().chain([&self.acquired]) {
                self.gpu.device.destroy_semaphore(s, None);
            }
            self.swapchain_fn.destroy_swapchain(self.handle, None);
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}
