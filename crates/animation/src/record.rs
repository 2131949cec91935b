//! A recorded performance brought down to keys.

use project::{HandlePose, Key, Pose, Project};

use crate::channels::Layout;

/// The default tolerance of [`simplify`], in pixels.
pub const DEFAULT_TOLERANCE: f64 = 0.5;

/// How far from a point handle its rotation and scale are measured: an error of `e`
/// radians in rotation (or `e` in scale) counts as `REACH · e` pixels.
const REACH: f64 = 20.0;

/// A performance's frames at `fps` from its timed `samples` (seconds since the
/// take began, and the pose then; in time order): frame `k` is at `k / fps`, up to
/// the last sample's time, its pose interpolated linearly (channel by channel, a bar
/// turning the smaller way) between the samples either side of it. So a take follows
/// the hand's timing however rarely it was sampled — a slow editor samples a pose per
/// drawn frame — rather than holding each sample until the next one.
///
/// No samples give no frames; one gives one frame.
pub fn resample(project: &Project, samples: &[(f64, Pose)], fps: f64) -> Vec<Pose> {
    let Some(&(last, _)) = samples.last() else {
        return Vec::new();
    };
    if samples.len() == 1 || !(fps.is_finite() && fps > 0.0) {
        return vec![samples[0].1.clone()];
    }
    let layout = Layout::of(project);
    let count = (last.max(0.0) * fps + 1e-9).floor() as usize + 1;
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut at = 0;
    (0..count)
        .map(|k| {
            let t = k as f64 / fps;
            while at + 2 < samples.len() && samples[at + 1].0 <= t {
                at += 1;
            }
            let ((ta, pa), (tb, pb)) = (&samples[at], &samples[at + 1]);
            let u = if tb > ta {
                ((t - ta) / (tb - ta)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            if u == 0.0 {
                return pa.clone();
            }
            if u == 1.0 {
                return pb.clone();
            }
            layout.channels(pa, None, &mut a);
            layout.channels(pb, Some(&a), &mut b);
            let between: Vec<f64> = a.iter().zip(&b).map(|(a, b)| a + u * (b - a)).collect();
            layout.pose(&between)
        })
        .collect()
}

/// The fewest keys (of `frames`, one pose per frame at `fps` from `start` seconds)
/// that reproduce every frame within `tolerance` pixels under linear interpolation:
/// Douglas–Peucker in time. The first and last frames are always keys; a tolerance
/// of 0 (or less) keeps every frame. A frame's error is the largest distance any
/// control lies from where the kept keys put it: a bar's ends, a cage vertex, a point
/// handle's position, and its rotation and scale as the movement they give 20 px
/// from it.
pub fn simplify(
    project: &Project,
    frames: &[Pose],
    start: f64,
    fps: f64,
    tolerance: f64,
) -> Vec<Key> {
    let time = |i: usize| start + i as f64 / fps;
    let key = |i: usize| Key {
        time: time(i),
        hold: false,
        pose: frames[i].clone(),
    };
    if frames.len() <= 2 || tolerance <= 0.0 {
        return (0..frames.len()).map(key).collect();
    }
    let layout = Layout::of(project);
    let mut keep = vec![false; frames.len()];
    keep[0] = true;
    keep[frames.len() - 1] = true;
    let mut stack = vec![(0, frames.len() - 1)];
    let (mut a, mut b) = (Vec::new(), Vec::new());
    while let Some((first, last)) = stack.pop() {
        if last - first < 2 {
            continue;
        }
        layout.channels(&frames[first], None, &mut a);
        layout.channels(&frames[last], Some(&a), &mut b);
        let mut worst = (0.0, first);
        for (i, frame) in frames.iter().enumerate().take(last).skip(first + 1) {
            let u = (i - first) as f64 / (last - first) as f64;
            let between: Vec<f64> = a.iter().zip(&b).map(|(a, b)| a + u * (b - a)).collect();
            let guess = layout.pose(&between);
            let error = distance(&guess, frame);
            if error > worst.0 {
                worst = (error, i);
            }
        }
        if worst.0 > tolerance {
            keep[worst.1] = true;
            stack.push((first, worst.1));
            stack.push((worst.1, last));
        }
    }
    (0..frames.len()).filter(|&i| keep[i]).map(key).collect()
}

/// The largest distance, in pixels, between where two poses put any control.
fn distance(a: &Pose, b: &Pose) -> f64 {
    let gap = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let handles = a
        .handles
        .iter()
        .zip(&b.handles)
        .map(|(pa, pb)| match (*pa, *pb) {
            (
                HandlePose::Point {
                    translate: t,
                    rotate: r,
                    scale: s,
                },
                HandlePose::Point {
                    translate: u,
                    rotate: q,
                    scale: z,
                },
            ) => gap(t, u) + REACH * ((r - q).abs() + (s - z).abs()),
            (HandlePose::Bar { pose: p }, HandlePose::Bar { pose: q }) => {
                gap(p[0], q[0]).max(gap(p[1], q[1]))
            }
            _ => f64::INFINITY,
        });
    let cage = match (&a.cage, &b.cage) {
        (Some(p), Some(q)) => p
            .iter()
            .zip(q)
            .map(|(p, q)| gap(*p, *q))
            .fold(0.0, f64::max),
        _ => 0.0,
    };
    handles.fold(cage, f64::max)
}

#[cfg(test)]
mod tests {
    use project::Animation;

    use super::*;
    use crate::pose_at;

    fn project() -> Project {
        Project::from_json(
            r#"{"version": 1, "handles": [{"type": "point", "rest": [10, 10]},
                {"type": "bar", "rest": [[20, 20], [40, 20]]}]}"#,
        )
        .expect("parses")
    }

    /// A performance: the point moves along a circle, the bar slides right.
    fn performance(frames: usize) -> Vec<Pose> {
        (0..frames)
            .map(|i| {
                let s = i as f64 / (frames - 1) as f64;
                let angle = std::f64::consts::PI * s;
                Pose {
                    handles: vec![
                        HandlePose::Point {
                            translate: [50.0 * angle.cos(), 50.0 * angle.sin()],
                            rotate: angle,
                            scale: 1.0,
                        },
                        HandlePose::Bar {
                            pose: [[20.0 + 30.0 * s, 20.0], [40.0 + 30.0 * s, 20.0]],
                        },
                    ],
                    cage: None,
                    overlaps: Vec::new(),
                }
            })
            .collect()
    }

    #[test]
    fn simplified_keys_replay_the_performance_within_the_tolerance() {
        let mut p = project();
        let frames = performance(97);
        for tolerance in [0.25, 2.0] {
            let keys = simplify(&p, &frames, 1.0, 24.0, tolerance);
            assert!(keys.len() < frames.len() / 2, "{} keys", keys.len());
            assert_eq!(keys[0].time, 1.0);
            assert!((keys[keys.len() - 1].time - 5.0).abs() < 1e-12);
            p.animation = Some(Animation {
                keys: keys.clone(),
                ..Animation::default()
            });
            p.validate(None).expect("valid keys");
            for (i, frame) in frames.iter().enumerate() {
                let replayed = pose_at(&p, 1.0 + i as f64 / 24.0).expect("a pose");
                let error = distance(&replayed, frame);
                assert!(error <= tolerance + 1e-9, "frame {i}: {error} px");
            }
        }
        // A tighter tolerance keeps more keys; none keeps every frame.
        let few = simplify(&p, &frames, 0.0, 24.0, 2.0).len();
        let more = simplify(&p, &frames, 0.0, 24.0, 0.25).len();
        assert!(few < more);
        assert_eq!(simplify(&p, &frames, 0.0, 24.0, 0.0).len(), frames.len());
    }

    #[test]
    fn a_still_performance_is_two_keys() {
        let p = project();
        let frames = vec![performance(2)[0].clone(); 50];
        assert_eq!(simplify(&p, &frames, 0.0, 24.0, DEFAULT_TOLERANCE).len(), 2);
    }
}
