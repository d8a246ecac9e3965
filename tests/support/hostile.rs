//! Files built to be awkward rather than broken, at any size: the inputs of
//! `tests/linear_cost.rs` (the work grows at most linearly with the file) and of
//! `benches/hostile.rs` (their wall times). Each builder returns the file's bytes and a name
//! whose extension picks the reader.
#![allow(dead_code)]
use std::fmt::Write;

/// The unit cube's corners (OBJ indices 1 to 8) and its 12 outward triangles.
const CUBE_V: [[u8; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [1, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
];
const CUBE_F: [[usize; 3]; 12] = [
    [1, 3, 2],
    [2, 3, 4],
    [5, 6, 7],
    [6, 8, 7],
    [1, 2, 5],
    [2, 6, 5],
    [3, 7, 4],
    [4, 7, 8],
    [1, 5, 3],
    [3, 5, 7],
    [2, 4, 6],
    [4, 8, 6],
];

fn cube(out: &mut String, scale: f64, base: usize) {
    for v in CUBE_V {
        let [x, y, z] = v.map(|c| c as f64 * scale);
        writeln!(out, "v {x} {y} {z}").unwrap();
    }
    for f in CUBE_F {
        writeln!(out, "f {} {} {}", f[0] + base, f[1] + base, f[2] + base).unwrap();
    }
}

/// One polygon of `n` corners over the 4 corners of a tetrahedron (`f 1 2 3 4 1 2 3 4 ...`).
pub fn polygon(n: usize) -> (Vec<u8>, String) {
    let mut s = String::from("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 1\nf");
    for i in 0..n {
        write!(s, " {}", 1 + i % 4).unwrap();
    }
    s.push('\n');
    (s.into_bytes(), format!("polygon_{n}.obj"))
}

/// A closed cube plus `n` copies of one of its triangles.
pub fn duplicates(n: usize) -> (Vec<u8>, String) {
    let mut s = String::new();
    cube(&mut s, 1.0, 0);
    for _ in 0..n {
        s.push_str("f 1 3 2\n");
    }
    (s.into_bytes(), format!("duplicates_{n}.obj"))
}

/// A closed cube plus `n` vertices no face uses.
pub fn unused_vertices(n: usize) -> (Vec<u8>, String) {
    let mut s = String::new();
    cube(&mut s, 1.0, 0);
    let mut r = Lcg(7);
    for _ in 0..n {
        writeln!(s, "v {:.6} {:.6} {:.6}", r.next(), r.next(), r.next()).unwrap();
    }
    (s.into_bytes(), format!("unused_{n}.obj"))
}

/// A closed cube whose every face is a fan of about `n / 6` sliver triangles from one
/// corner to the two far edges.
pub fn slivers(n: usize) -> (Vec<u8>, String) {
    let m = (n / 12).max(1);
    let mut s = String::new();
    let mut count = 0;
    for axis in 0..3 {
        for side in [0.0, 1.0] {
            let at = |u: f64, v: f64| {
                let mut p = [0.0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                p
            };
            let mut ring = vec![at(0.0, 0.0)];
            ring.extend((0..=m).map(|i| at(1.0, i as f64 / m as f64)));
            ring.extend((1..=m).map(|i| at(1.0 - i as f64 / m as f64, 1.0)));
            for p in &ring {
                writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
            }
            let c = count + 1;
            for i in 1..ring.len() - 1 {
                let (a, b) = (count + 1 + i, count + 2 + i);
                // Outward: counter-clockwise seen from outside.
                if side == 1.0 {
                    writeln!(s, "f {c} {a} {b}").unwrap();
                } else {
                    writeln!(s, "f {c} {b} {a}").unwrap();
                }
            }
            count += ring.len();
        }
    }
    (s.into_bytes(), format!("slivers_{n}.obj"))
}

/// `n` disjoint tetrahedra of side 0.01 scattered in a box of side 10.
pub fn tiny_tetrahedra(n: usize) -> (Vec<u8>, String) {
    let mut s = String::new();
    let mut r = Lcg(11);
    for t in 0..n {
        let [x, y, z] = [r.next(), r.next(), r.next()].map(|c| 10.0 * c);
        let e = 0.01;
        writeln!(
            s,
            "v {x} {y} {z}\nv {} {y} {z}\nv {x} {} {z}\nv {x} {y} {}",
            x + e,
            y + e,
            z + e
        )
        .unwrap();
        let b = 4 * t;
        for f in [[1, 3, 2], [1, 2, 4], [1, 4, 3], [2, 3, 4]] {
            writeln!(s, "f {} {} {}", b + f[0], b + f[1], b + f[2]).unwrap();
        }
    }
    (s.into_bytes(), format!("tetrahedra_{n}.obj"))
}

/// `n` distinct triangles, each spanning the whole bounding box (a fan of huge slivers).
pub fn huge_fan(n: usize) -> (Vec<u8>, String) {
    let mut s = String::from("v 0 0 0\n");
    for i in 0..n {
        let e = i as f64 * 1e-6;
        writeln!(s, "v 1 {e} 0\nv 0 1 {}", 1.0 + e).unwrap();
    }
    for i in 0..n {
        writeln!(s, "f 1 {} {}", 2 + 2 * i, 3 + 2 * i).unwrap();
    }
    (s.into_bytes(), format!("huge_fan_{n}.obj"))
}

/// `n` nested closed cubes, each 1e-4 larger than the last.
pub fn nested_cubes(n: usize) -> (Vec<u8>, String) {
    let mut s = String::new();
    for c in 0..n {
        cube(&mut s, 1.0 + c as f64 * 1e-4, 8 * c);
    }
    (s.into_bytes(), format!("nested_{n}.obj"))
}

/// Binary STL: a closed cube plus `n` copies of one of its triangles.
pub fn stl_duplicates(n: usize) -> (Vec<u8>, String) {
    let tris: Vec<[usize; 3]> = CUBE_F
        .iter()
        .copied()
        .chain(std::iter::repeat_n(CUBE_F[0], n))
        .collect();
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in &tris {
        b.extend_from_slice(&[0; 12]);
        for &i in t {
            for c in CUBE_V[i - 1] {
                b.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0; 2]);
    }
    (b, format!("duplicates_{n}.stl"))
}

/// A builder: the file's bytes and name for a size parameter.
pub type Builder = fn(usize) -> (Vec<u8>, String);

/// Every family, by name.
pub const FAMILIES: &[(&str, Builder)] = &[
    ("polygon", polygon),
    ("duplicates", duplicates),
    ("unused_vertices", unused_vertices),
    ("slivers", slivers),
    ("tiny_tetrahedra", tiny_tetrahedra),
    ("huge_fan", huge_fan),
    ("nested_cubes", nested_cubes),
    ("stl_duplicates", stl_duplicates),
];

/// A small deterministic generator of numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
