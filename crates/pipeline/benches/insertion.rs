//! Inserting a point handle (weights up to date) on the meshes the editor and `c2warp`
//! build, not on a friendly grid: the built-in lizard, a giraffe (long neck and legs)
//! and a spider (eight thin legs), meshed by `pipeline::prepare` at 20k and 100k
//! vertices (and 620k with `INSERTION_SIZES=20000,100000,620000`), with 10 point
//! handles spread over the extremities (farthest-point sampling) or clustered (a
//! tight group near the middle). Each case inserts at 64 fixed random vertices and
//! removes the handle again; besides criterion's mean it prints the median and the
//! 90th percentile of the insertions.
//!
//! ```sh
//! cargo bench -p pipeline --bench insertion
//! ```

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use image::RgbaImage;
use pipeline::{DEFAULT_IMAGE, prepare};
use project::{HandleSpec, Project};
use weights_core::Handle;

/// Positions tried per case.
const POSITIONS: usize = 64;

fn picture(name: &str) -> RgbaImage {
    let bytes: &[u8] = match name {
        "lizard" => DEFAULT_IMAGE,
        "giraffe" => include_bytes!("../../../assets/giraffe.png"),
        _ => include_bytes!("../../../assets/spider.png"),
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
fn handles(image: &RgbaImage, spread: bool) -> Vec<[f64; 2]> {
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

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

fn sizes() -> Vec<usize> {
    std::env::var("INSERTION_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|n| n.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![20_000, 100_000])
}

fn insertion(c: &mut Criterion) {
    let mut group = c.benchmark_group("insertion");
    group.sample_size(10);
    for name in ["lizard", "giraffe", "spider"] {
        let image = picture(name);
        for spread in [true, false] {
            let project = Project {
                handles: handles(&image, spread)
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
            for &density in &sizes() {
                let mut rig = prepare(&image, &project, Some(density)).expect("a rig").rig;
                let n = rig.domain().len() as u64;
                let mut rng = Rng(0x2545_F491_4F6C_DD1D);
                let positions: Vec<DVec2> = (0..POSITIONS)
                    .map(|_| rig.domain().positions()[(rng.next() % n) as usize])
                    .collect();
                let mut times = Vec::new();
                let mut next = 0;
                let label = format!(
                    "{name}/{}/{}k",
                    if spread { "spread" } else { "clustered" },
                    density / 1000
                );
                group.bench_function(&label, |b| {
                    b.iter_custom(|iterations| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iterations {
                            let at = positions[next % POSITIONS];
                            next += 1;
                            let clock = Instant::now();
                            let inserted = rig.insert_handle(Handle::point(at));
                            let elapsed = clock.elapsed();
                            total += elapsed;
                            if let Ok(index) = inserted {
                                times.push(elapsed.as_secs_f64() * 1e3);
                                rig.remove_handle(index).expect("the handle just added");
                            }
                        }
                        total
                    })
                });
                if !times.is_empty() {
                    eprintln!(
                        "{label}: {} samples, {} insertions: median {:.2} ms, p90 {:.2} ms",
                        rig.domain().len(),
                        times.len(),
                        quantile(times.clone(), 0.5),
                        quantile(times, 0.9)
                    );
                }
            }
        }
    }
    group.finish();
}

criterion_group!(benches, insertion);
criterion_main!(benches);
