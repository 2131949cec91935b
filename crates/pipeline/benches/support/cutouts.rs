//! The cut-outs and rigs the insertion benchmark and `insertion_report` share: the
//! built-in lizard, a giraffe (long neck and legs) and a spider (eight thin legs),
//! meshed by `pipeline::prepare`, with 10 point handles spread over the extremities
//! (farthest-point sampling) or clustered (12 px apart near the middle), and 64 fixed
//! random insertion positions per mesh.

use glam::DVec2;
use image::RgbaImage;
use pipeline::{DEFAULT_IMAGE, prepare};
use project::{HandleSpec, Project};
use weights_core::Rig;

/// Positions tried per case.
pub const POSITIONS: usize = 64;

/// The cut-outs by name.
pub const NAMES: [&str; 3] = ["lizard", "giraffe", "spider"];

pub fn picture(name: &str) -> RgbaImage {
    let bytes: &[u8] = match name {
        "lizard" => DEFAULT_IMAGE,
        "giraffe" => include_bytes!("../../../../assets/giraffe.png"),
        _ => include_bytes!("../../../../assets/spider.png"),
    };
    image::load_from_memory(bytes)
        .expect("a bundled picture")
        .to_rgba8()
}

/// A seeded generator (xorshift), so every run tries the same positions.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Ten handle positions on the opaque pixels: spread by farthest-point sampling
/// (which lands on the extremities), or clustered 12 px apart around the pixel nearest
/// the opaque pixels' centroid.
pub fn handles(image: &RgbaImage, spread: bool) -> Vec<[f64; 2]> {
    let opaque: Vec<DVec2> = image
        .enumerate_pixels()
        .filter(|(_, _, p)| p[3] > 200)
        .map(|(x, y, _)| DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5))
        .collect();
    if spread {
        let mut chosen = vec![opaque[opaque.len() / 2]];
        let mut nearest: Vec<f64> = opaque.iter().map(|p| p.distance(chosen[0])).collect();
        while chosen.len() < 10 {
            let (i, _) = nearest
                .iter()
                .enumerate()
                .fold((0, -1.0), |b, (i, &d)| if d > b.1 { (i, d) } else { b });
            chosen.push(opaque[i]);
            for (d, p) in nearest.iter_mut().zip(&opaque) {
                *d = d.min(p.distance(opaque[i]));
            }
        }
        chosen.iter().map(|p| p.to_array()).collect()
    } else {
        let centroid = opaque.iter().copied().sum::<DVec2>() / opaque.len() as f64;
        let mut chosen: Vec<DVec2> = Vec::new();
        let mut by_distance = opaque.clone();
        by_distance.sort_by(|a, b| a.distance(centroid).total_cmp(&b.distance(centroid)));
        for p in by_distance {
            if chosen.iter().all(|c| c.distance(p) >= 12.0) {
                chosen.push(p);
                if chosen.len() == 10 {
                    break;
                }
            }
        }
        chosen.iter().map(|p| p.to_array()).collect()
    }
}

/// The rig of a cut-out at a density, its handles spread or clustered.
pub fn rig(image: &RgbaImage, spread: bool, density: usize) -> Rig {
    let project = Project {
        handles: handles(image, spread)
            .into_iter()
            .map(|rest| HandleSpec::Point {
                rest,
                translate: [0.0, 0.0],
                rotate: 0.0,
                scale: 1.0,
                depth: 0,
            })
            .collect(),
        ..Project::default()
    };
    prepare(image, &project, Some(density)).expect("a rig").rig
}

/// The 64 fixed insertion positions of a rig: random mesh vertices.
pub fn positions(rig: &Rig) -> Vec<DVec2> {
    let n = rig.domain().len() as u64;
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    (0..POSITIONS)
        .map(|_| rig.domain().positions()[(rng.next() % n) as usize])
        .collect()
}

/// The `q`-quantile of some numbers (nearest rank).
pub fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// How many passes over the positions the insertion benchmark makes: `INSERTION_PASSES`,
/// else 3 (at least 1).
pub fn passes() -> usize {
    std::env::var("INSERTION_PASSES")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(3)
        .max(1)
}

/// The densities measured: `INSERTION_SIZES` (comma-separated), else 20k and 100k.
pub fn sizes() -> Vec<usize> {
    std::env::var("INSERTION_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|n| n.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![20_000, 100_000])
}

/// Whether a case (`name/spread|clustered/Nk`) is among those `INSERTION_ONLY` asks
/// for (a comma-separated list of parts of labels; all cases when unset).
pub fn selected(label: &str) -> bool {
    std::env::var("INSERTION_ONLY")
        .map(|only| only.split(',').any(|part| label.contains(part.trim())))
        .unwrap_or(true)
}
