//! How the build time grows with the number of handles: N random point handles on the
//! built-in lizard (a cut-out, so intrinsic distances), meshed and weighted as
//! `c2warp render` would, timed by phase.
//!
//! ```sh
//! cargo run --release -p pipeline --example many_handles [density] [N...]
//! ```
//!
//! Defaults: density 20000, N = 10 100 500 1000 2000 5000 10000. The handles are
//! opaque pixels drawn at random (seeded), no two closer than `GAP` pixels (default 2),
//! so that close pairs (timed by the `close_pair` examples) do not blur the picture.
//! `PAIRS=1` puts a second handle one pixel right of each (gap at least 3 between
//! pairs): the worst case, where nearly every sample becomes a virtual handle.
//! `VIRTUAL=n` adds n virtual handles at random pixels, as a rig file may list them.
//! `INSERTS=k` also times inserting a point handle at k random places (each removed
//! again), as a click in the editor does. `PRINT=1` counts the harmonic coefficients.
//! `LIMIT=0` builds past the handle limit (what the limit protects against).

use std::time::Instant;

use pipeline::{DEFAULT_IMAGE, DEFAULT_RIG};
use project::{HandleSpec, Project};

/// A small seeded generator (xorshift), so runs are comparable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let density: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let counts: Vec<usize> = if args.len() > 2 {
        args[2..].iter().filter_map(|s| s.parse().ok()).collect()
    } else {
        vec![10, 100, 500, 1000, 2000, 5000, 10_000]
    };
    let gap: f64 = std::env::var("GAP")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    let pairs = std::env::var_os("PAIRS").is_some_and(|v| v == "1");
    let virtuals: usize = std::env::var("VIRTUAL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let image = image::load_from_memory(DEFAULT_IMAGE)
        .expect("the built-in picture decodes")
        .to_rgba8();
    let (w, h) = image.dimensions();
    // Pixels well inside the shape: opaque with an opaque 7 × 7 neighbourhood.
    let opaque = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < i64::from(w)
            && y < i64::from(h)
            && image.get_pixel(x as u32, y as u32)[3] > 128
    };
    let inside: Vec<(u32, u32)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            (-3..=3).all(|dy| (-3..=3).all(|dx| opaque(i64::from(x) + dx, i64::from(y) + dy)))
        })
        .collect();
    println!(
        "lizard {w} x {h}, {} pixels well inside, density {density}, gap {gap} px",
        inside.len()
    );
    println!(
        "{:>6} {:>8} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "N",
        "samples",
        "virtual",
        "mesh ms",
        "dist ms",
        "voron ms",
        "virt ms",
        "weigh ms",
        "total s"
    );
    let base = Project::from_json(DEFAULT_RIG).expect("the built-in rig parses");
    for &n in &counts {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ n as u64);
        // A grid of cells `gap` wide finds a too-close point among a few neighbours.
        let cell = gap.max(1.0);
        let gap = if pairs { gap.max(3.0) } else { gap };
        let mut grid: std::collections::HashMap<(i64, i64), Vec<[f64; 2]>> =
            std::collections::HashMap::new();
        let mut points: Vec<[f64; 2]> = Vec::new();
        let mut tries = 0;
        while points.len() < n && tries < 100 * n {
            tries += 1;
            let (x, y) = inside[rng.below(inside.len())];
            let p = [f64::from(x) + 0.5, f64::from(y) + 0.5];
            let key = ((p[0] / cell) as i64, (p[1] / cell) as i64);
            let crowded = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    grid.get(&(key.0 + dx, key.1 + dy)).is_some_and(|list| {
                        list.iter().any(|q| (q[0] - p[0]).hypot(q[1] - p[1]) < gap)
                    })
                })
            });
            // With PAIRS=1 every handle gets a partner one pixel to its right: the
            // worst case, where Algorithm 1 must make nearly every sample a node.
            let partner = [p[0] + 1.0, p[1]];
            if !crowded && (!pairs || opaque(i64::from(x) + 4, i64::from(y))) {
                grid.entry(key).or_default().push(p);
                points.push(p);
                if pairs && points.len() < n {
                    points.push(partner);
                }
            }
        }
        if std::env::var_os("CLUMP").is_some() {
            // Every pixel nearest the centre of the shape: a solid block of handles.
            let c = inside.iter().fold((0.0, 0.0), |a, &(x, y)| {
                (a.0 + f64::from(x), a.1 + f64::from(y))
            });
            let c = (c.0 / inside.len() as f64, c.1 / inside.len() as f64);
            let mut near = inside.clone();
            near.sort_by(|a, b| {
                let d = |p: &(u32, u32)| (f64::from(p.0) - c.0).hypot(f64::from(p.1) - c.1);
                d(a).total_cmp(&d(b))
            });
            points = near
                .iter()
                .take(n)
                .map(|&(x, y)| [f64::from(x) + 0.5, f64::from(y) + 0.5])
                .collect();
        }
        let project = Project {
            handles: points
                .iter()
                .map(|&rest| HandleSpec::Point {
                    rest,
                    translate: [0.0, 0.0],
                    rotate: 0.0,
                    scale: 1.0,
                    depth: 0,
                })
                .collect(),
            density: Some(density),
            virtual_handles: (0..virtuals)
                .map(|_| {
                    let (x, y) = inside[rng.below(inside.len())];
                    let (dx, dy) = (rng.below(1000), rng.below(1000));
                    [
                        f64::from(x) + dx as f64 / 1000.0,
                        f64::from(y) + dy as f64 / 1000.0,
                    ]
                })
                .collect(),
            ..base.clone()
        };
        let clock = Instant::now();
        match pipeline::prepare(&image, &project, None) {
            Ok(prepared) => {
                let total = clock.elapsed().as_secs_f64();
                let t = prepared.rig.timings();
                let s = prepared.rig.stats();
                if std::env::var_os("PRINT").is_some() {
                    let rig = &prepared.rig;
                    let entries: usize = (0..rig.nodes().len())
                        .filter_map(|k| rig.harmonic_coordinates(k))
                        .map(<[_]>::len)
                        .sum();
                    println!("harmonic coefficients: {entries}");
                }
                // With INSERTS=k: insert a point handle at k random places (each
                // removed again), as the editor does on a click; the median times.
                let inserts: usize = std::env::var("INSERTS")
                    .ok()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(0);
                let mut rig = prepared.rig.clone();
                let (mut ins, mut rem) = (Vec::new(), Vec::new());
                let mut refused = 0;
                while ins.len() < inserts && refused < 100 * inserts {
                    let (x, y) = inside[rng.below(inside.len())];
                    let p = glam::DVec2::new(f64::from(x) + 0.25, f64::from(y) + 0.25);
                    let clock = Instant::now();
                    let i = match rig.insert_handle(weights_core::Handle::point(p)) {
                        Ok(i) => i,
                        Err(e) => {
                            refused += 1;
                            if refused == 1 {
                                println!("insertion refused: {e}");
                            }
                            continue;
                        }
                    };
                    ins.push(clock.elapsed().as_secs_f64() * 1e3);
                    let clock = Instant::now();
                    rig.remove_handle(i).expect("just inserted");
                    rem.push(clock.elapsed().as_secs_f64() * 1e3);
                }
                if !ins.is_empty() {
                    ins.sort_by(f64::total_cmp);
                    rem.sort_by(f64::total_cmp);
                    println!(
                        "insert a handle: median {:.1} ms, remove it: median {:.1} ms",
                        ins[ins.len() / 2],
                        rem[rem.len() / 2]
                    );
                }
                println!(
                    "{:>6} {:>8} {:>8} {:>9.0} {:>9.0} {:>9.0} {:>9.0} {:>9.0} {:>9.2}",
                    points.len(),
                    s.samples,
                    s.virtual_nodes,
                    total * 1e3 - t.total_ms(),
                    t.distances_ms,
                    t.voronoi_ms,
                    t.virtual_ms,
                    t.weights_ms,
                    total
                );
            }
            Err(e) => println!(
                "{:>6} refused after {:.2} s: {e:#}",
                points.len(),
                clock.elapsed().as_secs_f64()
            ),
        }
    }
}
