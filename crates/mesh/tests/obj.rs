//! Wavefront OBJ input and output.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use glam::DVec2;
use mesh::{Mesh, MeshError};

fn read(s: &str) -> Result<Mesh, MeshError> {
    Mesh::read_obj(s.as_bytes())
}

fn obj_line(s: &str) -> usize {
    match read(s) {
        Err(MeshError::Obj { line, .. }) => line,
        other => panic!("expected an OBJ error, got {other:?}"),
    }
}

#[test]
fn round_trip_is_exact() {
    let mesh = Mesh {
        vertices: vec![
            DVec2::new(0.1 + 0.2, -0.0),
            DVec2::new(1e-300, 123_456_789.123_456_79),
            DVec2::new(1.0 / 3.0, 2.0f64.sqrt()),
            DVec2::new(5e300, f64::MIN_POSITIVE),
        ],
        triangles: vec![[0, 2, 1], [1, 2, 3]],
    };
    let mut buf = Vec::new();
    mesh.write_obj(&mut buf).unwrap();
    let back = Mesh::read_obj(&buf[..]).unwrap();
    assert_eq!(back.triangles, mesh.triangles);
    for (a, b) in back.vertices.iter().zip(&mesh.vertices) {
        assert_eq!(a.x.to_bits(), b.x.to_bits());
        assert_eq!(a.y.to_bits(), b.y.to_bits());
    }
}

#[test]
fn round_trip_of_a_generated_mesh() {
    let domain = mesh::Domain::full_rectangle(37, 21);
    let opts = mesh::MeshOptions {
        target_vertices: 300,
        ..Default::default()
    };
    let t = mesh::triangulate(&domain, &mesh::Constraints::default(), &opts).unwrap();
    let mut buf = Vec::new();
    t.mesh.write_obj(&mut buf).unwrap();
    assert_eq!(Mesh::read_obj(&buf[..]).unwrap(), t.mesh);
}

#[test]
fn reads_the_common_forms() {
    let text = "# a comment\n\
                o thing\n\
                v 0 0 0\n\
                v 2 0 5\n\
                vt 0.5 0.5\n\
                v 2 2\n\
                v 0 2 0 1\n\
                vn 0 0 1\n\
                \n\
                f 1/1/1 2/1/1 3/1/1\n\
                f -4//1 -2//1 -1//1 # trailing comment\n";
    let m = read(text).unwrap();
    assert_eq!(m.vertices.len(), 4);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    m.sanity_check().unwrap();
}

#[test]
fn polygons_are_fan_triangulated() {
    let m = read("v 0 0\nv 1 0\nv 2 1\nv 1 2\nv 0 1\nf 1 2 3 4 5\n").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    m.sanity_check().unwrap();
}

#[test]
fn clockwise_files_are_flipped() {
    let m = read("v 0 0\nv 0 1\nv 1 0\nf 1 2 3\n").unwrap();
    assert!(m.area() > 0.0);
    m.sanity_check().unwrap();
}

#[test]
fn malformed_lines_report_their_number() {
    assert_eq!(obj_line("v 0 0\nv 1 x\n"), 2);
    assert_eq!(obj_line("v 0 0\nv 1\n"), 2);
    assert_eq!(obj_line("v 0 0\n\n\nv nan 1\n"), 4);
    assert_eq!(obj_line("v 0 0\nv inf 1\n"), 2);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 1 2\n"), 4);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 1 2 4\n"), 4);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 0 1 2\n"), 4);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 1 2 -4\n"), 4);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 1 2 2\n"), 4);
    assert_eq!(obj_line("v 0 0\nv 1 0\nv 0 1\nf 1 2 3\nf 1 2 a\n"), 5);
    assert_eq!(
        obj_line("v 0 0\nv 1 0\nv 0 1\n# x\nf 1 2 -1/2\nf 1 2 9\n"),
        6
    );
    let err = read("v 0 0\nv 1 0\nv 0 1\nf 1 2 7\n").unwrap_err();
    assert!(err.to_string().contains("line 4"), "{err}");
}

#[test]
fn empty_file_is_an_empty_mesh() {
    let m = read("").unwrap();
    assert!(m.vertices.is_empty() && m.triangles.is_empty());
}
