//! Whether two segments cross or touch.

use glam::DVec2;

use crate::area::orient;

/// Whether the segments `a b` and `c d` cross properly: each has one end strictly on
/// either side of the other's line, so they meet at one point inside both.
///
/// Touching (an end on the other segment, a shared end) and collinear overlap are not
/// crossings; nor is anything with a zero-length segment. The sides are the signs of
/// [`orient`], without tolerance: a point within rounding of a line may land on either
/// side. Non-finite input never crosses.
#[inline]
pub fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    orient(a, b, c) * orient(a, b, d) < 0.0 && orient(c, d, a) * orient(c, d, b) < 0.0
}

/// Whether the closed segments `a b` and `c d` share any point: they cross
/// ([`segments_cross`]), or an end of one lies on the other (collinear overlap, a
/// shared end, a T).
///
/// There is no tolerance: an end counts as on a segment when [`orient`] is exactly
/// zero and it lies in the segment's bounding box. That is exact for coordinates whose
/// differences and products are exact in `f64` (integers below 2²⁶, say); elsewhere a
/// touch within rounding may be missed. A zero-length segment touches what passes
/// through its point.
pub fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    segments_cross(a, b, c, d)
        || lies_on(a, b, c)
        || lies_on(a, b, d)
        || lies_on(c, d, a)
        || lies_on(c, d, b)
}

/// Whether `r` lies on the closed segment `p q` (exactly on its line, within its box).
fn lies_on(p: DVec2, q: DVec2, r: DVec2) -> bool {
    orient(p, q, r) == 0.0
        && r.x >= p.x.min(q.x)
        && r.x <= p.x.max(q.x)
        && r.y >= p.y.min(q.y)
        && r.y <= p.y.max(q.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// Both predicates for every order of the two segments and of their ends.
    fn both(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> (bool, bool) {
        let cross = segments_cross(a, b, c, d);
        let touch = segments_touch(a, b, c, d);
        for (a, b, c, d) in [(b, a, c, d), (a, b, d, c), (c, d, a, b), (d, c, b, a)] {
            assert_eq!(segments_cross(a, b, c, d), cross, "cross depends on order");
            assert_eq!(segments_touch(a, b, c, d), touch, "touch depends on order");
        }
        (cross, touch)
    }

    #[test]
    fn crossing_segments_cross_and_touch() {
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 4.0), p(0.0, 4.0), p(4.0, 0.0)),
            (true, true)
        );
        assert_eq!(
            both(p(0.0, 0.0), p(10.0, 1.0), p(3.0, -5.0), p(4.0, 7.0)),
            (true, true)
        );
    }

    #[test]
    fn touching_segments_touch_without_crossing() {
        // A T: an end on the other's interior.
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(2.0, 0.0), p(2.0, 3.0)),
            (false, true)
        );
        // A shared end.
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(4.0, 0.0), p(6.0, 5.0)),
            (false, true)
        );
    }

    #[test]
    fn parallel_segments_neither_cross_nor_touch() {
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(0.0, 1.0), p(4.0, 1.0)),
            (false, false)
        );
        // Apart, though their lines cross.
        assert_eq!(
            both(p(0.0, 0.0), p(1.0, 1.0), p(3.0, 0.0), p(2.0, 0.9)),
            (false, false)
        );
    }

    #[test]
    fn collinear_segments_touch_only_where_they_overlap() {
        // Overlapping.
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(3.0, 0.0), p(6.0, 0.0)),
            (false, true)
        );
        // One inside the other.
        assert_eq!(
            both(p(0.0, 0.0), p(6.0, 6.0), p(2.0, 2.0), p(3.0, 3.0)),
            (false, true)
        );
        // End to end.
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(4.0, 0.0), p(6.0, 0.0)),
            (false, true)
        );
        // On one line with a gap.
        assert_eq!(
            both(p(0.0, 0.0), p(4.0, 0.0), p(5.0, 0.0), p(6.0, 0.0)),
            (false, false)
        );
    }

    #[test]
    fn a_point_touches_the_segments_through_it() {
        let q = p(2.0, 1.0);
        assert_eq!(both(q, q, p(0.0, 0.0), p(4.0, 2.0)), (false, true));
        assert_eq!(both(q, q, q, q), (false, true));
        assert_eq!(both(q, q, p(0.0, 0.0), p(4.0, 2.5)), (false, false));
    }

    #[test]
    fn non_finite_segments_do_not_cross() {
        let nan = p(f64::NAN, 0.0);
        assert!(!segments_cross(nan, p(4.0, 4.0), p(0.0, 4.0), p(4.0, 0.0)));
        assert!(!segments_touch(nan, nan, nan, nan));
    }
}
