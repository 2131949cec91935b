//! Helpers shared by the integration tests.

#![allow(dead_code)]

use glam::Vec2;
use image::RgbaImage;

/// A small deterministic generator (xorshift64*), so tests need no `rand`.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    pub fn byte(&mut self) -> u8 {
        (self.next_u64() >> 56) as u8
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// An image of random colours and alphas (including fully transparent and
/// fully opaque pixels).
pub fn random_image(width: u32, height: u32, seed: u64) -> RgbaImage {
    let mut rng = Rng::new(seed);
    RgbaImage::from_fn(width, height, |_, _| {
        let a = match rng.byte() % 4 {
            0 => 0,
            1 => 255,
            _ => rng.byte(),
        };
        image::Rgba([rng.byte(), rng.byte(), rng.byte(), a])
    })
}

/// A grid mesh over `[0, width] × [0, height]` with `cols × rows` cells, two
/// triangles per cell. Grid lines are at `width * i / cols` (not necessarily
/// whole pixels).
pub struct Grid {
    pub positions: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    pub cols: u32,
    pub rows: u32,
}

impl Grid {
    pub fn new(width: f32, height: f32, cols: u32, rows: u32) -> Self {
        let mut positions = Vec::new();
        for j in 0..=rows {
            for i in 0..=cols {
                positions.push(Vec2::new(
                    width * i as f32 / cols as f32,
                    height * j as f32 / rows as f32,
                ));
            }
        }
        let mut triangles = Vec::new();
        let id = |i: u32, j: u32| j * (cols + 1) + i;
        for j in 0..rows {
            for i in 0..cols {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                // Alternate the diagonal so both directions get exercised.
                if (i + j).is_multiple_of(2) {
                    triangles.push([a, b, c]);
                    triangles.push([a, c, d]);
                } else {
                    triangles.push([a, b, d]);
                    triangles.push([b, c, d]);
                }
            }
        }
        Self {
            positions,
            triangles,
            cols,
            rows,
        }
    }

    /// Whether vertex `v` lies on the outer boundary.
    pub fn is_boundary(&self, v: usize) -> bool {
        let (i, j) = (v as u32 % (self.cols + 1), v as u32 / (self.cols + 1));
        i == 0 || j == 0 || i == self.cols || j == self.rows
    }

    /// Moves interior vertices by up to `amount` (a fraction of a cell, below
    /// 1/3 so no triangle flips), rounded to multiples of `quantum` pixels.
    pub fn jitter(&mut self, amount: f32, quantum: f32, seed: u64, cell: Vec2) {
        let mut rng = Rng::new(seed);
        for v in 0..self.positions.len() {
            if self.is_boundary(v) {
                continue;
            }
            let offset = Vec2::new(
                rng.range(-amount, amount) * cell.x,
                rng.range(-amount, amount) * cell.y,
            );
            let p = self.positions[v] + offset;
            self.positions[v] = (p / quantum).round() * quantum;
        }
    }
}

/// One PNG chunk: length, type, data, CRC.
pub fn png_chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let mut out = (data.len() as u32).to_be_bytes().to_vec();
    let mut body = kind.to_vec();
    body.extend_from_slice(data);
    out.extend_from_slice(&body);
    out.extend_from_slice(&crc32fast::hash(&body).to_be_bytes());
    out
}

/// A PNG whose header claims `width × height` RGBA8 pixels, with a tiny IDAT.
pub fn png_with_header(width: u32, height: u32) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    png.extend(png_chunk(b"IHDR", &ihdr));
    // A valid zlib stream of a few zero bytes.
    png.extend(png_chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x63, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01],
    ));
    png.extend(png_chunk(b"IEND", &[]));
    png
}

/// Encodes `image` as PNG in memory.
pub fn encode_png(image: &RgbaImage) -> Vec<u8> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, image::ImageFormat::Png)
        .expect("encoding a PNG in memory");
    bytes.into_inner()
}

/// Swirls `positions` about the centre of a `size × size` square: a rotation
/// by up to 1.2 rad at the centre, fading to none at radius `size / 2`.
pub fn swirl(positions: &[Vec2], size: f32) -> Vec<Vec2> {
    let centre = Vec2::splat(size / 2.0);
    positions
        .iter()
        .map(|&p| {
            let d = p - centre;
            let t = (1.0 - d.length() / (size / 2.0)).max(0.0);
            centre + Vec2::from_angle(1.2 * t * t).rotate(d)
        })
        .collect()
}

/// A `size × size` texture with smooth gradients and blocks of transparency.
pub fn gradient_texture(size: u32) -> RgbaImage {
    RgbaImage::from_fn(size, size, |x, y| {
        image::Rgba([
            (x * 255 / size) as u8,
            (y * 255 / size) as u8,
            ((x ^ y) & 0xff) as u8,
            if (x / 64 + y / 64) % 3 == 0 { 0 } else { 255 },
        ])
    })
}

/// Two cut-out parts side by side, for overlap tests: a `2s × s` texture whose halves
/// each hold an opaque disc of radius `0.35·s` with an anti-aliased rim (alpha falls
/// from 255 to 0 over two pixels) on transparent ground, and a mesh of each half (a
/// grid over it, as a picture's mesh covers a cut-out with some margin). The right
/// half's mesh is drawn after the left's, shifted left by `shift` pixels so the two
/// discs overlap: `(texture, rest, deformed, triangles)`.
pub fn overlapping_parts(s: u32, shift: f32) -> (RgbaImage, Vec<Vec2>, Vec<Vec2>, Vec<[u32; 3]>) {
    let r = 0.35 * s as f32;
    let texture = RgbaImage::from_fn(2 * s, s, |x, y| {
        let half = x / s;
        let centre = Vec2::new(half as f32 * s as f32 + 0.5 * s as f32, 0.5 * s as f32);
        let d = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - centre).length();
        let alpha = ((r - d) / 2.0 + 0.5).clamp(0.0, 1.0);
        let colour = if half == 0 {
            [200, 40, 30]
        } else {
            [30, 60, 210]
        };
        image::Rgba([
            colour[0],
            colour[1],
            colour[2],
            (alpha * 255.0).round() as u8,
        ])
    });
    let mut rest = Vec::new();
    let mut deformed = Vec::new();
    let mut triangles = Vec::new();
    for half in 0..2 {
        let mut grid = Grid::new(s as f32, s as f32, 7, 7);
        let first = rest.len() as u32;
        let offset = Vec2::new(half as f32 * s as f32, 0.0);
        let moved = if half == 1 { shift } else { 0.0 };
        rest.extend(grid.positions.iter().map(|&p| p + offset));
        deformed.extend(
            grid.positions
                .iter()
                .map(|&p| p + offset - Vec2::new(moved, 0.0)),
        );
        triangles.extend(grid.triangles.drain(..).map(|t| t.map(|v| v + first)));
    }
    (texture, rest, deformed, triangles)
}

/// Pixels of `out` that lie well inside either disc of [`overlapping_parts`] where it
/// was drawn (at least two pixels in from the rim, so its alpha was 255) and have lost
/// alpha: the cracks a front part's transparent edge would cut into the part behind.
pub fn cracks(out: &RgbaImage, s: u32, shift: f32) -> Vec<(u32, u32, u8)> {
    let r = 0.35 * s as f32 - 2.0;
    let centres = [
        Vec2::new(0.5 * s as f32, 0.5 * s as f32),
        Vec2::new(1.5 * s as f32 - shift, 0.5 * s as f32),
    ];
    let mut found = Vec::new();
    for (x, y, p) in out.enumerate_pixels() {
        let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        if centres.iter().any(|&o| (c - o).length() < r) && p[3] < 255 {
            found.push((x, y, p[3]));
        }
    }
    found
}
