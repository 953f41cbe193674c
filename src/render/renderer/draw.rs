//! Drawing a prepared frame: the passes in order, each group of instances one instanced draw
//! nearest first, each side of a comparison inside its scissor rectangle.

use super::cull::Region;
use super::keys::{
    DrawKey, PASS_DISSOLVE_OUT, PASS_DITHER_IN, PASS_DITHER_OUT, PASS_FADE, PASS_MORPH, PASS_OPAQUE,
};
use super::{CharacterShader, DebugView, SceneRenderer};
use crate::render::gpu::Gpu;
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
