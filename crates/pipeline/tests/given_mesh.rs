//! A C² rig on a given mesh is weighed on the mesh renumbered for locality, and
//! answers in the file's numbering: the same weights, rest mesh and deformed vertices,
//! vertex for vertex, as a rig built on the file as it is numbered.

use glam::DVec2;
use pipeline::{Deformer, Mesh, Source, WeightsListing};
use project::{HandleSpec, MetricChoice, Project};
use weights_core::{Domain, Metric};

use crate::support::point;

/// A long strip (a limb) of 48 × 12 vertices 10 px apart, jittered (no two distances
/// tie) or on a regular grid (ties everywhere), numbered in a scattered order as a mesh
/// generator numbers its vertices.
fn strip(jittered: bool) -> Mesh {
    let n = NX * NY;
    let mut vertices = vec![DVec2::ZERO; n as usize];
    for j in 0..NY {
        for i in 0..NX {
            let h = (i * 7919 + j * 104_729) % 1000;
            let jitter = DVec2::new(f64::from(h % 31) - 15.0, f64::from(h % 29) - 14.0) / 6.0;
            let edge = i == 0 || j == 0 || i == NX - 1 || j == NY - 1;
            let p = DVec2::new(f64::from(i), f64::from(j)) * 10.0 + 5.0;
            vertices[file(i, j) as usize] = if edge || !jittered { p } else { p + jitter };
        }
    }
    let mut triangles = Vec::new();
    for j in 0..NY - 1 {
        for i in 0..NX - 1 {
            let (a, b, c, d) = (
                file(i, j),
                file(i + 1, j),
                file(i + 1, j + 1),
                file(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}

const NX: u32 = 48;
const NY: u32 = 12;

/// The file's number of grid vertex `(i, j)`: `(g · 37) mod n` for its row-major
/// number `g`.
fn file(i: u32, j: u32) -> u32 {
    ((j * NX + i) * 37) % (NX * NY)
}

fn weights_of(deformer: &dyn Deformer, file_vertices: usize) -> serde_json::Value {
    deformer
        .weights(WeightsListing {
            file_vertices,
            positions: false,
        })
        .expect("C² lists weights")
}

/// Sets `project` up on `mesh` as a rig file's given mesh, and checks it against a rig
/// built on the mesh as numbered: its last handle (a point, off the file's vertices)
/// is inserted after them, then pulled up by 30 px.
fn answers_as_numbered(mesh: &Mesh, mut project: Project) {
    let Some(&HandleSpec::Point { rest: inserted, .. }) = project.handles.last() else {
        panic!("the last handle is a point");
    };
    let warper = pipeline::setup(Source::Mesh(mesh), &project, &()).expect("set up");
    let mut ours = warper.deformer;
    let n = mesh.vertices.len();
    assert_eq!(ours.rest().len(), n + 1, "one vertex inserted");
    assert_eq!(
        &ours.rest()[..n],
        &mesh.vertices[..],
        "the file's vertices, in order"
    );
    assert_eq!(
        ours.rest()[n],
        DVec2::from(inserted),
        "the inserted one after them"
    );

    // The rig on the mesh as numbered: the file's vertices and the inserted one.
    let metric = match project.metric {
        MetricChoice::Euclidean => Metric::Euclidean,
        _ => Metric::Intrinsic,
    };
    let domain =
        Domain::new(ours.rest().to_vec(), ours.triangles().to_vec(), metric).expect("a mesh");
    let plain = pipeline::rig_on_domain(domain, &project, &|_| {}).expect("a rig");
    assert!(
        plain.nodes().len() > 3,
        "the strip takes virtual handles too: {} nodes",
        plain.nodes().len()
    );
    let mut plain: Box<dyn Deformer> = Box::new(plain);
    // The same nodes on the same vertices, the same weights of every vertex.
    let (a, b) = (weights_of(&*ours, n), weights_of(&*plain, n));
    assert_eq!(a["nodes"], b["nodes"]);
    let rows = |w: &serde_json::Value| -> Vec<Vec<(u64, f64)>> {
        w["weights"]
            .as_array()
            .expect("rows")
            .iter()
            .map(|row| {
                let mut row: Vec<(u64, f64)> = (row.as_array().expect("a row").iter())
                    .map(|e| (e[0].as_u64().expect("node"), e[1].as_f64().expect("weight")))
                    .collect();
                // (A row lists its nodes in the order the searches reached the vertex.)
                row.sort_by_key(|e| e.0);
                row
            })
            .collect()
    };
    let (ra, rb) = (rows(&a), rows(&b));
    assert_eq!(ra.len(), n + 1);
    for (v, (x, y)) in ra.iter().zip(&rb).enumerate() {
        assert_eq!(x.len(), y.len(), "vertex {v}: {x:?} vs {y:?}");
        for (&(kx, wx), &(ky, wy)) in x.iter().zip(y) {
            assert!(
                kx == ky && (wx - wy).abs() < 1e-12,
                "vertex {v}: {x:?} vs {y:?}"
            );
        }
    }
    // A pose: the inserted pin pulled up, the drawn table and positions by file vertex.
    let last = project.handles.len() - 1;
    project.handles[last] = point(inserted, [0.0, -30.0]);
    ours.follow(&project).expect("follow");
    plain.follow(&project).expect("follow");
    let (da, db) = (ours.deformed(), plain.deformed());
    let moved = DVec2::from(inserted) - DVec2::new(0.0, 30.0);
    assert!((da[n] - moved).length() < 1e-9, "{}", da[n]);
    for (v, (p, q)) in da.iter().zip(&db).enumerate() {
        assert!((*p - *q).length() < 1e-9, "vertex {v}: {p} vs {q}");
    }
    let skinned = |d: &dyn Deformer| match d.output() {
        pipeline::Output::Skinned(s) => s.table(),
        pipeline::Output::Positions(_) => panic!("C² draws skinned"),
    };
    let (ta, tb) = (skinned(&*ours), skinned(&*plain));
    assert_eq!(ta.rows, tb.rows);
    for v in 0..=n {
        let row = |t: &pipeline::SkinTable| {
            let r = t.rows[v] as usize..t.rows[v + 1] as usize;
            let mut row: Vec<(u32, f32)> = t.nodes[r.clone()]
                .iter()
                .copied()
                .zip(t.weights[r].iter().copied())
                .collect();
            row.sort_by_key(|e| e.0);
            row
        };
        assert_eq!(row(&ta), row(&tb), "vertex {v}");
    }
}

/// A pin on grid vertex `(i, j)` of `mesh`.
fn pin(mesh: &Mesh, i: u32, j: u32) -> HandleSpec {
    let p = mesh.vertices[file(i, j) as usize];
    point([p.x, p.y], [0.0, 0.0])
}

#[test]
fn a_given_mesh_is_weighed_and_answered_in_the_files_numbering() {
    // Two pins on vertices, one between them (inserted as a vertex after the file's),
    // the shortest paths measured inside the strip.
    let mesh = strip(true);
    let project = Project {
        metric: MetricChoice::Intrinsic,
        handles: vec![
            pin(&mesh, 2, 6),
            pin(&mesh, 12, 5),
            point([243.0, 61.0], [0.0, 0.0]),
        ],
        ..Project::default()
    };
    answers_as_numbered(&mesh, project);
}

#[test]
fn ties_on_a_renumbered_mesh_go_as_the_files_numbering_has_them() {
    // A regular grid: equal distances everywhere, Algorithm 1's farthest samples and
    // the cells' borders decided by ties; with a bar, pins along the border, and the
    // symmetric placement, in either metric.
    let mesh = strip(false);
    let bar = HandleSpec::Bar {
        rest: [[55.0, 35.0], [55.0, 85.0]],
        pose: None,
        depth: 0,
    };
    for metric in [MetricChoice::Intrinsic, MetricChoice::Euclidean] {
        for (fixed_boundary, placement) in [
            (false, project::Placement::AsWritten),
            (true, project::Placement::AsWritten),
            (false, project::Placement::Symmetric),
        ] {
            let project = Project {
                metric,
                fixed_boundary,
                placement,
                handles: vec![
                    bar.clone(),
                    pin(&mesh, 14, 6),
                    point([240.0, 60.0], [0.0, 0.0]),
                ],
                ..Project::default()
            };
            answers_as_numbered(&mesh, project);
        }
    }
}

#[test]
fn saved_virtual_handles_keep_their_copy_of_a_cut_vertex() {
    // A slit up the middle of the strip: the vertices on it doubled, the copies (after
    // the file's vertices) used by the triangles on its right. Two saved virtual
    // handles sit on the slit, one on each copy.
    let mut mesh = strip(true);
    let slit: Vec<u32> = (0..6).map(|j| file(24, j)).collect();
    let mut copy = std::collections::HashMap::new();
    for &v in &slit {
        copy.insert(v, mesh.vertices.len() as u32);
        mesh.vertices.push(mesh.vertices[v as usize]);
    }
    for (t, tri) in mesh.triangles.iter_mut().enumerate() {
        // Triangles are made two a cell, cells row by row: cell i of the row.
        let i = (t / 2) as u32 % (NX - 1);
        if i >= 24 {
            *tri = tri.map(|v| copy.get(&v).copied().unwrap_or(v));
        }
    }
    let on_slit = |j: u32| {
        let p = mesh.vertices[file(24, j) as usize];
        [p.x, p.y]
    };
    let project = Project {
        metric: MetricChoice::Intrinsic,
        handles: vec![
            pin(&mesh, 4, 6),
            pin(&mesh, 44, 5),
            point([243.0, 81.0], [0.0, 0.0]),
        ],
        virtual_handles: vec![on_slit(2), on_slit(4)],
        virtual_placed_for: vec![Some(0), Some(1)],
        virtual_copy: vec![1, 0],
        ..Project::default()
    };
    answers_as_numbered(&mesh, project);
}
