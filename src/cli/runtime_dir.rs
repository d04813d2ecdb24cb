//! A private XDG runtime folder for the graphics stack, when the session has none.
//!
//! Mesa's Vulkan device-select layer (an implicit layer that every Mesa Vulkan driver package
//! installs, so the Vulkan loader loads it into every instance) asks the Wayland compositor
//! which GPU drives the display whenever the instance enables `VK_KHR_wayland_surface`, and wgpu
//! enables every surface extension the loader offers, a headless compute instance too. Without
//! `XDG_RUNTIME_DIR` (ssh, cron, CI, containers, `su`) libwayland-client then prints "error:
//! XDG_RUNTIME_DIR is invalid or not set in the environment." for each probe (twice a run),
//! although no compositor could be reached anyway and nothing is wrong.
//!
//! The XDG Base Directory specification asks an application without `XDG_RUNTIME_DIR` to fall
//! back to a replacement folder of the same kind: the user's own, mode 0700. [`provide`] gives
//! the graphics stack one, `$TMPDIR/specmap-runtime-UID`, before any thread starts: the probe
//! then finds no compositor there, quietly, and the layer goes on choosing the GPU exactly as
//! before (X11, then the boot GPU). A session's own `XDG_RUNTIME_DIR` is never replaced, the
//! layer and its settings (`MESA_VK_DEVICE_SELECT`, `DRI_PRIME`) stay in force, and every other
//! message of the graphics stack still reaches the user.

use std::path::{Path, PathBuf};

/// Points `XDG_RUNTIME_DIR` at a private folder when it is unset or not an absolute path (what
/// libwayland calls invalid); returns that folder, or None when the session's own is kept or no
/// private folder could be made safely (then nothing changes). Call it before spawning threads.
pub(crate) fn provide() -> Option<PathBuf> {
    let usable = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_absolute());
    if usable {
        return None;
    }
    let dir = private_dir()?;
    std::env::set_var("XDG_RUNTIME_DIR", &dir);
    Some(dir)
}

/// `$TMPDIR/specmap-runtime-UID`, created mode 0700 if missing; used only if it is a folder (not
/// a link) that this user owns and nobody else may enter.
#[cfg(target_os = "linux")]
fn private_dir() -> Option<PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let uid = std::fs::metadata("/proc/self").ok()?.uid();
    let dir = std::env::temp_dir().join(format!("specmap-runtime-{uid}"));
    match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(_) => return None,
    }
    let m = std::fs::symlink_metadata(&dir).ok()?;
    (m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0).then_some(dir)
}

/// Elsewhere (no /proc/self to learn the user from) nothing changes.
#[cfg(not(target_os = "linux"))]
fn private_dir() -> Option<PathBuf> {
    None
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn the_private_folder_is_the_users_own_and_closed_to_others() {
        let dir = private_dir().expect("a private folder in the temporary folder");
        let m = std::fs::symlink_metadata(&dir).unwrap();
        assert!(m.is_dir());
        assert_eq!(m.permissions().mode() & 0o777, 0o700, "{}", dir.display());
        // Made once, then reused.
        assert_eq!(private_dir(), Some(dir));
    }
}
