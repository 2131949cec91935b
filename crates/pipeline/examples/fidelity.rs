//! How many virtual handles the project's own rules place, against the paper's rules,
//! on the same meshes (see "Fidelity counts" in docs/methods/c2.md):
//!
//! 1. Algorithm 1 as written (one virtual handle a round, in the worst cell) against
//!    the symmetric placement (tied cells together, close candidates merged), on close
//!    pairs on a regular grid and on the cut-outs' spread and clustered rigs.
//! 2. The paper's bar cutting (every bar into ⌈L/d⌉ pieces, d the smallest distance
//!    between any two handles) against ours (a bar's own distance to its nearest
//!    handle, at most 16 pieces), on a point beside a bar and on the lizard's rig.
//! 3. Insertion: the virtual handles after inserting a handle into a built rig (those
//!    in place stay; those the new handle crowds go) against a build from scratch with
//!    the same handles, at the insertion benchmark's 64 positions.
//!
//! ```sh
//! cargo run --release -p pipeline --example fidelity [density]
//! ```

use geometry::point_segment_distance;
use glam::DVec2;
use pipeline::{DEFAULT_IMAGE, prepare};
use project::Project;
use weights_core::{Domain, Handle, Metric, Placement, Rig, RigOptions, bar_samples};

#[path = "../benches/support/cutouts.rs"]
#[allow(dead_code)]
mod cutouts;

fn options(placement: Placement) -> RigOptions {
    RigOptions {
        placement,
        ..RigOptions::default()
    }
}

fn virtual_count(domain: &Domain, handles: &[Handle], placement: Placement) -> usize {
    Rig::new(domain.clone(), handles.to_vec(), options(placement))
        .map_or(usize::MAX, |rig| rig.stats().virtual_nodes)
}

fn segment(h: &Handle) -> [DVec2; 2] {
    match h {
        Handle::Point { rest, .. } => [*rest, *rest],
        Handle::Bar { rest, .. } => *rest,
    }
}

/// Distance between two segments (points are segments of length 0), from their ends
/// alone: segments that cross count as apart.
fn segment_distance(a: [DVec2; 2], b: [DVec2; 2]) -> f64 {
    let to_segment = |p: DVec2, s: [DVec2; 2]| point_segment_distance(p, s[0], s[1]);
    [
        to_segment(a[0], b),
        to_segment(a[1], b),
        to_segment(b[0], a),
        to_segment(b[1], a),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// The handles with every bar replaced by point handles where the paper cuts it:
/// ⌈L/d⌉ pieces, d the smallest distance between any two handles. (A node's place is
/// all Algorithm 1 sees, so the count of virtual handles is the paper's.)
fn paper_bar_samples(handles: &[Handle]) -> Vec<Handle> {
    let mut d = f64::INFINITY;
    for i in 0..handles.len() {
        for j in i + 1..handles.len() {
            d = d.min(segment_distance(segment(&handles[i]), segment(&handles[j])));
        }
    }
    handles
        .iter()
        .flat_map(|h| match h {
            Handle::Point { .. } => vec![h.clone()],
            Handle::Bar { rest, .. } => bar_samples(*rest, d)
                .into_iter()
                .map(|(_, p)| Handle::point(p))
                .collect(),
        })
        .collect()
}

fn grid(nx: usize, ny: usize) -> Domain {
    let mut p = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            p.push(DVec2::new(i as f64, j as f64));
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut t = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Domain::new(p, t, Metric::Intrinsic).expect("a valid grid")
}

fn main() {
    let density: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let (as_written, symmetric) = (Placement::AsWritten, Placement::Symmetric);

    println!(
        "1. Close pairs on a 150 × 130 grid of unit edges (intrinsic), a third handle far away"
    );
    println!(
        "   gap  | two points: as written / symmetric | point beside a 100-long bar: as written / symmetric / paper's bar cutting"
    );
    let domain = grid(150, 130);
    for gap in [2.0, 3.0, 6.0, 12.0, 24.0] {
        let points = vec![
            Handle::point(DVec2::new(70.0, 60.0)),
            Handle::point(DVec2::new(70.0 + gap, 60.0)),
            Handle::point(DVec2::new(10.0, 10.0)),
        ];
        let bar = vec![
            Handle::bar(DVec2::new(20.0, 60.0), DVec2::new(120.0, 60.0)),
            Handle::point(DVec2::new(70.0, 60.0 + gap)),
            Handle::point(DVec2::new(10.0, 10.0)),
        ];
        println!(
            "   {gap:4} | {:5} / {:5} | {:5} / {:5} / {:5}",
            virtual_count(&domain, &points, as_written),
            virtual_count(&domain, &points, symmetric),
            virtual_count(&domain, &bar, as_written),
            virtual_count(&domain, &bar, symmetric),
            virtual_count(&domain, &paper_bar_samples(&bar), as_written),
        );
    }

    println!("\n2. Cut-outs at {density} vertices, 10 point handles: as written / symmetric");
    for name in cutouts::NAMES {
        let image = cutouts::picture(name);
        for spread in [true, false] {
            let rig = cutouts::rig(&image, spread, density);
            let handles = rig.handles().to_vec();
            println!(
                "   {name:8} {:9}: {:4} / {:4}",
                if spread { "spread" } else { "clustered" },
                virtual_count(rig.domain(), &handles, as_written),
                virtual_count(rig.domain(), &handles, symmetric),
            );
        }
    }
    let lizard = image::load_from_memory(DEFAULT_IMAGE)
        .expect("the built-in picture")
        .to_rgba8();
    let project = Project::from_json(include_str!("../../../assets/lizard-rig.json"))
        .expect("the sample rig");
    let rig = prepare(&lizard, &project, Some(density))
        .expect("a rig")
        .rig;
    let handles = rig.handles().to_vec();
    println!(
        "   lizard-rig.json (6 points, 1 bar): ours {} (bar in {} samples) / paper's bar cutting {} ({} samples)",
        virtual_count(rig.domain(), &handles, as_written),
        rig.stats().handle_nodes - 6,
        virtual_count(rig.domain(), &paper_bar_samples(&handles), as_written),
        paper_bar_samples(&handles).len() - 6,
    );

    println!("\n3. Insertion at the 64 benchmark positions ({density} vertices, spread handles):");
    println!(
        "   virtual handles after the insertion / after a build from scratch (sums; as written)"
    );
    for name in cutouts::NAMES {
        let image = cutouts::picture(name);
        let mut rig = cutouts::rig(&image, true, density);
        let (mut kept, mut fresh, mut fewer, mut more) = (0, 0, 0, 0);
        for at in cutouts::positions(&rig) {
            let Ok(index) = rig.insert_handle(Handle::point(at)) else {
                continue;
            };
            let after = rig.stats().virtual_nodes;
            let scratch = virtual_count(rig.domain(), rig.handles(), as_written);
            kept += after;
            fresh += scratch;
            fewer += usize::from(after < scratch);
            more += usize::from(after > scratch);
            rig.remove_handle(index).expect("the handle just added");
        }
        println!(
            "   {name:8}: {kept} / {fresh} ({:+.1}%; fewer at {fewer}, more at {more} of 64 positions)",
            (kept as f64 / fresh as f64 - 1.0) * 100.0
        );
    }
}
