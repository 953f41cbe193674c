//! Methods compared along their curves: errors at equal triangle counts, the noise band a
//! model's own reordering gives, lighting at equal influences.

use crate::app::commands::report::data::{Comparison, MethodReport, NEGLIGIBLE};
use std::collections::BTreeMap;

/// `y` of a curve at `x`, interpolated linearly in log–log; `None` outside its range.
pub fn interpolate(curve: &[(f64, f64)], x: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = curve.iter().copied().filter(|p| p.1 > NEGLIGIBLE).collect();
    between(pts, x, |a, b, t| (a.ln() + t * (b.ln() - a.ln())).exp())
}

/// `y` at `x` from the two points of `pts` either side of it, `blend(y_a, y_b, t)` with `t`
/// where `x` lies between their `x` in log scale; the point's own `y` where `x` is one; `None`
/// outside their range.
pub(crate) fn between(
    mut pts: Vec<(f64, f64)>,
    x: f64,
    blend: impl Fn(f64, f64, f64) -> f64,
) -> Option<f64> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let i = pts.partition_point(|p| p.0 < x);
    if i < pts.len() && pts[i].0 == x {
        return Some(pts[i].1);
    }
    if i == 0 || i == pts.len() {
        return None;
    }
    let (a, b) = (pts[i - 1], pts[i]);
    let t = (x.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
    Some(blend(a.1, b.1, t))
}

pub(crate) fn points(r: &MethodReport) -> Vec<(f64, f64)> {
    r.curve
        .iter()
        .map(|p| (p.influences as f64, p.rms_error))
        .collect()
}

/// `(influences, a / b)` at each of `a`'s points with error within `b`'s range.
pub(crate) fn ratios_at(a: &MethodReport, b: &MethodReport) -> Vec<(f64, f64)> {
    let reference = points(b);
    a.curve
        .iter()
        .filter(|p| p.rms_error > NEGLIGIBLE)
        .filter_map(|p| {
            let x = p.influences as f64;
            Some((x, p.rms_error / interpolate(&reference, x)?))
        })
        .collect()
}

/// `a / b` at each of `a`'s points with error within `b`'s range.
pub(crate) fn ratios(a: &MethodReport, b: &MethodReport) -> Vec<f64> {
    ratios_at(a, b).into_iter().map(|(_, r)| r).collect()
}

/// Fraction of `a`'s points (with error, within `b`'s range) where `a ≤ b × (1 + slack)`,
/// `slack` given at the point's influence count.
pub(crate) fn fraction_below(
    a: &MethodReport,
    b: &MethodReport,
    slack: impl Fn(f64) -> f64,
) -> Option<f64> {
    let r = ratios_at(a, b);
    let below = r
        .iter()
        .filter(|&&(x, ratio)| ratio <= (1.0 + slack(x)) * (1.0 + 1e-9))
        .count();
    (!r.is_empty()).then(|| below as f64 / r.len() as f64)
}

/// Reordered points either side of a point that its local noise band looks at.
pub(crate) const BAND_NEIGHBOURS: usize = 1;

/// The noise band at `x` influences: the largest |reordered / rest-pose − 1| at the reordered
/// point nearest `x` in log(influences) and at [`BAND_NEIGHBOURS`] points either side of it,
/// and no less than the median band. The noise is not even along a curve: where steps of
/// equal cost are many (chart and material borders at the coarse end), equal methods part by
/// half and more, so one band for the whole curve would call that a method's loss.
/// `sorted`: `(influences, deviation)` in order of influences.
pub(crate) fn local_band(sorted: &[(f64, f64)], median: f64, x: f64) -> f64 {
    let distance = |d: &(f64, f64)| (d.0.ln() - x.ln()).abs();
    let Some(nearest) =
        (0..sorted.len()).min_by(|&i, &j| distance(&sorted[i]).total_cmp(&distance(&sorted[j])))
    else {
        return median;
    };
    let from = nearest.saturating_sub(BAND_NEIGHBOURS);
    let to = (nearest + BAND_NEIGHBOURS + 1).min(sorted.len());
    sorted[from..to].iter().map(|d| d.1).fold(median, f64::max)
}

/// Colour errors (0 to 1) below this are invisible: a quarter of one 8-bit step over the
/// figure. Ratios of two such errors say nothing.
pub const VISIBLE_COLOUR: f64 = 1e-3;

/// The total influences of the level a lighting row measures.
pub(crate) fn influences_of(
    m: &MethodReport,
    s: &crate::measure::shading_error::LevelShading,
) -> Option<f64> {
    Some(m.levels.get(s.level)?.influences as f64)
}

/// `m`'s colour error by vertex normals at `influences` in all, interpolated between its
/// levels (linearly in the error, in log(influences)), full detail counting as exact; `None`
/// outside the levels' range or where no lighting was measured. Influences are the paper's
/// measure of a level's cost (Merry et al. §5, Figure 7): an AS+IS level that drops
/// influences and keeps every triangle is compared with the AS level as cheap as it.
pub(crate) fn lighting_at(m: &MethodReport, influences: f64) -> Option<f64> {
    let full = m.levels.first()?.influences as f64;
    let pts: Vec<(f64, f64)> = std::iter::once((full, 0.0))
        .chain(
            m.shading
                .iter()
                .filter_map(|s| Some((influences_of(m, s)?, s.vertex_normals as f64))),
        )
        .collect();
    if pts.len() < 2 {
        return None;
    }
    between(pts, influences, |a, b, t| a + t * (b - a))
}

/// See [`Comparison::as_is_lighting_over_as`].
pub(crate) fn lighting_over(is: &MethodReport, as_: &MethodReport) -> Option<f64> {
    is.shading
        .iter()
        .filter_map(|s| {
            let own = s.vertex_normals as f64;
            let reference = lighting_at(as_, influences_of(is, s)?)?;
            (own.max(reference) >= VISIBLE_COLOUR).then(|| own / reference.max(1e-6))
        })
        .reduce(f64::max)
}

/// `a`'s curve down to the coarsest level `a` or `b` has: where the viewer shows levels. What
/// lies beyond is the extreme simplification that no level reaches (Merry et al. find AS worse
/// than rest-pose there).
pub(crate) fn down_to_levels(a: &MethodReport, b: &MethodReport) -> MethodReport {
    let floor = |m: &MethodReport| m.levels.last().map_or(0, |l| l.influences);
    let lowest = floor(a).max(floor(b));
    MethodReport {
        curve: a
            .curve
            .iter()
            .filter(|p| p.influences >= lowest)
            .cloned()
            .collect(),
        levels: Vec::new(),
        shading: Vec::new(),
        ..*a
    }
}

pub(crate) fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

pub(crate) fn compare(methods: &BTreeMap<String, MethodReport>, twin: &MethodReport) -> Comparison {
    let get = |n: &str| methods.get(n);
    let pair = |a: &str, b: &str| match (get(a), get(b)) {
        (Some(a), Some(b)) => fraction_below(a, b, |_| 0.0),
        _ => None,
    };
    let rest = get("rest-pose");
    // |reordered / rest-pose − 1| along the curve, in order of influences.
    let deviations: Vec<(f64, f64)> = rest.map_or(Vec::new(), |r| {
        let mut d: Vec<(f64, f64)> = ratios_at(twin, r)
            .into_iter()
            .map(|(x, q)| (x, (q - 1.0).abs()))
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        d
    });
    let noise = median(deviations.iter().map(|d| d.1).collect());
    let as_rest = get("as").zip(rest);
    Comparison {
        as_le_rest_pose: pair("as", "rest-pose"),
        as_is_le_as: pair("as+is", "as"),
        meshopt_le_rest_pose: pair("meshopt", "rest-pose"),
        reordered_le_rest_pose: rest.and_then(|r| fraction_below(twin, r, |_| 0.0)),
        noise,
        as_le_rest_pose_within_noise: as_rest
            .zip(noise)
            .and_then(|((a, r), n)| fraction_below(a, r, |x| local_band(&deviations, n, x))),
        as_over_rest_pose: as_rest.and_then(|(a, r)| median(ratios(a, r))),
        as_is_lighting_over_as: get("as+is")
            .zip(get("as"))
            .and_then(|(i, a)| lighting_over(i, a)),
        as_le_rest_pose_at_levels: as_rest
            .and_then(|(a, r)| fraction_below(&down_to_levels(a, r), r, |_| 0.0)),
        min_influences: methods
            .iter()
            .map(|(k, v)| {
                let min = v.curve.iter().map(|p| p.influences).min().unwrap_or(0);
                (k.clone(), min)
            })
            .collect(),
    }
}
