//! Handles closer together than the mesh's spacing, and the points the picture's mesh
//! is refined with around them: the C² paper's dynamic up-sampling (§IV-A: "an
//! up-sampling step is required … when there is no point between two handles on the
//! mesh"), done so that any two handles farther apart than a millionth of a pixel can
//! be placed at any density.
//!
//! The refinement is a function of the rig file alone (the handles' rest geometry, the
//! picture's size and the density), so the editor's mesh, a reopened project's and
//! `c2warp render`'s are the same; it adds vertices only near crowded handles and
//! leaves every lattice vertex away from them where it was (see
//! [`mesh::MeshOptions::refine`]).

use glam::DVec2;
use project::{HandleSpec, Project};

/// Two handles closer than this many of the mesh's spacings are crowded: nodes a
/// spacing or two apart leave no room for the virtual handles graded between them (and
/// closer, both take the same vertex).
const CROWDED: f64 = 2.0;

/// Points on each ring around a crowded pair: with rings [`RING_RATIO`] apart, the
/// triangles between two rings are about as wide as they are deep, so that the mesh's
/// paths measure distances there nearly straight (the intrinsic metric's), as
/// Algorithm 1's graded virtual handles need.
const RING_POINTS: usize = 16;

/// Each ring's radius over the last's.
const RING_RATIO: f64 = 1.4;

/// Handles closer than this (pixels) are the same place: refused, not refined.
pub use weights_core::COINCIDENT;

/// The largest spacing of a `width × height` picture meshed at `target` vertices (its
/// whole rectangle's; a cut-out's lattice is finer).
pub fn spacing(width: u32, height: u32, target: usize) -> f64 {
    let area = f64::from(width) * f64::from(height);
    (2.0 * area / (3f64.sqrt() * target.max(1) as f64)).sqrt()
}

/// The points `project`'s picture (`width × height`, meshed at `target` vertices) is
/// refined with: for every pair of handles closer than two of the mesh's spacings, the
/// nearest points of the two (each a vertex, so each handle has its own sample) and
/// rings of [`RING_POINTS`] points around their midpoint at radii of their distance,
/// [`RING_RATIO`] times it, its square times it, … up to two spacings, so that the
/// samples go from the pair's spacing to the mesh's in small steps, as Algorithm 1's
/// graded virtual handles need.
/// Pairs closer than [`COINCIDENT`] are left alone (the rig refuses them). Points
/// closer to one already listed than a quarter of their ring's step are left out, so
/// rings of neighbouring pairs do not crowd each other; points off the picture too.
pub fn refinement(project: &Project, width: u32, height: u32, target: usize) -> Vec<DVec2> {
    let s = spacing(width, height, target);
    let reach = CROWDED * s;
    let shapes: Vec<[DVec2; 2]> = project.handles.iter().map(segment).collect();
    let mut points = Points::new(reach);
    let pairs: Vec<(DVec2, DVec2)> = crowded_pairs(&shapes, reach)
        .into_iter()
        .map(|(i, j)| closest_points(shapes[i], shapes[j]))
        .filter(|(a, b)| a.distance(*b) >= COINCIDENT)
        .collect();
    // The handles' own places first, so no ring point crowds one.
    for &(a, b) in &pairs {
        points.add(a, 0.0);
        points.add(b, 0.0);
    }
    for &(a, b) in &pairs {
        let d = a.distance(b);
        let centre = (a + b) * 0.5;
        let mut r = d;
        let mut k = 0;
        while r < reach {
            let turn = std::f64::consts::TAU / RING_POINTS as f64;
            // Each ring half a step turned from the last.
            let offset = 0.5 * turn * (k % 2) as f64;
            for n in 0..RING_POINTS {
                let angle = offset + turn * n as f64;
                points.add(centre + DVec2::from_angle(angle) * r, 0.25 * r);
            }
            r *= RING_RATIO;
            k += 1;
        }
    }
    let (w, h) = (f64::from(width), f64::from(height));
    points
        .list
        .into_iter()
        .filter(|p| p.x >= 0.0 && p.y >= 0.0 && p.x <= w && p.y <= h)
        .collect()
}

/// A handle's rest geometry as a segment (a point's: both ends the same).
fn segment(h: &HandleSpec) -> [DVec2; 2] {
    match *h {
        HandleSpec::Point { rest, .. } => [DVec2::from(rest); 2],
        HandleSpec::Bar { rest, .. } => rest.map(DVec2::from),
    }
}

/// The pairs `(i, j)`, `i < j`, of `shapes` closer than `reach`, in order, found
/// through a grid of cells `reach` wide.
fn crowded_pairs(shapes: &[[DVec2; 2]], reach: f64) -> Vec<(usize, usize)> {
    if !(reach.is_finite() && reach > 0.0) || shapes.iter().flatten().any(|p| !p.is_finite()) {
        return Vec::new();
    }
    let cell = |p: DVec2| ((p.x / reach).floor() as i64, (p.y / reach).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (i, s) in shapes.iter().enumerate() {
        let (lo, hi) = (cell(s[0].min(s[1])), cell(s[0].max(s[1])));
        // A bar across very many cells is listed in its bounding box's cells, at most a
        // few thousand of them (a longer one is checked against every handle).
        if (hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1) > 4096 {
            grid.entry((i64::MIN, i64::MIN)).or_default().push(i);
            continue;
        }
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                grid.entry((x, y)).or_default().push(i);
            }
        }
    }
    let everywhere = grid.get(&(i64::MIN, i64::MIN)).cloned().unwrap_or_default();
    let mut pairs = std::collections::BTreeSet::new();
    for (i, s) in shapes.iter().enumerate() {
        let (lo, hi) = (cell(s[0].min(s[1])), cell(s[0].max(s[1])));
        let mut near: Vec<usize> = everywhere.clone();
        if (hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1) > 4096 {
            near.extend(0..shapes.len());
        } else {
            for x in lo.0 - 1..=hi.0 + 1 {
                for y in lo.1 - 1..=hi.1 + 1 {
                    near.extend(grid.get(&(x, y)).into_iter().flatten());
                }
            }
        }
        for j in near {
            if j > i {
                let (a, b) = closest_points(*s, shapes[j]);
                if a.distance(b) < reach {
                    pairs.insert((i, j));
                }
            }
        }
    }
    pairs.into_iter().collect()
}

/// The nearest points of segments `s` and `t` (either may be a point).
fn closest_points(s: [DVec2; 2], t: [DVec2; 2]) -> (DVec2, DVec2) {
    let on = |p: DVec2, seg: [DVec2; 2]| {
        let d = seg[1] - seg[0];
        let len2 = d.length_squared();
        if len2 == 0.0 {
            return seg[0];
        }
        seg[0] + d * ((p - seg[0]).dot(d) / len2).clamp(0.0, 1.0)
    };
    if geometry::segments_touch(s[0], s[1], t[0], t[1]) && s[0] != s[1] && t[0] != t[1] {
        // Crossing bars: the crossing (found by the nearest of the ends below is not
        // it), taken as both points' place.
        let (d1, d2) = (s[1] - s[0], t[1] - t[0]);
        let denom = d1.perp_dot(d2);
        if denom != 0.0 {
            let u = (t[0] - s[0]).perp_dot(d2) / denom;
            let x = s[0] + d1 * u.clamp(0.0, 1.0);
            return (x, x);
        }
    }
    [
        (s[0], on(s[0], t)),
        (s[1], on(s[1], t)),
        (on(t[0], s), t[0]),
        (on(t[1], s), t[1]),
    ]
    .into_iter()
    .min_by(|x, y| x.0.distance(x.1).total_cmp(&y.0.distance(y.1)))
    .unwrap_or((s[0], t[0]))
}

/// Refinement points, each kept clear of those before it.
struct Points {
    list: Vec<DVec2>,
    /// Indices into `list` by cell of `cell` pixels.
    grid: std::collections::HashMap<(i64, i64), Vec<usize>>,
    cell: f64,
}

impl Points {
    fn new(reach: f64) -> Self {
        Self {
            list: Vec::new(),
            grid: Default::default(),
            cell: (reach * 0.5).max(1e-9),
        }
    }

    /// Adds `p` unless it is within `clearance` of a point already listed (a point of
    /// clearance 0 is left out only where the very same point is listed).
    fn add(&mut self, p: DVec2, clearance: f64) {
        let at = |q: DVec2, c: f64| ((q.x / c).floor() as i64, (q.y / c).floor() as i64);
        let (cx, cy) = at(p, self.cell);
        let span = (clearance / self.cell).ceil() as i64;
        for x in cx - span..=cx + span {
            for y in cy - span..=cy + span {
                if let Some(near) = self.grid.get(&(x, y))
                    && near.iter().any(|&k| {
                        let d = self.list[k].distance(p);
                        d == 0.0 || d < clearance
                    })
                {
                    return;
                }
            }
        }
        self.grid.entry((cx, cy)).or_default().push(self.list.len());
        self.list.push(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64) -> HandleSpec {
        HandleSpec::Point {
            rest: [x, y],
            translate: [0.0; 2],
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        }
    }

    #[test]
    fn only_crowded_handles_refine_and_rings_grow_by_two() {
        let mut project = Project {
            handles: vec![point(10.0, 10.0), point(200.0, 200.0)],
            ..Project::default()
        };
        // 400 × 400 at 20,000 vertices: a spacing of about 3.3 px.
        assert!(refinement(&project, 400, 400, 20_000).is_empty());
        project.handles.push(point(200.5, 200.0));
        let points = refinement(&project, 400, 400, 20_000);
        // Both handles, and rings from 0.5 px growing by RING_RATIO up to two spacings.
        assert!(points.contains(&DVec2::new(200.0, 200.0)));
        assert!(points.contains(&DVec2::new(200.5, 200.0)));
        let centre = DVec2::new(200.25, 200.0);
        let radii: Vec<u64> = points
            .iter()
            .skip(2)
            .map(|p| (p.distance(centre) * 1000.0).round() as u64)
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        let reach = CROWDED * spacing(400, 400, 20_000);
        let expected: Vec<u64> = std::iter::successors(Some(0.5), |r| Some(r * RING_RATIO))
            .take_while(|&r| r < reach)
            .map(|r| (r * 1000.0).round() as u64)
            .collect();
        assert_eq!(radii, expected);
        assert_eq!(points.len(), 2 + expected.len() * RING_POINTS);
        // The same file, the same points.
        assert_eq!(refinement(&project, 400, 400, 20_000), points);
        // Coincident handles are left to the rig to refuse.
        project.handles[2] = point(200.0, 200.0 + 1e-9);
        assert!(refinement(&project, 400, 400, 20_000).is_empty());
    }

    #[test]
    fn a_point_beside_a_bar_refines_at_its_foot() {
        let project = Project {
            handles: vec![
                HandleSpec::Bar {
                    rest: [[50.0, 50.0], [150.0, 50.0]],
                    pose: None,
                    depth: 0,
                },
                point(100.0, 51.0),
            ],
            ..Project::default()
        };
        let points = refinement(&project, 200, 100, 20_000);
        assert!(points.contains(&DVec2::new(100.0, 50.0)));
        assert!(points.contains(&DVec2::new(100.0, 51.0)));
    }
}
