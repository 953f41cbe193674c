//! Encoding a frame's instances: each instance's draw ([`LodDraw`]) turned into GPU instances
//! keyed by what draws them (see [`super::keys`]), then grouped into one instanced draw per key
//! and uploaded in one buffer write.

use super::SceneRenderer;
use super::keys::{
    DrawAt, DrawKey, FrameStats, PASS_DISSOLVE_OUT, PASS_DITHER_IN, PASS_DITHER_OUT, PASS_FADE,
    PASS_MORPH, PASS_OPAQUE,
};
use crate::bake::gpu_data::drawable::DrawClass;
use crate::render::character::GpuCharacter;
use crate::render::gpu::Gpu;
use crate::render::uniforms::{Cover, GpuInstance};
use crate::scene::lod::MAX_LEVELS;
use crate::scene::{Instance, LodDraw};

/// An instance as the vertex shader reads it, before its level: its transform, clip rows and
/// clocks, cross-fade and tint, and its wind (a tree's scaled by the scene's).
fn gpu_instance(c: &GpuCharacter, inst: &Instance, wind: f32) -> GpuInstance {
    let rows = &c.clip_rows;
    let row = |clip: u32| rows[(clip as usize).min(rows.len() - 1)];
    let mut g = GpuInstance::new(
        &inst.transform,
        row(inst.clip),
        inst.time_offset,
        inst.speed,
        inst.tint,
    );
    if let Some(f) = inst.fade {
        g = g.with_fade(row(f.clip), f.time_offset, f.speed, f.weight);
    }
    g.timing[2] = if c.class.is_tree() {
        inst.wind * wind
    } else {
        inst.wind
    };
    // Where its clip has carried it, on the ground: its blob shadow goes there.
    g.timing[3] = inst.travel.x;
    g.fade[3] = inst.travel.z;
    g
}

impl SceneRenderer {
    /// Keys the GPU instances of `inst` drawing `draw` at `at` (one, or two for a transition
    /// that draws both levels), each with its level and transition in `lod`, and counts what
    /// they draw into `stats`.
    pub(super) fn encode_instance(
        &mut self,
        inst: &Instance,
        draw: LodDraw,
        at: DrawAt,
        stats: &mut FrameStats,
    ) {
        let c = &self.characters[inst.model];
        let (slot, set) = match c.set(at.method) {
            Some(set) => (at.method, set),
            None => (0, c.full()),
        };
        let last = set.levels.len() - 1;
        let mut g = gpu_instance(c, inst, self.wind);
        let key = |pass, level: usize, hops: usize| {
            DrawKey::new(pass, at.side, inst.model, slot, level as u8, hops as u8)
                .with_variant(match at.sector {
                    Some(s) => s + 1,
                    None => at.nearest_view as u32,
                })
                .0
        };
        let near = at.near;
        // The outgoing half of a dissolve is the same instance as its incoming half, which
        // counts it.
        let second_half = matches!(
            draw,
            LodDraw::Dissolve {
                incoming: false,
                ..
            }
        );
        if !second_half {
            stats.instances += 1;
            // The level the instance asked for (a tree's level is a character of its own,
            // drawn at its only level).
            stats.levels[(draw.nearest_level() as usize).min(MAX_LEVELS - 1)] += 1;
            stats.in_transition += draw.in_transition() as u64;
            stats.kinds[c.level_kind as usize] += 1;
        }
        // A clump level seen from one sector draws that sector's triangles.
        let sector_triangles = at
            .sector
            .and_then(|s| set.view_subsets.get(s as usize))
            .map(|&[_, count]| count as u64 / 3);
        let mut count = |k: usize, extra_influences: u32| {
            let l = &set.levels[k];
            stats.triangles += sector_triangles.unwrap_or(l.triangles() as u64);
            stats.vertices += l.vertices as u64;
            stats.influences += (l.influences + extra_influences) as u64;
        };
        let keyed = &mut self.keyed;
        match draw {
            LodDraw::Level(asked) => {
                // The debug tint shows the level asked for (a tree's cloud level is a
                // character of its own, drawn at its only level).
                let k = (asked as usize).min(last);
                g.set_lod(asked as usize, 0, None, Cover::Whole);
                count(k, 0);
                keyed.keep(key(PASS_OPAQUE, k, 0), near, g);
            }
            LodDraw::Morph { fine, coarse, t } => {
                let fine = (fine as usize).min(last);
                let hops = (coarse as usize).min(last).saturating_sub(fine);
                g.set_lod(fine, hops, Some(t.clamp(0.0, 1.0)), Cover::Whole);
                count(fine, set.levels[fine + hops].influences);
                keyed.keep(key(PASS_MORPH, fine, hops), near, g);
            }
            LodDraw::Dither { from, to, p } => {
                // Both levels opaque, on complementary pixels (as a tree's dissolve); the
                // incoming one casts the shadow.
                let (from, to) = ((from as usize).min(last), (to as usize).min(last));
                let p = p.clamp(0.0, 1.0);
                count(from, 0);
                count(to, 0);
                for (level, pass, cover) in [
                    (to, PASS_DITHER_IN, Cover::Incoming(p)),
                    (from, PASS_DITHER_OUT, Cover::Outgoing(p)),
                ] {
                    g.set_lod(level, 0, Some(p), cover);
                    keyed.keep(key(pass, level, 0), near, g);
                }
            }
            LodDraw::Alpha { from, to, p } => {
                let (from, to) = ((from as usize).min(last), (to as usize).min(last));
                let p = p.clamp(0.0, 1.0);
                // See the module comment of `renderer`: the first half fades `to` in over
                // `from`, the second fades `from` out over `to`.
                let (opaque, faded, opacity) = if p < 0.5 {
                    (from, to, 2.0 * p)
                } else {
                    (to, from, 2.0 * (1.0 - p))
                };
                count(opaque, 0);
                count(faded, 0);
                g.set_lod(opaque, 0, Some(p), Cover::Whole);
                keyed.keep(key(PASS_OPAQUE, opaque, 0), near, g);
                g.set_lod(faded, 0, Some(p), Cover::Opacity(opacity));
                keyed.keep(key(PASS_FADE, faded, 0), near, g);
            }
            LodDraw::Dissolve { level, p, incoming } => {
                let k = (level as usize).min(last);
                let p = p.clamp(0.0, 1.0);
                // A mesh character's half (a character going to or from its animated
                // impostor, see `World::upload`) is dithered as in a dithered cross-fade;
                // impostors and trees dissolve in their own shaders.
                let dithered = c.class == DrawClass::Mesh;
                let (pass, cover) = match (incoming, dithered) {
                    (true, false) => (PASS_OPAQUE, Cover::Incoming(p)),
                    (false, false) => (PASS_DISSOLVE_OUT, Cover::Outgoing(p)),
                    (true, true) => (PASS_DITHER_IN, Cover::Incoming(p)),
                    (false, true) => (PASS_DITHER_OUT, Cover::Outgoing(p)),
                };
                g.set_lod(level as usize, 0, Some(p), cover);
                count(k, 0);
                keyed.keep(key(pass, k, 0), near, g);
            }
        }
    }

    /// Groups the keyed instances: sorted by key, each run of equal keys is one instanced
    /// draw, its instances nearest first. The groups are drawn nearest first too (by their
    /// nearest instance), each side in turn, so that early depth tests spare what near things
    /// hide.
    pub(super) fn group_draws(&mut self) {
        self.keyed
            .keys
            .sort_unstable_by_key(|&(k, near, _)| (k, near));
        self.staging.clear();
        self.draws.clear();
        for (n, &(key, _, at)) in self.keyed.keys.iter().enumerate() {
            self.staging.push(self.keyed.instances[at as usize]);
            match self.draws.last_mut() {
                Some((k, range)) if k.0 == key => range.end = n as u32 + 1,
                _ => self.draws.push((DrawKey(key), n as u32..n as u32 + 1)),
            }
        }
        let keyed = &self.keyed.keys;
        self.draws
            .sort_by_key(|(k, range)| (k.side(), keyed[range.start as usize].1));
    }

    /// Writes the grouped instances to the instance buffer, growing it first where they do not
    /// fit.
    pub(super) fn upload_instances(&mut self, gpu: &Gpu) {
        let total = self.staging.len();
        if total * std::mem::size_of::<GpuInstance>() > self.instance_buffer.size() as usize {
            // Doubling amortises growth; the device's limit caps it (the world checked that
            // its instances fit, see `max_instances`).
            let capacity = total
                .next_power_of_two()
                .max(256)
                .min(Self::max_entries(&gpu.device))
                .max(total);
            self.instance_buffer = Self::instance_buffer(&gpu.device, capacity);
        }
        if total > 0 {
            gpu.queue.write_buffer(
                &self.instance_buffer,
                0,
                bytemuck::cast_slice(&self.staging),
            );
        }
    }
}
