//! One welding rule and one closedness test, for every crate that needs them: vertices weld
//! when their coordinates are bit-identical (with -0.0 taken as 0.0), exactly what an
//! exporter that wrote the same vertex twice produces, and nothing a tolerance would guess.
use glam::DVec3;

use super::Mesh;

/// Merges vertices whose coordinates are bit-identical (with -0.0 taken as 0.0), keeping the
/// first occurrence and the order of first occurrences. Returns the distinct vertices and,
/// for each input vertex, its new index. Linear probing in a table keyed by the coordinate
/// bits: deterministic and O(n), where a sort of a triangle soup's vertices would dominate
/// the inside test. Only the first `u32::MAX` vertices are welded (indices are u32, so no
/// triangle can refer to the others).
pub fn weld(positions: &[DVec3]) -> (Vec<DVec3>, Vec<u32>) {
    // Every loader welds what it read, so this is where reading a file's vertices is counted.
    crate::work::add(positions.len());
    let n = positions.len().min(u32::MAX as usize);
    // +0.0 turns -0.0 into 0.0 so that both weld.
    let key = |p: DVec3| (p + DVec3::ZERO).to_array().map(f64::to_bits);
    let hash = |k: [u64; 3]| {
        let mut x = k[0] ^ k[1].rotate_left(21) ^ k[2].rotate_left(42);
        // splitmix64 finaliser.
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (x ^ (x >> 31)) as usize
    };
    let mask = (2 * n).next_power_of_two() - 1;
    // Each slot holds a new index (into `vertices`), or u32::MAX when empty.
    let mut table = vec![u32::MAX; mask + 1];
    let mut vertices = Vec::new();
    let mut remap = Vec::with_capacity(n);
    for &p in &positions[..n] {
        let k = key(p);
        let mut slot = hash(k) & mask;
        let id = loop {
            match table[slot] {
                u32::MAX => {
                    // At most n <= u32::MAX distinct vertices: the index fits.
                    let id = vertices.len() as u32;
                    vertices.push(p);
                    table[slot] = id;
                    break id;
                }
                j if key(vertices[j as usize]) == k => break j,
                _ => slot = (slot + 1) & mask,
            }
        };
        remap.push(id);
    }
    (vertices, remap)
}

impl Mesh {
    /// Whether the surface is closed: every edge is traversed equally often in both
    /// directions (the surface is a closed 2-cycle, so every ray's winding returns to 0).
    /// Equal positions under different indices (unwelded meshes) are merged first (by
    /// [`weld`]) if the indices alone do not close.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        let tris = self.triangles();
        let n = self.vertices().len();
        edges_balance(tris, n, |i| i) || {
            let (_, remap) = weld(self.vertices());
            edges_balance(tris, n, |i| remap[i as usize])
        }
    }
}

/// Whether the multiset of directed edges (vertex ids through `id`, all below `n`) equals
/// its reverse. Edges are bucketed by their smaller end (a counting sort), so only the few
/// edges around each vertex need comparing.
pub(crate) fn edges_balance(tris: &[[u32; 3]], n: usize, id: impl Fn(u32) -> u32) -> bool {
    let edges = || {
        tris.iter().flat_map(|t| {
            (0..3).filter_map(|e| {
                let (a, b) = (id(t[e]), id(t[(e + 1) % 3]));
                (a != b).then_some((a.min(b), a.max(b), a < b))
            })
        })
    };
    let mut start = vec![0usize; n + 1];
    for (lo, _, _) in edges() {
        start[lo as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut items = vec![0u64; start[n]];
    for (lo, hi, up) in edges() {
        items[fill[lo as usize]] = (u64::from(hi) << 1) | u64::from(up);
        fill[lo as usize] += 1;
    }
    (0..n).all(|v| {
        let bucket = &mut items[start[v]..start[v + 1]];
        bucket.sort_unstable();
        // Within each run of one edge, as many items going up as going down.
        bucket
            .chunk_by(|x, y| x >> 1 == y >> 1)
            .all(|run| 2 * run.iter().filter(|&&x| x & 1 == 1).count() == run.len())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_merges_equal_positions_only() {
        let v = [
            DVec3::new(0.0, 1.0, 2.0),
            DVec3::new(-0.0, 1.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0 + 1e-15),
            DVec3::new(0.0, 1.0, 2.0),
            DVec3::new(2.0, 1.0, 0.0),
        ];
        let (verts, remap) = weld(&v);
        assert_eq!(remap, vec![0, 0, 1, 0, 2]);
        assert_eq!(verts, vec![v[0], v[2], v[4]]);
    }

    #[test]
    fn closed_after_welding_open_with_a_hole() {
        // A tetrahedron as a triangle soup: each face has its own three vertices.
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let faces: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let soup: Vec<DVec3> = faces
            .iter()
            .flat_map(|f| f.map(|i| p[i as usize]))
            .collect();
        let tris: Vec<[u32; 3]> = (0..4).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        assert!(Mesh::new(soup.clone(), tris.clone()).unwrap().is_closed());
        assert!(!Mesh::new(soup, tris[..3].to_vec()).unwrap().is_closed());
        let indexed = Mesh::new(p.to_vec(), faces.to_vec()).unwrap();
        assert!(indexed.is_closed());
    }
}
