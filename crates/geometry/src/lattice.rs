//! Exact predicates on integer points, such as the pixel corners of a traced outline.
//!
//! Products are taken in `i128`, so every result is exact for coordinates of up to
//! 2⁶² in size; the signs follow the conventions of the crate's `f64` predicates.

/// An integer point `[x, y]`.
pub type Point = [i64; 2];

/// Twice the signed area of the triangle `a b c`, exactly: the integer twin of
/// [`crate::orient`] (positive when `a → b → c` turns counter-clockwise in a y-up frame,
/// zero exactly when the points are collinear).
pub fn orient(a: Point, b: Point, c: Point) -> i128 {
    let (abx, aby) = (i128::from(b[0] - a[0]), i128::from(b[1] - a[1]));
    let (acx, acy) = (i128::from(c[0] - a[0]), i128::from(c[1] - a[1]));
    abx * acy - aby * acx
}

/// Twice the signed area of a ring, exactly: the integer twin of
/// [`crate::signed_area`], doubled so that it stays an integer. Zero for fewer than
/// three vertices.
pub fn twice_signed_area(ring: &[Point]) -> i128 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            i128::from(a[0]) * i128::from(b[1]) - i128::from(a[1]) * i128::from(b[0])
        })
        .sum()
}

/// Whether the closed segments `a b` and `c d` share any point, exactly: they cross,
/// or an end of one lies on the other (collinear overlap, a shared end, a T). A
/// zero-length segment touches what passes through its point.
pub fn segments_touch(a: Point, b: Point, c: Point, d: Point) -> bool {
    let d1 = orient(c, d, a).signum();
    let d2 = orient(c, d, b).signum();
    let d3 = orient(a, b, c).signum();
    let d4 = orient(a, b, d).signum();
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && in_box(c, d, a))
        || (d2 == 0 && in_box(c, d, b))
        || (d3 == 0 && in_box(a, b, c))
        || (d4 == 0 && in_box(a, b, d))
}

/// Whether `p` lies in the bounding box of `a` and `b` (closed).
fn in_box(a: Point, b: Point, p: Point) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn f(p: Point) -> DVec2 {
        DVec2::new(p[0] as f64, p[1] as f64)
    }

    #[test]
    fn orient_agrees_with_the_float_one_and_is_exact_far_out() {
        let pts: [Point; 5] = [[0, 0], [7, -3], [2, 9], [-4, 4], [11, 11]];
        for a in pts {
            for b in pts {
                for c in pts {
                    assert_eq!(orient(a, b, c) as f64, crate::orient(f(a), f(b), f(c)));
                    assert_eq!(orient(a, c, b), -orient(a, b, c));
                    assert_eq!(orient(b, c, a), orient(a, b, c));
                }
            }
        }
        // Off by one in 2⁴⁰, which f64 products cannot see.
        let big = 1i64 << 40;
        assert_eq!(orient([0, 0], [big, big + 1], [big + 1, big + 2]), -1);
    }

    #[test]
    fn twice_signed_area_of_a_ring_and_its_reverse() {
        let mut ring: Vec<Point> = vec![[0, 0], [5, 0], [5, 3], [0, 3]];
        assert_eq!(twice_signed_area(&ring), 30);
        ring.reverse();
        assert_eq!(twice_signed_area(&ring), -30);
        assert_eq!(twice_signed_area(&ring[..2]), 0);
        assert_eq!(twice_signed_area(&[]), 0);
        let float: Vec<DVec2> = ring.iter().map(|&p| f(p)).collect();
        assert_eq!(
            twice_signed_area(&ring) as f64,
            2.0 * crate::signed_area(&float)
        );
    }

    #[test]
    fn touching_matches_the_float_predicate_on_small_integers() {
        let cases: [[Point; 4]; 8] = [
            [[0, 0], [4, 4], [0, 4], [4, 0]], // crossing
            [[0, 0], [4, 0], [2, 0], [2, 3]], // T
            [[0, 0], [4, 0], [4, 0], [6, 5]], // shared end
            [[0, 0], [4, 0], [0, 1], [4, 1]], // parallel
            [[0, 0], [4, 0], [3, 0], [6, 0]], // collinear overlap
            [[0, 0], [4, 0], [5, 0], [6, 0]], // collinear gap
            [[2, 1], [2, 1], [0, 0], [4, 2]], // a point on a segment
            [[2, 1], [2, 1], [0, 0], [4, 3]], // a point beside it
        ];
        let expected = [true, true, true, false, true, false, true, false];
        for ([a, b, c, d], want) in cases.into_iter().zip(expected) {
            assert_eq!(segments_touch(a, b, c, d), want, "{a:?} {b:?} {c:?} {d:?}");
            assert_eq!(segments_touch(c, d, a, b), want);
            assert_eq!(segments_touch(b, a, d, c), want);
            assert_eq!(crate::segments_touch(f(a), f(b), f(c), f(d)), want);
        }
    }
}
