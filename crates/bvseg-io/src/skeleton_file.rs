//! The `bvseg.skeleton/1` file: a skeleton for a mesh that has none (joints with positions
//! and parents), documented in docs/formats.md.
use std::path::Path;

use bvseg_core::{Joint, Skeleton};
use glam::{DMat4, DVec3};
use serde::Deserialize;

use crate::IoError;

/// The schema string of a skeleton file.
pub const SKELETON_SCHEMA: &str = "bvseg.skeleton/1";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    schema: String,
    joints: Vec<FileJoint>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileJoint {
    name: String,
    #[serde(default)]
    parent: Option<String>,
    position: [f64; 3],
}

/// Reads a skeleton file (see [`parse_skeleton`]).
///
/// # Errors
///
/// [`IoError::Io`] when the file cannot be read, else [`parse_skeleton`]'s.
pub fn read_skeleton(path: impl AsRef<Path>) -> Result<Skeleton, IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(&name, "read", e))?;
    parse_skeleton(&text, &name)
}

/// Parses a `bvseg.skeleton/1` document: `{"schema": "bvseg.skeleton/1", "joints": [{"name":
/// "hip", "position": [x, y, z]}, {"name": "knee", "parent": "hip", "position": [...]}]}`,
/// positions in the mesh's units and frame, parents by name (a joint without `parent` is a
/// root). The joints' frames are the model's axes at their positions.
///
/// # Errors
///
/// [`IoError::Parse`] naming the file for malformed JSON, another schema, a repeated or
/// unknown joint name, a non-finite position or parents that form a cycle.
pub fn parse_skeleton(text: &str, name: &str) -> Result<Skeleton, IoError> {
    let bad = |message: String| IoError::Parse {
        name: name.to_owned(),
        line: None,
        message,
    };
    let file: File = serde_json::from_str(text)
        .map_err(|e| bad(format!("not a skeleton file: {e}").replace('\n', " ")))?;
    if file.schema != SKELETON_SCHEMA {
        return Err(bad(format!(
            "schema {:?}, expected {SKELETON_SCHEMA:?}",
            file.schema
        )));
    }
    let mut index = std::collections::HashMap::new();
    for (i, j) in file.joints.iter().enumerate() {
        if index.insert(j.name.as_str(), i).is_some() {
            return Err(bad(format!("joint {:?} is named twice", j.name)));
        }
    }
    let mut joints = Vec::with_capacity(file.joints.len());
    for j in &file.joints {
        let parent =
            match &j.parent {
                None => None,
                Some(p) => Some(*index.get(p.as_str()).ok_or_else(|| {
                    bad(format!("joint {:?} has the unknown parent {p:?}", j.name))
                })?),
            };
        let at = DVec3::from_array(j.position);
        if !at.is_finite() {
            return Err(bad(format!("joint {:?} has a non-finite position", j.name)));
        }
        joints.push(Joint {
            name: j.name.clone(),
            parent,
            rest: DMat4::from_translation(at),
            node: None,
        });
    }
    let skeleton = Skeleton { joints };
    skeleton
        .validate()
        .map_err(|e| bad(format!("bad skeleton: {e}")))?;
    Ok(skeleton)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skeleton_file_and_its_errors() {
        let ok = r#"{"schema":"bvseg.skeleton/1","joints":[
            {"name":"hip","position":[0,0,0]},
            {"name":"knee","parent":"hip","position":[0,-1,0]}]}"#;
        let s = parse_skeleton(ok, "s.json").unwrap();
        assert_eq!(s.links(), vec![(0, 1)]);
        let cycle = r#"{"schema":"bvseg.skeleton/1","joints":[
            {"name":"a","parent":"b","position":[0,0,0]},
            {"name":"b","parent":"a","position":[0,1,0]}]}"#;
        let e = parse_skeleton(cycle, "s.json").unwrap_err().to_string();
        assert!(
            e.starts_with("s.json: bad skeleton:") && e.contains("cycle"),
            "{e}"
        );
        let unknown = r#"{"schema":"bvseg.skeleton/1","joints":[
            {"name":"a","parent":"z","position":[0,0,0]}]}"#;
        assert!(parse_skeleton(unknown, "s.json").is_err());
    }
}
