//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::collections::HashSet;

use glam::DVec2;
use mesh::Mesh;

/// An RGBA image whose alpha is 255 where `inside(pixel centre)` and 0 elsewhere.
pub fn image_from(w: u32, h: u32, inside: impl Fn(DVec2) -> bool) -> image::RgbaImage {
    image::RgbaImage::from_fn(w, h, |x, y| {
        let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        image::Rgba([90, 120, 200, if inside(c) { 255 } else { 0 }])
    })
}

/// A 200×160 cut-out: a disc with a square hole, and a separate smaller disc.
pub fn disc_with_hole_and_island() -> image::RgbaImage {
    image_from(200, 160, in_disc_with_hole_and_island)
}

/// [`disc_with_hole_and_island`] scaled up `k` times.
pub fn disc_with_hole_and_island_scaled(k: u32) -> image::RgbaImage {
    image_from(200 * k, 160 * k, |p| {
        in_disc_with_hole_and_island(p / k as f64)
    })
}

/// The shape of [`disc_with_hole_and_island`].
pub fn in_disc_with_hole_and_island(p: DVec2) -> bool {
    let disc = p.distance(DVec2::new(80.0, 80.0)) < 60.0;
    let hole = (p.x - 80.0).abs() < 15.0 && (p.y - 80.0).abs() < 15.0;
    let island = p.distance(DVec2::new(170.0, 40.0)) < 18.0;
    (disc && !hole) || island
}

/// Undirected edge set of a mesh.
pub fn edges(m: &Mesh) -> HashSet<(u32, u32)> {
    let mut e = HashSet::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            e.insert((a.min(b), a.max(b)));
        }
    }
    e
}

/// A uniform-grid point locator for many queries against one mesh.
pub struct Locator<'a> {
    mesh: &'a Mesh,
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<usize>>,
}

impl<'a> Locator<'a> {
    pub fn new(mesh: &'a Mesh) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let cell = ((hi - lo).max_element() / 256.0).max(1e-9);
        let nx = ((hi.x - lo.x) / cell) as usize + 1;
        let ny = ((hi.y - lo.y) / cell) as usize + 1;
        let mut cells = vec![Vec::new(); nx * ny];
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.triangle_positions(t);
            let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
            let (x0, y0) = (
                ((tl.x - lo.x) / cell) as usize,
                ((tl.y - lo.y) / cell) as usize,
            );
            let (x1, y1) = (
                ((th.x - lo.x) / cell) as usize,
                ((th.y - lo.y) / cell) as usize,
            );
            for y in y0..=y1.min(ny - 1) {
                for x in x0..=x1.min(nx - 1) {
                    cells[y * nx + x].push(t);
                }
            }
        }
        Locator {
            mesh,
            lo,
            cell,
            nx,
            ny,
            cells,
        }
    }

    /// Whether some triangle contains `p` (boundary included, tiny tolerance).
    pub fn contains(&self, p: DVec2) -> bool {
        let q = (p - self.lo) / self.cell;
        if q.x < 0.0 || q.y < 0.0 {
            return false;
        }
        let (x, y) = (q.x as usize, q.y as usize);
        if x >= self.nx || y >= self.ny {
            return false;
        }
        self.cells[y * self.nx + x].iter().any(|&t| {
            let [a, b, c] = self.mesh.triangle_positions(t);
            let o = |u: DVec2, v: DVec2| (v - u).perp_dot(p - u);
            o(a, b) >= -1e-9 && o(b, c) >= -1e-9 && o(c, a) >= -1e-9
        })
    }
}
