//! How much the picture jumps when a handle is inserted into a posed rig, as the editor
//! inserts it (the picture point under the click, the pose's local rotation and
//! scale there): the largest move of a mesh vertex outside the new handle's own cell,
//! before against after, over insertions at fixed random places.
//!
//! `cargo run --release -p editor --example insertion_jump -- [c2|arap] [INSERTIONS]`

use glam::DVec2;
use project::{HandleSpec, Method};

use editor::{Document, Edit};

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
}

/// One insertion's jump, in pixels: outside the new handle's own cell, and near it
/// (within twice the distance from it to its nearest node).
type Jump = (f64, f64);

/// The jumps of `insertions` point handles (and as many bars) inserted one at a time
/// (each undone before the next) into `doc`'s posed rig, in pixels.
fn jumps(doc: &mut Document, insertions: usize) -> (Vec<Jump>, Vec<Jump>) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut points, mut bars) = (Vec::new(), Vec::new());
    let mut tries = 0;
    while (points.len() < insertions || bars.len() < insertions) && tries < 50 * insertions {
        tries += 1;
        let n = doc.rig().domain().len();
        let v = (rng.next() % n as u64) as usize;
        let w = (rng.next() % n as u64) as usize;
        let deformed = doc.deformed().to_vec();
        let snapshot = doc.snapshot();
        let bar = points.len() >= insertions;
        let added = if bar {
            let (a, b) = (deformed[v], deformed[w]);
            if a.distance(b) > 80.0 || a.distance(b) < 20.0 {
                continue;
            }
            editor_bar(doc, a, b)
        } else {
            editor_point(doc, deformed[v])
        };
        if !added {
            continue;
        }
        let after = doc.deformed().to_vec();
        let rig = doc.rig();
        let new = doc.project().handles.len() - 1;
        let own: Vec<u32> = (0..rig.nodes().len())
            .filter(|&k| {
                rig.owner_handle(k) == Some(new)
                    && rig.nodes()[k].kind != weights_core::NodeKind::Virtual
            })
            .map(|k| k as u32)
            .collect();
        let cells = rig.cells();
        let (jump, at) = deformed
            .iter()
            .zip(&after)
            .enumerate()
            .filter(|(i, _)| !own.contains(&cells[*i]))
            .map(|(i, (a, b))| (a.distance(*b), i))
            .fold((0.0, 0), |m, x| if x.0 > m.0 { x } else { m });
        if std::env::var("WHERE").is_ok() {
            // Where the largest move is, how far from the new handle.
            let rest = rig.domain().positions();
            let node = rig.nodes()[own[0] as usize].vertex as usize;
            eprintln!(
                "jump {jump:.1} at {:.0?}, {:.0} px from the new handle; virtual {} -> {}",
                rest[at],
                rest[at].distance(rest[node]),
                snapshot.virtual_handles.len(),
                rig.virtual_vertices().len()
            );
        }
        // Near the new handle: within twice the distance from it to its nearest node.
        let rest = rig.domain().positions();
        let node = rest[rig.nodes()[own[0] as usize].vertex as usize];
        let reach = rig
            .nodes()
            .iter()
            .enumerate()
            .filter(|(k, _)| !own.contains(&(*k as u32)))
            .map(|(_, n)| rest[n.vertex as usize].distance(node))
            .fold(f64::INFINITY, f64::min);
        let near = deformed
            .iter()
            .zip(&after)
            .enumerate()
            .filter(|(i, _)| !own.contains(&cells[*i]) && rest[*i].distance(node) < 2.0 * reach)
            .map(|(_, (a, b))| a.distance(*b))
            .fold(0.0, f64::max);
        if bar {
            bars.push((jump, near));
        } else {
            points.push((jump, near));
        }
        doc.undo_to(snapshot).expect("undo");
    }
    (points, bars)
}

/// What `EditorApp::add_point` does.
fn editor_point(doc: &mut Document, at: DVec2) -> bool {
    let Some((rest, rotate, scale)) = doc.unwarp(at) else {
        return false;
    };
    let (rotate, scale) = if std::env::var("TRIANGLE").is_ok() {
        (rotate, scale)
    } else {
        doc.local_pose(rest, at)
    };
    let handle = HandleSpec::Point {
        rest: rest.to_array(),
        translate: (at - rest).to_array(),
        rotate,
        scale,
        depth: 0,
    };
    doc.apply(Edit::Add(handle)).is_ok()
}

/// What `EditorApp::add_bar` does.
fn editor_bar(doc: &mut Document, a: DVec2, b: DVec2) -> bool {
    let (Some((ra, _, _)), Some((rb, _, _))) = (doc.unwarp(a), doc.unwarp(b)) else {
        return false;
    };
    let handle = HandleSpec::Bar {
        rest: [ra.to_array(), rb.to_array()],
        pose: Some([a.to_array(), b.to_array()]),
        depth: 0,
    };
    doc.apply(Edit::Add(handle)).is_ok()
}

fn summary(name: &str, jumps: Vec<Jump>) {
    let mut v: Vec<f64> = jumps.iter().map(|j| j.0).collect();
    let mut n: Vec<f64> = jumps.iter().map(|j| j.1).collect();
    n.sort_by(f64::total_cmp);
    if !n.is_empty() {
        let at = |q: f64| n[((n.len() - 1) as f64 * q).round() as usize];
        println!(
            "  {name} near the new handle: median {:.2} px, p90 {:.2} px, largest {:.2} px",
            at(0.5),
            at(0.9),
            at(1.0)
        );
    }
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        println!("  {name}: none");
        return;
    }
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    println!(
        "  {name} ({}): median {:.2} px, p90 {:.2} px, largest {:.2} px",
        v.len(),
        at(0.5),
        at(0.9),
        at(1.0)
    );
}

fn main() -> anyhow::Result<()> {
    let method = match std::env::args().nth(1).as_deref() {
        Some("arap") => Method::Arap,
        _ => Method::C2,
    };
    let insertions: usize = std::env::args()
        .nth(2)
        .and_then(|n| n.parse().ok())
        .unwrap_or(24);
    let mut doc = Document::built_in()?;
    doc.apply(Edit::Method(method))?;
    let (points, bars) = jumps(&mut doc, insertions);
    println!("built-in lizard, posed, {}:", method.label());
    summary("points", points);
    summary("bars", bars);
    Ok(())
}
