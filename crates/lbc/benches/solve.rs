//! The whole solve (geodesics, factorisation, ADMM, projection) on the cages of
//! `cases/mod.rs`, the sizes of the paper's Table 2:
//! `cargo bench -p lbc --bench solve`. `examples/solve_report.rs` prints the
//! iterations and the time of each stage for the same cages.

mod cases;

use criterion::{Criterion, criterion_group, criterion_main};
use lbc::{Settings, solve};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("lbc_solve");
    group.sample_size(10);
    for case in cases::cases() {
        let domain = cases::domain(&case);
        let name = format!(
            "{} ({} cage vertices, {} mesh vertices)",
            case.name,
            case.cage.len(),
            domain.positions().len()
        );
        group.bench_function(name, |b| {
            b.iter(|| solve(&domain, &Settings::default(), &mut |_| true).expect("solves"));
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
