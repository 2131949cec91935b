//! Test domains: jittered grids, convex and with holes and notches (shared by the
//! benchmarks).
#![allow(dead_code, missing_docs)]

use glam::DVec2;
use weights_core::{Domain, Metric};

/// A small deterministic generator (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Shapes of test domains.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// The full rectangle (convex, Euclidean).
    Rectangle,
    /// A rectangle with a rectangular hole and a notch cut from the top (intrinsic).
    Holed,
}

/// A grid of `nx × ny` cells of size `h` with interior vertices jittered by up to
/// `jitter·h`, two triangles per cell (diagonals mirrored about the vertical centre
/// line), cells removed according to `shape`. Unused vertices are dropped.
pub fn grid_domain(nx: usize, ny: usize, h: f64, jitter: f64, shape: Shape, seed: u64) -> Domain {
    let mut rng = Rng(seed);
    let mut positions = Vec::new();
    for y in 0..=ny {
        for x in 0..=nx {
            let mut p = DVec2::new(x as f64 * h, y as f64 * h);
            if x > 0 && y > 0 && x < nx && y < ny {
                p += DVec2::new(rng.unit() - 0.5, rng.unit() - 0.5) * (2.0 * jitter * h);
            }
            positions.push(p);
        }
    }
    let keep = |x: usize, y: usize| match shape {
        Shape::Rectangle => true,
        Shape::Holed => {
            let in_hole = x >= nx * 2 / 5 && x < nx * 3 / 5 && y >= ny * 2 / 5 && y < ny * 3 / 5;
            let in_notch = x >= nx / 5 && x < nx * 3 / 10 && y < ny / 2;
            !in_hole && !in_notch
        }
    };
    let triangles = grid_triangles(nx, ny, keep);
    compact(
        positions,
        triangles,
        match shape {
            Shape::Rectangle => Metric::Euclidean,
            Shape::Holed => Metric::Intrinsic,
        },
    )
}

/// Two triangles for every kept cell of an `nx × ny` grid of `(nx + 1) × (ny + 1)`
/// vertices (row-major), with diagonals mirrored about the vertical centre line.
pub fn grid_triangles(nx: usize, ny: usize, keep: impl Fn(usize, usize) -> bool) -> Vec<[u32; 3]> {
    let id = |x: usize, y: usize| (y * (nx + 1) + x) as u32;
    let mut triangles = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            if !keep(x, y) {
                continue;
            }
            let (a, b, c, d) = (id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1));
            if 2 * x < nx {
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            } else {
                triangles.push([a, b, d]);
                triangles.push([b, c, d]);
            }
        }
    }
    triangles
}

/// Drops unused vertices and renumbers.
pub fn compact(positions: Vec<DVec2>, triangles: Vec<[u32; 3]>, metric: Metric) -> Domain {
    let mut map = vec![u32::MAX; positions.len()];
    let mut kept = Vec::new();
    let triangles: Vec<[u32; 3]> = triangles
        .into_iter()
        .map(|t| {
            t.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = kept.len() as u32;
                    kept.push(positions[v as usize]);
                }
                map[v as usize]
            })
        })
        .collect();
    Domain::new(kept, triangles, metric).expect("valid test domain")
}

/// `domain` renumbered along a Z-order curve ([`Domain::in_local_order`]) if
/// `renumbered`, its ties broken by its numbering before; else as it is.
pub fn renumbered_if(domain: Domain, renumbered: bool) -> Domain {
    if !renumbered {
        return domain;
    }
    let positions = domain.positions().to_vec();
    let triangles = domain.triangles().to_vec();
    Domain::in_local_order(positions, triangles, domain.metric())
        .expect("a valid domain")
        .0
}
