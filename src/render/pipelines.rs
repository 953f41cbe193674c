//! The scene renderer's render pipelines, built once: characters (skinned, geomorphed,
//! faded, wireframe), foliage, billboard outlines, the plain baseline shader, and the
//! environment (sky, ground, blob shadows).

use super::shaders;
use super::targets::DEPTH_FORMAT;
use super::uniforms::{GpuInstance, static_vertex_layout};

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
            compilation_options: Default::default(),
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

/// A character pipeline twice: shaded by its materials, and painted by a debug view. The debug
/// views are a fragment shader of their own, so that the shaded one carries no branch on the
/// view: on a software rasteriser every branch costs every pixel, about a quarter of a
/// character's fragment time.
pub(super) struct Shading {
    pub shaded: wgpu::RenderPipeline,
    pub debug: wgpu::RenderPipeline,
}

impl Shading {
    pub fn get(&self, debug: bool) -> &wgpu::RenderPipeline {
        if debug { &self.debug } else { &self.shaded }
    }
}

/// The shaded character pipelines again for levels lit through normal maps (the debug views
/// keep vertex normals): their own vertex shaders read each vertex's layer, their fragment
/// shaders the map.
pub(super) struct Mapped {
    pub skinned: wgpu::RenderPipeline,
    pub morph: wgpu::RenderPipeline,
    pub dither: wgpu::RenderPipeline,
    pub fade_color: wgpu::RenderPipeline,
}

/// Every pipeline the scene renderer draws with.
pub(super) struct Pipelines {
    pub skinned: Shading,
    pub morph: Shading,
    /// `skinned` keeping only its half's pixels of a dithered cross-fade.
    pub dither: Shading,
    /// The two passes of a faded level: depth only, then colour where the depth is equal.
    pub fade_depth: wgpu::RenderPipeline,
    pub fade_color: Shading,
    pub mapped: Mapped,
    /// Line-mode versions of `skinned` and `morph`, where the adapter can draw lines.
    pub wireframe: Option<(wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    /// Foliage (alpha-tested, two-sided) versions of `skinned` and `morph`.
    pub foliage: (wgpu::RenderPipeline, wgpu::RenderPipeline),
    /// Foliage lit per pixel: billboard clouds lit through their atlases.
    pub foliage_lit: wgpu::RenderPipeline,
    /// Octahedral impostors: one quad a tree facing the eye, cut out like foliage.
    pub impostor: wgpu::RenderPipeline,
    /// Characters' animated impostors: one quad a character facing the eye, cut out at half
    /// coverage (alpha to coverage with multisampling).
    pub animated_impostor: wgpu::RenderPipeline,
    /// Billboard outlines: lines over the billboards, tested against depth.
    pub outline: wgpu::RenderPipeline,
    pub plain: wgpu::RenderPipeline,
    pub sky: wgpu::RenderPipeline,
    pub ground: wgpu::RenderPipeline,
    pub shadow: wgpu::RenderPipeline,
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
        let (f, s) = (color_format, sample_count);
        let instances = [Some(GpuInstance::layout())];
        let plain_buffers = [Some(static_vertex_layout()), Some(GpuInstance::layout())];
        let character = |label, vs| PipelineSpec {
            buffers: &instances,
            cull: Some(wgpu::Face::Back),
            ..PipelineSpec::new(label, &character_module, vs, "fs_main")
        };
        let build = |layout, spec| pipeline(device, layout, f, s, spec);
        // The shaded pipeline of `spec`, and the same with the debug views' fragment shader.
        let shading = |spec: PipelineSpec<'_>| Shading {
            debug: pipeline(
                device,
                &with_characters,
                f,
                s,
                PipelineSpec {
                    fs: "fs_debug",
                    ..spec
                },
            ),
            shaded: pipeline(device, &with_characters, f, s, spec),
        };
        let skinned = shading(character("skinned characters", "vs_main"));
        let dither = Shading {
            debug: pipeline(
                device,
                &with_characters,
                f,
                s,
                PipelineSpec {
                    fs: "fs_debug_dither",
                    ..character("dithered characters, debug view", "vs_main")
                },
            ),
            shaded: pipeline(
                device,
                &with_characters,
                f,
                s,
                PipelineSpec {
                    fs: "fs_dither",
                    ..character("dithered characters", "vs_main")
                },
            ),
        };
        let morph = shading(character("geomorphed characters", "vs_morph"));
        let fade_depth = build(
            &with_characters,
            PipelineSpec {
                depth_only: true,
                ..character("faded level depth", "vs_main")
            },
        );
        let fade_color_spec = |label, vs| PipelineSpec {
            depth: Depth::Equal,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            ..character(label, vs)
        };
        let fade_color = shading(fade_color_spec("faded level colour", "vs_main"));
        let mapped_spec = |spec: PipelineSpec<'_>, fs| {
            pipeline(device, &with_characters, f, s, PipelineSpec { fs, ..spec })
        };
        let mapped = Mapped {
            skinned: mapped_spec(
                character("normal-mapped characters", "vs_main_mapped"),
                "fs_mapped",
            ),
            morph: mapped_spec(
                character("normal-mapped geomorphs", "vs_morph_mapped"),
                "fs_morph_mapped",
            ),
            dither: mapped_spec(
                character("normal-mapped dithered characters", "vs_main_mapped"),
                "fs_dither_mapped",
            ),
            fade_color: mapped_spec(
                fade_color_spec("normal-mapped faded level colour", "vs_main_mapped"),
                "fs_mapped",
            ),
        };
        // Foliage: no culling, the texture's alpha as a cut-out; with multisampling, alpha to
        // coverage smooths the cut edges.
        let foliage_fs = if s > 1 {
            "fs_foliage_coverage"
        } else {
            "fs_foliage"
        };
        let foliage_spec = |label, vs| PipelineSpec {
            cull: None,
            alpha_to_coverage: true,
            ..PipelineSpec {
                fs: foliage_fs,
                ..character(label, vs)
            }
        };
        let foliage = (
            build(&with_characters, foliage_spec("foliage", "vs_foliage")),
            build(
                &with_characters,
                foliage_spec("geomorphed foliage", "vs_foliage_morph"),
            ),
        );
        let foliage_lit = build(
            &with_characters,
            PipelineSpec {
                fs: if s > 1 {
                    "fs_foliage_lit_coverage"
                } else {
                    "fs_foliage_lit"
                },
                ..foliage_spec("atlas-lit foliage", "vs_foliage_lit")
            },
        );
        let impostor = build(
            &with_characters,
            PipelineSpec {
                fs: if s > 1 {
                    "fs_impostor_coverage"
                } else {
                    "fs_impostor"
                },
                ..foliage_spec("octahedral impostors", "vs_impostor")
            },
        );
        let animated_impostor = build(
            &with_characters,
            PipelineSpec {
                cull: None,
                alpha_to_coverage: true,
                fs: if s > 1 {
                    "fs_animated_impostor_coverage"
                } else {
                    "fs_animated_impostor"
                },
                ..character("animated impostors", "vs_animated_impostor")
            },
        );
        let outline = build(
            &with_characters,
            PipelineSpec {
                fs: "fs_outline",
                depth: Depth::TestOnly,
                // Half see-through: where thousands of fine billboards crowd, the leaves
                // still show.
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                cull: None,
                topology: wgpu::PrimitiveTopology::LineList,
                ..character("billboard outlines", "vs_outline")
            },
        );
        let wireframe = device
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE)
            .then(|| {
                // Wireframes are coloured by level: the debug views' shader.
                let line = |label, vs| PipelineSpec {
                    polygon_mode: wgpu::PolygonMode::Line,
                    fs: "fs_debug",
                    ..character(label, vs)
                };
                (
                    build(&with_characters, line("wireframe characters", "vs_main")),
                    build(&with_characters, line("wireframe geomorphs", "vs_morph")),
                )
            });
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
            skinned,
            morph,
            dither,
            fade_depth,
            fade_color,
            mapped,
            wireframe,
            foliage,
            foliage_lit,
            impostor,
            animated_impostor,
            outline,
            plain,
            sky,
            ground,
            shadow,
        }
    }
}
