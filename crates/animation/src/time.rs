//! Key poses in time: the pose at any time, and the frames of an export.

use project::{Animation, Interpolation, Pose, Project};

use crate::channels::Layout;

/// The pose of `project`'s handles and cage at `time` seconds, from its animation's
/// keys; `None` when it has no keys (its handles' own pose is then the only one).
///
/// Before the first key the first key's pose holds, after the last the last's. At a
/// key's time, and after a key that holds until the next, the pose is that key's
/// exactly (a cage left out of a key listed at rest, as [`Pose::of`] lists it). Between two keys `a` and `b`, with `u = (t − t_a)/(t_b − t_a)`:
/// * linear: every channel moves as `a + u·(b − a)` — a point's translation,
///   rotation (as keyed: more than half a turn stays more than half a turn) and
///   scale; a bar's centre and length, and its direction by the smaller turn; each
///   cage vertex;
/// * smooth: every channel follows the cubic Hermite curve through the keys with
///   Catmull–Rom slopes `(p₊ − p₋)/(t₊ − t₋)`; the slope is zero at the first and last
///   keys and where a hold starts or ends, so motion eases in and out there.
pub fn pose_at(project: &Project, time: f64) -> Option<Pose> {
    let animation = project.animation.as_ref()?;
    let keys = &animation.keys;
    let first = keys.first()?;
    let last = keys.last()?;
    let layout = Layout::of(project);
    if time.is_nan() || time <= first.time {
        return Some(layout.filled(first.pose.clone()));
    }
    if time >= last.time {
        return Some(layout.filled(last.pose.clone()));
    }
    // The key at or before `time`: keys[k].time <= time < keys[k + 1].time.
    let k = keys.partition_point(|key| key.time <= time) - 1;
    let (a, b) = (&keys[k], &keys[k + 1]);
    if time == a.time || a.hold {
        return Some(layout.filled(a.pose.clone()));
    }
    let u = (time - a.time) / (b.time - a.time);
    let mut pa = Vec::new();
    let mut pb = Vec::new();
    layout.channels(&a.pose, None, &mut pa);
    layout.channels(&b.pose, Some(&pa), &mut pb);
    let channels: Vec<f64> = match animation.interpolation {
        Interpolation::Linear => pa.iter().zip(&pb).map(|(a, b)| a + u * (b - a)).collect(),
        Interpolation::Smooth => {
            let slope_a = slope(animation, &layout, k, &pa, &pb, true);
            let slope_b = slope(animation, &layout, k + 1, &pb, &pa, false);
            let dt = b.time - a.time;
            let (h00, h10, h01, h11) = hermite(u);
            (0..pa.len())
                .map(|i| h00 * pa[i] + h10 * dt * slope_a[i] + h01 * pb[i] + h11 * dt * slope_b[i])
                .collect()
        }
    };
    // Overlap orders do not interpolate: between two keys, the earlier key's hold
    // while its regions last.
    let mut pose = layout.pose(&channels);
    pose.overlaps = a.pose.overlaps.clone();
    Some(pose)
}

/// The cubic Hermite basis at `u`: `(h00, h10, h01, h11)`.
fn hermite(u: f64) -> (f64, f64, f64, f64) {
    let u2 = u * u;
    let u3 = u2 * u;
    (
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    )
}

/// The slope of every channel at key `j` for the smooth curve: `(p_{j+1} − p_{j−1}) /
/// (t_{j+1} − t_{j−1})`, zero at the ends and where a hold starts or ends. `here` are
/// key `j`'s channels and `other` the segment's other key's (whose bar directions
/// `here` was unwrapped against), `start` whether key `j` begins the segment.
fn slope(
    animation: &Animation,
    layout: &Layout<'_>,
    j: usize,
    here: &[f64],
    other: &[f64],
    start: bool,
) -> Vec<f64> {
    let keys = &animation.keys;
    let flat = j == 0 || j + 1 == keys.len() || keys[j].hold || keys[j - 1].hold;
    if flat {
        return vec![0.0; here.len()];
    }
    // The neighbour across key j from the segment's other key, unwrapped against key j.
    let (before, after) = if start {
        let mut before = Vec::new();
        layout.channels(&keys[j - 1].pose, Some(here), &mut before);
        (before, other.to_vec())
    } else {
        let mut after = Vec::new();
        layout.channels(&keys[j + 1].pose, Some(here), &mut after);
        (other.to_vec(), after)
    };
    let dt = keys[j + 1].time - keys[j - 1].time;
    before
        .iter()
        .zip(&after)
        .map(|(b, a)| (a - b) / dt)
        .collect()
}

/// `project` posed at `time` (see [`pose_at`]): what `c2warp animate` renders for the
/// frame at that time, and `c2warp render` of the returned rig gives the same picture.
/// A rig without keys comes back as it is.
pub fn posed_at(project: &Project, time: f64) -> Project {
    let mut posed = project.clone();
    if let Some(pose) = pose_at(project, time) {
        pose.apply(&mut posed);
    }
    posed
}

/// How many frames `fps` frames a second give from `from` to `to` seconds, both ends
/// included when they fall on a frame: `⌊(to − from)·fps⌋ + 1` (a whisker of
/// rounding allowed), at least one.
pub fn frame_count(fps: f64, from: f64, to: f64) -> usize {
    let span = ((to - from) * fps + 1e-9).floor();
    if span.is_finite() && span > 0.0 {
        span as usize + 1
    } else {
        1
    }
}

/// The time of every frame from `from` to `to` at `fps`: `from + i/fps`.
pub fn frame_times(fps: f64, from: f64, to: f64) -> Vec<f64> {
    (0..frame_count(fps, from, to))
        .map(|i| from + i as f64 / fps)
        .collect()
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use project::{HandlePose, Key};

    use super::*;

    const RIG: &str = r#"{"version": 1,
        "handles": [{"type": "point", "rest": [10, 10]},
                    {"type": "bar", "rest": [[20, 20], [40, 20]]}],
        "cage": {"rest": [[0, 0], [50, 0], [50, 50]]}}"#;

    fn point(tx: f64, ty: f64, rotate: f64, scale: f64) -> HandlePose {
        HandlePose::Point {
            translate: [tx, ty],
            rotate,
            scale,
        }
    }

    fn bar(a: [f64; 2], b: [f64; 2]) -> HandlePose {
        HandlePose::Bar { pose: [a, b] }
    }

    fn key(time: f64, handles: Vec<HandlePose>, cage: Option<Vec<[f64; 2]>>) -> Key {
        Key {
            time,
            hold: false,
            pose: Pose {
                handles,
                cage,
                overlaps: Vec::new(),
            },
        }
    }

    fn project(keys: Vec<Key>, interpolation: Interpolation) -> Project {
        let mut project = Project::from_json(RIG).expect("parses");
        project.animation = Some(Animation {
            interpolation,
            keys,
            ..Animation::default()
        });
        project.validate(None).expect("valid");
        project
    }

    fn three_keys(interpolation: Interpolation) -> Project {
        project(
            vec![
                key(
                    0.0,
                    vec![point(0.0, 0.0, 0.0, 1.0), bar([20.0, 20.0], [40.0, 20.0])],
                    None,
                ),
                key(
                    1.0,
                    // More than a turn and a half; the bar turned a quarter turn.
                    vec![
                        point(10.0, -20.0, 3.0 * PI, 3.0),
                        bar([30.0, 10.0], [30.0, 30.0]),
                    ],
                    Some(vec![[0.0, 0.0], [60.0, 0.0], [50.0, 40.0]]),
                ),
                key(
                    3.0,
                    vec![point(-10.0, 0.0, PI, 1.0), bar([30.0, 0.0], [30.0, 40.0])],
                    None,
                ),
            ],
            interpolation,
        )
    }

    fn close(a: &Pose, b: &Pose, tolerance: f64) -> bool {
        let mut x = Vec::new();
        let mut y = Vec::new();
        let p = Project::from_json(RIG).expect("parses");
        let layout = Layout::of(&p);
        layout.channels(a, None, &mut x);
        layout.channels(b, Some(&x), &mut y);
        x.iter().zip(&y).all(|(a, b)| (a - b).abs() <= tolerance)
    }

    #[test]
    fn every_key_is_its_own_pose_exactly() {
        for interpolation in Interpolation::ALL {
            let p = three_keys(interpolation);
            let layout = Layout::of(&p);
            let keys = &p.animation.as_ref().expect("animation").keys;
            for k in keys {
                assert_eq!(pose_at(&p, k.time), Some(layout.filled(k.pose.clone())));
            }
            // The keys without a cage pose have the cage at rest.
            let rest = p.cage.as_ref().expect("a cage").rest.clone();
            assert_eq!(pose_at(&p, 0.0).and_then(|p| p.cage), Some(rest));
            assert_eq!(pose_at(&p, -5.0), Some(layout.filled(keys[0].pose.clone())));
            assert_eq!(pose_at(&p, 99.0), Some(layout.filled(keys[2].pose.clone())));
        }
    }

    #[test]
    fn linear_midpoints_are_halfway_in_every_channel() {
        let p = three_keys(Interpolation::Linear);
        let mid = pose_at(&p, 0.5).expect("a pose");
        assert_eq!(mid.handles[0], point(5.0, -10.0, 1.5 * PI, 2.0));
        // The bar: its centre stays, length 20 throughout, turned by half of the
        // quarter turn it makes.
        let HandlePose::Bar { pose: [a, b] } = mid.handles[1] else {
            panic!("a bar");
        };
        let centre = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
        assert!((centre[0] - 30.0).abs() < 1e-12 && (centre[1] - 20.0).abs() < 1e-12);
        assert!(((b[0] - a[0]).hypot(b[1] - a[1]) - 20.0).abs() < 1e-12);
        let angle = (b[1] - a[1]).atan2(b[0] - a[0]);
        assert!((angle - PI / 4.0).abs() < 1e-12, "{angle}");
        // The cage: the first key has it at rest.
        assert_eq!(
            mid.cage.as_deref(),
            Some(&[[0.0, 0.0], [55.0, 0.0], [50.0, 45.0]][..])
        );
        // A quarter of the way through the second segment.
        let later = pose_at(&p, 1.5).expect("a pose");
        assert!(close(
            &later,
            &Pose {
                handles: vec![
                    point(5.0, -15.0, 2.5 * PI, 2.5),
                    bar([30.0, 7.5], [30.0, 32.5])
                ],
                cage: Some(vec![[0.0, 0.0], [57.5, 0.0], [50.0, 42.5]]),
                overlaps: Vec::new(),
            },
            1e-12
        ));
    }

    #[test]
    fn a_bar_takes_the_smaller_turn_even_across_the_back() {
        // From pointing left (π) to pointing down-left (−3π/4): the short way is an
        // eighth of a turn through π, not seven eighths back through 0.
        let p = project(
            vec![
                key(
                    0.0,
                    vec![point(0.0, 0.0, 0.0, 1.0), bar([40.0, 20.0], [20.0, 20.0])],
                    None,
                ),
                key(
                    1.0,
                    vec![point(0.0, 0.0, 0.0, 1.0), bar([40.0, 20.0], [20.0, 0.0])],
                    None,
                ),
            ],
            Interpolation::Linear,
        );
        let mid = pose_at(&p, 0.5).expect("a pose");
        let HandlePose::Bar { pose: [a, b] } = mid.handles[1] else {
            panic!("a bar");
        };
        let angle = (b[1] - a[1]).atan2(b[0] - a[0]);
        assert!((angle.abs() - 7.0 * PI / 8.0).abs() < 1e-9, "{angle}");
    }

    #[test]
    fn a_hold_keeps_the_pose_until_the_next_key() {
        let mut p = three_keys(Interpolation::Smooth);
        p.animation.as_mut().expect("animation").keys[1].hold = true;
        let held = p.animation.as_ref().expect("animation").keys[1]
            .pose
            .clone();
        for t in [1.0, 1.5, 2.999] {
            assert_eq!(pose_at(&p, t), Some(held.clone()));
        }
        assert_ne!(pose_at(&p, 3.0), Some(held));
    }

    #[test]
    fn smooth_passes_through_the_keys_and_eases_at_the_ends() {
        let p = three_keys(Interpolation::Smooth);
        let rotation = |t: f64| match pose_at(&p, t).expect("a pose").handles[0] {
            HandlePose::Point { rotate, .. } => rotate,
            HandlePose::Bar { .. } => panic!("a point"),
        };
        // Continuous through the middle key, both ways.
        assert!((rotation(1.0 - 1e-7) - 3.0 * PI).abs() < 1e-5);
        assert!((rotation(1.0 + 1e-7) - 3.0 * PI).abs() < 1e-5);
        // Eases in: the first hundredth of a second moves much less than a linear
        // curve's hundredth (3π/100).
        assert!(rotation(0.01) < 0.01 * 3.0 * PI * 0.1);
        // Slope continuous at the middle key.
        let h = 1e-5;
        let left = (rotation(1.0) - rotation(1.0 - h)) / h;
        let right = (rotation(1.0 + h) - rotation(1.0)) / h;
        assert!(
            (left - right).abs() < 1e-3 * left.abs().max(1.0),
            "{left} vs {right}"
        );
        // Catmull–Rom slope at the middle key: (π − 0) / (3 − 0).
        assert!((left - PI / 3.0).abs() < 1e-3, "{left}");
    }

    #[test]
    fn posed_at_poses_the_rig_file() {
        let p = three_keys(Interpolation::Linear);
        let posed = posed_at(&p, 0.5);
        assert_eq!(Pose::of(&posed), pose_at(&p, 0.5).expect("a pose"));
        posed.validate(None).expect("a valid rig");
        let still = Project::from_json(RIG).expect("parses");
        assert_eq!(posed_at(&still, 1.0), still);
    }

    #[test]
    fn frames_cover_the_range_at_the_rate() {
        assert_eq!(frame_count(24.0, 0.0, 5.0), 121);
        assert_eq!(frame_count(30.0, 0.0, 0.1), 4);
        assert_eq!(frame_count(24.0, 1.0, 1.0), 1);
        assert_eq!(frame_count(24.0, 2.0, 1.0), 1);
        let times = frame_times(10.0, 0.5, 0.8);
        assert_eq!(times.len(), 4);
        assert!((times[3] - 0.8).abs() < 1e-12);
    }
}
