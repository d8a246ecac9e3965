//! An MJCF file and the files it includes, each kept as text: the reader walks them as one
//! model, the writer gives each back with its own edits.
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::robot::read_text;
use crate::IoError;

/// One file of an MJCF model: the main file (the first), or the file of one `<include>` (a
/// file included twice is here twice, once for each place it is included from).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct File {
    /// Where it was read from.
    pub(crate) path: PathBuf,
    /// As messages name it.
    pub(crate) name: String,
    /// Its text.
    pub(crate) text: String,
    /// Its `<include>` elements.
    pub(crate) includes: Vec<Include>,
    /// Just past the root element's start tag (`<mujoco ...>`).
    pub(crate) root_open: usize,
}

/// An `<include file=...>` element of a [`File`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Include {
    /// The element.
    pub(crate) element: Range<usize>,
    /// Its `file` attribute's value.
    pub(crate) value: Range<usize>,
    /// The index of the file it includes.
    pub(crate) file: usize,
}

/// The main file at `path` (already read as `text`, named `name` in messages) and every file
/// it includes, directly or not. An included name is looked up, as MuJoCo does, in the main
/// file's directory, then beside the including file.
///
/// # Errors
///
/// [`IoError::IncludeCycle`] for a file that includes itself, directly or not;
/// [`IoError::Robot`] for a file that is not well-formed XML or an `<include>` without a
/// file; [`IoError::Io`] for an included file that cannot be read.
pub(crate) fn load(path: &Path, name: &str, text: String) -> Result<Vec<File>, IoError> {
    let main_dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut files = vec![File {
        path: path.to_path_buf(),
        name: name.to_owned(),
        text,
        includes: Vec::new(),
        root_open: 0,
    }];
    let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let mut chain = vec![(key, name.to_owned())];
    add(&mut files, 0, &main_dir, &mut chain)?;
    Ok(files)
}

/// Parses file `at` of `files`, and adds the files it includes (and theirs) after it.
fn add(
    files: &mut Vec<File>,
    at: usize,
    main_dir: &Path,
    chain: &mut Vec<(PathBuf, String)>,
) -> Result<(), IoError> {
    let (found, root_open) = {
        let f = &files[at];
        let doc = roxmltree::Document::parse(&f.text).map_err(|e| IoError::Robot {
            name: f.name.clone(),
            message: e.to_string(),
        })?;
        let root_open = start_tag_end(&f.text, doc.root_element().range().start);
        let mut found = Vec::new();
        for node in doc.descendants().filter(|n| n.has_tag_name("include")) {
            let attr = node
                .attributes()
                .find(|a| a.name() == "file")
                .ok_or_else(|| IoError::Robot {
                    name: f.name.clone(),
                    message: "an <include> has no file".into(),
                })?;
            found.push((node.range(), attr.range_value(), attr.value().to_owned()));
        }
        (found, root_open)
    };
    files[at].root_open = root_open;
    let dir = files[at]
        .path
        .parent()
        .unwrap_or(Path::new(""))
        .to_path_buf();
    for (element, value, file) in found {
        let path = [main_dir.join(&file), dir.join(&file)]
            .into_iter()
            .find(|p| p.is_file())
            .unwrap_or_else(|| main_dir.join(&file));
        let key = path.canonicalize().unwrap_or_else(|_| path.clone());
        let name = path.display().to_string();
        if chain.iter().any(|(k, _)| *k == key) {
            let mut names: Vec<&str> = chain.iter().map(|(_, n)| n.as_str()).collect();
            names.push(&name);
            return Err(IoError::IncludeCycle {
                name: chain[0].1.clone(),
                chain: names.join(" -> "),
            });
        }
        let text = read_text(&path, &name)?;
        let index = files.len();
        files.push(File {
            path,
            name: name.clone(),
            text,
            includes: Vec::new(),
            root_open: 0,
        });
        files[at].includes.push(Include {
            element,
            value,
            file: index,
        });
        chain.push((key, name));
        add(files, index, main_dir, chain)?;
        chain.pop();
    }
    Ok(())
}

/// Just past the `>` of the start tag that begins at `start` (quoted `>`s skipped).
pub(crate) fn start_tag_end(text: &str, start: usize) -> usize {
    let mut quote = None;
    for (i, c) in text[start..].char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '>') => return start + i + 1,
            _ => {}
        }
    }
    text.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_tags_end_after_quoted_brackets() {
        let t = r#"<mujoco model="a>b"><x/></mujoco>"#;
        assert_eq!(&t[..start_tag_end(t, 0)], r#"<mujoco model="a>b">"#);
    }
}
