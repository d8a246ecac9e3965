//! Small closed meshes for the tests of every crate, as plain arrays (vertex positions and
//! outward-facing index triples), so that this crate needs none of bvseg's and each test
//! converts to the types it tests.

/// A mesh as arrays: vertex positions and outward-facing triangles indexing them.
pub type Arrays = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// The 12 outward-facing triangles of a box whose 8 corners are numbered by their bits:
/// corner `i` is at the high end of x when `i & 1`, of y when `i & 2`, of z when `i & 4`.
pub const BOX_TRIANGLES: [[u32; 3]; 12] = [
    [0, 2, 1],
    [1, 2, 3],
    [4, 5, 6],
    [5, 7, 6],
    [0, 1, 4],
    [1, 5, 4],
    [2, 6, 3],
    [3, 6, 7],
    [0, 4, 2],
    [2, 4, 6],
    [1, 3, 5],
    [3, 7, 5],
];

/// The axis-aligned box `[lo, hi]`: 8 corners numbered as in [`BOX_TRIANGLES`], 12
/// triangles.
#[must_use]
pub fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Arrays {
    let v = (0..8)
        .map(|i| {
            let bit = [i & 1, (i >> 1) & 1, (i >> 2) & 1];
            std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * bit[a] as f64)
        })
        .collect();
    (v, BOX_TRIANGLES.to_vec())
}

/// The unit cube `[0, 1]^3`, as [`cuboid`].
#[must_use]
pub fn unit_cube() -> Arrays {
    cuboid([0.0; 3], [1.0; 3])
}

/// The regular icosahedron with vertices `(0, ±1, ±t)` and its cyclic permutations (`t` the
/// golden ratio, so the vertices are not on the unit sphere), and its 20 outward faces.
#[must_use]
pub fn icosahedron() -> ([[f64; 3]; 12], [[usize; 3]; 20]) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let f = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (v, f)
}

/// The sphere of radius `r` about `c` as an icosahedron whose faces are split in four
/// `subdiv` times, new vertices pushed out to the sphere: `20 * 4^subdiv` triangles, indexed
/// (edges share their midpoints).
#[must_use]
pub fn icosphere(subdiv: usize, r: f64, c: [f64; 3]) -> Arrays {
    // As glam's `DVec3::normalize` rounds, so that tests moved here keep their exact points.
    let normalize = |p: [f64; 3]| {
        let inv = 1.0 / (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|x| x * inv)
    };
    let (base, faces) = icosahedron();
    let mut v: Vec<[f64; 3]> = base.iter().map(|&p| normalize(p)).collect();
    let mut f: Vec<[usize; 3]> = faces.to_vec();
    for _ in 0..subdiv {
        let mut mid = std::collections::HashMap::new();
        let mut m = |a: usize, b: usize, v: &mut Vec<[f64; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (pa, pb) = (v[a], v[b]);
                v.push(normalize(std::array::from_fn(|k| pa[k] + pb[k])));
                v.len() - 1
            })
        };
        f = f
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (m(a, b, &mut v), m(b, c, &mut v), m(c, a, &mut v));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (
        v.iter()
            .map(|p| std::array::from_fn(|k| c[k] + r * p[k]))
            .collect(),
        f.iter().map(|t| t.map(|i| i as u32)).collect(),
    )
}
