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
//!
//! That order is the *predefined* one. With automatic depth (the project's
//! `auto_depth`, on by default), the `depth` crate orders each overlap region of the
//! warped mesh wholly one way, starting from it, and keeps that order while the
//! region lasts ([`Arranger`]); the project's `overlaps` keep the orders of the pose
//! it holds, by a point at rest in each sheet.

use glam::DVec2;
use project::{OverlapOrder, Place};
use weights_core::Rig;

/// The triangles of `rig`'s mesh in drawing order for the handle depths `depths`
/// (one per real handle; a missing one is 0): back to front.
pub fn draw_order(rig: &Rig, depths: &[i32]) -> Vec<[u32; 3]> {
    let triangles = rig.domain().triangles();
    predefined_order(rig, depths)
        .into_iter()
        .map(|t| triangles[t as usize])
        .collect()
}

/// As [`draw_order`], each triangle by its index in the mesh's list.
pub fn predefined_order(rig: &Rig, depths: &[i32]) -> Vec<u32> {
    let triangles = rig.domain().triangles();
    let all = 0..triangles.len() as u32;
    if depths.iter().all(|&d| d == 0) {
        return all.collect();
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
    let mut keyed: Vec<(i32, u32)> = all
        .map(|t| {
            let depth = triangles[t as usize].iter().map(|&v| vertex_depth(v)).max();
            (depth.unwrap_or(0), t)
        })
        .collect();
    keyed.sort_by_key(|&(d, _)| d);
    keyed.into_iter().map(|(_, t)| t).collect()
}

/// Automatic depth for one mesh: its predefined order and the overlap regions of the
/// pose last arranged, which the next pose's regions continue.
#[derive(Clone, Debug)]
pub struct Arranger {
    /// The triangles (indices) back to front without adjustment.
    predefined: Vec<u32>,
    /// The mesh's boundary and pieces, so that a pose without overlaps costs little.
    topology: depth::Topology,
    /// For a mesh joined from parts, each triangle's part (a layer's index).
    part_of: Option<Vec<u32>>,
    /// The last pose's regions.
    regions: Vec<depth::Region>,
    /// The last pose's overlapping triangles (only those that moved are tested again).
    pairs: depth::PairCache,
}

impl Arranger {
    /// Starts from `predefined` (every triangle's index, back to front) and the
    /// region orders `overlaps` saved with a pose of the mesh whose rest positions
    /// and triangles are `rest` and `triangles`.
    pub fn new(
        predefined: Vec<u32>,
        overlaps: &[OverlapOrder],
        rest: &[DVec2],
        triangles: &[[u32; 3]],
    ) -> Self {
        let mut arranger = Self {
            predefined,
            topology: depth::Topology::new(rest, triangles),
            part_of: None,
            regions: Vec::new(),
            pairs: depth::PairCache::default(),
        };
        arranger.restart(overlaps, rest, triangles);
        arranger
    }

    /// As [`Arranger::new`] for a mesh joined from parts (whose rest positions lie
    /// over one another), `part_of` giving each triangle's part: a saved place names
    /// the nearest triangle of its own part.
    pub fn with_parts(
        predefined: Vec<u32>,
        overlaps: &[OverlapOrder],
        rest: &[DVec2],
        triangles: &[[u32; 3]],
        part_of: Vec<u32>,
    ) -> Self {
        let mut arranger = Self {
            predefined,
            topology: depth::Topology::new(rest, triangles),
            part_of: Some(part_of),
            regions: Vec::new(),
            pairs: depth::PairCache::default(),
        };
        arranger.restart(overlaps, rest, triangles);
        arranger
    }

    /// Each triangle's part, for a mesh of parts joined.
    pub fn part_of(&self) -> Option<&[u32]> {
        self.part_of.as_deref()
    }

    /// Takes another predefined order for the same mesh (new handle depths), keeping
    /// what it remembers.
    pub fn set_predefined(&mut self, predefined: Vec<u32>) {
        self.predefined = predefined;
    }

    /// Forgets the last pose's regions and starts the next arrangement from the
    /// orders `overlaps` saved (each sheet by the triangle whose rest centroid is
    /// nearest its place).
    pub fn restart(&mut self, overlaps: &[OverlapOrder], rest: &[DVec2], triangles: &[[u32; 3]]) {
        if overlaps.is_empty() {
            self.regions.clear();
            return;
        }
        let centroids = centroids(rest, triangles);
        let part_of = self.part_of.as_deref();
        let nearest = |place: &Place| {
            let at = DVec2::from(place.at);
            let on_part = |t: &u32| match (part_of, place.part) {
                (Some(parts), Some(part)) => parts[*t as usize] as usize == part,
                _ => true,
            };
            (0..centroids.len() as u32)
                .filter(on_part)
                .min_by(|&a, &b| {
                    let d = |t: u32| centroids[t as usize].distance_squared(at);
                    d(a).total_cmp(&d(b))
                })
        };
        self.regions = overlaps
            .iter()
            .filter_map(|o| {
                Some(depth::Region {
                    front: vec![nearest(&o.front)?],
                    back: vec![nearest(&o.back)?],
                })
            })
            .collect();
    }

    /// The triangles (indices) back to front for the mesh warped to `deformed`,
    /// remembering its regions for the next pose. Positions that are not finite
    /// leave the predefined order (and nothing is remembered).
    pub fn arrange(&mut self, deformed: &[DVec2], triangles: &[[u32; 3]]) -> Vec<u32> {
        if deformed.iter().any(|p| !p.is_finite()) {
            self.regions.clear();
            return self.predefined.clone();
        }
        let arranged = depth::arrange_cached(
            Some(&self.topology),
            Some(&mut self.pairs),
            deformed,
            triangles,
            &self.predefined,
            &self.regions,
        );
        self.regions = arranged.regions;
        arranged.order
    }

    /// The overlap regions of the pose last arranged.
    pub fn regions(&self) -> &[depth::Region] {
        &self.regions
    }

    /// The regions' orders as a rig file keeps them: the rest centroid of one triangle
    /// of each sheet, one that lies in no other sheet where the sheet has one. (A
    /// triangle can lie in two regions — the middle of three layers is in front of one
    /// and behind the other — and a reopened pose, remembering one triangle a sheet,
    /// would count such a triangle for both regions and could turn one of them over.)
    pub fn overlaps(&self, rest: &[DVec2], triangles: &[[u32; 3]]) -> Vec<OverlapOrder> {
        let mut sheets_of: std::collections::HashMap<u32, u32> = Default::default();
        for region in &self.regions {
            for &t in region.front.iter().chain(&region.back) {
                *sheets_of.entry(t).or_default() += 1;
            }
        }
        let place = |sheet: &[u32]| {
            let own = sheet.iter().find(|t| sheets_of.get(t) == Some(&1));
            own.or(sheet.first()).map(|&t| {
                let [a, b, c] = triangles[t as usize].map(|v| rest[v as usize]);
                let at = (a + b + c) / 3.0;
                Place {
                    at: [at.x, at.y],
                    part: self.part_of.as_ref().map(|p| p[t as usize] as usize),
                }
            })
        };
        self.regions
            .iter()
            .filter_map(|r| {
                Some(OverlapOrder {
                    front: place(&r.front)?,
                    back: place(&r.back)?,
                })
            })
            .collect()
    }
}

/// Each triangle's centroid.
fn centroids(rest: &[DVec2], triangles: &[[u32; 3]]) -> Vec<DVec2> {
    triangles
        .iter()
        .map(|t| t.iter().map(|&v| rest[v as usize]).sum::<DVec2>() / 3.0)
        .collect()
}

/// `order` (triangle indices) as the triangles themselves.
pub fn as_triangles(order: &[u32], triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
    order.iter().map(|&t| triangles[t as usize]).collect()
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

    #[test]
    fn a_saved_sheet_is_named_by_a_triangle_of_its_own_region_alone() {
        // Two regions between the same two sheets, in opposite orders (a tail over the
        // body here, under it there), sharing triangles 1 and 10: saved by those, a
        // reopened pose would find region 2's places in region 1's sheets turned over,
        // count them against region 1's own, and could turn region 1 over.
        let rig = strip_rig();
        let (rest, triangles) = (rig.domain().positions(), rig.domain().triangles());
        let mut arranger = Arranger::new((0..40).collect(), &[], rest, triangles);
        arranger.regions = vec![
            depth::Region {
                front: vec![1, 2, 3],
                back: vec![10, 11],
            },
            depth::Region {
                front: vec![10, 12],
                back: vec![1, 4],
            },
        ];
        let at = |t: usize| {
            let c = triangles[t].map(|v| rest[v as usize]);
            let at = (c[0] + c[1] + c[2]) / 3.0;
            [at.x, at.y]
        };
        let saved = arranger.overlaps(rest, triangles);
        let named: Vec<[[f64; 2]; 2]> = saved.iter().map(|o| [o.front.at, o.back.at]).collect();
        assert_eq!(named, [[at(2), at(11)], [at(12), at(4)]]);
        // A sheet all of whose triangles lie in another region too: its first.
        arranger.regions[1].front = vec![10];
        let saved = arranger.overlaps(rest, triangles);
        assert_eq!(saved[1].front.at, at(10));
        assert_eq!(saved[0].back.at, at(11));
    }
}
