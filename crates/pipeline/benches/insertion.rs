//! Inserting a point handle (weights up to date) on the meshes the editor and `c2warp`
//! build, not on a friendly grid: the built-in lizard, a giraffe (long neck and legs)
//! and a spider (eight thin legs), meshed by `pipeline::prepare` at 20k and 100k
//! vertices (and 620k with `INSERTION_SIZES=20000,100000,620000`), with 10 point
//! handles spread over the extremities (farthest-point sampling) or clustered (a
//! tight group near the middle). Each case first inserts a handle at each of 64 fixed
//! random vertices in turn, removing it again, and prints the median and the 90th
//! percentile of those 64 insertions; then goes over the positions again
//! (`INSERTION_PASSES` passes in all, 3 unless set) and prints the same of each
//! position's fastest insertion; then criterion measures the mean over the same
//! positions.
//!
//! ```sh
//! cargo bench -p pipeline --bench insertion
//! INSERTION_ONLY=spider/spread cargo bench -p pipeline --bench insertion  # some cases
//! INSERTION_PASSES=1 cargo bench -p pipeline --bench insertion  # one pass only
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
                // Every position once, in order, for the median and the 90th percentile;
                // then more passes, keeping each position's fastest time (what the
                // insertion costs when nothing else on the machine gets in its way).
                let passes = cutouts::passes();
                let mut first = Vec::new();
                let mut best = vec![f64::INFINITY; positions.len()];
                for pass in 0..passes {
                    for (i, &at) in positions.iter().enumerate() {
                        let clock = Instant::now();
                        let inserted = rig.insert_handle(Handle::point(at));
                        let elapsed = clock.elapsed().as_secs_f64() * 1e3;
                        if let Ok(index) = inserted {
                            if pass == 0 {
                                first.push(elapsed);
                            }
                            best[i] = best[i].min(elapsed);
                            rig.remove_handle(index).expect("the handle just added");
                        }
                    }
                }
                let best: Vec<f64> = best.into_iter().filter(|t| t.is_finite()).collect();
                eprintln!(
                    "{label}: {} samples, {} insertions: median {:.2} ms, p90 {:.2} ms; \
                     best of {} passes: median {:.2} ms, p90 {:.2} ms",
                    rig.domain().len(),
                    first.len(),
                    cutouts::quantile(first.clone(), 0.5),
                    cutouts::quantile(first, 0.9),
                    passes,
                    cutouts::quantile(best.clone(), 0.5),
                    cutouts::quantile(best, 0.9)
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
