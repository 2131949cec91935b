//! How many virtual handles a rig needs when two handles are close, by their distance
//! (mesh edges of length 1): two points, or with `BAR=1` a point beside a bar.
//! One edge apart, every sample becomes a node (r_d < r_h leaves no room to grade);
//! from two edges on the refinement is graded. Run with
//! `cargo run --release -p weights-core --example close_pair`.
use glam::DVec2;
use weights_core::{Domain, Handle, Metric, Rig, RigOptions};

fn main() {
    let (nx, ny) = (150usize, 130usize);
    let mut p = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            p.push(DVec2::new(i as f64, j as f64));
        }
    }
    let mut t = Vec::new();
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    for metric in [Metric::Intrinsic, Metric::Euclidean] {
        for gap in [1.0, 2.0, 3.0, 6.0, 12.0, 24.0] {
            let d = Domain::new(p.clone(), t.clone(), metric).expect("a valid grid");
            let handles = if std::env::var("BAR").is_ok() {
                vec![
                    Handle::bar(DVec2::new(20.0, 60.0), DVec2::new(120.0, 60.0)),
                    Handle::point(DVec2::new(70.0, 60.0 + gap)),
                    Handle::point(DVec2::new(10.0, 10.0)),
                ]
            } else {
                vec![
                    Handle::point(DVec2::new(70.0, 60.0)),
                    Handle::point(DVec2::new(70.0 + gap, 60.0)),
                    Handle::point(DVec2::new(10.0, 10.0)),
                ]
            };
            let clock = std::time::Instant::now();
            let rig = Rig::new(d, handles, RigOptions::default()).expect("a valid rig");
            println!(
                "{metric:?} gap {gap}: {} virtual, {:?}",
                rig.stats().virtual_nodes,
                clock.elapsed()
            );
        }
    }
}
