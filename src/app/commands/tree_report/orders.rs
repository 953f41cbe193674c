//! The report's two orders of a tree's levels: what the ε chain draws at each switch size and
//! what ordering by measured error per cost draws there instead (`orders.md`), and each
//! level's colour error against its cost at every switch size (`error-per-cost.png`), and each
//! order's chain as one curve, the error and cost of what it draws from size to size
//! (`chains-error-per-cost.png`).

use crate::app::plotting::{plot_error, register_font, write_plot};
use crate::bake::foliage::billboard::chain::order::{self, CostChoice};
use crate::bake::foliage::billboard::chain::{ChainBake, ChainOptions, CloudKind, TreeLevel};
use crate::bake::gpu_products::{MeasureColour, RasterizeAtlas};
use crate::model::Model;
use anyhow::Result;
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Every level of the chain measured at every switch size it could stand in, and the two
/// orders' choices.
#[derive(Clone, Debug, Serialize)]
pub struct OrdersReport {
    /// The candidates' names (level 0 the tree, the impostor last where it has a place).
    pub levels: Vec<String>,
    pub stretches: Vec<Stretch>,
}

/// One switch size of the ε chain: the candidates measured there, and the choices.
#[derive(Clone, Debug, Serialize)]
pub struct Stretch {
    pub choice: CostChoice,
    /// The ε chain's level there, as a candidate index.
    pub epsilon_candidate: usize,
    /// (candidate, colour error, cost) of every candidate measured at this size.
    pub measured: Vec<(usize, f32, f64)>,
}

/// Measures `chain` (built by `tree_chain` for `opts`, level 0 the tree) with its impostor
/// placed as the bake places it, and both orders' choices.
pub fn orders(
    raster: &dyn RasterizeAtlas,
    measure: &dyn MeasureColour,
    tree: &Model,
    chain: &[TreeLevel],
    opts: &ChainOptions,
) -> Result<OrdersReport> {
    let chains = ChainBake::placing_impostor(raster, measure, tree, chain.to_vec(), opts)?
        .chains(chain[0].clone());
    let height = crate::bake::foliage::billboard::tree_height(tree);
    let table = order::measure_costs(measure, tree, &chains, height, opts.tolerance_px)?;
    let choices = order::choose(
        &table.switch_px,
        &chains.reference,
        &table.errors,
        &table.costs,
    );
    let stretches = choices
        .into_iter()
        .map(|choice| {
            let k = choice.epsilon_level;
            let measured = (0..chains.candidates.len())
                .filter(|&j| table.errors[j][k].is_finite())
                .map(|j| (j, table.errors[j][k], table.costs[j][k]))
                .collect();
            Stretch {
                epsilon_candidate: chains.reference[k],
                choice,
                measured,
            }
        })
        .collect();
    Ok(OrdersReport {
        levels: chains
            .candidates
            .iter()
            .map(|l| CloudKind::name(l.kind.as_ref()))
            .collect(),
        stretches,
    })
}

/// `orders.md`: at each switch size, the ε chain's level and the cost order's, side by side.
pub fn orders_table(r: &OrdersReport) -> String {
    let mut out = String::from(
        "# The chain by ε and by error per cost\n\nAt each switch size (the tree's height in \
         pixels where the ε chain's level comes in), the level each order draws, its colour \
         error there and its cost (fragments shaded plus 9 a triangle). The cost order draws \
         the cheapest level whose error is no worse than the ε chain's.\n\n\
         | from px | ε order: level | error | cost | cost order: level | error | cost | cheaper |\n\
         |---:|---|---:|---:|---|---:|---:|---:|\n",
    );
    for s in &r.stretches {
        let c = &s.choice;
        let _ = writeln!(
            out,
            "| {:.1} | {} {} | {:.3} | {:.0} | {} {} | {:.3} | {:.0} | {:.1}× |",
            c.px,
            s.epsilon_candidate,
            r.levels[s.epsilon_candidate],
            c.epsilon_error,
            c.epsilon_cost,
            c.drawn_level,
            r.levels[c.drawn_level],
            c.drawn_error,
            c.drawn_cost,
            c.epsilon_cost / c.drawn_cost.max(1.0)
        );
    }
    out
}

/// `error-per-cost.png`: at each switch size a curve of the levels measured there, colour
/// error against cost (log), the ε chain's level ringed and the cost order's filled.
pub fn orders_plot(r: &OrdersReport, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (900u32, 600u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let points: Vec<(f64, f64)> = r
            .stretches
            .iter()
            .flat_map(|s| s.measured.iter().map(|&(_, e, c)| (c.max(1.0), e as f64)))
            .collect();
        let caption = "Colour error against cost at each switch size";
        let mut chart = cost_chart(&root, caption, &points, 1.5)?;
        for (i, s) in r.stretches.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let mut curve: Vec<(f64, f64)> = s
                .measured
                .iter()
                .map(|&(_, e, c)| (c.max(1.0), e as f64))
                .collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(curve.clone(), colour.stroke_width(2)))
                .map_err(plot_error)?
                .label(format!("from {:.0} px", s.choice.px))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            let at = |j: usize| {
                s.measured
                    .iter()
                    .find(|m| m.0 == j)
                    .map(|&(_, e, c)| (c.max(1.0), e as f64))
            };
            if let Some(p) = at(s.epsilon_candidate) {
                chart
                    .draw_series([Circle::new(p, 8, colour.stroke_width(2))])
                    .map_err(plot_error)?;
            }
            if let Some(p) = at(s.choice.drawn_level) {
                chart
                    .draw_series([Circle::new(p, 5, colour.filled())])
                    .map_err(plot_error)?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// A chart of colour error against cost (log) on `root`, with its axes drawn, holding
/// `points` with `headroom` times the largest cost as the right edge.
fn cost_chart<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    caption: &str,
    points: &[(f64, f64)],
    headroom: f64,
) -> Result<
    ChartContext<
        'a,
        BitMapBackend<'b>,
        Cartesian2d<LogCoord<f64>, plotters::coord::types::RangedCoordf64>,
    >,
> {
    let max_cost = points.iter().map(|p| p.0).fold(10.0, f64::max) * headroom;
    let min_cost = points.iter().map(|p| p.0).fold(max_cost, f64::min) / 1.5;
    let max_error = points.iter().map(|p| p.1).fold(0.1, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d((min_cost..max_cost).log_scale(), 0.0..max_error)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("cost (fragments + 9 a triangle)")
        .y_desc("colour error")
        .x_label_formatter(&|v| crate::app::plotting::log_label(*v))
        .draw()
        .map_err(plot_error)?;
    Ok(chart)
}

/// A curve of a plot: its name, colour and points.
type Curve = (&'static str, RGBColor, Vec<(f64, f64)>);

/// `chains-error-per-cost.png`: each order's chain as a curve through what it draws at each
/// switch size, colour error against cost (log), the sizes marked on the ε chain's points.
pub fn chains_plot(r: &OrdersReport, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (900u32, 600u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let by_order: [Curve; 2] = [
        ("ε order", RGBColor(200, 60, 40), {
            let c = r.stretches.iter().map(|s| &s.choice);
            c.map(|c| (c.epsilon_cost.max(1.0), c.epsilon_error as f64))
                .collect()
        }),
        ("cost order", RGBColor(30, 110, 200), {
            let c = r.stretches.iter().map(|s| &s.choice);
            c.map(|c| (c.drawn_cost.max(1.0), c.drawn_error as f64))
                .collect()
        }),
    ];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let all: Vec<(f64, f64)> = by_order.iter().flat_map(|(_, _, p)| p.clone()).collect();
        let caption = "What each order draws, from one switch size to the next";
        // Room on the right for the last size's label.
        let mut chart = cost_chart(&root, caption, &all, 3.0)?;
        for (name, colour, points) in &by_order {
            let colour = *colour;
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(plot_error)?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(plot_error)?;
        }
        // Which size each step is: the ε chain's points, labelled.
        chart
            .draw_series(r.stretches.iter().zip(&by_order[0].2).map(|(s, &p)| {
                EmptyElement::at(p)
                    + Text::new(
                        format!("from {:.0} px", s.choice.px),
                        (8, -18),
                        ("sans-serif", 13).into_font().color(&BLACK),
                    )
            }))
            .map_err(plot_error)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}
