//! The ARAP paper's Fig. 8 set-up and a limb swung across the body and back, drawn
//! with and without automatic depth adjustment.

use depth::{Region, arrange};
use glam::DVec2;

/// A mesh built of pieces, each a grid of unit cells `length × width` in its own
/// coordinates `(u, v)`, placed by a map into the plane.
#[derive(Default)]
struct Scene {
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    /// For each triangle, its piece and its cell's `u`.
    owner: Vec<(usize, f64)>,
    pieces: usize,
}

impl Scene {
    /// Adds a piece; returns its index.
    fn piece(&mut self, length: u32, width: u32, place: impl Fn(f64, f64) -> DVec2) -> usize {
        let base = self.positions.len() as u32;
        for v in 0..=width {
            for u in 0..=length {
                self.positions.push(place(f64::from(u), f64::from(v)));
            }
        }
        let at = |u: u32, v: u32| base + v * (length + 1) + u;
        for v in 0..width {
            for u in 0..length {
                let (a, b, c, d) = (at(u, v), at(u + 1, v), at(u + 1, v + 1), at(u, v + 1));
                self.triangles.push([a, b, c]);
                self.triangles.push([a, c, d]);
                let middle = f64::from(u) + 0.5;
                self.owner.push((self.pieces, middle));
                self.owner.push((self.pieces, middle));
            }
        }
        self.pieces += 1;
        self.pieces - 1
    }

    /// Moves a piece's vertices by `place` again (same grid).
    fn replace(
        &mut self,
        first_vertex: usize,
        length: u32,
        width: u32,
        place: impl Fn(f64, f64) -> DVec2,
    ) {
        let mut k = first_vertex;
        for v in 0..=width {
            for u in 0..=length {
                self.positions[k] = place(f64::from(u), f64::from(v));
                k += 1;
            }
        }
    }

    /// The triangles (indices) of `piece` whose `u` satisfies `keep`.
    fn of(&self, piece: usize, keep: impl Fn(f64) -> bool) -> Vec<u32> {
        (0..self.triangles.len() as u32)
            .filter(|&t| {
                let (p, u) = self.owner[t as usize];
                p == piece && keep(u)
            })
            .collect()
    }
}

/// Where each triangle is drawn in `order`.
fn places(order: &[u32]) -> Vec<usize> {
    let mut at = vec![0; order.len()];
    for (i, &t) in order.iter().enumerate() {
        at[t as usize] = i;
    }
    at
}

/// The triangle pairs of pieces `p` and `q` that overlap, by brute force.
fn overlapping(scene: &Scene, p: usize, q: usize) -> Vec<(u32, u32)> {
    let corners = |t: u32| scene.triangles[t as usize].map(|v| scene.positions[v as usize]);
    let inside = |x: DVec2, t: [DVec2; 3]| {
        let s = |a: DVec2, b: DVec2| (b - a).perp_dot(x - a);
        let (d0, d1, d2) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
        (d0 > 0.0 && d1 > 0.0 && d2 > 0.0) || (d0 < 0.0 && d1 < 0.0 && d2 < 0.0)
    };
    let mut pairs = Vec::new();
    for s in scene.of(p, |_| true) {
        for t in scene.of(q, |_| true) {
            let (a, b) = (corners(s), corners(t));
            let centroid = |x: [DVec2; 3]| (x[0] + x[1] + x[2]) / 3.0;
            // Unit cells against unit cells: overlapping ones hold one another's
            // centroid or a point near it.
            let probe = |x: [DVec2; 3], y: [DVec2; 3]| {
                (0..3).any(|i| inside(x[i] * 0.9 + centroid(x) * 0.1, y)) || inside(centroid(x), y)
            };
            if probe(a, b) || probe(b, a) {
                pairs.push((s, t));
            }
        }
    }
    pairs
}

/// Whether piece `p` is drawn wholly in front of (`Some(true)`), wholly behind
/// (`Some(false)`) or partly in front and partly behind (`None`) piece `q` where
/// they overlap; `Some(true)` also where they do not overlap.
fn in_front(scene: &Scene, order: &[u32], p: usize, q: usize) -> Option<bool> {
    let at = places(order);
    let pairs = overlapping(scene, p, q);
    let ahead = pairs
        .iter()
        .filter(|&&(s, t)| at[s as usize] > at[t as usize])
        .count();
    match ahead {
        a if a == pairs.len() => Some(true),
        0 => Some(false),
        _ => None,
    }
}

/// The paper's Fig. 8 set-up: a strip 20 × 2 whose predefined depth rises along it
/// (its left half behind, its right half in front), and a bar 3 × 12 whose depth lies
/// between, laid across the strip from `x` on. Returns the scene, the strip, the bar
/// and the predefined order.
fn figure_8(x: f64) -> (Scene, usize, usize, Vec<u32>) {
    let mut scene = Scene::default();
    let strip = scene.piece(20, 2, DVec2::new);
    let bar = scene.piece(2, 12, |u, v| DVec2::new(x + u * 1.5, v - 5.0));
    let mut predefined = scene.of(strip, |u| u < 10.0);
    predefined.extend(scene.of(bar, |_| true));
    predefined.extend(scene.of(strip, |u| u > 10.0));
    (scene, strip, bar, predefined)
}

#[test]
fn figure_8_a_region_brought_between_two_depths_is_drawn_wholly_on_one_side() {
    // A strip whose depth rises along it (its left half behind, its right half in
    // front), and a bar whose depth lies between, laid across the strip where the
    // two halves meet, mostly over the left half.
    let (mut scene, strip, bar, predefined) = figure_8(7.5);
    assert_eq!(predefined.len(), scene.triangles.len());
    // Drawn in the predefined order, the bar is partly in front and partly behind.
    assert_eq!(in_front(&scene, &predefined, bar, strip), None);
    let arranged = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert_eq!(
        in_front(&scene, &arranged.order, bar, strip),
        Some(true),
        "the bar lies mostly over the strip's back half"
    );
    assert_eq!(arranged.regions.len(), 1);
    // A permutation, and the triangles that overlap nothing keep their places.
    let mut sorted = arranged.order.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..scene.triangles.len() as u32).collect::<Vec<_>>()
    );
    let region = &arranged.regions[0];
    for (i, &t) in predefined.iter().enumerate() {
        if !region.front.contains(&t) && !region.back.contains(&t) {
            assert_eq!(arranged.order[i], t);
        }
    }
    // Moved over the front half instead, the bar goes wholly behind.
    let first_bar_vertex = 21 * 3;
    scene.replace(first_bar_vertex, 2, 12, |u, v| {
        DVec2::new(9.5 + u * 1.5, v - 5.0)
    });
    let arranged = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert_eq!(in_front(&scene, &arranged.order, bar, strip), Some(false));
}

#[test]
fn a_limb_swung_across_the_body_and_back_keeps_its_order_while_it_overlaps() {
    // A square body and a limb pivoting at a corner outside it. The limb's far end
    // is predefined in front of the body, the rest behind (a hand's handle in front,
    // an elbow's behind): the far end reaches the body first, so the limb goes in
    // front, and stays there as the swing lays its near part over the body.
    let mut scene = Scene::default();
    let body = scene.piece(10, 10, DVec2::new);
    let pivot = DVec2::new(-4.0, -4.0);
    let limb_at = |angle: f64| {
        move |u: f64, v: f64| {
            let along = DVec2::from_angle(angle.to_radians());
            pivot + along * u + along.perp() * (v - 1.0)
        }
    };
    let first_limb_vertex = scene.positions.len();
    let limb = scene.piece(14, 2, limb_at(-10.0));
    let mut predefined = scene.of(limb, |u| u < 11.0);
    predefined.extend(scene.of(body, |_| true));
    predefined.extend(scene.of(limb, |u| u > 11.0));
    let angles: Vec<f64> = (-10..=45).chain((-10..45).rev()).map(f64::from).collect();
    let mut remembered: Vec<Region> = Vec::new();
    let (mut kept, mut fresh) = (Vec::new(), Vec::new());
    let topology = depth::Topology::new(&scene.positions, &scene.triangles);
    for &angle in &angles {
        scene.replace(first_limb_vertex, 14, 2, limb_at(angle));
        // The shortcut for poses without overlaps never misses one.
        let (p, t) = (&scene.positions, &scene.triangles);
        assert_eq!(
            depth::arrange_on(Some(&topology), p, t, &predefined, &remembered),
            arrange(p, t, &predefined, &remembered),
            "at {angle}°"
        );
        if overlapping(&scene, limb, body).is_empty() {
            remembered.clear();
            continue;
        }
        let arranged = arrange(&scene.positions, &scene.triangles, &predefined, &remembered);
        kept.push((angle, in_front(&scene, &arranged.order, limb, body)));
        remembered = arranged.regions;
        let alone = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
        fresh.push((angle, in_front(&scene, &alone.order, limb, body)));
    }
    assert!(!kept.is_empty());
    for &(angle, front) in &kept {
        assert_eq!(front, Some(true), "at {angle}°: {kept:?}");
    }
    // Decided afresh at every pose, the order flips half-way.
    assert!(
        fresh.iter().any(|&(_, f)| f == Some(false)),
        "the set-up must make a fresh decision flip: {fresh:?}"
    );
    // Without the predefined order's help: the same swing with the limb wholly
    // behind at first stays behind.
    let behind: Vec<u32> = scene
        .of(limb, |_| true)
        .into_iter()
        .chain(scene.of(body, |_| true))
        .collect();
    let mut remembered: Vec<Region> = Vec::new();
    for &angle in &angles {
        scene.replace(first_limb_vertex, 14, 2, limb_at(angle));
        let arranged = arrange(&scene.positions, &scene.triangles, &behind, &remembered);
        // Where they do not overlap there is nothing to order (`Some(true)`).
        let expected = if overlapping(&scene, limb, body).is_empty() {
            Some(true)
        } else {
            Some(false)
        };
        assert_eq!(
            in_front(&scene, &arranged.order, limb, body),
            expected,
            "at {angle}°"
        );
        remembered = arranged.regions;
    }
}

#[test]
fn a_saved_region_given_by_one_triangle_a_side_keeps_its_order() {
    // The Fig. 8 bar over the strip's front half: alone it goes behind; remembered in
    // front by one triangle of each sheet, it stays in front.
    let (scene, strip, bar, predefined) = figure_8(9.5);
    let alone = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert_eq!(in_front(&scene, &alone.order, bar, strip), Some(false));
    let region = &alone.regions[0];
    let saved = [Region {
        front: vec![region.back[0]],
        back: vec![region.front[0]],
    }];
    let kept = arrange(&scene.positions, &scene.triangles, &predefined, &saved);
    assert_eq!(in_front(&scene, &kept.order, bar, strip), Some(true));
}

#[test]
fn no_overlap_keeps_the_predefined_order_and_three_sheets_in_a_cycle_are_drawn() {
    let mut scene = Scene::default();
    scene.piece(4, 4, DVec2::new);
    scene.piece(4, 4, |u, v| DVec2::new(u + 10.0, v));
    let predefined: Vec<u32> = (0..scene.triangles.len() as u32).rev().collect();
    let arranged = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert_eq!(arranged.order, predefined);
    assert!(arranged.regions.is_empty());
    // Three bars woven over and under one another, remembered so.
    let mut scene = Scene::default();
    let a = scene.piece(12, 1, |u, v| DVec2::new(u, v + 2.0));
    let b = scene.piece(12, 1, |u, v| {
        DVec2::new(6.0, 6.0)
            + DVec2::from_angle(2.1) * (u - 6.0)
            + DVec2::from_angle(2.1).perp() * v
    });
    let c = scene.piece(12, 1, |u, v| {
        DVec2::new(6.0, 6.0)
            + DVec2::from_angle(-2.1) * (u - 6.0)
            + DVec2::from_angle(-2.1).perp() * v
    });
    let predefined: Vec<u32> = (0..scene.triangles.len() as u32).collect();
    let first = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert_eq!(first.regions.len(), 3, "{:?}", first.regions);
    // Turn each region's order so that a > b > c > a.
    let set = |p: usize| scene.of(p, |_| true);
    let cycle: Vec<Region> = first
        .regions
        .iter()
        .map(|r| {
            let holds = |p: usize| set(p).contains(&r.front[0]) || set(p).contains(&r.back[0]);
            let (front, back) = if holds(a) && holds(b) {
                (a, b)
            } else if holds(b) && holds(c) {
                (b, c)
            } else {
                (c, a)
            };
            Region {
                front: set(front),
                back: set(back),
            }
        })
        .collect();
    let woven = arrange(&scene.positions, &scene.triangles, &predefined, &cycle);
    let mut sorted = woven.order.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, predefined, "every triangle drawn once");
}

#[test]
fn the_arrangement_is_a_function_of_the_pose_alone() {
    // A strip wound into a spiral, each turn over the one before.
    let mut scene = Scene::default();
    scene.piece(120, 2, |u, v| {
        let angle = u * 0.12;
        let radius = 4.0 + u * 0.02 + v;
        DVec2::new(radius * angle.cos(), radius * angle.sin())
    });
    let predefined: Vec<u32> = (0..scene.triangles.len() as u32).collect();
    let first = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
    assert!(!first.regions.is_empty());
    for _ in 0..8 {
        let again = arrange(&scene.positions, &scene.triangles, &predefined, &[]);
        assert_eq!(again, first);
        let kept = arrange(
            &scene.positions,
            &scene.triangles,
            &predefined,
            &first.regions,
        );
        assert_eq!(kept.order, first.order);
    }
}
