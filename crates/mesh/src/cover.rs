//! Cover polygons for content finer than the mesh: specks, hair, text.
//!
//! Every visible pixel must end up inside the domain, but a picture of thousands of
//! specks or a page of text traced pixel-exactly has tens of thousands of outline
//! vertices, far beyond what a mesh of a few thousand vertices can afford, and each
//! separate speck would be a piece of the mesh of its own.
//!
//! * A piece (connected component of the dilated mask) is *fine* when its mean width,
//!   twice its area over its perimeter, is under two lattice spacings for the target
//!   vertex count and under [`MAX_FINE_WIDTH`]. Other pieces keep their exact outlines at
//!   every density: the lizard's legs stay apart.
//! * While the fine pieces' exact outlines cost at most [`budget`] vertices (their
//!   vertices plus the splits `triangulate` adds, one a spacing), nothing changes.
//! * Beyond that, [`plan`] covers them by the cells of a square grid that hold one of
//!   their pixels, grown by one cell, so that pieces less than about a cell apart merge
//!   and every covered pixel lies at least a cell inside. A piece is only covered by cells
//!   wider than itself. The cell size is the smallest power of two, from 2 px, whose
//!   outline fits the budget; if none does, or the cells would cover more than the fine
//!   pieces' bounding rectangle, that rectangle covers them.

use crate::triangulate::MAX_VERTICES_PER_PIXEL;

/// Level code of a piece that is never covered (or of a pixel outside every piece).
const NEVER: u8 = u8::MAX;

/// Pieces at most this many lattice spacings wide (on average) count as fine: the mesh
/// has at most a row or two of vertices across them.
const FINE_SPACINGS: f64 = 2.0;

/// Pieces at least this wide (px, on average, with the default one-pixel margin) are
/// never covered, whatever the density: they are shapes (a lizard's leg), not specks or
/// strokes. A wider margin raises the limit by as much.
const MAX_FINE_WIDTH: f64 = 8.0;

/// Least number of outline vertices the fine pieces may always take.
pub(crate) const MIN_BUDGET: usize = 1024;

/// How many outline vertices the fine pieces may take when the mesh aims at `target`
/// vertices: half the target, and never fewer than [`MIN_BUDGET`].
pub(crate) fn budget(target: usize) -> usize {
    (target / 2).max(MIN_BUDGET)
}

/// What the traced outline says about one piece (connected component) of the mask.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Piece {
    /// Pixels in the piece (holes excluded).
    pub area: usize,
    /// Length of its traced outlines (outer ring and holes), in pixel edges.
    pub perimeter: usize,
    /// Vertices of its simplified outlines.
    pub vertices: usize,
}

/// The chosen cover: which pieces it replaces and the region that replaces them.
#[derive(Debug, Clone)]
pub(crate) struct Cover {
    /// For each piece, whether the cover takes it over.
    pub covered: Vec<bool>,
    /// Douglas–Peucker tolerance for outlines of the cover alone (pixels); every covered
    /// pixel's centre lies more than this inside the cover, away from the image border.
    pub tolerance: f64,
    region: Region,
}

#[derive(Debug, Clone)]
enum Region {
    /// Grid cells of `1 << level` pixels, `gw` per row, row-major.
    Cells {
        level: u32,
        gw: usize,
        on: Vec<bool>,
    },
    /// Pixels `x0..x1` × `y0..y1`.
    Rectangle {
        x0: usize,
        y0: usize,
        x1: usize,
        y1: usize,
    },
}

impl Cover {
    /// Sets every pixel of the cover region in the `w`-wide mask.
    pub(crate) fn paint(&self, mask: &mut [bool], w: usize) {
        match &self.region {
            Region::Cells { level, gw, on } => {
                for (y, row) in mask.chunks_exact_mut(w).enumerate() {
                    let cells = &on[(y >> level) * gw..];
                    for (x, m) in row.iter_mut().enumerate() {
                        *m |= cells[x >> level];
                    }
                }
            }
            &Region::Rectangle { x0, y0, x1, y1 } => {
                for row in mask.chunks_exact_mut(w).take(y1).skip(y0) {
                    row[x0..x1].fill(true);
                }
            }
        }
    }
}

/// The lattice spacing (px) that [`triangulate`](crate::triangulate) uses for about
/// `target` vertices over `area` px².
fn spacing(area: f64, target: usize) -> f64 {
    let n = (target as f64).min(MAX_VERTICES_PER_PIXEL * area).max(1.0);
    (2.0 * area / (3f64.sqrt() * n)).sqrt()
}

/// Decides whether the pieces of a `w × h` mask (`labels` per pixel, `u32::MAX` outside;
/// `pieces` indexed by label) need a cover to mesh at about `target` vertices, and which.
/// `None` when the fine pieces' exact outlines fit the budget. The mask is the visible
/// pixels dilated by `margin` px, its outlines simplified at `tolerance` px.
pub(crate) fn plan(
    labels: &[u32],
    w: usize,
    h: usize,
    pieces: &[Piece],
    (tolerance, margin): (f64, usize),
    target: usize,
) -> Option<Cover> {
    let budget = budget(target) as f64;
    let area: usize = pieces.iter().map(|p| p.area).sum();
    let s0 = spacing(area as f64, target);
    // What an exact outline costs: its vertices, and those `triangulate` splits its
    // segments with (about one per spacing).
    let cost = |p: &Piece| p.vertices as f64 + p.perimeter as f64 / s0;
    // Level (cell size 2^level px, the first wider than the piece) from which each piece
    // may be covered; `NEVER` for pieces the mesh resolves.
    let levels: Vec<u8> = pieces
        .iter()
        .map(|p| {
            let width = 2.0 * p.area as f64 / p.perimeter.max(1) as f64;
            let widest = MAX_FINE_WIDTH + 2.0 * margin.saturating_sub(1) as f64;
            if width >= (FINE_SPACINGS * s0).min(widest) {
                return NEVER;
            }
            let mut level = 1u8;
            while f64::from(1u32 << level) <= width {
                level += 1;
            }
            level
        })
        .collect();
    let fine: f64 = pieces
        .iter()
        .zip(&levels)
        .filter(|(_, l)| **l != NEVER)
        .map(|(p, _)| cost(p))
        .sum();
    if fine <= budget {
        return None;
    }
    // Cost and area of the pieces still exact at each level.
    let mut fine_left = [0.0f64; 64];
    let mut area_left = [0usize; 64];
    for (p, &l) in pieces.iter().zip(&levels) {
        for k in 0..usize::from(l).min(64) {
            area_left[k] += p.area;
            if l != NEVER {
                fine_left[k] += cost(p);
            }
        }
    }

    // Cells of 2 px holding the lowest level of their pixels' pieces, then coarser grids
    // by taking the lowest of 2 × 2 cells.
    let (mut gw, mut gh) = (w.div_ceil(2), h.div_ceil(2));
    let mut grid = vec![NEVER; gw * gh];
    for (y, row) in labels.chunks_exact(w).enumerate() {
        let cells = &mut grid[(y >> 1) * gw..(y >> 1) * gw + gw];
        for (x, &l) in row.iter().enumerate() {
            if l != u32::MAX {
                let c = &mut cells[x >> 1];
                *c = (*c).min(levels[l as usize]);
            }
        }
    }
    // The bounding rectangle of the fine pieces: the cover of last resort, and a better
    // one than any grid whose cells would cover more.
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (y, row) in labels.chunks_exact(w).enumerate() {
        for (x, &l) in row.iter().enumerate() {
            if l != u32::MAX && levels[l as usize] != NEVER {
                (x0, y0) = (x0.min(x), y0.min(y));
                (x1, y1) = (x1.max(x + 1), y1.max(y + 1));
            }
        }
    }
    let rectangle = Cover {
        covered: levels.iter().map(|&l| l != NEVER).collect(),
        tolerance,
        region: Region::Rectangle { x0, y0, x1, y1 },
    };
    let rectangle_area = (x1 - x0) * (y1 - y0);

    let mut level = 1u32;
    loop {
        let mut on: Vec<bool> = grid.iter().map(|&l| u32::from(l) <= level).collect();
        grow(&mut on, gw, gh);
        let cell = 1usize << level;
        let cells = on.iter().filter(|&&v| v).count();
        if cells * cell * cell >= rectangle_area {
            return Some(rectangle);
        }
        let (corners, edges) = outline_size(&on, gw, gh);
        let k = (level as usize).min(63);
        let s = spacing((area_left[k] + cells * cell * cell) as f64, target);
        let vertices = corners as f64 + (edges * cell) as f64 / s + fine_left[k];
        if vertices <= budget {
            let covered = levels.iter().map(|&l| u32::from(l) <= level).collect();
            return Some(Cover {
                covered,
                tolerance: tolerance.max(0.75 * cell as f64),
                region: Region::Cells { level, gw, on },
            });
        }
        if gw == 1 && gh == 1 {
            return Some(rectangle);
        }
        let (nw, nh) = (gw.div_ceil(2), gh.div_ceil(2));
        let mut next = vec![NEVER; nw * nh];
        for y in 0..gh {
            for x in 0..gw {
                let c = &mut next[(y / 2) * nw + x / 2];
                *c = (*c).min(grid[y * gw + x]);
            }
        }
        (grid, gw, gh) = (next, nw, nh);
        level += 1;
    }
}

/// Grows the set cells of a `gw × gh` grid by one cell in all eight directions.
fn grow(on: &mut [bool], gw: usize, gh: usize) {
    let mut tmp = vec![false; gw];
    for row in on.chunks_exact_mut(gw) {
        for (x, t) in tmp.iter_mut().enumerate() {
            *t = row[x.saturating_sub(1)..(x + 2).min(gw)].iter().any(|&v| v);
        }
        row.copy_from_slice(&tmp);
    }
    let rows = on.to_vec();
    for (y, row) in on.chunks_exact_mut(gw).enumerate() {
        for near in rows
            .chunks_exact(gw)
            .take((y + 2).min(gh))
            .skip(y.saturating_sub(1))
        {
            for (v, &n) in row.iter_mut().zip(near) {
                *v |= n;
            }
        }
    }
}

/// Corners and edges of the outlines of the set cells of a `gw × gh` grid: the vertices
/// of the traced rings (a diagonal contact counts twice) and their length in cells.
fn outline_size(on: &[bool], gw: usize, gh: usize) -> (usize, usize) {
    let at = |x: usize, y: usize| x > 0 && y > 0 && x <= gw && y <= gh && on[(y - 1) * gw + x - 1];
    let (mut corners, mut edges) = (0, 0);
    for y in 0..=gh {
        for x in 0..=gw {
            // The 2 × 2 cells around grid corner (x, y), `d` the one below right.
            let (a, b, c, d) = (at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1));
            corners += match usize::from(a) + usize::from(b) + usize::from(c) + usize::from(d) {
                1 | 3 => 1,
                2 if a == d => 2,
                _ => 0,
            };
            // The edges above and left of cell `d`.
            edges += usize::from(b != d) + usize::from(c != d);
        }
    }
    (corners, edges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outlines_of_simple_shapes() {
        // One cell, a 2 × 2 block, an L, and two cells touching at a corner.
        assert_eq!(outline_size(&[true], 1, 1), (4, 4));
        assert_eq!(outline_size(&[true; 4], 2, 2), (4, 8));
        assert_eq!(outline_size(&[true, false, true, true], 2, 2), (6, 8));
        assert_eq!(outline_size(&[true, false, false, true], 2, 2), (8, 8));
    }

    #[test]
    fn growing_adds_the_eight_neighbours() {
        let mut on = vec![false; 25];
        on[12] = true;
        grow(&mut on, 5, 5);
        assert_eq!(on.iter().filter(|&&v| v).count(), 9);
        assert!(on[6] && on[18] && !on[0]);
    }

    #[test]
    fn few_fine_pieces_need_no_cover() {
        let pieces = vec![
            Piece {
                area: 9,
                perimeter: 12,
                vertices: 4,
            };
            10
        ];
        let labels = vec![u32::MAX; 100];
        assert!(plan(&labels, 10, 10, &pieces, (0.75, 1), 500).is_none());
    }
}
