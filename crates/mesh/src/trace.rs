//! Tracing the outlines of a binary pixel mask along pixel edges.

/// One closed outline, in pixel-corner coordinates, corners only (no collinear vertices).
///
/// Outer outlines have positive signed area (shoelace in pixel coordinates), hole
/// outlines negative: the inside pixels are on the left when walking in a y-up frame.
pub(crate) struct TracedRing {
    /// Corner vertices; the ring closes from the last back to the first.
    pub pts: Vec<[i64; 2]>,
    /// An inside pixel `(x, y)` adjacent to the ring, to find its component.
    pub fg_pixel: (usize, usize),
}

/// Traces every boundary between inside (`true`) and outside pixels of a `w × h` mask,
/// pixels outside the image counting as outside.
///
/// The mask must be *well-composed*: no 2×2 block whose inside pixels touch only
/// diagonally. Then every pixel corner has at most one outgoing boundary edge and the
/// outlines are simple, pairwise disjoint rings.
pub(crate) fn trace(mask: &[bool], w: usize, h: usize) -> Vec<TracedRing> {
    let vid = |x: usize, y: usize| (y * (w + 1) + x) as u64;
    let at = |x: usize, y: usize| mask[y * w + x];
    // (from corner, to corner, direction 0:+x 1:+y 2:-x 3:-y)
    let mut edges: Vec<(u64, u64, u8)> = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if !at(x, y) {
                continue;
            }
            if y == 0 || !at(x, y - 1) {
                edges.push((vid(x, y), vid(x + 1, y), 0));
            }
            if x + 1 == w || !at(x + 1, y) {
                edges.push((vid(x + 1, y), vid(x + 1, y + 1), 1));
            }
            if y + 1 == h || !at(x, y + 1) {
                edges.push((vid(x + 1, y + 1), vid(x, y + 1), 2));
            }
            if x == 0 || !at(x - 1, y) {
                edges.push((vid(x, y + 1), vid(x, y), 3));
            }
        }
    }
    edges.sort_unstable_by_key(|e| e.0);
    let find = |v: u64| edges.binary_search_by_key(&v, |e| e.0).ok();
    let coords = |v: u64| {
        let v = v as usize;
        [(v % (w + 1)) as i64, (v / (w + 1)) as i64]
    };
    let mut visited = vec![false; edges.len()];
    let mut rings = Vec::new();
    let mut cycle: Vec<usize> = Vec::new();
    for start in 0..edges.len() {
        if visited[start] {
            continue;
        }
        cycle.clear();
        let mut e = start;
        loop {
            visited[e] = true;
            cycle.push(e);
            match find(edges[e].1) {
                Some(next) if !visited[next] => e = next,
                _ => break,
            }
        }
        let n = cycle.len();
        let mut pts = Vec::new();
        for k in 0..n {
            let prev = edges[cycle[(k + n - 1) % n]].2;
            let cur = edges[cycle[k]];
            if cur.2 != prev {
                pts.push(coords(cur.0));
            }
        }
        if pts.len() < 4 {
            continue; // Cannot happen for a well-composed mask.
        }
        let (from, dir) = (coords(edges[start].0), edges[start].2);
        let (fx, fy) = (from[0] as usize, from[1] as usize);
        let fg_pixel = match dir {
            0 => (fx, fy),
            1 => (fx - 1, fy),
            2 => (fx - 1, fy - 1),
            _ => (fx, fy - 1),
        };
        rings.push(TracedRing { pts, fg_pixel });
    }
    rings
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn area(pts: &[[i64; 2]]) -> i128 {
        geometry::lattice::twice_signed_area(pts) / 2
    }

    #[test]
    fn ring_with_hole() {
        // 5x5 block with a 1-pixel hole in the middle.
        let (w, h) = (7, 7);
        let mut mask = vec![false; w * h];
        for y in 1..6 {
            for x in 1..6 {
                mask[y * w + x] = !(x == 3 && y == 3);
            }
        }
        let rings = trace(&mask, w, h);
        assert_eq!(rings.len(), 2);
        let mut areas: Vec<i128> = rings.iter().map(|r| area(&r.pts)).collect();
        areas.sort();
        assert_eq!(areas, vec![-1, 25]);
        for r in &rings {
            assert!(mask[r.fg_pixel.1 * w + r.fg_pixel.0]);
        }
    }

    #[test]
    fn full_mask_is_rectangle() {
        let rings = trace(&[true; 6], 3, 2);
        assert_eq!(rings.len(), 1);
        assert_eq!(rings[0].pts.len(), 4);
        assert_eq!(area(&rings[0].pts), 6);
    }
}
