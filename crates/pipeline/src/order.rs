//! Overlap order (§5.1 of the ARAP paper; Photoshop's pin depth): where parts of the
//! warped picture overlap — an arm bent over the body, a fold of the C² weights — the
//! part belonging to a handle of greater depth is drawn in front.
//!
//! Every triangle takes the depth of the handle nearest it in the shape's own metric:
//! the C² rig's Voronoi cells already say which node is nearest each vertex, and
//! which handle each node belongs to (a virtual handle to the one with the largest
//! harmonic coordinate). A triangle whose corners lie in cells of different depths
//! takes the greatest. The triangles are then drawn in order of depth (a stable
//! sort: equal depths keep the mesh's order), the same list on the CPU and on the GPU,
//! so the exported picture equals the preview.

use weights_core::Rig;

/// The triangles of `rig`'s mesh in drawing order for the handle depths `depths`
/// (one per real handle; a missing one is 0): back to front.
pub fn draw_order(rig: &Rig, depths: &[i32]) -> Vec<[u32; 3]> {
    let triangles = rig.domain().triangles();
    if depths.iter().all(|&d| d == 0) {
        return triangles.to_vec();
    }
    let node_depth: Vec<i32> = (0..rig.nodes().len())
        .map(|k| {
            rig.owner_handle(k)
                .and_then(|h| depths.get(h).copied())
                .unwrap_or(0)
        })
        .collect();
    let vertex_depth = |v: u32| {
        rig.cells()
            .get(v as usize)
            .and_then(|&k| node_depth.get(k as usize).copied())
            .unwrap_or(0)
    };
    let mut keyed: Vec<(i32, [u32; 3])> = triangles
        .iter()
        .map(|t| (t.iter().map(|&v| vertex_depth(v)).max().unwrap_or(0), *t))
        .collect();
    keyed.sort_by_key(|&(d, _)| d);
    keyed.into_iter().map(|(_, t)| t).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use weights_core::{Domain, Handle, Metric, RigOptions};

    fn strip_rig() -> Rig {
        let positions = (0..=1)
            .flat_map(|y| (0..=20).map(move |x| DVec2::new(f64::from(x), f64::from(y))))
            .collect();
        let triangles = (0..20u32)
            .flat_map(|x| [[x, x + 1, x + 22], [x, x + 22, x + 21]])
            .collect();
        let domain = Domain::new(positions, triangles, Metric::Euclidean).expect("a strip");
        let handles = vec![
            Handle::point(DVec2::new(0.0, 0.0)),
            Handle::point(DVec2::new(20.0, 1.0)),
        ];
        Rig::new(domain, handles, RigOptions::default()).expect("a rig")
    }

    #[test]
    fn no_depths_keep_the_mesh_order_and_the_deeper_handles_part_comes_last() {
        let rig = strip_rig();
        let triangles = rig.domain().triangles();
        assert_eq!(draw_order(&rig, &[0, 0]), triangles);
        assert_eq!(draw_order(&rig, &[]), triangles);
        let order = draw_order(&rig, &[0, 3]);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        let mut all = triangles.to_vec();
        all.sort_unstable();
        assert_eq!(sorted, all, "a permutation");
        // The right end (handle 1's cell) comes after the left end.
        let position = |t: [u32; 3]| order.iter().position(|&o| o == t).expect("present");
        assert!(position(triangles[39]) > position(triangles[0]));
        assert_eq!(order.last(), triangles.last(), "stable within a depth");
        // Negative depths go behind.
        let order = draw_order(&rig, &[0, -3]);
        assert!(
            order.iter().position(|&o| o == triangles[39])
                < order.iter().position(|&o| o == triangles[0])
        );
    }
}
