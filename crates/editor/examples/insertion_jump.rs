//! How much the picture moves when a handle is inserted into a posed rig, or one is
//! removed from it, as the editor does it (an insertion: the picture point under the
//! click, the pose's local rotation and scale there).
//!
//! For each insertion (points, then bars, at fixed random places, each undone before
//! the next) and each removal (every handle of the rig, each undone before the next):
//! the largest move of a mesh vertex of the picture anywhere, and outside the new
//! (removed) handle's neighbourhood — farther from it than twice the distance to its
//! nearest other handle at rest (for an insertion under C², outside its own Voronoi
//! cell too: the figure the paper's insertion is measured by).
//!
//! `cargo run --release -p editor --example insertion_jump -- [c2|arap|mls] [lizard|giraffe|spider] [INSERTIONS]`
//! (`HOLDS=off`: ARAP's new pins hold nothing, as before they did; `SOLVER=two-step`:
//! ARAP's two steps alone)

use glam::DVec2;
use project::{HandleSpec, Method, Project};

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

    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One change's moves, in pixels: anywhere, away from the handle, and (insertions
/// under C²) outside the new handle's own cell.
#[derive(Clone, Copy, Default)]
struct Jump {
    anywhere: f64,
    away: f64,
    outside_cell: f64,
}

/// The largest moves between `before` and `after` (the picture's mesh), away from
/// `at` (rest) beyond `reach`, and outside the vertices in `own`.
fn jump(
    before: &[DVec2],
    after: &[DVec2],
    rest: &[DVec2],
    at: &[DVec2],
    reach: f64,
    own: &dyn Fn(usize) -> bool,
) -> Jump {
    let mut j = Jump::default();
    for (i, (a, b)) in before.iter().zip(after).enumerate() {
        let d = a.distance(*b);
        j.anywhere = j.anywhere.max(d);
        let near = at
            .iter()
            .any(|p| geometry::point_segment_distance(rest[i], *p, *p) < reach);
        if !near {
            j.away = j.away.max(d);
        }
        if !own(i) {
            j.outside_cell = j.outside_cell.max(d);
        }
    }
    j
}

/// The rest points of a handle (a point's, a bar's two ends and its middle).
fn rest_points(h: &HandleSpec) -> Vec<DVec2> {
    match *h {
        HandleSpec::Point { rest, .. } => vec![DVec2::from(rest)],
        HandleSpec::Bar { rest, .. } => {
            let (a, b) = (DVec2::from(rest[0]), DVec2::from(rest[1]));
            vec![a, (a + b) * 0.5, b]
        }
    }
}

/// Twice the distance from handle `i` to its nearest other handle, at rest.
fn reach(project: &Project, i: usize) -> f64 {
    let mine = rest_points(&project.handles[i]);
    let nearest = project
        .handles
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .flat_map(|(_, h)| rest_points(h))
        .flat_map(|p| mine.iter().map(move |q| p.distance(*q)))
        .fold(f64::INFINITY, f64::min);
    2.0 * nearest.min(1e6)
}

/// The jumps of `insertions` point handles (and as many bars) inserted one at a time
/// (each undone before the next) into `doc`'s posed rig.
fn insertion_jumps(doc: &mut Document, insertions: usize) -> (Vec<Jump>, Vec<Jump>) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut points, mut bars) = (Vec::new(), Vec::new());
    let mut tries = 0;
    let diagonal = {
        let (w, h) = doc.image.dimensions();
        f64::from(w).hypot(f64::from(h))
    };
    while (points.len() < insertions || bars.len() < insertions) && tries < 50 * insertions {
        tries += 1;
        let n = doc.mesh().len();
        let v = (rng.next() % n as u64) as usize;
        let w = (rng.next() % n as u64) as usize;
        let deformed = doc.deformed().to_vec();
        let rest = doc.mesh().positions().to_vec();
        let snapshot = doc.snapshot();
        let bar = points.len() >= insertions;
        let added = if bar {
            let (a, b) = (deformed[v], deformed[w]);
            let length = a.distance(b);
            if length > 0.1 * diagonal || length < 0.025 * diagonal {
                continue;
            }
            editor_bar(doc, a, b)
        } else {
            editor_point(doc, deformed[v])
        };
        if !added {
            continue;
        }
        if std::env::var("HOLDS").is_ok_and(|v| v == "off") {
            // How it was before ARAP's pins held what they are placed on.
            let mut project = doc.project().clone();
            project.holds.clear();
            doc.restore(project).expect("without holds");
        }
        let project = doc.project().clone();
        let new = project.handles.len() - 1;
        // (A handle close to another re-meshes around them: the picture is compared
        // at the old mesh's points, where the method itself takes them.)
        let after = {
            let after = doc.deformed().to_vec();
            let mesh = doc.mesh();
            let same_mesh = mesh.positions() == rest.as_slice();
            rest.iter()
                .enumerate()
                .map(|(i, p)| {
                    if same_mesh {
                        after[i]
                    } else if let Some(at) = arap_map(doc, *p) {
                        at
                    } else {
                        through(mesh, &after, *p).unwrap_or(*p)
                    }
                })
                .collect::<Vec<_>>()
        };
        // Under C², the new handle's own nodes: their discs of half the support, and
        // their Voronoi cells (ARAP and MLS weigh by no cells).
        let (own_disc, own_cells, cells, same_mesh) = match doc.rig() {
            Some(rig) => {
                let nodes: Vec<usize> = (0..rig.nodes().len())
                    .filter(|&k| {
                        rig.owner_handle(k) == Some(new)
                            && rig.nodes()[k].kind != weights_core::NodeKind::Virtual
                    })
                    .collect();
                let positions = rig.domain().positions();
                let own_disc: Vec<(DVec2, f64)> = nodes
                    .iter()
                    .map(|&k| {
                        (
                            positions[rig.nodes()[k].vertex as usize],
                            rig.radii(k).support / 2.0,
                        )
                    })
                    .collect();
                let own_cells: Vec<u32> = nodes.iter().map(|&k| k as u32).collect();
                (
                    own_disc,
                    own_cells,
                    rig.cells().to_vec(),
                    positions == rest.as_slice(),
                )
            }
            None => (Vec::new(), Vec::new(), Vec::new(), false),
        };
        let own = |i: usize| {
            (same_mesh && own_cells.contains(&cells[i]))
                || own_disc.iter().any(|(c, r)| rest[i].distance(*c) < *r)
        };
        let j = jump(
            &deformed,
            &after,
            &rest,
            &rest_points(&project.handles[new]),
            reach(&project, new),
            &own,
        );
        if bar {
            bars.push(j);
        } else {
            points.push(j);
        }
        doc.undo_to(snapshot).expect("undo");
    }
    (points, bars)
}

/// The jumps of removing each of `doc`'s handles from its posed rig (each undone).
fn removal_jumps(doc: &mut Document) -> Vec<Jump> {
    let count = doc.project().handles.len();
    let mut jumps = Vec::new();
    for i in 0..count {
        let project = doc.project().clone();
        let before = doc.deformed().to_vec();
        let snapshot = doc.snapshot();
        if doc.apply(Edit::Remove(i)).is_err() {
            continue;
        }
        let after = doc.deformed().to_vec();
        let rest = doc.mesh().positions().to_vec();
        let j = jump(
            &before,
            &after,
            &rest,
            &rest_points(&project.handles[i]),
            reach(&project, i),
            &|_| false,
        );
        jumps.push(j);
        doc.undo_to(snapshot).expect("undo");
    }
    jumps
}

/// Where ARAP takes the rest point `p`: through its own mesh, which does not change
/// with the handles (the picture's mesh, re-meshed around crowded handles, draws that
/// map sampled at other points, which differs from it by up to a tenth of a pixel).
fn arap_map(doc: &Document, p: DVec2) -> Option<DVec2> {
    let arap = doc.arap()?;
    let (t, b) = arap.arap_mesh().locate(p)?;
    let corners = arap.arap_mesh().triangles()[t];
    let at = arap.arap_positions();
    Some(
        corners
            .iter()
            .zip(b)
            .map(|(&c, w)| at[c as usize] * w)
            .sum(),
    )
}

/// What `EditorApp::add_point` does.
fn editor_point(doc: &mut Document, at: DVec2) -> bool {
    let Some((rest, _, _)) = doc.unwarp(at) else {
        return false;
    };
    let (rotate, scale) = doc.local_pose(rest, at);
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

/// Median, 90th percentile and largest of `values`.
fn spread(mut values: Vec<f64>) -> String {
    if values.is_empty() {
        return "none".to_owned();
    }
    values.sort_by(f64::total_cmp);
    let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
    format!("{:.2} / {:.2} / {:.2}", at(0.5), at(0.9), at(1.0))
}

fn summary(name: &str, jumps: &[Jump], cells: bool) {
    let pick = |f: fn(&Jump) -> f64| spread(jumps.iter().map(f).collect());
    print!(
        "  {name} ({}): anywhere {} px; away {} px",
        jumps.len(),
        pick(|j| j.anywhere),
        pick(|j| j.away)
    );
    if cells {
        print!("; outside its cell {} px", pick(|j| j.outside_cell));
    }
    println!("   (median / p90 / largest)");
}

/// A document on `name`'s picture with a posed rig: the lizard's sample rig, or seven
/// point handles spread over the shape and moved, turned and scaled a little.
fn document(name: &str) -> anyhow::Result<Document> {
    if name == "lizard" {
        return Document::built_in();
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(format!("{name}.png"));
    let image = pipeline::load_image(&path)?;
    let mut doc = Document::new(image, Some(path), Project::default())?;
    let diagonal = {
        let (w, h) = doc.image.dimensions();
        f64::from(w).hypot(f64::from(h))
    };
    let mut rng = Rng(0x51_7cc1_b727_220a);
    let rest = doc.mesh().positions().to_vec();
    let mut placed: Vec<DVec2> = Vec::new();
    while placed.len() < 7 {
        let p = rest[(rng.next() % rest.len() as u64) as usize];
        if placed.iter().all(|q| q.distance(p) > 0.15 * diagonal) {
            placed.push(p);
        }
    }
    // Placed at rest, then posed, as an artist rigs a picture.
    for p in &placed {
        doc.apply(Edit::Add(HandleSpec::Point {
            rest: p.to_array(),
            translate: [0.0; 2],
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        }))?;
    }
    for (i, p) in placed.into_iter().enumerate() {
        let offset = DVec2::new(rng.unit() - 0.5, rng.unit() - 0.5) * 0.12 * diagonal;
        doc.apply(Edit::Pose(
            i,
            HandleSpec::Point {
                rest: p.to_array(),
                translate: offset.to_array(),
                rotate: (rng.unit() - 0.5) * 0.6,
                scale: 1.0,
                depth: 0,
            },
        ))?;
    }
    Ok(doc)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let method = match args.first().map(String::as_str) {
        Some("arap") => Method::Arap,
        Some("mls") => Method::Mls,
        _ => Method::C2,
    };
    let picture = args.get(1).map_or("lizard", String::as_str);
    let insertions: usize = args.get(2).and_then(|n| n.parse().ok()).unwrap_or(24);
    let mut doc = document(picture)?;
    doc.apply(Edit::Method(method))?;
    if std::env::var("SOLVER").is_ok_and(|v| v == "two-step") {
        // ARAP's two steps alone (the paper's).
        let mut project = doc.project().clone();
        project.arap = Some(project::ArapSettings {
            solver: Some(project::ArapSolver::TwoStep),
            ..project.arap.unwrap_or_default()
        });
        doc.restore(project)?;
    }
    let (points, bars) = insertion_jumps(&mut doc, insertions);
    let removals = removal_jumps(&mut doc);
    let c2 = method == Method::C2;
    println!("{picture}, posed, {}:", method.label());
    summary("points inserted", &points, c2);
    summary("bars inserted", &bars, c2);
    summary("handles removed", &removals, false);
    Ok(())
}

/// Where `deformed` (a pose of `mesh`) takes the point `p` at rest: through the rest
/// triangle holding it.
fn through(mesh: &weights_core::Domain, deformed: &[DVec2], p: DVec2) -> Option<DVec2> {
    let (t, bary) = mesh.locate(p)?;
    let corners = mesh.triangles()[t];
    (0..3)
        .map(|i| deformed.get(corners[i] as usize).map(|&q| q * bary[i]))
        .sum()
}
