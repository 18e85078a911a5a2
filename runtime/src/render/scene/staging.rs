//! Staging: the scene's device buffers, and the uploader that streams byte
//! ranges into them through one reused staging buffer in two halves.

use crate::gpu::{Buffer, BufferDesc, Fence, Gpu, GpuError, MemoryLocation, VkContext};
use ash::vk;

pub(super) fn device_buffer(
    gpu: &Gpu,
    usage: vk::BufferUsageFlags,
    size: u64,
) -> Result<Buffer, GpuError> {
    Buffer::new(
        gpu,
        BufferDesc {
            size: size.max(4),
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        },
    )
}

/// Which of the three scene buffers a copy fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Target {
    Vertices,
    Indices,
    Coefficients,
}

/// One half of the staging buffer: its own pending copies, command buffer and
/// fence, so the host fills one half while the device copies out of the other.
pub(super) struct StagingHalf {
    /// Where the half starts in the staging buffer, and its size.
    pub(super) offset: u64,
    pub(super) size: u64,
    pub(super) fill: u64,
    pub(super) regions: Vec<(Target, vk::BufferCopy)>,
    pub(super) cmd: vk::CommandBuffer,
    pub(super) fence: Fence,
    /// Submitted and not yet waited for.
    pub(super) pending: bool,
}

/// Streams byte ranges into the scene buffers through one reused staging
/// buffer in two halves: [`Uploader::push`] copies into the current half; a
/// full half is submitted without waiting and filling goes on in the other,
/// once the device has finished copying out of it.
pub(super) struct Uploader<'a> {
    pub(super) gpu: &'a Gpu,
    // Declared before `staging`: dropped (and waited for) first.
    pub(super) halves: [StagingHalf; 2],
    pub(super) current: usize,
    pub(super) staging: Buffer,
    pub(super) targets: [vk::Buffer; 3],
    /// Submits so far (one per filled half) and the time spent waiting for
    /// them, for `--timings`.
    pub(super) submits: u32,
    pub(super) transfer: std::time::Duration,
}

impl<'a> Uploader<'a> {
    /// A staging buffer of two halves of `half` bytes each.
    pub(super) fn new(gpu: &'a Gpu, half: u64, targets: [vk::Buffer; 3]) -> Result<Self, GpuError> {
        let half = half.max(4).div_ceil(4) * 4;
        let staging = Buffer::new(
            gpu,
            BufferDesc {
                size: 2 * half,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::Mapped,
            },
        )?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(gpu.command_pool())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(2);
        // SAFETY: the pool belongs to this device and is used from this thread;
        // the buffers are freed in Drop after their fences are waited for.
        let cmds = unsafe { gpu.device().allocate_command_buffers(&alloc) }
            .ctx("vkAllocateCommandBuffers")?;
        let half_at = |k: usize, fence: Fence| StagingHalf {
            offset: k as u64 * half,
            size: half,
            fill: 0,
            regions: Vec::new(),
            cmd: cmds[k],
            fence,
            pending: false,
        };
        Ok(Uploader {
            gpu,
            halves: [
                half_at(0, Fence::new(gpu, false)?),
                half_at(1, Fence::new(gpu, false)?),
            ],
            current: 0,
            staging,
            targets,
            submits: 0,
            transfer: std::time::Duration::ZERO,
        })
    }

    pub(super) fn room(&self) -> u64 {
        let half = &self.halves[self.current];
        half.size - half.fill
    }

    /// Copies `bytes` (at most a half's size) to staging, bound for `target`
    /// at `dst_offset`.
    pub(super) fn push(
        &mut self,
        target: Target,
        dst_offset: u64,
        bytes: &[u8],
    ) -> Result<(), GpuError> {
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() as u64 > self.room() {
            self.flush()?;
        }
        let size = bytes.len() as u64;
        let half = &mut self.halves[self.current];
        let src_offset = half.offset + half.fill;
        // SAFETY: the half is not pending (flush waited for its fence before
        // making it current), so no device work reads this range of staging.
        unsafe { self.staging.write(src_offset, bytes) };
        // Consecutive pieces of one section continue the previous region.
        match half.regions.last_mut() {
            Some((t, r))
                if *t == target
                    && r.src_offset + r.size == src_offset
                    && r.dst_offset + r.size == dst_offset =>
            {
                r.size += size;
            }
            _ => half.regions.push((
                target,
                vk::BufferCopy {
                    src_offset,
                    dst_offset,
                    size,
                },
            )),
        }
        half.fill += size;
        Ok(())
    }

    /// Submits the current half's copies without waiting, then makes the other
    /// half current once the device has finished with it.
    pub(super) fn flush(&mut self) -> Result<(), GpuError> {
        if !self.halves[self.current].regions.is_empty() {
            self.submit(self.current)?;
        }
        self.current ^= 1;
        self.wait(self.current)
    }

    pub(super) fn submit(&mut self, k: usize) -> Result<(), GpuError> {
        let device = self.gpu.device();
        let half = &mut self.halves[k];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the half is not pending (waited for before it was filled), so
        // its command buffer may be re-recorded (the pool allows resets); every
        // region lies inside the staging buffer (push kept `fill` ≤ the half)
        // and inside its target, which `Plan` sized for every batch at its
        // offset; the fence is unsignalled (reset after its last wait).
        unsafe {
            device
                .begin_command_buffer(half.cmd, &begin)
                .ctx("vkBeginCommandBuffer")?;
            for (t, target) in [Target::Vertices, Target::Indices, Target::Coefficients]
                .into_iter()
                .enumerate()
            {
                let list: Vec<vk::BufferCopy> = half
                    .regions
                    .iter()
                    .filter(|(r, _)| *r == target)
                    .map(|(_, r)| *r)
                    .collect();
                if !list.is_empty() {
                    device.cmd_copy_buffer(half.cmd, self.staging.raw, self.targets[t], &list);
                }
            }
            device
                .end_command_buffer(half.cmd)
                .ctx("vkEndCommandBuffer")?;
            let cmds = [half.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            device
                .queue_submit(self.gpu.queue, &submit, half.fence.raw)
                .ctx("vkQueueSubmit")?;
        }
        half.pending = true;
        half.regions.clear();
        self.submits += 1;
        Ok(())
    }

    /// Waits for half `k`'s copies, leaving it empty and its fence reset.
    pub(super) fn wait(&mut self, k: usize) -> Result<(), GpuError> {
        let half = &mut self.halves[k];
        if half.pending {
            let start = std::time::Instant::now();
            half.fence.wait()?;
            half.fence.reset()?;
            half.pending = false;
            self.transfer += start.elapsed();
        }
        half.fill = 0;
        Ok(())
    }

    pub(super) fn finish(mut self) -> Result<(u32, std::time::Duration), GpuError> {
        self.flush()?;
        self.wait(self.current ^ 1)?;
        self.wait(self.current)?;
        Ok((self.submits, self.transfer))
    }
}

impl Drop for Uploader<'_> {
    fn drop(&mut self) {
        for half in &self.halves {
            if half.pending {
                // An upload abandoned mid-way (a checksum mismatch): the device
                // must stop reading staging memory before it is freed.
                let _ = half.fence.wait();
            }
        }
        let cmds = [self.halves[0].cmd, self.halves[1].cmd];
        // SAFETY: no submission of these command buffers is pending (waited for
        // above or in `finish`), and they came from this pool.
        unsafe {
            self.gpu
                .device()
                .free_command_buffers(self.gpu.command_pool(), &cmds)
        };
    }
}
