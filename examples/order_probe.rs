//! How much a method's error curve depends on the order a file lists its vertices and
//! triangles in (issue: comparisons with error bars). For each model named and each method:
//! the levels of the model [`relisted`](lodlab::model::Model::relisted) in three random orders
//! against the original's at the same influence count, each measured by its own probe (the
//! bake's): the median ratio over the curve and over its coarsest tenth, the widest of the
//! three, and how far each simplifies (its coarsest influence count). Then, for comparison,
//! the spread the tie orders give (`report`'s band): the same, order k against order 0.
//!
//! `cargo run --release --example order_probe -- walker horse patchwork`

use lodlab::app::commands::report::compare::interpolate;
use lodlab::app::commands::report::data::SAMPLES;
use lodlab::app::commands::report::measure_sequence;
use lodlab::bake::character::lod::{SharedBake, full_detail};
use lodlab::bake::character::lod_error::Probe;
use lodlab::bake::character::simplify::Method;
use lodlab::model::Model;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[v.len() / 2]
}

/// `(influences, rms)` of `model`'s curve by `method` in tie order `order`.
fn curve(model: &Model, method: Method, order: u32) -> Vec<(f64, f64)> {
    let base = full_detail(model);
    let seq = SharedBake::default().sequence(model, &base, method, order, &|_| {});
    let probe = Probe::for_model(model, &base, SAMPLES);
    measure_sequence(&probe, &base, &seq)
        .iter()
        .map(|p| (p.influences as f64, p.rms_error))
        .collect()
}

/// Median of `other / reference` over the curve and over its coarsest tenth, at `reference`'s
/// points that `other` covers.
fn spread(reference: &[(f64, f64)], other: &[(f64, f64)]) -> (f64, f64) {
    let ratios: Vec<f64> = reference
        .iter()
        .filter(|p| p.1 > 1e-9)
        .filter_map(|&(x, y)| Some(interpolate(other, x)? / y))
        .collect();
    let coarse = ratios[ratios.len() * 9 / 10..].to_vec();
    (median(ratios), median(coarse))
}

/// The widest of several (median, coarse) ratios: the one furthest from 1 on each.
fn widest(all: &[(f64, f64)]) -> (f64, f64) {
    let far = |f: fn(&(f64, f64)) -> f64| {
        all.iter()
            .map(f)
            .max_by(|a, b| (a.ln().abs()).total_cmp(&b.ln().abs()))
            .unwrap_or(f64::NAN)
    };
    (far(|r| r.0), far(|r| r.1))
}

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    println!(
        "| model | method | relisted / original: median, coarsest 10% (widest of 3) | coarsest influences, original / relisted | tie order k / order 0: median, coarsest 10% (widest of 4) |"
    );
    println!("|---|---|---|---|---|");
    for name in &names {
        let model = lodlab::import::load_model(name).unwrap();
        for method in Method::PAPERS {
            let original = curve(&model, method, 0);
            let relisted: Vec<Vec<(f64, f64)>> = (1..=3)
                .map(|s| curve(&model.relisted(s), method, 0))
                .collect();
            let by_file = widest(
                &relisted
                    .iter()
                    .map(|c| spread(&original, c))
                    .collect::<Vec<_>>(),
            );
            let reach: Vec<String> = relisted
                .iter()
                .map(|c| format!("{:.0}", c.last().map_or(0.0, |p| p.0)))
                .collect();
            let by_tie = widest(
                &(1..5)
                    .map(|k| spread(&original, &curve(&model, method, k)))
                    .collect::<Vec<_>>(),
            );
            println!(
                "| {name} | {method} | {:.3}, {:.3} | {:.0} / {} | {:.3}, {:.3} |",
                by_file.0,
                by_file.1,
                original.last().map_or(0.0, |p| p.0),
                reach.join(", "),
                by_tie.0,
                by_tie.1
            );
        }
    }
}
