//! The bench's coverage: at a few views along the path, each method's frame is timed for its
//! fragment counts, then each pass it drew is drawn alone to count the pixels it covers, and
//! each level kind is drawn alone for its cost (see [`crate::measure::coverage`]). Outside
//! the timed frames, between the warm-up and the measuring.
//!
//! It goes in two steps so that it can say how long it will take: first the frame of every
//! method at every view (a round each, like the measuring's, which also sizes the measuring),
//! then the passes and kinds drawn alone, view by view. The second step's cost follows the
//! frame's (it draws the same passes again), so its first view of every method, over that
//! view's frame, scales the other views' frames into an estimate of the rest.

use super::frame::{Bench, Samples, path_time};
use crate::app::progress::Progress;
use crate::render::CharacterShader;
use crate::render::timer::{Pass, PassTimes};
use crate::scene::LodMethod;
use anyhow::Result;
use std::time::Instant;

/// Views along the path at which each method's passes are drawn apart to see the pixels they
/// cover.
pub const COVERAGE_VIEWS: usize = 4;

/// The frame of one method at one coverage view: its passes' figures, and the wall seconds
/// of showing and drawing it skinned, and of the whole round (with the calibration).
struct ViewFrame {
    times: PassTimes,
    skinned_seconds: f64,
    round_seconds: f64,
}

/// The coverage under way: every method's frame at every view, `[method][view]`.
pub struct Coverage {
    frames: Vec<Vec<ViewFrame>>,
    bar: Progress,
}

impl Coverage {
    /// The first step: every method's frame at every view, views in turn. None where the
    /// adapter counts no fragments.
    pub fn frames(bench: &mut Bench, order: &[LodMethod]) -> Result<Option<Coverage>> {
        let bar = Progress::new(
            true,
            "bench coverage",
            (2 * COVERAGE_VIEWS * order.len()) as u64,
        );
        let mut frames: Vec<Vec<ViewFrame>> = order.iter().map(|_| Vec::new()).collect();
        for i in 0..COVERAGE_VIEWS {
            for (f, &m) in frames.iter_mut().zip(order) {
                bar.set_stage(m.name());
                let start = Instant::now();
                bench.show(m, path_time(&bench.path, i, COVERAGE_VIEWS));
                let Some(times) = bench.time(CharacterShader::Skinned)?.1 else {
                    bar.finish();
                    return Ok(None);
                };
                let skinned_seconds = start.elapsed().as_secs_f64();
                bench.time(CharacterShader::Plain)?;
                f.push(ViewFrame {
                    times,
                    skinned_seconds,
                    round_seconds: start.elapsed().as_secs_f64(),
                });
                bar.inc();
            }
        }
        Ok(Some(Coverage { frames, bar }))
    }

    /// Wall seconds of its rounds of every method, one a view, and how many they are.
    pub fn rounds(&self) -> (f64, usize) {
        let total: f64 = self.frames.iter().flatten().map(|f| f.round_seconds).sum();
        (total, self.frames.first().map_or(0, Vec::len))
    }

    /// The second step's first view of every method, added to `samples`; returns the
    /// estimate of the other views' seconds.
    pub fn first_view(
        &self,
        bench: &mut Bench,
        order: &[LodMethod],
        samples: &mut [Samples],
    ) -> Result<f64> {
        let mut left = 0.0;
        for ((s, &m), frames) in samples.iter_mut().zip(order).zip(&self.frames) {
            let start = Instant::now();
            self.view(bench, m, 0, &frames[0].times, s)?;
            let scale = start.elapsed().as_secs_f64() / frames[0].skinned_seconds.max(1e-9);
            left += frames[1..]
                .iter()
                .map(|f| scale * f.skinned_seconds)
                .sum::<f64>();
        }
        Ok(left)
    }

    /// The second step's other views, view by view, every method at each.
    pub fn other_views(
        self,
        bench: &mut Bench,
        order: &[LodMethod],
        samples: &mut [Samples],
    ) -> Result<()> {
        for i in 1..COVERAGE_VIEWS {
            for ((s, &m), frames) in samples.iter_mut().zip(order).zip(&self.frames) {
                self.view(bench, m, i, &frames[i].times, s)?;
            }
        }
        self.bar.finish();
        Ok(())
    }

    /// View `i` of method `m`, whose frame there counted `times`: each pass drawn alone for
    /// the pixels it covers, each level kind for its cost, added to `s`.
    fn view(
        &self,
        bench: &mut Bench,
        m: LodMethod,
        i: usize,
        times: &PassTimes,
        s: &mut Samples,
    ) -> Result<()> {
        self.bar.set_stage(m.name());
        let pixels = (bench.size[0] as u64 * bench.size[1] as u64).max(1) as f64;
        bench.show(m, path_time(&bench.path, i, COVERAGE_VIEWS));
        let mut view = [None; Pass::COUNT];
        for pass in Pass::ALL {
            let Some(fragments) = times.fragments[pass as usize] else {
                continue;
            };
            let covered = crate::measure::coverage::covered_pixels(
                &bench.gpu,
                &bench.world.renderer,
                &bench.target,
                pass,
            )?;
            let f = fragments as f64;
            view[pass as usize] = Some([
                f / pixels,
                f / covered.max(1) as f64,
                covered as f64 / pixels,
            ]);
        }
        s.coverage.push(view);
        if let Some(timer) = &mut bench.timer {
            s.kind_costs.push(crate::measure::coverage::kinds_alone(
                &bench.gpu,
                &mut bench.world.renderer,
                &bench.target,
                timer,
            )?);
        }
        self.bar.inc();
        Ok(())
    }
}
