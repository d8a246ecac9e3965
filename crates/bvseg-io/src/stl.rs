//! STL input, binary and ASCII, parsed by hand so that every allocation is bounded by the
//! file's size.
//!
//! A file is binary when its size is exactly 84 + 50 * (the triangle count in its header):
//! binary files from some exporters also start with `solid`, so the first word alone cannot
//! decide. Otherwise a file starting with `solid` is read as ASCII.
use glam::DVec3;

use crate::finish::{finish, RawMesh};
use crate::{IoError, LoadedMesh};

/// Parses an STL file held in memory; `name` is what error messages call it.
pub(crate) fn read_stl(bytes: &[u8], name: &str) -> Result<LoadedMesh, IoError> {
    let raw = if binary_count(bytes).is_some() {
        read_binary(bytes)
    } else if starts_with_solid(bytes) {
        read_ascii(bytes, name)?
    } else if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
        return Err(parse(
            name,
            None,
            format!(
                "not an STL file: as binary STL its header announces {n} triangles \
                 ({} bytes), but the file has {} bytes; as ASCII STL it lacks `solid`",
                84 + 50 * n as u64,
                bytes.len()
            ),
        ));
    } else {
        return Err(parse(
            name,
            None,
            format!(
                "not an STL file: {} bytes is too short for binary STL and it does not \
                 start with `solid`",
                bytes.len()
            ),
        ));
    };
    finish(raw, name)
}

fn parse(name: &str, line: Option<usize>, message: String) -> IoError {
    IoError::Parse {
        name: name.to_owned(),
        line,
        message,
    }
}

/// The triangle count when `bytes` is exactly a binary STL's size.
fn binary_count(bytes: &[u8]) -> Option<usize> {
    let header = bytes.get(80..84)?;
    let n = u32::from_le_bytes([header[0], header[1], header[2], header[3]]) as u64;
    (84 + 50 * n == bytes.len() as u64).then_some(n as usize)
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace());
    start.is_some_and(|s| {
        bytes[s..]
            .get(..5)
            .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"))
    })
}

fn read_binary(bytes: &[u8]) -> RawMesh {
    // The count was checked against the file's size, so these allocations are bounded by it.
    let n = binary_count(bytes).unwrap_or(0);
    let mut raw = RawMesh {
        positions: Vec::with_capacity(3 * n),
        triangles: Vec::with_capacity(n),
    };
    for rec in bytes[84..].chunks_exact(50) {
        let f = |o: usize| f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
        let base = raw.positions.len();
        // Bytes 0..12 are the facet normal, which the winding makes redundant.
        for v in 0..3 {
            let o = 12 + 12 * v;
            raw.positions
                .push(DVec3::new(f(o) as f64, f(o + 4) as f64, f(o + 8) as f64));
        }
        raw.triangles.push([base, base + 1, base + 2]);
    }
    raw
}

/// Where the ASCII parser is in the `solid / facet / outer loop / vertex` nesting.
#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    Top,
    Solid,
    Facet,
    Loop,
}

fn read_ascii(bytes: &[u8], name: &str) -> Result<RawMesh, IoError> {
    let mut raw = RawMesh::default();
    let mut state = State::Top;
    let mut loop_start = 0usize;
    let mut solids = 0usize;
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let lineno = i + 1;
        let err = |m: String| parse(name, Some(lineno), m);
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        let Some(word) = words.next() else { continue };
        let word = word.to_ascii_lowercase();
        state = match (state, word.as_slice()) {
            // The name after `solid` / `endsolid` is free text.
            (State::Top, b"solid") => {
                solids += 1;
                State::Solid
            }
            (State::Solid, b"endsolid") => State::Top,
            (State::Solid, b"facet") => State::Facet,
            (State::Facet, b"outer") => {
                if words.next().map(|w| w.eq_ignore_ascii_case(b"loop")) != Some(true) {
                    return Err(err("expected `outer loop`".into()));
                }
                loop_start = raw.positions.len();
                State::Loop
            }
            (State::Loop, b"vertex") => {
                let mut p = [0.0f64; 3];
                for c in &mut p {
                    *c = words
                        .next()
                        .and_then(|w| std::str::from_utf8(w).ok())
                        .and_then(|w| w.parse().ok())
                        .ok_or_else(|| err("bad vertex: expected `vertex x y z`".into()))?;
                }
                if words.next().is_some() {
                    return Err(err("bad vertex: expected `vertex x y z`".into()));
                }
                raw.positions.push(DVec3::from_array(p));
                State::Loop
            }
            (State::Loop, b"endloop") => {
                let n = raw.positions.len() - loop_start;
                if n < 3 {
                    return Err(err(format!("a facet has {n} vertices; at least 3 needed")));
                }
                raw.reserve_triangles(n - 2, name)?;
                // Polygons are fanned, as for OBJ.
                for j in 1..n - 1 {
                    raw.triangles
                        .push([loop_start, loop_start + j, loop_start + j + 1]);
                }
                State::Facet
            }
            (State::Facet, b"endfacet") => State::Solid,
            (_, w) => {
                let w = String::from_utf8_lossy(&w[..w.len().min(20)]).into_owned();
                let expected = match state {
                    State::Top => "`solid`",
                    State::Solid => "`facet` or `endsolid`",
                    State::Facet => "`outer loop` or `endfacet`",
                    State::Loop => "`vertex` or `endloop`",
                };
                return Err(err(format!(
                    "unexpected `{w}` in ASCII STL (expected {expected})"
                )));
            }
        };
    }
    if state != State::Top || solids == 0 {
        return Err(parse(
            name,
            None,
            "truncated ASCII STL (no closing `endsolid`)".into(),
        ));
    }
    Ok(raw)
}
