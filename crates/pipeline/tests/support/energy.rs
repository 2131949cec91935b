//! Pictures posed under ARAP, and a plain local/global solve to measure them against:
//! the energy Σ w·Σ‖d − R·e‖² over ARAP's own mesh, minimised by alternating the
//! best rotation per triangle with conjugate gradients on the positions, written from
//! the definitions. Shared by `tests/arap_energy.rs` and `examples/arap_energy.rs`.

#![allow(dead_code)]

use glam::DVec2;
use image::{Rgba, RgbaImage};
use project::Project;

pub use super::figure::figure_picture;

/// A picture and a rig posing it.
pub struct EnergyCase {
    pub name: &'static str,
    pub image: RgbaImage,
    pub project: Project,
}

impl EnergyCase {
    fn new(name: &'static str, image: RgbaImage, handles: &str, arap: &str) -> Self {
        let json =
            format!(r#"{{"version": 1, "method": "arap", "handles": {handles}, "arap": {arap}}}"#);
        let project = Project::from_json(&json).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        Self {
            name,
            image,
            project,
        }
    }
}

/// An opaque `w × h` picture: a gradient with a dark grid every 40 px.
pub fn opaque_picture(w: u32, h: u32) -> RgbaImage {
    RgbaImage::from_fn(w, h, |x, y| {
        if x % 40 < 2 || y % 40 < 2 {
            Rgba([20, 20, 20, 255])
        } else {
            Rgba([(x * 255 / w) as u8, (y * 255 / h) as u8, 160, 255])
        }
    })
}

fn point(x: f64, y: f64, dx: f64, dy: f64) -> String {
    format!(r#"{{"type": "point", "rest": [{x}, {y}], "translate": [{dx}, {dy}]}}"#)
}

/// The cases, with `arap` as the rig file's ARAP settings (JSON).
pub fn cases(arap: &str) -> Vec<EnergyCase> {
    let fixed = |points: &[(f64, f64)]| -> Vec<String> {
        points.iter().map(|&(x, y)| point(x, y, 0.0, 0.0)).collect()
    };
    let list = |handles: Vec<String>| format!("[{}]", handles.join(", "));
    // Opaque: six pins and a bar at rest, one pin pulled by (100, 50).
    let mut opaque = fixed(&[
        (300.0, 200.0),
        (900.0, 200.0),
        (300.0, 600.0),
        (900.0, 600.0),
        (600.0, 120.0),
        (600.0, 700.0),
    ]);
    opaque.push(r#"{"type": "bar", "rest": [[120, 380], [220, 440]]}"#.to_owned());
    opaque.push(point(700.0, 400.0, 100.0, 50.0));
    // The figure: feet and body at rest, the right hand pulled (90, −40).
    let mut arm = fixed(&[(222.0, 462.0), (378.0, 462.0), (300.0, 270.0)]);
    arm.push(point(470.0, 200.0, 90.0, -40.0));
    // The figure: the right arm swung down across the body, the head held.
    let mut swing = fixed(&[(222.0, 462.0), (378.0, 462.0), (300.0, 120.0)]);
    swing.push(point(470.0, 200.0, -230.0, 120.0));
    swing.push(point(400.0, 200.0, -120.0, 60.0));
    vec![
        EnergyCase::new(
            "opaque 1200 × 800",
            opaque_picture(1200, 800),
            &list(opaque),
            arap,
        ),
        EnergyCase::new("figure, hand pulled", figure_picture(), &list(arm), arap),
        EnergyCase::new(
            "figure, arm swung across",
            figure_picture(),
            &list(swing),
            arap,
        ),
    ]
}

/// ARAP's own mesh: rest positions, triangles, and rigidity weights per triangle.
pub struct ControlMesh<'a> {
    pub rest: &'a [DVec2],
    pub triangles: &'a [[u32; 3]],
    pub weights: &'a [f64],
}

/// The rotation (as a unit complex number) that best turns the rest triangle's edges
/// onto the posed ones: the angle of Σ conj(e)·d.
pub fn best_rotation(rest: [DVec2; 3], posed: [DVec2; 3]) -> DVec2 {
    let mut z = DVec2::ZERO;
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        let (e, d) = (rest[b] - rest[a], posed[b] - posed[a]);
        z += DVec2::new(e.x * d.x + e.y * d.y, e.x * d.y - e.y * d.x);
    }
    z.try_normalize().unwrap_or(DVec2::X)
}

/// Σ w·Σ‖d − R·e‖² over every triangle's edges, R its best rotation.
pub fn energy(mesh: &ControlMesh, v: &[DVec2]) -> f64 {
    mesh.triangles
        .iter()
        .zip(mesh.weights)
        .map(|(t, &w)| {
            let rest = t.map(|i| mesh.rest[i as usize]);
            let posed = t.map(|i| v[i as usize]);
            let r = best_rotation(rest, posed);
            [(0, 1), (1, 2), (2, 0)]
                .iter()
                .map(|&(a, b)| {
                    let e = rest[b] - rest[a];
                    let d = posed[b] - posed[a];
                    (d - DVec2::new(r.x * e.x - r.y * e.y, r.y * e.x + r.x * e.y)).length_squared()
                })
                .sum::<f64>()
                * w
        })
        .sum()
}

/// Plain local/global iterations: rotations fitted, then the positions minimising
/// the energy for those rotations (conjugate gradients, the pinned vertices held at
/// `start`'s places), `rounds` times from `start`.
pub fn local_global(
    mesh: &ControlMesh,
    pinned: &[bool],
    start: &[DVec2],
    rounds: usize,
) -> Vec<DVec2> {
    let n = mesh.rest.len();
    let mut v = start.to_vec();
    for _ in 0..rounds {
        // The energy's gradient is 2·(L·v − b): L the weighted edge Laplacian (each
        // triangle's edge counts once from that triangle), b the rotated rest edges.
        let mut b = vec![DVec2::ZERO; n];
        for (t, &w) in mesh.triangles.iter().zip(mesh.weights) {
            let rest = t.map(|i| mesh.rest[i as usize]);
            let r = best_rotation(rest, t.map(|i| v[i as usize]));
            for (a, c) in [(0, 1), (1, 2), (2, 0)] {
                let e = rest[c] - rest[a];
                let re = DVec2::new(r.x * e.x - r.y * e.y, r.y * e.x + r.x * e.y) * w;
                b[t[c] as usize] += re;
                b[t[a] as usize] -= re;
            }
        }
        let laplacian = |x: &[DVec2]| -> Vec<DVec2> {
            let mut out = vec![DVec2::ZERO; n];
            for (t, &w) in mesh.triangles.iter().zip(mesh.weights) {
                for (a, c) in [(0, 1), (1, 2), (2, 0)] {
                    let (i, j) = (t[a] as usize, t[c] as usize);
                    let d = (x[j] - x[i]) * w;
                    out[j] += d;
                    out[i] -= d;
                }
            }
            out
        };
        // Solve L·v = b over the free vertices: conjugate gradients from v.
        let free = |mut r: Vec<DVec2>| {
            for (x, &p) in r.iter_mut().zip(pinned) {
                if p {
                    *x = DVec2::ZERO;
                }
            }
            r
        };
        let dot = |a: &[DVec2], b: &[DVec2]| a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum::<f64>();
        let lv = laplacian(&v);
        let mut r = free(b.iter().zip(&lv).map(|(b, l)| *b - *l).collect());
        let mut p = r.clone();
        let mut rr = dot(&r, &r);
        let stop = 1e-20 * dot(&b, &b).max(1.0);
        for _ in 0..4 * n {
            if rr <= stop {
                break;
            }
            let ap = free(laplacian(&p));
            let alpha = rr / dot(&p, &ap);
            for i in 0..n {
                v[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            let next = dot(&r, &r);
            for i in 0..n {
                p[i] = r[i] + (next / rr) * p[i];
            }
            rr = next;
        }
    }
    v
}

/// Σ area·‖J − R‖² over a mesh's triangles (J the triangle's Jacobian from rest to
/// posed, R the rotation nearest it) and the number of triangles turned over.
pub fn jacobian_energy(rest: &[DVec2], triangles: &[[u32; 3]], posed: &[DVec2]) -> (f64, usize) {
    let mut total = 0.0;
    let mut flipped = 0;
    for t in triangles {
        let [a, b, c] = t.map(|i| rest[i as usize]);
        let [p, q, r] = t.map(|i| posed[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let det = e1.perp_dot(e2);
        if det.abs() < 1e-12 {
            continue;
        }
        let (d1, d2) = (q - p, r - p);
        if d1.perp_dot(d2) * det < 0.0 {
            flipped += 1;
        }
        // J = [d1 d2]·[e1 e2]⁻¹.
        let inv = [[e2.y / det, -e2.x / det], [-e1.y / det, e1.x / det]];
        let j = [
            [
                d1.x * inv[0][0] + d2.x * inv[1][0],
                d1.x * inv[0][1] + d2.x * inv[1][1],
            ],
            [
                d1.y * inv[0][0] + d2.y * inv[1][0],
                d1.y * inv[0][1] + d2.y * inv[1][1],
            ],
        ];
        let angle = (j[1][0] - j[0][1]).atan2(j[0][0] + j[1][1]);
        let (s, c) = angle.sin_cos();
        let norm = (j[0][0] - c).powi(2)
            + (j[0][1] + s).powi(2)
            + (j[1][0] - s).powi(2)
            + (j[1][1] - c).powi(2);
        total += 0.5 * det.abs() * norm;
    }
    (total, flipped)
}
