//! Where an insertion's time goes on the benchmark's cut-outs: for each of the 64 fixed
//! positions of one case, the wall-clock time of inserting a point handle, the phases
//! (`UpdateTimings`), and the virtual handles before and after; then the median and the
//! 90th percentile.
//!
//! ```sh
//! cargo run --release -p pipeline --example insertion_report -- spider spread 100000
//! BUILD_ONLY=1 cargo run --release -p pipeline --example insertion_report -- giraffe spread 620000
//! ```

use std::time::Instant;

use weights_core::Handle;

#[path = "../benches/support/cutouts.rs"]
#[allow(dead_code)]
mod cutouts;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("spider", String::as_str);
    let spread = args.get(1).is_none_or(|s| s != "clustered");
    let density = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let image = cutouts::picture(name);
    let clock = Instant::now();
    let mut rig = cutouts::rig(&image, spread, density);
    let build = rig.timings();
    println!(
        "{name} {} {density}: {} samples, {} virtual handles, meshed and built in {:.0} ms; \
         the build (distances, Voronoi, virtual handles, weights) {:.1} ms: {:.1} + {:.1} + {:.1} + {:.1}",
        if spread { "spread" } else { "clustered" },
        rig.domain().len(),
        rig.stats().virtual_nodes,
        clock.elapsed().as_secs_f64() * 1e3,
        build.total_ms(),
        build.distances_ms,
        build.voronoi_ms,
        build.virtual_ms,
        build.weights_ms,
    );
    if std::env::var("BUILD_ONLY").is_ok() {
        return;
    }
    println!("  ms      plan  partition  virtual  weights  transforms  virtual handles");
    let mut times = Vec::new();
    for at in cutouts::positions(&rig) {
        let before = rig.stats().virtual_nodes;
        let clock = Instant::now();
        let Ok(index) = rig.insert_handle(Handle::point(at)) else {
            println!("  refused at {at}");
            continue;
        };
        let ms = clock.elapsed().as_secs_f64() * 1e3;
        let t = rig.update_timings();
        println!(
            "{ms:6.2}  {:6.2}  {:9.2}  {:7.2}  {:7.2}  {:10.2}  {before} -> {}",
            t.plan_ms,
            t.partition_ms,
            t.virtual_ms,
            t.weights_ms,
            t.transforms_ms,
            rig.stats().virtual_nodes
        );
        times.push(ms);
        rig.remove_handle(index).expect("the handle just added");
    }
    println!(
        "{} insertions: median {:.2} ms, p90 {:.2} ms",
        times.len(),
        cutouts::quantile(times.clone(), 0.5),
        cutouts::quantile(times, 0.9)
    );
}
