//! A corpus of malformed and hostile mesh files, written by the test: each must end in one
//! error line naming the file, exit code 2, no panic and no output file. Merely imperfect
//! meshes must work with a warning.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;
use std::process::{Command, Output};

use bvseg_testkit::{scratch, BUNNY};

const BIN: &str = env!("CARGO_BIN_EXE_bvseg");

/// Runs `bvseg` in `dir`. On Unix the address space is capped at 2 GiB, so that an
/// allocation sized by a lying count in a file would fail the run instead of passing.
fn bvseg(dir: &Path, args: &[&str]) -> Output {
    #[cfg(unix)]
    {
        let mut script = String::from("ulimit -v 2097152; exec \"$0\"");
        for (i, _) in args.iter().enumerate() {
            script += &format!(" \"${}\"", i + 1);
        }
        Command::new("sh")
            .current_dir(dir)
            .arg("-c")
            .arg(script)
            .arg(BIN)
            .args(args)
            .output()
            .unwrap()
    }
    #[cfg(not(unix))]
    bvseg_testkit::run(BIN, dir, args)
}

fn pseudo_random(n: usize, seed: u32) -> Vec<u8> {
    let mut x = seed.wrapping_mul(2654435761) | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 7) as u8
        })
        .collect()
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// One triangle's worth of glTF around `bin`, with accessor `count` and buffer length
/// `byte_length` as given (so that they can lie).
fn tri_gltf(uri: &str, byte_length: usize, count: usize, indices: bool) -> String {
    let idx = if indices { r#","indices":1"# } else { "" };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{idx}}}]}}],
"buffers":[{{{uri}"byteLength":{byte_length}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{byte_length}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
{{"bufferView":0,"componentType":5125,"count":3,"type":"SCALAR"}}]}}"#
    )
}

fn tetra_bin() -> Vec<u8> {
    [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect()
}

/// Every file of the corpus: (name, bytes, a word the error must contain).
fn corpus() -> Vec<(String, Vec<u8>, &'static str)> {
    let mut c: Vec<(String, Vec<u8>, &'static str)> = Vec::new();
    let mut add = |n: &str, b: Vec<u8>, w: &'static str| c.push((n.to_owned(), b, w));
    for ext in ["obj", "stl", "gltf", "glb"] {
        add(&format!("empty.{ext}"), vec![], "");
        add(
            &format!("random.{ext}"),
            pseudo_random(4096, ext.len() as u32 + 7),
            "",
        );
    }
    add(
        "comments.obj",
        b"# nothing\n# here\n\n".to_vec(),
        "no triangles",
    );
    add(
        "truncated.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1".to_vec(),
        "line 3",
    );
    add(
        "nan.obj",
        b"v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n".to_vec(),
        "non-finite",
    );
    add("inf.stl", b"solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex inf 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n".to_vec(), "non-finite");
    add(
        "huge.obj",
        b"v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nv 0 0 1e300\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
            .to_vec(),
        "out-of-range",
    );
    add(
        "bad_index.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(),
        "does not exist",
    );
    add(
        "garbage_index.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x9\n".to_vec(),
        "bad face",
    );
    add(
        "huge_index.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 184467440737095516160\n".to_vec(),
        "bad face",
    );
    let mut ngon = String::new();
    for i in 0..5000 {
        let a = i as f64 * std::f64::consts::TAU / 5000.0;
        ngon += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    ngon += "f";
    for i in 1..=5000 {
        ngon += &format!(" {i}");
    }
    add("thousand_gon.obj", (ngon + "\n").into_bytes(), "no volume");
    add(
        "no_triangles.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n".to_vec(),
        "no triangles",
    );
    add(
        "one_triangle.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        "no volume",
    );
    add(
        "zero_volume.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n".to_vec(),
        "no volume",
    );
    add(
        "collinear.obj",
        b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 1 3 4\nf 2 4 3\n".to_vec(),
        "no volume",
    );
    add("degenerate.stl", b"solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n".to_vec(), "no triangles");
    add(
        "truncated_ascii.stl",
        b"solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\n".to_vec(),
        "truncated",
    );
    // Binary STL announcing 10^9 triangles in a 184-byte file.
    let mut stl = vec![0u8; 80];
    stl.extend(1_000_000_000u32.to_le_bytes());
    stl.extend(vec![0u8; 100]);
    add("lying_count.stl", stl, "announces 1000000000 triangles");
    // glTF: accessor past the end of its buffer, missing buffer file, no buffers at all.
    let bin = tetra_bin();
    let data = |b: &[u8]| {
        const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::from(r#""uri":"data:application/octet-stream;base64,"#);
        for ch in b.chunks(3) {
            let n = (ch[0] as u32) << 16
                | (*ch.get(1).unwrap_or(&0) as u32) << 8
                | *ch.get(2).unwrap_or(&0) as u32;
            for k in 0..4 {
                s.push(if k <= ch.len() {
                    A[(n >> (18 - 6 * k)) as usize & 63] as char
                } else {
                    '='
                });
            }
        }
        s + "\","
    };
    add(
        "accessor_past_end.gltf",
        tri_gltf(&data(&bin), bin.len(), 1_000_000_000, false).into_bytes(),
        "runs past the end",
    );
    let mut with_indices = bin.clone();
    with_indices.extend([0u32, 1, 7].iter().flat_map(|i| i.to_le_bytes()));
    let doc = tri_gltf("", 48, 3, true).replace(
        r#"{"bufferView":0,"componentType":5125"#,
        r#"{"bufferView":0,"byteOffset":36,"componentType":5125"#,
    );
    add(
        "index_out_of_range.glb",
        glb(&doc, &with_indices),
        "index 7 is out of range",
    );
    add(
        "short_buffer.gltf",
        tri_gltf(&data(&bin), 4000, 3, false).into_bytes(),
        "declares 4000 bytes",
    );
    add(
        "missing_file.gltf",
        tri_gltf(r#""uri":"nowhere.bin","#, 36, 3, false).into_bytes(),
        "nowhere.bin",
    );
    add("no_buffers.gltf", br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}]}"#.to_vec(), "invalid glTF");
    add(
        "no_bin_chunk.glb",
        {
            let mut g = glb(&tri_gltf("", 36, 3, false), &[]);
            let n = g.len() - 8;
            g.truncate(n);
            g[8..12].copy_from_slice(&(n as u32).to_le_bytes());
            g
        },
        "BIN chunk",
    );
    add("cyclic_nodes.gltf", br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"children":[1,1]},{"children":[0,0]}]}"#.to_vec(), "cyclic");
    // GLB headers that lie.
    let good = glb(&tri_gltf("", 36, 3, false), &bin);
    let mut short = good.clone();
    short[8..12].copy_from_slice(&8u32.to_le_bytes());
    add("header_length_8.glb", short, "bad GLB header");
    let mut long = good.clone();
    long[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    add("header_length_huge.glb", long, "bad GLB header");
    let mut chunk = good.clone();
    chunk[12..16].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    add("chunk_length_huge.glb", chunk, "runs past the end");
    add(
        "truncated.glb",
        good[..good.len() / 2].to_vec(),
        "bad GLB header",
    );
    add("tiny.glb", b"glTF\x02\x00".to_vec(), "truncated GLB header");
    c
}

#[test]
fn every_bad_file_is_one_clean_error() {
    let dir = scratch("every_bad_file_is_one_clean_error");
    let corpus = corpus();
    for (name, bytes, _) in &corpus {
        fs::write(dir.join(name), bytes).unwrap();
    }
    for (name, _, word) in &corpus {
        for sub in ["segment", "info"] {
            let o = if sub == "segment" {
                bvseg(
                    &dir,
                    &[
                        "segment",
                        name,
                        "--samples",
                        "2000",
                        "-o",
                        "out.json",
                        "-o",
                        "out.glb",
                        "--labels",
                        "l.txt",
                    ],
                )
            } else {
                bvseg(&dir, &["info", name])
            };
            let err = String::from_utf8_lossy(&o.stderr);
            if sub == "info" && o.status.success() {
                // `info` reports meshes without volume instead of failing on them.
                assert!(word.contains("no volume"), "{name}: info succeeded: {err}");
                continue;
            }
            assert_eq!(o.status.code(), Some(2), "{sub} {name}: {err}");
            assert_eq!(err.lines().count(), 1, "{sub} {name}: {err}");
            assert!(
                err.starts_with(&format!("bvseg: error: {name}: ")),
                "{sub} {name}: {err}"
            );
            let message = &err[format!("bvseg: error: {name}: ").len()..];
            assert!(
                message.contains(word),
                "{sub} {name}: {word:?} not in {err}"
            );
            assert!(o.stdout.is_empty(), "{sub} {name}");
        }
    }
    // No output file, not even a temporary one.
    let mut left: Vec<String> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let mut names: Vec<String> = corpus.into_iter().map(|c| c.0).collect();
    names.sort();
    assert_eq!(left, names);
}

#[test]
fn imperfect_meshes_work_with_a_warning() {
    let dir = scratch("imperfect_meshes_work_with_a_warning");
    let text = fs::read_to_string(BUNNY).unwrap();
    let (verts, faces): (Vec<&str>, Vec<&str>) = text
        .lines()
        .filter(|l| l.starts_with("v ") || l.starts_with("f "))
        .partition(|l| l.starts_with("v "));
    let write = |name: &str, faces: &[String]| {
        fs::write(
            dir.join(name),
            format!("{}\n{}\n", verts.join("\n"), faces.join("\n")),
        )
        .unwrap();
    };
    let flip = |f: &str| {
        let w: Vec<&str> = f.split_whitespace().collect();
        format!("f {} {} {}", w[1], w[3], w[2])
    };
    let all: Vec<String> = faces.iter().map(|f| f.to_string()).collect();
    write(
        "inward.obj",
        &all.iter().map(|f| flip(f)).collect::<Vec<_>>(),
    );
    write("hole.obj", &all[1..]);
    let mut dup = all.clone();
    dup.extend(all[..20].iter().cloned());
    write("duplicates.obj", &dup);
    for (name, warning) in [
        ("inward.obj", "orientation was reversed"),
        ("hole.obj", "3 open edges"),
        ("duplicates.obj", "20 duplicate faces"),
    ] {
        let o = bvseg(
            &dir,
            &[
                "segment",
                name,
                "--samples",
                "2000",
                "--k",
                "2",
                "-o",
                "o.json",
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{name}: {err}");
        assert!(
            err.contains(&format!("bvseg: warning: {name}: ")) && err.contains(warning),
            "{name}: {err}"
        );
        let info = bvseg(&dir, &["info", name]);
        assert!(info.status.success());
        assert!(
            String::from_utf8_lossy(&info.stdout).contains(warning),
            "{name}"
        );
    }
}
