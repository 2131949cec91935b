//! Moving least squares image deformation (Schaefer, McPhail and Warren 2006; the
//! `mls` crate) behind the method seam.
//!
//! Every vertex of the picture's mesh goes where the map fitted at it takes it (rigid,
//! similarity or affine: the rig file's `mls.variant`), each handle weighted by
//! `1 / |p − v|^{2α}` (`mls.alpha`; a bar, that integrated along it). A point handle
//! acts by its position alone (rest → rest + translation: its rotation and scale do not
//! enter MLS); a bar by its ends. The weights are Euclidean: a handle pulls what is
//! near it in the plane, whatever the shape between (a leg moved drags the other leg
//! beside it; C² and ARAP follow the shape).
//!
//! What depends only on rest positions is worked out when the handles or the settings
//! change ([`mls::Mls::new`]); a pose costs a few multiply-adds per vertex and handle.

use std::any::Any;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DVec2;
use project::{MlsVariant, Project};
use serde::Serialize;
use weights_core::{Domain, Handle};

use crate::deformer::{
    Deformer, Follow, Method, Output, Sequence, WeightsListing, json, median, quantile,
};

/// Moving least squares on the picture's mesh (see the module docs).
#[derive(Clone)]
pub struct MlsRig {
    /// The picture's mesh at rest.
    rest: Arc<[DVec2]>,
    triangles: Arc<[[u32; 3]]>,
    /// The handles, in their current poses.
    handles: Vec<Handle>,
    options: mls::MlsOptions,
    /// What depends on the rest positions of the vertices and the handles.
    table: Arc<mls::Mls>,
    /// The vertices in the current pose.
    positions: Vec<DVec2>,
    /// The previous pose's buffer, reused for the next.
    spare: Vec<DVec2>,
    /// Milliseconds of the last precomputation and the last pose.
    setup_ms: f64,
    pose_ms: f64,
}

/// The `mls` crate's options for `project`'s `"mls"` settings.
pub fn options(project: &Project) -> mls::MlsOptions {
    let settings = project.mls.unwrap_or_default();
    mls::MlsOptions {
        alpha: settings.alpha.unwrap_or(1.0),
        variant: match settings.variant.unwrap_or_default() {
            MlsVariant::Rigid => mls::Variant::Rigid,
            MlsVariant::Similarity => mls::Variant::Similarity,
            MlsVariant::Affine => mls::Variant::Affine,
        },
    }
}

/// A handle's place at rest, as MLS sees it.
fn rest_control(handle: &Handle) -> mls::Control {
    match *handle {
        Handle::Point { rest, .. } => mls::Control::Point(rest),
        Handle::Bar { rest, .. } => mls::Control::Bar(rest),
    }
}

/// A handle's place in its pose, as MLS sees it: a point by its position alone.
fn posed_control(handle: &Handle) -> mls::Control {
    match *handle {
        Handle::Point { rest, transform } => mls::Control::Point(rest + transform.translation),
        Handle::Bar { pose, .. } => mls::Control::Bar(pose),
    }
}

impl MlsRig {
    /// `project`'s MLS (its handles and `"mls"` settings) on the picture's mesh
    /// `domain`.
    ///
    /// # Errors
    /// Handles MLS refuses (non-finite, a bar of no length).
    pub fn on_mesh(project: &Project, domain: &Domain) -> Result<Self> {
        let (handles, options) = (crate::handles(project), options(project));
        let rest: Arc<[DVec2]> = domain.positions().into();
        let clock = Instant::now();
        let table = precompute(&rest, &handles, &options)?;
        let mut mls = Self {
            rest,
            triangles: domain.triangles().into(),
            handles: handles.clone(),
            options,
            table: Arc::new(table),
            positions: Vec::new(),
            spare: Vec::new(),
            setup_ms: ms(clock),
            pose_ms: 0.0,
        };
        mls.set(&handles, options)?;
        Ok(mls)
    }

    /// Takes `handles` with `options`: precomputes again where a handle came, went or
    /// moved at rest, or the options changed; then poses. On error nothing changes.
    fn set(&mut self, handles: &[Handle], options: mls::MlsOptions) -> Result<()> {
        let same_rest = options == self.options
            && self.handles.len() == handles.len()
            && self
                .handles
                .iter()
                .map(rest_control)
                .eq(handles.iter().map(rest_control));
        if same_rest && self.handles == handles && self.positions.len() == self.rest.len() {
            // The same pose, posed already: the positions stand.
            return Ok(());
        }
        if !same_rest {
            let clock = Instant::now();
            let rest: Vec<mls::Control> = handles.iter().map(rest_control).collect();
            // What the table before worked out for the bars that stay is kept.
            let table = (self.table)
                .renewed(&self.rest, &rest, &options)
                .context("moving least squares cannot use these handles")?;
            self.table = Arc::new(table);
            self.options = options;
            self.setup_ms = ms(clock);
        }
        let clock = Instant::now();
        let posed: Vec<mls::Control> = handles.iter().map(posed_control).collect();
        // Deformed into the spare buffer, which becomes the positions only when all
        // went well (no allocation per pose).
        let mut positions = std::mem::take(&mut self.spare);
        positions.resize(self.rest.len(), DVec2::ZERO);
        self.table.deform(&posed, &mut positions)?;
        if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
            bail!("moving least squares sent vertex {v} to a non-finite position");
        }
        self.spare = std::mem::replace(&mut self.positions, positions);
        self.handles = handles.to_vec();
        self.pose_ms = ms(clock);
        Ok(())
    }

    /// The handles, in their current poses.
    pub fn handles(&self) -> &[Handle] {
        &self.handles
    }

    /// The options in use.
    pub fn options(&self) -> mls::MlsOptions {
        self.options
    }
}

impl Deformer for MlsRig {
    fn method(&self) -> Method {
        Method::Mls
    }

    fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        self.set(&crate::handles(project), options(project))?;
        Ok(Follow::Followed)
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.positions.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Positions(&self.positions)
    }

    fn weights(&self, _listing: WeightsListing) -> Result<serde_json::Value> {
        bail!(
            "moving least squares has no weights per handle to list (it fits a map at every \
             point): `c2warp weights` lists C² weights (\"method\": \"c2\") or LBC \
             coordinates (\"method\": \"lbc\")"
        )
    }

    /// The precomputation (as it was measured), then `poses` random poses.
    fn bench(&mut self, _project: &Project, poses: usize) -> Result<serde_json::Value> {
        let handles = self.handles.clone();
        let setup_ms = self.setup_ms;
        let scale = mean_edge(&self.rest, &self.triangles) * 10.0;
        let mut sequence = Sequence::new();
        let mut pose = Vec::new();
        for _ in 0..poses.max(1) {
            let posed = sequence.jiggle(&handles, scale);
            self.set(&posed, self.options)?;
            pose.push(self.pose_ms);
        }
        self.set(&handles, self.options)?;
        // A point handle inserted at a random vertex, and removed again.
        let mut insert = Vec::new();
        let n = self.rest.len() as u64;
        for _ in 0..poses.max(1) {
            let at = self.rest[(sequence.next_u64() % n) as usize];
            let mut more = handles.clone();
            more.push(Handle::point(at));
            self.set(&more, self.options)?;
            insert.push(self.setup_ms);
            self.set(&handles, self.options)?;
        }
        json(&MlsReport {
            method: "mls",
            variant: match self.options.variant {
                mls::Variant::Rigid => "rigid",
                mls::Variant::Similarity => "similarity",
                mls::Variant::Affine => "affine",
            },
            alpha: self.options.alpha,
            samples: self.rest.len(),
            triangles: self.triangles.len(),
            real_handles: handles.len(),
            precompute_ms: setup_ms,
            pose_ms_p90: quantile(pose.clone(), 0.9),
            pose_ms_median: median(pose.clone()),
            poses: pose.len(),
            insert_precompute_ms_median: median(insert),
        })
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// What MLS works out from the rest positions of `vertices` and `handles`.
fn precompute(
    vertices: &[DVec2],
    handles: &[Handle],
    options: &mls::MlsOptions,
) -> Result<mls::Mls> {
    let rest: Vec<mls::Control> = handles.iter().map(rest_control).collect();
    mls::Mls::new(vertices, &rest, options).context("moving least squares cannot use these handles")
}

/// The mean edge length of a mesh (each triangle's three edges), pixels.
pub(crate) fn mean_edge(positions: &[DVec2], triangles: &[[u32; 3]]) -> f64 {
    let (sum, count) = triangles.iter().fold((0.0, 0usize), |(sum, count), t| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        (
            sum + a.distance(b) + b.distance(c) + c.distance(a),
            count + 3,
        )
    });
    if count == 0 { 1.0 } else { sum / count as f64 }
}

fn ms(clock: Instant) -> f64 {
    clock.elapsed().as_secs_f64() * 1e3
}

/// MLS's steps, timed (`c2warp bench`).
#[derive(Serialize)]
struct MlsReport {
    method: &'static str,
    variant: &'static str,
    alpha: f64,
    samples: usize,
    triangles: usize,
    real_handles: usize,
    /// What depends on rest positions only (once per set of handles), ms.
    precompute_ms: f64,
    /// Median pose (every vertex moved), ms.
    pose_ms_median: f64,
    /// 90th percentile of the poses, ms.
    pose_ms_p90: f64,
    /// Poses timed.
    poses: usize,
    /// Median precomputation again for a point handle inserted at a random vertex
    /// (the bars' integrals kept), ms.
    insert_precompute_ms_median: f64,
}
