//! Inserting a point handle (weights up to date) on the meshes the editor and `c2warp`
//! build, not on a friendly grid: the built-in lizard, a giraffe (long neck and legs)
//! and a spider (eight thin legs), meshed by `pipeline::prepare` at 20k and 100k
//! vertices (and 620k with `INSERTION_SIZES=20000,100000,620000`), with 10 point
//! handles spread over the extremities (farthest-point sampling) or clustered (a
//! tight group near the middle). Each case first inserts a handle at each of 64 fixed
//! random vertices in turn, removing it again, and prints the median and the 90th
//! percentile of those 64 insertions; then criterion measures the mean over the same
//! positions.
//!
//! ```sh
//! cargo bench -p pipeline --bench insertion
//! INSERTION_ONLY=spider/spread cargo bench -p pipeline --bench insertion  # some cases
//! ```

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use weights_core::Handle;

#[path = "support/cutouts.rs"]
mod cutouts;

fn insertion(c: &mut Criterion) {
    let mut group = c.benchmark_group("insertion");
    group.sample_size(10);
    for name in cutouts::NAMES {
        let image = cutouts::picture(name);
        for spread in [true, false] {
            for &density in &cutouts::sizes() {
                let label = format!(
                    "{name}/{}/{}k",
                    if spread { "spread" } else { "clustered" },
                    density / 1000
                );
                if !cutouts::selected(&label) {
                    continue;
                }
                let mut rig = cutouts::rig(&image, spread, density);
                let positions = cutouts::positions(&rig);
                // Every position once, in order, for the median and the 90th percentile.
                let mut times = Vec::new();
                for &at in &positions {
                    let clock = Instant::now();
                    let inserted = rig.insert_handle(Handle::point(at));
                    let elapsed = clock.elapsed();
                    if let Ok(index) = inserted {
                        times.push(elapsed.as_secs_f64() * 1e3);
                        rig.remove_handle(index).expect("the handle just added");
                    }
                }
                eprintln!(
                    "{label}: {} samples, {} insertions: median {:.2} ms, p90 {:.2} ms",
                    rig.domain().len(),
                    times.len(),
                    cutouts::quantile(times.clone(), 0.5),
                    cutouts::quantile(times, 0.9)
                );
                let mut next = 0;
                group.bench_function(&label, |b| {
                    b.iter_custom(|iterations| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iterations {
                            let at = positions[next % positions.len()];
                            next += 1;
                            let clock = Instant::now();
                            let inserted = rig.insert_handle(Handle::point(at));
                            total += clock.elapsed();
                            if let Ok(index) = inserted {
                                rig.remove_handle(index).expect("the handle just added");
                            }
                        }
                        total
                    })
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, insertion);
criterion_main!(benches);
