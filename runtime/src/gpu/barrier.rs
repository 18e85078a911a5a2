//! Image layout transitions: the one shape of `vkCmdPipelineBarrier` the
//! runtime records (image barriers only, no queue-family transfer), so that each
//! call site states just the image, the layouts, the accesses and the stages.

use ash::vk;

/// A barrier that moves `image` (the subresources in `range`) from layout
/// `from` to `to`, making the `src` accesses before it available to the `dst`
/// accesses after it. The queue family does not change.
pub fn image_barrier(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    (from, src): (vk::ImageLayout, vk::AccessFlags),
    (to, dst): (vk::ImageLayout, vk::AccessFlags),
) -> vk::ImageMemoryBarrier<'static> {
    vk::ImageMemoryBarrier::default()
        .src_access_mask(src)
        .dst_access_mask(dst)
        .old_layout(from)
        .new_layout(to)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)
}

/// Records one pipeline barrier holding `barriers` (and no global or buffer
/// barriers) between the `src` and `dst` pipeline stages.
///
/// # Safety
///
/// `cmd` is a command buffer of `device` in the recording state, outside a
/// render pass, and every barrier names a live image of `device` whose current
/// layout, when the barrier executes, is the barrier's old layout (or the
/// old layout is `UNDEFINED`).
pub unsafe fn cmd_image_barriers(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    src: vk::PipelineStageFlags,
    dst: vk::PipelineStageFlags,
    barriers: &[vk::ImageMemoryBarrier<'_>],
) {
    // SAFETY: the caller guarantees the command buffer's state and the images;
    // the barrier arrays are borrowed for the call.
    unsafe {
        device.cmd_pipeline_barrier(
            cmd,
            src,
            dst,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            barriers,
        )
    };
}
