//! What one frame of playback costs the editor's CPU, for every method, on the
//! built-in lizard at the default density (20k vertices): the keys' pose at the
//! frame's time, the method's update (C²'s node transforms, ARAP's solve, MLS's fits,
//! LBC's cage), and the GPU frame brought up to date (what a frame uploads). The same
//! for the control cursor of the perform tool: the blend of three pose markers at a
//! moving cursor, and the update. The GPU's own drawing is not in these figures (on a
//! real GPU it is a fraction of a millisecond for 40k triangles).
//!
//! Playback and the cursor pose live, as a drag does (ARAP starts from the frame before
//! and stops early); when playback stops the pose is solved in full, and the example
//! says how far that moves the picture.
//!
//! `cargo run --release -p editor --example playback [-- FRAMES]`

use std::time::Instant;

use anyhow::Result;
use glam::DVec2;
use project::{
    Animation, HandlePose, HandleSpec, Interpolation, Key, Method, Pose, Project, SpatialKey,
};

use editor::{Document, Edit, EditorApp};

/// A pose of `project`'s handles `k` steps along: points moved and turned, bars turned
/// about their first end; the cage's vertices pushed out.
fn pose(project: &Project, k: f64) -> Pose {
    let handles = project
        .handles
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let s = k * if i % 2 == 0 { 1.0 } else { -1.0 };
            match *h {
                HandleSpec::Point { .. } => HandlePose::Point {
                    translate: [12.0 * s, -8.0 * s],
                    rotate: 0.15 * s,
                    scale: 1.0,
                },
                HandleSpec::Bar { rest: [a, b], .. } => {
                    let (a, b) = (DVec2::from(a), DVec2::from(b));
                    let turned = a + DVec2::from_angle(0.1 * s).rotate(b - a);
                    HandlePose::Bar {
                        pose: [a.to_array(), turned.to_array()],
                    }
                }
            }
        })
        .collect();
    let cage = project.cage.as_ref().map(|c| {
        let n = c.rest.len() as f64;
        let centre = c.rest.iter().fold(DVec2::ZERO, |s, p| s + DVec2::from(*p)) / n;
        c.rest
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let p = DVec2::from(*p);
                let push = if i % 3 == 0 { 0.06 * k } else { 0.0 };
                (p + (p - centre) * push).to_array()
            })
            .collect()
    });
    Pose {
        handles,
        cage,
        overlaps: Vec::new(),
    }
}

/// Median, 90th percentile and largest of `times` (milliseconds).
fn summary(mut times: Vec<f64>) -> String {
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize];
    format!(
        "median {:.3} ms, p90 {:.3} ms, max {:.3} ms ({} frames)",
        at(0.5),
        at(0.9),
        at(1.0),
        times.len()
    )
}

fn main() -> Result<()> {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(240);
    for method in Method::ALL {
        let mut doc = Document::built_in()?;
        if method == Method::Lbc {
            let (w, h) = doc.image.dimensions();
            let offset = pipeline::cage::outline_offset(w, h);
            let ring = pipeline::cage::cage_from_outline(&doc.image, 16, offset)?;
            doc.apply(Edit::Cage {
                rest: ring.iter().map(|p| p.to_array()).collect(),
                vertices: pipeline::DEFAULT_DENSITY,
            })?;
            doc.solve_cage(&mut |_| true)?;
        } else {
            doc.apply(Edit::Method(method))?;
        }
        let project = doc.project().clone();
        let keys = (0..3)
            .map(|k| Key {
                time: k as f64,
                hold: false,
                pose: pose(&project, [0.0, 3.0, -2.0][k]),
            })
            .collect();
        let spatial_keys = [[100.0, 100.0], [600.0, 120.0], [350.0, 600.0]]
            .iter()
            .enumerate()
            .map(|(k, &at)| SpatialKey {
                at,
                pose: pose(&project, [0.0, 3.0, -2.0][k]),
            })
            .collect();
        doc.apply(Edit::Animation(Some(Box::new(Animation {
            interpolation: Interpolation::Smooth,
            keys,
            spatial_keys,
            ..Animation::default()
        }))))?;
        let vertices = doc.deformer().rest().len();
        let mut app = EditorApp::with_document(doc);
        app.update_gpu_frame();
        // Playback: the time of each frame over the two seconds of keys.
        let mut times = Vec::with_capacity(frames);
        for i in 0..frames {
            // As playback does: the wall clock's time, between frames of the rate too.
            let t = 2.0 * i as f64 / frames as f64;
            let clock = Instant::now();
            if let Some(doc) = app.document_mut() {
                doc.play_time(t)?;
            }
            app.update_gpu_frame();
            times.push(clock.elapsed().as_secs_f64() * 1e3);
        }
        // When playback stops, the pose shown is solved in full: how far that moves the
        // last live frame's picture.
        let settled = match app.document_mut() {
            Some(doc) => {
                let live = doc.deformer().deformed();
                doc.settle()?;
                let settled = doc.deformer().deformed();
                live.iter()
                    .zip(&settled)
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f64::max)
            }
            None => 0.0,
        };
        println!(
            "{:<4} playback  {vertices:>6} vertices: {}; stopping moves it {settled:.3} px",
            method.name(),
            summary(times)
        );
        // The control cursor: a circle through the three markers' triangle.
        let project = app
            .document()
            .map(|d| d.project().clone())
            .unwrap_or_default();
        let blend = animation::SpatialBlend::of(&project).expect("three markers");
        let mut times = Vec::with_capacity(frames);
        for i in 0..frames {
            let angle = std::f64::consts::TAU * i as f64 / frames as f64;
            let at = DVec2::new(350.0, 300.0) + 220.0 * DVec2::from_angle(angle);
            let clock = Instant::now();
            let pose = blend
                .pose(&project, at.to_array())
                .expect("the markers blended");
            if let Some(doc) = app.document_mut() {
                // As the perform tool's drag does: a live preview.
                let mut posed = doc.project().clone();
                pose.apply(&mut posed);
                doc.preview(posed)?;
            }
            app.update_gpu_frame();
            times.push(clock.elapsed().as_secs_f64() * 1e3);
        }
        println!(
            "{:<4} cursor    {vertices:>6} vertices: {}",
            method.name(),
            summary(times)
        );
    }
    Ok(())
}
