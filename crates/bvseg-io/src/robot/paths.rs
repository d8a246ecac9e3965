//! Where a robot file's mesh names point, and how an output names a file beside its input.
use std::path::{Component, Path, PathBuf};

use crate::IoError;

/// [`resolve`] for link `link` of robot `robot`: a file not found is
/// [`IoError::MissingMesh`], naming every path tried.
pub(crate) fn resolve_mesh(
    dir: &Path,
    given: &str,
    robot: &str,
    link: &str,
) -> Result<PathBuf, IoError> {
    resolve(dir, given).map_err(|tried| IoError::MissingMesh {
        name: robot.to_owned(),
        link: link.to_owned(),
        file: given.to_owned(),
        tried: tried
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// Resolves a mesh file name of a robot file: `file://` and `package://NAME/` prefixes
/// dropped, relative names read from `dir`, then from each of its parents (a ROS package's
/// meshes often sit beside or above the robot file), and for `package://` also as
/// `NAME/rest` there. Returns the path found, or the paths tried.
fn resolve(dir: &Path, given: &str) -> Result<PathBuf, Vec<PathBuf>> {
    let (rest, package) = if let Some(r) = given.strip_prefix("package://") {
        match r.split_once('/') {
            Some((pkg, rest)) => (rest, Some(pkg)),
            None => (r, None),
        }
    } else {
        (given.strip_prefix("file://").unwrap_or(given), None)
    };
    let rel = Path::new(rest);
    let mut tried = Vec::new();
    if rel.is_absolute() {
        if rel.is_file() {
            return Ok(rel.to_path_buf());
        }
        return Err(vec![rel.to_path_buf()]);
    }
    let mut at = Some(dir);
    while let Some(d) = at {
        let mut candidates = vec![d.join(rel)];
        if let Some(pkg) = package {
            candidates.push(d.join(pkg).join(rel));
        }
        for c in candidates {
            if c.is_file() {
                return Ok(c);
            }
            tried.push(c);
        }
        // Give up above the package's likely root instead of walking to `/`.
        if tried.len() >= 8 || d.as_os_str().is_empty() {
            break;
        }
        at = d.parent();
    }
    Err(tried)
}

/// The path that leads from directory `from` to `to`, both absolute and without `..`
/// (canonical paths): relative when they share a root (`""` for the same directory), else
/// `to` itself.
pub(crate) fn relative(from: &Path, to: &Path) -> PathBuf {
    let a: Vec<Component> = from.components().collect();
    let b: Vec<Component> = to.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return to.to_path_buf();
    }
    let mut out = PathBuf::new();
    for _ in common..a.len() {
        out.push("..");
    }
    for c in &b[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// A name with path separators and other awkward characters replaced by `_`, without
/// leading dots (no hidden files, no `..`).
pub(crate) fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect::<String>()
        .trim_start_matches('.')
        .to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        let r = |a: &str, b: &str| relative(Path::new(a), Path::new(b));
        assert_eq!(r("/a/b/out", "/a/b"), PathBuf::from(".."));
        assert_eq!(r("/a/out", "/a/b/c"), PathBuf::from("../b/c"));
        assert_eq!(r("/a", "/a"), PathBuf::from(""));
        assert_eq!(r("/a", "/a/m"), PathBuf::from("m"));
    }

    #[test]
    fn names_are_safe_for_files() {
        assert_eq!(file_safe("../a b/c"), "_a_b_c");
        assert_eq!(file_safe("link_1.x"), "link_1.x");
    }
}
