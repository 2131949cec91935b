//! No minimum spacing between handles: two handles half a pixel apart are placed on
//! any picture at any density, by every method, the mesh refined around them; only
//! handles closer than a millionth of a pixel are refused.

use std::path::Path;

use glam::DVec2;
use project::{HandleSpec, Method, Project};

fn picture(name: &str) -> image::RgbaImage {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name);
    pipeline::load_image(&path).expect("test picture")
}

fn point(rest: DVec2, translate: [f64; 2]) -> HandleSpec {
    HandleSpec::Point {
        rest: rest.to_array(),
        translate,
        rotate: 0.0,
        scale: 1.0,
        depth: 0,
    }
}

#[test]
fn two_handles_half_a_pixel_apart_work_on_every_picture_at_every_density() {
    for (name, at) in [
        ("opaque.png", DVec2::new(40.0, 30.0)),
        ("dino.png", DVec2::new(60.0, 60.0)),
    ] {
        let image = picture(name);
        for density in [16, 300, 5_000, 20_000] {
            for method in [Method::C2, Method::Arap, Method::Mls] {
                let project = Project {
                    density: Some(density),
                    method,
                    handles: vec![
                        point(at, [3.0, -2.0]),
                        point(at + DVec2::new(0.5, 0.0), [-2.0, 1.0]),
                        point(at + DVec2::new(0.0, 12.0), [0.0, 0.0]),
                    ],
                    ..Project::default()
                };
                let what = format!("{name} at {density} vertices, {}", method.name());
                let warper = pipeline::prepare_warper(&image, &project, None, &())
                    .unwrap_or_else(|e| panic!("{what}: {}", pipeline::error_line(&e)));
                let deformed = warper.deformer.deformed();
                assert!(deformed.iter().all(|p| p.is_finite()), "{what}");
                // The two close handles have vertices of their own, and C² moves each
                // exactly as it is posed.
                let rest = warper.deformer.rest();
                for h in &project.handles[..2] {
                    let HandleSpec::Point {
                        rest: r, translate, ..
                    } = h
                    else {
                        unreachable!()
                    };
                    let v = rest
                        .iter()
                        .position(|p| *p == DVec2::from(*r))
                        .unwrap_or_else(|| panic!("{what}: no vertex at {r:?}"));
                    if method == Method::C2 {
                        let moved = deformed[v] - rest[v];
                        assert!(
                            moved.distance(DVec2::from(*translate)) < 1e-6,
                            "{what}: {moved} for {translate:?}"
                        );
                    }
                }
                // The rig file alone gives the same mesh again.
                let again = pipeline::prepare_warper(&image, &project, None, &()).expect("again");
                assert_eq!(again.deformer.rest(), rest, "{what}");
            }
        }
    }
}

#[test]
fn only_coincident_handles_are_refused_and_the_message_says_so() {
    let image = picture("opaque.png");
    let at = DVec2::new(40.0, 30.0);
    let project = Project {
        handles: vec![
            point(at, [0.0; 2]),
            point(at + DVec2::new(4e-7, 0.0), [0.0; 2]),
        ],
        ..Project::default()
    };
    let error = pipeline::prepare_warper(&image, &project, None, &())
        .err()
        .expect("coincident handles are refused");
    let line = pipeline::error_line(&error);
    assert!(
        line.contains("coincide (closer than 0.000001 px)"),
        "{line}"
    );
}
