//! The frame times the panel shows: a few seconds of them, their median and spread, and
//! whether the viewer paused (a bake, a resize) so that a gap is not read as a slow frame.

use std::collections::VecDeque;

/// How much history the frame-time graph shows.
pub(crate) const HISTORY_SECONDS: f64 = 5.0;
/// Frames the history keeps however old they are.
pub(crate) const MIN_SAMPLES: usize = 8;
/// A frame at least this long may be a pause rather than rendering (see
/// [`FrameHistory::animation_step`]).
pub(crate) const PAUSE_SECONDS: f32 = 0.5;

/// Frame times over the last few seconds.
#[derive(Default)]
pub struct FrameHistory {
    pub(crate) samples: VecDeque<(f64, f32)>,
}

impl FrameHistory {
    /// Records a frame that took `ms` milliseconds and ended at `now` seconds, however long
    /// that was: on a software rasteriser a frame can take seconds, and the readout must say
    /// so. The last few frames stay even when they are older than the graph's span, so that
    /// a slow frame rate still draws a line.
    pub fn push(&mut self, now: f64, ms: f32) {
        self.samples.push_back((now, ms));
        while self.samples.len() > MIN_SAMPLES
            && self
                .samples
                .front()
                .is_some_and(|(t, _)| now - t > HISTORY_SECONDS)
        {
            self.samples.pop_front();
        }
    }

    /// The median frame time of the history, in milliseconds (0 with none).
    pub fn median_ms(&self) -> f32 {
        let mut ms: Vec<f32> = self.samples.iter().map(|s| s.1).collect();
        if ms.is_empty() {
            return 0.0;
        }
        ms.sort_by(f32::total_cmp);
        ms[ms.len() / 2]
    }

    /// How far the animation advances for a frame that took `seconds`: the wall time, except
    /// after a pause (a dragged window, a blocking dialog, a level installed), which shows as a
    /// frame far longer than the usual. A frame counts as a pause beyond four times the median
    /// of the history, and never below half a second, so a steadily slow renderer still plays
    /// in real time.
    pub fn animation_step(&self, seconds: f32) -> f32 {
        let usual = 4.0 * self.median_ms() / 1000.0;
        seconds.min(usual.max(PAUSE_SECONDS))
    }

    /// Frames per second over the last second.
    pub fn fps(&self) -> f32 {
        let Some(&(last, _)) = self.samples.back() else {
            return 0.0;
        };
        let recent: Vec<f32> = self
            .samples
            .iter()
            .filter(|(t, _)| last - t <= 1.0)
            .map(|s| s.1)
            .collect();
        let total: f32 = recent.iter().sum();
        if total > 0.0 {
            recent.len() as f32 * 1000.0 / total
        } else {
            0.0
        }
    }

    pub fn mean_ms(&self) -> f32 {
        if self.samples.is_empty() {
            return 0.0;
        }
        self.samples.iter().map(|s| s.1).sum::<f32>() / self.samples.len() as f32
    }

    /// Draws the frame times as a line over the last [`HISTORY_SECONDS`].
    pub(crate) fn graph(&self, ui: &mut egui::Ui) {
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), 64.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
        let Some(&(now, _)) = self.samples.back() else {
            return;
        };
        let top = self.samples.iter().map(|s| s.1).fold(16.7f32, f32::max) * 1.1;
        let to_screen = |t: f64, ms: f32| {
            let x = rect.right() - ((now - t) / HISTORY_SECONDS) as f32 * rect.width();
            let y = rect.bottom() - (ms / top) * rect.height();
            egui::pos2(x, y)
        };
        // Reference lines at 60, 30 and 10 frames per second, where they stand clear of each
        // other and of the bottom edge.
        let mut last_y = rect.bottom();
        for (ms, label) in [
            (1000.0 / 60.0, "60 fps"),
            (1000.0 / 30.0, "30 fps"),
            (100.0, "10 fps"),
        ] {
            let y = to_screen(now, ms).y;
            if ms < top && last_y - y >= 12.0 {
                last_y = y;
                painter.hline(
                    rect.x_range(),
                    y,
                    egui::Stroke::new(1.0, egui::Color32::from_gray(70)),
                );
                painter.text(
                    egui::pos2(rect.left() + 2.0, y),
                    egui::Align2::LEFT_BOTTOM,
                    label,
                    egui::FontId::proportional(10.0),
                    egui::Color32::from_gray(120),
                );
            }
        }
        let points: Vec<egui::Pos2> = self
            .samples
            .iter()
            .map(|&(t, ms)| to_screen(t, ms))
            .collect();
        painter.add(egui::Shape::line(
            points,
            egui::Stroke::new(1.5, egui::Color32::from_rgb(120, 200, 120)),
        ));
        painter.text(
            rect.right_top() + egui::vec2(-2.0, 2.0),
            egui::Align2::RIGHT_TOP,
            format!("{top:.0} ms"),
            egui::FontId::proportional(10.0),
            egui::Color32::from_gray(150),
        );
    }
}
