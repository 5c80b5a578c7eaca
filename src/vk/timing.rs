//! Timestamp scopes per pass; medians over the frames rendered.

use super::{Check, Context, VkResult};
use ash::vk;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Frames of timings kept: a renderer can run for hours (a window, `voxgi soak`); the reports'
/// medians are over the last of them.
pub const TIMED_FRAMES: usize = 600;

/// Once a series reaches twice [`TIMED_FRAMES`], keeps only its last [`TIMED_FRAMES`].
pub fn keep_recent(v: &mut Vec<f64>) {
    if v.len() >= 2 * TIMED_FRAMES {
        v.drain(..v.len() - TIMED_FRAMES);
    }
}

pub struct PassTimer {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    capacity: u32,
    used: u32,
    /// Pass names in the order their scopes began this frame.
    names: Vec<String>,
    /// Milliseconds per pass over the collected frames (the last [`TIMED_FRAMES`] to twice
    /// that), in first-seen order.
    pub samples: Vec<(String, Vec<f64>)>,
}

pub struct Scope(u32);

impl PassTimer {
    /// None when the queue has no timestamps.
    pub fn new(ctx: &Arc<Context>, max_passes: u32) -> VkResult<Option<PassTimer>> {
        if ctx.timestamp_valid_bits == 0 {
            return Ok(None);
        }
        let capacity = max_passes * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool =
            unsafe { ctx.device.create_query_pool(&info, None) }.check("vkCreateQueryPool")?;
        unsafe { ctx.device.reset_query_pool(pool, 0, capacity) };
        Ok(Some(PassTimer {
            ctx: ctx.clone(),
            pool,
            capacity,
            used: 0,
            names: Vec::new(),
            samples: Vec::new(),
        }))
    }

    pub fn begin(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, name: &str) -> Scope {
        let q = self.used;
        if q + 2 > self.capacity {
            return Scope(u32::MAX);
        }
        self.used += 2;
        self.names.push(name.to_string());
        // ALL_COMMANDS on both ends: the scope starts when earlier work is done and ends when
        // its own is (lavapipe writes TOP/BOTTOM_OF_PIPE timestamps without waiting for compute).
        unsafe {
            device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, q)
        };
        Scope(q)
    }

    pub fn end(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, scope: Scope) {
        if scope.0 == u32::MAX {
            return;
        }
        unsafe {
            device.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                scope.0 + 1,
            )
        };
    }

    /// After the frame's command buffer has completed: reads the scopes and resets the pool.
    pub fn collect(&mut self) -> VkResult<()> {
        if self.used == 0 {
            return Ok(());
        }
        let mut data = vec![0u64; self.used as usize];
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .check("vkGetQueryPoolResults")?;
        let period = self.ctx.properties.limits.timestamp_period as f64;
        let mask = if self.ctx.timestamp_valid_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << self.ctx.timestamp_valid_bits) - 1
        };
        // Scopes of the same name within a frame add up (e.g. one per mip level).
        let mut frame: Vec<(String, f64)> = Vec::new();
        for (i, name) in self.names.drain(..).enumerate() {
            let t0 = data[2 * i] & mask;
            let t1 = data[2 * i + 1] & mask;
            let ms = t1.wrapping_sub(t0) as f64 * period / 1e6;
            match frame.iter_mut().find(|(n, _)| *n == name) {
                Some((_, t)) => *t += ms,
                None => frame.push((name, ms)),
            }
        }
        for (name, ms) in frame {
            match self.samples.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => {
                    v.push(ms);
                    keep_recent(v);
                }
                None => self.samples.push((name, vec![ms])),
            }
        }
        unsafe { self.ctx.device.reset_query_pool(self.pool, 0, self.used) };
        self.used = 0;
        Ok(())
    }

    /// (pass, median ms, min ms, max ms) per pass.
    pub fn medians(&self) -> Vec<(String, f64, f64, f64)> {
        self.samples
            .iter()
            .map(|(n, v)| {
                let mut s = v.clone();
                s.sort_by(|a, b| a.total_cmp(b));
                let med = if s.len() % 2 == 1 {
                    s[s.len() / 2]
                } else {
                    0.5 * (s[s.len() / 2 - 1] + s[s.len() / 2])
                };
                (n.clone(), med, s[0], s[s.len() - 1])
            })
            .collect()
    }

    pub fn report(&self) -> String {
        let rows: BTreeMap<usize, String> = self
            .medians()
            .into_iter()
            .enumerate()
            .map(|(i, (n, med, lo, hi))| {
                (
                    i,
                    format!("  {n:<16} {med:9.3} ms  (min {lo:.3}, max {hi:.3})"),
                )
            })
            .collect();
        let total: f64 = self.medians().iter().map(|r| r.1).sum();
        let frames = self.samples.iter().map(|s| s.1.len()).max().unwrap_or(0);
        let mut out = format!("pass timings, median over {frames} frame(s):\n");
        for r in rows.values() {
            out.push_str(r);
            out.push('\n');
        }
        out.push_str(&format!("  {:<16} {total:9.3} ms\n", "sum"));
        out
    }
}

impl Drop for PassTimer {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timings_keep_only_recent_frames() {
        let mut v: Vec<f64> = (0..2 * TIMED_FRAMES - 1).map(|i| i as f64).collect();
        keep_recent(&mut v);
        assert_eq!(v.len(), 2 * TIMED_FRAMES - 1);
        v.push(v.len() as f64);
        keep_recent(&mut v);
        assert_eq!(v.len(), TIMED_FRAMES);
        assert_eq!(v[0], TIMED_FRAMES as f64);
        assert_eq!(*v.last().unwrap(), (2 * TIMED_FRAMES - 1) as f64);
    }
}
