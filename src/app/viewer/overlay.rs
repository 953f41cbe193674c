//! What is drawn over the 3D view rather than beside it: the split screen's divider and
//! method names, and where the panel is hidden, how to bring it back.

use crate::scene::LodMethod;

/// Where the panel is hidden, a small label in the view's corner says how to bring it back.
pub fn hidden_hint(ui: &egui::Ui, view: egui::Rect) {
    let painter = ui.ctx().layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::unique("hidden panel hint"),
    ));
    let galley = painter.layout_no_wrap(
        "F1: panel".into(),
        egui::FontId::proportional(12.0),
        egui::Color32::from_gray(230),
    );
    let rect = egui::Align2::LEFT_BOTTOM
        .anchor_size(view.left_bottom() + egui::vec2(8.0, -8.0), galley.size())
        .expand(3.0);
    painter.rect_filled(rect, 3.0, egui::Color32::from_black_alpha(140));
    painter.galley(
        rect.min + egui::vec2(3.0, 3.0),
        galley,
        egui::Color32::WHITE,
    );
}

/// The divider and the method names over the 3D view in compare mode.
pub fn compare_overlay(ui: &egui::Ui, view: egui::Rect, left: LodMethod, right: LodMethod) {
    let painter = ui.ctx().layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::unique("compare overlay"),
    ));
    // Two physical pixels wide on the pixel grid, whatever the interface's zoom: a line of
    // 1.5 pixels at a small window's zoom blurred to grey over two.
    let pixel = 1.0 / ui.ctx().pixels_per_point();
    let x = painter.round_to_pixel_center(view.center().x) + 0.5 * pixel;
    painter.vline(
        x,
        view.y_range(),
        egui::Stroke::new(2.0 * pixel, egui::Color32::from_gray(235)),
    );
    for (pos, align, name) in [
        (
            egui::pos2(x - 10.0, view.top() + 10.0),
            egui::Align2::RIGHT_TOP,
            left,
        ),
        (
            egui::pos2(x + 10.0, view.top() + 10.0),
            egui::Align2::LEFT_TOP,
            right,
        ),
    ] {
        let galley = painter.layout_no_wrap(
            name.name().to_string(),
            egui::FontId::proportional(16.0),
            egui::Color32::WHITE,
        );
        let rect = align.anchor_size(pos, galley.size()).expand(4.0);
        painter.rect_filled(rect, 3.0, egui::Color32::from_black_alpha(150));
        painter.galley(
            rect.min + egui::vec2(4.0, 4.0),
            galley,
            egui::Color32::WHITE,
        );
    }
}
