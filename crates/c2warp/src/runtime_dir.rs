//! A private, empty `XDG_RUNTIME_DIR` for GPU runs started without one.
//!
//! Mesa's Vulkan drivers come with an implicit layer, device-select, that orders the
//! GPUs and puts first the one a Wayland compositor draws with whenever the Vulkan
//! instance enables `VK_KHR_wayland_surface` (wgpu always enables it where it is
//! available). To find that compositor it calls `wl_display_connect`, and libwayland
//! prints `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` on
//! standard error when the variable is missing (under `env -i`, `sudo`, cron, a
//! service), twice per run, although nothing is wrong and the picture is drawn. With
//! the variable naming an empty directory of our own, the lookup finds no socket and
//! gives up silently; the layer's other rules (`MESA_VK_DEVICE_SELECT`, `DRI_PRIME`)
//! still apply.

use std::path::{Path, PathBuf};

/// The private directory; removed when dropped.
pub struct PrivateRuntimeDir {
    path: PathBuf,
}

impl Drop for PrivateRuntimeDir {
    fn drop(&mut self) {
        // Best effort: it is empty, and in the temporary directory anyway.
        let _ = std::fs::remove_dir(&self.path);
    }
}

/// When `XDG_RUNTIME_DIR` is unset or not an absolute path (which libwayland refuses
/// with that message), creates an empty directory readable only by this user and
/// points the variable at it for this process.
///
/// Must be called before any other thread starts (see [`set_runtime_dir`]).
pub fn ensure() -> Option<PrivateRuntimeDir> {
    let current = std::env::var_os("XDG_RUNTIME_DIR");
    if current.is_some_and(|dir| Path::new(&dir).is_absolute()) {
        return None;
    }
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let path = std::env::temp_dir().join(format!("c2warp-runtime-{}-{nanos}", std::process::id()));
    let mut builder = std::fs::DirBuilder::new();
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
    // Without it the run still works; it only prints the loader's line.
    builder.create(&path).ok()?;
    set_runtime_dir(&path);
    Some(PrivateRuntimeDir { path })
}

/// Sets `XDG_RUNTIME_DIR` for this process.
#[allow(unsafe_code)]
fn set_runtime_dir(path: &Path) {
    // SAFETY: `set_var` is unsound only while another thread may read or write the
    // environment. This runs in `main` right after the arguments are parsed, before
    // anything starts a thread (rayon's pool, wgpu and the progress counter all start
    // theirs later), so this is the only thread.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", path) };
}
