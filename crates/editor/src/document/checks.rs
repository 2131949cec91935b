//! The document's invariants, and the check that its saved rig file gives back what
//! it shows (the editor's tests and the monkey run both).

use std::sync::Arc;

use anyhow::{Context, Result, bail};
use pipeline::{Deformer, Follow};
use project::Project;

use super::Document;

impl Document {
    /// Checks the document's invariants: the rig file is valid for the picture, the
    /// rig has exactly its handles, nodes sit on samples, weights are non-negative and
    /// sum to one wherever a node reaches, and the pose deforms every sample to a
    /// finite point. Used by tests after every step of a session.
    ///
    /// # Errors
    /// The first broken invariant, in words.
    pub fn sanity_check(&self) -> Result<()> {
        let (width, height) = self.image.dimensions();
        self.project
            .validate(Some((width, height)))
            .context("the rig file")?;
        if !self.project.virtual_handles.is_empty() {
            bail!("virtual handles belong to the rig while editing, not to the rig file");
        }
        if self.project.method.uses_virtual_handles() != self.rig().is_some() {
            bail!(
                "{} with{} a C² rig",
                self.project.method.label(),
                if self.rig().is_some() { "" } else { "out" }
            );
        }
        let Some(rig) = self.rig() else {
            // The mesh alone: what the method set up on it is checked below.
            self.method_sanity_check()?;
            return self.cage_sanity_check();
        };
        let expected = pipeline::handles(&self.project);
        if rig.handles() != expected.as_slice() {
            bail!(
                "the rig's {} handles are not the rig file's {}",
                rig.handles().len(),
                expected.len()
            );
        }
        let samples = rig.domain().len();
        let nodes = rig.nodes();
        if let Some(node) = nodes.iter().find(|n| n.vertex as usize >= samples) {
            bail!("a node sits on sample {} of {samples}", node.vertex);
        }
        // Every sample on small pictures; a spread of them on large ones.
        let stride = (samples / 4000).max(1);
        for v in (0..samples).step_by(stride) {
            let mut sum = 0.0;
            let mut any = false;
            for (k, w) in rig.weights(v) {
                if k >= nodes.len() || !w.is_finite() || w < 0.0 {
                    bail!("sample {v} has weight {w} on node {k} of {}", nodes.len());
                }
                sum += w;
                any = true;
            }
            if any && (sum - 1.0).abs() > 1e-9 {
                bail!("the weights of sample {v} sum to {sum}");
            }
        }
        if let Some(v) = rig.deform().iter().position(|p| !p.is_finite()) {
            bail!("sample {v} deforms to a non-finite point");
        }
        self.method_sanity_check()?;
        if self.weights_version == 0 || self.pose_version == 0 {
            bail!("versions start at 1");
        }
        self.cage_sanity_check()
    }

    /// The method's deformer is in step with the rig file: set up on this mesh for the
    /// method chosen, and following the rig file again changes nothing.
    fn method_sanity_check(&self) -> Result<()> {
        let method = self.project.method;
        let Some((mesh, deformer)) = &self.method else {
            if !self.rigging().may_have_no_state(self) {
                bail!("method {} has no deformer", method.name());
            }
            return Ok(());
        };
        if deformer.method() != method {
            bail!(
                "method {} with a deformer of {}",
                method.name(),
                deformer.method().name()
            );
        }
        self.rigging().check(self, *mesh, deformer.as_ref())?;
        let deformed = deformer.deformed();
        if let Some(v) = deformed.iter().position(|p| !p.is_finite()) {
            bail!("{} sends sample {v} to a non-finite point", method.label());
        }
        // Following again changes nothing — but for a frame of a live drag or of
        // playback, which an iterative method (ARAP's) solved on from the frame before
        // and stopped early: following it again iterates on. What it shows is checked
        // once [`Document::settle`] has solved it in full.
        let mut again = deformer.clone_box();
        let followed = again.follow(&self.project)?;
        if followed != Follow::Followed || (!self.live && again.deformed() != deformed) {
            bail!(
                "the {} deformer is out of step with the rig file",
                method.label()
            );
        }
        Ok(())
    }

    /// The parts' part of [`Document::method_sanity_check`]: set up for this picture,
    /// bound as the rig file binds them, and every overlap's order kept on a triangle.
    pub(super) fn parts_sanity_check(&self, mesh: u64) -> Result<()> {
        let parts = self.parts().context("drawn as parts without the parts")?;
        if mesh != self.mesh_version || self.layers.is_none() {
            bail!("the parts were set up for another picture");
        }
        if parts.rest().len() != parts.composer().uv().len() {
            bail!("the parts' mesh and texture disagree");
        }
        let layers = self.layers.as_deref().context("parts without layers")?;
        if parts.rig().bindings() != pipeline::parts::bindings(layers, &self.project)? {
            bail!("the parts are bound otherwise than the rig file binds them");
        }
        // Each overlap's order is kept at a triangle's rest centroid on the
        // part it names (looked up by the bits of its coordinates, -0 as 0).
        let key = |part: Option<usize>, at: [f64; 2]| (part, at.map(|c| (c + 0.0).to_bits()));
        let places: Vec<_> = (self.project.overlaps.iter())
            .flat_map(|o| [o.front, o.back])
            .collect();
        let mut missing: std::collections::HashSet<_> =
            places.iter().map(|p| key(p.part, p.at)).collect();
        let (rest, triangles) = (parts.rest(), parts.triangles());
        for (t, &k) in triangles.iter().zip(parts.part_of()) {
            if missing.is_empty() {
                break;
            }
            let centroid = t.iter().map(|&v| rest[v as usize]).sum::<glam::DVec2>() / 3.0;
            missing.remove(&key(Some(k as usize), centroid.to_array()));
        }
        if let Some(place) = places.iter().find(|p| missing.contains(&key(p.part, p.at))) {
            bail!("an overlap's order is kept at {place:?}, on no triangle of that part");
        }
        Ok(())
    }

    /// The cage's part of [`Document::method_sanity_check`]: `deformer` is the solved
    /// cage's, or the picture at rest until it is solved.
    pub(super) fn cage_deformer_check(&self, deformer: &dyn Deformer) -> Result<()> {
        let in_step = match (self.cage_deformer(), self.cage_solution()) {
            (Some(cage), Some(solved)) => Arc::ptr_eq(cage.solution(), solved),
            (None, None) => deformer.as_any().is::<pipeline::Still>(),
            _ => false,
        };
        if !in_step {
            bail!("the cage deformer is not the rig file's solved cage");
        }
        Ok(())
    }

    /// Checks that the rig file this document saves gives back what the document
    /// shows: reopened (through the JSON text, as a file would be), it builds the same
    /// mesh, handles, virtual handles and weights bit for bit, and the method puts every
    /// vertex in the same place. This is what an export, a reopened project and `c2warp
    /// render` of the saved file draw, so they are the picture on screen. Used by tests
    /// (the monkey runs it at random points of its walks).
    ///
    /// # Errors
    /// The first difference, in words.
    pub fn check_reopens(&self) -> Result<()> {
        let text = self.project_for_saving(None).to_json();
        let saved = Project::from_json(&text).context("the saved rig file does not load")?;
        let mut fresh = Document::with_layers(
            self.image.clone(),
            self.layers.clone(),
            self.image_path.clone(),
            saved,
        )
        .context("the saved rig file does not build")?;
        fresh.image_paths.clone_from(&self.image_paths);
        // Solved cages are not saved (`c2warp render` solves again, to the same
        // coordinates): the reopened document finds this one's for its cage, if the
        // saved cage, τ and density are the same.
        fresh.keep_solutions_of(self)?;
        let (a, b) = (self.mesh(), fresh.mesh());
        if a.positions() != b.positions() || a.triangles() != b.triangles() {
            bail!(
                "reopened, the picture meshes to {} vertices and {} triangles, not {} and {}",
                b.len(),
                b.triangles().len(),
                a.len(),
                a.triangles().len()
            );
        }
        match (self.rig(), fresh.rig()) {
            (Some(rig), Some(again)) => {
                if rig.handles() != again.handles() {
                    bail!("reopened, the rig has other handles");
                }
                if rig.virtual_vertices() != again.virtual_vertices() {
                    bail!(
                        "reopened, the rig has {} virtual handles, not {}",
                        again.virtual_vertices().len(),
                        rig.virtual_vertices().len()
                    );
                }
                rig.same_weights_as(again)
                    .map_err(|e| anyhow::anyhow!("reopened, the weights differ: {e}"))?;
            }
            (None, None) => {
                // The mesh alone: the virtual handles kept for C² are saved as kept.
                if self.snapshot().virtual_handles != fresh.snapshot().virtual_handles {
                    bail!("reopened, the virtual handles kept for C² differ");
                }
            }
            _ => bail!("reopened, one has a C² rig and the other not"),
        }
        // (A frame of a live drag or of playback is solved on from the frame before
        // and stopped early; the pose it shows reopens as `settle` solves it.)
        if !self.live && self.deformer().deformed() != fresh.deformer().deformed() {
            bail!(
                "reopened, {} puts the vertices elsewhere",
                self.project.method.label()
            );
        }
        // (Mid-drag on a large mesh the order waits for the drag's end.)
        if !self.depth_deferred && self.draw_order() != fresh.draw_order() {
            let (this, reopened) = (self.overlap_regions(), fresh.overlap_regions());
            let turned = (this.iter())
                .filter(|r| (reopened.iter()).any(|q| q.front == r.back && q.back == r.front))
                .count();
            bail!(
                "reopened, the triangles are drawn in another order ({} overlap regions, {} \
                 reopened; {turned} turned over)",
                this.len(),
                reopened.len()
            );
        }
        Ok(())
    }
}
