//! Properties of interpolation and blending over random keys.

use proptest::prelude::*;

use project::{Animation, HandlePose, Interpolation, Key, Pose, Project, SpatialKey};

fn rig() -> Project {
    Project::from_json(
        r#"{"version": 1, "handles": [{"type": "point", "rest": [10, 10]},
            {"type": "bar", "rest": [[20, 20], [40, 20]]}]}"#,
    )
    .expect("parses")
}

fn pose(p: [f64; 6]) -> Pose {
    Pose {
        handles: vec![
            HandlePose::Point {
                translate: [p[0], p[1]],
                rotate: p[2],
                scale: 0.5 + p[3].abs(),
            },
            HandlePose::Bar {
                pose: [[p[4], p[5]], [p[4] + 10.0 + p[0].abs(), p[5] - p[1]]],
            },
        ],
        cage: None,
        overlaps: Vec::new(),
    }
}

fn numbers() -> impl Strategy<Value = [f64; 6]> {
    [
        -100.0..100.0f64,
        -100.0..100.0f64,
        -20.0..20.0f64,
        0.0..3.0f64,
        -100.0..100.0f64,
        -100.0..100.0f64,
    ]
}

fn keyed(times: &[f64], poses: &[[f64; 6]], interpolation: Interpolation) -> Project {
    let mut project = rig();
    project.animation = Some(Animation {
        interpolation,
        keys: times
            .iter()
            .zip(poses)
            .map(|(&time, &p)| Key {
                time,
                hold: false,
                pose: pose(p),
            })
            .collect(),
        ..Animation::default()
    });
    project
}

/// Increasing key times from positive gaps.
fn times(gaps: &[f64]) -> Vec<f64> {
    gaps.iter()
        .scan(0.0, |t, g| {
            let now = *t;
            *t += g;
            Some(now)
        })
        .collect()
}

proptest! {
    #[test]
    fn keys_are_met_exactly_and_linear_stays_between_them(
        gaps in prop::collection::vec(0.05..2.0f64, 2..6),
        poses in prop::collection::vec(numbers(), 6),
        u in 0.0..1.0f64,
    ) {
        let times = times(&gaps);
        for interpolation in Interpolation::ALL {
            let project = keyed(&times, &poses, interpolation);
            project.validate(None).expect("valid");
            let keys = &project.animation.as_ref().expect("animation").keys;
            for key in keys {
                prop_assert_eq!(animation::pose_at(&project, key.time), Some(key.pose.clone()));
            }
        }
        let project = keyed(&times, &poses, Interpolation::Linear);
        let keys = &project.animation.as_ref().expect("animation").keys;
        for pair in keys.windows(2) {
            let t = pair[0].time + u * (pair[1].time - pair[0].time);
            let between = animation::pose_at(&project, t).expect("a pose");
            let channel = |p: &Pose| match p.handles[0] {
                HandlePose::Point { translate, rotate, scale } => [translate[0], translate[1], rotate, scale],
                HandlePose::Bar { .. } => unreachable!(),
            };
            let (a, b, c) = (channel(&pair[0].pose), channel(&pair[1].pose), channel(&between));
            for i in 0..4 {
                let want = a[i] + u * (b[i] - a[i]);
                prop_assert!((c[i] - want).abs() <= 1e-9 * (1.0 + want.abs()), "{} vs {}", c[i], want);
            }
            // A bar keeps a length between its keys' lengths.
            let length = |p: &Pose| match p.handles[1] {
                HandlePose::Bar { pose: [a, b] } => (b[0] - a[0]).hypot(b[1] - a[1]),
                HandlePose::Point { .. } => unreachable!(),
            };
            let (la, lb, lc) = (length(&pair[0].pose), length(&pair[1].pose), length(&between));
            prop_assert!(lc >= la.min(lb) - 1e-9 && lc <= la.max(lb) + 1e-9);
        }
    }

    #[test]
    fn spatial_weights_sum_to_one_and_meet_each_marker(
        markers in prop::collection::vec((-500.0..500.0f64, -500.0..500.0f64), 1..8),
        cursor in (-2000.0..2000.0f64, -2000.0..2000.0f64),
    ) {
        let markers: Vec<[f64; 2]> = markers.into_iter().map(|(x, y)| [x, y]).collect();
        // Markers closer than the file allows are not a blend the editor makes.
        for (i, a) in markers.iter().enumerate() {
            for b in &markers[..i] {
                prop_assume!((a[0] - b[0]).hypot(a[1] - b[1]) > 5.0);
            }
        }
        let blend = animation::SpatialBlend::new(&markers).expect("a blend");
        let w = blend.weights([cursor.0, cursor.1]);
        prop_assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-8);
        for (k, m) in markers.iter().enumerate() {
            let w = blend.weights(*m);
            prop_assert!((w[k] - 1.0).abs() < 1e-6, "marker {}: {:?}", k, w);
        }
        // The pose at each marker is its key's.
        let mut project = rig();
        project.animation = Some(Animation {
            spatial_keys: markers
                .iter()
                .enumerate()
                .map(|(k, &at)| SpatialKey { at, pose: pose([k as f64; 6]) })
                .collect(),
            ..Animation::default()
        });
        for key in &project.animation.as_ref().expect("animation").spatial_keys {
            prop_assert_eq!(blend.pose(&project, key.at), Some(key.pose.clone()));
        }
    }
}
