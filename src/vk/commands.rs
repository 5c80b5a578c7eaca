//! A command pool and the one command buffer a renderer records each frame into.

use super::{Check, Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// A command pool with one resettable primary command buffer, freed on drop (also when its
/// owner's constructor fails half way).
pub struct CommandPool {
    ctx: Arc<Context>,
    raw: vk::CommandPool,
    /// Reset and recorded again each frame.
    pub cmd: vk::CommandBuffer,
}

impl CommandPool {
    pub fn new(ctx: &Arc<Context>) -> VkResult<CommandPool> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let raw =
            unsafe { ctx.device.create_command_pool(&info, None) }.check("vkCreateCommandPool")?;
        let mut pool = CommandPool {
            ctx: ctx.clone(),
            raw,
            cmd: vk::CommandBuffer::null(),
        };
        pool.cmd = unsafe {
            ctx.device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(raw)
                    .command_buffer_count(1),
            )
        }
        .check("vkAllocateCommandBuffers")?[0];
        Ok(pool)
    }

    /// Resets the command buffer and begins recording it for one submission.
    pub fn begin(&self) -> VkResult<vk::CommandBuffer> {
        let d = &self.ctx.device;
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .check("vkResetCommandBuffer")?;
            d.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .check("vkBeginCommandBuffer")?;
        }
        Ok(self.cmd)
    }

    pub fn end(&self) -> VkResult<()> {
        unsafe { self.ctx.device.end_command_buffer(self.cmd) }.check("vkEndCommandBuffer")
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_command_pool(self.raw, None) };
    }
}
