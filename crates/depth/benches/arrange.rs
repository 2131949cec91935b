//! Automatic depth's cost per pose: a body of about 10,000 vertices (a grid of
//! unit cells) and a limb of about 2,000 laid across it, and the same with the limb
//! beside it (no overlap: the cost every drag frame pays).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;

/// A grid of `w × h` cells placed by `place`, appended to the mesh.
fn grid(
    positions: &mut Vec<DVec2>,
    triangles: &mut Vec<[u32; 3]>,
    w: u32,
    h: u32,
    place: impl Fn(f64, f64) -> DVec2,
) {
    let base = positions.len() as u32;
    for y in 0..=h {
        for x in 0..=w {
            positions.push(place(f64::from(x), f64::from(y)));
        }
    }
    let at = |x: u32, y: u32| base + y * (w + 1) + x;
    for y in 0..h {
        for x in 0..w {
            triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
            triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
        }
    }
}

fn scene(across: bool) -> (Vec<DVec2>, Vec<[u32; 3]>) {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    grid(&mut positions, &mut triangles, 100, 100, |x, y| {
        DVec2::new(x, y) * 4.0
    });
    let (dx, angle) = if across { (120.0, 0.6) } else { (600.0, 0.0) };
    grid(&mut positions, &mut triangles, 200, 10, |x, y| {
        let along = DVec2::from_angle(angle);
        DVec2::new(dx, 40.0) + (along * x + along.perp() * y) * 2.0
    });
    (positions, triangles)
}

fn arrange(c: &mut Criterion) {
    for (name, across) in [("beside", false), ("across", true)] {
        let (positions, triangles) = scene(across);
        let predefined: Vec<u32> = (0..triangles.len() as u32).collect();
        let first = depth::arrange(&positions, &triangles, &predefined, &[]);
        assert_eq!(first.regions.is_empty(), !across);
        c.bench_function(
            &format!("depth/arrange/{}k_triangles_{name}", triangles.len() / 1000),
            |b| b.iter(|| depth::arrange(&positions, &triangles, &predefined, &first.regions)),
        );
        let rest = scene(false).0;
        let topology = depth::Topology::new(&rest, &triangles);
        c.bench_function(
            &format!(
                "depth/arrange_on/{}k_triangles_{name}",
                triangles.len() / 1000
            ),
            |b| {
                b.iter(|| {
                    let on = Some(&topology);
                    depth::arrange_on(on, &positions, &triangles, &predefined, &first.regions)
                })
            },
        );
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = arrange
}
criterion_main!(benches);
