//! The document's cage (LBC): the rig file's cage, its solved coordinates kept by
//! [`CageKey`] (so an undo back to an earlier cage finds them again), and the cage
//! method's deformer built from them.

use std::sync::Arc;

use anyhow::{Context, Result, bail};
use glam::DVec2;
use pipeline::cage::{CageCoordinates, CageDeformer, CageMesh};
use pipeline::{Controls, Follow, Method, PartsDeformer};
use project::{CageSpec, LbcSettings, Project, Tau};

use super::Document;

/// What a cage's coordinates are solved for: the rest cage, τ, the number of mesh
/// vertices inside it and the cuts it is split along (as `c2warp render` reads them
/// from the rig file).
#[derive(Clone, Debug, PartialEq)]
pub struct CageKey {
    /// The rest cage, image pixels.
    pub rest: Vec<[f64; 2]>,
    /// The locality weighting.
    pub tau: Tau,
    /// Target mesh vertices inside the cage.
    pub vertices: usize,
    /// The rig file's cuts (the cage's inside is split along them).
    pub cuts: Vec<project::Cut>,
}

impl CageKey {
    /// The key of `project`'s cage (`None` without a cage).
    pub fn of(project: &Project) -> Option<Self> {
        let cage = project.cage.as_ref()?;
        Some(Self {
            rest: cage.rest.clone(),
            tau: project.lbc.unwrap_or_default().tau,
            vertices: pipeline::cage::cage_vertices(project, None),
            cuts: project.cuts.clone(),
        })
    }

    /// The key of the cage that moves `project`'s picture: its cage, with LBC chosen
    /// (`None` under a handle method, or without a cage).
    pub fn in_use(project: &Project) -> Option<Self> {
        Self::of(project).filter(|_| project.method.controls() == Controls::Cage)
    }

    /// Why this cage cannot be solved (not a simple polygon), if it cannot.
    pub fn problem(&self) -> Option<String> {
        let points = self.rest.iter().map(|&p| DVec2::from(p)).collect();
        lbc::Cage::new(points).err().map(|e| {
            let hint = match e {
                lbc::LbcError::SelfIntersection { .. } => {
                    ": move a vertex so that no two edges cross"
                }
                lbc::LbcError::RepeatedVertex { .. } => ": move or remove one of them",
                _ => "",
            };
            format!("the cage cannot be solved: {e}{hint}")
        })
    }
}

/// Solves the local barycentric coordinates of `key`'s cage, telling `progress` each
/// ADMM iteration (it returns `false` to cancel). The same computation as `c2warp
/// render` does for a rig file with that cage, τ and density.
///
/// # Errors
/// A cage that is not a simple polygon, or a cancelled solve.
pub fn solve_cage(
    key: &CageKey,
    progress: &mut dyn FnMut(&lbc::Progress) -> bool,
) -> Result<Arc<CageCoordinates>> {
    let project = Project {
        method: Method::for_controls(Controls::Cage),
        cage: Some(CageSpec {
            rest: key.rest.clone(),
            pose: None,
        }),
        lbc: Some(LbcSettings {
            tau: key.tau,
            density: Some(key.vertices),
        }),
        cuts: key.cuts.clone(),
        ..Project::default()
    };
    let mesh = CageMesh::Triangulate {
        target_vertices: key.vertices,
    };
    Ok(Arc::new(pipeline::cage::cage_coordinates(
        &project, mesh, progress,
    )?))
}

/// Solved cages kept, so an undo or a redo across cage edits needs no new solve.
const SOLUTIONS_KEPT: usize = 4;

impl Document {
    /// The cage method's deformer: the rig file's cage posed by its solved coordinates
    /// (kept while the solution stays the same; none until the cage is solved).
    pub(super) fn sync_cage(&mut self) -> Result<()> {
        let Some(solution) = self.cage_solution().cloned() else {
            // Not solved yet: the picture at rest.
            let mesh = self.mesh();
            let still = pipeline::Still::new(
                self.project.method,
                mesh.positions().to_vec(),
                mesh.triangles().to_vec(),
            );
            self.method = Some((self.mesh_version, Box::new(still)));
            return Ok(());
        };
        if let Some(layers) = self.layers.clone().filter(|_| self.project.parts.is_some()) {
            // Drawn as parts: every part inside the cage follows it (the parts tied to
            // the same solve kept).
            if let Some((_, deformer)) = &mut self.method
                && (deformer.as_any().downcast_ref::<PartsDeformer>())
                    .and_then(|parts| parts.rig().cage())
                    .is_some_and(|cage| Arc::ptr_eq(cage.solution(), &solution))
                && deformer.follow(&self.project)? == Follow::Followed
            {
                return Ok(());
            }
            let cage = CageDeformer::new(solution, self.cage_pose())?;
            let parts = PartsDeformer::with_cage(&layers, &self.project, cage, self.parts())?;
            self.method = Some((self.mesh_version, Box::new(parts)));
            return Ok(());
        }
        if let Some((_, deformer)) = &mut self.method
            && deformer
                .as_any()
                .downcast_ref::<CageDeformer>()
                .is_some_and(|cage| Arc::ptr_eq(cage.solution(), &solution))
            && deformer.follow(&self.project)? == Follow::Followed
        {
            return Ok(());
        }
        let deformer = CageDeformer::new(solution, self.cage_pose())?;
        self.method = Some((self.mesh_version, Box::new(deformer)));
        Ok(())
    }

    /// The cage method's deformer, when the rig file's cage is solved and LBC chosen.
    pub fn cage_deformer(&self) -> Option<&CageDeformer> {
        if let Some(parts) = self.parts() {
            return parts.rig().cage();
        }
        let (_, deformer) = self.method.as_ref()?;
        deformer.as_any().downcast_ref::<CageDeformer>()
    }

    /// The cage, if the rig file has one.
    pub fn cage(&self) -> Option<&CageSpec> {
        self.project.cage.as_ref()
    }

    /// The cage at rest (empty without a cage).
    pub fn cage_rest(&self) -> Vec<DVec2> {
        self.cage()
            .map(|c| c.rest.iter().map(|&p| DVec2::from(p)).collect())
            .unwrap_or_default()
    }

    /// Where the cage's vertices are posed (at rest where the rig file gives no pose;
    /// empty without a cage).
    pub fn cage_pose(&self) -> Vec<DVec2> {
        self.cage()
            .map(|c| {
                c.pose
                    .as_ref()
                    .unwrap_or(&c.rest)
                    .iter()
                    .map(|&p| DVec2::from(p))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The solved coordinates of the rig file's cage, if they have been solved for
    /// this rest cage, τ and density.
    pub fn cage_solution(&self) -> Option<&Arc<CageCoordinates>> {
        let key = CageKey::of(&self.project)?;
        self.solution_for(&key)
    }

    /// The coordinates solved for `key`, if kept.
    pub fn solution_for(&self, key: &CageKey) -> Option<&Arc<CageCoordinates>> {
        self.solutions
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, s)| s)
    }

    /// Whether the picture is warped by a solved cage: LBC chosen and its cage solved.
    pub fn cage_warps(&self) -> bool {
        self.cage_deformer().is_some()
    }

    /// Keeps coordinates solved for `key` (the oldest kept are forgotten). If `key` is
    /// the rig file's cage, the picture is now warped by it.
    ///
    /// # Errors
    /// Coordinates that do not fit `key` (another number of cage vertices).
    pub fn add_solution(&mut self, key: CageKey, solution: Arc<CageCoordinates>) -> Result<()> {
        if solution.weights.cage_vertices() != key.rest.len() {
            bail!(
                "coordinates for {} cage vertices solved for a cage of {}",
                solution.weights.cage_vertices(),
                key.rest.len()
            );
        }
        self.solutions.retain(|(k, _)| *k != key);
        if self.solutions.len() >= SOLUTIONS_KEPT {
            self.solutions.remove(0);
        }
        let current = CageKey::of(&self.project).as_ref() == Some(&key);
        self.solutions.push((key, solution));
        if current {
            self.weights_version += 1;
            self.pose_version += 1;
            self.sync_method()?;
        }
        Ok(())
    }

    /// Takes over the solved cages of `other` (the same picture, rebuilt): solutions
    /// depend only on the cage, not on the picture's mesh.
    ///
    /// # Errors
    /// A kept solution that does not fit the rig file's cage pose.
    pub(crate) fn keep_solutions_of(&mut self, other: &Document) -> Result<()> {
        self.solutions.clone_from(&other.solutions);
        self.sync_method()
    }

    /// Solves the rig file's cage here and now (seconds; the editor does it on its
    /// worker), unless it is solved already.
    ///
    /// # Errors
    /// No cage, a cage that is not a simple polygon, or a cancelled solve.
    pub fn solve_cage(&mut self, progress: &mut dyn FnMut(&lbc::Progress) -> bool) -> Result<()> {
        let Some(key) = CageKey::of(&self.project) else {
            bail!("there is no cage to solve");
        };
        if self.solution_for(&key).is_some() {
            return Ok(());
        }
        if let Some(problem) = key.problem() {
            bail!(problem);
        }
        let solution = solve_cage(&key, progress)?;
        self.add_solution(key, solution)
    }

    /// Every vertex of the solved cage's mesh where the cage's pose takes it; `None`
    /// unless LBC is chosen and its cage solved.
    pub fn cage_deformed(&self) -> Option<&[DVec2]> {
        self.cage_deformer().map(CageDeformer::positions)
    }

    /// Cage vertex `i`'s coordinate function at every vertex of the solved cage's mesh
    /// (its compact rows: zero where the weight fell below `10⁻³/n`); `None` unless the
    /// cage is solved and has that vertex.
    pub fn cage_influence(&self, i: usize) -> Option<Vec<f32>> {
        let weights = &self.cage_solution()?.weights;
        if i >= weights.cage_vertices() {
            return None;
        }
        Some(
            (0..weights.vertices())
                .map(|v| {
                    weights
                        .row(v)
                        .iter()
                        .find(|&&(k, _)| k as usize == i)
                        .map_or(0.0, |&(_, w)| w as f32)
                })
                .collect(),
        )
    }

    /// The cage's part of [`Document::sanity_check`]: kept solutions fit their keys,
    /// the current one's rows are coordinates, and the pose deforms its mesh to finite
    /// points.
    pub(super) fn cage_sanity_check(&self) -> Result<()> {
        let method = self.project.method;
        if let Some(why) = self.rigging().refusal(method, &self.project) {
            bail!("{} chosen though {why}", method.label());
        }
        if self.solutions.len() > SOLUTIONS_KEPT {
            bail!("{} solved cages kept", self.solutions.len());
        }
        for (i, (key, solution)) in self.solutions.iter().enumerate() {
            if self.solutions[..i].iter().any(|(k, _)| k == key) {
                bail!("a cage is kept solved twice");
            }
            let (n, weights) = (key.rest.len(), &solution.weights);
            if weights.cage_vertices() != n || solution.domain.cage().len() != n {
                bail!("coordinates of another cage kept for a cage of {n} vertices");
            }
            if weights.vertices() != solution.domain.positions().len() {
                bail!(
                    "{} rows for a cage mesh of {} vertices",
                    weights.vertices(),
                    solution.domain.positions().len()
                );
            }
        }
        if let Some(solution) = self.cage_solution() {
            let weights = &solution.weights;
            let rows = weights.vertices();
            let stride = (rows / 2000).max(1);
            for v in (0..rows).step_by(stride) {
                let row = weights.row(v);
                let mut sum = 0.0;
                for &(k, w) in row {
                    if k as usize >= weights.cage_vertices() || !w.is_finite() || w < 0.0 {
                        bail!("cage mesh vertex {v} has weight {w} on cage vertex {k}");
                    }
                    sum += w;
                }
                if (sum - 1.0).abs() > 1e-9 {
                    bail!("the coordinates of cage mesh vertex {v} sum to {sum}");
                }
            }
            let deformed = weights
                .deform(&self.cage_pose())
                .context("the cage's pose")?;
            if let Some(v) = deformed.iter().position(|p| !p.is_finite()) {
                bail!("the cage sends its mesh vertex {v} to a non-finite point");
            }
        }
        Ok(())
    }
}
