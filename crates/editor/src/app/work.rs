//! Work that can take longer than a frame — opening, re-meshing, rebuilding, solving a
//! cage, exporting — started on the worker thread as a [`Job`], and its outcome
//! brought into the document and the history when it is in.

use super::files::file_name;
use super::*;

impl EditorApp {
    /// Opens a picture or (for `.json`) a project, asking first if there are unsaved
    /// changes.
    pub fn request_open(&mut self, path: PathBuf) {
        self.request_open_all(vec![path]);
    }

    /// Opens pictures (several: as the layers of one, bottom first) or one project,
    /// asking first if there are unsaved changes.
    pub fn request_open_all(&mut self, paths: Vec<PathBuf>) {
        if self.dirty {
            self.pending = Some(Pending::Open(paths));
        } else {
            self.open_all_in_background(paths);
        }
    }

    /// Opens a picture or (for `.json`) a project now, waiting for it. On failure the
    /// current document stays and the status line says why.
    pub fn open(&mut self, path: &Path) {
        let outcome = open_outcome(
            vec![path.to_path_buf()],
            &CancelFlag::default(),
            &SolveProgress::default(),
        );
        self.finish(outcome);
    }

    /// Opens a picture or project on a worker thread (an LBC project's cage is solved
    /// there too); the editor shows progress and takes no edits until it is in.
    pub fn open_in_background(&mut self, path: PathBuf) {
        self.open_all_in_background(vec![path]);
    }

    /// Opens pictures (several: as the layers of one, bottom first) or one project on
    /// a worker thread, as [`EditorApp::open_in_background`] opens one.
    pub fn open_all_in_background(&mut self, paths: Vec<PathBuf>) {
        let label = match paths.as_slice() {
            [one] => format!("Opening {}", file_name(one)),
            several => format!("Opening {} pictures", several.len()),
        };
        let (cancel, progress) = (CancelFlag::default(), SolveProgress::default());
        let (flag, steps) = (cancel.clone(), progress.clone());
        let work = move || open_outcome(paths, &flag, &steps);
        self.start_job(label, cancel, work);
        if let Some(job) = &mut self.job {
            job.progress = Some(progress);
        }
    }

    /// Solves the cage of `key` on the worker, showing its iterations and residuals;
    /// `then`: undo (`true`) or redo once it is in.
    pub(crate) fn start_cage_solve(&mut self, key: CageKey, then: Option<bool>) {
        if let Some(problem) = key.problem() {
            self.error(&anyhow::anyhow!(problem));
            return;
        }
        let (cancel, progress) = (CancelFlag::default(), SolveProgress::default());
        let (flag, steps) = (cancel.clone(), progress.clone());
        let label = format!("Solving the cage ({} vertices inside)", key.vertices);
        self.start_job(label, cancel, move || {
            let clock = Instant::now();
            let solution = crate::document::solve_cage(&key, &mut |step| {
                steps.set(*step);
                !flag.is_set()
            });
            Outcome::CageSolved {
                key,
                solution,
                then,
                ms: clock.elapsed().as_secs_f64() * 1e3,
            }
        });
        if let Some(job) = &mut self.job {
            job.progress = Some(progress);
        }
    }

    /// The first and latest iteration of a cage's solve under way.
    pub fn solve_progress(&self) -> Option<(lbc::Progress, lbc::Progress)> {
        self.job.as_ref()?.progress.as_ref()?.get()
    }

    /// Starts `work` on a worker thread unless a job is running (then says so). Any
    /// gesture in progress ends first: the document may change when the job is in.
    pub(super) fn start_job(
        &mut self,
        label: String,
        cancel: CancelFlag,
        work: impl FnOnce() -> Outcome + Send + 'static,
    ) {
        if let Some(job) = &self.job {
            let running = job.label.clone();
            self.error(&anyhow::anyhow!(
                "{label} waits: {running}… is still running (cancel it with Escape)"
            ));
            return;
        }
        self.end_gesture();
        self.job = Some(Job::spawn_cancellable(
            label,
            self.wake.clone(),
            cancel,
            work,
        ));
    }

    /// Re-meshes and re-weights the picture for `settings` on a worker thread.
    pub(super) fn rebuild_in_background(&mut self, settings: crate::document::Settings) {
        let Some(doc) = &self.doc else { return };
        let before = doc.snapshot();
        let mut project = doc.project().clone();
        settings.write_to(&mut project);
        let label = format!("Meshing at {} vertices", settings.density);
        let work = remesh(
            doc,
            project,
            Rebuild::Edit {
                before: Box::new(before),
            },
        );
        self.start_job(label, CancelFlag::default(), work);
    }

    /// Steps through the history to `target`, whose density differs from the
    /// document's, on a worker thread. The history moves when the new mesh is in.
    pub(super) fn restore_in_background(&mut self, back: bool, target: project::Project) {
        let Some(doc) = &self.doc else { return };
        let density = crate::document::Settings::of(&target).density;
        let label = format!(
            "{} a density change: meshing at {density} vertices",
            if back { "Undoing" } else { "Redoing" }
        );
        let work = remesh(doc, target, Rebuild::History { back });
        self.start_job(label, CancelFlag::default(), work);
    }

    /// Whether a job (opening, re-meshing, exporting) is running.
    pub fn is_busy(&self) -> bool {
        self.job.is_some()
    }

    /// What the running job does, and for how long it has run (seconds).
    pub fn busy_with(&self) -> Option<(&str, f64)> {
        self.job
            .as_ref()
            .map(|j| (j.label.as_str(), j.started.elapsed().as_secs_f64()))
    }

    /// Gives up on the running job, if any: the document stays as it was, and an
    /// export writes nothing (unless it was already writing).
    pub fn cancel_job(&mut self) {
        if let Some(job) = self.job.take() {
            let label = job.label.clone();
            job.cancel();
            self.info(format!("cancelled: {label}"));
        }
    }

    /// Takes in the running job's result if it is done.
    pub(crate) fn poll_job(&mut self) {
        if let Some(outcome) = self.job.as_ref().and_then(Job::poll) {
            self.job = None;
            self.finish(outcome);
        }
    }

    /// Waits for the running job, if any, and takes in its result.
    pub fn wait_for_job(&mut self) {
        if let Some(outcome) = self.job.take().and_then(Job::wait) {
            self.finish(outcome);
        }
    }

    pub(super) fn finish(&mut self, outcome: Outcome) {
        self.finish_outcome(outcome);
        self.sync_tool();
    }

    pub(super) fn finish_outcome(&mut self, outcome: Outcome) {
        match outcome {
            Outcome::Opened {
                paths,
                is_project,
                document: Ok(doc),
            } => {
                let samples = doc.mesh().len();
                let what = match (is_project, paths.len()) {
                    (true, _) => "project".to_owned(),
                    (false, 1) => "image".to_owned(),
                    (false, n) => format!("{n} pictures as layers:"),
                };
                self.end_gesture();
                let in_use = CageKey::in_use(doc.project());
                let unsolved = in_use.is_some() && doc.cage_solution().is_none();
                let problem = in_use.and_then(|k| k.problem());
                self.doc = Some(doc);
                self.history.clear();
                self.dirty = false;
                self.mls_warned = false;
                self.selected = None;
                self.selected_part = None;
                self.timeline = crate::timeline::Timeline::default();
                self.perform = crate::perform::PerformTool::default();
                self.show_current_time();
                self.cage.forget_document();
                // A project a cage moves opens with the cage tool.
                self.sync_tool();
                self.needs_fit = true;
                self.settings_draft = None;
                let notes = self
                    .doc
                    .as_ref()
                    .map(|d| d.picture_notes.join("; "))
                    .filter(|n| !n.is_empty())
                    .map_or_else(String::new, |n| format!("; {n}"));
                self.info(format!(
                    "opened {what} {} ({} mesh vertices){notes}",
                    named(&paths),
                    samples
                ));
                if unsolved {
                    let why = problem.unwrap_or_else(|| {
                        "the cage is not solved: press Solve (Enter) to warp".to_owned()
                    });
                    self.error(&anyhow::anyhow!(why));
                }
            }
            Outcome::Opened {
                paths,
                document: Err(e),
                ..
            } => self.error(&e.context(format!("cannot open {}", named(&paths)))),
            Outcome::Rebuilt {
                cause,
                document: Ok(doc),
            } => self.rebuilt(cause, doc),
            Outcome::Rebuilt {
                document: Err(e), ..
            } => {
                self.settings_draft = None;
                self.error(&e.context("cannot rebuild the weights"));
            }
            Outcome::Exported {
                path,
                result: Ok(()),
                ms,
            } => self.info(format!("exported {} in {ms:.0} ms", path.display())),
            Outcome::Exported { result: Err(e), .. } => self.error(&e),
            Outcome::CageSolved {
                key,
                solution: Ok(solution),
                then,
                ms,
            } => {
                let Some(doc) = &mut self.doc else { return };
                let report = solution.report.clone();
                let vertices = solution.domain.positions().len();
                if let Err(e) = doc.add_solution(key, solution) {
                    self.error(&e);
                    return;
                }
                self.info(format!(
                    "solved the cage in {:.1} s: {vertices} vertices inside, {} ADMM \
                     iterations{}; drag a vertex to warp",
                    ms / 1e3,
                    report.iterations,
                    if report.converged {
                        ""
                    } else {
                        " (stopped at the iteration cap, not converged)"
                    }
                ));
                if let Some(back) = then {
                    self.step_history(back);
                }
            }
            Outcome::CageSolved {
                solution: Err(e), ..
            } => self.error(&e.context("cannot solve the cage")),
        }
    }

    /// A rebuilt document comes in: it replaces the open one (which lends it its solved
    /// cages, file and versions), and the history moves as its cause says.
    fn rebuilt(&mut self, cause: Rebuild, mut doc: Document) {
        self.end_gesture();
        let was = self.controls();
        let mut history = None;
        let mut kept = Ok(());
        if let Some(old) = &self.doc {
            kept = doc.keep_solutions_of(old);
            doc.project_path.clone_from(&old.project_path);
            doc.weights_version = old.weights_version + 1;
            doc.pose_version = old.pose_version + 1;
            let current = old.snapshot();
            match cause {
                Rebuild::Edit { before } => {
                    let label = crate::history::describe_change(&before, doc.project());
                    self.history.push(*before, label);
                }
                Rebuild::History { back } => {
                    let step = if back {
                        self.history.undo(current)
                    } else {
                        self.history.redo(current)
                    };
                    history = step.map(|(_, what)| {
                        format!("{}: {what}; ", if back { "undone" } else { "redone" })
                    });
                }
            }
        }
        if let Err(e) = kept {
            self.error(&e.context("the solved cage does not fit the rebuilt picture"));
        }
        let samples = doc.mesh().len();
        let ms = doc.last_update_ms;
        let handles = doc.project().handles.len();
        let remeshed = self
            .doc
            .as_ref()
            .is_none_or(|old| old.settings().density != doc.settings().density);
        let short = remeshed
            .then(|| pipeline::density_shortfall(doc.mesh(), doc.settings().density))
            .flatten();
        self.doc = Some(doc);
        if self.selected.is_some_and(|s| s >= handles) {
            self.selected = None;
        }
        if let Some(doc) = &self.doc {
            self.cage
                .retain_valid(doc.cage().map_or(0, |c| c.rest.len()));
        }
        self.dirty = true;
        self.settings_draft = None;
        let what = if remeshed { "re-meshed" } else { "rebuilt" };
        self.info(format!(
            "{}{what}: {} vertices, weights in {ms:.0} ms{}",
            history.unwrap_or_default(),
            samples,
            short.unwrap_or_default()
        ));
        self.sync_tool_after_history(was);
        self.show_current_time();
    }
}

/// The re-mesh of `doc`'s picture for `project` (with its virtual handles, so a step
/// through the history gets exactly that state's weights), ready to run anywhere.
fn remesh(
    doc: &Document,
    project: project::Project,
    cause: Rebuild,
) -> impl FnOnce() -> Outcome + Send + 'static {
    let image = doc.image.clone();
    let deep = doc.deep.clone();
    let layers = doc.layers.clone();
    let notes = doc.picture_notes.clone();
    let image_path = doc.image_path.clone();
    let image_paths = doc.image_paths.clone();
    move || Outcome::Rebuilt {
        cause,
        // The same picture: its depth, its layers and the files it came from kept.
        document: Document::with_layers(image, layers, image_path, project).map(|mut d| {
            d.deep = deep;
            d.picture_notes = notes;
            d.image_paths = image_paths;
            d
        }),
    }
}

/// The files `paths` names, for a message: their paths, comma-separated.
fn named(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(", ")
}

/// Opens pictures (several: as the layers of one) or (for `.json`) a project; an LBC
/// project's cage is solved (a cage that cannot be is left unsolved, for the user to
/// fix).
fn open_outcome(paths: Vec<PathBuf>, cancel: &CancelFlag, progress: &SolveProgress) -> Outcome {
    let is_json = |p: &PathBuf| {
        p.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    };
    let is_project = paths.len() == 1 && is_json(&paths[0]);
    let document = if paths.len() > 1 && paths.iter().any(is_json) {
        Err(anyhow::anyhow!(
            "a project opens alone: open several pictures, or one project"
        ))
    } else if is_project {
        Document::open_project(&paths[0]).map(|mut doc| {
            let solvable = CageKey::in_use(doc.project()).is_some_and(|k| k.problem().is_none());
            if solvable {
                // Failing (cancelled) leaves the cage unsolved.
                let _ = doc.solve_cage(&mut |step| {
                    progress.set(*step);
                    !cancel.is_set()
                });
            }
            doc
        })
    } else {
        Document::open_pictures(&paths)
    };
    Outcome::Opened {
        paths,
        is_project,
        document,
    }
}
