//! `c2warp bench`: one JSON object of timings for a rig.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;
use weights_core::Handle;

use crate::{Source, export};
use pipeline::{ArapOptions, ArapRig, Deformer, Method, load_project};

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
    /// 90th percentile of the insertions.
    insert_ms_p90: f64,
    /// Median time to remove it again.
    remove_ms_median: f64,
    /// 90th percentile of the removals.
    remove_ms_p90: f64,
    /// Positions tried.
    positions: usize,
    /// Median time to deform every sample with the sparse weights.
    deform_ms_median: f64,
    nonzeros: usize,
    weight_bytes_per_nonzero: f64,
}

fn median(v: Vec<f64>) -> f64 {
    quantile(v, 0.5)
}

/// The `q`-quantile (nearest rank) of `v`; NaN for none.
fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// ARAP's steps, timed.
#[derive(Serialize)]
struct ArapReport {
    method: &'static str,
    samples: usize,
    triangles: usize,
    real_handles: usize,
    /// Vertices of the mesh ARAP solves on (its own mesh of the picture, or the given
    /// mesh).
    arap_vertices: usize,
    /// What each handle holds, pixels (0: its nearest vertex).
    pin_radius: f64,
    /// Vertices the handles pin.
    pinned_vertices: usize,
    /// Registration (once per mesh; ARAP's meshing of the picture included), ms.
    registration_ms: f64,
    /// Median compilation (factorising both steps' systems), ms.
    compile_ms_median: f64,
    /// Median update (a new pose: step one, the fit, step two), ms.
    update_ms_median: f64,
    /// 90th percentile of the updates, ms.
    update_ms_p90: f64,
    /// Poses timed.
    poses: usize,
}

/// Runs `c2warp bench` for `method` (else the rig's).
pub fn run(
    source: &Source,
    rig_path: &Path,
    positions: usize,
    method: Option<Method>,
) -> Result<()> {
    let project = load_project(rig_path)?;
    let method = method.unwrap_or(project.method);
    if method == Method::Lbc {
        return crate::lbc::bench(source, &project);
    }
    let built = export::build(source, &project, &|_| {})?;
    match method {
        Method::Arap => arap(built.rig, built.picture.as_ref(), &project, positions),
        _ => c2(built.rig, positions),
    }
}

/// Times ARAP on the rig's handles (on its own mesh of `picture`, else on the rig's
/// mesh): registration once, compilation by dropping and restoring the last handle,
/// updates over `poses` random poses.
fn arap(
    rig: weights_core::Rig,
    picture: Option<&image::RgbaImage>,
    project: &project::Project,
    poses: usize,
) -> Result<()> {
    let handles = rig.handles().to_vec();
    let domain = rig.domain().clone();
    let strokes = &project.rigidity;
    let mut arap = match picture {
        Some(p) => {
            let options = ArapOptions::for_picture(project, p);
            ArapRig::with_own_mesh(p, domain, &handles, strokes, options)?
        }
        None => ArapRig::new(domain, &handles, strokes, ArapOptions::of(project, None))?,
    };
    let registration_ms = arap.times().registration_ms;
    let mut compile = vec![arap.times().compile_ms];
    if let Some((_, fewer)) = handles.split_last() {
        for _ in 0..4 {
            arap.set_handles(fewer)?;
            arap.set_handles(&handles)?;
            compile.push(arap.times().compile_ms);
        }
    }
    let pinned_vertices = arap.pinned();
    let scale = rig.domain().mean_edge_length() * 10.0;
    let mut state = 0x2545F4914F6CDD1Du64;
    let mut random = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut update = Vec::new();
    for _ in 0..poses.max(1) {
        let posed: Vec<Handle> = handles
            .iter()
            .map(|h| match *h {
                Handle::Point {
                    rest,
                    mut transform,
                } => {
                    transform.translation += glam::DVec2::new(random(), random()) * scale;
                    Handle::Point { rest, transform }
                }
                Handle::Bar { rest, pose } => {
                    let d = glam::DVec2::new(random(), random()) * scale;
                    Handle::Bar {
                        rest,
                        pose: [pose[0] + d, pose[1] + d],
                    }
                }
            })
            .collect();
        arap.set_handles(&posed)?;
        update.push(arap.times().update_ms);
    }
    let mut sorted = update.clone();
    sorted.sort_by(f64::total_cmp);
    let report = ArapReport {
        method: "arap",
        samples: rig.domain().len(),
        triangles: rig.domain().triangles().len(),
        real_handles: handles.len(),
        arap_vertices: arap.arap_mesh().len(),
        pin_radius: arap.options().pin_radius,
        pinned_vertices,
        registration_ms,
        compile_ms_median: median(compile),
        update_ms_p90: quantile(sorted.clone(), 0.9),
        update_ms_median: median(update),
        poses: sorted.len(),
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

/// Times the C² rig: the build's phases, insertions and removals at `positions`
/// random samples, deformation.
fn c2(mut rig: weights_core::Rig, positions: usize) -> Result<()> {
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
        insert_ms_p90: quantile(insert.clone(), 0.9),
        insert_ms_median: median(insert),
        remove_ms_p90: quantile(remove.clone(), 0.9),
        remove_ms_median: median(remove),
        deform_ms_median: median(deform),
        nonzeros: stats.nonzeros,
        weight_bytes_per_nonzero: stats.weight_bytes as f64 / stats.nonzeros.max(1) as f64,
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
