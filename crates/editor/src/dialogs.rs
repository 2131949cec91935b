//! File dialogs behind a trait, so tests can answer them without a desktop.

use std::path::PathBuf;

/// Asks the user for files. Each method returns `None` when the user cancels (or no
/// dialog can be shown).
pub trait Dialogs {
    /// A picture to open.
    fn open_image(&mut self) -> Option<PathBuf>;
    /// A project (rig file) to open.
    fn open_project(&mut self) -> Option<PathBuf>;
    /// Where to save the project.
    fn save_project(&mut self, suggested: &str) -> Option<PathBuf>;
    /// Where to export the warped PNG.
    fn export_png(&mut self, suggested: &str) -> Option<PathBuf>;
}

/// The desktop's own dialogs (through rfd).
#[derive(Default)]
pub struct NativeDialogs;

const IMAGES: &[&str] = &["png", "jpg", "jpeg", "PNG", "JPG", "JPEG"];

impl Dialogs for NativeDialogs {
    fn open_image(&mut self) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Open image")
            .add_filter("Images", IMAGES)
            .pick_file()
    }

    fn open_project(&mut self) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Open project")
            .add_filter("C2Warp project", &["json"])
            .pick_file()
    }

    fn save_project(&mut self, suggested: &str) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Save project")
            .add_filter("C2Warp project", &["json"])
            .set_file_name(suggested)
            .save_file()
    }

    fn export_png(&mut self, suggested: &str) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Export warped PNG")
            .add_filter("PNG", &["png"])
            .set_file_name(suggested)
            .save_file()
    }
}
