//! Times reading a layered file and flattening it: the median of several runs.
//!
//! `cargo run --release -p layers --example read_time -- FILE.psd [RUNS]`

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: read_time FILE [RUNS]")?;
    let runs: usize = args.next().map_or(Ok(5), |r| r.parse())?;
    let bytes = std::fs::read(&path)?;
    let limits = render::ImageLimits::default();
    let (mut read, mut flat) = (Vec::new(), Vec::new());
    let mut layers = 0;
    for _ in 0..runs {
        let clock = Instant::now();
        let artwork = layers::decode(&bytes, &limits)?;
        read.push(clock.elapsed().as_secs_f64() * 1e3);
        let clock = Instant::now();
        let picture = artwork.flatten();
        flat.push(clock.elapsed().as_secs_f64() * 1e3);
        layers = artwork.layers.len();
        std::hint::black_box(picture);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{path}: {layers} layers, {} MB; read {:.0} ms, flatten {:.0} ms (median of {runs})",
        bytes.len() >> 20,
        median(&mut read),
        median(&mut flat)
    );
    Ok(())
}
