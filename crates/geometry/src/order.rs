//! Orders of points that keep neighbours near each other in memory.

use glam::DVec2;

/// The indices of `points` sorted along the Z-order (Morton) curve of their positions
/// quantised to a 65536 × 65536 grid over their bounding box (ties by index).
pub fn z_order(points: &[DVec2]) -> Vec<u32> {
    let (lo, hi) = points.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let scale = 65535.0 / (hi - lo).max_element().max(f64::MIN_POSITIVE);
    let spread = |x: u32| -> u64 {
        let mut x = u64::from(x);
        x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
        x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
        x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        x = (x | (x << 2)) & 0x3333_3333_3333_3333;
        (x | (x << 1)) & 0x5555_5555_5555_5555
    };
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let q = (p - lo) * scale;
            let (x, y) = (
                q.x.clamp(0.0, 65535.0) as u32,
                q.y.clamp(0.0, 65535.0) as u32,
            );
            (spread(x) | (spread(y) << 1), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_order_is_a_permutation_visiting_quadrants_in_turn() {
        // A 4 × 4 grid given row by row: the curve visits each 2 × 2 quadrant whole.
        let points: Vec<DVec2> = (0..16)
            .map(|i| DVec2::new(f64::from(i % 4), f64::from(i / 4)))
            .collect();
        let order = z_order(&points);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..16).collect::<Vec<u32>>());
        assert_eq!(order[..4], [0, 1, 4, 5]);
        assert_eq!(order[4..8], [2, 3, 6, 7]);
        assert!(z_order(&[]).is_empty());
    }
}
