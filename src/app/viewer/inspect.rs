//! The panel's "Selection" section: the picked instance's levels as Unity's LOD Group shows
//! them (coloured bands by screen height, the current one marked, with their triangles), the
//! camera's bookmark, "copy as command" and the recent files.

use super::figures::{level_color, thousands};
use crate::runtime::world::selection::{Band, Inspected};
use crate::scene::LodDraw;
use std::path::PathBuf;

/// What the section shows.
#[derive(Clone, Copy, Default)]
pub struct SelectionInfo<'a> {
    /// The instance selected, as it is now, and whether it was picked since the panel last ran.
    pub inspected: Option<&'a Inspected>,
    pub just_picked: bool,
    /// Whether a camera is bookmarked; the last "copy as command"; the recent files.
    pub bookmarked: bool,
    pub command: Option<&'a str>,
    pub recent: &'a [PathBuf],
}

/// What the section's buttons asked for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SelectionRequests {
    /// Frame the selection; let it go.
    pub frame: bool,
    pub deselect: bool,
    /// Keep the camera; go back to it.
    pub bookmark: bool,
    pub back_to_bookmark: bool,
    /// "Copy as command".
    pub copy_command: bool,
    /// A recent file clicked: show it instead.
    pub open_recent: Option<PathBuf>,
}

/// Screen heights the strip spans, pixels: from its left edge down to its right.
const STRIP_TOP_PX: f32 = 2048.0;
const STRIP_BOTTOM_PX: f32 = 4.0;

/// The section, folded at first; open on the frame something is picked.
pub(super) fn section(ui: &mut egui::Ui, info: &SelectionInfo, requests: &mut SelectionRequests) {
    let title = match info.inspected {
        Some(p) => format!("Selection: {} #{}", p.name, p.instance),
        None => "Selection".into(),
    };
    let mut header = egui::CollapsingHeader::new(egui::RichText::new(title).strong())
        .id_salt("selection")
        .default_open(false);
    if info.just_picked {
        header = header.open(Some(true));
    }
    header.show(ui, |ui| body(ui, info, requests));
}

fn body(ui: &mut egui::Ui, info: &SelectionInfo, requests: &mut SelectionRequests) {
    match info.inspected {
        Some(p) => {
            ui.label(what_it_draws(p));
            let triangles = match p.bands.get(p.level as usize) {
                Some(b) if b.impostor => " · 2 triangles".to_string(),
                Some(Band {
                    triangles: Some(t), ..
                }) => format!(" · {} triangles", thousands(*t)),
                _ => String::new(),
            };
            ui.label(format!(
                "{:.0} px high · error {:.2} px{triangles}",
                p.height_px, p.error_px
            ));
            strip(ui, p);
            ui.horizontal(|ui| {
                requests.frame |= ui
                    .button("frame (F)")
                    .on_hover_text("Look at it from where it fills half the view, and follow it until you pan or fly")
                    .clicked();
                requests.deselect |= ui.button("deselect").clicked();
            });
        }
        None => {
            ui.label(
                egui::RichText::new("Click a character or a tree to see its levels; F frames it.")
                    .small(),
            );
        }
    }
    ui.horizontal(|ui| {
        requests.bookmark |= ui
            .button("bookmark (B)")
            .on_hover_text("Keep this camera, and print it as --camera for shot")
            .clicked();
        requests.back_to_bookmark |= ui
            .add_enabled(info.bookmarked, egui::Button::new("back (Shift+B)"))
            .on_hover_text("Go back to the bookmarked camera")
            .clicked();
    });
    requests.copy_command |= ui
        .button("copy as command (Ctrl+C)")
        .on_hover_text("The lodlab shot line that renders this view (scene, levels of detail, camera, size, time) headless: on the clipboard and on stderr. Animation speed, pause and shadows are not in it.")
        .clicked();
    if let Some(line) = info.command {
        ui.label(egui::RichText::new(line).small().monospace());
    }
    if !info.recent.is_empty() {
        ui.label(egui::RichText::new("recent files").small());
        for path in info.recent {
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into(),
            );
            if ui
                .small_button(name)
                .on_hover_text(path.display().to_string())
                .clicked()
            {
                requests.open_recent = Some(path.clone());
            }
        }
    }
}

/// "level 3 of 8, morphing to 4 (45%)".
fn what_it_draws(p: &Inspected) -> String {
    let of = p.bands.len();
    let kind = |k: u8| {
        if p.bands.get(k as usize).is_some_and(|b| b.impostor) {
            format!("{k} (impostor)")
        } else {
            k.to_string()
        }
    };
    match p.draw {
        LodDraw::Level(k) => format!("level {} of {of}", kind(k)),
        LodDraw::Morph { fine, coarse, t } => format!(
            "level {} of {of}, morphing to {} ({:.0}%)",
            kind(fine),
            kind(coarse),
            t * 100.0
        ),
        LodDraw::Alpha { from, to, p: f } | LodDraw::Dither { from, to, p: f } => format!(
            "level {} of {of}, fading to {} ({:.0}%)",
            kind(from),
            kind(to),
            f * 100.0
        ),
        LodDraw::Dissolve { level, p: f, .. } => {
            format!(
                "level {} of {of}, dissolving ({:.0}%)",
                kind(level),
                f * 100.0
            )
        }
    }
}

/// Where a screen height falls on the strip, 0 (left, large) to 1 (right, small): log scale.
fn strip_x(px: f32) -> f32 {
    let px = px.clamp(STRIP_BOTTOM_PX, STRIP_TOP_PX);
    (STRIP_TOP_PX / px).ln() / (STRIP_TOP_PX / STRIP_BOTTOM_PX).ln()
}

/// The bands of the levels, left (large on screen, level 0) to right, with a marker at the
/// selection's height now.
fn strip(ui: &mut egui::Ui, p: &Inspected) {
    let (rect, response) =
        ui.allocate_exact_size(egui::vec2(ui.available_width(), 40.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let x_of = |px: f32| rect.left() + strip_x(px) * rect.width();
    for (k, band) in p.bands.iter().enumerate() {
        let left = x_of(band.from_px);
        let right = p.bands.get(k + 1).map_or(rect.right(), |b| x_of(b.from_px));
        if right - left < 0.5 {
            continue;
        }
        let r = egui::Rect::from_min_max(
            egui::pos2(left, rect.top() + 2.0),
            egui::pos2(right, rect.bottom() - 12.0),
        );
        painter.rect_filled(r, 1.0, level_color(k));
        if right - left > 14.0 {
            painter.text(
                r.center(),
                egui::Align2::CENTER_CENTER,
                format!("{k}"),
                egui::FontId::proportional(11.0),
                egui::Color32::BLACK,
            );
        }
    }
    for px in [1024.0, 256.0, 64.0, 16.0] {
        painter.text(
            egui::pos2(x_of(px), rect.bottom()),
            egui::Align2::CENTER_BOTTOM,
            format!("{px:.0}"),
            egui::FontId::proportional(9.0),
            egui::Color32::from_gray(150),
        );
    }
    let now = x_of(p.height_px);
    painter.line_segment(
        [
            egui::pos2(now, rect.top()),
            egui::pos2(now, rect.bottom() - 10.0),
        ],
        egui::Stroke::new(2.0, egui::Color32::WHITE),
    );
    response.on_hover_text(band_table(&p.bands));
}

/// Each level's screen heights and triangles, for the strip's tooltip.
fn band_table(bands: &[Band]) -> String {
    let mut lines =
        vec!["Levels by the model's height on screen (pixels), at this tolerance:".to_string()];
    for (k, b) in bands.iter().enumerate() {
        let below = bands.get(k + 1).map_or(0.0, |n| n.from_px);
        let from = if b.from_px.is_finite() {
            format!("{:.0}", b.from_px)
        } else {
            "∞".into()
        };
        let what = match (b.impostor, b.triangles) {
            (true, _) => "impostor, 2 triangles".to_string(),
            (false, Some(t)) => format!("{} triangles", thousands(t)),
            (false, None) => "–".to_string(),
        };
        lines.push(format!("level {k}: {from} to {below:.0} px, {what}"));
    }
    lines.join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strip_is_logarithmic_and_clamped() {
        assert_eq!(strip_x(STRIP_TOP_PX), 0.0);
        assert_eq!(strip_x(1e9), 0.0);
        assert!((strip_x(STRIP_BOTTOM_PX) - 1.0).abs() < 1e-6);
        // Halving the height moves as far at any size.
        let step = strip_x(512.0) - strip_x(1024.0);
        assert!((strip_x(32.0) - strip_x(64.0) - step).abs() < 1e-6);
    }
}
