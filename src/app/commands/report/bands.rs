//! Error bars: each method's curve over several tie orders, as a median and a band from the
//! lowest to the highest order, and where two methods' bands separate (issue: comparisons with
//! error bars).
//!
//! The simplifier breaks ties between steps of equal cost by a rank of what each position is
//! ([`Ties`](crate::bake::character::simplify::Ties)), so the order a file lists its vertices in
//! changes nothing; the tie order itself still chooses among equals, and another would be as
//! right. A method's band is what its choices among equals span: two methods differ where their
//! bands do not overlap, and only there.

use crate::app::commands::report::data::{
    CurvePoint, MethodReport, NEGLIGIBLE, Separation, Span, Verdict,
};
use crate::app::viewer::figures::thousands;

/// One curve per tie order, each measured at the same target influence counts (`None` where
/// that order's sequence stops short of a target), made into one: at every target some order
/// reaches, the median error and the lowest and highest.
pub fn banded(per_order: &[Vec<Option<CurvePoint>>]) -> Vec<CurvePoint> {
    let targets = per_order.iter().map(Vec::len).max().unwrap_or(0);
    let mut curve: Vec<CurvePoint> = (0..targets)
        .filter_map(|j| {
            let at: Vec<&CurvePoint> = per_order
                .iter()
                .filter_map(|c| c.get(j)?.as_ref())
                .collect();
            let first = at.first()?;
            let rms: Vec<f64> = at.iter().map(|p| p.rms_error).collect();
            Some(CurvePoint {
                // Order 0's, where it reaches: the levels the viewer draws.
                influences: first.influences,
                triangles: median_u32(at.iter().map(|p| p.triangles).collect()),
                rms_error: median(rms.clone()),
                rms_low: rms.iter().copied().fold(f64::MAX, f64::min),
                rms_high: rms.iter().copied().fold(0.0, f64::max),
                max_error: median(at.iter().map(|p| p.max_error).collect()),
                orders: at.len() as u32,
            })
        })
        .collect();
    // Where one step passed several targets in every order, their points are one.
    curve.dedup_by(|b, a| {
        (a.influences, a.rms_error, a.rms_low, a.rms_high)
            == (b.influences, b.rms_error, b.rms_low, b.rms_high)
    });
    curve
}

/// The median of `v` (the mean of the middle two of an even count); 0 for none.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn median_u32(v: Vec<u32>) -> u32 {
    median(v.into_iter().map(f64::from).collect()).round() as u32
}

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

/// A curve's band width: the median over its points with error of (highest − lowest) /
/// median. 0 where one order was baked.
pub fn band_width(curve: &[CurvePoint]) -> Option<f64> {
    let widths: Vec<f64> = curve
        .iter()
        .filter(|p| p.rms_error > NEGLIGIBLE)
        .map(|p| (p.rms_high - p.rms_low) / p.rms_error)
        .collect();
    (!widths.is_empty()).then(|| median(widths))
}

/// Where `a`'s band lies under, over or across `b`'s, at each of `a`'s points with error that
/// `b`'s curve covers (its band interpolated in log–log); `None` where none is.
pub fn separation(
    a_name: &str,
    a: &MethodReport,
    b_name: &str,
    b: &MethodReport,
) -> Option<Separation> {
    let side = |f: fn(&CurvePoint) -> f64| -> Vec<(f64, f64)> {
        b.curve
            .iter()
            .map(|p| (p.influences as f64, f(p)))
            .collect()
    };
    let (low, high) = (side(|p| p.rms_low), side(|p| p.rms_high));
    let verdicts: Vec<(u32, Verdict)> = a
        .curve
        .iter()
        .filter(|p| p.rms_high > NEGLIGIBLE)
        .filter_map(|p| {
            let x = p.influences as f64;
            let (b_low, b_high) = (interpolate(&low, x)?, interpolate(&high, x)?);
            let v = if p.rms_high < b_low {
                Verdict::Better
            } else if p.rms_low > b_high {
                Verdict::Worse
            } else {
                Verdict::Indistinguishable
            };
            Some((p.influences, v))
        })
        .collect();
    if verdicts.is_empty() {
        return None;
    }
    let mut spans: Vec<Span> = Vec::new();
    for &(x, v) in &verdicts {
        match spans.last_mut() {
            Some(s) if s.verdict == v => s.to = x,
            _ => spans.push(Span {
                verdict: v,
                from: x,
                to: x,
            }),
        }
    }
    let share =
        |v: Verdict| verdicts.iter().filter(|p| p.1 == v).count() as f64 / verdicts.len() as f64;
    let says = spans
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let what = if k == 0 {
                format!("{a_name} {} than {b_name}", s.verdict.word())
                    .replace("indistinguishable than", "indistinguishable from")
            } else {
                s.verdict.word().to_string()
            };
            let range = if s.from == s.to {
                format!("at {} influences", thousands(u64::from(s.from)))
            } else {
                format!(
                    "from {} to {}{}",
                    thousands(u64::from(s.from)),
                    thousands(u64::from(s.to)),
                    if k == 0 { " influences" } else { "" }
                )
            };
            format!("{what} {range}")
        })
        .collect::<Vec<_>>()
        .join(", ");
    Some(Separation {
        better: share(Verdict::Better),
        indistinguishable: share(Verdict::Indistinguishable),
        worse: share(Verdict::Worse),
        spans,
        says,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(influences: u32, low: f64, mid: f64, high: f64) -> CurvePoint {
        CurvePoint {
            influences,
            triangles: influences,
            rms_error: mid,
            rms_low: low,
            rms_high: high,
            max_error: high,
            orders: 3,
        }
    }

    fn method(curve: Vec<CurvePoint>) -> MethodReport {
        MethodReport {
            bake_seconds: 0.0,
            orders_seconds: 0.0,
            cache_hit_rate: None,
            band: band_width(&curve),
            curve,
            levels: Vec::new(),
            shading: Vec::new(),
        }
    }

    #[test]
    fn orders_make_a_median_and_a_band_where_they_reach() {
        let p = |x: u32, e: f64| Some(point(x, e, e, e));
        let per_order = vec![
            vec![p(1000, 0.0), p(500, 1.0), p(100, 4.0)],
            vec![p(1000, 0.0), p(500, 3.0), None],
            vec![p(1000, 0.0), p(500, 2.0), p(100, 6.0)],
        ];
        let curve = banded(&per_order);
        assert_eq!(curve.len(), 3);
        assert_eq!(
            (curve[1].rms_low, curve[1].rms_error, curve[1].rms_high),
            (1.0, 2.0, 3.0)
        );
        assert_eq!(curve[1].orders, 3);
        // Two orders reach the last point: the median is their mean.
        assert_eq!(
            (curve[2].rms_low, curve[2].rms_error, curve[2].rms_high),
            (4.0, 5.0, 6.0)
        );
        assert_eq!(curve[2].orders, 2);
        // Widths 2/2 and 2/5: their median is their mean.
        assert_eq!(band_width(&curve), Some(0.7));
    }

    #[test]
    fn bands_separate_where_they_do_not_overlap_and_say_where() {
        // a is under b's band at the fine end, across it in the middle, over it at the end.
        let a = method(vec![
            point(8000, 0.0, 0.0, 0.0),
            point(4000, 0.1, 0.15, 0.2),
            point(2000, 0.2, 0.25, 0.3),
            point(1000, 0.9, 1.0, 1.1),
            point(500, 1.5, 2.0, 2.5),
            point(250, 5.0, 6.0, 7.0),
        ]);
        let b = method(vec![
            point(8000, 0.0, 0.0, 0.0),
            point(4000, 0.5, 0.6, 0.7),
            point(2000, 0.5, 0.6, 0.7),
            point(1000, 1.0, 1.1, 1.2),
            point(500, 2.0, 2.2, 2.4),
            point(250, 3.0, 3.5, 4.0),
        ]);
        let s = separation("as", &a, "rest-pose", &b).unwrap();
        let verdicts: Vec<Verdict> = s.spans.iter().map(|s| s.verdict).collect();
        assert_eq!(
            verdicts,
            [Verdict::Better, Verdict::Indistinguishable, Verdict::Worse]
        );
        assert_eq!((s.spans[0].from, s.spans[0].to), (4000, 2000));
        assert_eq!((s.better, s.indistinguishable, s.worse), (0.4, 0.4, 0.2));
        assert_eq!(s.better_where_separate(), Some(2.0 / 3.0));
        assert_eq!(s.runs(), "better 4,000–2,000, overlap 1,000–500, worse 250");
        assert_eq!(
            s.says,
            "as better than rest-pose from 4,000 to 2,000 influences, indistinguishable from \
             1,000 to 500, worse at 250 influences"
        );
        // Zero-width bands that cross: nothing but ties is indistinguishable.
        let same = separation("as", &b, "rest-pose", &b).unwrap();
        assert_eq!(same.indistinguishable, 1.0);
        assert_eq!(same.better_where_separate(), None);
    }
}
