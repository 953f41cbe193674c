//! The report's chart: each method's error against triangles, on log axes.

use crate::app::commands::report::compare::{interpolate, points};
use crate::app::commands::report::data::{NEGLIGIBLE, Report};
use crate::app::plotting::{log_label, plot_error, register_font, write_plot};
use anyhow::Result;
use plotters::prelude::*;
use std::path::Path;

/// A named, coloured curve: its median's (x, y) points and its band's (x, low, high).
pub(crate) struct Series {
    name: &'static str,
    colour: RGBColor,
    median: Vec<(f64, f64)>,
    band: Vec<(f64, f64, f64)>,
}

/// Figure 7 redrawn: each method's RMS error divided by rest-pose's median at the same
/// influence count, against total influences, both on log scales; each curve the median over
/// the tie orders, shaded from the lowest to the highest.
pub fn plot(report: &Report, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (1000u32, 640u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let rest = points(&report.methods["rest-pose"]);
    // Both axes are drawn as log10 of the value on a linear axis, labelled with the value:
    // plotters' own log axes leave a narrow range (a few hundred influences) unlabelled.
    let series: Vec<Series> = [
        ("rest-pose", RGBColor(40, 40, 40)),
        ("as", RGBColor(30, 100, 220)),
        ("as+is", RGBColor(220, 50, 40)),
        ("meshopt", RGBColor(40, 160, 70)),
    ]
    .into_iter()
    .filter_map(|(name, colour)| Some((name, colour, &report.methods.get(name)?.curve)))
    .map(|(name, colour, curve)| {
        let relative: Vec<(f64, [f64; 3])> = curve
            .iter()
            .filter(|p| p.rms_low > NEGLIGIBLE)
            .filter_map(|p| {
                let r = interpolate(&rest, p.influences as f64)?;
                let y = [p.rms_low, p.rms_error, p.rms_high].map(|e| (e / r).log10());
                Some(((p.influences as f64).log10(), y))
            })
            .collect();
        Series {
            name,
            colour,
            median: relative.iter().map(|&(x, y)| (x, y[1])).collect(),
            band: relative.iter().map(|&(x, y)| (x, y[0], y[2])).collect(),
        }
    })
    .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in series.iter().flat_map(|s| s.median.iter()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 >= x1 {
        (x0, x1) = (0.0, 1.0);
    }
    let pad = 0.03 * (x1 - x0);
    let (x0, x1) = (x0 - pad, x1 + pad);
    let (y0, y1) = ((y0.min(-0.3) - 0.1).max(-4.0), (y1.max(0.3) + 0.1).min(4.0));
    // Headroom above every curve for the legend in the upper left (a quarter of the plot's
    // height holds its lines): it hid curves' highest points.
    let y1 = y1 + 0.35 * (y1 - y0);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}: RMS error relative to rest-pose simplification ({} tie orders)",
                    report.model, report.orders
                ),
                ("sans-serif", 26),
            )
            .margin(20)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("total influences (log scale)")
            .x_labels(10)
            .x_label_formatter(&|x| format!("{:.0}", 10f64.powf(*x)))
            .y_desc("RMS error / rest-pose RMS error (log scale)")
            .y_labels(12)
            .y_label_formatter(&|y| log_label(10f64.powf(*y)))
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 19))
            .draw()
            .map_err(plot_error)?;
        // The bands first, under every median line.
        for s in &series {
            let outline: Vec<(f64, f64)> = s
                .band
                .iter()
                .map(|&(x, lo, _)| (x, lo))
                .chain(s.band.iter().rev().map(|&(x, _, hi)| (x, hi)))
                .collect();
            chart
                .draw_series(std::iter::once(Polygon::new(
                    outline,
                    s.colour.mix(0.18).filled(),
                )))
                .map_err(plot_error)?;
        }
        for s in &series {
            let colour = s.colour;
            let style = ShapeStyle::from(colour).stroke_width(2);
            chart
                .draw_series(LineSeries::new(s.median.iter().copied(), style))
                .map_err(plot_error)?
                .label(s.name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
            chart
                .draw_series(
                    s.median
                        .iter()
                        .map(|&p| Circle::new(p, 3, ShapeStyle::from(colour).filled())),
                )
                .map_err(plot_error)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 18))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}
