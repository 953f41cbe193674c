//! Chart helpers the reports and the study share: labels of log axes, the font, writing a PNG.

use anyhow::{Context, Result};
use plotters::prelude::*;
use std::path::Path;

/// A value on a log axis with two significant digits: 0.0012, 0.050, 0.50, 3.2, 40. (With two
/// decimals, every label under 0.01 read "0.00".)
pub(crate) fn log_label(v: f64) -> String {
    // NaN, infinities, zero and below: no log label; written as they are.
    if !v.is_finite() || v <= 0.0 {
        return format!("{v}");
    }
    if v >= 10.0 {
        return format!("{v:.0}");
    }
    let decimals = (1 - v.log10().floor() as i32).max(1) as usize;
    format!("{v:.decimals$}")
}

/// Writes a plot drawn into an RGB buffer `w`×`h` as a PNG.
pub(crate) fn write_plot(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> Result<()> {
    let rgb = image::RgbImage::from_raw(w, h, buf).context("plot buffer size")?;
    crate::atomic::write_png(path, &image::DynamicImage::ImageRgb8(rgb).to_rgba8())
}

pub(crate) fn plot_error<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::anyhow!("cannot draw the plot: {e}")
}

/// plotters draws text with fonts registered by name; lodlab brings its own (the one egui
/// ships), so plots look the same on every machine and need no system fonts.
pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}
