//! Meshes made in code, a seeded generator, distortion measures and an independent
//! dense reference solver, shared by the integration tests and the benchmarks.
#![allow(dead_code)]

pub mod dense;

use glam::DVec2;

/// A rest mesh.
#[derive(Clone, Debug)]
pub struct MeshData {
    pub rest: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
}

/// SplitMix64: small, seeded, good enough for test data.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// How each grid cell is split into two triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Diagonals {
    /// Every cell along the same diagonal.
    Same,
    /// Mirror-symmetric about the vertical centre line (needs an even `nx`).
    Mirrored,
    /// Alternating like a union jack.
    Alternating,
}

/// A grid of `nx × ny` square cells of side `h` starting at the origin; interior
/// vertices jittered by up to `jitter · h` in each coordinate.
pub fn grid(
    nx: usize,
    ny: usize,
    h: f64,
    jitter: f64,
    diagonals: Diagonals,
    seed: u64,
) -> MeshData {
    let mut rng = Rng(seed);
    let mut rest = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            let mut p = DVec2::new(i as f64 * h, j as f64 * h);
            if i > 0 && i < nx && j > 0 && j < ny && jitter > 0.0 {
                p += DVec2::new(rng.range(-jitter, jitter), rng.range(-jitter, jitter)) * h;
            }
            rest.push(p);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            let slash = match diagonals {
                Diagonals::Same => true,
                Diagonals::Mirrored => 2 * i < nx,
                Diagonals::Alternating => (i + j) % 2 == 0,
            };
            if slash {
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            } else {
                triangles.push([a, b, d]);
                triangles.push([b, c, d]);
            }
        }
    }
    MeshData { rest, triangles }
}

/// Keeps the triangles whose centroid `keep` accepts and drops unused vertices
/// (renumbering the rest in order).
pub fn cut(mesh: &MeshData, keep: impl Fn(DVec2) -> bool) -> MeshData {
    let kept: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| keep(t.iter().map(|&v| mesh.rest[v as usize]).sum::<DVec2>() / 3.0))
        .collect();
    let mut new_index = vec![u32::MAX; mesh.rest.len()];
    for t in &kept {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut rest = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = rest.len() as u32;
            rest.push(mesh.rest[v]);
        }
    }
    let triangles = kept
        .into_iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    MeshData { rest, triangles }
}

/// An L: a `2n × 2n` grid without its upper-right quarter.
pub fn l_shape(n: usize, jitter: f64, seed: u64) -> MeshData {
    let g = grid(2 * n, 2 * n, 1.0, jitter, Diagonals::Alternating, seed);
    let n = n as f64;
    cut(&g, |c| !(c.x > n && c.y > n))
}

/// A `w × h` grid with a square hole of side `hole` in the middle.
pub fn holed(w: usize, h: usize, hole: f64, jitter: f64, seed: u64) -> MeshData {
    let g = grid(w, h, 1.0, jitter, Diagonals::Alternating, seed);
    let centre = DVec2::new(w as f64, h as f64) / 2.0;
    cut(&g, |c| {
        let d = (c - centre).abs();
        d.x > hole / 2.0 || d.y > hole / 2.0
    })
}

/// A cut-out like the ones the product meshes from pictures: a jittered grid of
/// about `vertices` vertices (unit spacing, 5:4) with two round holes and a notch
/// cut into one side.
pub fn cut_out(vertices: usize, seed: u64) -> MeshData {
    let side = (vertices as f64 * 1.12).sqrt();
    let nx = (side * 1.118).round().max(4.0) as usize;
    let ny = ((vertices as f64 * 1.12) / nx as f64).round().max(4.0) as usize;
    let g = grid(nx, ny, 1.0, 0.3, Diagonals::Alternating, seed);
    let (w, h) = (nx as f64, ny as f64);
    let holes = [
        (DVec2::new(0.3 * w, 0.35 * h), 0.12 * h),
        (DVec2::new(0.68 * w, 0.6 * h), 0.1 * h),
    ];
    cut(&g, |c| {
        let in_hole = holes.iter().any(|(o, r)| (c - *o).length() < *r);
        let in_notch = c.x > 0.55 * w && c.x < 0.6 * w && c.y < 0.4 * h;
        !in_hole && !in_notch
    })
}

/// Two meshes side by side as one (the second's indices shifted).
pub fn side_by_side(a: &MeshData, b: &MeshData, offset: DVec2) -> MeshData {
    let shift = a.rest.len() as u32;
    MeshData {
        rest: a
            .rest
            .iter()
            .copied()
            .chain(b.rest.iter().map(|p| *p + offset))
            .collect(),
        triangles: a
            .triangles
            .iter()
            .copied()
            .chain(b.triangles.iter().map(|t| t.map(|v| v + shift)))
            .collect(),
    }
}

/// The vertex nearest to `p`.
pub fn nearest(mesh: &MeshData, p: DVec2) -> u32 {
    let mut best = (f64::INFINITY, 0u32);
    for (i, q) in mesh.rest.iter().enumerate() {
        let d = (*q - p).length_squared();
        if d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}

/// Signed area of a triangle.
pub fn area(p: [DVec2; 3]) -> f64 {
    0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0])
}

/// Mean over triangles of `|area / rest area − 1|`.
pub fn mean_area_deviation(mesh: &MeshData, positions: &[DVec2]) -> f64 {
    let sum: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let a0 = area(t.map(|v| mesh.rest[v as usize]));
            let a1 = area(t.map(|v| positions[v as usize]));
            (a1 / a0 - 1.0).abs()
        })
        .sum();
    sum / mesh.triangles.len() as f64
}

/// The deformation gradient of a triangle (rest → deformed), columns as vectors.
pub fn gradient(rest: [DVec2; 3], deformed: [DVec2; 3]) -> glam::DMat2 {
    let r = glam::DMat2::from_cols(rest[1] - rest[0], rest[2] - rest[0]);
    let d = glam::DMat2::from_cols(deformed[1] - deformed[0], deformed[2] - deformed[0]);
    d * r.inverse()
}

/// Frobenius distance of a triangle's deformation gradient from its closest rotation.
pub fn rigidity_error(rest: [DVec2; 3], deformed: [DVec2; 3]) -> f64 {
    let j = gradient(rest, deformed);
    let c = DVec2::new(j.x_axis.x + j.y_axis.y, j.x_axis.y - j.y_axis.x);
    let c = c.try_normalize().unwrap_or(DVec2::X);
    let r = glam::DMat2::from_cols(DVec2::new(c.x, c.y), DVec2::new(-c.y, c.x));
    let d = j - r;
    (d.x_axis.length_squared() + d.y_axis.length_squared()).sqrt()
}

/// Every position finite.
pub fn all_finite(p: &[DVec2]) -> bool {
    p.iter().all(|p| p.is_finite())
}

/// Largest distance between corresponding points.
pub fn max_distance(a: &[DVec2], b: &[DVec2]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max)
}

/// A rotation by `angle` about the origin followed by `translation`, scaled by `scale`.
pub fn similarity(angle: f64, scale: f64, translation: DVec2) -> impl Fn(DVec2) -> DVec2 {
    let rot = DVec2::from_angle(angle) * scale;
    move |p: DVec2| rot.rotate(p) + translation
}

/// Four handles spread over a mesh: the vertices nearest to points inset from the
/// corners of its bounding box.
pub fn spread_handles(mesh: &MeshData) -> Vec<u32> {
    let (lo, hi) = mesh.rest.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let at = |fx: f64, fy: f64| nearest(mesh, lo + (hi - lo) * DVec2::new(fx, fy));
    vec![at(0.1, 0.15), at(0.9, 0.2), at(0.15, 0.85), at(0.85, 0.9)]
}

/// A drag of [`spread_handles`] at time `t ∈ [0, 1]`: every other handle pulled
/// right and up by up to a third of the mesh's size, the others nudged.
pub fn drag_pose(mesh: &MeshData, handles: &[u32], t: f64) -> Vec<DVec2> {
    let size = mesh.rest.iter().fold(0.0_f64, |m, p| m.max(p.x).max(p.y));
    handles
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let p = mesh.rest[v as usize];
            if i % 2 == 1 {
                p + DVec2::new(0.2 * t * size, -0.3 * t * size)
            } else {
                p + DVec2::new(0.0, 0.05 * t * size)
            }
        })
        .collect()
}
