//! `c2warp bench`: one JSON object of timings for a rig.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;
use weights_core::Handle;

use crate::{Source, export};
use pipeline::load_project;

#[derive(Serialize)]
struct Phases {
    distances: f64,
    voronoi: f64,
    virtual_handles: f64,
    weights: f64,
    total: f64,
}

#[derive(Serialize)]
struct Report {
    samples: usize,
    triangles: usize,
    metric: &'static str,
    real_handles: usize,
    handle_nodes: usize,
    boundary_nodes: usize,
    virtual_handles: usize,
    /// Full build (distances, Voronoi, virtual handles, weights), ms.
    build_ms: Phases,
    /// Median time to insert one point handle at a random sample, weights up to date.
    insert_ms_median: f64,
    /// Median time to remove it again.
    remove_ms_median: f64,
    /// Positions tried.
    positions: usize,
    /// Median time to deform every sample with the sparse weights.
    deform_ms_median: f64,
    nonzeros: usize,
    weight_bytes_per_nonzero: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Runs `c2warp bench`.
pub fn run(source: &Source, rig_path: &Path, positions: usize) -> Result<()> {
    let project = load_project(rig_path)?;
    let mut rig = export::build(source, &project)?.rig;
    let timings = rig.timings();
    let stats = rig.stats();
    let mut deform = Vec::new();
    let mut out = vec![glam::DVec2::ZERO; rig.domain().len()];
    for _ in 0..15 {
        let t = Instant::now();
        rig.deform_into(&mut out);
        deform.push(ms(t));
    }
    // Random samples (a fixed sequence, so runs compare).
    let n = rig.domain().len() as u64;
    let mut state = 0x2545F4914F6CDD1Du64;
    let (mut insert, mut remove) = (Vec::new(), Vec::new());
    let mut tries = 0;
    while insert.len() < positions && tries < positions * 10 {
        tries += 1;
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let p = rig.domain().positions()[(state % n) as usize];
        let t = Instant::now();
        let Ok(index) = rig.insert_handle(Handle::point(p)) else {
            continue;
        };
        insert.push(ms(t));
        let t = Instant::now();
        rig.remove_handle(index)?;
        remove.push(ms(t));
    }
    let report = Report {
        samples: stats.samples,
        triangles: rig.domain().triangles().len(),
        metric: match rig.domain().metric() {
            weights_core::Metric::Euclidean => "euclidean",
            weights_core::Metric::Intrinsic => "intrinsic",
        },
        real_handles: stats.real_handles,
        handle_nodes: stats.handle_nodes,
        boundary_nodes: stats.boundary_nodes,
        virtual_handles: stats.virtual_nodes,
        build_ms: Phases {
            distances: timings.distances_ms,
            voronoi: timings.voronoi_ms,
            virtual_handles: timings.virtual_ms,
            weights: timings.weights_ms,
            total: timings.total_ms(),
        },
        positions: insert.len(),
        insert_ms_median: median(insert),
        remove_ms_median: median(remove),
        deform_ms_median: median(deform),
        nonzeros: stats.nonzeros,
        weight_bytes_per_nonzero: stats.weight_bytes as f64 / stats.nonzeros.max(1) as f64,
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
