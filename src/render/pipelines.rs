//! The scene renderer's render pipelines, built once: characters (skinned, geomorphed,
//! faded, wireframe), foliage, billboard outlines, the plain baseline shader, and the
//! environment (sky, ground, blob shadows).

use super::shaders;
use super::targets::DEPTH_FORMAT;
use super::uniforms::{GpuInstance, static_vertex_layout};
use crate::bake::gpu_data::drawable::DrawClass;
use std::collections::HashMap;

/// Depth state: test and write, test only, or equal only (the colour pass of a faded level).
#[derive(Clone, Copy)]
enum Depth {
    Write,
    TestOnly,
    Equal,
}

struct PipelineSpec<'a> {
    label: &'a str,
    module: &'a wgpu::ShaderModule,
    vs: &'a str,
    fs: &'a str,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth: Depth,
    blend: Option<wgpu::BlendState>,
    cull: Option<wgpu::Face>,
    /// Colour writes off: a depth-only pass.
    depth_only: bool,
    polygon_mode: wgpu::PolygonMode,
    /// Alpha to coverage (only where there is multisampling).
    alpha_to_coverage: bool,
    /// Depth bias: pulls a surface lying on another towards the eye.
    bias: wgpu::DepthBiasState,
    topology: wgpu::PrimitiveTopology,
    /// Values of the module's `override` constants, for the fragment shader.
    constants: &'a [(&'a str, f64)],
}

impl<'a> PipelineSpec<'a> {
    fn new(label: &'a str, module: &'a wgpu::ShaderModule, vs: &'a str, fs: &'a str) -> Self {
        PipelineSpec {
            label,
            module,
            vs,
            fs,
            buffers: &[],
            depth: Depth::Write,
            blend: None,
            cull: None,
            depth_only: false,
            polygon_mode: wgpu::PolygonMode::Fill,
            alpha_to_coverage: false,
            bias: Default::default(),
            topology: wgpu::PrimitiveTopology::TriangleList,
            constants: &[],
        }
    }
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    format: wgpu::TextureFormat,
    samples: u32,
    spec: PipelineSpec,
) -> wgpu::RenderPipeline {
    let depth_stencil = match spec.depth {
        Depth::Write => Some((true, wgpu::CompareFunction::Less)),
        Depth::TestOnly => Some((false, wgpu::CompareFunction::LessEqual)),
        Depth::Equal => Some((false, wgpu::CompareFunction::Equal)),
    }
    .map(|(write, compare)| wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: spec.bias,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vs),
            compilation_options: Default::default(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: spec.topology,
            cull_mode: spec.cull,
            polygon_mode: spec.polygon_mode,
            ..Default::default()
        },
        depth_stencil,
        multisample: wgpu::MultisampleState {
            count: samples,
            alpha_to_coverage_enabled: spec.alpha_to_coverage && samples > 1,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fs),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: spec.constants,
                ..Default::default()
            },
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: spec.blend,
                // The target's alpha stays the clear's 1 everywhere: a fragment's alpha is for
                // coverage (foliage's alpha to coverage) or blending (shadows, faded levels)
                // only. Written, it would leave partly transparent pixels at every leaf's edge
                // and under every shadow, which a PNG viewer or a compositing window shows
                // over white: a pale fringe.
                write_mask: if spec.depth_only {
                    wgpu::ColorWrites::empty()
                } else {
                    wgpu::ColorWrites::COLOR
                },
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// What picks a character pipeline: the family of shaders (a drawable's [`DrawClass`]), whether
/// the vertices geomorph, the stage of the frame it draws in, how it is painted, and whether
/// it draws a mesh's cut-out triangles. A draw finds its pipeline by its key (see
/// `renderer::draw`); [`PipelineKey::all`] lists the keys pipelines are built for at once,
/// [`PipelineKey::cut_out`] those built when the first mesh with cut-out parts arrives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    pub class: DrawClass,
    /// A geomorph: each vertex moves towards its place in a coarser level.
    pub morph: bool,
    pub stage: Stage,
    pub look: Look,
    /// A mesh's triangles of cut-out materials (a character's hair cards, feathers, lace; see
    /// `PackedLevel::cut_indices`): drawn two-sided, lit on the side the eye sees, and
    /// alpha-tested at one half by the same fragment shaders (their `cut_out` override).
    pub cut: bool,
}

/// The stage of the frame a character pipeline draws in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Depth tested and written, the whole level.
    Opaque,
    /// One half of a dithered cross-fade: only its half's pixels.
    Dither,
    /// A faded level's first pass: depth only.
    FadeDepth,
    /// A faded level's second pass: colour blended where the depth is equal.
    FadeColor,
    /// Lines, coloured by level (where the adapter draws lines).
    Wireframe,
    /// Foliage's depth pre-pass: depth only, alpha tested (see `FoliagePhase`).
    PrepassDepth,
    /// Foliage's colour after its pre-pass: where the depth is equal, no alpha test.
    PrepassColour,
    /// A tree impostor far enough off that the view its blend weighs most, alone, is within
    /// the tolerance: one colour and one normal read a pixel instead of seven.
    NearestView,
}

/// How a character pipeline paints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Look {
    /// Lit by its materials and vertex normals.
    Shaded,
    /// A debug view. The debug views are a fragment shader of their own, so that the shaded
    /// one carries no branch on the view: on a software rasteriser every branch costs every
    /// pixel, about a quarter of a character's fragment time.
    Debug,
    /// Lit through normal maps: its own vertex shaders read each vertex's layer, its fragment
    /// shaders the map (the debug views keep vertex normals).
    Mapped,
}

impl PipelineKey {
    /// A mesh's pipeline.
    pub fn mesh(morph: bool, stage: Stage, look: Look) -> PipelineKey {
        PipelineKey {
            class: DrawClass::Mesh,
            morph,
            stage,
            look,
            cut: false,
        }
    }

    /// The same pipeline for a mesh's cut-out triangles.
    pub fn cut_out(self) -> PipelineKey {
        PipelineKey { cut: true, ..self }
    }

    /// The one pipeline foliage and impostors of `class` draw with (foliage also geomorphs).
    pub fn own(class: DrawClass, morph: bool) -> PipelineKey {
        PipelineKey {
            class,
            morph,
            stage: Stage::Opaque,
            look: Look::Shaded,
            cut: false,
        }
    }

    /// The filled meshes' keys: each look at each stage of a level, a geomorph, a dithered
    /// half and an alpha transition's colour, and a transition's depth.
    fn meshes() -> Vec<PipelineKey> {
        use Stage::*;
        let mut keys = Vec::new();
        for look in [Look::Shaded, Look::Debug, Look::Mapped] {
            for (morph, stage) in [
                (false, Opaque),
                (true, Opaque),
                (false, Dither),
                (false, FadeColor),
            ] {
                keys.push(Self::mesh(morph, stage, look));
            }
        }
        keys.push(Self::mesh(false, FadeDepth, Look::Shaded));
        keys
    }

    /// The keys of the pipelines for meshes' cut-out triangles: [`Self::cut_out`] of every
    /// filled mesh key (a wireframe draws them as lines with the rest). Built only once a
    /// mesh with cut-out parts is uploaded: most scenes have none, and on a CPU adapter each
    /// pipeline costs tens of milliseconds to build.
    pub fn cut_outs() -> Vec<PipelineKey> {
        Self::meshes().into_iter().map(Self::cut_out).collect()
    }

    /// Every key a pipeline is built for at once; wireframes where the adapter draws lines.
    pub fn all(wireframe: bool) -> Vec<PipelineKey> {
        use Stage::*;
        let mut keys = Self::meshes();
        if wireframe {
            keys.push(Self::mesh(false, Wireframe, Look::Debug));
            keys.push(Self::mesh(true, Wireframe, Look::Debug));
        }
        keys.push(Self::own(DrawClass::Foliage, false));
        keys.push(Self::own(DrawClass::Foliage, true));
        for morph in [false, true] {
            for stage in [PrepassDepth, PrepassColour] {
                keys.push(PipelineKey {
                    stage,
                    ..Self::own(DrawClass::Foliage, morph)
                });
            }
        }
        keys.push(Self::own(DrawClass::AtlasLitFoliage, false));
        keys.push(Self::own(DrawClass::TreeImpostor, false));
        keys.push(PipelineKey {
            stage: NearestView,
            ..Self::own(DrawClass::TreeImpostor, false)
        });
        keys.push(Self::own(DrawClass::CharacterImpostor, false));
        keys
    }

    /// The vertex and fragment entry points (`shaders/character.wgsl`, `impostor.wgsl`). With
    /// multisampling, cut-outs have fragment shaders of their own that sharpen the alpha for
    /// alpha to coverage.
    fn entry_points(self, multisampled: bool) -> (&'static str, &'static str) {
        let cut = |single, multi| if multisampled { multi } else { single };
        match self.class {
            DrawClass::Foliage => (
                if self.morph {
                    "vs_foliage_morph"
                } else {
                    "vs_foliage"
                },
                match self.stage {
                    Stage::PrepassDepth => "fs_foliage_depth",
                    Stage::PrepassColour => "fs_foliage_equal",
                    _ => cut("fs_foliage", "fs_foliage_coverage"),
                },
            ),
            DrawClass::AtlasLitFoliage => (
                "vs_foliage_lit",
                cut("fs_foliage_lit", "fs_foliage_lit_coverage"),
            ),
            DrawClass::TreeImpostor if self.stage == Stage::NearestView => (
                "vs_impostor",
                cut("fs_impostor_nearest", "fs_impostor_nearest_coverage"),
            ),
            DrawClass::TreeImpostor => ("vs_impostor", cut("fs_impostor", "fs_impostor_coverage")),
            DrawClass::CharacterImpostor => (
                "vs_animated_impostor",
                cut("fs_animated_impostor", "fs_animated_impostor_coverage"),
            ),
            DrawClass::Mesh => {
                let mapped = self.look == Look::Mapped;
                let vs = match (self.morph, mapped) {
                    (false, false) => "vs_main",
                    (true, false) => "vs_morph",
                    (false, true) => "vs_main_mapped",
                    (true, true) => "vs_morph_mapped",
                };
                let fs = match (self.stage, self.look) {
                    (Stage::Wireframe, _) => "fs_debug",
                    (Stage::Dither, Look::Shaded) => "fs_dither",
                    (Stage::Dither, Look::Debug) => "fs_debug_dither",
                    (Stage::Dither, Look::Mapped) => "fs_dither_mapped",
                    (_, Look::Mapped) if self.morph => "fs_morph_mapped",
                    (_, Look::Mapped) => "fs_mapped",
                    (_, Look::Debug) => "fs_debug",
                    (_, Look::Shaded) => "fs_main",
                };
                (vs, fs)
            }
        }
    }

    /// The pipeline's description, on the characters' vertex buffer `instances`.
    fn spec<'a>(
        self,
        label: &'a str,
        module: &'a wgpu::ShaderModule,
        instances: &'a [Option<wgpu::VertexBufferLayout<'a>>],
        multisampled: bool,
    ) -> PipelineSpec<'a> {
        let (vs, fs) = self.entry_points(multisampled);
        let base = PipelineSpec {
            buffers: instances,
            ..PipelineSpec::new(label, module, vs, fs)
        };
        if self.class != DrawClass::Mesh {
            // Cut out: no culling, the texture's alpha as a cut-out; with multisampling, alpha
            // to coverage smooths the cut edges. The pre-pass's two stages cut out by depth.
            return match self.stage {
                Stage::PrepassDepth => PipelineSpec {
                    depth_only: true,
                    ..base
                },
                Stage::PrepassColour => PipelineSpec {
                    depth: Depth::Equal,
                    ..base
                },
                _ => PipelineSpec {
                    alpha_to_coverage: true,
                    ..base
                },
            };
        }
        let mesh = if self.cut {
            PipelineSpec {
                constants: &[("cut_out", 1.0)],
                ..base
            }
        } else {
            PipelineSpec {
                cull: Some(wgpu::Face::Back),
                ..base
            }
        };
        match self.stage {
            // (The pre-pass stages are foliage's only, the nearest view an impostor's; a mesh
            // never has them.)
            Stage::Opaque
            | Stage::Dither
            | Stage::PrepassDepth
            | Stage::PrepassColour
            | Stage::NearestView => mesh,
            Stage::FadeDepth => PipelineSpec {
                depth_only: true,
                ..mesh
            },
            Stage::FadeColor => PipelineSpec {
                depth: Depth::Equal,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                ..mesh
            },
            Stage::Wireframe => PipelineSpec {
                polygon_mode: wgpu::PolygonMode::Line,
                ..mesh
            },
        }
    }
}

/// Every pipeline the scene renderer draws with.
pub(super) struct Pipelines {
    /// The characters' and trees' pipelines, by key (built for [`PipelineKey::all`]).
    characters: HashMap<PipelineKey, wgpu::RenderPipeline>,
    /// Billboard outlines: lines over the billboards, tested against depth.
    pub outline: wgpu::RenderPipeline,
    /// The plain calibration shader: every level drawn from one fixed pose.
    pub plain: wgpu::RenderPipeline,
    pub sky: wgpu::RenderPipeline,
    pub ground: wgpu::RenderPipeline,
    pub shadow: wgpu::RenderPipeline,
    /// What [`Self::build_cut_outs`] builds from, later.
    character_module: wgpu::ShaderModule,
    with_characters: wgpu::PipelineLayout,
    color_format: wgpu::TextureFormat,
    sample_count: u32,
}

impl Pipelines {
    /// The pipelines for colour targets of `color_format` with `sample_count` samples, on the
    /// frame's bind group layout and the characters' (group 1).
    pub fn new(
        device: &wgpu::Device,
        frame_layout: &wgpu::BindGroupLayout,
        character_layout: &wgpu::BindGroupLayout,
        color_format: wgpu::TextureFormat,
        sample_count: u32,
    ) -> Pipelines {
        let with_characters = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("characters"),
            bind_group_layouts: &[Some(frame_layout), Some(character_layout)],
            immediate_size: 0,
        });
        let frame_only = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("environment"),
            bind_group_layouts: &[Some(frame_layout)],
            immediate_size: 0,
        });

        let character_module = shaders::CHARACTER_SHADER.create(device);
        let plain_module = shaders::PLAIN_SHADER.create(device);
        let environment_module = shaders::ENVIRONMENT_SHADER.create(device);
        let shadow_module = shaders::SHADOW_SHADER.create(device);
        let build = |layout, spec| pipeline(device, layout, color_format, sample_count, spec);
        let instances = [Some(GpuInstance::layout())];
        let plain_buffers = [Some(static_vertex_layout()), Some(GpuInstance::layout())];
        let lines = device
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE);
        let characters = PipelineKey::all(lines)
            .into_iter()
            .map(|key| {
                let label = format!("{key:?}");
                let spec = key.spec(&label, &character_module, &instances, sample_count > 1);
                let made = pipeline(device, &with_characters, color_format, sample_count, spec);
                (key, made)
            })
            .collect();
        let outline = build(
            &with_characters,
            PipelineSpec {
                buffers: &instances,
                depth: Depth::TestOnly,
                // Half see-through: where thousands of fine billboards crowd, the leaves
                // still show.
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                topology: wgpu::PrimitiveTopology::LineList,
                ..PipelineSpec::new(
                    "billboard outlines",
                    &character_module,
                    "vs_outline",
                    "fs_outline",
                )
            },
        );
        let plain = build(
            &with_characters,
            PipelineSpec {
                buffers: &plain_buffers,
                cull: Some(wgpu::Face::Back),
                ..PipelineSpec::new("plain characters", &plain_module, "vs_main", "fs_main")
            },
        );
        let sky = build(
            &frame_only,
            PipelineSpec {
                depth: Depth::TestOnly,
                ..PipelineSpec::new("sky", &environment_module, "vs_sky", "fs_sky")
            },
        );
        let ground = build(
            &frame_only,
            PipelineSpec::new("ground", &environment_module, "vs_ground", "fs_ground"),
        );
        let shadow = build(
            &with_characters,
            PipelineSpec {
                buffers: &instances,
                depth: Depth::TestOnly,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                // The shadows lie on the ground: at grazing angles and a distance their depth
                // and the ground's fight in bands without a bias towards the eye.
                bias: wgpu::DepthBiasState {
                    constant: -8,
                    slope_scale: -2.0,
                    clamp: 0.0,
                },
                ..PipelineSpec::new("blob shadows", &shadow_module, "vs_main", "fs_main")
            },
        );
        Pipelines {
            characters,
            outline,
            plain,
            sky,
            ground,
            shadow,
            character_module,
            with_characters,
            color_format,
            sample_count,
        }
    }

    /// Builds the pipelines of meshes' cut-out triangles ([`PipelineKey::cut_outs`]), where
    /// they are not built yet.
    pub fn build_cut_outs(&mut self, device: &wgpu::Device) {
        let instances = [Some(GpuInstance::layout())];
        for key in PipelineKey::cut_outs() {
            if self.characters.contains_key(&key) {
                continue;
            }
            let label = format!("{key:?}");
            let spec = key.spec(
                &label,
                &self.character_module,
                &instances,
                self.sample_count > 1,
            );
            let made = pipeline(
                device,
                &self.with_characters,
                self.color_format,
                self.sample_count,
                spec,
            );
            self.characters.insert(key, made);
        }
    }

    /// The pipeline of `key`: one of [`PipelineKey::all`], or of [`PipelineKey::cut_outs`]
    /// once built (the renderer's choice of keys is checked against those lists by a test).
    pub fn get(&self, key: PipelineKey) -> &wgpu::RenderPipeline {
        &self.characters[&key]
    }

    /// Whether the adapter draws lines, so that there are wireframe pipelines.
    pub fn has_wireframe(&self) -> bool {
        self.characters
            .contains_key(&PipelineKey::mesh(false, Stage::Wireframe, Look::Debug))
    }
}
