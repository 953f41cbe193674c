//! The tree report's pictures: error against billboards, leaf motion traced, and a contact
//! sheet of the levels.

use crate::app::commands::tree_report::data::{LevelReport, TreeReport};
use crate::app::plotting::{plot_error, register_font, write_plot};
use crate::bake::foliage::billboard::chain::TreeLevel;
use crate::render::Gpu;
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use std::path::Path;

/// A few leaves' sway over one loop (their x and z about their mean), against where their
/// billboards take them: a spectral level, and the skeleton-only level at the same ε.
pub(crate) type Shown<'a> = (usize, &'a TreeLevel);

pub(crate) fn motion_plot(
    report: &TreeReport,
    pair: Option<(Shown<'_>, Option<Shown<'_>>)>,
    path: &Path,
) -> Result<()> {
    register_font();
    let (w, h) = (1200u32, 900u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let Some(((sk, spectral), skeleton)) = pair else {
            root.titled(
                &format!("{}: no spectral level in the chain", report.model),
                ("sans-serif", 24),
            )
            .map_err(plot_error)?;
            root.present().map_err(plot_error)?;
            drop(root);
            return write_plot(path, w, h, buf);
        };
        let root = root
            .titled(
                &format!(
                    "{}: leaves' sway over one loop (x and z about the leaf's mean, m)",
                    report.model
                ),
                ("sans-serif", 22),
            )
            .map_err(plot_error)?;
        let traces = &spectral.cloud.animation.traces;
        let rows = traces.len().max(1);
        let cells = root.split_evenly((rows, 2));
        let black = RGBColor(20, 20, 20);
        let blue = RGBColor(30, 100, 220);
        let orange = RGBColor(230, 120, 20);
        for (i, trace) in traces.iter().enumerate() {
            let other = skeleton.and_then(|(_, l)| {
                l.cloud
                    .animation
                    .traces
                    .iter()
                    .find(|t| t.leaf == trace.leaf)
            });
            for (axis, name) in [(0usize, "x"), (2, "z")] {
                let mean = trace.original.iter().map(|p| p[axis]).sum::<f32>()
                    / trace.original.len().max(1) as f32;
                let curve = |t: &[glam::Vec3]| -> Vec<(f64, f64)> {
                    let n = t.len().max(1) as f64;
                    t.iter()
                        .enumerate()
                        .map(|(s, p)| (s as f64 / n, (p[axis] - mean) as f64))
                        .collect()
                };
                let mut curves = vec![(curve(&trace.original), black, "leaf".to_string())];
                curves.push((
                    curve(&trace.billboard),
                    blue,
                    format!("spectral L{sk} ({} billboards)", spectral.cloud.billboards),
                ));
                if let (Some(t), Some((k, l))) = (other, skeleton) {
                    curves.push((
                        curve(&t.billboard),
                        orange,
                        format!("skeleton L{k} ({} billboards)", l.cloud.billboards),
                    ));
                }
                let span = curves
                    .iter()
                    .flat_map(|(c, _, _)| c.iter().map(|p| p.1.abs()))
                    .fold(0.01f64, f64::max)
                    * 1.15;
                let mut chart = ChartBuilder::on(&cells[2 * i + axis / 2])
                    .caption(
                        format!("leaf {} along {name}", trace.leaf),
                        ("sans-serif", 17),
                    )
                    .margin(12)
                    .x_label_area_size(32)
                    .y_label_area_size(60)
                    .build_cartesian_2d(0.0..1.0, -span..span)
                    .map_err(plot_error)?;
                chart
                    .configure_mesh()
                    .x_desc("loop time")
                    .label_style(("sans-serif", 13))
                    .draw()
                    .map_err(plot_error)?;
                // Widest first: where a billboard follows its leaf exactly the curves coincide,
                // and each still shows as a band round the one drawn over it.
                let widths = [2u32, 4, 6];
                for (k, (points, colour, label)) in curves.into_iter().enumerate().rev() {
                    let width = widths[k.min(2)];
                    chart
                        .draw_series(LineSeries::new(points, colour.stroke_width(width)))
                        .map_err(plot_error)?
                        .label(label)
                        .legend(move |(x, y)| {
                            PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(width))
                        });
                }
                if i == 0 && axis == 0 {
                    chart
                        .configure_series_labels()
                        .position(SeriesLabelPosition::UpperRight)
                        .border_style(BLACK)
                        .background_style(WHITE.mix(0.9))
                        .label_font(("sans-serif", 13))
                        .draw()
                        .map_err(plot_error)?;
                }
            }
        }
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// Colour error (top) and billboard count (bottom, log scale) against ε.
pub(crate) fn plot(report: &TreeReport, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (1000u32, 800u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let pts: Vec<&LevelReport> = report.levels.iter().skip(1).collect();
    let x1 = pts.iter().map(|l| l.epsilon).fold(0.01f32, f32::max) as f64 * 1.08;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (top, bottom) = root.split_vertically(h / 2);
        error_chart(&top, report, &pts, x1)?;
        count_chart(&bottom, report, &pts, x1)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// One half of [`plot`]'s picture, drawn on a shared bitmap.
type Half<'b> = DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>;

/// The colour of the chain's series, whose markers are circles, in [`plot`]'s top chart.
const CHAIN_ERROR: RGBColor = RGBColor(30, 100, 220);
/// The colour of one static cloud at rest (the thesis's set-up), in both of [`plot`]'s charts.
const STILL: RGBColor = RGBColor(40, 160, 70);
/// The colour of the skeleton-only clouds, in both of [`plot`]'s charts.
const SKELETON: RGBColor = RGBColor(230, 120, 20);
/// The colour of the chain's series in [`plot`]'s bottom chart.
const CHAIN_COUNT: RGBColor = RGBColor(220, 50, 40);

/// [`plot`]'s top chart: its layout (caption, axes up to `x1` and the largest colour error,
/// mesh), then the chain's, the static cloud's and the skeleton clouds' colour error against
/// ε, in that order, and the legend over them.
fn error_chart(top: &Half<'_>, report: &TreeReport, pts: &[&LevelReport], x1: f64) -> Result<()> {
    let mut chart = ChartBuilder::on(top)
        .caption(
            format!("{}: colour error of its billboard clouds", report.model),
            ("sans-serif", 24),
        )
        .margin(18)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            0.0..x1,
            0.0..(pts
                .iter()
                .map(|l| l.colour_error)
                .chain(report.static_clouds.iter().map(|l| l.colour_error))
                .fold(0.05f32, f32::max) as f64
                * 1.15),
        )
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("ε (fraction of tree height)")
        .y_desc("colour error")
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(plot_error)?;
    let chain_errors: Vec<(f64, f64)> = pts
        .iter()
        .map(|l| (l.epsilon as f64, l.colour_error as f64))
        .collect();
    let chain_label = "the chain (skeleton clouds, spectral, then clumps), animated";
    series(
        &mut chart,
        &chain_errors,
        CHAIN_ERROR,
        Marker::Circle,
        Some(chain_label),
    )?;
    let still_errors: Vec<(f64, f64)> = report
        .static_clouds
        .iter()
        .map(|l| (l.epsilon as f64, l.colour_error as f64))
        .collect();
    let still_label = "one static cloud, at rest (thesis §8.4)";
    series(
        &mut chart,
        &still_errors,
        STILL,
        Marker::Triangle,
        Some(still_label),
    )?;
    let skeleton_errors: Vec<(f64, f64)> = report
        .skeleton_levels
        .iter()
        .map(|l| (l.epsilon as f64, l.colour_error as f64))
        .collect();
    series(
        &mut chart,
        &skeleton_errors,
        SKELETON,
        Marker::Triangle,
        Some("skeleton clouds only (branch subtrees), animated"),
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(plot_error)?;
    Ok(())
}

/// [`plot`]'s bottom chart: its layout (caption, axes up to `x1` and a log scale of the
/// largest billboard count, mesh), then the chain's billboards drawn from a view, the static
/// cloud's and the skeleton clouds' billboards against ε, in that order, without a legend
/// (the top chart's serves both).
fn count_chart(
    bottom: &Half<'_>,
    report: &TreeReport,
    pts: &[&LevelReport],
    x1: f64,
) -> Result<()> {
    let max_count = pts.iter().map(|l| l.billboards).max().unwrap_or(10).max(10) as f64;
    let mut chart = ChartBuilder::on(bottom)
        .caption("billboards drawn from a view", ("sans-serif", 22))
        .margin(18)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x1, 0.0..(max_count * 1.5).log10())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("ε (fraction of tree height)")
        .y_desc("billboards (log scale)")
        .y_label_formatter(&|y| format!("{:.0}", 10f64.powf(*y)))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(plot_error)?;
    let log_count = |n: usize| (n.max(1) as f64).log10();
    let chain_counts: Vec<(f64, f64)> = pts
        .iter()
        .map(|l| (l.epsilon as f64, log_count(l.drawn_billboards)))
        .collect();
    series(&mut chart, &chain_counts, CHAIN_COUNT, Marker::Circle, None)?;
    let still_counts: Vec<(f64, f64)> = report
        .static_clouds
        .iter()
        .map(|l| (l.epsilon as f64, log_count(l.billboards)))
        .collect();
    series(&mut chart, &still_counts, STILL, Marker::Triangle, None)?;
    let skeleton_counts: Vec<(f64, f64)> = report
        .skeleton_levels
        .iter()
        .map(|l| (l.epsilon as f64, log_count(l.billboards)))
        .collect();
    series(
        &mut chart,
        &skeleton_counts,
        SKELETON,
        Marker::Triangle,
        None,
    )?;
    Ok(())
}

/// How a series marks its points: the chain with circles, the thesis's set-up with triangles.
#[derive(Clone, Copy)]
pub(crate) enum Marker {
    Circle,
    Triangle,
}

pub(crate) type Chart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// One series: a line through `points` (thicker for circles) and a marker on each, with a
/// legend entry when it has a label.
pub(crate) fn series(
    chart: &mut Chart<'_, '_>,
    points: &[(f64, f64)],
    colour: RGBColor,
    marker: Marker,
    label: Option<&str>,
) -> Result<()> {
    let width = match marker {
        Marker::Circle => 2,
        Marker::Triangle => 1,
    };
    chart
        .draw_series(LineSeries::new(
            points.iter().copied(),
            colour.stroke_width(width),
        ))
        .map_err(plot_error)?;
    let style = colour.filled();
    match marker {
        Marker::Circle => {
            let drawn = chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, style)))
                .map_err(plot_error)?;
            if let Some(label) = label {
                drawn
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, style));
            }
        }
        Marker::Triangle => {
            let drawn = chart
                .draw_series(points.iter().map(|&p| TriangleMarker::new(p, 5, style)))
                .map_err(plot_error)?;
            if let Some(label) = label {
                drawn
                    .label(label)
                    .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 5, style));
            }
        }
    }
    Ok(())
}

/// Every level from the same view, side by side, labelled.
pub(crate) fn contact_sheet(
    gpu: &Gpu,
    chain: &[TreeLevel],
    report: &TreeReport,
    path: &Path,
) -> Result<()> {
    use crate::render::targets::{OFFSCREEN_FORMAT, Offscreen};
    use crate::runtime::spec::Loaded;
    use crate::runtime::world::World;
    let (tw, th) = (300u32, 400u32);
    let columns = chain.len().min(6) as u32;
    let rows = (chain.len() as u32).div_ceil(columns);
    let mut sheet =
        image::RgbImage::from_pixel(tw * columns, th * rows, image::Rgb([255, 255, 255]));
    let target = Offscreen::new(gpu, tw, th, 4);
    for (k, l) in chain.iter().enumerate() {
        let bake = l
            .cloud
            .bake()
            .map_err(|e| anyhow!("{}: {e}", l.cloud.model.name))?;
        let loaded = Loaded::forest_of_bake(&l.cloud.model, bake, 1);
        let mut world = World::new(gpu, loaded, OFFSCREEN_FORMAT, 4)?;
        // The billboards as their atlases light them, whatever the adapter's default.
        world.renderer.atlas_lighting = true;
        let height = world.bakes[0].bounds.size().y;
        world.camera = crate::scene::Camera::new(
            glam::Vec3::new(0.0, height * 0.5, 0.0),
            30.0,
            6.0,
            height * 1.45,
        );
        world.prepare(gpu, [tw, th], 1.0, 0.0);
        world
            .renderer
            .render_to(gpu, &target.targets, &target.view)?;
        let tile = image::DynamicImage::ImageRgba8(target.read_rgba(gpu)?).to_rgb8();
        let (x, y) = ((k as u32 % columns) * tw, (k as u32 / columns) * th);
        image::imageops::replace(&mut sheet, &tile, x as i64, y as i64);
    }
    // Labels.
    register_font();
    let (w, h) = sheet.dimensions();
    let mut buf = sheet.into_raw();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        for (k, l) in report.levels.iter().enumerate() {
            let (x, y) = ((k as u32 % columns) * tw, (k as u32 / columns) * th);
            let text = if k == 0 {
                format!("L0: {} leaves", report.leaves)
            } else {
                let drawn = if l.drawn_billboards < l.billboards {
                    format!("{} of {}", l.drawn_billboards, l.billboards)
                } else {
                    l.billboards.to_string()
                };
                format!(
                    "L{k}: ε {:.3} h · {drawn} billboards · {:.3}",
                    l.epsilon, l.colour_error
                )
            };
            root.draw(&Text::new(
                text,
                (x as i32 + 8, y as i32 + 8),
                ("sans-serif", 15).into_font().color(&BLACK),
            ))
            .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}
