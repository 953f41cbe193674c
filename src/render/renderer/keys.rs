//! The keys a frame's instances are grouped by: (pass, side, model, level, hops), one
//! instanced draw per key, and the figures a prepared frame reports.

use crate::bake::gpu_data::drawable::LevelKind;
use crate::render::uniforms::GpuInstance;
use crate::scene::lod::MAX_LEVELS;

/// What a frame drew.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Instances drawn (in the view frustum).
    pub instances: u64,
    /// Instances outside the view frustum, not drawn.
    pub culled: u64,
    pub triangles: u64,
    pub vertices: u64,
    /// Animation-space influences skinned: a morphing vertex counts those of both its levels.
    pub influences: u64,
    pub draw_calls: u32,
    /// Instances by the level they mostly show (the last bin holds the coarser ones too).
    pub levels: [u32; MAX_LEVELS],
    pub in_transition: u64,
    /// Instances by what their level shows, indexed by [`LevelKind`] (a transition's
    /// instance by the level it goes to).
    pub kinds: [u32; LevelKind::COUNT],
}

/// The kinds of draw, in the order they are issued.
pub(super) const PASS_OPAQUE: u64 = 0;
pub(super) const PASS_MORPH: u64 = 1;
pub(super) const PASS_FADE: u64 = 2;
/// The outgoing half of a dissolve: drawn with the opaque draws, but its shadow is the
/// incoming half's.
pub(super) const PASS_DISSOLVE_OUT: u64 = 3;
/// The two halves of a character's dithered cross-fade ([`LodDraw::Dither`]): drawn with the
/// opaque draws by a fragment shader that keeps its half's pixels; the incoming half casts the
/// shadow.
pub(super) const PASS_DITHER_IN: u64 = 4;
pub(super) const PASS_DITHER_OUT: u64 = 5;

/// A group of instances drawn by one instanced call. The fields are packed into a sort key:
/// pass, side, model, method slot, level, hops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct DrawKey(pub(super) u64);

impl DrawKey {
    pub(super) fn new(
        pass: u64,
        side: usize,
        model: usize,
        slot: usize,
        level: u8,
        hops: u8,
    ) -> DrawKey {
        DrawKey(
            pass << 56
                | (side as u64 & 0xff) << 48
                | (model as u64 & 0xffff) << 32
                | (slot as u64 & 0xff) << 16
                | (level as u64) << 8
                | hops as u64,
        )
    }
    pub(super) fn pass(self) -> u64 {
        self.0 >> 56
    }
    pub(super) fn side(self) -> usize {
        (self.0 >> 48 & 0xff) as usize
    }
    pub(super) fn model(self) -> usize {
        (self.0 >> 32 & 0xffff) as usize
    }
    pub(super) fn slot(self) -> usize {
        (self.0 >> 16 & 0xff) as usize
    }
    pub(super) fn level(self) -> usize {
        (self.0 >> 8 & 0xff) as usize
    }
    pub(super) fn hops(self) -> usize {
        (self.0 & 0xff) as usize
    }
}

/// The frame's instances, each filed under its draw key and its distance from the eye (as
/// bits, which order like the non-negative floats they are). Sorting moves the 16-byte keys
/// with the instance's place in `instances`, not the 144 bytes of an instance (moving
/// instances was a third of a 10,000-character frame's CPU time).
#[derive(Default)]
pub(super) struct Keyed {
    pub(super) keys: Vec<(u64, u32, u32)>,
    pub(super) instances: Vec<GpuInstance>,
}

impl Keyed {
    pub(super) fn clear(&mut self) {
        self.keys.clear();
        self.instances.clear();
    }

    pub(super) fn keep(&mut self, key: u64, near: u32, g: GpuInstance) {
        self.keys.push((key, near, self.instances.len() as u32));
        self.instances.push(g);
    }
}

/// Where an instance is drawn: its side of the screen, the method slot shown there, and its
/// distance from the eye (as ordered bits: groups and instances are drawn nearest first).
#[derive(Clone, Copy, Debug)]
pub(super) struct DrawAt {
    pub side: usize,
    pub method: usize,
    pub near: u32,
}
