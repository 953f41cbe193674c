//! The scene renderer: sky, ground, blob shadows and instanced skinned characters at their
//! levels of detail.
//!
//! Per frame the caller hands over the camera and, for each side of the screen (all of it, or
//! the two halves of a comparison), the instances with what each draws ([`LodDraw`]).
//! [`SceneRenderer::prepare`] groups the instances by (side, model, level, transition state) and
//! uploads them in one buffer write, and [`SceneRenderer::draw`] issues one instanced draw per
//! group. Nothing is allocated per frame once the buffers are big enough.
//!
//! Alpha-blend transitions (Houle & Poulin §3, Figure 1) are drawn so that they neither see
//! through a character nor depend on triangle order. A transition with progress p draws one level
//! opaque and fades the other over it: for p < ½ the outgoing level is opaque and the incoming
//! one fades in with opacity 2p; for p ≥ ½ the incoming one is opaque and the outgoing one fades
//! out with opacity 2(1 − p). The faded level is drawn after every opaque draw, in two passes:
//! first depth only, then colour with an *equal* depth test. Only its nearest surface is blended,
//! once per pixel, so its own overlapping parts (a leg in front of the body) never blend over
//! each other, and where the opaque level is in front the faded one is hidden. At p = 0 the
//! faded level has opacity 0 and the image is exactly the outgoing level; at p = 1 exactly the
//! incoming one; at p = ½ both halves show the depth-nearest of the two levels, so the switch of
//! roles is seamless.
//!
//! The dithered cross-fade ([`LodDraw::Dither`]) draws both levels of a character opaque, each
//! by a fragment shader that keeps the pixels of its half (the incoming level where a fixed
//! per-pixel threshold lies below p): every level is drawn once, with no blending and no second
//! pass, and p = 0 and p = 1 are exactly the two levels.
//!
//! Trees change level by a screen-door cross-dissolve instead ([`LodDraw::Dissolve`]): their
//! billboard-cloud levels have no vertices in common to morph, and blending thousands of
//! overlapping cut-out leaves would need sorting. Both levels are drawn opaque, the incoming one
//! only where a fixed per-pixel threshold lies below p and the outgoing one only where it does
//! not, so each pixel shows exactly one of them, the share of the incoming one grows evenly with
//! p, and p = 0 and p = 1 are exactly the two levels.

use super::character::{self, GpuCharacter};
use super::gpu::Gpu;
use super::pipelines::Pipelines;
use super::timer::{FrameTimer, Pass};
use super::uniforms::{FrameUniforms, FrameView, GpuInstance, Lighting};
use crate::bake::gpu_data::drawable::CharacterBake;
use crate::bake::gpu_data::lod_pack::LodPack;
use crate::scene::lod::MAX_LEVELS;
use crate::scene::{Instance, LodDraw};
use anyhow::{Result, bail};
use std::ops::Range;

/// Instance-buffer entries one instance can take in a frame: one per side of a side-by-side
/// comparison, times two where it changes level (the two levels of an alpha blend, a dithered
/// cross-fade or a dissolve).
pub const ENTRIES_PER_INSTANCE: usize = 4;

/// Which vertex shader draws the characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CharacterShader {
    /// Animation-space skinning from the animation and vertex textures.
    Skinned,
    /// The same triangles in one fixed pose from a plain vertex buffer: the calibration baseline.
    Plain,
}

crate::choice! {
    /// What the characters are coloured by.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
    pub enum DebugView {
        /// Their materials.
        #[default]
        Shaded => "shaded",
        /// One colour per level of detail, blended while morphing.
        LodTint => "lod",
        /// Transition t from blue (0) to red (1); grey outside transitions.
        TransitionTint => "transition",
        /// Triangle edges, coloured by level (needs `POLYGON_MODE_LINE`).
        Wireframe => "wireframe",
        /// Animation-space influences per vertex, one (blue) to eight or more (red).
        Influences => "influences",
    }
}

impl DebugView {
    /// The mode `fs_main` in `shaders/character.wgsl` switches on.
    fn shader_mode(self) -> u32 {
        match self {
            DebugView::Shaded => 0,
            DebugView::LodTint | DebugView::Wireframe => 1,
            DebugView::TransitionTint => 2,
            DebugView::Influences => 3,
        }
    }
}

crate::named_serde!(DebugView, "a debug view");

/// Which part of the view a side covers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Region {
    #[default]
    Full,
    Left,
    Right,
}

impl Region {
    /// The planes (xyz · p + w ≥ 0 inside) of the part of the view frustum of `view_proj` that
    /// this region shows: left, right, bottom, top, near, each normalised so that a sphere
    /// test is a signed distance.
    pub fn frustum(self, view_proj: glam::Mat4) -> [glam::Vec4; 5] {
        let row = |i| view_proj.row(i);
        let (x, y, z, w) = (row(0), row(1), row(2), row(3));
        // Clip-space x runs from −w to w; a half keeps x ≥ 0 or x ≤ 0.
        let (left, right) = match self {
            Region::Full => (w + x, w - x),
            Region::Left => (w + x, -x),
            Region::Right => (x, w - x),
        };
        [left, right, w + y, w - y, z].map(|p| p / p.truncate().length().max(1e-12))
    }

    /// The region's rectangle (x, y, width, height) within `view`.
    pub fn rect(self, [x, y, w, h]: [u32; 4]) -> [u32; 4] {
        let half = w / 2;
        match self {
            Region::Full => [x, y, w, h],
            Region::Left => [x, y, half.max(1), h],
            Region::Right => [x + half, y, (w - half).max(1), h],
        }
    }
}

/// What one side of the screen shows: the instances, drawn from one method's levels.
#[derive(Clone, Copy, Debug)]
pub struct Side<'a> {
    /// The method's slot ([`crate::scene::LodMethod::index`]); a model without that set
    /// uploaded is drawn at full detail.
    pub method: usize,
    pub instances: &'a [Instance],
    /// What each instance draws; empty: full detail for all.
    pub draws: &'a [LodDraw],
    pub region: Region,
}

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
}

/// The kinds of draw, in the order they are issued.
const PASS_OPAQUE: u64 = 0;
const PASS_MORPH: u64 = 1;
const PASS_FADE: u64 = 2;
/// The outgoing half of a dissolve: drawn with the opaque draws, but its shadow is the
/// incoming half's.
const PASS_DISSOLVE_OUT: u64 = 3;
/// The two halves of a character's dithered cross-fade ([`LodDraw::Dither`]): drawn with the
/// opaque draws by a fragment shader that keeps its half's pixels; the incoming half casts the
/// shadow.
const PASS_DITHER_IN: u64 = 4;
const PASS_DITHER_OUT: u64 = 5;

/// A group of instances drawn by one instanced call. The fields are packed into a sort key:
/// pass, side, model, method slot, level, hops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct DrawKey(u64);

impl DrawKey {
    fn new(pass: u64, side: usize, model: usize, slot: usize, level: u8, hops: u8) -> DrawKey {
        DrawKey(
            pass << 56
                | (side as u64 & 0xff) << 48
                | (model as u64 & 0xffff) << 32
                | (slot as u64 & 0xff) << 16
                | (level as u64) << 8
                | hops as u64,
        )
    }
    fn pass(self) -> u64 {
        self.0 >> 56
    }
    fn side(self) -> usize {
        (self.0 >> 48 & 0xff) as usize
    }
    fn model(self) -> usize {
        (self.0 >> 32 & 0xffff) as usize
    }
    fn slot(self) -> usize {
        (self.0 >> 16 & 0xff) as usize
    }
    fn level(self) -> usize {
        (self.0 >> 8 & 0xff) as usize
    }
    fn hops(self) -> usize {
        (self.0 & 0xff) as usize
    }
}

pub struct SceneRenderer {
    pub lighting: Lighting,
    pub shader: CharacterShader,
    pub shadows: bool,
    /// Light the coarse levels through their normal maps, where their sets have them (see
    /// `bake::normal_map`); off, every level keeps its vertex normals.
    pub normal_maps: bool,
    /// Scales every tree's own wind strength (foliage only; characters play their clips as
    /// they are).
    pub wind: f32,
    /// Draw the outlines of billboard clouds' billboards over them.
    pub outlines: bool,
    /// Tint foliage (trees) by level whatever the debug view, so that a tree's level shows
    /// while the characters keep their colours.
    pub foliage_tint: bool,
    /// Light billboard clouds per texel through their atlases (see `bake::billboard::atlas`);
    /// off, by their planes' normals. By adapter at first (`Gpu::atlas_lighting`).
    pub atlas_lighting: bool,
    frame_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    pub(crate) frame_layout: wgpu::BindGroupLayout,
    pub(crate) character_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    characters: Vec<GpuCharacter>,
    pub debug: DebugView,
    pipelines: Pipelines,
    instance_buffer: wgpu::Buffer,
    keyed: Keyed,
    staging: Vec<GpuInstance>,
    draws: Vec<(DrawKey, Range<u32>)>,
    /// Regions of the sides of the current frame.
    regions: Vec<Region>,
}

/// The frame's instances, each filed under its draw key and its distance from the eye (as
/// bits, which order like the non-negative floats they are). Sorting moves the 16-byte keys
/// with the instance's place in `instances`, not the 144 bytes of an instance (moving
/// instances was a third of a 10,000-character frame's CPU time).
#[derive(Default)]
struct Keyed {
    keys: Vec<(u64, u32, u32)>,
    instances: Vec<GpuInstance>,
}

impl Keyed {
    fn clear(&mut self) {
        self.keys.clear();
        self.instances.clear();
    }

    fn keep(&mut self, key: u64, near: u32, g: GpuInstance) {
        self.keys.push((key, near, self.instances.len() as u32));
        self.instances.push(g);
    }
}

pub(crate) fn frame_bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

impl SceneRenderer {
    pub fn new(gpu: &Gpu, color_format: wgpu::TextureFormat, sample_count: u32) -> Self {
        let device = &gpu.device;
        let frame_layout = frame_bind_group_layout(device);
        let character_layout = character::bind_group_layout(device);
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let pipelines = Pipelines::new(
            device,
            &frame_layout,
            &character_layout,
            color_format,
            sample_count,
        );
        let instance_buffer = Self::instance_buffer(device, 256);
        SceneRenderer {
            lighting: Lighting::default(),
            shader: CharacterShader::Skinned,
            shadows: true,
            normal_maps: true,
            wind: 1.0,
            outlines: false,
            foliage_tint: false,
            atlas_lighting: gpu.lights_atlases(),
            frame_buffer,
            frame_bind_group,
            frame_layout,
            character_layout,
            sampler,
            characters: Vec::new(),
            debug: DebugView::Shaded,
            pipelines,
            instance_buffer,
            keyed: Keyed::default(),
            staging: Vec::new(),
            draws: Vec::new(),
            regions: Vec::new(),
        }
    }

    /// The most instances a frame can hold on `device`: every instance takes at most
    /// [`ENTRIES_PER_INSTANCE`] entries of the one instance buffer, which may be no larger
    /// than the device's `max_buffer_size`.
    pub fn max_instances(device: &wgpu::Device) -> usize {
        Self::max_entries(device) / ENTRIES_PER_INSTANCE
    }

    fn max_entries(device: &wgpu::Device) -> usize {
        let bytes = device.limits().max_buffer_size.min(usize::MAX as u64) as usize;
        bytes / std::mem::size_of::<GpuInstance>()
    }

    fn instance_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (capacity * std::mem::size_of::<GpuInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Uploads a baked character at full detail; returns its index for [`Instance::model`].
    pub fn add_character(&mut self, gpu: &Gpu, bake: &CharacterBake) -> Result<usize> {
        let name = &bake.name;
        let grid = |what: &str, g: &crate::bake::gpu_data::texels::TexelGrid| {
            gpu.texture_fits(&format!("{name}: {what}"), g.width, g.height, 1)
        };
        grid("the animation", &bake.animation.grid)?;
        grid("the vertices", &bake.vertices.grid)?;
        let m = &bake.materials;
        gpu.texture_fits(
            &format!("{name}: {} materials", m.layer_count),
            m.width,
            m.height,
            m.layer_count,
        )?;
        let c = gpu.checked(&format!("uploading {name}"), || {
            GpuCharacter::upload(gpu, &self.character_layout, &self.sampler, bake)
        })?;
        self.characters.push(c);
        Ok(self.characters.len() - 1)
    }

    /// Uploads `bake` in place of character `index` (one no instance draws any more), freeing
    /// what that one held; returns `index`.
    pub fn replace_character(
        &mut self,
        gpu: &Gpu,
        index: usize,
        bake: &CharacterBake,
    ) -> Result<usize> {
        if index >= self.characters.len() {
            bail!("no character {index}");
        }
        let added = self.add_character(gpu, bake)?;
        self.characters.swap_remove(index);
        debug_assert_eq!(added, self.characters.len());
        Ok(index)
    }

    /// Uploads one method's levels of detail of character `model` into `slot`
    /// ([`crate::scene::LodMethod::index`]). Done once per (model, method).
    pub fn add_levels(
        &mut self,
        gpu: &Gpu,
        model: usize,
        slot: usize,
        pack: &LodPack,
    ) -> Result<()> {
        let Some(c) = self.characters.get_mut(model) else {
            bail!("no character {model}");
        };
        let g = &pack.vertices.grid;
        gpu.texture_fits("the levels of detail' vertices", g.width, g.height, 1)?;
        if let Some(n) = &pack.normal_maps {
            gpu.texture_fits(
                &format!("{} normal maps", n.layer_count),
                n.size,
                n.size,
                n.layer_count,
            )?;
        }
        gpu.buffer_fits(
            "the levels of detail's indices",
            std::mem::size_of_val(pack.indices.as_slice()) as u64,
        )?;
        let (layout, sampler) = (&self.character_layout, &self.sampler);
        gpu.checked("uploading levels of detail", || {
            c.add_set(gpu, layout, sampler, slot, pack)
        })
    }

    pub fn characters(&self) -> &[GpuCharacter] {
        &self.characters
    }

    /// What the characters and the instance buffer hold on the GPU.
    pub fn memory(&self) -> super::memory::GpuMemory {
        let mut total = super::memory::GpuMemory {
            other_buffers: self.instance_buffer.size(),
            ..Default::default()
        };
        for c in &self.characters {
            total += c.bytes();
        }
        total
    }

    /// Does the adapter draw wireframes?
    pub fn has_wireframe(&self) -> bool {
        self.pipelines.wireframe.is_some()
    }

    /// Uploads the frame's uniforms and instances (one buffer write each) and plans the draws:
    /// one per (side, model, level, transition state).
    pub fn prepare(&mut self, gpu: &Gpu, view: &FrameView, sides: &[Side]) -> FrameStats {
        let uniforms = FrameUniforms::new(
            view,
            &self.lighting,
            [
                self.debug.shader_mode(),
                DebugView::LodTint.shader_mode() * self.foliage_tint as u32,
                0,
                0,
            ],
        );
        gpu.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));

        let mut stats = FrameStats::default();
        self.keyed.clear();
        self.regions.clear();
        let view_proj = view.proj * view.view;
        for (side_index, side) in sides.iter().enumerate() {
            self.regions.push(side.region);
            // Instances whose bounding sphere lies outside the side's part of the frustum are
            // not drawn (in compare mode each half draws only what it shows).
            let planes = side.region.frustum(view_proj);
            for (i, inst) in side.instances.iter().enumerate() {
                let Some(c) = self.characters.get(inst.model) else {
                    continue;
                };
                let centre = inst.transform.transform_point3(c.sphere.0);
                let m = inst.transform.matrix3;
                let radius = c.sphere.1
                    * m.x_axis
                        .length()
                        .max(m.y_axis.length())
                        .max(m.z_axis.length());
                if planes
                    .iter()
                    .any(|p| p.truncate().dot(centre) + p.w < -radius)
                {
                    stats.culled += 1;
                    continue;
                }
                let (slot, set) = match c.set(side.method) {
                    Some(set) => (side.method, set),
                    None => (0, c.full()),
                };
                let last = set.levels.len() - 1;
                let draw = side.draws.get(i).copied().unwrap_or(LodDraw::Level(0));
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
                g.timing[2] = if c.two_sided {
                    inst.wind * self.wind
                } else {
                    inst.wind
                };
                let key = |pass, level: usize, hops: usize| {
                    DrawKey::new(pass, side_index, inst.model, slot, level as u8, hops as u8).0
                };
                let near = ((centre - view.eye).length() - radius).max(0.0).to_bits();
                // The outgoing half of a dissolve is the same instance as its incoming half,
                // which counts it.
                let second_half = matches!(
                    draw,
                    LodDraw::Dissolve {
                        incoming: false,
                        ..
                    }
                );
                if !second_half {
                    stats.instances += 1;
                    // The level the instance asked for (a tree's level is a character of its
                    // own, drawn at its only level).
                    stats.levels[(draw.nearest_level() as usize).min(MAX_LEVELS - 1)] += 1;
                    stats.in_transition += draw.in_transition() as u64;
                }
                let mut count = |k: usize, extra_influences: u32| {
                    let l = &set.levels[k];
                    stats.triangles += l.triangles() as u64;
                    stats.vertices += l.vertices as u64;
                    stats.influences += (l.influences + extra_influences) as u64;
                };
                match draw {
                    LodDraw::Level(asked) => {
                        // The debug tint shows the level asked for (a tree's cloud level is a
                        // character of its own, drawn at its only level).
                        let k = (asked as usize).min(last);
                        g.lod = [-1.0, 0.0, 1.0, asked as f32];
                        count(k, 0);
                        self.keyed.keep(key(PASS_OPAQUE, k, 0), near, g);
                    }
                    LodDraw::Morph { fine, coarse, t } => {
                        let fine = (fine as usize).min(last);
                        let hops = (coarse as usize).min(last).saturating_sub(fine);
                        g.lod = [t.clamp(0.0, 1.0), hops as f32, 1.0, fine as f32];
                        count(fine, set.levels[fine + hops].influences);
                        self.keyed.keep(key(PASS_MORPH, fine, hops), near, g);
                    }
                    LodDraw::Dither { from, to, p } => {
                        // Both levels opaque, on complementary pixels (the coverage sign picks
                        // the half, as for a tree's dissolve); the incoming one casts the
                        // shadow.
                        let (from, to) = ((from as usize).min(last), (to as usize).min(last));
                        let p = p.clamp(0.0, 1.0);
                        count(from, 0);
                        count(to, 0);
                        for (level, pass, coverage) in
                            [(to, PASS_DITHER_IN, p), (from, PASS_DITHER_OUT, -1.0 - p)]
                        {
                            g.lod = [p, 0.0, coverage, level as f32];
                            self.keyed.keep(key(pass, level, 0), near, g);
                        }
                    }
                    LodDraw::Alpha { from, to, p } => {
                        let (from, to) = ((from as usize).min(last), (to as usize).min(last));
                        let p = p.clamp(0.0, 1.0);
                        // See the module comment: the first half fades `to` in over `from`,
                        // the second fades `from` out over `to`.
                        let (opaque, faded, opacity) = if p < 0.5 {
                            (from, to, 2.0 * p)
                        } else {
                            (to, from, 2.0 * (1.0 - p))
                        };
                        count(opaque, 0);
                        count(faded, 0);
                        g.lod = [p, 0.0, 1.0, opaque as f32];
                        self.keyed.keep(key(PASS_OPAQUE, opaque, 0), near, g);
                        g.lod = [p, 0.0, opacity, faded as f32];
                        self.keyed.keep(key(PASS_FADE, faded, 0), near, g);
                    }
                    LodDraw::Dissolve { level, p, incoming } => {
                        // The foliage shaders keep a pixel where its threshold lies below
                        // lod.z ≥ 0, or at or above −lod.z − 1 when lod.z < 0 (see
                        // shaders/character.wgsl): the two halves cover complementary pixels.
                        let k = (level as usize).min(last);
                        let p = p.clamp(0.0, 1.0);
                        // A mesh character's half (a character going to or from its
                        // animated impostor, see `World::upload`) is dithered as in a
                        // dithered cross-fade; impostors and trees dissolve in their own
                        // shaders.
                        let dithered = !(c.two_sided || c.impostor || c.animated_impostor);
                        let (pass, coverage) = match (incoming, dithered) {
                            (true, false) => (PASS_OPAQUE, p),
                            (false, false) => (PASS_DISSOLVE_OUT, -1.0 - p),
                            (true, true) => (PASS_DITHER_IN, p),
                            (false, true) => (PASS_DITHER_OUT, -1.0 - p),
                        };
                        g.lod = [p, 0.0, coverage, level as f32];
                        count(k, 0);
                        self.keyed.keep(key(pass, k, 0), near, g);
                    }
                }
            }
        }
        // Group: sort by key, then each run of equal keys is one instanced draw, its instances
        // nearest first. The groups are drawn nearest first too (by their nearest instance),
        // each side in turn, so that early depth tests spare what near things hide.
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
        stats.draw_calls = self.draws.len() as u32;
        stats
    }

    /// The passes this frame draws, in order (see [`Pass`]): the opaque characters and the
    /// trees first, each group nearest first, so that early depth testing spares what they
    /// hide; then the ground and the sky (at the far plane, tested against depth), so that
    /// each pixel of the environment is shaded once and only where nothing covers it; then
    /// the blob shadows, blended over the ground and hidden behind characters by the depth
    /// test; then the faded levels of alpha transitions over all of it.
    pub fn passes(&self) -> smallvec::SmallVec<[Pass; Pass::COUNT]> {
        let plain = self.shader == CharacterShader::Plain;
        let wireframe = self.debug == DebugView::Wireframe && self.pipelines.wireframe.is_some();
        let foliage = |k: &DrawKey| self.characters[k.model()].two_sided;
        let any = |f: &dyn Fn(&DrawKey) -> bool| self.draws.iter().any(|(k, _)| f(k));
        let mut passes = smallvec::SmallVec::new();
        let shown = |k: &DrawKey| wireframe || k.pass() != PASS_FADE;
        if any(&|k| plain || (!foliage(k) && shown(k))) {
            passes.push(Pass::Characters);
        }
        if !plain && any(&|k| foliage(k) && shown(k)) {
            passes.push(Pass::Foliage);
        }
        passes.push(Pass::Environment);
        if !self.draws.is_empty() && (self.shadows || self.shows_outlines()) {
            passes.push(Pass::Shadows);
        }
        if !plain && !wireframe && any(&|k| k.pass() == PASS_FADE) {
            passes.push(Pass::Transitions);
        }
        passes
    }

    /// Whether the billboards' outlines are drawn: asked for, and neither the plain
    /// calibration draw nor a wireframe.
    fn shows_outlines(&self) -> bool {
        let wireframe = self.debug == DebugView::Wireframe && self.pipelines.wireframe.is_some();
        self.outlines && self.shader != CharacterShader::Plain && !wireframe
    }

    /// Records pass `which` of the frame. `view` is the rectangle the scene covers (x, y,
    /// width, height), for the sides' scissor rectangles.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, which: Pass, view: [u32; 4]) {
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
        let mut scissor = Scissor {
            view,
            regions: &self.regions,
            side: None,
        };
        pass.set_vertex_buffer(0, self.instance_buffer.slice(..));
        match which {
            Pass::Characters => self.draw_opaque(pass, &mut scissor, false),
            Pass::Foliage => self.draw_opaque(pass, &mut scissor, true),
            Pass::Environment => {
                // Over the whole view.
                scissor.whole(pass);
                pass.set_pipeline(&self.pipelines.ground);
                pass.draw(0..6, 0..1);
                pass.set_pipeline(&self.pipelines.sky);
                pass.draw(0..3, 0..1);
            }
            Pass::Shadows => {
                // Every instance has exactly one opaque draw (opaque level, morph, or the
                // incoming half of a dissolve or a dithered cross-fade): its shadow goes with
                // it.
                if self.shadows {
                    pass.set_pipeline(&self.pipelines.shadow);
                    let casts =
                        |k: &DrawKey| matches!(k.pass(), PASS_OPAQUE | PASS_MORPH | PASS_DITHER_IN);
                    for (key, range) in self.draws.iter().filter(|(k, _)| casts(k)) {
                        scissor.side(pass, key.side());
                        let c = &self.characters[key.model()];
                        pass.set_bind_group(1, &c.full().bind_group, &[]);
                        pass.draw(0..6, range.clone());
                    }
                }
                // The billboards' outlines, a debug overlay, after the ground so that it
                // shows where a billboard's cut-out leaves the ground visible.
                if self.shows_outlines() {
                    self.draw_outlines(pass, &mut scissor);
                }
            }
            Pass::Transitions => {
                let debug = self.debug != DebugView::Shaded;
                let fades = || self.draws.iter().filter(|(k, _)| k.pass() == PASS_FADE);
                pass.set_pipeline(&self.pipelines.fade_depth);
                for (key, range) in fades() {
                    scissor.side(pass, key.side());
                    self.draw_group(pass, key, range);
                }
                let mut current = None;
                for (key, range) in fades() {
                    let mapped = self.mapped(key, debug);
                    if current != Some(mapped) {
                        current = Some(mapped);
                        pass.set_pipeline(if mapped {
                            &self.pipelines.mapped.fade_color
                        } else {
                            self.pipelines.fade_color.get(debug)
                        });
                    }
                    scissor.side(pass, key.side());
                    self.draw_group(pass, key, range);
                }
            }
            Pass::Ui => {}
        }
    }

    /// The outlines of the billboards of every billboard-cloud draw (both halves of a
    /// dissolve: each shows its own billboards' outlines where it shows its billboards).
    fn draw_outlines(&self, pass: &mut wgpu::RenderPass<'_>, scissor: &mut Scissor) {
        let mut set = false;
        for (key, range) in &self.draws {
            let c = &self.characters[key.model()];
            let Some((buffer, count)) = &c.outlines else {
                continue;
            };
            if !matches!(key.pass(), PASS_OPAQUE | PASS_DISSOLVE_OUT) {
                continue;
            }
            if !set {
                pass.set_pipeline(&self.pipelines.outline);
                set = true;
            }
            scissor.side(pass, key.side());
            pass.set_bind_group(1, &c.full().bind_group, &[]);
            pass.set_index_buffer(buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..*count, 0, range.clone());
        }
    }

    /// Whether the draw `key` is lit through normal maps: shaded (not a debug view), maps on,
    /// a character's level (or, in a geomorph, either end) that has one.
    fn mapped(&self, key: &DrawKey, debug: bool) -> bool {
        if debug || !self.normal_maps {
            return false;
        }
        let c = &self.characters[key.model()];
        if c.two_sided || c.impostor || c.animated_impostor {
            return false;
        }
        let Some(set) = c.set(key.slot()) else {
            return false;
        };
        let last = key.level()
            + if key.pass() == PASS_MORPH {
                key.hops()
            } else {
                0
            };
        set.levels
            .get(key.level()..=last.min(set.levels.len().saturating_sub(1)))
            .is_some_and(|l| l.iter().any(|l| l.normal_mapped))
    }

    /// One instanced draw of a group's level from its method's set.
    fn draw_group(&self, pass: &mut wgpu::RenderPass<'_>, key: &DrawKey, range: &Range<u32>) {
        let c = &self.characters[key.model()];
        let set = c.set(key.slot()).unwrap_or_else(|| c.full());
        let level = &set.levels[key.level().min(set.levels.len() - 1)];
        pass.set_bind_group(1, &set.bind_group, &[]);
        pass.set_index_buffer(set.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        let indices = level.first_index..level.first_index + level.index_count;
        pass.draw_indexed(indices, level.base_vertex as i32, range.clone());
    }

    /// The opaque draws of the characters (`foliage` false) or of the trees: levels and
    /// geomorphs (in wireframe mode the faded levels of alpha transitions too, as lines), or
    /// the plain calibration draw of everything.
    fn draw_opaque(&self, pass: &mut wgpu::RenderPass<'_>, scissor: &mut Scissor, foliage: bool) {
        if self.shader == CharacterShader::Plain {
            pass.set_pipeline(&self.pipelines.plain);
            pass.set_vertex_buffer(1, self.instance_buffer.slice(..));
            // Every draw's own level, faded and outgoing halves included: the triangles the
            // frame statistics count.
            for &(key, ref range) in &self.draws {
                scissor.side(pass, key.side());
                let c = &self.characters[key.model()];
                let set = c.set(key.slot()).unwrap_or_else(|| c.full());
                let level = &set.levels[key.level().min(set.levels.len() - 1)];
                pass.set_bind_group(1, &set.bind_group, &[]);
                pass.set_vertex_buffer(0, set.static_vertices.slice(..));
                pass.set_index_buffer(set.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                let indices = level.first_index..level.first_index + level.index_count;
                pass.draw_indexed(indices, level.base_vertex as i32, range.clone());
            }
            pass.set_vertex_buffer(0, self.instance_buffer.slice(..));
            return;
        }
        let wire = self
            .pipelines
            .wireframe
            .as_ref()
            .filter(|_| self.debug == DebugView::Wireframe);
        let debug = self.debug != DebugView::Shaded;
        let mut current = None;
        for &(key, ref range) in &self.draws {
            if self.characters[key.model()].two_sided != foliage {
                continue;
            }
            let c = &self.characters[key.model()];
            let (impostor, animated) = (c.impostor, c.animated_impostor);
            let mapped = self.mapped(&key, debug);
            let (pipeline, id) = match (key.pass(), wire, foliage) {
                // An impostor's mesh is only where its rows sway (or, animated, four
                // corners): it is always drawn as the quad its shader makes.
                (PASS_FADE, None, _) if impostor || animated => continue,
                _ if impostor => (&self.pipelines.impostor, 6),
                _ if animated => (&self.pipelines.animated_impostor, 8),
                (PASS_MORPH, Some((_, m)), _) => (m, 0),
                (_, Some((l, _)), _) => (l, 1),
                (PASS_FADE, None, _) => continue,
                (PASS_MORPH, None, true) => (&self.pipelines.foliage.1, 2),
                (_, None, true) if c.atlas_lit && self.atlas_lighting => {
                    (&self.pipelines.foliage_lit, 12)
                }
                (_, None, true) => (&self.pipelines.foliage.0, 3),
                (PASS_MORPH, None, false) if mapped => (&self.pipelines.mapped.morph, 9),
                (PASS_MORPH, None, false) => (self.pipelines.morph.get(debug), 4),
                (PASS_DITHER_IN | PASS_DITHER_OUT, None, false) if mapped => {
                    (&self.pipelines.mapped.dither, 10)
                }
                (PASS_DITHER_IN | PASS_DITHER_OUT, None, false) => {
                    (self.pipelines.dither.get(debug), 7)
                }
                _ if mapped => (&self.pipelines.mapped.skinned, 11),
                _ => (self.pipelines.skinned.get(debug), 5),
            };
            if current != Some(id) {
                current = Some(id);
                pass.set_pipeline(pipeline);
            }
            scissor.side(pass, key.side());
            self.draw_group(pass, &key, range);
        }
    }
}

/// The scissor rectangle of the side being drawn, set only when the side changes.
struct Scissor<'a> {
    view: [u32; 4],
    regions: &'a [Region],
    side: Option<usize>,
}

impl Scissor<'_> {
    fn side(&mut self, pass: &mut wgpu::RenderPass<'_>, side: usize) {
        if self.side != Some(side) {
            self.side = Some(side);
            let region = self.regions.get(side).copied().unwrap_or(Region::Full);
            let [x, y, w, h] = region.rect(self.view);
            pass.set_scissor_rect(x, y, w, h);
        }
    }

    fn whole(&mut self, pass: &mut wgpu::RenderPass<'_>) {
        self.side = None;
        let [x, y, w, h] = self.view;
        pass.set_scissor_rect(x, y, w, h);
    }
}

impl SceneRenderer {
    /// Records the frame's passes into `target` through `targets`, drawing only inside
    /// `viewport` (x, y, width, height in pixels) when one is given; each pass timed by `timer`
    /// where one is given.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &super::targets::RenderTargets,
        target: &wgpu::TextureView,
        viewport: Option<[u32; 4]>,
        timer: Option<&FrameTimer>,
    ) {
        let view = viewport.unwrap_or([0, 0, targets.width, targets.height]);
        let [x, y, w, h] = view;
        let passes = self.passes();
        for (n, &which) in passes.iter().enumerate() {
            let (first, last) = (n == 0, n + 1 == passes.len());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(which.name()),
                color_attachments: &[Some(targets.color(target, first, last))],
                depth_stencil_attachment: Some(targets.depth(first, last)),
                timestamp_writes: timer.map(|t| t.writes(which)),
                ..Default::default()
            });
            if let Some(t) = timer {
                t.begin_count(&mut pass, which);
            }
            pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, w, h);
            self.draw(&mut pass, which, view);
            if let Some(t) = timer {
                t.end_count(&mut pass);
            }
        }
    }

    /// Renders one complete frame into `target` through `targets` and submits it.
    pub fn render_to(
        &self,
        gpu: &Gpu,
        targets: &super::targets::RenderTargets,
        target: &wgpu::TextureView,
    ) -> Result<wgpu::SubmissionIndex> {
        self.render_timed(gpu, targets, target, None)
    }

    /// [`Self::render_to`], each pass timed by `timer` where one is given (read the figures
    /// with [`FrameTimer::read`]).
    pub fn render_timed(
        &self,
        gpu: &Gpu,
        targets: &super::targets::RenderTargets,
        target: &wgpu::TextureView,
        mut timer: Option<&mut FrameTimer>,
    ) -> Result<wgpu::SubmissionIndex> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.encode(&mut enc, targets, target, None, timer.as_deref());
        if let Some(t) = timer.as_deref_mut() {
            t.resolve(&mut enc);
        }
        let index = gpu.queue.submit([enc.finish()]);
        if let Some(t) = timer {
            t.submitted();
        }
        gpu.take_error()?;
        Ok(index)
    }
}
