//! The document's animation: showing the pose of a time, keying the current pose,
//! and fitting a new handle into every key.

use anyhow::Result;
use glam::DVec2;
use project::{Animation, HandlePose, HandleSpec, Key, Pose};

use super::Document;

impl Document {
    /// The animation's keys in time (none without an animation).
    pub fn keys(&self) -> &[Key] {
        self.project
            .animation
            .as_ref()
            .map_or(&[], |a| a.keys.as_slice())
    }

    /// Shows the pose the animation's keys give at `time` (a pose only: cheap, and no
    /// undo step). Returns whether the pose changed; without keys nothing changes.
    ///
    /// # Errors
    /// What the method refuses of the pose (the document is then unchanged).
    pub fn show_time(&mut self, time: f64) -> Result<bool> {
        let Some(pose) = animation::pose_at(&self.project, time) else {
            return Ok(false);
        };
        self.show_pose(&pose)
    }

    /// Shows the keys' pose at `time` as a frame of playback: live, as a drag's frame
    /// is ([`Document::preview`]: a method that iterates to its answer starts from the
    /// frame before and stops early), so that playback keeps up; [`Document::settle`]
    /// solves the pose shown in full when playback stops. Returns whether the pose
    /// changed.
    ///
    /// # Errors
    /// As [`Document::show_time`].
    pub fn play_time(&mut self, time: f64) -> Result<bool> {
        let Some(pose) = animation::pose_at(&self.project, time) else {
            return Ok(false);
        };
        if Pose::of(&self.project).same_controls(&pose) {
            return Ok(false);
        }
        let mut project = self.project.clone();
        pose.apply(&mut project);
        self.preview(project)?;
        Ok(true)
    }

    /// Shows `pose` (a pose only, no undo step). Returns whether it changed.
    ///
    /// # Errors
    /// As [`Document::show_time`].
    pub fn show_pose(&mut self, pose: &Pose) -> Result<bool> {
        if Pose::of(&self.project).same_controls(pose) {
            return Ok(false);
        }
        let mut project = self.project.clone();
        pose.apply(&mut project);
        self.restore(project)?;
        Ok(true)
    }

    /// The animation with the current pose keyed at `time`: the key there replaced
    /// (keeping its hold), or a new one inserted in time order. The first key makes an
    /// animation at the default rate.
    pub fn keyed_at(&self, time: f64) -> Animation {
        let mut animation = self.project.animation.clone().unwrap_or_default();
        let pose = Pose::of(&self.project);
        match animation.keys.iter().position(|k| k.time >= time) {
            Some(i) if animation.keys[i].time == time => animation.keys[i].pose = pose,
            Some(i) => animation.keys.insert(
                i,
                Key {
                    time,
                    hold: false,
                    pose,
                },
            ),
            None => animation.keys.push(Key {
                time,
                hold: false,
                pose,
            }),
        }
        animation
    }

    /// Where the current pose takes the picture's point `p` (image pixels at rest):
    /// through the rest triangle of the mesh shown that contains it. `None` off the
    /// mesh.
    pub fn forward(&mut self, p: DVec2) -> Option<DVec2> {
        self.deformed();
        // Drawn as parts, the parts' joined mesh (the topmost triangle first), whose
        // vertices the positions are; else the mesh the method moves.
        let on_top: Option<Vec<[u32; 3]>> = self.parts().map(|_| {
            let mut order = self.draw_order();
            order.reverse();
            order
        });
        let deformed = self.deformed.as_ref().map(|(_, d)| d.as_slice())?;
        let ([a, b, c], [u, v, w]) = match (self.parts(), &on_top) {
            (Some(parts), Some(order)) => super::locate(pipeline::Deformer::rest(parts), order, p)?,
            _ => {
                let deformer = self.deformer();
                super::locate(deformer.rest(), deformer.triangles(), p)?
            }
        };
        let at = |v: u32| deformed.get(v as usize).copied();
        Some(at(a)? * u + at(b)? * v + at(c)? * w)
    }

    /// The pose `handle` (not yet added) should have in each of the animation's keys,
    /// in time then on the canvas, so that adding it changes each key's picture as
    /// little as it can: a point where the key's pose takes its rest position, turned
    /// and scaled by the similarity fitted there ([`Document::local_pose`]); a bar's
    /// ends where the key's pose takes them. At rest where the key's pose cannot say
    /// (off the mesh, or a cage method's own mesh).
    ///
    /// # Errors
    /// A key's pose the method refuses; the document is left as it was.
    pub(super) fn fit_into_keys(&mut self, handle: &HandleSpec) -> Result<Vec<HandlePose>> {
        let Some(animation) = &self.project.animation else {
            return Ok(Vec::new());
        };
        let poses: Vec<Pose> = animation
            .keys
            .iter()
            .map(|k| k.pose.clone())
            .chain(animation.spatial_keys.iter().map(|k| k.pose.clone()))
            .collect();
        let rigging = self.rigging();
        rigging.fit_into(self, handle, &poses)
    }

    /// `handle`'s pose that fits the current pose (see [`Document::fit_into_keys`]).
    pub(super) fn fit(&mut self, handle: &HandleSpec) -> HandlePose {
        match *handle {
            HandleSpec::Point { rest, .. } => {
                let rest = DVec2::from(rest);
                let Some(at) = self.forward(rest) else {
                    return HandlePose::rest(handle);
                };
                let (rotate, scale) = self.local_pose(rest, at);
                HandlePose::Point {
                    translate: (at - rest).to_array(),
                    rotate,
                    scale,
                }
            }
            HandleSpec::Bar { rest, .. } => {
                let ends = rest.map(|p| self.forward(DVec2::from(p)));
                match ends {
                    [Some(a), Some(b)] if a != b => HandlePose::Bar {
                        pose: [a.to_array(), b.to_array()],
                    },
                    _ => HandlePose::rest(handle),
                }
            }
        }
    }
}

impl Document {
    /// The mesh the view draws, posed as `pose`: its rest positions (texture
    /// coordinates), where `pose` takes them, and its triangles in drawing order. The
    /// document is left as it was (for the onion skin's ghosts).
    ///
    /// # Errors
    /// A pose the method refuses.
    pub fn posed_mesh(&mut self, pose: &Pose) -> Result<PosedMesh> {
        let current = self.project.clone();
        let shown = self.show_pose(pose).map(|_| {
            let deformer = self.deformer();
            PosedMesh {
                rest: deformer.rest().to_vec(),
                deformed: deformer.deformed(),
                triangles: self.rigging().drawn_triangles(self),
            }
        });
        self.restore(current)?;
        shown
    }
}

/// A mesh at rest and posed (see [`Document::posed_mesh`]).
pub struct PosedMesh {
    /// Rest positions, image pixels.
    pub rest: Vec<DVec2>,
    /// Posed positions, image pixels.
    pub deformed: Vec<DVec2>,
    /// Triangles, back to front.
    pub triangles: Vec<[u32; 3]>,
}
