//! Copies out of a frame: image layout barriers, reading an image back into a host buffer, and
//! the blit of the float output into a window's swapchain image.

use super::objects::whole;
use ash::vk;

const COLOR: vk::ImageAspectFlags = vk::ImageAspectFlags::COLOR;

/// A barrier that moves `image` from layout `from` to `to`, ordering `src` accesses before
/// `dst` ones.
pub(crate) fn layout_barrier(
    image: vk::Image,
    (from, src): (vk::ImageLayout, vk::AccessFlags),
    (to, dst): (vk::ImageLayout, vk::AccessFlags),
) -> vk::ImageMemoryBarrier<'static> {
    vk::ImageMemoryBarrier::default()
        .old_layout(from)
        .new_layout(to)
        .src_access_mask(src)
        .dst_access_mask(dst)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(whole(COLOR))
}

/// The one mip level and layer of a colour image.
fn colour_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers {
        aspect_mask: COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// Record one barrier between `from` and `to` stages.
///
/// # Safety
/// `cmd` is recording, and the barrier's image is the device's.
unsafe fn barrier(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    (from, to): (vk::PipelineStageFlags, vk::PipelineStageFlags),
    b: vk::ImageMemoryBarrier<'_>,
) {
    // SAFETY: the caller's contract.
    unsafe { d.cmd_pipeline_barrier(cmd, from, to, vk::DependencyFlags::empty(), &[], &[], &[b]) };
}

/// Record copying `image` (of `size`, in TRANSFER_SRC_OPTIMAL) into `buffer`, visible to the
/// host once the submission completes. With `around`, the image is in that layout, read by
/// shaders, and is moved to the transfer layout and back.
///
/// # Safety
/// `cmd` is recording; `image` and `buffer` are the device's, and `buffer` holds the image.
pub unsafe fn record_readback(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    (image, size): (vk::Image, (u32, u32)),
    buffer: vk::Buffer,
    around: Option<vk::ImageLayout>,
) {
    let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    let (shader, read) = (vk::AccessFlags::SHADER_READ, vk::AccessFlags::TRANSFER_READ);
    let all = vk::PipelineStageFlags::ALL_COMMANDS;
    let region = vk::BufferImageCopy::default()
        .image_subresource(colour_layers())
        .image_extent(vk::Extent3D {
            width: size.0,
            height: size.1,
            depth: 1,
        });
    let to_host = vk::BufferMemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(vk::AccessFlags::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(buffer)
        .size(vk::WHOLE_SIZE);
    let back = around.map(|l| layout_barrier(image, (src, read), (l, shader)));
    // SAFETY: the caller's contract.
    unsafe {
        if let Some(l) = around {
            barrier(
                d,
                cmd,
                (all, all),
                layout_barrier(image, (l, shader), (src, read)),
            );
        }
        d.cmd_copy_image_to_buffer(cmd, image, src, buffer, &[region]);
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST | all,
            vk::DependencyFlags::empty(),
            &[],
            &[to_host],
            back.as_slice(),
        );
    }
}

/// Record the blit of `output` (of `size`, in TRANSFER_SRC_OPTIMAL) into the acquired
/// swapchain image `target` (of `target_size`; the blit scales the frame to it, filtering
/// linearly where `linear`, and converts it to the image's format), leaving the image ready to
/// present; with `screenshot`, also read it back into that buffer.
///
/// # Safety
/// `cmd` is recording; the submission waits for `target`'s acquisition at the transfer stage;
/// with `screenshot`, `target` can be read and fits in the buffer.
pub unsafe fn record_present(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    (output, size): (vk::Image, (u32, u32)),
    (target, target_size): (vk::Image, (u32, u32)),
    screenshot: Option<vk::Buffer>,
    linear: bool,
) {
    let corner = |(w, h): (u32, u32)| vk::Offset3D {
        x: w as i32,
        y: h as i32,
        z: 1,
    };
    let blit = vk::ImageBlit {
        src_subresource: colour_layers(),
        src_offsets: [vk::Offset3D::default(), corner(size)],
        dst_subresource: colour_layers(),
        dst_offsets: [vk::Offset3D::default(), corner(target_size)],
    };
    let filter = if linear && size != target_size {
        vk::Filter::LINEAR
    } else {
        vk::Filter::NEAREST
    };
    let transfer = vk::PipelineStageFlags::TRANSFER;
    let none = vk::AccessFlags::empty();
    let dst = (
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::AccessFlags::TRANSFER_WRITE,
    );
    let src = (
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        vk::AccessFlags::TRANSFER_READ,
    );
    // SAFETY: the caller's contract.
    unsafe {
        let undefined = (vk::ImageLayout::UNDEFINED, none);
        barrier(
            d,
            cmd,
            (transfer, transfer),
            layout_barrier(target, undefined, dst),
        );
        d.cmd_blit_image(cmd, output, src.0, target, dst.0, &[blit], filter);
        let mut last = dst;
        if let Some(buffer) = screenshot {
            barrier(
                d,
                cmd,
                (transfer, transfer),
                layout_barrier(target, dst, src),
            );
            record_readback(d, cmd, (target, target_size), buffer, None);
            last = src;
        }
        let present = (vk::ImageLayout::PRESENT_SRC_KHR, none);
        let stages = (transfer, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
        barrier(d, cmd, stages, layout_barrier(target, last, present));
    }
}
