//! The cages the solver is timed on: the sizes of the paper's Table 2 (26 cage
//! vertices on about 6,000 mesh vertices, 27 on 12,900, 34 on 11,600), on shapes with
//! long limbs, where geodesic and Euclidean distances differ most.

use glam::DVec2;
use lbc::{Cage, Domain};

/// One timing case.
pub struct Case {
    /// A short name.
    pub name: &'static str,
    /// The cage.
    pub cage: Cage,
    /// Target mesh vertex count.
    pub target: usize,
}

/// A standing figure, arms out: 26 vertices.
fn figure() -> Vec<DVec2> {
    let right = [
        (5.0, 22.0),
        (8.0, 0.0),
        (22.0, 0.0),
        (20.0, 30.0),
        (16.0, 60.0),
        (18.0, 95.0),
        (50.0, 100.0),
        (52.0, 112.0),
        (18.0, 118.0),
        (8.0, 122.0),
        (12.0, 135.0),
        (8.0, 148.0),
    ];
    let mut v = vec![DVec2::new(0.0, 45.0)];
    v.extend(right.iter().map(|&(x, y)| DVec2::new(x, y)));
    v.push(DVec2::new(0.0, 152.0));
    v.extend(right.iter().rev().map(|&(x, y)| DVec2::new(-x, y)));
    v
}

/// A starfish of nine arms: 27 vertices (a notch and the two corners of each tip).
fn starfish() -> Vec<DVec2> {
    (0..9)
        .flat_map(|k| {
            let a = f64::from(k) / 9.0 * std::f64::consts::TAU;
            let step = std::f64::consts::TAU / 9.0;
            [
                DVec2::from_angle(a) * 30.0,
                DVec2::from_angle(a + 0.38 * step) * 100.0,
                DVec2::from_angle(a + 0.62 * step) * 100.0,
            ]
        })
        .collect()
}

/// A snake: a wavy band, 17 vertices along each side, 34 in all.
fn snake() -> Vec<DVec2> {
    let centre = |t: f64| DVec2::new(t * 300.0, 40.0 * (t * 9.0).sin());
    let half_width = |t: f64| 6.0 + 10.0 * (1.0 - (2.0 * t - 1.0).powi(2));
    let side = |sign: f64| -> Vec<DVec2> {
        (0..17)
            .map(|k| {
                let t = f64::from(k) / 16.0;
                let tangent = (centre(t + 1e-4) - centre(t - 1e-4)).normalize();
                centre(t) + sign * half_width(t) * tangent.perp()
            })
            .collect()
    };
    let mut v = side(-1.0);
    v.extend(side(1.0).into_iter().rev());
    v
}

/// The three cases.
pub fn cases() -> Vec<Case> {
    let make = |name, points, target| Case {
        name,
        cage: Cage::new(points).expect("a simple polygon"),
        target,
    };
    vec![
        make("figure-26", figure(), 6_069),
        make("starfish-27", starfish(), 12_862),
        make("snake-34", snake(), 11_554),
    ]
}

/// The case's triangulated inside.
#[allow(dead_code)] // The example triangulates to a count of its own.
pub fn domain(case: &Case) -> Domain {
    Domain::triangulate(&case.cage, case.target).expect("triangulates")
}
