//! File dialogs: the desktop's own where it has one, the editor's built-in one
//! everywhere else (a bare X session has no portal and no zenity, and the user must
//! still be able to open, save and export). The desktop's sit behind a trait so tests
//! can answer them without a desktop.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

/// What a file dialog asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileAction {
    /// A picture to open.
    OpenImage,
    /// A project (rig file) to open.
    OpenProject,
    /// Where to save the project.
    SaveProject,
    /// Where to export the warped PNG.
    ExportPng,
    /// Where to export the warped layers (OpenRaster).
    ExportLayers,
    /// Where to export the animation (an animated PNG, WebP or GIF; for a PNG
    /// sequence, the folder is named after the file).
    ExportAnimation,
}

impl FileAction {
    /// The dialog's title.
    pub fn title(self) -> &'static str {
        match self {
            Self::OpenImage => "Open image",
            Self::OpenProject => "Open project",
            Self::SaveProject => "Save project",
            Self::ExportPng => "Export warped PNG",
            Self::ExportLayers => "Export warped layers",
            Self::ExportAnimation => "Export animation",
        }
    }

    /// Whether the dialog names a file to write.
    pub fn writes(self) -> bool {
        matches!(
            self,
            Self::SaveProject | Self::ExportPng | Self::ExportLayers | Self::ExportAnimation
        )
    }

    /// The file name extensions it offers.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::OpenImage => IMAGES,
            Self::OpenProject | Self::SaveProject => &["json"],
            Self::ExportPng => &["png"],
            Self::ExportLayers => &["ora"],
            Self::ExportAnimation => &["png", "webp", "gif"],
        }
    }
}

/// The file name extensions of the pictures the editor opens (layered PSD and
/// OpenRaster files among them).
pub const IMAGES: &[&str] = &[
    "png", "jpg", "jpeg", "webp", "tif", "tiff", "bmp", "gif", "psd", "ora",
];

/// A dialog's answer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Answer {
    /// The user chose this file.
    Chosen(PathBuf),
    /// The user chose several pictures to open (as the layers of one).
    Several(Vec<PathBuf>),
    /// The user cancelled.
    Cancelled,
    /// No dialog can be shown here: the editor shows its built-in one instead.
    Unavailable,
}

/// Asks the user for files.
pub trait Dialogs {
    /// Asks for a file for `action`; `suggested` is the file name offered when saving.
    fn ask(&mut self, action: FileAction, suggested: &str) -> Answer;
}

/// The desktop's own dialogs (through rfd: the XDG desktop portal, or zenity), where
/// the desktop has them.
pub struct NativeDialogs {
    available: bool,
}

impl Default for NativeDialogs {
    fn default() -> Self {
        Self::new()
    }
}

impl NativeDialogs {
    /// The desktop's dialogs, if [`desktop_has_dialogs`] finds any.
    pub fn new() -> Self {
        Self {
            available: desktop_has_dialogs(),
        }
    }
}

impl Dialogs for NativeDialogs {
    fn ask(&mut self, action: FileAction, suggested: &str) -> Answer {
        if !self.available {
            return Answer::Unavailable;
        }
        let mut dialog = rfd::FileDialog::new().set_title(action.title());
        dialog = match action {
            FileAction::OpenImage => dialog.add_filter("Images", &with_upper_case(IMAGES)),
            FileAction::OpenProject | FileAction::SaveProject => {
                dialog.add_filter("C2Warp project", &["json"])
            }
            FileAction::ExportPng => dialog.add_filter("PNG", &["png"]),
            FileAction::ExportLayers => dialog.add_filter("OpenRaster", &["ora"]),
            FileAction::ExportAnimation => dialog.add_filter("Animation", &["png", "webp", "gif"]),
        };
        let chosen = if action.writes() {
            dialog.set_file_name(suggested).save_file()
        } else if action == FileAction::OpenImage {
            // Several pictures open as the layers of one.
            match dialog.pick_files() {
                Some(several) if several.len() > 1 => return Answer::Several(several),
                Some(mut one) => one.pop(),
                None => None,
            }
        } else {
            dialog.pick_file()
        };
        chosen.map_or(Answer::Cancelled, Answer::Chosen)
    }
}

fn with_upper_case(extensions: &[&str]) -> Vec<String> {
    extensions
        .iter()
        .flat_map(|e| [e.to_string(), e.to_uppercase()])
        .collect()
}

/// Whether the desktop can show a file dialog: `C2WARP_FILE_DIALOG=builtin` or
/// `=native` decides; otherwise there must be zenity on the `PATH`, or a session bus
/// and an XDG desktop portal with a file chooser installed. (rfd cannot tell "no
/// dialog" from "cancelled", so the editor looks before it asks.)
pub fn desktop_has_dialogs() -> bool {
    match std::env::var("C2WARP_FILE_DIALOG").as_deref() {
        Ok("builtin") => return false,
        Ok("native") => return true,
        _ => {}
    }
    if cfg!(not(target_os = "linux")) {
        return true;
    }
    let on_path = |name: &str| {
        std::env::var_os("PATH")
            .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(name).is_file()))
    };
    if on_path("zenity") {
        return true;
    }
    let has_bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some()
        || std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).join("bus").exists());
    has_bus && portal_has_file_chooser()
}

/// Whether an XDG desktop portal backend offering a file chooser is installed.
fn portal_has_file_chooser() -> bool {
    let data_dirs = std::env::var("XDG_DATA_DIRS")
        .ok()
        .filter(|d| !d.is_empty())
        .unwrap_or_else(|| "/usr/local/share:/usr/share".to_owned());
    std::env::split_paths(&data_dirs).any(|dir| {
        let portals = dir.join("xdg-desktop-portal/portals");
        std::fs::read_dir(portals).is_ok_and(|entries| {
            entries.flatten().any(|entry| {
                entry.path().extension() == Some(OsStr::new("portal"))
                    && std::fs::read_to_string(entry.path())
                        .is_ok_and(|text| text.contains("org.freedesktop.impl.portal.FileChooser"))
            })
        })
    })
}

/// The editor's own file dialog (egui_file), shown inside the window.
pub(crate) struct BuiltinDialog {
    /// What the chosen file is for.
    pub action: FileAction,
    dialog: egui_file::FileDialog,
}

/// What the built-in dialog says this frame.
pub(crate) enum Shown {
    /// Still open.
    Open,
    /// Closed without a choice.
    Cancelled,
    /// A file was chosen.
    Chosen(PathBuf),
}

impl BuiltinDialog {
    /// Opens a dialog for `action` in `folder`, offering `suggested` as the file name
    /// when saving.
    pub fn open(action: FileAction, folder: &Path, suggested: &str) -> Self {
        let extensions = action.extensions();
        let matches = move |path: &Path| {
            path.extension()
                .and_then(OsStr::to_str)
                .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
        };
        let mut dialog = if action.writes() {
            egui_file::FileDialog::save_file()
                .default_filename(suggested)
                .save_button_text("Save".into())
        } else {
            egui_file::FileDialog::open_file()
        }
        .title(action.title())
        .initial_path(folder)
        .show_rename(false)
        .show_new_folder(action.writes())
        .default_size([640.0, 420.0])
        .show_files_filter(Box::new(matches));
        dialog.open();
        Self { action, dialog }
    }

    /// Shows the dialog; call every frame while it is open.
    pub fn show(&mut self, ctx: &egui::Context) -> Shown {
        self.dialog.show(ctx);
        match self.dialog.state() {
            egui_file::State::Open => Shown::Open,
            egui_file::State::Selected => match self.dialog.path() {
                Some(path) => Shown::Chosen(path.to_path_buf()),
                None => Shown::Cancelled,
            },
            egui_file::State::Cancelled | egui_file::State::Closed => Shown::Cancelled,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_action_offers_its_files() {
        assert!(FileAction::OpenImage.extensions().contains(&"webp"));
        assert!(FileAction::SaveProject.writes() && FileAction::ExportPng.writes());
        assert!(!FileAction::OpenProject.writes());
        assert_eq!(with_upper_case(&["png"]), ["png", "PNG"]);
    }
}
