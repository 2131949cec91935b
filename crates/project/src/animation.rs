//! The rig file's animation: key poses in time and key poses on the canvas.
//!
//! ```json
//! "animation": {"fps": 24, "interpolation": "linear",
//!   "keys": [{"time": 0, "pose": [{"translate": [0, 0]}, {"pose": [[40, 200], [160, 200]]}]},
//!            {"time": 1.5, "hold": true, "pose": [{"translate": [30, -10], "rotate": 4.0},
//!                                                  {"pose": [[40, 210], [160, 190]]}]}],
//!   "spatial_keys": [{"at": [100, 40], "pose": [...]}]}
//! ```
//!
//! A key's `pose` has one entry per handle, in the file's handle order, with that
//! handle's pose fields as in `"handles"`; its `cage`, where the rig has a cage, the
//! cage's posed vertices (left out: the cage at rest). How poses are interpolated is
//! the `animation` crate's; this module holds the data and its checks.

use serde::{Deserialize, Serialize};

use crate::{HandleSpec, MAX_POSE, MAX_SCALE, MIN_SCALE, Project};

/// The default frame rate.
pub const DEFAULT_FPS: f64 = 24.0;
/// The highest frame rate a rig file may ask for.
pub const MAX_FPS: f64 = 240.0;
/// The most keys (in time) an animation may have.
pub const MAX_KEYS: usize = 100_000;
/// The most spatial keys: their blend solves a dense system of this size.
pub const MAX_SPATIAL_KEYS: usize = 256;
/// The latest key time, in seconds (a day).
pub const MAX_TIME: f64 = 86_400.0;
/// How close two spatial keys' markers may be, in pixels: closer ones would make
/// the blend's system (nearly) singular.
pub const MIN_MARKER_DISTANCE: f64 = 0.5;

/// The animation of a rig: key poses in time, and key poses on the canvas.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Animation {
    /// Frames per second of playback and export.
    #[serde(default = "default_fps")]
    pub fps: f64,
    /// How poses between keys are found.
    #[serde(default)]
    pub interpolation: Interpolation,
    /// Key poses in time, in time order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keys: Vec<Key>,
    /// Key poses on the canvas (spatial keyframing).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spatial_keys: Vec<SpatialKey>,
}

impl Default for Animation {
    fn default() -> Self {
        Self {
            fps: DEFAULT_FPS,
            interpolation: Interpolation::Linear,
            keys: Vec::new(),
            spatial_keys: Vec::new(),
        }
    }
}

impl Animation {
    /// Whether there is nothing to keep (no keys of either kind): such an animation
    /// is left out of the file when its rate and interpolation are the defaults.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty() && self.spatial_keys.is_empty()
    }

    /// The time of the last key (0 without keys).
    pub fn duration(&self) -> f64 {
        self.keys.last().map_or(0.0, |k| k.time)
    }

    /// The key at `time` exactly, if any.
    pub fn key_at(&self, time: f64) -> Option<usize> {
        self.keys.iter().position(|k| k.time == time)
    }

    /// Removes handle `index` from every key's pose (its track).
    pub fn remove_handle(&mut self, index: usize) {
        for pose in self.poses_mut() {
            if index < pose.handles.len() {
                pose.handles.remove(index);
            }
        }
    }

    /// Every key's pose, in time then on the canvas.
    pub fn poses_mut(&mut self) -> impl Iterator<Item = &mut Pose> {
        self.keys
            .iter_mut()
            .map(|k| &mut k.pose)
            .chain(self.spatial_keys.iter_mut().map(|k| &mut k.pose))
    }
}

fn default_fps() -> f64 {
    DEFAULT_FPS
}

/// How the pose between two keys is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    /// Straight lines: each number of a pose moves at a constant rate from key to key.
    #[default]
    Linear,
    /// Smooth curves through the keys (cubic Hermite with Catmull–Rom slopes), easing
    /// in at the first key and out at the last.
    Smooth,
}

deserialize_by_name!(Interpolation, "an interpolation", [
    "linear" => Interpolation::Linear,
    "smooth" => Interpolation::Smooth,
]);

impl Interpolation {
    /// Both, in the order a menu lists them.
    pub const ALL: [Interpolation; 2] = [Interpolation::Linear, Interpolation::Smooth];

    /// The name a person reads.
    pub fn label(self) -> &'static str {
        match self {
            Interpolation::Linear => "Linear",
            Interpolation::Smooth => "Smooth",
        }
    }
}

/// The pose of every control: one entry per handle, and the cage's vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pose {
    /// One entry per handle, in the file's handle order.
    pub handles: Vec<HandlePose>,
    /// The cage's posed vertices (`None`: the cage at rest, or no cage).
    pub cage: Option<Vec<[f64; 2]>>,
    /// The order of the picture's overlap regions in this pose (automatic depth,
    /// [`Project::overlaps`]).
    pub overlaps: Vec<crate::OverlapOrder>,
}

/// One handle's pose: a point's transform about its rest position, or a bar's posed
/// ends (the pose fields of [`HandleSpec`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    deny_unknown_fields,
    expecting = "a point's pose {\"translate\": [x, y], \"rotate\": radians, \"scale\": s} \
                 or a bar's {\"pose\": [[x, y], [x, y]]}"
)]
pub enum HandlePose {
    /// A bar's posed end points.
    Bar {
        /// The posed ends.
        pose: [[f64; 2]; 2],
    },
    /// A point handle's displacement, rotation and scale about its rest position.
    Point {
        /// Displacement, pixels.
        #[serde(default)]
        translate: [f64; 2],
        /// Rotation, radians (more than a turn is more than a turn).
        #[serde(default)]
        rotate: f64,
        /// Uniform scale.
        #[serde(default = "crate::one")]
        scale: f64,
    },
}

impl HandlePose {
    /// The pose `handle` has in the rig file.
    pub fn of(handle: &HandleSpec) -> Self {
        match *handle {
            HandleSpec::Point {
                translate,
                rotate,
                scale,
                ..
            } => HandlePose::Point {
                translate,
                rotate,
                scale,
            },
            HandleSpec::Bar { rest, pose, .. } => HandlePose::Bar {
                pose: pose.unwrap_or(rest),
            },
        }
    }

    /// The pose of `handle` at rest.
    pub fn rest(handle: &HandleSpec) -> Self {
        match *handle {
            HandleSpec::Point { .. } => HandlePose::Point {
                translate: [0.0; 2],
                rotate: 0.0,
                scale: 1.0,
            },
            HandleSpec::Bar { rest, .. } => HandlePose::Bar { pose: rest },
        }
    }

    /// Sets `handle`'s pose fields to this pose (a pose of the other kind is ignored:
    /// [`Project::validate`] refuses such a file).
    pub fn apply(&self, handle: &mut HandleSpec) {
        match (self, handle) {
            (
                HandlePose::Point {
                    translate,
                    rotate,
                    scale,
                },
                HandleSpec::Point {
                    translate: t,
                    rotate: r,
                    scale: s,
                    ..
                },
            ) => {
                *t = *translate;
                *r = *rotate;
                *s = *scale;
            }
            (HandlePose::Bar { pose }, HandleSpec::Bar { rest, pose: p, .. }) => {
                *p = (pose != rest).then_some(*pose);
            }
            _ => {}
        }
    }
}

impl Pose {
    /// The pose `project`'s handles and cage have: every bar's ends and, with a cage,
    /// every cage vertex's position (at rest included), so that two poses that look
    /// the same compare equal.
    pub fn of(project: &Project) -> Self {
        Self {
            handles: project.handles.iter().map(HandlePose::of).collect(),
            cage: project
                .cage
                .as_ref()
                .map(|c| c.pose.clone().unwrap_or_else(|| c.rest.clone())),
            overlaps: project.overlaps.clone(),
        }
    }

    /// Whether the two poses put every handle and the cage in the same place (their
    /// overlap orders aside, which follow from them).
    pub fn same_controls(&self, other: &Pose) -> bool {
        self.handles == other.handles && self.cage == other.cage
    }

    /// Poses `project`'s handles and cage.
    pub fn apply(&self, project: &mut Project) {
        for (pose, handle) in self.handles.iter().zip(&mut project.handles) {
            pose.apply(handle);
        }
        if let Some(cage) = &mut project.cage {
            cage.pose = self.cage.clone().filter(|p| *p != cage.rest);
        }
        project.overlaps = self.overlaps.clone();
    }
}

/// A key pose in time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "KeyFields", into = "KeyFields")]
pub struct Key {
    /// When, in seconds from the start.
    pub time: f64,
    /// Keep this pose until the next key (no interpolation after it).
    pub hold: bool,
    /// The pose.
    pub pose: Pose,
}

/// A key pose on the canvas: the control cursor at `at` gives this pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "SpatialKeyFields", into = "SpatialKeyFields")]
pub struct SpatialKey {
    /// Where its marker lies, in image pixels.
    pub at: [f64; 2],
    /// The pose.
    pub pose: Pose,
}

/// [`Key`] as the file has it: the pose's fields beside the time.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyFields {
    time: f64,
    #[serde(default, skip_serializing_if = "is_false")]
    hold: bool,
    #[serde(default)]
    pose: Vec<HandlePose>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cage: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    overlaps: Vec<crate::OverlapOrder>,
}

/// [`SpatialKey`] as the file has it.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpatialKeyFields {
    at: [f64; 2],
    #[serde(default)]
    pose: Vec<HandlePose>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cage: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    overlaps: Vec<crate::OverlapOrder>,
}

impl From<KeyFields> for Key {
    fn from(k: KeyFields) -> Self {
        Self {
            time: k.time,
            hold: k.hold,
            pose: Pose {
                handles: k.pose,
                cage: k.cage,
                overlaps: k.overlaps,
            },
        }
    }
}

impl From<Key> for KeyFields {
    fn from(k: Key) -> Self {
        Self {
            time: k.time,
            hold: k.hold,
            pose: k.pose.handles,
            cage: k.pose.cage,
            overlaps: k.pose.overlaps,
        }
    }
}

impl From<SpatialKeyFields> for SpatialKey {
    fn from(k: SpatialKeyFields) -> Self {
        Self {
            at: k.at,
            pose: Pose {
                handles: k.pose,
                cage: k.cage,
                overlaps: k.overlaps,
            },
        }
    }
}

impl From<SpatialKey> for SpatialKeyFields {
    fn from(k: SpatialKey) -> Self {
        Self {
            at: k.at,
            pose: k.pose.handles,
            cage: k.pose.cage,
            overlaps: k.pose.overlaps,
        }
    }
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl Animation {
    /// Checks the animation against `project`'s handles and cage: the rate, key times
    /// (finite, from 0, in increasing order), one pose of the right kind per handle
    /// with numbers in the handles' ranges, cages of the right size, markers apart.
    ///
    /// # Errors
    /// The first problem, naming the key.
    pub fn validate(&self, project: &Project) -> Result<(), String> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= MAX_FPS) {
            return Err(format!(
                "animation.fps must be above 0 and at most {MAX_FPS}, got {}",
                self.fps
            ));
        }
        if self.keys.len() > MAX_KEYS {
            return Err(format!(
                "animation has {} keys; at most {MAX_KEYS} are read",
                self.keys.len()
            ));
        }
        if self.spatial_keys.len() > MAX_SPATIAL_KEYS {
            return Err(format!(
                "animation has {} spatial keys; at most {MAX_SPATIAL_KEYS} are read",
                self.spatial_keys.len()
            ));
        }
        let mut last = None;
        for (i, key) in self.keys.iter().enumerate() {
            let at = format!("animation.keys[{i}]");
            if !(key.time.is_finite() && (0.0..=MAX_TIME).contains(&key.time)) {
                return Err(format!(
                    "{at}: time must be between 0 and {MAX_TIME} seconds, got {}",
                    key.time
                ));
            }
            if let Some(last) = last
                && key.time <= last
            {
                return Err(format!(
                    "{at}: keys must be in increasing time order, but {} s follows {last} s",
                    key.time
                ));
            }
            last = Some(key.time);
            check_pose(&key.pose, project, &at)?;
        }
        for (i, key) in self.spatial_keys.iter().enumerate() {
            let at = format!("animation.spatial_keys[{i}]");
            if key.at.iter().any(|x| !x.is_finite() || x.abs() > MAX_POSE) {
                return Err(format!("{at}: \"at\" must be finite numbers of pixels"));
            }
            if let Some(j) = self.spatial_keys[..i].iter().position(|other| {
                (other.at[0] - key.at[0]).hypot(other.at[1] - key.at[1]) < MIN_MARKER_DISTANCE
            }) {
                return Err(format!(
                    "{at}: its marker lies on spatial key {j}'s (markers must be at least \
                     {MIN_MARKER_DISTANCE} px apart)"
                ));
            }
            check_pose(&key.pose, project, &at)?;
        }
        Ok(())
    }
}

/// Checks one key's pose against the project's handles and cage.
fn check_pose(pose: &Pose, project: &Project, at: &str) -> Result<(), String> {
    if pose.handles.len() != project.handles.len() {
        return Err(format!(
            "{at}: pose has {} entries for {} handles (one per handle, in the handles' order)",
            pose.handles.len(),
            project.handles.len()
        ));
    }
    for (i, (pose, handle)) in pose.handles.iter().zip(&project.handles).enumerate() {
        let numbers: Vec<f64> = match (pose, handle) {
            (
                HandlePose::Point {
                    translate,
                    rotate,
                    scale,
                },
                HandleSpec::Point { .. },
            ) => {
                if !(MIN_SCALE..=MAX_SCALE).contains(scale) {
                    return Err(format!(
                        "{at}.pose[{i}]: scale must be between {MIN_SCALE:e} and {MAX_SCALE:e}, \
                         got {scale}"
                    ));
                }
                vec![translate[0], translate[1], *rotate]
            }
            (HandlePose::Bar { pose }, HandleSpec::Bar { .. }) => {
                pose.iter().flatten().copied().collect()
            }
            (HandlePose::Bar { .. }, HandleSpec::Point { .. }) => {
                return Err(format!(
                    "{at}.pose[{i}]: handle {i} is a point; its pose is \
                     {{\"translate\": [x, y], \"rotate\": r, \"scale\": s}}"
                ));
            }
            (HandlePose::Point { .. }, HandleSpec::Bar { .. }) => {
                return Err(format!(
                    "{at}.pose[{i}]: handle {i} is a bar; its pose is \
                     {{\"pose\": [[x, y], [x, y]]}}"
                ));
            }
        };
        if numbers.iter().any(|x| !x.is_finite() || x.abs() > MAX_POSE) {
            return Err(format!(
                "{at}.pose[{i}]: coordinates must be finite numbers within ±{MAX_POSE:e}"
            ));
        }
    }
    match (&pose.cage, &project.cage) {
        (None, _) => {}
        (Some(_), None) => {
            return Err(format!("{at}: a cage pose, but the rig has no cage"));
        }
        (Some(posed), Some(cage)) => {
            if posed.len() != cage.rest.len() {
                return Err(format!(
                    "{at}: cage has {} points for {} cage vertices",
                    posed.len(),
                    cage.rest.len()
                ));
            }
            if posed
                .iter()
                .flatten()
                .any(|x| !x.is_finite() || x.abs() > MAX_POSE)
            {
                return Err(format!(
                    "{at}: cage coordinates must be finite numbers within ±{MAX_POSE:e}"
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const RIG: &str = r#"{"version": 1,
        "handles": [{"type": "point", "rest": [10, 10]},
                    {"type": "bar", "rest": [[20, 20], [40, 20]]}],
        "cage": {"rest": [[0, 0], [50, 0], [50, 50]]},
        "animation": {"fps": 12, "interpolation": "smooth", "keys": [
            {"time": 0, "pose": [{}, {"pose": [[20, 20], [40, 20]]}]},
            {"time": 0.5, "hold": true,
             "pose": [{"translate": [1, 2], "rotate": 7.5, "scale": 2},
                      {"pose": [[21, 20], [40, 25]]}],
             "cage": [[0, 0], [51, 1], [50, 50]]}],
          "spatial_keys": [{"at": [5, 5], "pose": [{"rotate": 1}, {"pose": [[20, 20], [40, 20]]}]}]}}"#;

    fn with_animation(animation: &str) -> Result<Project, crate::ProjectError> {
        let rig = format!(
            r#"{{"version": 1,
                "handles": [{{"type": "point", "rest": [10, 10]}},
                            {{"type": "bar", "rest": [[20, 20], [40, 20]]}}],
                "animation": {animation}}}"#
        );
        Project::from_json(&rig)
    }

    fn message(animation: &str) -> String {
        match with_animation(animation) {
            Ok(_) => panic!("{animation} was accepted"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn an_animation_reads_and_writes_back_the_same() {
        let project = Project::from_json(RIG).expect("parses");
        let animation = project.animation.as_ref().expect("an animation");
        assert_eq!(animation.fps, 12.0);
        assert_eq!(animation.interpolation, Interpolation::Smooth);
        assert_eq!(animation.keys.len(), 2);
        assert_eq!(
            animation.keys[0].pose.handles[0],
            HandlePose::Point {
                translate: [0.0; 2],
                rotate: 0.0,
                scale: 1.0
            }
        );
        assert!(animation.keys[1].hold);
        assert_eq!(
            animation.keys[1].pose.handles[1],
            HandlePose::Bar {
                pose: [[21.0, 20.0], [40.0, 25.0]]
            }
        );
        assert_eq!(animation.keys[0].pose.cage, None);
        assert_eq!(animation.spatial_keys[0].at, [5.0, 5.0]);
        let again = Project::from_json(&project.to_json()).expect("reads back");
        assert_eq!(again, project);
        // A rig without an animation writes none.
        let plain = Project::from_json(r#"{"version": 1, "handles": []}"#).expect("parses");
        assert!(!plain.to_json().contains("animation"));
    }

    #[test]
    fn a_pose_applied_to_a_project_reads_back_as_that_pose() {
        let mut project = Project::from_json(RIG).expect("parses");
        let key = project.animation.as_ref().expect("animation").keys[1]
            .pose
            .clone();
        key.apply(&mut project);
        assert_eq!(Pose::of(&project), key);
        let rest = project.animation.as_ref().expect("animation").keys[0]
            .pose
            .clone();
        rest.apply(&mut project);
        // At rest a bar and the cage write no pose.
        assert!(matches!(
            project.handles[1],
            HandleSpec::Bar { pose: None, .. }
        ));
        assert_eq!(project.cage.as_ref().and_then(|c| c.pose.clone()), None);
    }

    #[test]
    fn bad_animations_are_refused_with_the_key_named() {
        let two = r#"[{}, {"pose": [[20, 20], [40, 20]]}]"#;
        assert!(message(r#"{"fps": 0}"#).contains("animation.fps must be above 0"));
        assert!(message(r#"{"fps": 1000}"#).contains("at most 240"));
        assert!(
            message(&format!(
                r#"{{"keys": [{{"time": 1, "pose": {two}}}, {{"time": 0.5, "pose": {two}}}]}}"#
            ))
            .contains("animation.keys[1]: keys must be in increasing time order")
        );
        assert!(
            message(&format!(r#"{{"keys": [{{"time": -1, "pose": {two}}}]}}"#))
                .contains("time must be between 0")
        );
        assert!(
            message(r#"{"keys": [{"time": 0, "pose": [{}]}]}"#)
                .contains("pose has 1 entries for 2 handles")
        );
        assert!(
            message(r#"{"keys": [{"time": 0, "pose": [{}, {}]}]}"#)
                .contains("animation.keys[0].pose[1]: handle 1 is a bar")
        );
        assert!(
            message(r#"{"keys": [{"time": 0, "pose": [{"pose": [[0, 0], [1, 1]]}, {}]}]}"#)
                .contains("handle 0 is a point")
        );
        assert!(
            message(
                r#"{"keys": [{"time": 0, "pose": [{"scale": 0}, {"pose": [[20, 20], [40, 20]]}]}]}"#
            )
            .contains("scale must be between")
        );
        assert!(
            message(&format!(
                r#"{{"keys": [{{"time": 0, "pose": {two}, "cage": [[0, 0]]}}]}}"#
            ))
            .contains("a cage pose, but the rig has no cage")
        );
        assert!(
            message(&format!(
                r#"{{"spatial_keys": [{{"at": [1, 1], "pose": {two}}}, {{"at": [1.1, 1], "pose": {two}}}]}}"#
            ))
            .contains("animation.spatial_keys[1]: its marker lies on spatial key 0's")
        );
        // A misspelt field and a pose of neither kind name where they are.
        let typo = message(&format!(
            r#"{{"keys": [{{"time": 0, "hodl": true, "pose": {two}}}]}}"#
        ));
        assert!(
            typo.contains("animation.keys[0]") && typo.contains("hodl"),
            "{typo}"
        );
        let neither = message(r#"{"keys": [{"time": 0, "pose": [{"spin": 1}, {}]}]}"#);
        assert!(
            neither.contains("animation.keys[0].pose[0]") && neither.contains("a bar's"),
            "{neither}"
        );
        assert!(message(r#"{"interpolation": "cubic"}"#).contains("\"linear\" or \"smooth\""));
    }

    #[test]
    fn removing_a_handle_removes_its_track() {
        let mut project = Project::from_json(RIG).expect("parses");
        let animation = project.animation.as_mut().expect("animation");
        animation.remove_handle(0);
        assert!(animation.poses_mut().all(|p| p.handles.len() == 1));
        project.handles.remove(0);
        project.validate(None).expect("still valid");
    }
}
