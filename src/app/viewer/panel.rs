//! The egui side panel: performance, adapter, and the crowd's controls.

use crate::render::FrameStats;
use std::collections::VecDeque;

/// How much history the frame-time graph shows.
const HISTORY_SECONDS: f64 = 5.0;

/// Frame times over the last few seconds.
#[derive(Default)]
pub struct FrameHistory {
    samples: VecDeque<(f64, f32)>,
}

impl FrameHistory {
    /// Records a frame that took `ms` milliseconds and ended at `now` seconds.
    pub fn push(&mut self, now: f64, ms: f32) {
        self.samples.push_back((now, ms));
        while self
            .samples
            .front()
            .is_some_and(|(t, _)| now - t > HISTORY_SECONDS)
        {
            self.samples.pop_front();
        }
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
    fn graph(&self, ui: &mut egui::Ui) {
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

/// What the user can change.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub count: usize,
    /// `None`: every model; otherwise only this one.
    pub model: Option<usize>,
    /// `None`: each character plays a clip of its own.
    pub clip: Option<String>,
    pub playing: bool,
    pub speed: f32,
    pub shadows: bool,
}

/// Facts the panel shows.
pub struct Info<'a> {
    pub adapter: &'a str,
    pub backend: &'a str,
    pub models: &'a [String],
    /// Clip names of every model.
    pub clips: &'a [Vec<String>],
    pub stats: FrameStats,
    pub time: f32,
}

/// What the panel asks for beyond changing [`Settings`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Requests {
    pub relayout: bool,
    pub reset_camera: bool,
}

pub fn show(ui: &mut egui::Ui, s: &mut Settings, history: &FrameHistory, info: &Info) -> Requests {
    let mut req = Requests::default();
    ui.heading("lodlab");
    ui.label(egui::RichText::new(format!("{} · {}", info.adapter, info.backend)).small());
    ui.separator();

    ui.strong("Performance");
    ui.label(format!(
        "{:.1} fps · {:.1} ms mean over 5 s",
        history.fps(),
        history.mean_ms()
    ));
    history.graph(ui);
    let st = info.stats;
    egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
        ui.label("instances");
        ui.label(thousands(st.instances));
        ui.end_row();
        ui.label("triangles");
        ui.label(thousands(st.triangles));
        ui.end_row();
        ui.label("influences");
        ui.label(thousands(st.influences));
        ui.end_row();
        ui.label("draw calls");
        ui.label(st.draw_calls.to_string());
        ui.end_row();
    });
    ui.separator();

    ui.strong("Crowd");
    if ui
        .add(
            egui::Slider::new(&mut s.count, 0..=2000)
                .logarithmic(true)
                .text("instances"),
        )
        .changed()
    {
        req.relayout = true;
    }
    let model_label = |m: Option<usize>| match m {
        None => info.models.join(" + "),
        Some(i) => info.models[i].clone(),
    };
    egui::ComboBox::from_label("model")
        .selected_text(model_label(s.model))
        .show_ui(ui, |ui| {
            for choice in std::iter::once(None).chain((0..info.models.len()).map(Some)) {
                if ui
                    .selectable_value(&mut s.model, choice, model_label(choice))
                    .changed()
                {
                    s.clip = None;
                    req.relayout = true;
                }
            }
        });
    let mut names: Vec<String> = Vec::new();
    for (i, clips) in info.clips.iter().enumerate() {
        if s.model.is_none_or(|m| m == i) {
            for c in clips {
                if !names.contains(c) {
                    names.push(c.clone());
                }
            }
        }
    }
    egui::ComboBox::from_label("clip")
        .selected_text(s.clip.clone().unwrap_or_else(|| "mixed".into()))
        .show_ui(ui, |ui| {
            if ui.selectable_value(&mut s.clip, None, "mixed").changed() {
                req.relayout = true;
            }
            for n in &names {
                if ui
                    .selectable_value(&mut s.clip, Some(n.clone()), n)
                    .changed()
                {
                    req.relayout = true;
                }
            }
        });
    ui.separator();

    ui.strong("Animation");
    ui.horizontal(|ui| {
        let label = if s.playing { "Pause" } else { "Play" };
        if ui.button(label).clicked() {
            s.playing = !s.playing;
        }
        ui.label(format!("t = {:.2} s", info.time));
    });
    ui.add(egui::Slider::new(&mut s.speed, 0.0..=3.0).text("speed"));
    ui.checkbox(&mut s.shadows, "blob shadows");
    ui.separator();

    ui.strong("Camera");
    if ui.button("reset view (R)").clicked() {
        req.reset_camera = true;
    }
    ui.label(
        egui::RichText::new(
            "left drag: orbit · right drag: pan\nwheel: zoom · WASD: fly · Q/E: down/up\nShift: faster · Space: play/pause",
        )
        .small(),
    );
    req
}

fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fps_counts_the_last_second() {
        let mut h = FrameHistory::default();
        for k in 0..200 {
            h.push(k as f64 * 0.02, 20.0);
        }
        assert!((h.fps() - 50.0).abs() < 0.5);
        // Old samples drop out of the window.
        assert!(h.samples.len() <= 252);
    }

    #[test]
    fn thousands_separators() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(1234567), "1,234,567");
        assert_eq!(thousands(999), "999");
    }
}
