//! Spatial keyframing (Igarashi, Moscovich and Hughes 2005, §5.3): key poses placed
//! at markers on the canvas, blended at the control cursor by radial basis
//! functions.
//!
//! The blend interpolates every channel of the pose over the markers with Gaussian
//! radial basis functions `φ(r) = exp(−(r/σ)²)` plus a constant:
//! `f(x) = Σⱼ λⱼ φ(|x − mⱼ|) + β`, with `f(mₖ)` = key k's channel and `Σⱼ λⱼ = 0`.
//! The width σ is the mean distance from each marker to its nearest other marker, so
//! the blend does not change when the canvas is scaled and each key's influence
//! reaches about as far as its neighbours. No regularisation: the Gaussian kernel is
//! strictly positive definite, so the system is invertible for distinct markers (the
//! rig file keeps them half a pixel apart) and the keys are reproduced exactly at
//! their markers. Why this kernel: it is smooth everywhere (the cursor's motion gives
//! smooth animation), it is local (a key matters near its marker, as the paper asks:
//! "interpolating nearby key poses"), and with the constant term the weights sum to
//! one everywhere, so a rigid pose shared by all keys is kept and far from every
//! marker the blend settles on a fixed average pose instead of running off as a
//! thin-plate spline's linear term would.
//!
//! Every channel is blended with the same weights, so the blend is computed once as
//! the cardinal weights `w(x)` (one per key) and the pose is `Σₖ wₖ(x)·poseₖ`.

use project::{Pose, Project};

use crate::channels::Layout;

/// The blend of a set of markers: the inverse of its interpolation system.
#[derive(Clone, Debug)]
pub struct SpatialBlend {
    markers: Vec<[f64; 2]>,
    /// 1/σ².
    inverse_width: f64,
    /// The inverse of the (n+1)×(n+1) system `[Φ 1; 1ᵀ 0]`, row-major.
    inverse: Vec<f64>,
}

impl SpatialBlend {
    /// The blend over `markers`; `None` without markers, or when two coincide (the
    /// system is singular).
    pub fn new(markers: &[[f64; 2]]) -> Option<Self> {
        let n = markers.len();
        if n == 0 {
            return None;
        }
        let distance = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        let sigma = if n == 1 {
            1.0
        } else {
            let nearest: f64 = markers
                .iter()
                .enumerate()
                .map(|(i, &a)| {
                    markers
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != i)
                        .map(|(_, &b)| distance(a, b))
                        .fold(f64::INFINITY, f64::min)
                })
                .sum();
            nearest / n as f64
        };
        if !(sigma.is_finite() && sigma > 0.0) {
            return None;
        }
        let inverse_width = 1.0 / (sigma * sigma);
        let m = n + 1;
        let mut system = vec![0.0; m * m];
        for (i, &a) in markers.iter().enumerate() {
            for (j, &b) in markers.iter().enumerate() {
                let r = distance(a, b);
                system[i * m + j] = (-r * r * inverse_width).exp();
            }
            system[i * m + n] = 1.0;
            system[n * m + i] = 1.0;
        }
        let inverse = invert(system, m)?;
        Some(Self {
            markers: markers.to_vec(),
            inverse_width,
            inverse,
        })
    }

    /// The blend over `project`'s spatial keys; `None` without them.
    pub fn of(project: &Project) -> Option<Self> {
        let keys = &project.animation.as_ref()?.spatial_keys;
        Self::new(&keys.iter().map(|k| k.at).collect::<Vec<_>>())
    }

    /// Each key's weight with the cursor at `at`: they sum to one, and at a marker
    /// its key's weight is one and the others' zero (up to rounding).
    pub fn weights(&self, at: [f64; 2]) -> Vec<f64> {
        let n = self.markers.len();
        let m = n + 1;
        let mut row: Vec<f64> = self
            .markers
            .iter()
            .map(|b| {
                let r2 = (at[0] - b[0]).powi(2) + (at[1] - b[1]).powi(2);
                (-r2 * self.inverse_width).exp()
            })
            .collect();
        row.push(1.0);
        (0..n)
            .map(|k| (0..m).map(|i| row[i] * self.inverse[i * m + k]).sum())
            .collect()
    }

    /// `project`'s spatial keys blended with the cursor at `at` (see the module's
    /// text); a cursor on a marker gives that key's pose exactly. `None` when the
    /// project has no spatial keys or others than this blend was made for.
    pub fn pose(&self, project: &Project, at: [f64; 2]) -> Option<Pose> {
        let keys = &project.animation.as_ref()?.spatial_keys;
        if keys.len() != self.markers.len()
            || keys.iter().zip(&self.markers).any(|(k, m)| k.at != *m)
        {
            return None;
        }
        let layout = Layout::of(project);
        if let Some(k) = keys.iter().find(|k| k.at == at) {
            return Some(layout.filled(k.pose.clone()));
        }
        let weights = self.weights(at);
        let mut first = Vec::new();
        layout.channels(&keys[0].pose, None, &mut first);
        let mut blend: Vec<f64> = first.iter().map(|c| c * weights[0]).collect();
        let mut channels = Vec::new();
        for (key, w) in keys.iter().zip(&weights).skip(1) {
            layout.channels(&key.pose, Some(&first), &mut channels);
            for (b, c) in blend.iter_mut().zip(&channels) {
                *b += w * c;
            }
        }
        // Overlap orders do not blend: the key weighing most lends its own.
        let heaviest = (0..keys.len()).max_by(|&a, &b| weights[a].total_cmp(&weights[b]));
        let mut pose = layout.pose(&blend);
        pose.overlaps = heaviest.map_or_else(Vec::new, |k| keys[k].pose.overlaps.clone());
        Some(pose)
    }
}

/// The inverse of the `m × m` row-major matrix `a` by Gauss–Jordan elimination with
/// partial pivoting; `None` when it is singular.
fn invert(mut a: Vec<f64>, m: usize) -> Option<Vec<f64>> {
    let mut inverse = vec![0.0; m * m];
    for i in 0..m {
        inverse[i * m + i] = 1.0;
    }
    let scale = a.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    for col in 0..m {
        let pivot =
            (col..m).max_by(|&r, &s| a[r * m + col].abs().total_cmp(&a[s * m + col].abs()))?;
        if a[pivot * m + col].abs() <= 1e-14 * scale {
            return None;
        }
        for j in 0..m {
            a.swap(col * m + j, pivot * m + j);
            inverse.swap(col * m + j, pivot * m + j);
        }
        let p = 1.0 / a[col * m + col];
        for j in 0..m {
            a[col * m + j] *= p;
            inverse[col * m + j] *= p;
        }
        for r in 0..m {
            if r == col {
                continue;
            }
            let f = a[r * m + col];
            if f != 0.0 {
                for j in 0..m {
                    a[r * m + j] -= f * a[col * m + j];
                    inverse[r * m + j] -= f * inverse[col * m + j];
                }
            }
        }
    }
    Some(inverse)
}

#[cfg(test)]
mod tests {
    use project::{Animation, HandlePose, SpatialKey};

    use super::*;

    fn project() -> Project {
        let mut p = Project::from_json(
            r#"{"version": 1, "handles": [{"type": "point", "rest": [10, 10]},
                {"type": "bar", "rest": [[20, 20], [40, 20]]}]}"#,
        )
        .expect("parses");
        let key = |at: [f64; 2], t: [f64; 2], r: f64, bar: [[f64; 2]; 2]| SpatialKey {
            at,
            pose: Pose {
                handles: vec![
                    HandlePose::Point {
                        translate: t,
                        rotate: r,
                        scale: 1.0,
                    },
                    HandlePose::Bar { pose: bar },
                ],
                cage: None,
                overlaps: Vec::new(),
            },
        };
        p.animation = Some(Animation {
            spatial_keys: vec![
                key([0.0, 0.0], [0.0, 0.0], 0.0, [[20.0, 20.0], [40.0, 20.0]]),
                key([100.0, 0.0], [30.0, 0.0], 1.0, [[20.0, 25.0], [40.0, 25.0]]),
                key([0.0, 80.0], [0.0, 40.0], -2.0, [[30.0, 10.0], [30.0, 30.0]]),
            ],
            ..Animation::default()
        });
        p.validate(None).expect("valid");
        p
    }

    fn translate(pose: &Pose) -> [f64; 2] {
        match pose.handles[0] {
            HandlePose::Point { translate, .. } => translate,
            HandlePose::Bar { .. } => panic!("a point"),
        }
    }

    #[test]
    fn each_key_is_reproduced_at_its_marker() {
        let p = project();
        let blend = SpatialBlend::of(&p).expect("a blend");
        for (k, key) in p
            .animation
            .as_ref()
            .expect("animation")
            .spatial_keys
            .iter()
            .enumerate()
        {
            let w = blend.weights(key.at);
            for (j, w) in w.iter().enumerate() {
                let want = if j == k { 1.0 } else { 0.0 };
                assert!((w - want).abs() < 1e-12, "key {k}: weight {j} is {w}");
            }
            assert_eq!(blend.pose(&p, key.at).as_ref(), Some(&key.pose));
            // A hair off the marker: the pose within a hair of the key's.
            let near = blend
                .pose(&p, [key.at[0] + 1e-6, key.at[1]])
                .expect("a pose");
            let (a, b) = (translate(&near), translate(&key.pose));
            assert!((a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4);
        }
    }

    #[test]
    fn weights_sum_to_one_and_change_continuously() {
        let p = project();
        let blend = SpatialBlend::of(&p).expect("a blend");
        let mut last: Option<[f64; 2]> = None;
        for i in 0..=400 {
            let s = f64::from(i) / 400.0;
            // A path from beyond the first marker, past the others, far away.
            let at = [-50.0 + 300.0 * s, 120.0 * s * s];
            let w = blend.weights(at);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let t = translate(&blend.pose(&p, at).expect("a pose"));
            if let Some(last) = last {
                let step = (t[0] - last[0]).hypot(t[1] - last[1]);
                assert!(step < 2.0, "a jump of {step} px at {at:?}");
            }
            last = Some(t);
        }
        // Far from every marker the blend settles on one pose.
        let far = translate(&blend.pose(&p, [1e6, 1e6]).expect("a pose"));
        let farther = translate(&blend.pose(&p, [-1e7, 3e6]).expect("a pose"));
        assert!((far[0] - farther[0]).abs() < 1e-9 && (far[1] - farther[1]).abs() < 1e-9);
    }

    #[test]
    fn one_key_is_its_pose_everywhere_and_coincident_markers_are_refused() {
        let blend = SpatialBlend::new(&[[3.0, 4.0]]).expect("a blend");
        assert!((blend.weights([100.0, -7.0])[0] - 1.0).abs() < 1e-15);
        assert!(SpatialBlend::new(&[]).is_none());
        assert!(SpatialBlend::new(&[[1.0, 1.0], [1.0, 1.0]]).is_none());
    }
}
