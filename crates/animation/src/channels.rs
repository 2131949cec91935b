//! A pose as numbers that interpolate well, and back.

use std::f64::consts::PI;

use project::{HandlePose, HandleSpec, MIN_SCALE, Pose};

/// The shortest a bar may become between keys (pixels): a blend that would shorten
/// it further keeps it this long, so its direction stays defined.
const MIN_BAR_LENGTH: f64 = 1e-3;

/// `angle` brought into (−π, π].
pub(crate) fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(2.0 * PI);
    if a > PI { a - 2.0 * PI } else { a }
}

/// What a pose is made of, beyond its numbers: each handle's kind, and the cage's
/// rest (a key without a cage pose has the cage at rest).
pub(crate) struct Layout<'a> {
    pub handles: &'a [HandleSpec],
    pub cage_rest: Option<&'a [[f64; 2]]>,
}

impl<'a> Layout<'a> {
    pub fn of(project: &'a project::Project) -> Self {
        Self {
            handles: &project.handles,
            cage_rest: project.cage.as_ref().map(|c| c.rest.as_slice()),
        }
    }

    /// `pose` with the cage's vertices listed where it leaves them out (the cage at
    /// rest), as [`project::Pose::of`] lists them.
    pub fn filled(&self, mut pose: Pose) -> Pose {
        if pose.cage.is_none() {
            pose.cage = self.cage_rest.map(<[_]>::to_vec);
        }
        pose
    }

    /// Numbers per pose: 4 per handle, 2 per cage vertex.
    pub fn len(&self) -> usize {
        4 * self.handles.len() + 2 * self.cage_rest.map_or(0, <[_]>::len)
    }

    /// `pose`'s channels written into `out` (length [`Layout::len`]); each bar's
    /// direction is unwrapped to lie within half a turn of its entry in `near` (the
    /// neighbouring key's channels), so that interpolating turns it the smaller way.
    pub fn channels(&self, pose: &Pose, near: Option<&[f64]>, out: &mut Vec<f64>) {
        out.clear();
        for (i, handle) in pose.handles.iter().enumerate() {
            match *handle {
                HandlePose::Point {
                    translate,
                    rotate,
                    scale,
                } => out.extend([translate[0], translate[1], rotate, scale]),
                HandlePose::Bar { pose: [a, b] } => {
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    let mut angle = dy.atan2(dx);
                    if let Some(near) = near {
                        let reference = near[4 * i + 2];
                        angle = reference + wrap(angle - reference);
                    }
                    out.extend([
                        0.5 * (a[0] + b[0]),
                        0.5 * (a[1] + b[1]),
                        angle,
                        dx.hypot(dy),
                    ]);
                }
            }
        }
        if let Some(rest) = self.cage_rest {
            let cage = pose.cage.as_deref().unwrap_or(rest);
            out.extend(cage.iter().flatten());
        }
    }

    /// The pose whose channels are `c` (scales and bar lengths kept positive).
    pub fn pose(&self, c: &[f64]) -> Pose {
        debug_assert_eq!(c.len(), self.len());
        let handles = self
            .handles
            .iter()
            .enumerate()
            .map(|(i, handle)| {
                let c = &c[4 * i..4 * i + 4];
                match handle {
                    HandleSpec::Point { .. } => HandlePose::Point {
                        translate: [c[0], c[1]],
                        rotate: c[2],
                        scale: c[3].max(MIN_SCALE),
                    },
                    HandleSpec::Bar { .. } => {
                        let half = 0.5 * c[3].max(MIN_BAR_LENGTH);
                        let (sin, cos) = c[2].sin_cos();
                        HandlePose::Bar {
                            pose: [
                                [c[0] - half * cos, c[1] - half * sin],
                                [c[0] + half * cos, c[1] + half * sin],
                            ],
                        }
                    }
                }
            })
            .collect();
        let cage = self.cage_rest.map(|_| {
            c[4 * self.handles.len()..]
                .chunks_exact(2)
                .map(|p| [p[0], p[1]])
                .collect()
        });
        Pose {
            handles,
            cage,
            overlaps: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_keeps_angles_within_half_a_turn() {
        assert_eq!(wrap(0.0), 0.0);
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-12);
        assert!((wrap(PI) - PI).abs() < 1e-12);
        assert!((wrap(-PI) - PI).abs() < 1e-12);
    }

    #[test]
    fn channels_give_back_the_pose() {
        let handles = [
            HandleSpec::Point {
                rest: [1.0, 2.0],
                translate: [0.0; 2],
                rotate: 0.0,
                scale: 1.0,
                depth: 0,
            },
            HandleSpec::Bar {
                rest: [[0.0, 0.0], [10.0, 0.0]],
                pose: None,
                depth: 0,
            },
        ];
        let rest = [[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]];
        let layout = Layout {
            handles: &handles,
            cage_rest: Some(&rest),
        };
        let pose = Pose {
            handles: vec![
                HandlePose::Point {
                    translate: [3.0, -4.0],
                    rotate: 7.0,
                    scale: 0.5,
                },
                HandlePose::Bar {
                    pose: [[1.0, 1.0], [-3.0, 4.0]],
                },
            ],
            cage: None,
            overlaps: Vec::new(),
        };
        let mut c = Vec::new();
        layout.channels(&pose, None, &mut c);
        assert_eq!(c.len(), layout.len());
        let back = layout.pose(&c);
        assert_eq!(back.handles[0], pose.handles[0]);
        let (HandlePose::Bar { pose: got }, HandlePose::Bar { pose: want }) =
            (back.handles[1], pose.handles[1])
        else {
            panic!("a bar");
        };
        for (g, w) in got.iter().flatten().zip(want.iter().flatten()) {
            assert!((g - w).abs() < 1e-12, "{got:?} vs {want:?}");
        }
        assert_eq!(back.cage.as_deref(), Some(&rest[..]));
    }
}
