//! Drawing a prepared frame: the passes in order, each group of instances one instanced draw
//! nearest first, each side of a comparison inside its scissor rectangle.

use super::cull::Region;
use super::keys::{
    DrawKey, PASS_DISSOLVE_OUT, PASS_DITHER_IN, PASS_DITHER_OUT, PASS_FADE, PASS_MORPH, PASS_OPAQUE,
};
use super::{CharacterShader, DebugView, SceneRenderer};
use crate::bake::gpu_data::drawable::DrawClass;
use crate::render::gpu::Gpu;
use crate::render::pipelines::{Look, PipelineKey, Stage};
use crate::render::timer::{FrameTimer, Pass};
use anyhow::Result;
use std::ops::Range;

impl SceneRenderer {
    /// The passes this frame draws, in order (see [`Pass`]): the opaque characters and the
    /// trees first, each group nearest first, so that early depth testing spares what they
    /// hide; then the ground and the sky (at the far plane, tested against depth), so that
    /// each pixel of the environment is shaded once and only where nothing covers it; then
    /// the blob shadows, blended over the ground and hidden behind characters by the depth
    /// test; then the faded levels of alpha transitions over all of it.
    pub fn passes(&self) -> smallvec::SmallVec<[Pass; Pass::COUNT]> {
        let plain = self.shader == CharacterShader::Plain;
        let wireframe = self.wireframe();
        let foliage = |k: &DrawKey| self.characters[k.model()].class.is_tree();
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
        self.outlines && self.shader != CharacterShader::Plain && !self.wireframe()
    }

    /// Whether the foliage pass draws plain foliage's depth first (see [`FoliagePhase`]):
    /// asked for, one sample a pixel (with more, alpha to coverage needs the cut-out's
    /// alpha), and neither lines nor the plain calibration draw.
    fn uses_foliage_prepass(&self) -> bool {
        self.foliage_prepass
            && self.sample_count == 1
            && !self.wireframe()
            && self.shader != CharacterShader::Plain
    }

    /// Whether the frame is drawn as lines: asked for, where the adapter draws lines.
    fn wireframe(&self) -> bool {
        self.debug == DebugView::Wireframe && self.pipelines.has_wireframe()
    }

    /// How the mesh draw `key` is painted: by its debug view, through normal maps, or shaded.
    fn look(&self, key: &DrawKey) -> Look {
        if self.debug != DebugView::Shaded {
            Look::Debug
        } else if self.mapped(key) {
            Look::Mapped
        } else {
            Look::Shaded
        }
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
            Pass::Characters => self.draw_opaque(pass, &mut scissor, None),
            Pass::Foliage if self.uses_foliage_prepass() => {
                self.draw_opaque(pass, &mut scissor, Some(FoliagePhase::Depth));
                self.draw_opaque(pass, &mut scissor, Some(FoliagePhase::Colour));
            }
            Pass::Foliage => self.draw_opaque(pass, &mut scissor, Some(FoliagePhase::Single)),
            Pass::Environment if !self.environment => {}
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
                let fades = || self.draws.iter().filter(|(k, _)| k.pass() == PASS_FADE);
                let depth = PipelineKey::mesh(false, Stage::FadeDepth, Look::Shaded);
                let mut current = None;
                for (key, range) in fades() {
                    scissor.side(pass, key.side());
                    self.draw_group(pass, key, range, depth, &mut current);
                }
                for (key, range) in fades() {
                    let pipeline = PipelineKey::mesh(false, Stage::FadeColor, self.look(key));
                    scissor.side(pass, key.side());
                    self.draw_group(pass, key, range, pipeline, &mut current);
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

    /// Whether the draw `key` can be lit through normal maps: maps on, a mesh's level (or, in
    /// a geomorph, either end) that has one.
    fn mapped(&self, key: &DrawKey) -> bool {
        if !self.normal_maps {
            return false;
        }
        let c = &self.characters[key.model()];
        if c.class != DrawClass::Mesh {
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

    /// One instanced draw of a group's level from its method's set by `pipeline` (`current`:
    /// the pipeline the pass has set). A mesh level with cut-out triangles is two: its opaque
    /// triangles by `pipeline`, its cut-out ones by that pipeline's cut-out twin (in
    /// wireframe, all of them as lines).
    fn draw_group(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        key: &DrawKey,
        range: &Range<u32>,
        pipeline: PipelineKey,
        current: &mut Option<PipelineKey>,
    ) {
        let c = &self.characters[key.model()];
        let set = c.set(key.slot()).unwrap_or_else(|| c.full());
        let level = &set.levels[key.level().min(set.levels.len() - 1)];
        pass.set_bind_group(1, &set.bind_group, &[]);
        pass.set_index_buffer(set.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        let all = drawn_indices(set, level, key);
        let cut = match pipeline {
            PipelineKey {
                class: DrawClass::Mesh,
                stage,
                ..
            } if stage != Stage::Wireframe => level.cut_indices.min(all.len() as u32),
            _ => 0,
        };
        let split = all.end - cut;
        for (indices, pipeline) in [
            (all.start..split, pipeline),
            (split..all.end, pipeline.cut_out()),
        ] {
            if indices.is_empty() {
                continue;
            }
            if *current != Some(pipeline) {
                *current = Some(pipeline);
                pass.set_pipeline(self.pipelines.get(pipeline));
            }
            pass.draw_indexed(indices, level.base_vertex as i32, range.clone());
        }
    }

    /// The opaque draws of the characters (`foliage` None) or of the trees in one of their
    /// phases: levels and geomorphs (in wireframe mode the faded levels of alpha transitions
    /// too, as lines), or the plain calibration draw of everything.
    fn draw_opaque(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        scissor: &mut Scissor,
        foliage: Option<FoliagePhase>,
    ) {
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
                pass.draw_indexed(
                    drawn_indices(set, level, &key),
                    level.base_vertex as i32,
                    range.clone(),
                );
            }
            pass.set_vertex_buffer(0, self.instance_buffer.slice(..));
            return;
        }
        let wire = self.wireframe();
        let mut current = None;
        for &(key, ref range) in &self.draws {
            let c = &self.characters[key.model()];
            if c.class.is_tree() != foliage.is_some()
                || self.only_kind.is_some_and(|k| k != c.level_kind)
            {
                continue;
            }
            let class = match c.class {
                DrawClass::AtlasLitFoliage if !self.atlas_lighting => DrawClass::Foliage,
                class => class,
            };
            let phase = foliage.unwrap_or(FoliagePhase::Single);
            let nearest_view = key.variant() == 1;
            let Some(pipeline) =
                opaque_pipeline(class, key.pass(), wire, phase, nearest_view, || {
                    self.look(&key)
                })
            else {
                continue;
            };
            scissor.side(pass, key.side());
            self.draw_group(pass, &key, range, pipeline, &mut current);
        }
    }
}

/// The indices a group of `key` draws of `level` of `set`: a clump level seen from one view
/// sector only the planes that sector can show (the key's variant, 1 + the sector), else
/// the whole level.
pub(super) fn drawn_indices(
    set: &crate::render::character::GpuLodSet,
    level: &crate::bake::gpu_data::lod_pack::PackedLevel,
    key: &DrawKey,
) -> Range<u32> {
    let sector = (key.variant() as usize)
        .checked_sub(1)
        .and_then(|s| set.view_subsets.get(s));
    match sector {
        Some(&[first, count]) => first..first + count,
        None => level.first_index..level.first_index + level.index_count,
    }
}

/// The pipeline of an opaque-pass draw of a `class` drawable in `pass` (one of the
/// `PASS_*` keys), `wire` when the frame is drawn as lines, `nearest_view` for a tree
/// impostor far enough off to show one view; `look` tells how a mesh is painted. None: not
/// drawn in the opaque passes (a faded level, which the transitions pass draws; an
/// impostor's faded half).
fn opaque_pipeline(
    class: DrawClass,
    pass: u64,
    wire: bool,
    phase: FoliagePhase,
    nearest_view: bool,
    look: impl FnOnce() -> Look,
) -> Option<PipelineKey> {
    let morph = pass == PASS_MORPH;
    let prepass = |stage| PipelineKey {
        stage,
        ..PipelineKey::own(DrawClass::Foliage, morph)
    };
    Some(match class {
        _ if pass == PASS_FADE && !wire => return None,
        // The pre-pass is plain foliage's; everything else draws in the colour phase.
        DrawClass::Foliage if phase == FoliagePhase::Depth && !wire => prepass(Stage::PrepassDepth),
        DrawClass::Foliage if phase == FoliagePhase::Colour && !wire => {
            prepass(Stage::PrepassColour)
        }
        _ if phase == FoliagePhase::Depth => return None,
        // An impostor's mesh is only where its rows sway (or, animated, four corners): it is
        // always drawn as the quad its shader makes, in wireframe too.
        DrawClass::TreeImpostor if nearest_view => PipelineKey {
            stage: Stage::NearestView,
            ..PipelineKey::own(class, false)
        },
        DrawClass::TreeImpostor | DrawClass::CharacterImpostor => PipelineKey::own(class, false),
        _ if wire => PipelineKey::mesh(morph, Stage::Wireframe, Look::Debug),
        DrawClass::AtlasLitFoliage if morph => PipelineKey::own(DrawClass::Foliage, true),
        DrawClass::Foliage | DrawClass::AtlasLitFoliage => PipelineKey::own(class, morph),
        DrawClass::Mesh => match pass {
            PASS_DITHER_IN | PASS_DITHER_OUT => PipelineKey::mesh(false, Stage::Dither, look()),
            _ => PipelineKey::mesh(morph, Stage::Opaque, look()),
        },
    })
}

/// How the foliage pass draws plain foliage (plane-lit billboards and leaves, the default on
/// a CPU adapter). Alpha-tested geometry defeats early depth testing on llvmpipe, so every
/// layer of leaves at a pixel pays the full shader; with the pre-pass, every layer pays a
/// depth-only shader with one texture read, and the nearest alone the colour shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoliagePhase {
    /// In one pass, alpha tested.
    Single,
    /// The pre-pass: depth only, alpha tested.
    Depth,
    /// After the pre-pass: colour where the depth is equal, no alpha test.
    Colour,
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
        targets: &crate::render::targets::RenderTargets,
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
        targets: &crate::render::targets::RenderTargets,
        target: &wgpu::TextureView,
    ) -> Result<wgpu::SubmissionIndex> {
        self.render_timed(gpu, targets, target, None)
    }

    /// [`Self::render_to`], each pass timed by `timer` where one is given (read the figures
    /// with [`FrameTimer::read`]).
    pub fn render_timed(
        &self,
        gpu: &Gpu,
        targets: &crate::render::targets::RenderTargets,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::renderer::keys::{PASS_DISSOLVE_OUT, PASS_OPAQUE};

    /// Every pipeline a draw can ask for is one that is built, and the choices follow the
    /// draw kinds: impostors always by their own shaders, only meshes lit through maps or
    /// dithered, faded levels left to the transitions pass.
    #[test]
    fn every_chosen_pipeline_is_built() {
        let classes = [
            DrawClass::Mesh,
            DrawClass::Foliage,
            DrawClass::AtlasLitFoliage,
            DrawClass::TreeImpostor,
            DrawClass::CharacterImpostor,
        ];
        let passes = [
            PASS_OPAQUE,
            PASS_MORPH,
            PASS_FADE,
            PASS_DISSOLVE_OUT,
            PASS_DITHER_IN,
            PASS_DITHER_OUT,
        ];
        let built = PipelineKey::all(true);
        let mut chosen = std::collections::HashSet::new();
        for class in classes {
            for pass in passes {
                for wire in [false, true] {
                    for phase in [
                        FoliagePhase::Single,
                        FoliagePhase::Depth,
                        FoliagePhase::Colour,
                    ] {
                        if wire && phase != FoliagePhase::Single {
                            // The renderer draws no pre-pass in wireframe.
                            continue;
                        }
                        for (look, nearest) in [Look::Shaded, Look::Debug, Look::Mapped]
                            .into_iter()
                            .flat_map(|l| [(l, false), (l, true)])
                        {
                            let Some(key) =
                                opaque_pipeline(class, pass, wire, phase, nearest, || look)
                            else {
                                assert!(
                                    (pass == PASS_FADE && !wire)
                                        || (phase == FoliagePhase::Depth
                                            && class != DrawClass::Foliage),
                                    "{class:?} {pass} {wire} {phase:?}"
                                );
                                continue;
                            };
                            assert!(built.contains(&key), "{key:?} is not built");
                            chosen.insert(key);
                            if class == DrawClass::TreeImpostor && nearest {
                                assert_eq!(key.stage, Stage::NearestView);
                            } else if class.faces_eye() {
                                assert_eq!(key, PipelineKey::own(class, false));
                            } else if wire {
                                assert_eq!(key.stage, Stage::Wireframe);
                            } else if class == DrawClass::Foliage && phase != FoliagePhase::Single {
                                let stage = match phase {
                                    FoliagePhase::Depth => Stage::PrepassDepth,
                                    _ => Stage::PrepassColour,
                                };
                                assert_eq!((key.stage, key.look), (stage, Look::Shaded));
                            } else if class != DrawClass::Mesh {
                                assert_eq!((key.stage, key.look), (Stage::Opaque, Look::Shaded));
                            }
                        }
                    }
                }
            }
        }
        // The transitions pass's two stages are the only keys the opaque passes never pick.
        let fades: Vec<_> = built.iter().filter(|k| !chosen.contains(k)).collect();
        assert!(
            fades
                .iter()
                .all(|k| matches!(k.stage, Stage::FadeDepth | Stage::FadeColor)),
            "{fades:?}"
        );
        assert_eq!(fades.len(), 4);
        // Every filled mesh pipeline (the opaque passes' and the transitions') has a cut-out
        // twin, which draw_group picks for a level's cut-out triangles; nothing else has.
        let twins: Vec<PipelineKey> = built
            .iter()
            .filter(|k| k.class == DrawClass::Mesh && k.stage != Stage::Wireframe)
            .map(|k| k.cut_out())
            .collect();
        let cut_outs = PipelineKey::cut_outs();
        assert_eq!(twins.len(), cut_outs.len());
        assert!(
            twins
                .iter()
                .all(|k| cut_outs.contains(k) && !built.contains(k))
        );
    }
}
