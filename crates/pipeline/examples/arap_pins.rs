//! How ARAP's pins follow and hold at the product's densities (see
//! `tests/support/pins.rs`): `cargo run --release -p pipeline --example arap_pins --
//! [ARAP settings as JSON, e.g. '{"pin_radius": 0}'] [FOLDER]`; with a folder, the
//! warped pictures at each density are written there as PNG.

#[path = "../tests/support/figure.rs"]
mod figure;
#[path = "../tests/support/pins.rs"]
mod pins;

fn main() {
    let arap = std::env::args().nth(1).filter(|a| a != "-");
    let folder = std::env::args().nth(2).map(std::path::PathBuf::from);
    for case in [pins::opaque(), pins::figure()] {
        let mut warps = Vec::new();
        for density in [500, 2_000, 5_000, 20_000, 80_000] {
            let clock = std::time::Instant::now();
            let (report, deformed, domain) = pins::measure(&case, density, arap.as_deref());
            println!(
                "{}, density {density} ({} vertices): follow {:.2}, hold {:.3}, pin off by \
                 {:.2} px, {} folded triangles ({:.0} ms)",
                case.name,
                report.vertices,
                report.follow,
                report.hold,
                report.pin_error,
                report.folds,
                clock.elapsed().as_secs_f64() * 1e3
            );
            if let Some(folder) = &folder {
                let project = case.project(arap.as_deref());
                let warper = pipeline::prepare_warper(&case.image, &project, Some(density), &())
                    .expect("warper");
                let name = case.name.split(' ').next().unwrap_or("case");
                pipeline::warp(&case.image, &warper)
                    .expect("warp")
                    .save(folder.join(format!("{name}-{density}.png")))
                    .expect("write");
            }
            warps.push((density, domain, deformed));
        }
        let at = |d: usize| {
            let (_, domain, deformed) = warps.iter().find(|w| w.0 == d).expect("warped");
            (domain, deformed.as_slice())
        };
        println!(
            "{}: 5,000 against 80,000 differ by at most {:.2}% of the diagonal",
            case.name,
            100.0 * pins::largest_difference(&case, at(5_000), at(80_000))
        );
    }
}
