//! The seam where the editor and the command line choose a warping method.
//!
//! Every method answers one question — given this rest mesh and these handles, where
//! does every vertex go? — through [`Deformer`]. Each has an expensive step when the
//! set of handles (or the method's parameters) changes: building weights, factorising
//! systems; and a cheap step when only the handles' poses change, as in a drag. Both
//! happen in [`Deformer::set_handles`], which tells them apart by comparing the
//! handles' rest positions.
//!
//! The methods:
//! - [`Method::C2`]: the C² weights of `weights-core` ([`Rig`]); its result is best
//!   drawn skinned (sparse weights and one transform per node, blended per vertex).
//! - [`Method::Arap`]: as-rigid-as-possible manipulation of the `arap` crate
//!   ([`ArapRig`]); its result is a position per vertex.
//!
//! To add a method: a variant of [`Method`] (in the `project` crate, with its rig-file
//! name), a type implementing [`Deformer`], and a case in [`deformer`].

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::DVec2;
pub use project::Method;
use project::RigidityStroke;
use weights_core::{Domain, Handle, Rig, Similarity};

/// How a method's result is best drawn.
pub enum Output<'a> {
    /// Sparse weights and node transforms, blended per vertex (on the GPU, in the
    /// vertex shader): only the transforms change during a drag.
    Skinned(&'a Rig),
    /// A deformed position per mesh vertex (8 bytes a vertex to upload in f32).
    Positions(&'a [DVec2]),
}

/// A warping method set up on a rest mesh and a set of handles.
pub trait Deformer: Send {
    /// Which method this is.
    fn method(&self) -> Method;

    /// The rest mesh.
    fn domain(&self) -> &Domain;

    /// The handles, in their current poses.
    fn handles(&self) -> &[Handle];

    /// Takes new handles: the expensive step when handles were added, removed or moved
    /// at rest, else the cheap one (a new pose). On error nothing changes.
    ///
    /// # Errors
    /// Handles the method refuses (off the shape, coincident, non-finite).
    fn set_handles(&mut self, handles: &[Handle]) -> Result<()>;

    /// Where every mesh vertex goes in the current pose.
    fn deformed(&self) -> Vec<DVec2>;

    /// The result, in the form that draws best.
    fn output(&self) -> Output<'_>;
}

impl Deformer for Rig {
    fn method(&self) -> Method {
        Method::C2
    }

    fn domain(&self) -> &Domain {
        Rig::domain(self)
    }

    fn handles(&self) -> &[Handle] {
        Rig::handles(self)
    }

    fn set_handles(&mut self, handles: &[Handle]) -> Result<()> {
        Ok(Rig::set_handles(self, handles.to_vec())?)
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.deform()
    }

    fn output(&self) -> Output<'_> {
        Output::Skinned(self)
    }
}

/// Sets up `method` on the mesh of `rig` (the C² rig built by [`crate::prepare`],
/// whose mesh has every handle as a vertex) with its handles, and `rigidity` for ARAP.
///
/// # Errors
/// What the method refuses.
pub fn deformer(
    method: Method,
    rig: Rig,
    rigidity: &[RigidityStroke],
) -> Result<Box<dyn Deformer>> {
    Ok(match method {
        Method::C2 => Box::new(rig),
        Method::Arap => Box::new(ArapRig::new(rig.domain().clone(), rig.handles(), rigidity)?),
        Method::Lbc => anyhow::bail!("LBC warps by a cage, not by handles (see pipeline::cage)"),
    })
}

/// Milliseconds an ARAP rig spent in each of its steps, most recently.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArapTimes {
    /// Registration (once per mesh).
    pub registration_ms: f64,
    /// Compilation (when the pinned vertices or the rigidity change).
    pub compile_ms: f64,
    /// The last update (every pose).
    pub update_ms: f64,
}

/// As-rigid-as-possible manipulation with C2Warp's handles.
///
/// The paper's handles are mesh vertices that carry a position. Here:
/// - a point handle pins its mesh vertex (the one nearest its rest position) to where
///   the handle's transform takes it: rest + translate. With a rotation or a scale
///   other than 1 it also pins the vertex's one-ring, each to where the handle's
///   similarity about its rest position takes it, so the surroundings turn and scale
///   with the handle as an artist expects (with rotate = 0 and scale = 1 it pins the
///   one vertex, exactly the paper);
/// - a bar pins its samples — the points the C² weights sample it at
///   ([`weights_core::bar_samples`] at [`weights_core::bar_spacing`]: its ends and up to
///   15 points between, which the meshes of [`crate::prepare`] and `c2warp --mesh` have
///   as vertices; elsewhere the nearest vertex), each to where the similarity taking the
///   rest ends to the posed ends takes it;
/// - a vertex claimed by two handles belongs to the first.
///
/// Changing which vertices are pinned recompiles (factorises); a pose of the same pins
/// only updates. Turning a point handle away from rotate = 0, scale = 1 adds its ring
/// and so recompiles once, at the start of the turn.
///
/// Cloning shares the factorised systems.
#[derive(Clone)]
pub struct ArapRig {
    domain: Domain,
    registration: arap::Registration,
    handles: Vec<Handle>,
    /// The painted strokes, and the per-triangle rigidity they give (1 where nothing
    /// is painted).
    strokes: Vec<RigidityStroke>,
    rigidity: Vec<f64>,
    /// The pinned vertices, each with the handle that pins it.
    pins: Vec<(u32, usize)>,
    compiled: Arc<arap::Compiled>,
    pose: arap::Deformation,
    times: ArapTimes,
}

impl ArapRig {
    /// Registers the mesh of `domain`, compiles for `handles` and poses it.
    ///
    /// # Errors
    /// A degenerate mesh, or handles that cannot be pinned (non-finite).
    pub fn new(
        domain: Domain,
        handles: &[Handle],
        rigidity_strokes: &[RigidityStroke],
    ) -> Result<Self> {
        let clock = Instant::now();
        let registration = arap::Registration::new(domain.positions(), domain.triangles())
            .context("cannot set up ARAP on this mesh")?;
        let registration_ms = ms(clock);
        let rigidity = rigidity_weights(&domain, rigidity_strokes);
        let pins = pins(&domain, &registration, handles)?;
        let clock = Instant::now();
        let vertices: Vec<u32> = pins.iter().map(|&(v, _)| v).collect();
        let compiled = Arc::new(registration.compile(&vertices, Some(&rigidity))?);
        let compile_ms = ms(clock);
        let mut rig = Self {
            domain,
            registration,
            handles: handles.to_vec(),
            strokes: rigidity_strokes.to_vec(),
            rigidity,
            pins,
            compiled,
            pose: arap::Deformation::default(),
            times: ArapTimes {
                registration_ms,
                compile_ms,
                update_ms: 0.0,
            },
        };
        rig.update()?;
        Ok(rig)
    }

    /// The times of the last registration, compilation and update.
    pub fn times(&self) -> ArapTimes {
        self.times
    }

    /// How many vertices the handles pin.
    pub fn pinned(&self) -> usize {
        self.pins.len()
    }

    /// The per-triangle rigidity weights in use (1 where nothing is painted).
    pub fn rigidity(&self) -> &[f64] {
        &self.rigidity
    }

    /// Step one's result for the current pose (the scale-free fit of the paper's
    /// §4.1).
    pub fn step_one(&self) -> &[DVec2] {
        &self.pose.step_one
    }

    /// The deformed positions of the current pose.
    pub fn positions(&self) -> &[DVec2] {
        &self.pose.positions
    }

    /// Paints new rigidity (recompiles).
    ///
    /// # Errors
    /// As [`ArapRig::new`].
    pub fn set_rigidity(&mut self, strokes: &[RigidityStroke]) -> Result<()> {
        if strokes == self.strokes {
            return Ok(());
        }
        let rigidity = rigidity_weights(&self.domain, strokes);
        if rigidity != self.rigidity {
            let clock = Instant::now();
            let vertices: Vec<u32> = self.pins.iter().map(|&(v, _)| v).collect();
            self.compiled = Arc::new(self.registration.compile(&vertices, Some(&rigidity))?);
            self.times.compile_ms = ms(clock);
            self.rigidity = rigidity;
            self.update()?;
        }
        self.strokes = strokes.to_vec();
        Ok(())
    }

    /// The strokes the rigidity comes from.
    pub fn strokes(&self) -> &[RigidityStroke] {
        &self.strokes
    }

    /// Poses the compiled system for the current handles.
    fn update(&mut self) -> Result<()> {
        let clock = Instant::now();
        let positions = self.domain.positions();
        let targets: Vec<DVec2> = self
            .pins
            .iter()
            .map(|&(v, h)| handle_map(&self.handles[h], positions[v as usize]))
            .collect();
        self.compiled.update_into(&targets, &mut self.pose)?;
        self.times.update_ms = ms(clock);
        Ok(())
    }
}

impl Deformer for ArapRig {
    fn method(&self) -> Method {
        Method::Arap
    }

    fn domain(&self) -> &Domain {
        &self.domain
    }

    fn handles(&self) -> &[Handle] {
        &self.handles
    }

    fn set_handles(&mut self, handles: &[Handle]) -> Result<()> {
        let pins = pins(&self.domain, &self.registration, handles)?;
        let old = std::mem::replace(&mut self.handles, handles.to_vec());
        let result = if pins == self.pins {
            self.update()
        } else {
            let clock = Instant::now();
            let vertices: Vec<u32> = pins.iter().map(|&(v, _)| v).collect();
            match self.registration.compile(&vertices, Some(&self.rigidity)) {
                Ok(compiled) => {
                    self.times.compile_ms = ms(clock);
                    let old_compiled = std::mem::replace(&mut self.compiled, Arc::new(compiled));
                    let old_pins = std::mem::replace(&mut self.pins, pins);
                    let result = self.update();
                    if result.is_err() {
                        self.compiled = old_compiled;
                        self.pins = old_pins;
                    }
                    result
                }
                Err(e) => Err(e.into()),
            }
        };
        if result.is_err() {
            self.handles = old;
            // The previous pose stands; recompute it so the buffers match it.
            let _ = self.update();
        }
        result
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.pose.positions.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Positions(&self.pose.positions)
    }
}

/// Where `handle` takes the rest point `p`: a point handle's similarity about its rest
/// position, or for a bar the similarity taking its rest ends to its posed ends.
pub fn handle_map(handle: &Handle, p: DVec2) -> DVec2 {
    match *handle {
        Handle::Point { rest, transform } => transform.apply(rest, p),
        Handle::Bar { rest, pose } => {
            let c = (rest[0] + rest[1]) * 0.5;
            Similarity::from_segments(c, rest, pose).apply(c, p)
        }
    }
}

/// The vertices each handle pins, in handle order, each with its handle; a vertex
/// already pinned by an earlier handle is left to it.
fn pins(
    domain: &Domain,
    registration: &arap::Registration,
    handles: &[Handle],
) -> Result<Vec<(u32, usize)>> {
    let mut taken = std::collections::HashSet::new();
    let mut pins = Vec::new();
    let mut pin = |v: u32, h: usize, pins: &mut Vec<(u32, usize)>| {
        if taken.insert(v) {
            pins.push((v, h));
        }
    };
    for (h, handle) in handles.iter().enumerate() {
        match *handle {
            Handle::Point { rest, transform } => {
                anyhow::ensure!(
                    rest.is_finite() && transform.is_finite(),
                    "handle {h} has a non-finite position or pose"
                );
                let v = domain
                    .nearest_vertex(rest)
                    .with_context(|| format!("handle {h} is off the mesh"))?;
                pin(v, h, &mut pins);
                if transform.rotation != 0.0 || transform.scale != 1.0 {
                    for n in registration.neighbours(v)? {
                        pin(n, h, &mut pins);
                    }
                }
            }
            Handle::Bar { rest, pose } => {
                anyhow::ensure!(
                    rest.iter().chain(&pose).all(|p| p.is_finite()),
                    "bar {h} has a non-finite position or pose"
                );
                let spacing = weights_core::bar_spacing(handles, h);
                for (_, p) in weights_core::bar_samples(rest, spacing) {
                    let v = domain
                        .nearest_vertex(p)
                        .with_context(|| format!("bar {h} is off the mesh"))?;
                    pin(v, h, &mut pins);
                }
            }
        }
    }
    Ok(pins)
}

/// The rigidity of every triangle: the largest weight of the strokes whose polyline
/// passes within their radius of the triangle's centroid, 1 where none does.
pub fn rigidity_weights(domain: &Domain, strokes: &[RigidityStroke]) -> Vec<f64> {
    let positions = domain.positions();
    let centroids: Vec<DVec2> = domain
        .triangles()
        .iter()
        .map(|t| t.iter().map(|&v| positions[v as usize]).sum::<DVec2>() / 3.0)
        .collect();
    let mut weights = vec![1.0; centroids.len()];
    let mut painted = vec![false; centroids.len()];
    for stroke in strokes {
        let points: Vec<DVec2> = stroke.stroke.iter().map(|&p| DVec2::from(p)).collect();
        let Some(first) = points.first() else {
            continue;
        };
        let (lo, hi) = points
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let (lo, hi) = (lo - stroke.radius, hi + stroke.radius);
        let r2 = stroke.radius * stroke.radius;
        for (t, c) in centroids.iter().enumerate() {
            if c.cmplt(lo).any() || c.cmpgt(hi).any() {
                continue;
            }
            if polyline_distance_squared(&points, *c) <= r2 {
                weights[t] = if painted[t] {
                    f64::max(weights[t], stroke.weight)
                } else {
                    stroke.weight
                };
                painted[t] = true;
            }
        }
    }
    weights
}

/// The squared distance from `p` to the polyline through `points` (a point when it
/// has one, infinite when it has none): how far a brush stroke reaches.
pub fn polyline_distance_squared(points: &[DVec2], p: DVec2) -> f64 {
    if points.len() == 1 {
        return points[0].distance_squared(p);
    }
    points
        .windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            let t = if d.length_squared() > 0.0 {
                ((p - w[0]).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (w[0] + d * t).distance_squared(p)
        })
        .fold(f64::INFINITY, f64::min)
}

fn ms(clock: Instant) -> f64 {
    clock.elapsed().as_secs_f64() * 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use weights_core::Metric;

    /// A `w × h` grid of unit squares, each cut into two triangles.
    fn grid(w: u32, h: u32) -> Domain {
        let positions = (0..=h)
            .flat_map(|y| (0..=w).map(move |x| DVec2::new(f64::from(x), f64::from(y))))
            .collect();
        let mut triangles = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = y * (w + 1) + x;
                triangles.push([v, v + 1, v + w + 2]);
                triangles.push([v, v + w + 2, v + w + 1]);
            }
        }
        Domain::new(positions, triangles, Metric::Euclidean).expect("a grid")
    }

    fn point(rest: DVec2, translation: DVec2, rotation: f64, scale: f64) -> Handle {
        Handle::Point {
            rest,
            transform: Similarity {
                translation,
                rotation,
                scale,
            },
        }
    }

    #[test]
    fn a_rigid_motion_of_every_handle_moves_every_vertex_by_it() {
        let domain = grid(12, 6);
        let (angle, centre, shift) = (0.7, DVec2::new(6.0, 3.0), DVec2::new(3.0, -2.0));
        let motion = |p: DVec2| centre + shift + glam::DMat2::from_angle(angle) * (p - centre);
        let rests = [
            DVec2::new(1.0, 1.0),
            DVec2::new(11.0, 5.0),
            DVec2::new(6.0, 0.0),
        ];
        let mut handles: Vec<Handle> = rests
            .iter()
            .map(|&r| point(r, motion(r) - r, angle, 1.0))
            .collect();
        let bar = [DVec2::new(2.0, 5.0), DVec2::new(5.0, 5.0)];
        handles.push(Handle::Bar {
            rest: bar,
            pose: bar.map(motion),
        });
        let arap = ArapRig::new(domain.clone(), &handles, &[]).expect("ARAP");
        for (p, r) in arap.positions().iter().zip(domain.positions()) {
            assert!((*p - motion(*r)).length() < 1e-9, "{r} went to {p}");
        }
    }

    #[test]
    fn a_plain_point_handle_pins_one_vertex_and_a_turned_one_its_ring() {
        let domain = grid(8, 8);
        let centre = DVec2::new(4.0, 4.0);
        let plain = ArapRig::new(
            domain.clone(),
            &[point(centre, DVec2::new(1.0, 0.0), 0.0, 1.0)],
            &[],
        )
        .expect("ARAP");
        assert_eq!(plain.pinned(), 1);
        // One handle: the whole shape translates with it.
        for (p, r) in plain.positions().iter().zip(domain.positions()) {
            assert!((*p - *r - DVec2::new(1.0, 0.0)).length() < 1e-9);
        }
        let mut turned = plain.clone();
        turned
            .set_handles(&[point(centre, DVec2::new(1.0, 0.0), 0.5, 1.2)])
            .expect("turned");
        assert_eq!(turned.pinned(), 7, "the vertex and its six neighbours");
        let v = domain
            .nearest_vertex(DVec2::new(5.0, 4.0))
            .expect("a vertex") as usize;
        let expected = Similarity {
            translation: DVec2::new(1.0, 0.0),
            rotation: 0.5,
            scale: 1.2,
        }
        .apply(centre, DVec2::new(5.0, 4.0));
        assert!((turned.positions()[v] - expected).length() < 1e-9);
    }

    #[test]
    fn no_handles_give_the_rest_shape_and_crowded_handles_stay_finite() {
        let domain = grid(6, 3);
        let arap = ArapRig::new(domain.clone(), &[], &[]).expect("ARAP");
        assert_eq!(arap.positions(), domain.positions());
        // Turned handles whose rings overlap, a collinear row, a bar along the border.
        let handles = [
            point(DVec2::new(2.0, 1.0), DVec2::new(0.0, 1.0), 1.0, 2.0),
            point(DVec2::new(3.0, 1.0), DVec2::new(0.0, -1.0), -1.0, 0.5),
            point(DVec2::new(4.0, 1.0), DVec2::ZERO, 0.0, 1.0),
            Handle::Bar {
                rest: [DVec2::new(0.0, 3.0), DVec2::new(6.0, 3.0)],
                pose: [DVec2::new(0.0, 4.0), DVec2::new(6.0, 2.0)],
            },
        ];
        let arap = ArapRig::new(domain, &handles, &[]).expect("ARAP");
        assert!(arap.positions().iter().all(|p| p.is_finite()));
        // A non-finite pose is refused and the last one stays.
        let mut same = arap.clone();
        let mut bad = handles.to_vec();
        bad[0] = point(DVec2::new(2.0, 1.0), DVec2::new(f64::NAN, 0.0), 0.0, 1.0);
        assert!(same.set_handles(&bad).is_err());
        assert_eq!(same.positions(), arap.positions());
        assert_eq!(Deformer::handles(&same), &handles);
    }

    #[test]
    fn rigidity_takes_the_largest_stroke_within_reach_of_each_centroid() {
        let domain = grid(10, 1);
        let stroke = |points: Vec<[f64; 2]>, radius, weight| RigidityStroke {
            stroke: points,
            radius,
            weight,
        };
        let weights = rigidity_weights(
            &domain,
            &[
                // A disc around x = 1.5: the centroids of the first squares' triangles.
                stroke(vec![[1.5, 0.5]], 0.6, 100.0),
                // A line over x ∈ [5, 7], overlapping a stronger disc at x = 7.
                stroke(vec![[5.0, 0.5], [7.0, 0.5]], 0.4, 10.0),
                stroke(vec![[7.5, 0.5]], 0.5, 1000.0),
            ],
        );
        let centroid = |t: usize| {
            let tri = domain.triangles()[t];
            tri.iter()
                .map(|&v| domain.positions()[v as usize])
                .sum::<DVec2>()
                / 3.0
        };
        for (t, &w) in weights.iter().enumerate() {
            let c = centroid(t);
            let expected = if (c - DVec2::new(7.5, 0.5)).length() <= 0.5 {
                1000.0
            } else if (5.0 - 0.4..=7.0 + 0.4).contains(&c.x) && (c.y - 0.5).abs() <= 0.4 {
                10.0
            } else if (c - DVec2::new(1.5, 0.5)).length() <= 0.6 {
                100.0
            } else {
                1.0
            };
            // The segment's distance is exact only away from its ends.
            if (c.x - 4.6).abs() > 0.05 && (c.x - 7.4).abs() > 0.05 {
                assert_eq!(w, expected, "triangle {t} at {c}");
            }
        }
        assert!(weights.contains(&1000.0) && weights.contains(&10.0));
        assert!(weights.contains(&100.0) && weights.contains(&1.0));
    }
}
