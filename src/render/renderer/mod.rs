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
use super::uniforms::{FrameUniforms, FrameView, GpuInstance, Lighting};
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_data::lod_pack::LodPack;
use crate::scene::{Instance, LodDraw};
use anyhow::{Result, bail};

mod cull;
mod draw;
mod encode;
mod keys;

pub use cull::Region;
pub use keys::FrameStats;
use keys::{DrawKey, Keyed};
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

pub struct SceneRenderer {
    pub lighting: Lighting,
    pub shader: CharacterShader,
    pub shadows: bool,
    /// Draw the ground and the sky; off, the figures stand on black (`shot --backdrop plain`).
    pub environment: bool,
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
    /// off, one normal a billboard (its leaves' mean). By adapter at first (`Gpu::atlas_lighting`).
    pub atlas_lighting: bool,
    /// Draw plain foliage's depth first, then its colour where the depth is equal (see
    /// `draw::FoliagePhase`); only without multisampling.
    pub foliage_prepass: bool,
    /// A measurement's filter: the opaque passes draw only instances whose level is of this
    /// kind (`None`: every instance). See `bench`'s cost by level kind.
    pub only_kind: Option<crate::bake::gpu_data::drawable::LevelKind>,
    /// The screen tolerance as a share of half the view's height (0: off): a tree impostor
    /// whose nearest view alone projects within it draws that view alone, one colour and one
    /// normal read a pixel instead of seven (see [`Self::set_tolerance`]).
    pub nearest_view_tolerance: f32,
    /// Samples per pixel of the targets this renderer's pipelines draw into.
    sample_count: u32,
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
            environment: true,
            normal_maps: true,
            wind: 1.0,
            outlines: false,
            foliage_tint: false,
            atlas_lighting: gpu.lights_atlases(),
            foliage_prepass: false,
            only_kind: None,
            nearest_view_tolerance: 0.0,
            sample_count,
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
    pub fn add_character(&mut self, gpu: &Gpu, bake: &Drawable) -> Result<usize> {
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
        if let Some(a) = bake.kind.character_impostor() {
            // One texel a view, then one a page's travel (see `impostor_views`).
            let texels = (a.rects.len() + a.travel.len()) as u32;
            gpu.texture_fits(&format!("{name}: impostor views"), texels, 1, 1)?;
        }
        let c = gpu.checked(&format!("uploading {name}"), || {
            GpuCharacter::upload(gpu, &self.character_layout, &self.sampler, bake)
        })?;
        if c.full().levels.iter().any(|l| l.cut_indices > 0) {
            self.pipelines.build_cut_outs(&gpu.device);
        }
        self.characters.push(c);
        Ok(self.characters.len() - 1)
    }

    /// Counts character `index`'s instances as `kind` in the frame's figures (a forest patch
    /// is drawn as a tree impostor but counted apart).
    pub fn set_level_kind(
        &mut self,
        index: usize,
        kind: crate::bake::gpu_data::drawable::LevelKind,
    ) {
        if let Some(c) = self.characters.get_mut(index) {
            c.level_kind = kind;
        }
    }

    /// Uploads `bake` in place of character `index` (one no instance draws any more), freeing
    /// what that one held; returns `index`.
    pub fn replace_character(&mut self, gpu: &Gpu, index: usize, bake: &Drawable) -> Result<usize> {
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
        })?;
        if pack.levels.iter().any(|l| l.cut_indices > 0) {
            self.pipelines.build_cut_outs(&gpu.device);
        }
        Ok(())
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
        self.pipelines.has_wireframe()
    }

    /// The screen tolerance, `pixels` of a view `height` pixels high, that decides where a
    /// tree impostor shows its nearest view alone (0: never).
    pub fn set_tolerance(&mut self, pixels: f32, height: u32) {
        self.nearest_view_tolerance = if height > 0 {
            (pixels / (0.5 * height as f32)).max(0.0)
        } else {
            0.0
        };
    }

    /// Uploads the frame's uniforms and instances (one buffer write each) and plans the draws:
    /// one per (side, model, level, transition state). Each side's instances are culled
    /// against its part of the frustum ([`cull`]), encoded by what they draw ([`encode`]),
    /// then grouped and uploaded.
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
                let sphere = (c.sphere.0 + inst.travel, c.sphere.1);
                let (centre, radius) = cull::bounding_sphere(sphere, &inst.transform);
                if cull::outside(&planes, centre, radius) {
                    stats.culled += 1;
                    continue;
                }
                let draw = side.draws.get(i).copied().unwrap_or(LodDraw::Level(0));
                let distance = (centre - view.eye).length();
                // A clump level draws only the planes of the sector the eye is in, where its
                // wind does not turn them out of their sectors.
                let set = c.full();
                let sway = set.view_subset_sway * (inst.wind * self.wind).abs();
                let sector = if set.view_subsets.is_empty()
                    || sway.is_nan()
                    || sway > set.view_subset_margin
                {
                    None
                } else {
                    let eye = inst.transform.inverse().transform_point3(view.eye);
                    crate::bake::gpu_data::view_subsets::sector_of(eye)
                };
                let near = (distance - radius).max(0.0).to_bits();
                let at = keys::DrawAt {
                    side: side_index,
                    method: side.method,
                    near,
                    nearest_view: keys::shows_nearest_view(
                        c.nearest_view_error,
                        inst.transform.matrix3.x_axis.length(),
                        radius,
                        distance,
                        view.proj.y_axis.y,
                        self.nearest_view_tolerance,
                    ),
                    sector,
                };
                self.encode_instance(inst, draw, at, &mut stats);
            }
        }
        self.group_draws();
        self.upload_instances(gpu);
        stats.draw_calls = self.draws.len() as u32;
        stats
    }
}
