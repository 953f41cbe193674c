//! Methods compared along their curves: errors at equal influence counts where their bands
//! separate ([`super::bands`]), lighting at equal influences.

pub use crate::app::commands::report::bands::interpolate;
use crate::app::commands::report::bands::{between, separation};
use crate::app::commands::report::data::{Comparison, MethodReport, NEGLIGIBLE, Separation};
use std::collections::BTreeMap;

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

/// Every pair of methods the report compares, `(a, b)`: AS against rest-pose, AS+IS against
/// AS, meshopt against rest-pose.
pub(crate) const PAIRS: [(&str, &str); 3] = [
    ("as", "rest-pose"),
    ("as+is", "as"),
    ("meshopt", "rest-pose"),
];

pub(crate) fn compare(methods: &BTreeMap<String, MethodReport>) -> Comparison {
    let get = |n: &str| methods.get(n);
    let separations: BTreeMap<String, Separation> = PAIRS
        .iter()
        .filter_map(|&(a, b)| {
            let s = separation(a, get(a)?, b, get(b)?)?;
            Some((format!("{a} vs {b}"), s))
        })
        .collect();
    let share = |a: &str, b: &str| {
        separations
            .get(&format!("{a} vs {b}"))
            .and_then(Separation::better_where_separate)
    };
    let as_rest = get("as").zip(get("rest-pose"));
    Comparison {
        as_le_rest_pose: share("as", "rest-pose"),
        as_is_le_as: share("as+is", "as"),
        meshopt_le_rest_pose: share("meshopt", "rest-pose"),
        as_le_rest_pose_at_levels: as_rest.and_then(|(a, r)| {
            separation("as", &down_to_levels(a, r), "rest-pose", r)?.better_where_separate()
        }),
        separations,
        as_over_rest_pose: as_rest.and_then(|(a, r)| median(ratios(a, r))),
        as_is_lighting_over_as: get("as+is")
            .zip(get("as"))
            .and_then(|(i, a)| lighting_over(i, a)),
        min_influences: methods
            .iter()
            .map(|(k, v)| {
                let min = v.curve.iter().map(|p| p.influences).min().unwrap_or(0);
                (k.clone(), min)
            })
            .collect(),
    }
}
