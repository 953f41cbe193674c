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
/// pass, side, model, method slot, variant, level, hops.
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
    /// How the group is drawn where a drawable has more than one way: for a tree impostor, 1
    /// where it is far enough off to show its nearest view alone ([`DrawAt::nearest_view`]);
    /// for a clump level, 1 + the view sector whose planes it draws ([`DrawAt::sector`]);
    /// else 0.
    pub(super) fn with_variant(self, variant: u32) -> DrawKey {
        DrawKey(self.0 & !(0xff << 24) | (variant as u64 & 0xff) << 24)
    }
    pub(super) fn variant(self) -> u32 {
        (self.0 >> 24 & 0xff) as u32
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

/// Where an instance is drawn: its side of the screen, the method slot shown there, its
/// distance from the eye (as ordered bits: groups and instances are drawn nearest first),
/// and, for a tree impostor, whether it is far enough off to show its nearest view alone.
#[derive(Clone, Copy, Debug)]
pub(super) struct DrawAt {
    pub side: usize,
    pub method: usize,
    pub near: u32,
    pub nearest_view: bool,
    /// A clump level's view sector of the eye ([`crate::bake::gpu_data::view_subsets`]).
    pub sector: Option<u32>,
}

/// Whether an impostor whose nearest view alone is off by `error` model units, scaled by
/// `scale`, at `distance` from the eye, projects that error within `tolerance` (a share of
/// half the view's height) through a projection whose vertical scale is `proj_y`
/// (1 / tan(fov_y / 2)). Never for an eye inside its sphere of `radius`.
pub(super) fn shows_nearest_view(
    error: f32,
    scale: f32,
    radius: f32,
    distance: f32,
    proj_y: f32,
    tolerance: f32,
) -> bool {
    error > 0.0
        && tolerance > 0.0
        && distance > radius
        && error * scale * proj_y <= tolerance * distance
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_impostor_shows_its_nearest_view_only_where_that_projects_within_the_tolerance() {
        // A 1.5 px tolerance on a 720 px view; a 60° field of view.
        let tolerance = 1.5 / 360.0;
        let proj_y = 1.0 / 30f32.to_radians().tan();
        // An error of 0.35 m (a 1 m sphere, views 20° apart) projects to 1.5 px at about
        // 0.35 · proj_y · 360 / 1.5 m.
        let edge = 0.35 * proj_y / tolerance;
        let shows = |error: f32, scale: f32, distance: f32| {
            shows_nearest_view(error, scale, 1.0, distance, proj_y, tolerance)
        };
        assert!(shows(0.35, 1.0, edge * 1.01));
        assert!(!shows(0.35, 1.0, edge * 0.99));
        // A tree scaled twice as large has twice the error.
        assert!(!shows(0.35, 2.0, edge * 1.5));
        assert!(shows(0.35, 2.0, edge * 2.01));
        // Not an impostor, no tolerance, or an eye inside the tree's sphere: never.
        assert!(!shows(0.0, 1.0, 1e6));
        assert!(!shows_nearest_view(0.35, 1.0, 1.0, 1e6, proj_y, 0.0));
        assert!(!shows_nearest_view(1e-9, 1.0, 5.0, 4.0, proj_y, tolerance));
    }

    #[test]
    fn a_variant_takes_its_own_bits_of_the_key() {
        let key = DrawKey::new(PASS_MORPH, 3, 70, 2, 5, 1);
        let v = key.with_variant(1);
        assert_eq!(v.variant(), 1);
        assert_eq!(
            (v.pass(), v.side(), v.model(), v.slot(), v.level(), v.hops()),
            (PASS_MORPH, 3, 70, 2, 5, 1)
        );
        assert_eq!(v.with_variant(0), key);
        assert!(
            v.0 > key.0,
            "variants sort after the plain draw of the same group"
        );
    }
}
