//! # bvseg-testkit
//!
//! What bvseg's tests share (a dev-dependency only, never published): fresh scratch
//! directories, the paths of the bundled meshes, running a binary in a directory, reading
//! what it printed or left behind, and small test meshes ([`geometry`]).
// A fixture that cannot set up fails the test that asked for it, loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]
pub mod geometry;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// The bundled Stanford bunny (`assets/meshes/bunny.obj`, 3,674 triangles), as an absolute
/// path.
pub const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");

/// A mesh of `assets/meshes` (e.g. `spot.obj`), as an absolute path.
pub fn bundled_mesh(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/meshes")
        .join(file)
}

/// A fresh, empty directory for the test `test`, unique to it and to this process (so tests
/// of the same name in other test binaries, or in another run going on at the same time, do
/// not share it). It is left in place after the test, to be looked at when it fails.
///
/// The directories live beside the test binary, in the build directory
/// (`target/<profile>/tmp/bvseg-scratch/<binary>-<pid>/<test>`; the system's temporary
/// directory when the binary is elsewhere). On Linux, the directories of earlier runs of the
/// same binary are removed on the first call.
///
/// # Panics
///
/// When the directory cannot be created.
pub fn scratch(test: &str) -> PathBuf {
    let dir = process_root().join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir)
        .unwrap_or_else(|e| panic!("cannot create the scratch directory {}: {e}", dir.display()));
    dir
}

/// `<base>/<binary>-<pid>`, made once per process.
fn process_root() -> &'static Path {
    static ROOT: OnceLock<PathBuf> = OnceLock::new();
    ROOT.get_or_init(|| {
        let exe = std::env::current_exe().ok();
        let binary = exe
            .as_deref()
            .and_then(Path::file_stem)
            .map_or_else(|| "test".to_owned(), |s| s.to_string_lossy().into_owned());
        // Test binaries are `target/<profile>/deps/<name>-<hash>`.
        let base = exe
            .as_deref()
            .and_then(Path::parent)
            .filter(|d| d.file_name().is_some_and(|n| n == "deps"))
            .and_then(Path::parent)
            .map_or_else(std::env::temp_dir, |profile| profile.join("tmp"))
            .join("bvseg-scratch");
        remove_stale(&base, &binary);
        base.join(format!("{binary}-{}", std::process::id()))
    })
}

/// Removes `<base>/<binary>-<pid>` of processes that are gone (Linux only: elsewhere there is
/// no cheap way to tell, and the directories stay until `cargo clean`).
fn remove_stale(base: &Path, binary: &str) {
    if !Path::new("/proc/self").is_dir() {
        return;
    }
    let Ok(entries) = fs::read_dir(base) else {
        return;
    };
    let prefix = format!("{binary}-");
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = fs::remove_dir_all(e.path());
        }
    }
}

/// Runs the program `bin` in `dir` with `args`, waiting for it; what it printed is in the
/// returned [`Output`].
///
/// # Panics
///
/// When the program cannot be started.
pub fn run(bin: &str, dir: &Path, args: &[&str]) -> Output {
    Command::new(bin)
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {bin}: {e}"))
}

/// What a finished program printed on stderr, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The names of the entries of `dir`, sorted.
///
/// # Panics
///
/// When `dir` cannot be read.
pub fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scratch_is_fresh_and_per_test() {
        let a = scratch("a");
        fs::write(a.join("x"), "1").unwrap();
        assert_eq!(files(&a), ["x"]);
        assert_eq!(scratch("a"), a);
        assert!(files(&a).is_empty());
        let b = scratch("b");
        assert_ne!(a, b);
        assert!(a.parent().unwrap().ends_with(format!(
            "{}-{}",
            std::env::current_exe()
                .unwrap()
                .file_stem()
                .unwrap()
                .to_string_lossy(),
            std::process::id()
        )));
    }

    #[test]
    fn bundled_meshes_are_there() {
        assert!(Path::new(BUNNY).is_file());
        assert!(bundled_mesh("spot.obj").is_file());
    }
}
