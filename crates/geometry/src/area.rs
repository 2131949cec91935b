//! Orientation of three points and the signed area of a ring.

use glam::DVec2;

/// Twice the signed area of the triangle `a b c`: `(b − a) × (c − a)`.
///
/// Positive when `a → b → c` turns counter-clockwise in a y-up frame (clockwise on
/// screen in image coordinates, y down), negative the other way, zero when the three
/// points are collinear up to rounding (or two coincide). Swapping `b` and `c` flips
/// the sign exactly; any other swap flips it and a cyclic rotation keeps it, both up to
/// rounding (the differences are taken from `a`).
#[inline]
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// The signed area of a ring by the shoelace formula, in square units.
///
/// Positive for a ring that runs counter-clockwise in a y-up frame (the sign of
/// [`orient`] at its convex corners), negative for the reverse order. A ring of fewer
/// than three vertices has area `0`; a self-intersecting ring gets the sum of its
/// loops' signed areas.
pub fn signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    let mut twice = 0.0;
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        twice += a.perp_dot(b);
    }
    0.5 * twice
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn orient_is_positive_for_a_left_turn_and_flips_under_swaps() {
        let (a, b, c) = (p(0.3, -1.2), p(4.1, 0.7), p(1.9, 3.3));
        let o = orient(a, b, c);
        assert!(o > 0.0);
        // Swapping the last two flips the sign exactly, the others up to rounding.
        assert_eq!(orient(a, c, b), -o);
        assert!((orient(b, a, c) + o).abs() <= 1e-12 * o.abs());
        assert!((orient(c, b, a) + o).abs() <= 1e-12 * o.abs());
        // Rotating the points keeps the turn (up to rounding).
        assert!((orient(b, c, a) - o).abs() <= 1e-12 * o.abs());
        assert!((orient(c, a, b) - o).abs() <= 1e-12 * o.abs());
        // Twice the area: the unit right triangle gives 1.
        assert_eq!(orient(p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)), 1.0);
    }

    #[test]
    fn orient_is_zero_on_a_line_and_for_repeated_points() {
        let (a, b) = (p(1.0, 2.0), p(5.0, 10.0));
        assert_eq!(orient(a, b, p(3.0, 6.0)), 0.0);
        assert_eq!(orient(a, b, p(-7.0, -14.0)), 0.0);
        assert_eq!(orient(a, a, b), 0.0);
        assert_eq!(orient(a, b, b), 0.0);
    }

    #[test]
    fn signed_area_of_a_ring_and_its_reverse() {
        let ccw = [p(0.0, 0.0), p(4.0, 0.0), p(4.0, 3.0), p(0.0, 3.0)];
        assert_eq!(signed_area(&ccw), 12.0);
        let mut cw = ccw;
        cw.reverse();
        assert_eq!(signed_area(&cw), -12.0);
        // Independent of where the ring starts.
        let rotated = [ccw[2], ccw[3], ccw[0], ccw[1]];
        assert_eq!(signed_area(&rotated), 12.0);
        // Independent of where the origin is (exact for these small integers).
        let moved: Vec<DVec2> = ccw.iter().map(|&q| q + p(-100.0, 37.0)).collect();
        assert_eq!(signed_area(&moved), 12.0);
    }

    #[test]
    fn signed_area_matches_orient_on_a_triangle() {
        let t = [p(0.5, 0.25), p(7.0, 1.0), p(2.0, 5.5)];
        assert_eq!(signed_area(&t), 0.5 * orient(t[0], t[1], t[2]));
    }

    #[test]
    fn signed_area_of_degenerate_rings_is_zero() {
        assert_eq!(signed_area(&[]), 0.0);
        assert_eq!(signed_area(&[p(1.0, 1.0)]), 0.0);
        assert_eq!(signed_area(&[p(1.0, 1.0), p(3.0, 2.0)]), 0.0);
        assert_eq!(signed_area(&[p(0.0, 0.0), p(1.0, 1.0), p(2.0, 2.0)]), 0.0);
        // A figure eight: its two loops cancel.
        let eight = [p(0.0, 0.0), p(2.0, 2.0), p(2.0, 0.0), p(0.0, 2.0)];
        assert_eq!(signed_area(&eight), 0.0);
    }
}
