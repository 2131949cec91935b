//! Files: the open, save and export dialogs (the desktop's, or the built-in one), and
//! saving and exporting to a path.

use std::sync::Arc;

use pipeline::cage::CageCoordinates;

use super::*;

impl EditorApp {
    /// Asks for a file for `action` — with the desktop's dialog where there is one,
    /// else with the built-in one — and acts on it when chosen.
    pub fn ask_file(&mut self, action: FileAction) {
        if self.file_dialog.is_some() {
            return;
        }
        let suggested = match action {
            FileAction::SaveProject => self.suggested_name("json"),
            FileAction::ExportPng => self.suggested_name("warped.png"),
            FileAction::ExportLayers => self.suggested_name("warped.ora"),
            FileAction::ExportAnimation => self.suggested_animation_name(),
            FileAction::OpenImage | FileAction::OpenProject => String::new(),
        };
        if !self.builtin_dialogs {
            match self.dialogs.ask(action, &suggested) {
                Answer::Chosen(path) => return self.file_chosen(action, path),
                Answer::Several(paths) => return self.request_open_all(paths),
                Answer::Cancelled => return,
                Answer::Unavailable => {
                    self.builtin_dialogs = true;
                    self.info("the desktop offers no file dialog here: using the built-in one");
                }
            }
        }
        let folder = self.working_folder();
        self.file_dialog = Some(BuiltinDialog::open(action, &folder, &suggested));
    }

    /// Whether the built-in file dialog is open.
    pub fn file_dialog_open(&self) -> bool {
        self.file_dialog.is_some()
    }

    /// Shows the built-in file dialog, if open, and acts on its answer.
    pub(crate) fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.file_dialog else {
            return;
        };
        let action = dialog.action;
        match dialog.show(ctx) {
            Shown::Open => {}
            Shown::Cancelled => self.file_dialog = None,
            Shown::Chosen(path) => {
                self.file_dialog = None;
                if action.writes() && path.exists() {
                    // The desktop's dialogs ask before replacing a file; so does this one.
                    self.pending = Some(Pending::Replace(action, path));
                } else {
                    self.file_chosen(action, path);
                }
            }
        }
    }

    /// Acts on a file the user chose for `action`.
    pub(crate) fn file_chosen(&mut self, action: FileAction, path: PathBuf) {
        match action {
            FileAction::OpenImage | FileAction::OpenProject => self.request_open(path),
            FileAction::SaveProject => self.save_to(&path),
            FileAction::ExportPng => self.export_in_background(path),
            FileAction::ExportLayers => self.export_layers_in_background(path),
            FileAction::ExportAnimation => self.export_animation_to(path),
        }
    }

    /// The folder dialogs start in: the project's or the picture's, else the current one.
    pub(super) fn working_folder(&self) -> PathBuf {
        let from_doc = self.doc.as_ref().and_then(|d| {
            d.project_path
                .as_deref()
                .or(d.image_path.as_deref())
                .and_then(Path::parent)
                .filter(|p| !p.as_os_str().is_empty())
                .map(Path::to_path_buf)
        });
        from_doc
            .or_else(|| self.default_folder.clone())
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_else(|| PathBuf::from("."))
    }

    /// Saves the project where it was last saved, or asks where.
    pub fn save(&mut self) {
        match self.doc.as_ref().and_then(|d| d.project_path.clone()) {
            Some(path) => self.save_to(&path),
            None => self.ask_file(FileAction::SaveProject),
        }
    }

    /// Asks where to save the project, then saves it.
    pub fn save_as(&mut self) {
        self.ask_file(FileAction::SaveProject);
    }

    /// Writes the project to `path` atomically (a failure leaves any old file intact).
    pub fn save_to(&mut self, path: &Path) {
        let Some(doc) = &mut self.doc else { return };
        // Saving over the project itself is what Save does; over the picture, never.
        let picture: Vec<&Path> = doc.pictures().collect();
        if let Err(e) = render::refuse_input_as_output(path, &picture) {
            return self.error(&anyhow::Error::from(e));
        }
        let project = doc.project_for_saving(Some(path));
        match render::write_atomic(path, project.to_json().as_bytes()) {
            Ok(()) => {
                doc.project_path = Some(path.to_path_buf());
                self.dirty = false;
                self.info(format!("saved {}", path.display()));
            }
            Err(e) => self.error(&anyhow::Error::from(e)),
        }
    }

    /// Asks where to export, then writes the warped PNG.
    pub fn export(&mut self) {
        self.ask_file(FileAction::ExportPng);
    }

    /// Writes the warped picture at full resolution to `path` atomically, now: the
    /// same pixels as `c2warp render` of the saved project.
    pub fn export_to(&mut self, path: &Path) {
        self.export_now(path, Export::Picture);
    }

    /// As [`EditorApp::export_to`], on a worker thread (the editor shows progress).
    pub fn export_in_background(&mut self, path: PathBuf) {
        self.export_on_worker(path, Export::Picture);
    }

    /// Asks where to export the layers, then writes them.
    pub fn export_layers(&mut self) {
        self.ask_file(FileAction::ExportLayers);
    }

    /// Writes each layer of the picture warped on a layer of its own to `path` (an
    /// OpenRaster file), atomically, now: what `c2warp render --layers` writes for the
    /// saved project.
    pub fn export_layers_to(&mut self, path: &Path) {
        self.export_now(path, Export::Layers);
    }

    /// As [`EditorApp::export_layers_to`], on a worker thread.
    pub fn export_layers_in_background(&mut self, path: PathBuf) {
        self.export_on_worker(path, Export::Layers);
    }

    fn export_now(&mut self, path: &Path, what: Export) {
        if let Some(work) = self.export_work(path.to_path_buf(), CancelFlag::default(), what) {
            self.finish(work());
        }
    }

    fn export_on_worker(&mut self, path: PathBuf, what: Export) {
        let cancel = CancelFlag::default();
        if let Some(work) = self.export_work(path.clone(), cancel.clone(), what) {
            self.start_job(format!("Exporting {}", file_name(&path)), cancel, work);
        }
    }

    /// The export of the current document to `path` as `what`, ready to run anywhere;
    /// it writes nothing once `cancel` is set.
    pub(super) fn export_work(
        &mut self,
        path: PathBuf,
        cancel: CancelFlag,
        what: Export,
    ) -> Option<impl FnOnce() -> Outcome + Send + 'static> {
        if let Err(e) = self.refuse_sources(&path) {
            self.error(&e);
            return None;
        }
        let doc = self.doc.as_ref()?;
        let project = doc.project_for_saving(None);
        let image = doc.image.clone();
        let deep = doc.deep.clone();
        let layers = match what {
            Export::Picture => None,
            Export::Layers => Some(doc.layers.clone().unwrap_or_else(|| {
                let picture = match &doc.deep {
                    Some(deep) => deep.as_ref().clone(),
                    None => render::Picture::Rgba8(doc.image.as_ref().clone()),
                };
                Arc::new(pipeline::Artwork::from_picture("lizard", picture))
            })),
        };
        let cage = ExportSetup::of(doc, &project);
        // Drawn as parts: the export is `c2warp render` of the saved project, parts
        // and all (under a cage too, which the view still draws as one picture).
        let parts = doc.layers.clone().filter(|_| doc.project().parts.is_some());
        Some(move || {
            let clock = Instant::now();
            let result = (|| -> Result<()> {
                if let Some(artwork) = parts {
                    let parts = pipeline::warp_parts(&artwork, &project, None, &())?;
                    anyhow::ensure!(!cancel.is_set(), "cancelled");
                    return match what {
                        Export::Layers => Ok(pipeline::write_ora(&path, &parts.warped)?),
                        Export::Picture => Ok(render::save_png_atomic(&path, &parts.composite)?),
                    };
                }
                let warper = cage.warper(&image, &project, &cancel)?;
                if let Some(layers) = layers {
                    let warped = pipeline::warp_layers(&layers, &warper)?;
                    anyhow::ensure!(!cancel.is_set(), "cancelled");
                    pipeline::write_ora(&path, &warped)?;
                } else {
                    // A 16-bit picture exports with 16 bits, as `c2warp render` does.
                    let warped = match &deep {
                        Some(deep) => pipeline::warp_picture(deep, &warper)?,
                        None => render::Picture::Rgba8(pipeline::warp(&image, &warper)?),
                    };
                    anyhow::ensure!(!cancel.is_set(), "cancelled");
                    render::save_png_atomic(&path, &warped)?;
                }
                Ok(())
            })()
            .with_context(|| format!("cannot export {}", path.display()));
            Outcome::Exported {
                path,
                result,
                ms: clock.elapsed().as_secs_f64() * 1e3,
            }
        })
    }

    /// Refuses an export to `path` that would replace the document's picture or its
    /// project file (through links and `..` too).
    pub(super) fn refuse_sources(&self, path: &Path) -> Result<()> {
        let Some(doc) = &self.doc else { return Ok(()) };
        let sources: Vec<&Path> = doc.pictures().chain(doc.project_path.as_deref()).collect();
        render::refuse_input_as_output(path, &sources)?;
        Ok(())
    }

    pub(super) fn suggested_name(&self, extension: &str) -> String {
        let stem = self
            .doc
            .as_ref()
            .and_then(|d| d.image_path.as_ref())
            .and_then(|p| p.file_stem())
            .map_or_else(|| "lizard".to_owned(), |s| s.to_string_lossy().into_owned());
        if extension.contains('.') {
            format!("{stem}-{extension}")
        } else {
            format!("{stem}.{extension}")
        }
    }
}

/// What an export writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Export {
    /// The warped picture, as a PNG.
    Picture,
    /// Each layer warped on its own, as OpenRaster.
    Layers,
}

/// A path's file name, for messages.
pub(super) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// How an export sets the method up: on the picture, as `c2warp render` does, or with
/// the cage's coordinates the editor has solved already (else solved on the worker).
pub(super) struct ExportSetup(Option<(Option<Arc<CageCoordinates>>, CageKey, Vec<DVec2>)>);

impl ExportSetup {
    /// What exporting `project` (the document's, as saved) needs of `doc`.
    pub(super) fn of(doc: &Document, project: &project::Project) -> Self {
        Self(
            CageKey::in_use(project)
                .map(|key| (doc.solution_for(&key).cloned(), key, doc.cage_pose())),
        )
    }

    /// The method set up for `project` on `image`, posed as `project` is.
    pub(super) fn warper(
        self,
        image: &image::RgbaImage,
        project: &project::Project,
        cancel: &CancelFlag,
    ) -> Result<pipeline::Warper> {
        Ok(match self.0 {
            Some((solution, key, pose)) => {
                let solution = match solution {
                    Some(solution) => solution,
                    None => crate::document::solve_cage(&key, &mut |_| !cancel.is_set())?,
                };
                let deformer = pipeline::cage::CageDeformer::new(solution, pose)?;
                pipeline::Warper::in_mesh_order(Box::new(deformer), project)
            }
            None => pipeline::prepare_warper(image, project, None, &())?,
        })
    }
}
