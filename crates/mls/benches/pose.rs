//! Criterion benchmarks of one pose ([`Mls::deform`], the per-frame cost of a drag)
//! and of the precomputation ([`Mls::new`], paid when handles are added, removed or
//! the options change), on the vertices of a long-limbed figure (a body and five thin
//! limbs, filled to about 20k and 100k vertices) with 10 handles: spread over the
//! figure (ten points; seven points and three bars along limbs) and clustered (ten
//! points on one hand). Every variant; α = 1.

#[path = "../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use mls::{Control, Mls, MlsOptions, Variant};
use support::{Rng, VARIANTS};

const SIZES: [usize; 2] = [20_000, 100_000];

/// A figure of 700 × 900 px: a disc (the body) and five limbs, each a thin strip
/// from the body outwards, as segments `(from, to, half width)`.
const LIMBS: [([f64; 2], [f64; 2], f64); 5] = [
    ([350.0, 300.0], [350.0, 60.0], 30.0),  // neck and head
    ([300.0, 380.0], [40.0, 520.0], 14.0),  // left arm
    ([400.0, 380.0], [660.0, 300.0], 14.0), // right arm
    ([320.0, 520.0], [200.0, 880.0], 20.0), // left leg
    ([380.0, 520.0], [520.0, 880.0], 20.0), // right leg
];
const BODY: ([f64; 2], f64) = ([350.0, 430.0], 120.0);

fn inside(p: DVec2) -> bool {
    let (c, r) = BODY;
    if p.distance(DVec2::from(c)) <= r {
        return true;
    }
    LIMBS.iter().any(|(a, b, w)| {
        let (a, b) = (DVec2::from(*a), DVec2::from(*b));
        let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        p.distance(a.lerp(b, t)) <= *w
    })
}

/// `n` vertices spread uniformly over the figure (rejection sampling).
fn figure(n: usize, seed: u64) -> Vec<DVec2> {
    let mut rng = Rng(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = rng.point(700.0, 900.0);
        if inside(p) {
            out.push(p);
        }
    }
    out
}

fn limb_point(limb: usize, t: f64) -> DVec2 {
    let (a, b, _) = LIMBS[limb];
    DVec2::from(a).lerp(DVec2::from(b), t)
}

/// Ten handles in three layouts, at rest.
fn layouts() -> [(&'static str, Vec<Control>); 3] {
    let mut spread: Vec<Control> = (0..5)
        .flat_map(|limb| {
            [
                Control::Point(limb_point(limb, 0.35)),
                Control::Point(limb_point(limb, 0.95)),
            ]
        })
        .collect();
    spread.truncate(10);
    let mut mixed: Vec<Control> = (0..5)
        .map(|limb| Control::Point(limb_point(limb, 0.95)))
        .collect();
    mixed.push(Control::Point(DVec2::from(BODY.0)));
    mixed.push(Control::Point(DVec2::from(BODY.0) + DVec2::new(0.0, 60.0)));
    mixed.extend((0..3).map(|limb| Control::Bar([limb_point(limb, 0.2), limb_point(limb, 0.7)])));
    let hand = limb_point(1, 1.0);
    let clustered: Vec<Control> = (0..10)
        .map(|i| Control::Point(hand + DVec2::from_angle(i as f64 * 0.63) * (6.0 + 2.0 * i as f64)))
        .collect();
    [
        ("spread", spread),
        ("bars", mixed),
        ("clustered", clustered),
    ]
}

/// The rest controls with the first moved 80 px and turned about the figure.
fn posed(rest: &[Control]) -> Vec<Control> {
    let turn = DVec2::from_angle(0.2);
    let centre = DVec2::from(BODY.0);
    rest.iter()
        .enumerate()
        .map(|(i, c)| {
            let f = |p: DVec2| {
                if i == 0 {
                    p + DVec2::new(80.0, -40.0)
                } else {
                    centre + turn.rotate(p - centre)
                }
            };
            match *c {
                Control::Point(p) => Control::Point(f(p)),
                Control::Bar([a, b]) => Control::Bar([f(a), f(b)]),
            }
        })
        .collect()
}

fn name(variant: Variant) -> &'static str {
    match variant {
        Variant::Affine => "affine",
        Variant::Similarity => "similarity",
        Variant::Rigid => "rigid",
    }
}

fn pose(c: &mut Criterion) {
    let mut group = c.benchmark_group("pose");
    for n in SIZES {
        let vertices = figure(n, 7);
        let mut out = vec![DVec2::ZERO; n];
        for (layout, rest) in layouts() {
            let posed = posed(&rest);
            for variant in VARIANTS {
                let options = MlsOptions {
                    alpha: 1.0,
                    variant,
                };
                let mls = Mls::new(&vertices, &rest, &options).expect("valid scene");
                group.bench_function(format!("{}/{layout}/{n}", name(variant)), |b| {
                    b.iter(|| {
                        mls.deform(black_box(&posed), black_box(&mut out))
                            .expect("valid pose")
                    })
                });
            }
        }
    }
    group.finish();
}

fn precompute(c: &mut Criterion) {
    let mut group = c.benchmark_group("precompute");
    group.sample_size(10);
    for n in SIZES {
        let vertices = figure(n, 7);
        for (layout, rest) in layouts() {
            let options = MlsOptions::default();
            group.bench_function(format!("rigid/{layout}/{n}"), |b| {
                b.iter(|| {
                    Mls::new(black_box(&vertices), black_box(&rest), &options).expect("valid scene")
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, pose, precompute);
criterion_main!(benches);
