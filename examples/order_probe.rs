//! How much a rest-pose error curve depends on the order a file lists its vertices and
//! triangles (issue: comparisons with error bars). For each model named:
//! - the same levels measured with every triangle's corners rotated, and with the triangle list
//!   reversed: the measurement's own dependence on order (1.000 where it has none);
//! - the levels of the reordered twin (`report`'s [`reordered`]: vertices reversed, corners
//!   rotated) against the original's at the same influence count, each measured by its own
//!   probe: the bake's; and how far each simplifies (its coarsest influence count).
//!
//! `cargo run --release --example order_probe -- walker horse patchwork`

use lodlab::app::commands::report::{measure_sequence, reordered};
use lodlab::bake::character::lod::{Replay, progressive_mesh};
use lodlab::bake::character::lod_error::Probe;
use lodlab::bake::character::simplify::Method;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return f64::NAN;
    }
    v[v.len() / 2]
}

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    for name in &names {
        let model = lodlab::import::load_model(name).unwrap();
        let (base, seq, _) = progressive_mesh(&model, Method::RestPose, &|_| {});
        let probe = Probe::for_model(&model, &base, 6000);
        let curve = measure_sequence(&probe, &base, &seq);
        // The same levels, measured with their triangles' corners rotated, and listed backwards.
        let mut replay = Replay::new(&base, &seq);
        let (mut rot, mut rev) = (Vec::new(), Vec::new());
        let n = seq.steps.len();
        for k in 1..=20 {
            let p = n * k / 21;
            replay.advance_to(&seq, p);
            let tris: Vec<[u32; 3]> = replay.triangles().collect();
            let a = probe.measure(&tris, |r| replay.influences_of(r)).rms;
            let r: Vec<[u32; 3]> = tris.iter().map(|t| [t[1], t[2], t[0]]).collect();
            let b = probe.measure(&r, |r| replay.influences_of(r)).rms;
            let mut v = tris.clone();
            v.reverse();
            let c = probe.measure(&v, |r| replay.influences_of(r)).rms;
            if a > 0.0 {
                rot.push(b / a);
                rev.push(c / a);
            }
        }
        let twin = reordered(&model);
        let (tbase, tseq, _) = progressive_mesh(&twin, Method::RestPose, &|_| {});
        let tprobe = Probe::for_model(&twin, &tbase, 6000);
        let tcurve = measure_sequence(&tprobe, &tbase, &tseq);
        // The twin's levels measured with its own probe, against the original's at the same
        // influence count (log-log interpolation of the twin's curve), where both reach.
        let at = |x: f64| -> Option<f64> {
            let pts: Vec<(f64, f64)> = tcurve
                .iter()
                .filter(|p| p.rms_error > 0.0)
                .map(|p| ((p.influences as f64).ln(), p.rms_error.ln()))
                .collect();
            let x = x.ln();
            pts.windows(2).find_map(|w| {
                let ((x0, y0), (x1, y1)) = (w[0], w[1]);
                let (lo, hi) = (x0.min(x1), x0.max(x1));
                (lo <= x && x <= hi && hi > lo)
                    .then(|| (y0 + (y1 - y0) * (x - x0) / (x1 - x0)).exp())
            })
        };
        let ratios: Vec<f64> = curve
            .iter()
            .filter(|a| a.rms_error > 0.0)
            .filter_map(|a| at(a.influences as f64).map(|b| b / a.rms_error))
            .collect();
        let reach = (
            curve.last().map_or(0, |p| p.influences),
            tcurve.last().map_or(0, |p| p.influences),
        );
        let coarse: Vec<f64> = ratios[ratios.len() * 9 / 10..].to_vec();
        println!(
            "{name}: same levels, corners rotated: median {:.3} (min {:.3} max {:.3}); triangles reversed: median {:.3} (max {:.3}); twin/original: median {:.3}, coarsest 10% {:.3}, share twin worse {:.0}%; coarsest influences {} / {}",
            median(rot.clone()),
            rot.iter().cloned().fold(f64::MAX, f64::min),
            rot.iter().cloned().fold(0.0, f64::max),
            median(rev.clone()),
            rev.iter().cloned().fold(0.0, f64::max),
            median(ratios.clone()),
            median(coarse),
            100.0 * ratios.iter().filter(|&&r| r > 1.0).count() as f64 / ratios.len() as f64,
            reach.0,
            reach.1
        );
    }
}
