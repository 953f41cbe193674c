//! Order statistics of measured figures: quantiles of frame times, medians over views.

/// The median of each figure of entry `i` over `views` (each an array of optional figures),
/// where any view has it.
pub fn medians<const N: usize, const M: usize>(
    views: &[[Option<[f64; N]>; M]],
    i: usize,
) -> Option<[f64; N]> {
    let present: Vec<[f64; N]> = views.iter().filter_map(|v| v[i]).collect();
    (!present.is_empty()).then(|| {
        std::array::from_fn(|k| percentile(&present.iter().map(|v| v[k]).collect::<Vec<_>>(), 0.5))
    })
}

/// The `q` quantile of `values`, linearly interpolated between the closest ranks.
pub fn percentile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let x = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (x - lo as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_skip_the_views_without_the_entry() {
        let views = [
            [Some([1.0, 10.0]), None],
            [Some([3.0, 30.0]), None],
            [None, Some([5.0, 6.0])],
        ];
        assert_eq!(medians(&views, 0), Some([2.0, 20.0]));
        assert_eq!(medians(&views, 1), Some([5.0, 6.0]));
        let none: [[Option<[f64; 2]>; 2]; 0] = [];
        assert_eq!(medians(&none, 0), None);
    }
}
