//! The viewer's state, sorted by concern: what a frame's figures show, the scene's clock, the
//! background bakes and the start-up report. [`super::Viewer`] holds one of each beside its
//! window, world and panel.

use super::history::FrameHistory;
use crate::render::FrameStats;
use crate::render::timer::{FrameTimer, PassTimes};
use crate::runtime::levels::BackgroundBake;
use web_time::Instant;

/// When the viewer was launched, and how long its models took to load: the start-up figures
/// it prints.
#[derive(Clone, Copy)]
pub(super) struct Launch {
    pub at: Instant,
    pub models_seconds: f32,
    /// Seconds from launch to the window and the scene on the GPU.
    pub window_seconds: f32,
}

/// When the viewer was launched, and whether its first frame, and the moment every level the
/// view asks for is on the GPU, have been reported.
pub(super) struct Startup {
    pub launched: Launch,
    pub reported_first_frame: bool,
    pub reported_levels: bool,
}

/// What the panel's figures show.
pub(super) struct Figures {
    /// Recent frame times.
    pub history: FrameHistory,
    /// The adapter and its backend, by name.
    pub adapter: String,
    pub backend: String,
    /// What the last frame drew.
    pub stats: FrameStats,
    /// Each pass's GPU time, where the adapter has timestamp queries: read back a frame or
    /// two late, without waiting.
    pub timer: Option<FrameTimer>,
    /// The passes' times, smoothed over the last second or so of frames.
    pub passes: Option<PassTimes>,
    /// Where memory goes (see [`crate::runtime::world::World::memory`]) and when that was
    /// last looked at.
    pub memory: Vec<(&'static str, u64)>,
    pub memory_at: Option<Instant>,
}

/// The scene's clock.
pub(super) struct Clock {
    pub started: Instant,
    pub last_frame: Option<Instant>,
    /// Seconds of scene time.
    pub time: f32,
    /// Frames drawn.
    pub frames: usize,
}

/// Levels of detail baked in the background.
pub(super) struct Baking {
    /// The bake running, one method at a time.
    pub bake: Option<BackgroundBake>,
    /// What the last bake failed with.
    pub bake_error: Option<String>,
    /// When the foliage settings last changed: a new chain is baked once they have been still
    /// for [`super::SETTLE_BEFORE_BAKE`] (not for every step of a slider's drag).
    pub foliage_changed: Instant,
}
