//! The panel's read-outs: frame statistics and the levels drawn, GPU time by pass, memory
//! by kind, and a tree chain's levels as a table.

use crate::app::viewer::history::FrameHistory;
use crate::bake::foliage::billboard::chain::CloudKind;
use crate::render::FrameStats;
use crate::render::timer::{Pass, PassTimes};
use crate::runtime::world::LevelSummary;

pub(crate) fn level_color(k: usize) -> egui::Color32 {
    use crate::render::shaders::LEVEL_COLORS;
    let [r, g, b] = LEVEL_COLORS[k.min(LEVEL_COLORS.len() - 1)];
    egui::Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

pub(crate) fn statistics(ui: &mut egui::Ui, history: &FrameHistory, st: &FrameStats) {
    ui.strong("Statistics");
    ui.label(format!(
        "{:.1} fps · {:.1} ms mean over 5 s",
        history.fps(),
        history.mean_ms()
    ));
    history.graph(ui);
    // Two figures a row: the panel fits a 720-line window.
    egui::Grid::new("stats").num_columns(4).show(ui, |ui| {
        let figures = [
            ("instances", st.instances),
            ("triangles", st.triangles),
            ("culled", st.culled),
            ("influences", st.influences),
            ("in transition", st.in_transition),
            ("draw calls", st.draw_calls as u64),
        ];
        for pair in figures.chunks(2) {
            for (label, value) in pair {
                ui.label(*label);
                ui.label(thousands(*value));
            }
            ui.end_row();
        }
    });
    level_histogram(ui, &st.levels);
}

/// Where the frame's GPU time goes, pass by pass, and the fragments shaded per pixel; the
/// panel's own CPU time, `panel_cpu_ms` a frame; and where memory goes. Folded, its title
/// saying the frame's GPU time, so that the panel fits a 720-line window.
pub(crate) fn pass_times(
    ui: &mut egui::Ui,
    passes: Option<&PassTimes>,
    pixels: u64,
    panel_cpu_ms: f64,
    rows: &[(&'static str, u64)],
) {
    let title = match passes {
        Some(p) => format!("GPU time: {:.1} ms a frame", p.frame_ms),
        None => "GPU time: no timestamp queries here".to_string(),
    };
    egui::CollapsingHeader::new(title)
        .id_salt("gpu time")
        .default_open(false)
        .show(ui, |ui| {
            ui.label(
                egui::RichText::new(format!("this panel: {panel_cpu_ms:.2} ms of CPU a frame"))
                    .small(),
            );
            if let Some(p) = passes {
                pass_grid(ui, p, pixels);
            }
            memory(ui, rows);
        });
}

/// GPU milliseconds of every pass, two a row; a pass not drawn shows a dash, so that nothing
/// below moves when a pass comes and goes (transitions do, every few seconds).
fn pass_grid(ui: &mut egui::Ui, p: &PassTimes, pixels: u64) {
    egui::Grid::new("passes").num_columns(4).show(ui, |ui| {
        let rows: Vec<_> = Pass::ALL.iter().zip(&p.ms).collect();
        for pair in rows.chunks(2) {
            for (pass, ms) in pair {
                ui.label(pass.name());
                ui.label(ms.map_or_else(|| "–".to_string(), |ms| format!("{ms:.2}")));
            }
            ui.end_row();
        }
        if let Some(x) = p.overdraw(pixels) {
            ui.label("fragments per pixel");
            ui.label(format!("{x:.2}"));
            ui.end_row();
        }
    });
}

/// Where memory goes, in MB by kind.
fn memory(ui: &mut egui::Ui, rows: &[(&'static str, u64)]) {
    egui::CollapsingHeader::new("Memory")
        .id_salt("memory")
        .show(ui, |ui| {
            egui::Grid::new("memory grid")
                .num_columns(2)
                .show(ui, |ui| {
                    for &(name, bytes) in rows.iter().filter(|(_, b)| *b > 0) {
                        ui.label(name);
                        ui.label(format!("{:.1} MB", bytes as f64 / 1e6));
                        ui.end_row();
                    }
                });
        });
}

/// Instances per level as bars in the levels' debug colours.
pub(crate) fn level_histogram(ui: &mut egui::Ui, levels: &[u32]) {
    let used = levels.iter().rposition(|&n| n > 0).map_or(1, |i| i + 1);
    let (rect, response) =
        ui.allocate_exact_size(egui::vec2(ui.available_width(), 56.0), egui::Sense::hover());
    response.on_hover_text("Instances drawn at each level of detail, in the level tint's colours");
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let top = levels.iter().copied().max().unwrap_or(0).max(1) as f32;
    let slot = rect.width() / used.max(4) as f32;
    for (k, &n) in levels.iter().enumerate().take(used) {
        let x = rect.left() + k as f32 * slot;
        let h = (n as f32 / top) * (rect.height() - 24.0);
        let bar = egui::Rect::from_min_max(
            egui::pos2(x + 2.0, rect.bottom() - 12.0 - h),
            egui::pos2(x + slot - 2.0, rect.bottom() - 12.0),
        );
        painter.rect_filled(bar, 1.0, level_color(k));
        painter.text(
            egui::pos2(x + slot * 0.5, rect.bottom() - 1.0),
            egui::Align2::CENTER_BOTTOM,
            format!("{k}"),
            egui::FontId::proportional(10.0),
            egui::Color32::from_gray(160),
        );
        if n > 0 {
            painter.text(
                egui::pos2(x + slot * 0.5, bar.top() - 1.0),
                egui::Align2::CENTER_BOTTOM,
                n.to_string(),
                egui::FontId::proportional(9.0),
                egui::Color32::from_gray(200),
            );
        }
    }
}

/// A tree's levels: ε, kind, billboards, triangles and animation error, each level's row
/// marked in its tint colour.
pub(crate) fn chain_table(ui: &mut egui::Ui, name: &str, levels: &[LevelSummary]) {
    egui::Grid::new(("levels", name))
        .num_columns(5)
        .striped(true)
        .show(ui, |ui| {
            for h in ["", "ε (m)", "kind", "billb.", "anim"] {
                ui.label(egui::RichText::new(h).small().strong());
            }
            ui.end_row();
            for (k, l) in levels.iter().enumerate() {
                ui.colored_label(level_color(k), format!("L{k}"));
                ui.label(format!("{:.3}", l.epsilon));
                ui.label(CloudKind::word(l.kind.as_ref()));
                ui.label(thousands(l.billboards as u64))
                    .on_hover_text(format!(
                        "{} triangles with the wood",
                        thousands(l.triangles as u64)
                    ));
                ui.label(format!("{:.3}", l.anim_rms))
                    .on_hover_text("RMS animation error, in tree heights");
                ui.end_row();
            }
        });
}

pub(crate) fn thousands(n: u64) -> String {
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
