//! Wavefront OBJ input, through `tobj`.
//!
//! Only positions and faces matter to bvseg. Every object and group is merged into one mesh,
//! polygons are fanned into triangles, and exactly coincident positions are welded so that a
//! file that repeats positions (per object, or per face as some exporters do) still yields a
//! closed surface.
use std::fs::File;
use std::io::{self, BufRead, Read};
use std::path::Path;

use glam::DVec3;

use crate::finish::{finish, RawMesh};
use crate::{IoError, LoadedMesh};

/// Inputs larger than this are refused before parsing. The parser keeps every position and
/// face in memory at several times its text size, so this keeps a stray multi-gigabyte file
/// from exhausting memory.
pub const MAX_INPUT_BYTES: u64 = 2 << 30;

/// Opens `path` for reading, refusing directories and files over [`MAX_INPUT_BYTES`] up front
/// (the reader enforces the size limit again for files that grow or lie about their size).
pub(crate) fn open_input(path: &Path, name: &str) -> Result<File, IoError> {
    let file = File::open(path).map_err(|e| IoError::io(name, "open", e))?;
    let meta = file.metadata().map_err(|e| IoError::io(name, "read", e))?;
    if meta.is_dir() {
        return Err(IoError::BadPath {
            name: name.to_owned(),
            message: "is a directory, not a mesh file".into(),
        });
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(IoError::TooLarge {
            name: name.to_owned(),
            limit: MAX_INPUT_BYTES,
        });
    }
    Ok(file)
}

pub(crate) fn read_obj(
    reader: impl BufRead,
    name: &str,
    object: Option<&str>,
) -> Result<LoadedMesh, IoError> {
    let mut lines = PositionLines::new(reader, MAX_INPUT_BYTES);
    // The struct update is needed when another crate in the build enables tobj's `merging`
    // or `reordering` features, which add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        // Positions keep the file's indexing: splitting by normal/uv would open the surface.
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials are never needed, and `tobj::load_obj` would open .mtl files next to the
    // input; this loader never touches another file.
    let parsed = tobj::load_obj_buf(&mut lines, &options, |_| Ok(Default::default()));
    let models = match parsed {
        Ok((models, _materials)) => models,
        Err(e) => return Err(parse_error(e, &lines, name)),
    };

    let mut raw = RawMesh::default();
    let mut found = object.is_none();
    for model in &models {
        if object.is_some_and(|o| o != model.name) {
            continue;
        }
        found = true;
        let m = &model.mesh;
        let base = raw.positions.len();
        raw.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0], p[1], p[2])),
        );
        for t in m.indices.chunks_exact(3) {
            raw.triangles.push([0, 1, 2].map(|j| base + t[j] as usize));
        }
    }
    if let (false, Some(object)) = (found, object) {
        return Err(IoError::Parse {
            name: name.to_owned(),
            line: None,
            message: format!(
                "no object or group named '{object}' (the file has: {})",
                name_list(models.iter().map(|m| m.name.as_str()))
            ),
        });
    }
    finish(raw, name)
}

/// The first few distinct names, quoted, for an error message.
pub(crate) fn name_list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut seen: Vec<&str> = Vec::new();
    for n in names {
        if !seen.contains(&n) {
            seen.push(n);
        }
    }
    if seen.is_empty() {
        return "none".into();
    }
    let mut s: Vec<String> = seen.iter().take(10).map(|n| format!("'{n}'")).collect();
    if seen.len() > 10 {
        s.push(format!("and {} more", seen.len() - 10));
    }
    s.join(", ")
}

/// Turns a `tobj` error into a one-line message, with the line number where it is known.
fn parse_error<R>(e: tobj::LoadError, lines: &PositionLines<R>, name: &str) -> IoError {
    use tobj::LoadError as E;
    match lines.failure.as_ref() {
        Some(Failure::TooLarge) => {
            return IoError::TooLarge {
                name: name.to_owned(),
                limit: lines.limit,
            };
        }
        Some(Failure::Io(kind, msg)) => {
            return IoError::io(name, "read", io::Error::new(*kind, msg.clone()));
        }
        None => {}
    }
    // Errors raised while a line is parsed are at the line the reader stopped on. Index
    // errors are only found when an object is closed (at the next `o`/`g` or at the end), so
    // a line number there would point at the wrong place.
    let (at_line, message) = match e {
        E::ReadError => (true, "not valid UTF-8 text (is this a binary file?)"),
        E::PositionParseError => (
            true,
            "bad vertex: expected `v x y z [w]` with three numbers",
        ),
        E::ScalingByZeroError => (true, "bad vertex: the w coordinate is zero"),
        E::ColorParseError => (
            true,
            "bad vertex: expected `v x y z [w]` or `v x y z r g b`",
        ),
        E::FaceParseError => (true, "bad face: expected `f` followed by vertex indices"),
        E::FaceVertexOutOfBounds => (false, "a face refers to a vertex that does not exist"),
        E::FaceColorOutOfBounds => (false, "vertex colours are given for only some vertices"),
        E::InvalidPolygon => (false, "a face has fewer than three vertices"),
        E::UnrecognizedCharacter => (true, "unrecognized character"),
        // The remaining kinds concern lines the reader drops (normals, texture coordinates,
        // materials) or options this loader does not set; keep tobj's own words for them.
        _ => (true, ""),
    };
    let message = if message.is_empty() {
        e.to_string()
    } else {
        message.to_owned()
    };
    IoError::Parse {
        name: name.to_owned(),
        line: at_line.then_some(lines.line),
        message,
    }
}

/// Why [`PositionLines`] stopped; `tobj` reduces every read error to `ReadError`, so the
/// cause is kept here.
#[derive(Debug)]
enum Failure {
    TooLarge,
    Io(io::ErrorKind, String),
}

/// A line-by-line reader in front of `tobj` that
/// - counts source lines, so that parse errors can name the line (tobj does not);
/// - drops normal, texture-coordinate and material lines: bvseg needs none of them, and
///   tobj's index arithmetic on texture/normal references can overflow on hostile input;
/// - enforces a byte limit.
struct PositionLines<R> {
    inner: io::Take<R>,
    buf: Vec<u8>,
    pos: usize,
    eof: bool,
    /// Source lines read so far; the one tobj is parsing is the last of them.
    line: usize,
    limit: u64,
    read: u64,
    failure: Option<Failure>,
}

impl<R: BufRead> PositionLines<R> {
    fn new(inner: R, limit: u64) -> Self {
        Self {
            // One byte past the limit tells "exactly at the limit" from "over it".
            inner: inner.take(limit.saturating_add(1)),
            buf: Vec::new(),
            pos: 0,
            eof: false,
            line: 0,
            limit,
            read: 0,
            failure: None,
        }
    }

    fn fail(&mut self, failure: Failure) -> io::Error {
        self.failure = Some(failure);
        self.eof = true;
        io::Error::other("read failed")
    }
}

fn is_dropped(line: &[u8]) -> bool {
    let word = line
        .split(|b| b.is_ascii_whitespace())
        .find(|w| !w.is_empty())
        .unwrap_or_default();
    matches!(word, b"vt" | b"vn" | b"vp" | b"mtllib" | b"usemtl")
}

impl<R: BufRead> BufRead for PositionLines<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        while self.pos >= self.buf.len() && !self.eof {
            self.buf.clear();
            self.pos = 0;
            let n = match self.inner.read_until(b'\n', &mut self.buf) {
                Ok(n) => n,
                Err(e) => return Err(self.fail(Failure::Io(e.kind(), e.to_string()))),
            };
            if n == 0 {
                self.eof = true;
                break;
            }
            self.read += n as u64;
            if self.read > self.limit {
                return Err(self.fail(Failure::TooLarge));
            }
            self.line += 1;
            if is_dropped(&self.buf) {
                self.buf.clear();
            }
        }
        Ok(&self.buf[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.buf.len());
    }
}

impl<R: BufRead> Read for PositionLines<R> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        out[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn load(text: &str) -> Result<LoadedMesh, IoError> {
        read_obj(text.as_bytes(), "t.obj", None)
    }

    fn err(text: &str) -> String {
        match load(text) {
            Ok(m) => panic!("expected an error, got {m:?}"),
            Err(e) => e.to_string(),
        }
    }

    const CUBE_VERTS: &str =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";

    /// A unit cube as six outward quads with one normal and four uvs per face, in the way
    /// exporters write hard-edged meshes.
    fn cube_with_normals() -> String {
        let mut s = String::from("# cube\nmtllib cube.mtl\no cube\n");
        s += CUBE_VERTS;
        for n in ["0 0 -1", "0 0 1", "0 -1 0", "1 0 0", "0 1 0", "-1 0 0"] {
            s += &format!("vn {n}\n");
        }
        for uv in ["0 0", "1 0", "1 1", "0 1"] {
            s += &format!("vt {uv}\n");
        }
        s += "usemtl red\ns off\n";
        let quads = [
            [1, 4, 3, 2],
            [5, 6, 7, 8],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 4, 8, 7],
            [4, 1, 5, 8],
        ];
        for (f, q) in quads.iter().enumerate() {
            s += "f";
            for (j, v) in q.iter().enumerate() {
                s += &format!(" {v}/{}/{}", j + 1, f + 1);
            }
            s += "\n";
        }
        s
    }

    #[test]
    fn cube_with_per_face_normals_keeps_eight_vertices() {
        let l = load(&cube_with_normals()).unwrap();
        assert_eq!(l.mesh.vertices().len(), 8);
        assert_eq!(l.mesh.triangles().len(), 12);
        assert!(l.mesh.is_closed());
        assert_eq!(l.stats.degenerate, 0);
        assert!((l.mesh.signed_volume() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn objects_and_groups_are_merged_and_welded() {
        // Two objects sharing the cube's vertex list, and a group inside the second.
        let s = format!(
            "{CUBE_VERTS}o bottom_half\nf 1 4 3 2\nf 1 2 6 5\nf 2 3 7 6\n\
             o top_half\nf 5 6 7 8\ng sides\nf 3 4 8 7\nf 4 1 5 8\n"
        );
        let l = load(&s).unwrap();
        assert_eq!(l.mesh.triangles().len(), 12);
        assert_eq!(l.mesh.vertices().len(), 8);
        assert!(
            l.stats.welded > 0,
            "tobj copies shared positions per object"
        );
        assert!(l.mesh.is_closed());
    }

    #[test]
    fn duplicated_positions_are_welded() {
        // Every face has its own four vertices, as in a "flat shaded" export.
        let corners = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let quads = [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ];
        let mut s = String::new();
        for q in &quads {
            for &c in q {
                let [x, y, z] = corners[c];
                // -0 must weld with 0.
                let x = if x == 0.0 {
                    "-0.0".to_string()
                } else {
                    x.to_string()
                };
                s += &format!("v {x} {y} {z}\n");
            }
        }
        for f in 0..6 {
            let b = 4 * f + 1;
            s += &format!("f {} {} {} {}\n", b, b + 1, b + 2, b + 3);
        }
        let l = load(&s).unwrap();
        assert_eq!(l.stats.vertices_read, 24);
        assert_eq!(l.stats.welded, 16);
        assert_eq!(l.mesh.vertices().len(), 8);
        assert!(l.mesh.is_closed());
    }

    #[test]
    fn ngons_are_fanned_in_order() {
        let s = "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n";
        let m = load(s).unwrap().mesh;
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn relative_indices() {
        let s = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -1 -3\n";
        let m = load(s).unwrap().mesh;
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 3, 1]]);
    }

    #[test]
    fn slash_forms_and_w_are_accepted() {
        let s = "v 0 0 0 1\nv 2 0 0 2\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1//1 2/1 3/1/1\n";
        let m = load(s).unwrap().mesh;
        assert_eq!(m.vertices()[1], DVec3::X);
        assert_eq!(m.triangles().len(), 1);
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        // The fourth vertex repeats the first, so the third triangle collapses.
        let s = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nf 1 2 3\nf 2 3 4 \nf 1 2 4\n";
        let l = load(s).unwrap();
        assert_eq!(l.mesh.triangles(), &[[0, 1, 2], [1, 2, 0]]);
        assert_eq!(l.stats.degenerate, 1);
        assert_eq!(l.stats.triangles_read, 3);
    }

    #[test]
    fn points_and_lines_are_ignored() {
        let s = "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\nl 1 2\nf 1 2 3\n";
        let l = load(s).unwrap();
        assert_eq!(l.mesh.triangles().len(), 1);
        assert_eq!(l.stats.degenerate, 0);
    }

    #[test]
    fn bundled_bunny_is_closed() {
        let bytes = include_bytes!("../../../assets/meshes/bunny.obj");
        let l = read_obj(&bytes[..], "bunny.obj", None).unwrap();
        assert_eq!(l.mesh.triangles().len(), 3674);
        assert!(l.mesh.is_closed());
        let used: HashSet<u32> = l.mesh.triangles().iter().flatten().copied().collect();
        assert_eq!(used.len(), l.mesh.vertices().len());
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        assert_eq!(err(""), "t.obj: no triangles");
        assert_eq!(err("# only\n# comments\n\n"), "t.obj: no triangles");
        assert_eq!(
            err("hello world\nthis is not an obj file\n"),
            "t.obj: no triangles"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n"),
            "t.obj: no triangles (1 degenerate dropped)"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
            "t.obj: a face refers to a vertex that does not exist"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
            "t.obj: a face refers to a vertex that does not exist"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
            "t.obj: a face refers to a vertex that does not exist"
        );
        assert!(err("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
            .starts_with("t.obj: a vertex has a non-finite coordinate (NaN"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 1e400 1 0\nf 1 2 3\n").contains("non-finite"));
        assert_eq!(
            err("# x\nv 0 0 0\nv 1 zero 0\n"),
            "t.obj: line 3: bad vertex: expected `v x y z [w]` with three numbers"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\n\n\nf 1 2 x\n"),
            "t.obj: line 6: bad face: expected `f` followed by vertex indices"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999"),
            "t.obj: line 4: bad face: expected `f` followed by vertex indices"
        );
        assert!(err("v 0 0 0 0\n").starts_with("t.obj: line 1: bad vertex"));
        // Huge relative texture / normal indices overflow inside tobj; they are never seen.
        let m = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-9/-9 2/0/0 3/-1/-1\n").unwrap();
        assert_eq!(m.mesh.triangles().len(), 1);
        // Binary garbage.
        let bytes: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect();
        let e = read_obj(&bytes[..], "t.obj", None).unwrap_err().to_string();
        assert!(e.starts_with("t.obj: "), "{e}");
        assert!(!e.contains('\n'));
    }

    #[test]
    fn reader_over_the_limit_is_refused() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let mut lines = PositionLines::new(text.as_bytes(), 10);
        let r = tobj::load_obj_buf(&mut lines, &tobj::LoadOptions::default(), |_| {
            Ok(Default::default())
        });
        let e = parse_error(r.unwrap_err(), &lines, "t.obj");
        assert!(matches!(e, IoError::TooLarge { limit: 10, .. }), "{e}");
        // Exactly at the limit is fine.
        let mut lines = PositionLines::new(text.as_bytes(), text.len() as u64);
        assert!(
            tobj::load_obj_buf(&mut lines, &tobj::LoadOptions::default(), |_| {
                Ok(Default::default())
            })
            .is_ok()
        );
    }

    #[test]
    fn line_without_trailing_newline_is_counted() {
        assert_eq!(
            err("v 0 0 0\nv 1 0"),
            "t.obj: line 2: bad vertex: expected `v x y z [w]` with three numbers"
        );
        assert_eq!(
            err("v 0 0 0\r\nvn 0 0 1\r\nv 1 0\r\n"),
            "t.obj: line 3: bad vertex: expected `v x y z [w]` with three numbers"
        );
    }
}
