//! Distances from points to segments and polylines, and between segments.

use glam::DVec2;

use crate::intersect::segments_cross;

/// The point of the segment `a b` closest to `p`, and its parameter `t` in `[0, 1]`
/// (the point is `a + (b − a)·t`).
///
/// Beyond an end the end itself is closest (`t` clamped to `0` or `1`). A zero-length
/// segment (`a == b`) is the point `a`, with `t = 0`. A non-finite input gives a
/// non-finite result.
#[inline]
pub fn closest_point_on_segment(p: DVec2, a: DVec2, b: DVec2) -> (DVec2, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t, t)
}

/// The squared distance from `p` to the segment `a b` (to the point `a` when
/// `a == b`); see [`closest_point_on_segment`].
#[inline]
pub fn point_segment_distance_squared(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    closest_point_on_segment(p, a, b).0.distance_squared(p)
}

/// The distance from `p` to the segment `a b` (to the point `a` when `a == b`): the
/// square root of [`point_segment_distance_squared`], to the bit.
#[inline]
pub fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    closest_point_on_segment(p, a, b).0.distance(p)
}

/// The squared distance from `p` to the open polyline through `points` (consecutive
/// points joined; the last is not joined back to the first).
///
/// One point is a polyline of no length: the squared distance to it. No points are
/// infinitely far: `f64::INFINITY`. A segment whose distance is NaN is passed over.
pub fn polyline_distance_squared(points: &[DVec2], p: DVec2) -> f64 {
    if points.len() == 1 {
        return points[0].distance_squared(p);
    }
    points
        .windows(2)
        .map(|w| point_segment_distance_squared(p, w[0], w[1]))
        .fold(f64::INFINITY, f64::min)
}

/// The distance between the closed segments `s` and `t` (either may have zero
/// length): `0` when they cross ([`segments_cross`]), otherwise the least distance
/// from an end of one to the other, which is where two disjoint segments come
/// closest. Segments that touch without crossing are `0` apart up to rounding.
pub fn segment_distance(s: [DVec2; 2], t: [DVec2; 2]) -> f64 {
    if segments_cross(s[0], s[1], t[0], t[1]) {
        return 0.0;
    }
    point_segment_distance(s[0], t[0], t[1])
        .min(point_segment_distance(s[1], t[0], t[1]))
        .min(point_segment_distance(t[0], s[0], s[1]))
        .min(point_segment_distance(t[1], s[0], s[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn a_point_on_the_segment_is_at_distance_zero() {
        let (a, b) = (p(1.0, 1.0), p(9.0, 5.0));
        for t in [0.0, 0.25, 0.5, 1.0] {
            let q = a + (b - a) * t;
            assert_eq!(point_segment_distance(q, a, b), 0.0, "t = {t}");
            let (closest, s) = closest_point_on_segment(q, a, b);
            assert_eq!(closest, q);
            assert_eq!(s, t);
        }
    }

    #[test]
    fn the_distance_is_perpendicular_inside_and_to_an_end_beyond() {
        let (a, b) = (p(0.0, 0.0), p(10.0, 0.0));
        assert_eq!(point_segment_distance(p(4.0, 3.0), a, b), 3.0);
        assert_eq!(point_segment_distance(p(4.0, -3.0), a, b), 3.0);
        // Beyond an end the end is closest, and the parameter is clamped.
        assert_eq!(closest_point_on_segment(p(-3.0, 4.0), a, b), (a, 0.0));
        assert_eq!(point_segment_distance(p(-3.0, 4.0), a, b), 5.0);
        assert_eq!(closest_point_on_segment(p(13.0, -4.0), a, b), (b, 1.0));
        assert_eq!(point_segment_distance(p(13.0, -4.0), a, b), 5.0);
        // The same either way round.
        assert_eq!(point_segment_distance(p(13.0, -4.0), b, a), 5.0);
    }

    #[test]
    fn the_squared_distance_is_the_square_of_the_distance() {
        let (a, b) = (p(0.3, 1.7), p(-2.9, 8.1));
        for q in [p(5.0, 5.0), p(0.0, 0.0), p(-7.5, 11.25), p(1.0, 4.0)] {
            let d = point_segment_distance(q, a, b);
            assert_eq!(point_segment_distance_squared(q, a, b).sqrt(), d);
        }
    }

    #[test]
    fn a_zero_length_segment_is_a_point() {
        let a = p(2.0, 3.0);
        assert_eq!(closest_point_on_segment(p(5.0, 7.0), a, a), (a, 0.0));
        assert_eq!(point_segment_distance(p(5.0, 7.0), a, a), 5.0);
        assert_eq!(point_segment_distance_squared(p(5.0, 7.0), a, a), 25.0);
        assert!(point_segment_distance(p(f64::NAN, 0.0), a, a).is_nan());
    }

    #[test]
    fn polyline_distance_is_the_least_over_its_segments() {
        let line = [p(0.0, 0.0), p(10.0, 0.0), p(10.0, 10.0)];
        assert_eq!(polyline_distance_squared(&line, p(5.0, 2.0)), 4.0);
        assert_eq!(polyline_distance_squared(&line, p(13.0, 6.0)), 9.0);
        // Open: the last point is not joined back to the first.
        assert_eq!(polyline_distance_squared(&line, p(2.0, 8.0)), 64.0);
        // A lone point, and nothing at all.
        assert_eq!(polyline_distance_squared(&line[..1], p(3.0, 4.0)), 25.0);
        assert_eq!(polyline_distance_squared(&[], p(3.0, 4.0)), f64::INFINITY);
    }

    #[test]
    fn segments_that_cross_or_touch_are_zero_apart() {
        let s = [p(0.0, 0.0), p(4.0, 4.0)];
        assert_eq!(segment_distance(s, [p(0.0, 4.0), p(4.0, 0.0)]), 0.0);
        // An end on the other segment, and a shared end.
        assert_eq!(segment_distance(s, [p(2.0, 2.0), p(5.0, 0.0)]), 0.0);
        assert_eq!(segment_distance(s, [p(4.0, 4.0), p(9.0, 1.0)]), 0.0);
    }

    #[test]
    fn disjoint_segments_are_as_far_apart_as_their_closest_ends_reach() {
        // Parallel, overlapping in x: the gap between the lines.
        let s = [p(0.0, 0.0), p(10.0, 0.0)];
        assert_eq!(segment_distance(s, [p(2.0, 3.0), p(12.0, 3.0)]), 3.0);
        // Collinear with a gap.
        assert_eq!(segment_distance(s, [p(13.0, 0.0), p(20.0, 0.0)]), 3.0);
        // A T that stops short.
        assert_eq!(segment_distance(s, [p(5.0, 2.0), p(5.0, 9.0)]), 2.0);
        // Symmetric, and points are segments of length zero.
        let t = [p(5.0, 2.0), p(5.0, 9.0)];
        assert_eq!(segment_distance(t, s), segment_distance(s, t));
        assert_eq!(segment_distance([p(0.0, 0.0); 2], [p(3.0, 4.0); 2]), 5.0);
        assert_eq!(segment_distance([p(4.0, 1.0); 2], s), 1.0);
    }
}
