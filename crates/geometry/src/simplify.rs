//! Douglas–Peucker simplification of rings and polylines.

use glam::DVec2;

use crate::distance::point_segment_distance_squared;

/// The vertex strictly between `i` and `j`, going forward around the ring (from `i`
/// up, wrapping past the last vertex to the first), farthest from the chord
/// `ring[i] ring[j]`, with its squared distance to the chord.
///
/// `i == j` means every other vertex of the ring (the chord is then a point). Of
/// several vertices equally far, the first one met wins. `None` when no vertex lies
/// between (`j` follows `i`) or every distance is NaN. On an open polyline, `i < j`
/// gives the vertices between them.
///
/// # Panics
/// If `i` or `j` is not an index of `ring`.
pub fn farthest_from_chord(ring: &[DVec2], i: usize, j: usize) -> Option<(usize, f64)> {
    let n = ring.len();
    let (a, b) = (ring[i], ring[j]);
    let mut best = None;
    let mut best_d = -1.0;
    let mut k = (i + 1) % n;
    while k != j {
        let d = point_segment_distance_squared(ring[k], a, b);
        if d > best_d {
            best_d = d;
            best = Some((k, d));
        }
        k = (k + 1) % n;
    }
    best
}

/// Douglas–Peucker on the given spans of a ring: each span `(i, j)` (the vertices
/// strictly between `i` and `j` as [`farthest_from_chord`] walks them) keeps, in
/// `keep`, its vertex farthest from the chord when that is more than `tolerance`
/// away, and the two spans that vertex splits it into are treated the same way.
///
/// The ends of the spans are the caller's to keep; vertices already kept stay kept,
/// and vertices outside the spans are not looked at. Afterwards every vertex of a span
/// that is not kept lies within `tolerance` of the chord between the nearest kept
/// vertices around it. A vertex exactly `tolerance` away is dropped; a tolerance of
/// zero keeps every vertex off the chords, a NaN tolerance none. To simplify an open
/// polyline, keep both ends and pass the one span `(0, len − 1)`.
///
/// # Panics
/// If a span's ends are not indices of `ring`, or `keep` is shorter than `ring`.
pub fn douglas_peucker(
    ring: &[DVec2],
    keep: &mut [bool],
    mut spans: Vec<(usize, usize)>,
    tolerance: f64,
) {
    let tolerance2 = tolerance * tolerance;
    while let Some((i, j)) = spans.pop() {
        if let Some((k, d)) = farthest_from_chord(ring, i, j)
            && d > tolerance2
        {
            keep[k] = true;
            spans.push((i, k));
            spans.push((k, j));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// A wobbly open polyline: a sine with bumps of different sizes.
    fn wobbly() -> Vec<DVec2> {
        (0..60)
            .map(|i| {
                let x = i as f64;
                let bump = if i % 7 == 3 { 2.5 } else { 0.0 };
                p(x, 4.0 * (x * 0.21).sin() + 0.3 * (x * 1.7).cos() + bump)
            })
            .collect()
    }

    fn simplify_open(points: &[DVec2], tolerance: f64) -> Vec<bool> {
        let mut keep = vec![false; points.len()];
        keep[0] = true;
        keep[points.len() - 1] = true;
        douglas_peucker(points, &mut keep, vec![(0, points.len() - 1)], tolerance);
        keep
    }

    #[test]
    fn simplification_keeps_the_ends_and_stays_within_the_tolerance() {
        let line = wobbly();
        for tolerance in [0.1, 0.5, 1.0, 3.0] {
            let keep = simplify_open(&line, tolerance);
            assert!(keep[0] && keep[line.len() - 1]);
            let kept: Vec<usize> = (0..line.len()).filter(|&k| keep[k]).collect();
            if tolerance >= 1.0 {
                assert!(
                    kept.len() < line.len() / 2,
                    "tolerance {tolerance}: {kept:?}"
                );
            }
            for w in kept.windows(2) {
                for k in w[0] + 1..w[1] {
                    let d = point_segment_distance_squared(line[k], line[w[0]], line[w[1]]);
                    assert!(
                        d <= tolerance * tolerance,
                        "vertex {k} at tolerance {tolerance}"
                    );
                }
            }
        }
        // A larger tolerance keeps a subset: its splits are the first ones of a smaller.
        let (fine, coarse) = (simplify_open(&line, 0.5), simplify_open(&line, 3.0));
        assert!(fine.iter().zip(&coarse).all(|(&f, &c)| f || !c));
    }

    #[test]
    fn collinear_vertices_go_and_corners_farther_than_the_tolerance_stay() {
        // The chord from the first to the last vertex misses the corner by √2.
        let line = [p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0), p(2.0, 2.0)];
        assert_eq!(simplify_open(&line, 0.0), [true, false, true, true]);
        assert_eq!(simplify_open(&line, 1.0), [true, false, true, true]);
        assert_eq!(simplify_open(&line, 1.5), [true, false, false, true]);
        // Exactly at the tolerance is within it.
        let tent = [p(0.0, 0.0), p(1.0, 1.0), p(2.0, 0.0)];
        assert_eq!(simplify_open(&tent, 1.0), [true, false, true]);
        assert_eq!(simplify_open(&tent, f64::NAN), [true, false, true]);
    }

    #[test]
    fn farthest_vertex_walks_forward_around_the_ring() {
        let ring = [
            p(0.0, 0.0),
            p(4.0, 0.0),
            p(4.0, 4.0),
            p(1.0, 5.0),
            p(0.0, 4.0),
        ];
        // From 1 round to 0: vertices 2, 3, 4; the chord runs along y = 0.
        assert_eq!(farthest_from_chord(&ring, 1, 0), Some((3, 25.0)));
        // From 4 round to 2: vertices 0 and 1, wrapping.
        let (k, _) = farthest_from_chord(&ring, 4, 2).unwrap_or((usize::MAX, 0.0));
        assert_eq!(k, 0);
        // Neighbours have nothing between them.
        assert_eq!(farthest_from_chord(&ring, 2, 3), None);
        assert_eq!(farthest_from_chord(&ring, 4, 0), None);
        // The whole ring from a vertex: the point chord at vertex 0.
        assert_eq!(farthest_from_chord(&ring, 0, 0), Some((2, 32.0)));
    }

    #[test]
    fn a_ring_keeps_its_shape_under_span_simplification() {
        // A noisy circle: anchors at two opposite vertices, the rest by tolerance.
        let n = 64;
        let ring: Vec<DVec2> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = 10.0 + if i % 5 == 0 { 0.4 } else { 0.0 };
                p(r * a.cos(), r * a.sin())
            })
            .collect();
        let mut keep = vec![false; n];
        keep[0] = true;
        keep[n / 2] = true;
        douglas_peucker(&ring, &mut keep, vec![(0, n / 2), (n / 2, 0)], 0.5);
        let kept: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
        assert!(kept.len() > 4 && kept.len() < n);
        for (w, &next) in kept.iter().zip(kept.iter().cycle().skip(1)) {
            let mut k = (w + 1) % n;
            while k != next {
                let d = point_segment_distance_squared(ring[k], ring[*w], ring[next]);
                assert!(d <= 0.25, "vertex {k}");
                k = (k + 1) % n;
            }
        }
    }
}
