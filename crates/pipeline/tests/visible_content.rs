//! A warp never deletes visible content: an identity render of pictures made of specks,
//! one-pixel lines, thin strokes and faint pixels on a transparent background gives back
//! every pixel with alpha > 0, at every density.
//!
//! The renderer draws only inside the mesh, so this holds exactly when the mesh covers
//! the centre of every visible pixel. The comparison is in premultiplied colour (what
//! the pixel looks like), with a tolerance of [`TOLERANCE`] per channel.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use glam::DVec2;
use image::{Rgba, RgbaImage};
use project::Project;

/// Largest difference allowed per premultiplied channel (0–255).
const TOLERANCE: i32 = 2;

/// Densities (target vertex counts) every picture is rendered at.
const DENSITIES: [usize; 3] = [500, 3_000, 20_000];

/// A small xorshift generator, so the pictures are the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % u64::from(n)) as u32
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn colour(&mut self, alpha: u8) -> Rgba<u8> {
        let c = self.next().to_le_bytes();
        Rgba([c[0], c[1], c[2], alpha])
    }
}

/// `count` specks of 1 to 3 px on a side in random colours.
fn specks(w: u32, h: u32, count: usize, seed: u64) -> RgbaImage {
    let mut rng = Rng(seed);
    let mut img = RgbaImage::new(w, h);
    for _ in 0..count {
        let s = 1 + rng.below(3);
        let (x, y) = (rng.below(w - s + 1), rng.below(h - s + 1));
        let a = 1 + rng.below(255) as u8;
        let c = rng.colour(a);
        for dy in 0..s {
            for dx in 0..s {
                img.put_pixel(x + dx, y + dy, c);
            }
        }
    }
    img
}

/// Plots the pixel under `p` if it is on the image.
fn plot(img: &mut RgbaImage, p: DVec2, c: Rgba<u8>) {
    if p.x >= 0.0 && p.y >= 0.0 && p.x < f64::from(img.width()) && p.y < f64::from(img.height()) {
        img.put_pixel(p.x as u32, p.y as u32, c);
    }
}

/// One-pixel-wide curves (thin hair): random cubic Béziers, some crossing, plus straight
/// horizontal, vertical and diagonal lines one pixel wide.
fn hair(w: u32, h: u32, strands: usize, seed: u64) -> RgbaImage {
    let mut rng = Rng(seed);
    let mut img = RgbaImage::new(w, h);
    let size = DVec2::new(f64::from(w), f64::from(h));
    for _ in 0..strands {
        let mut pt = || DVec2::new(rng.unit(), rng.unit()) * size;
        let (p0, p1, p2, p3) = (pt(), pt(), pt(), pt());
        let a = 40 + rng.below(216) as u8;
        let c = rng.colour(a);
        let steps = 4 * (w + h);
        for k in 0..=steps {
            let t = f64::from(k) / f64::from(steps);
            let u = 1.0 - t;
            let p = p0 * (u * u * u)
                + p1 * (3.0 * u * u * t)
                + p2 * (3.0 * u * t * t)
                + p3 * (t * t * t);
            plot(&mut img, p, c);
        }
    }
    let c = Rgba([250, 250, 250, 255]);
    for x in 5..w - 5 {
        img.put_pixel(x, 3, c);
    }
    for y in 5..h - 5 {
        img.put_pixel(w - 4, y, c);
    }
    for k in 0..h.min(w) / 2 {
        img.put_pixel(10 + k, h / 4 + k, c);
    }
    img
}

/// Lines of text-like glyphs: 5×7 cells of one-pixel strokes, one pixel apart, in a few
/// colours, on a transparent page.
fn text(w: u32, h: u32, seed: u64) -> RgbaImage {
    let mut rng = Rng(seed);
    let mut img = RgbaImage::new(w, h);
    let ink = [
        Rgba([0, 0, 0, 255]),
        Rgba([20, 40, 160, 255]),
        Rgba([150, 0, 0, 200]),
    ];
    let mut y = 4;
    while y + 7 < h {
        let mut x = 4;
        while x + 5 < w {
            // A word of 2 to 8 glyphs, then a space.
            let word = 2 + rng.below(7);
            for _ in 0..word {
                if x + 5 >= w {
                    break;
                }
                let c = ink[rng.below(3) as usize];
                // Each glyph: a random choice of strokes on a 5×7 cell.
                let bits = rng.next();
                let strokes: [&[(u32, u32)]; 8] = [
                    &[(0, 0), (1, 0), (2, 0), (3, 0), (4, 0)],
                    &[(0, 3), (1, 3), (2, 3), (3, 3), (4, 3)],
                    &[(0, 6), (1, 6), (2, 6), (3, 6), (4, 6)],
                    &[(0, 0), (0, 1), (0, 2), (0, 3), (0, 4), (0, 5), (0, 6)],
                    &[(4, 0), (4, 1), (4, 2), (4, 3), (4, 4), (4, 5), (4, 6)],
                    &[(2, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (2, 6)],
                    &[(0, 6), (1, 5), (2, 4), (3, 3), (4, 2)],
                    &[(1, 1), (3, 5)],
                ];
                let mut any = false;
                for (k, s) in strokes.iter().enumerate() {
                    if bits >> k & 1 == 1 {
                        any = true;
                        for &(dx, dy) in *s {
                            img.put_pixel(x + dx, y + dy, c);
                        }
                    }
                }
                if !any {
                    img.put_pixel(x + 2, y + 6, c);
                }
                x += 6;
            }
            x += 4;
        }
        y += 11;
    }
    img
}

/// One visible pixel in a transparent picture.
fn single_pixel() -> RgbaImage {
    let mut img = RgbaImage::new(120, 90);
    img.put_pixel(77, 31, Rgba([10, 200, 30, 255]));
    img
}

/// Faint pixels (alpha 1 to 8): scattered ones, a faint disc and a faint one-pixel line.
fn faint(seed: u64) -> RgbaImage {
    let mut rng = Rng(seed);
    let (w, h) = (200, 150);
    let mut img = RgbaImage::new(w, h);
    for _ in 0..300 {
        let (x, y) = (rng.below(w), rng.below(h));
        let a = 1 + rng.below(8) as u8;
        let c = rng.colour(a);
        img.put_pixel(x, y, c);
    }
    for (x, y, p) in img.enumerate_pixels_mut() {
        let d = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5).distance(DVec2::new(60.0, 50.0));
        if d < 25.0 {
            *p = Rgba([200, 100, 50, 1 + (x + y) as u8 % 8]);
        }
        if y == 120 && x > 20 {
            *p = Rgba([90, 90, 255, 3]);
        }
    }
    img
}

/// A big opaque disc with a one-pixel tail and an isolated one-pixel dot far from it.
fn tail_and_dot() -> RgbaImage {
    let (w, h) = (240, 180);
    let mut img = RgbaImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
        if c.distance(DVec2::new(80.0, 90.0)) < 50.0 {
            *p = Rgba([180, 120, 60, 255]);
        }
        // The tail: a one-pixel line leaving the disc to the right.
        if y == 90 && (130..220).contains(&x) {
            *p = Rgba([40, 40, 40, 255]);
        }
    }
    img.put_pixel(225, 20, Rgba([255, 0, 255, 255]));
    img
}

/// A checkerboard of one-pixel squares (every other pixel visible) in a region, and a
/// sparser one (every other pixel of every other row) beside it.
fn checkerboard() -> RgbaImage {
    RgbaImage::from_fn(160, 100, |x, y| {
        let dense = x < 80 && (x + y) % 2 == 0;
        let sparse = x >= 80 && y % 2 == 0 && x % 2 == 0 && y > 10;
        if dense || sparse {
            Rgba([(x * 3) as u8, (y * 2) as u8, 128, 255])
        } else {
            Rgba([0, 0, 0, 0])
        }
    })
}

/// The first visible pixel's centre, at which a point handle can sit.
fn a_visible_pixel(img: &RgbaImage) -> DVec2 {
    let (x, y, _) = img.enumerate_pixels().find(|(_, _, p)| p.0[3] > 0).unwrap();
    DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5)
}

fn premultiplied(p: Rgba<u8>) -> [i32; 4] {
    let a = i32::from(p.0[3]);
    let m = |c: u8| (i32::from(c) * a + 127) / 255;
    [m(p.0[0]), m(p.0[1]), m(p.0[2]), a]
}

/// Renders `img` at identity at every density, with no handle and with one point handle
/// at rest on a visible pixel, and checks that every visible pixel comes back.
fn identity_keeps_every_visible_pixel(name: &str, img: &RgbaImage) {
    let visible = img.pixels().filter(|p| p.0[3] > 0).count();
    assert!(visible > 0, "{name}: the picture has no visible pixel");
    let handle = a_visible_pixel(img);
    let rigs = [
        r#"{"version": 1, "handles": []}"#.to_string(),
        format!(
            r#"{{"version": 1, "handles": [{{"type": "point", "rest": [{}, {}]}}]}}"#,
            handle.x, handle.y
        ),
    ];
    for density in DENSITIES {
        for rig in &rigs {
            let project = Project::from_json(rig).unwrap();
            let prepared = pipeline::prepare(img, &project, Some(density))
                .unwrap_or_else(|e| panic!("{name} at density {density}: {e:#}"));
            let vertices = prepared.rig.domain().len();
            let out =
                pipeline::warp(img, &pipeline::Warper::on_rig(prepared.rig, &project)).unwrap();
            let mut lost = 0;
            let mut first = None;
            for (x, y, p) in img.enumerate_pixels() {
                if p.0[3] == 0 {
                    continue;
                }
                let (a, b) = (premultiplied(*p), premultiplied(*out.get_pixel(x, y)));
                if a.iter().zip(&b).any(|(a, b)| (a - b).abs() > TOLERANCE) {
                    lost += 1;
                    first.get_or_insert((x, y, a, b));
                }
            }
            assert!(
                lost == 0,
                "{name}, density {density}, {} handle(s), {} mesh vertices: {lost} of \
                 {visible} visible pixels changed, first {:?}",
                project.handles.len(),
                vertices,
                first.unwrap()
            );
        }
    }
}

#[test]
fn specks_survive_an_identity_render() {
    identity_keeps_every_visible_pixel("800 specks", &specks(300, 220, 800, 7));
    identity_keeps_every_visible_pixel("3000 specks", &specks(500, 400, 3_000, 11));
}

#[test]
fn thin_lines_survive_an_identity_render() {
    identity_keeps_every_visible_pixel("hair", &hair(320, 240, 12, 5));
}

#[test]
fn text_survives_an_identity_render() {
    identity_keeps_every_visible_pixel("text", &text(400, 260, 3));
}

#[test]
fn a_single_pixel_survives_an_identity_render() {
    identity_keeps_every_visible_pixel("single pixel", &single_pixel());
}

#[test]
fn faint_pixels_survive_an_identity_render() {
    identity_keeps_every_visible_pixel("faint pixels", &faint(13));
}

#[test]
fn a_thin_tail_and_a_dot_survive_an_identity_render() {
    identity_keeps_every_visible_pixel("tail and dot", &tail_and_dot());
}

#[test]
fn a_checkerboard_survives_an_identity_render() {
    identity_keeps_every_visible_pixel("checkerboard", &checkerboard());
}

/// Whether the pixel square of `(x, y)` lies inside the cage or on it (every corner).
fn enclosed(cage: &lbc::Cage, ring: &[DVec2], x: u32, y: u32) -> bool {
    let n = ring.len();
    let on_edge = |p: DVec2| {
        (0..n).any(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            (a + t * ab).distance(p) < 1e-9
        })
    };
    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .into_iter()
        .map(|(dx, dy)| DVec2::new(f64::from(x) + dx, f64::from(y) + dy))
        .all(|p| cage.contains(p) || on_edge(p))
}

/// A cage from the outline encloses every visible pixel whole, as a simple polygon of
/// the vertices asked for, for every count from 8 to 64.
fn outline_cage_encloses(name: &str, img: &RgbaImage) {
    let visible: Vec<(u32, u32)> = img
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[3] > 0)
        .map(|(x, y, _)| (x, y))
        .collect();
    let (w, h) = img.dimensions();
    let offset = (0.01 * f64::from(w).hypot(f64::from(h))).clamp(3.0, 20.0);
    for n in 8..=64 {
        let ring = pipeline::cage::cage_from_outline(img, n, offset)
            .unwrap_or_else(|e| panic!("{name}, {n} vertices: {e:#}"));
        assert_eq!(ring.len(), n, "{name}: {n} vertices asked for");
        let cage =
            lbc::Cage::new(ring.clone()).unwrap_or_else(|e| panic!("{name}, {n} vertices: {e}"));
        let left_out: Vec<_> = visible
            .iter()
            .filter(|&&(x, y)| !enclosed(&cage, &ring, x, y))
            .collect();
        assert!(
            left_out.is_empty(),
            "{name}, {n} vertices: {} visible pixels outside the cage, first {:?}",
            left_out.len(),
            left_out[0]
        );
    }
}

#[test]
fn an_outline_cage_encloses_every_visible_pixel() {
    outline_cage_encloses("800 specks", &specks(300, 220, 800, 7));
    outline_cage_encloses("hair", &hair(320, 240, 12, 5));
    outline_cage_encloses("tail and dot", &tail_and_dot());
    outline_cage_encloses("text", &text(400, 260, 3));
    outline_cage_encloses("single pixel", &single_pixel());
    outline_cage_encloses("faint pixels", &faint(13));
}

#[test]
fn an_outline_cage_encloses_every_cut_out_in_assets() {
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    for name in ["lizard.png", "giraffe.png", "spider.png"] {
        let img = image::open(assets.join(name)).unwrap().to_rgba8();
        outline_cage_encloses(name, &img);
    }
}
