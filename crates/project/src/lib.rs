//! The rig / project file (RIG.json): what a user keeps of a warp.
//!
//! ```json
//! {"version": 1, "alpha": 1.0, "degree": 5, "fixed_boundary": false,
//!  "handles": [
//!    {"type": "point", "rest": [120, 80], "translate": [10, 0], "rotate": 0.3, "scale": 1.0},
//!    {"type": "bar", "rest": [[40, 200], [160, 200]], "pose": [[40, 210], [160, 190]]}
//!  ]}
//! ```
//!
//! Coordinates are image pixels, origin top-left, y down; angles in radians. Every
//! field but `version` and `handles` has a default, so hand-written rigs stay short.
//! The file carries no `NaN` (JSON cannot), and [`Project::validate`] refuses
//! infinities, out-of-range options and handles off the image.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// The file format version this crate reads and writes.
pub const VERSION: u32 = 1;

/// The most handles a rig file may have: the weights are built for up to this many
/// (`weights_core::MAX_HANDLES`; this crate does not depend on it, and the pipeline's
/// tests check that the two agree). A larger rig is refused with a message naming the
/// limit before anything is computed.
pub const MAX_HANDLES: usize = 10_000;

/// Which distance the weights use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MetricChoice {
    /// Euclidean for an opaque (rectangular) image, intrinsic for a cut-out.
    #[default]
    Auto,
    /// Straight-line distance everywhere.
    Euclidean,
    /// Shortest paths inside the shape.
    Intrinsic,
}

/// Placement of the basis's middle Bézier controls (degrees above 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Middle {
    /// All 0.5.
    #[default]
    Half,
    /// On the line between the outer controls.
    Linear,
}

/// One handle as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum HandleSpec {
    /// A point handle.
    Point {
        /// Rest position.
        rest: [f64; 2],
        /// Displacement of the handle.
        #[serde(default)]
        translate: [f64; 2],
        /// Rotation about the rest position, radians.
        #[serde(default)]
        rotate: f64,
        /// Uniform scale about the rest position.
        #[serde(default = "one")]
        scale: f64,
    },
    /// A bar (segment) handle.
    Bar {
        /// Rest end points.
        rest: [[f64; 2]; 2],
        /// Posed end points (default: at rest).
        #[serde(default)]
        pose: Option<[[f64; 2]; 2]>,
    },
}

fn one() -> f64 {
    1.0
}
fn default_alpha() -> f64 {
    1.0
}
fn default_degree() -> u32 {
    5
}

/// The project: which image, how it is meshed and weighted, and the handles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    /// Format version; must be [`VERSION`].
    pub version: u32,
    /// The image, relative to the project file (optional for a bare rig).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// Shape factor α ∈ [0, 1].
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// Basis degree n ≥ 5.
    #[serde(default = "default_degree")]
    pub degree: u32,
    /// Middle controls of the basis.
    #[serde(default)]
    pub middle: Middle,
    /// Pin the image border.
    #[serde(default)]
    pub fixed_boundary: bool,
    /// Distance choice.
    #[serde(default)]
    pub metric: MetricChoice,
    /// Target number of mesh vertices (default: the tool's default density).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<usize>,
    /// The handles, in order.
    pub handles: Vec<HandleSpec>,
    /// Virtual handles placed so far (rest positions), so a saved rig reloads with
    /// exactly the weights it had. Omit to let them be computed afresh.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_handles: Vec<[f64; 2]>,
    /// For each of [`Project::virtual_handles`], in the same order, the index into
    /// [`Project::handles`] of the handle it was placed for (`null` for none), so that
    /// removing that handle after a reload takes it along, as it would have before.
    /// Either empty (omitted: no virtual handle was placed for a handle, as in files
    /// from before this field) or as long as `virtual_handles`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_placed_for: Vec<Option<usize>>,
}

impl Default for Project {
    fn default() -> Self {
        Self {
            version: VERSION,
            image: None,
            alpha: 1.0,
            degree: 5,
            middle: Middle::Half,
            fixed_boundary: false,
            metric: MetricChoice::Auto,
            density: None,
            handles: Vec::new(),
            virtual_handles: Vec::new(),
            virtual_placed_for: Vec::new(),
        }
    }
}

/// Why a project cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    /// Not JSON, or not the expected fields.
    #[error("malformed rig file: {0}")]
    Json(#[from] serde_json::Error),
    /// A version this build does not read.
    #[error("unsupported rig file version {0} (this build reads version {VERSION})")]
    Version(u32),
    /// A value out of range.
    #[error("invalid rig: {0}")]
    Invalid(String),
}

impl Project {
    /// Parses and validates (without an image size) a project from JSON text.
    ///
    /// # Errors
    /// Malformed JSON, an unknown version, or values out of range.
    pub fn from_json(text: &str) -> Result<Self, ProjectError> {
        // Read the version first so a future file gets a clear message.
        #[derive(Deserialize)]
        struct Probe {
            version: Option<u32>,
        }
        let probe: Probe = serde_json::from_str(text)?;
        match probe.version {
            Some(VERSION) => {}
            Some(v) => return Err(ProjectError::Version(v)),
            None => return Err(ProjectError::Invalid("missing \"version\"".into())),
        }
        let project: Self = serde_json::from_str(text)?;
        project.validate(None)?;
        Ok(project)
    }

    /// The project as pretty-printed JSON (numbers round-trip exactly).
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).unwrap_or_default();
        s.push('\n');
        s
    }

    /// Checks ranges and finiteness, the number of handles (at most [`MAX_HANDLES`]),
    /// that [`Project::virtual_placed_for`] matches the virtual handles and names
    /// handles that exist, and with `image_size = Some((w, h))` that every handle lies
    /// on the image.
    ///
    /// # Errors
    /// The first problem found, naming the handle.
    pub fn validate(&self, image_size: Option<(u32, u32)>) -> Result<(), ProjectError> {
        let bad = |m: String| Err(ProjectError::Invalid(m));
        if self.handles.len() > MAX_HANDLES {
            return bad(format!(
                "{} handles; C2Warp is built for up to {MAX_HANDLES} handles",
                self.handles.len()
            ));
        }
        if !self.virtual_placed_for.is_empty() {
            if self.virtual_placed_for.len() != self.virtual_handles.len() {
                return bad(format!(
                    "virtual_placed_for has {} entries for {} virtual handles (one each, or \
                     leave it out)",
                    self.virtual_placed_for.len(),
                    self.virtual_handles.len()
                ));
            }
            if let Some((i, h)) = self
                .virtual_placed_for
                .iter()
                .enumerate()
                .find_map(|(i, h)| h.filter(|&h| h >= self.handles.len()).map(|h| (i, h)))
            {
                return bad(format!(
                    "virtual handle {i} was placed for handle {h}, but there are {} handles",
                    self.handles.len()
                ));
            }
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return bad(format!("alpha must be in [0, 1], got {}", self.alpha));
        }
        if !(5..=25).contains(&self.degree) {
            return bad(format!(
                "degree must be between 5 and 25, got {}",
                self.degree
            ));
        }
        if let Some(d) = self.density
            && !(16..=4_000_000).contains(&d)
        {
            return bad(format!(
                "density must be between 16 and 4000000 vertices, got {d}"
            ));
        }
        let inside = |p: [f64; 2]| match image_size {
            Some((w, h)) => {
                p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= f64::from(w) && p[1] <= f64::from(h)
            }
            None => true,
        };
        for (i, h) in self.handles.iter().enumerate() {
            let (points, numbers): (Vec<[f64; 2]>, Vec<f64>) = match h {
                HandleSpec::Point {
                    rest,
                    translate,
                    rotate,
                    scale,
                } => {
                    if *scale <= 0.0 {
                        return bad(format!("handle {i}: scale must be positive, got {scale}"));
                    }
                    (
                        vec![*rest],
                        vec![translate[0], translate[1], *rotate, *scale],
                    )
                }
                HandleSpec::Bar { rest, pose } => {
                    if rest[0] == rest[1] {
                        return bad(format!("handle {i}: bar has zero length"));
                    }
                    let pose = pose.unwrap_or(*rest);
                    (rest.to_vec(), pose.iter().flatten().copied().collect())
                }
            };
            if points
                .iter()
                .flatten()
                .chain(&numbers)
                .any(|x| !x.is_finite())
            {
                return bad(format!("handle {i}: coordinates must be finite numbers"));
            }
            if let Some(p) = points.iter().find(|p| !inside(**p)) {
                return bad(format!(
                    "handle {i}: rest position ({}, {}) lies outside the image",
                    p[0], p[1]
                ));
            }
        }
        if let Some(p) = self
            .virtual_handles
            .iter()
            .find(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            return bad(format!("virtual handle ({}, {}) is not finite", p[0], p[1]));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Project {
        Project {
            image: Some("cat.png".into()),
            alpha: 0.75,
            degree: 7,
            middle: Middle::Linear,
            fixed_boundary: true,
            metric: MetricChoice::Intrinsic,
            density: Some(5000),
            handles: vec![
                HandleSpec::Point {
                    rest: [10.5, 20.25],
                    translate: [0.1, -3.0 / 7.0],
                    rotate: std::f64::consts::PI / 3.0,
                    scale: 1.1,
                },
                HandleSpec::Bar {
                    rest: [[1.0, 2.0], [30.0, 40.0]],
                    pose: Some([[1.0 / 3.0, 2.0], [31.0, 41.0]]),
                },
            ],
            virtual_handles: vec![[5.0, 6.0], [0.1, 0.2]],
            virtual_placed_for: vec![Some(1), None],
            ..Project::default()
        }
    }

    #[test]
    fn round_trip_is_exact() {
        let p = sample();
        let back = Project::from_json(&p.to_json()).expect("parses");
        assert_eq!(p, back);
    }

    #[test]
    fn minimal_rig_gets_defaults() {
        let p = Project::from_json(
            r#"{"version":1,"handles":[{"type":"point","rest":[1,2]},{"type":"bar","rest":[[0,0],[5,0]]}]}"#,
        )
        .expect("parses");
        assert_eq!(p.alpha, 1.0);
        assert_eq!(p.degree, 5);
        assert_eq!(
            p.handles[0],
            HandleSpec::Point {
                rest: [1.0, 2.0],
                translate: [0.0, 0.0],
                rotate: 0.0,
                scale: 1.0
            }
        );
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let cases = [
            ("", "malformed"),
            ("{", "malformed"),
            (r#"{"version":2,"handles":[]}"#, "version 2"),
            (r#"{"handles":[]}"#, "version"),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[NaN,1]}]}"#,
                "malformed",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1e999,1]}]}"#,
                "",
            ),
            (
                r#"{"version":1,"handles":[{"type":"blob","rest":[1,1]}]}"#,
                "malformed",
            ),
            (r#"{"version":1,"alpha":2,"handles":[]}"#, "alpha"),
            (r#"{"version":1,"degree":3,"handles":[]}"#, "degree"),
            (
                r#"{"version":1,"handles":[{"type":"bar","rest":[[1,1],[1,1]]}]}"#,
                "zero length",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1],"scale":0}]}"#,
                "scale",
            ),
            (r#"{"version":1,"handels":[]}"#, "malformed"),
            (
                r#"{"version":1,"handles":[],"virtual_handles":[[1,1]],"virtual_placed_for":[null,0]}"#,
                "2 entries for 1 virtual handles",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1]}],"virtual_handles":[[1,2]],"virtual_placed_for":[1]}"#,
                "placed for handle 1, but there are 1 handles",
            ),
        ];
        for (text, expected) in cases {
            let err = Project::from_json(text).expect_err(text).to_string();
            assert!(err.contains(expected), "{text}: {err}");
        }
    }

    #[test]
    fn handles_must_lie_on_the_image() {
        let p = sample();
        assert!(p.validate(Some((100, 100))).is_ok());
        let err = p
            .validate(Some((20, 20)))
            .expect_err("bar end off the image");
        assert!(err.to_string().contains("outside the image"), "{err}");
    }

    #[test]
    fn files_without_virtual_placed_for_still_load_and_files_with_it_round_trip() {
        let old = r#"{"version":1,"handles":[{"type":"point","rest":[1,2]}],"virtual_handles":[[3,4],[5,6]]}"#;
        let p = Project::from_json(old).expect("an older file");
        assert!(p.virtual_placed_for.is_empty());
        assert!(!p.to_json().contains("virtual_placed_for"));
        let with = Project {
            virtual_placed_for: vec![None, Some(0)],
            ..p
        };
        let text = with.to_json();
        assert!(text.contains("\"virtual_placed_for\""), "{text}");
        assert_eq!(Project::from_json(&text).expect("parses"), with);
    }

    #[test]
    fn too_many_handles_are_refused_naming_the_limit() {
        let point = HandleSpec::Point {
            rest: [1.0, 1.0],
            translate: [0.0, 0.0],
            rotate: 0.0,
            scale: 1.0,
        };
        let mut p = Project {
            handles: vec![point; MAX_HANDLES],
            ..Project::default()
        };
        assert!(p.validate(None).is_ok());
        p.handles.push(p.handles[0].clone());
        let err = p.validate(None).expect_err("one too many").to_string();
        assert!(
            err.contains("10001 handles; C2Warp is built for up to 10000 handles"),
            "{err}"
        );
    }
}
