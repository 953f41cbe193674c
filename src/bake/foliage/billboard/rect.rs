//! The least-area rectangle round a set of points in a plane, by rotating calipers on their convex
//! hull (Bennett-Therkildsen, Carlsen & Schmid, "Animated Billboard Clouds for Foliage
//! Simplification", Aalborg University, 2007 §3.5, after Pirzadeh; Freeman & Shapira: the
//! least-area enclosing rectangle has a side on a hull edge).

use glam::Vec2;

/// A rectangle: centre, unit direction of its first side, half extents along that side and
/// along its perpendicular.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub center: Vec2,
    pub axis: Vec2,
    pub half: Vec2,
}

impl Rect {
    pub fn area(&self) -> f32 {
        4.0 * self.half.x * self.half.y
    }

    /// Corners counter-clockwise, starting at (−u, −v).
    pub fn corners(&self) -> [Vec2; 4] {
        let u = self.axis * self.half.x;
        let v = self.axis.perp() * self.half.y;
        let c = self.center;
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// Does the rectangle contain `p` (with a tolerance)?
    pub fn contains(&self, p: Vec2, tolerance: f32) -> bool {
        let d = p - self.center;
        d.dot(self.axis).abs() <= self.half.x + tolerance
            && d.dot(self.axis.perp()).abs() <= self.half.y + tolerance
    }
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's monotone chain).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p: Vec<Vec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// The least-area rectangle containing `points`. Degenerate sets (a point, a segment) give a
/// rectangle of zero width.
pub fn min_area_rect(points: &[Vec2]) -> Rect {
    let hull = convex_hull(points);
    match hull.len() {
        0 => {
            return Rect {
                center: Vec2::ZERO,
                axis: Vec2::X,
                half: Vec2::ZERO,
            };
        }
        1 => {
            return Rect {
                center: hull[0],
                axis: Vec2::X,
                half: Vec2::ZERO,
            };
        }
        2 => {
            let d = hull[1] - hull[0];
            return Rect {
                center: (hull[0] + hull[1]) * 0.5,
                axis: d.normalize_or(Vec2::X),
                half: Vec2::new(d.length() * 0.5, 0.0),
            };
        }
        _ => {}
    }
    let n = hull.len();
    let at = |i: usize| hull[i % n];
    // Calipers: for edge i, `right` is the farthest point along the edge, `top` the farthest
    // from it, `left` the farthest against it. Each only ever moves forward round the hull.
    let (mut right, mut top, mut left) = (1usize, 1usize, 1usize);
    let mut best: Option<Rect> = None;
    for i in 0..n {
        let e = (at(i + 1) - at(i)).normalize();
        let normal = e.perp();
        let origin = at(i);
        right = right.max(i + 1);
        while (at(right + 1) - origin).dot(e) >= (at(right) - origin).dot(e) - 1e-9 && right < i + n
        {
            right += 1;
        }
        top = top.max(right);
        while (at(top + 1) - origin).dot(normal) >= (at(top) - origin).dot(normal) - 1e-9
            && top < i + n
        {
            top += 1;
        }
        left = left.max(top);
        while (at(left + 1) - origin).dot(e) <= (at(left) - origin).dot(e) + 1e-9 && left < i + n {
            left += 1;
        }
        let (min_u, max_u) = ((at(left) - origin).dot(e), (at(right) - origin).dot(e));
        let height = (at(top) - origin).dot(normal);
        let rect = Rect {
            center: origin + e * (min_u + max_u) * 0.5 + normal * height * 0.5,
            axis: e,
            half: Vec2::new((max_u - min_u) * 0.5, height * 0.5),
        };
        if best.is_none_or(|b| rect.area() < b.area()) {
            best = Some(rect);
        }
    }
    best.expect("a hull of three or more points has edges")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: every direction in fine steps.
    fn brute(points: &[Vec2]) -> f32 {
        (0..20_000)
            .map(|k| {
                let a = std::f32::consts::PI * k as f32 / 20_000.0;
                let (u, v) = (Vec2::from_angle(a), Vec2::from_angle(a).perp());
                let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
                for p in points {
                    let q = Vec2::new(p.dot(u), p.dot(v));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                (hi - lo).x * (hi - lo).y
            })
            .fold(f32::MAX, f32::min)
    }

    #[test]
    fn calipers_find_the_least_area_rectangle_and_it_contains_everything() {
        let mut rng = fastrand::Rng::with_seed(9);
        for case in 0..40 {
            let n = 3 + case % 17;
            let stretch = Vec2::new(1.0 + 3.0 * rng.f32(), 0.2 + rng.f32());
            let turn = Vec2::from_angle(rng.f32() * 6.0);
            let points: Vec<Vec2> = (0..n)
                .map(|_| turn.rotate(Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * stretch))
                .collect();
            let r = min_area_rect(&points);
            for p in &points {
                assert!(r.contains(*p, 1e-4), "case {case}: {p} outside");
            }
            let b = brute(&points);
            assert!(
                r.area() <= b * 1.0005 + 1e-6,
                "case {case}: {} vs {b}",
                r.area()
            );
        }
    }

    #[test]
    fn a_rotated_square_is_found_exactly() {
        let turn = Vec2::from_angle(0.4);
        let square: Vec<Vec2> = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (0.2, 0.3),
        ]
        .iter()
        .map(|&(x, y)| turn.rotate(Vec2::new(x, y)))
        .collect();
        let r = min_area_rect(&square);
        assert!((r.area() - 4.0).abs() < 1e-4);
        assert_eq!(convex_hull(&square).len(), 4);
    }
}
