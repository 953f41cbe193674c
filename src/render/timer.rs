//! GPU time of a render pass from timestamp queries, where the adapter has them
//! (`Features::TIMESTAMP_QUERY`): what `lodlab bench` reports in place of wall time.

use super::gpu::Gpu;
use anyhow::{Result, anyhow};

/// Two timestamps, at the beginning and at the end of one render pass, resolved into a buffer
/// and read back after the frame.
pub struct PassTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

const QUERIES: u32 = 2;
const BYTES: u64 = QUERIES as u64 * 8;

impl PassTimer {
    /// A timer, or `None` where the device has no timestamp queries.
    pub fn new(gpu: &Gpu) -> Option<PassTimer> {
        if !gpu
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            return None;
        }
        let queries = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: QUERIES,
        });
        let buffer = |label, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(PassTimer {
            queries,
            resolved: buffer(
                "timestamps",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "timestamps read-back",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            period_ns: gpu.queue.get_timestamp_period() as f64,
        })
    }

    /// What the timed pass writes.
    pub fn writes(&self) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// Resolves the timestamps for reading, after the timed pass, in the same encoder.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..QUERIES, &self.resolved, 0);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.readback, 0, BYTES);
    }

    /// The timed pass's GPU time in milliseconds, once the frame is submitted (waits for it).
    pub fn read_ms(&self, gpu: &Gpu) -> Result<f64> {
        let (tx, rx) = std::sync::mpsc::channel();
        self.readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        gpu.wait()?;
        rx.recv()?
            .map_err(|e| anyhow!("timestamp read-back failed: {e}"))?;
        let ticks: [u64; 2] = {
            let data = self
                .readback
                .get_mapped_range(..)
                .map_err(|e| anyhow!("timestamp read-back failed: {e}"))?;
            bytemuck::pod_read_unaligned(&data[..BYTES as usize])
        };
        self.readback.unmap();
        Ok(ticks[1].saturating_sub(ticks[0]) as f64 * self.period_ns * 1e-6)
    }
}
