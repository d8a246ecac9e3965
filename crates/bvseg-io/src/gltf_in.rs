//! glTF 2.0 input (`.gltf` JSON and `.glb` binary), through the `gltf` crate for the
//! document and by hand for everything that touches bytes.
//!
//! The crate's own GLB and accessor readers trust the file's lengths (version 1.4.1
//! overflows on a GLB header length under 12 and slices buffers without bounds checks), so
//! the GLB container is split here, and every accessor is checked against its buffer view
//! and buffer before a single element is read. Allocations are then bounded by the file.
use std::path::Path;

use glam::{DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use crate::finish::{finish, RawMesh};
use crate::{IoError, LoadedMesh, MAX_INPUT_BYTES};

/// Deepest node nesting followed; deeper (or cyclic) hierarchies are refused.
const MAX_DEPTH: usize = 256;
/// Most node visits in one scene: a cycle through nodes with several children would
/// otherwise be walked an exponential number of times before reaching [`MAX_DEPTH`].
const MAX_NODE_VISITS: usize = 1_000_000;
/// Most vertices a scene may add by instancing a mesh again (every instance after a mesh's
/// first). A mesh's first instance is bounded by the file's size, its repeats are not: a
/// 3 KB file instancing 20 primitives 100,000 times asked for gigabytes before reaching the
/// triangle budget (found while fuzzing). 2^24 vertices are ~400 MB once read.
const MAX_INSTANCED_VERTICES: usize = 1 << 24;

fn err(name: &str, message: impl Into<String>) -> IoError {
    IoError::Parse {
        name: name.to_owned(),
        line: None,
        message: message.into(),
    }
}

/// Where external buffers (`"uri": "x.bin"`) are read from.
pub(crate) enum Externals<'a> {
    /// Relative to this directory.
    Dir(&'a Path),
    /// Not at all: the document was given as bytes.
    None,
}

/// Reads a `.gltf` or `.glb` held in memory. `mesh` restricts the scene to the nodes whose
/// mesh has that name.
pub(crate) fn read_gltf(
    bytes: &[u8],
    name: &str,
    externals: Externals<'_>,
    mesh: Option<&str>,
) -> Result<LoadedMesh, IoError> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        split_glb(bytes, name)?
    } else {
        (bytes, None)
    };
    let doc = parse_document(json, name)?;
    let buffers = doc
        .buffers()
        .map(|b| load_buffer(&b, bin, name, &externals))
        .collect::<Result<Vec<_>, _>>()?;

    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| err(name, "the document has no scene"))?;
    let locals = crate::character::node_locals(json, &doc);
    let mut character = crate::character::Character::new(&doc, &locals, &buffers, name)?;
    let mut raw = RawMesh::default();
    let mut found = mesh.is_none();
    // Depth-first over the node tree with world matrices in f64.
    let mut stack: Vec<(gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    stack.reverse();
    let mut visits = 0usize;
    let mut instanced_meshes = std::collections::HashSet::new();
    let mut instanced_vertices = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        visits += 1;
        if depth > MAX_DEPTH || visits > MAX_NODE_VISITS {
            return Err(err(
                name,
                format!(
                    "the node hierarchy is cyclic, or deeper than {MAX_DEPTH} levels, or has \
                     more than {MAX_NODE_VISITS} node instances"
                ),
            ));
        }
        let world = parent * locals[node.index()].matrix();
        if let Some(m) = node.mesh() {
            if mesh.is_none_or(|want| m.name() == Some(want)) {
                found = true;
                if !instanced_meshes.insert(m.index()) {
                    let vertices = m
                        .primitives()
                        .filter_map(|p| p.get(&gltf::Semantic::Positions));
                    instanced_vertices =
                        instanced_vertices.saturating_add(vertices.map(|a| a.count()).sum());
                    if instanced_vertices > MAX_INSTANCED_VERTICES {
                        return Err(err(
                            name,
                            format!(
                                "the scene instances its meshes into more than \
                                 {MAX_INSTANCED_VERTICES} extra vertices; refusing to load"
                            ),
                        ));
                    }
                }
                for prim in m.primitives() {
                    let place = character.as_mut().map(|c| (c, &node));
                    read_primitive(&prim, &world, place, &buffers, &mut raw, name)?;
                }
            }
        }
        let children: Vec<_> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, world, depth + 1));
        }
    }
    if let (false, Some(want)) = (found, mesh) {
        return Err(err(
            name,
            format!(
                "no mesh named '{want}' in the scene (the file has: {})",
                crate::obj::name_list(doc.meshes().filter_map(|m| m.name()))
            ),
        ));
    }
    let Some(character) = character else {
        return finish(raw, name);
    };
    let (positions, triangles) = (raw.positions.clone(), raw.triangles.clone());
    let mut loaded = finish(raw, name)?;
    let (rig, info) = character.rig(
        &doc,
        &positions,
        &triangles,
        &loaded.dropped,
        loaded.report.flipped,
    );
    loaded.mesh = loaded
        .mesh
        .with_rig(rig)
        .map_err(|e| err(name, e.to_string()))?;
    loaded.character = Some(info);
    loaded.skinning = Some(std::sync::Arc::new(character.skinning(&doc)));
    loaded.animations = character.animation_names();
    Ok(loaded)
}

/// Parses and validates the JSON document. The index checks of the validation are what
/// make the crate's accessors safe to call; the one rule relaxed is that POSITION accessors
/// declare `min` and `max`, which many exporters omit and which bvseg does not use.
fn parse_document(json: &[u8], name: &str) -> Result<gltf::Document, IoError> {
    use gltf::json::validation::{Error as V, Validate};
    let root = gltf::json::Root::from_slice(json).map_err(|e| {
        let msg = e.to_string().replace(['\n', '\r'], " ");
        err(name, format!("not a valid glTF document: {msg}"))
    })?;
    // gltf-json 1.4's validation indexes `accessors` with a primitive's POSITION index
    // before checking it is in range, and panics on a bad one (found by fuzzing): check it
    // first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&pos) {
                if i.value() >= root.accessors.len() {
                    return Err(err(
                        name,
                        format!(
                            "invalid glTF document: meshes[{m}].primitives[{p}].attributes\
                             .POSITION: Index out of range"
                        ),
                    ));
                }
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, e| {
        let path = path();
        let optional = matches!(e, V::Missing)
            && (path.as_str().ends_with(".min") || path.as_str().ends_with(".max"));
        if !optional && problems.len() < 3 {
            problems.push(format!("{path}: {e}"));
        }
    });
    if !problems.is_empty() {
        return Err(err(
            name,
            format!("invalid glTF document: {}", problems.join("; ")),
        ));
    }
    Ok(gltf::Document::from_json_without_validation(root))
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk, checking every length.
fn split_glb<'a>(bytes: &'a [u8], name: &str) -> Result<(&'a [u8], Option<&'a [u8]>), IoError> {
    let u32_at = |o: usize| -> Option<u32> {
        let b = bytes.get(o..o + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(err(name, "truncated GLB header (under 12 bytes)"));
    };
    if version != 2 {
        return Err(err(
            name,
            format!("GLB version {version}; only glTF 2.0 is supported"),
        ));
    }
    let length = length as usize;
    if length < 12 || length > bytes.len() {
        return Err(err(
            name,
            format!(
                "bad GLB header: it gives a total length of {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let body = &bytes[..length];
    let mut offset = 12usize;
    let mut chunks: Vec<(u32, &[u8])> = Vec::new();
    while offset < body.len() {
        let (Some(len), Some(kind)) = (u32_at(offset), u32_at(offset + 4)) else {
            return Err(err(name, "truncated GLB chunk header"));
        };
        let start = offset + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= body.len())
            .ok_or_else(|| {
                err(
                    name,
                    format!("a GLB chunk of {len} bytes runs past the end of the file"),
                )
            })?;
        chunks.push((kind, &body[start..end]));
        // Chunks are 4-byte aligned.
        offset = end.div_ceil(4) * 4;
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => {
            let bin = chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1);
            Ok((json, bin))
        }
        _ => Err(err(name, "the GLB does not start with a JSON chunk")),
    }
}

/// The bytes of one buffer, at least `byteLength` long (and cut to it).
fn load_buffer(
    buffer: &gltf::Buffer,
    bin: Option<&[u8]>,
    name: &str,
    externals: &Externals<'_>,
) -> Result<Vec<u8>, IoError> {
    let i = buffer.index();
    let data = match buffer.source() {
        gltf::buffer::Source::Bin => bin
            .ok_or_else(|| {
                err(
                    name,
                    format!("buffer {i} refers to a missing GLB BIN chunk"),
                )
            })?
            .to_vec(),
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => decode_data_uri(uri)
            .ok_or_else(|| err(name, format!("buffer {i}: malformed base64 data URI")))?,
        gltf::buffer::Source::Uri(uri) => {
            let Externals::Dir(dir) = externals else {
                return Err(err(
                    name,
                    format!(
                        "buffer {i} is the external file '{uri}', which cannot be read when \
                         the document is given as bytes (use .glb or embedded buffers)"
                    ),
                ));
            };
            let rel = percent_decode(uri);
            if uri.contains("://") || Path::new(&rel).is_absolute() {
                return Err(err(
                    name,
                    format!("buffer {i}: only relative file URIs are supported, not '{uri}'"),
                ));
            }
            let path = dir.join(&rel);
            let shown = path.display().to_string();
            let file = crate::obj::open_input(&path, &shown).map_err(|e| {
                err(
                    name,
                    format!("buffer {i}: {}", e.to_string().replace('\n', " ")),
                )
            })?;
            read_limited(file, &shown).map_err(|e| err(name, format!("buffer {i}: {e}")))?
        }
    };
    let want = buffer.length();
    if data.len() < want {
        return Err(err(
            name,
            format!(
                "buffer {i} declares {want} bytes but holds only {}",
                data.len()
            ),
        ));
    }
    let mut data = data;
    data.truncate(want);
    Ok(data)
}

pub(crate) fn read_limited(file: std::fs::File, name: &str) -> Result<Vec<u8>, IoError> {
    use std::io::Read;
    let mut bytes = Vec::new();
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| IoError::io(name, "read", e))?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(IoError::TooLarge {
            name: name.to_owned(),
            limit: MAX_INPUT_BYTES,
        });
    }
    Ok(bytes)
}

fn decode_data_uri(uri: &str) -> Option<Vec<u8>> {
    let (_, payload) = uri.split_once(";base64,")?;
    decode_base64(payload)
}

/// Standard base64 with optional padding; whitespace is not allowed in data URIs.
fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The bytes of accessor `acc`'s elements: (data, offset of the first element, stride),
/// after checking that all `count` elements of `elem` bytes lie inside the view and buffer.
pub(crate) fn accessor_bytes<'b>(
    acc: &gltf::Accessor,
    elem: usize,
    buffers: &'b [Vec<u8>],
    name: &str,
) -> Result<(&'b [u8], usize, usize), IoError> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(err(
            name,
            format!("accessor {i}: sparse accessors are not supported"),
        ));
    }
    let view = acc
        .view()
        .ok_or_else(|| err(name, format!("accessor {i} has no buffer view")))?;
    let data = &buffers[view.buffer().index()];
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(err(
            name,
            format!("accessor {i}: byte stride {stride} is smaller than an element ({elem})"),
        ));
    }
    let count = acc.count();
    let view_end = view.offset().checked_add(view.length());
    // Bytes the accessor spans within its view.
    let span = count
        .checked_sub(1)
        .map(|c| c.checked_mul(stride).and_then(|x| x.checked_add(elem)))
        .unwrap_or(Some(0))
        .and_then(|s| s.checked_add(acc.offset()));
    match (view_end, span) {
        (Some(ve), Some(sp)) if ve <= data.len() && sp <= view.length() => {
            Ok((&data[view.offset()..ve], acc.offset(), stride))
        }
        _ => Err(err(
            name,
            format!(
                "accessor {i} ({count} elements) runs past the end of its buffer view or buffer"
            ),
        )),
    }
}

fn read_primitive(
    prim: &gltf::Primitive,
    world: &DMat4,
    place: Option<(&mut crate::character::Character, &gltf::Node)>,
    buffers: &[Vec<u8>],
    raw: &mut RawMesh,
    name: &str,
) -> Result<(), IoError> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(());
    }
    let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
        return Err(err(name, "a triangle primitive has no POSITION attribute"));
    };
    if pos.dimensions() != Dimensions::Vec3 || pos.data_type() != DataType::F32 || pos.normalized()
    {
        return Err(err(
            name,
            format!(
                "accessor {}: positions must be float VEC3 (quantized positions are not supported)",
                pos.index()
            ),
        ));
    }
    let (data, off, stride) = accessor_bytes(&pos, 12, buffers, name)?;
    let base = raw.positions.len();
    let f = |o: usize| f32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]) as f64;
    let n = pos.count();
    // Instancing can repeat a mesh without bound; its vertices count against the budget too.
    if base.saturating_add(n) > 3 * crate::finish::MAX_TRIANGLES {
        return Err(err(
            name,
            "too many vertices in the scene; refusing to load",
        ));
    }
    raw.positions.reserve(n);
    let local = (0..n).map(|k| {
        let o = off + k * stride;
        DVec3::new(f(o), f(o + 4), f(o + 8))
    });
    // A skinned mesh is where its skin puts it (its node's transform does not apply).
    let mut skinned = false;
    match place {
        None => raw
            .positions
            .extend(local.map(|p| world.transform_point3(p))),
        Some((character, node)) => {
            let local: Vec<DVec3> = local.collect();
            let influences = match node.skin() {
                Some(skin) => {
                    skinned = true;
                    crate::character::skinned_influences(prim, &skin, &local, buffers, name)?
                }
                None => local
                    .iter()
                    .map(|&local| crate::character::Influence::Rigid {
                        local,
                        node: node.index(),
                    })
                    .collect(),
            };
            for inf in influences {
                raw.positions.push(character.add(inf));
            }
        }
    }

    let indices: Vec<usize> = match prim.indices() {
        None => (0..n).collect(),
        Some(acc) => {
            let size = match (acc.dimensions(), acc.data_type()) {
                (Dimensions::Scalar, DataType::U8) => 1,
                (Dimensions::Scalar, DataType::U16) => 2,
                (Dimensions::Scalar, DataType::U32) => 4,
                _ => {
                    return Err(err(
                        name,
                        format!(
                            "accessor {}: indices must be unsigned integer scalars",
                            acc.index()
                        ),
                    ))
                }
            };
            let (data, off, stride) = accessor_bytes(&acc, size, buffers, name)?;
            let mut v = Vec::with_capacity(acc.count());
            for k in 0..acc.count() {
                let o = off + k * stride;
                let i = match size {
                    1 => data[o] as usize,
                    2 => u16::from_le_bytes([data[o], data[o + 1]]) as usize,
                    _ => u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]])
                        as usize,
                };
                if i >= n {
                    return Err(err(
                        name,
                        format!(
                            "accessor {}: index {i} is out of range ({n} vertices)",
                            acc.index()
                        ),
                    ));
                }
                v.push(i);
            }
            v
        }
    };
    let tris: Vec<[usize; 3]> = match mode {
        Mode::Triangles => {
            if indices.len() % 3 != 0 {
                return Err(err(
                    name,
                    format!(
                        "a triangle list has {} indices, not a multiple of 3",
                        indices.len()
                    ),
                ));
            }
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect()
        }
        Mode::TriangleStrip => (2..indices.len())
            .map(|k| {
                let (a, b, c) = (indices[k - 2], indices[k - 1], indices[k]);
                if k % 2 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        _ => (2..indices.len())
            .map(|k| [indices[0], indices[k - 1], indices[k]])
            .collect(),
    };
    raw.reserve_triangles(tris.len(), name)?;
    // A mirroring transform turns the winding inside out.
    let mirror = !skinned && world.determinant() < 0.0;
    raw.triangles.extend(tris.into_iter().map(|[a, b, c]| {
        if mirror {
            [base + a, base + c, base + b]
        } else {
            [base + a, base + b, base + c]
        }
    }));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(decode_base64("TWFu").unwrap(), b"Man");
        assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
        assert_eq!(decode_base64("TQ==").unwrap(), b"M");
        assert!(decode_base64("T!==").is_none());
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("a%2"), "a%2");
    }

    /// 2.7 KB instancing 20 primitives of 99 vertices 100,000 times: refused before reading
    /// them, not after allocating gigabytes on the way to the triangle budget.
    #[test]
    fn instancing_amplification_is_refused_early() {
        let bytes = include_bytes!(
            "../../../tests/data/fuzz-regressions/gltf/instancing-amplification.gltf"
        );
        let e = read_gltf(bytes, "x.gltf", Externals::None, None).unwrap_err();
        assert!(e.to_string().contains("instances its meshes"), "{e}");
    }

    /// gltf-json's validation panicked on this out-of-range POSITION index (fuzzing).
    #[test]
    fn position_index_out_of_range_is_an_error() {
        let bytes = include_bytes!(
            "../../../tests/data/fuzz-regressions/gltf/position-accessor-out-of-range.gltf"
        );
        let e = read_gltf(bytes, "x.gltf", Externals::None, None).unwrap_err();
        assert!(
            e.to_string().contains("POSITION: Index out of range"),
            "{e}"
        );
    }
}
