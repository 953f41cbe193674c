//! Where a frame's GPU time goes: the time of each render pass from timestamp queries
//! (`Features::TIMESTAMP_QUERY`), and the fragments each pass shades from pipeline-statistics
//! queries (`Features::PIPELINE_STATISTICS_QUERY`), where the adapter has them.
//!
//! Why passes and not timestamps inside one pass: a software rasteriser (Mesa lavapipe, on
//! llvmpipe) bins a whole pass and then rasterises it tile by tile on several threads, so a
//! timestamp written between two draws of a pass only says when the last thread passed that
//! point in its last tile, near the end of the pass. Timestamps at the boundaries of render
//! passes are taken after a flush, so they split the frame honestly on every adapter, and
//! wgpu needs no feature beyond `TIMESTAMP_QUERY` for them.
//!
//! Results come back through a small ring of read-back buffers: `bench` and `shot` wait for
//! each frame's ([`FrameTimer::read`]), while the viewer takes whichever frame has arrived
//! ([`FrameTimer::try_read`]) and never stalls on the GPU.

use super::gpu::Gpu;
use anyhow::{Result, anyhow};
use std::cell::Cell;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

crate::choice! {
    /// The render passes of a frame, in the order they are drawn.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
    pub enum Pass {
        /// Opaque characters (and everything, for the plain calibration shader).
        Characters => "characters",
        /// Trees: full-detail foliage and billboard clouds, alpha tested.
        Foliage => "foliage",
        /// The ground and the sky, behind everything drawn before them.
        Environment => "sky and ground",
        /// Blob shadows blended over the ground.
        Shadows => "shadows",
        /// The faded levels of alpha-blend transitions.
        Transitions => "transitions",
        /// The viewer's panel.
        Ui => "ui",
    }
}

impl Pass {
    pub const COUNT: usize = Pass::ALL.len();

    fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// One frame's figures, by pass; `None` for a pass the frame did not draw.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// GPU milliseconds of each pass.
    pub ms: [Option<f64>; Pass::COUNT],
    /// Fragment-shader invocations of each pass, where the adapter counts them.
    pub fragments: [Option<u64>; Pass::COUNT],
    /// From the beginning of the first pass to the end of the last: the frame's GPU time,
    /// gaps between passes included.
    pub frame_ms: f64,
}

impl PassTimes {
    /// The passes drawn, with their milliseconds.
    pub fn drawn(&self) -> impl Iterator<Item = (Pass, f64)> + '_ {
        Pass::ALL
            .iter()
            .zip(&self.ms)
            .filter_map(|(&p, ms)| ms.map(|ms| (p, ms)))
    }

    /// Fragments shaded per pixel of a `pixels`-pixel view over all passes: the overdraw.
    pub fn overdraw(&self, pixels: u64) -> Option<f64> {
        let counted = self.fragments.iter().flatten();
        (counted.clone().next().is_some() && pixels > 0)
            .then(|| counted.sum::<u64>() as f64 / pixels as f64)
    }
}

impl PassTimes {
    /// An exponential moving average: `self` moved by `weight` towards `new` (a pass either
    /// lacks takes `new`'s figure or drops out).
    pub fn smoothed(&self, new: &PassTimes, weight: f64) -> PassTimes {
        let mix = |a: f64, b: f64| a + (b - a) * weight;
        let mut out = *new;
        for i in 0..Pass::COUNT {
            if let (Some(a), Some(b)) = (self.ms[i], new.ms[i]) {
                out.ms[i] = Some(mix(a, b));
            }
            if let (Some(a), Some(b)) = (self.fragments[i], new.fragments[i]) {
                out.fragments[i] = Some(mix(a as f64, b as f64).round() as u64);
            }
        }
        out.frame_ms = mix(self.frame_ms, new.frame_ms);
        out
    }
}

/// Median milliseconds of each pass over the frames that drew it, by pass name.
pub fn pass_medians(frames: &[PassTimes]) -> BTreeMap<String, f64> {
    Pass::ALL
        .iter()
        .filter_map(|&p| {
            let ms: Vec<f64> = frames.iter().filter_map(|t| t.ms[p as usize]).collect();
            median(ms).map(|m| (p.name().to_string(), m))
        })
        .collect()
}

/// Median fragments shaded per pixel of a `width` × `height` view over the frames, where
/// they were counted.
pub fn overdraw_median(frames: &[PassTimes], width: u32, height: u32) -> Option<f64> {
    let pixels = width as u64 * height as u64;
    median(frames.iter().filter_map(|t| t.overdraw(pixels)).collect())
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// Bytes between the results of two passes: query resolves must start at multiples of
/// `QUERY_RESOLVE_BUFFER_ALIGNMENT`.
const STRIDE: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;
/// Pass `i`'s two timestamps lie at `i · STRIDE`, its fragment count at `(COUNT + i) · STRIDE`.
const BYTES: u64 = 2 * Pass::COUNT as u64 * STRIDE;
/// Frames in flight at most: the viewer skips timing a frame while all are out.
const RING: usize = 3;

const IDLE: u8 = 0;
const MAPPING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

struct Readback {
    buffer: wgpu::Buffer,
    /// The passes its frame recorded, and those whose fragments were counted.
    passes: u32,
    counted: u32,
    state: Arc<AtomicU8>,
}

pub struct FrameTimer {
    timestamps: wgpu::QuerySet,
    statistics: Option<wgpu::QuerySet>,
    resolved: wgpu::Buffer,
    ring: Vec<Readback>,
    /// Ring slots holding frames, oldest first.
    queued: Vec<usize>,
    /// The slot the frame being recorded resolves into, once [`Self::resolve`] ran.
    pending: Option<usize>,
    /// Passes recorded in the frame being recorded, and those of them whose fragments were
    /// counted.
    recorded: Cell<u32>,
    counted: Cell<u32>,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

impl FrameTimer {
    /// A timer, or `None` where the device has no timestamp queries.
    pub fn new(gpu: &Gpu) -> Option<FrameTimer> {
        let features = gpu.device.features();
        if !features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let timestamps = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * Pass::COUNT as u32,
        });
        let statistics = features
            .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
            .then(|| {
                gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass fragments"),
                    ty: wgpu::QueryType::PipelineStatistics(
                        wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                    ),
                    count: Pass::COUNT as u32,
                })
            });
        let buffer = |label, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES,
                usage,
                mapped_at_creation: false,
            })
        };
        let ring = (0..RING)
            .map(|_| Readback {
                buffer: buffer(
                    "pass queries read-back",
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                ),
                passes: 0,
                counted: 0,
                state: Arc::new(AtomicU8::new(IDLE)),
            })
            .collect();
        Some(FrameTimer {
            timestamps,
            statistics,
            resolved: buffer(
                "pass queries",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            ring,
            queued: Vec::new(),
            pending: None,
            recorded: Cell::new(0),
            counted: Cell::new(0),
            period_ns: gpu.queue.get_timestamp_period() as f64,
        })
    }

    /// The timestamps `pass` writes at its beginning and end; marks it recorded.
    pub fn writes(&self, pass: Pass) -> wgpu::RenderPassTimestampWrites<'_> {
        self.recorded.set(self.recorded.get() | pass.bit());
        let i = pass as u32;
        wgpu::RenderPassTimestampWrites {
            query_set: &self.timestamps,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        }
    }

    /// Starts counting `pass`'s fragments in `rp`, where the adapter counts them; end with
    /// [`Self::end_count`].
    pub fn begin_count(&self, rp: &mut wgpu::RenderPass<'_>, pass: Pass) {
        if let Some(q) = &self.statistics {
            self.counted.set(self.counted.get() | pass.bit());
            rp.begin_pipeline_statistics_query(q, pass as u32);
        }
    }

    pub fn end_count(&self, rp: &mut wgpu::RenderPass<'_>) {
        if self.statistics.is_some() {
            rp.end_pipeline_statistics_query();
        }
    }

    /// Resolves the queries of the passes recorded since the last call, after the last of
    /// them, into a free read-back slot. Times nothing when no pass was recorded or every
    /// slot is still waiting for an earlier frame.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let passes = self.recorded.replace(0);
        let counted = self.counted.replace(0) & passes;
        self.pending = None;
        if passes == 0 {
            return;
        }
        let idle = |s: &usize| self.ring[*s].state.load(Ordering::Acquire) == IDLE;
        let Some(slot) = (0..RING).find(idle) else {
            return;
        };
        for pass in Pass::ALL.into_iter().filter(|p| passes & p.bit() != 0) {
            let i = pass as u32;
            encoder.resolve_query_set(
                &self.timestamps,
                2 * i..2 * i + 2,
                &self.resolved,
                i as u64 * STRIDE,
            );
            if let Some(q) = self
                .statistics
                .as_ref()
                .filter(|_| counted & pass.bit() != 0)
            {
                encoder.resolve_query_set(
                    q,
                    i..i + 1,
                    &self.resolved,
                    (Pass::COUNT as u64 + i as u64) * STRIDE,
                );
            }
        }
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.ring[slot].buffer, 0, BYTES);
        self.ring[slot].passes = passes;
        self.ring[slot].counted = counted;
        self.pending = Some(slot);
    }

    /// After the frame [`Self::resolve`] went into was submitted: starts reading it back.
    pub fn submitted(&mut self) {
        let Some(slot) = self.pending.take() else {
            return;
        };
        let state = self.ring[slot].state.clone();
        state.store(MAPPING, Ordering::Release);
        self.ring[slot]
            .buffer
            .map_async(wgpu::MapMode::Read, .., move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
        self.queued.push(slot);
    }

    /// The figures of the frame just submitted (and [`Self::submitted`]), waiting for the GPU
    /// to finish it.
    pub fn read(&mut self, gpu: &Gpu) -> Result<PassTimes> {
        gpu.wait()?;
        // Where other threads poll the same device (tree bakes measuring side by side), one of
        // them may run the read-back's callback a moment after this wait returns: poll on
        // until it has (or a read-back is plainly lost).
        let start = web_time::Instant::now();
        loop {
            let mut last = None;
            while let Some(t) = self.take_oldest()? {
                last = Some(t);
            }
            if let Some(t) = last {
                return Ok(t);
            }
            if self.queued.is_empty() || start.elapsed() > std::time::Duration::from_secs(30) {
                return Err(anyhow!("no pass timestamps were recorded"));
            }
            std::thread::yield_now();
            let _ = gpu.device.poll(wgpu::PollType::Poll);
        }
    }

    /// The figures of the newest frame that has come back, without waiting; `None` when none
    /// has yet.
    pub fn try_read(&mut self, gpu: &Gpu) -> Result<Option<PassTimes>> {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        let mut last = None;
        while let Some(t) = self.take_oldest()? {
            last = Some(t);
        }
        Ok(last)
    }

    /// Reads the oldest queued frame if it has come back, freeing its slot.
    fn take_oldest(&mut self) -> Result<Option<PassTimes>> {
        let Some(&slot) = self.queued.first() else {
            return Ok(None);
        };
        let r = &self.ring[slot];
        match r.state.load(Ordering::Acquire) {
            MAPPED => {}
            FAILED => {
                self.queued.remove(0);
                r.state.store(IDLE, Ordering::Release);
                return Err(anyhow!("pass timestamp read-back failed"));
            }
            _ => return Ok(None),
        }
        let times = {
            let data = r
                .buffer
                .get_mapped_range(..)
                .map_err(|e| anyhow!("pass timestamp read-back failed: {e}"))?;
            let word = |offset: u64| -> u64 {
                let o = offset as usize;
                bytemuck::pod_read_unaligned(&data[o..o + 8])
            };
            let mut t = PassTimes::default();
            let (mut first, mut end) = (u64::MAX, 0);
            for pass in Pass::ALL.into_iter().filter(|p| r.passes & p.bit() != 0) {
                let i = pass as usize;
                let (a, b) = (word(i as u64 * STRIDE), word(i as u64 * STRIDE + 8));
                t.ms[i] = Some(b.saturating_sub(a) as f64 * self.period_ns * 1e-6);
                (first, end) = (first.min(a), end.max(b));
                if r.counted & pass.bit() != 0 {
                    t.fragments[i] = Some(word((Pass::COUNT + i) as u64 * STRIDE));
                }
            }
            t.frame_ms = end.saturating_sub(first) as f64 * self.period_ns * 1e-6;
            t
        };
        r.buffer.unmap();
        r.state.store(IDLE, Ordering::Release);
        self.queued.remove(0);
        Ok(Some(times))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(characters: Option<f64>, environment: f64, fragments: u64) -> PassTimes {
        let mut t = PassTimes::default();
        t.ms[Pass::Characters as usize] = characters;
        t.ms[Pass::Environment as usize] = Some(environment);
        t.fragments[Pass::Environment as usize] = Some(fragments);
        t.frame_ms = characters.unwrap_or(0.0) + environment;
        t
    }

    #[test]
    fn medians_are_over_the_frames_that_drew_a_pass() {
        let frames = [
            frame(Some(4.0), 1.0, 100),
            frame(None, 3.0, 300),
            frame(Some(8.0), 2.0, 200),
        ];
        let m = pass_medians(&frames);
        assert_eq!(m.len(), 2);
        assert_eq!(m["characters"], 6.0);
        assert_eq!(m["sky and ground"], 2.0);
        assert_eq!(overdraw_median(&frames, 10, 10), Some(2.0));
        assert_eq!(overdraw_median(&[], 10, 10), None);
        let drawn: Vec<Pass> = frames[1].drawn().map(|(p, _)| p).collect();
        assert_eq!(drawn, [Pass::Environment]);
    }

    #[test]
    fn smoothing_moves_towards_the_new_frame() {
        let a = frame(Some(10.0), 2.0, 100);
        let b = frame(None, 4.0, 300);
        let s = a.smoothed(&b, 0.25);
        assert_eq!(s.ms[Pass::Environment as usize], Some(2.5));
        assert_eq!(s.fragments[Pass::Environment as usize], Some(150));
        // A pass the new frame did not draw drops out.
        assert_eq!(s.ms[Pass::Characters as usize], None);
        assert_eq!(s.frame_ms, 12.0 + (4.0 - 12.0) * 0.25);
    }

    #[test]
    fn pass_names_are_distinct() {
        let mut names: Vec<&str> = Pass::ALL.iter().map(|p| p.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Pass::COUNT);
    }
}
