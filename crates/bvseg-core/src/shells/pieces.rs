//! A mesh's pieces (connected components) and what each one is: a solid the lattice can
//! sample, or a shell (open, or too thin for the lattice) that only its surface can bound.
use std::collections::HashMap;

use glam::DVec3;

use crate::mesh::Mesh;

/// Share of a piece's area its holes may have and the piece still count as a solid: a scan
/// with a few small holes is a solid with holes, an open box is a shell.
const HOLES: f64 = 0.05;

/// One connected piece of a mesh.
#[derive(Debug, Clone)]
pub struct Piece {
    /// Its triangles (indices into the mesh's).
    pub triangles: Vec<u32>,
    /// Its surface area.
    pub area: f64,
    /// The area of its holes: the sum of the vector areas of its boundary loops.
    pub holes: f64,
    /// Its volume by the divergence theorem (exact when closed, about right with small holes).
    pub volume: f64,
}

impl Piece {
    /// Whether the piece is a solid a lattice of cell size `h` samples: holes at most
    /// [`HOLES`] of its area, and at least two cells thick on average (for a slab of
    /// thickness `d`, `2 V / A` is `d`; for a rod of radius `r`, `r`).
    pub fn is_solid(&self, h: f64) -> bool {
        self.is_closed() && self.volume.abs() >= h * self.area
    }

    /// Whether the piece is closed up to holes of at most [`HOLES`] of its area.
    pub fn is_closed(&self) -> bool {
        self.holes <= HOLES * self.area
    }
}

/// The cell size of the lattice that `samples` samples of `pieces`' solid would get.
pub fn cell_size(pieces: &[Piece], samples: usize) -> f64 {
    let v: f64 = pieces.iter().map(|p| p.volume.abs()).sum();
    (v / samples.max(1) as f64).cbrt()
}

/// The pieces of `mesh`: triangles sharing a vertex position belong to one piece. In the
/// order of their first triangle.
pub fn pieces(mesh: &Mesh) -> Vec<Piece> {
    let v = mesh.vertices();
    // Vertices at one position are one vertex here, whatever the loader welded.
    let mut at: HashMap<[u64; 3], u32> = HashMap::new();
    let id: Vec<u32> = v
        .iter()
        .enumerate()
        .map(|(i, p)| *at.entry(p.to_array().map(f64::to_bits)).or_insert(i as u32))
        .collect();
    let mut parent: Vec<u32> = (0..v.len() as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let tris = mesh.triangles();
    for t in tris {
        let a = find(&mut parent, id[t[0] as usize]);
        for &c in &t[1..] {
            let b = find(&mut parent, id[c as usize]);
            if a != b {
                let (lo, hi) = (a.min(b), a.max(b));
                parent[hi as usize] = lo;
            }
        }
    }
    let mut index: HashMap<u32, usize> = HashMap::new();
    let mut out: Vec<Vec<u32>> = Vec::new();
    for (t, tri) in tris.iter().enumerate() {
        let root = find(&mut parent, id[tri[0] as usize]);
        let i = *index.entry(root).or_insert_with(|| {
            out.push(Vec::new());
            out.len() - 1
        });
        out[i].push(t as u32);
    }
    out.into_iter()
        .map(|triangles| measure(mesh, &id, triangles))
        .collect()
}

fn measure(mesh: &Mesh, id: &[u32], triangles: Vec<u32>) -> Piece {
    let v = mesh.vertices();
    let (mut area, mut volume) = (0.0, 0.0);
    let origin = v[mesh.triangles()[triangles[0] as usize][0] as usize];
    // Directed edges; an edge without its reverse is on a hole's boundary.
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for &t in &triangles {
        let [a, b, c] = mesh.corners(t as usize);
        area += 0.5 * (b - a).cross(c - a).length();
        volume += (a - origin).dot((b - origin).cross(c - origin)) / 6.0;
        let ids = mesh.triangles()[t as usize].map(|i| id[i as usize]);
        for e in 0..3 {
            let (p, q) = (ids[e], ids[(e + 1) % 3]);
            if p == q {
                continue;
            }
            *edges.entry((p, q)).or_default() += 1;
            *edges.entry((q, p)).or_default() -= 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut open: Vec<(u32, u32)> = edges
        .iter()
        .filter(|(_, &n)| n > 0)
        .map(|(&e, _)| e)
        .collect();
    open.sort_unstable();
    for &(p, q) in &open {
        next.entry(p).or_default().push(q);
    }
    // Walk the boundary loops; each loop's vector area is the area of the hole it rims.
    let mut holes = 0.0;
    for &(start, _) in &open {
        let Some(first) = next.get_mut(&start).and_then(Vec::pop) else {
            continue;
        };
        let (mut sum, mut at) = (DVec3::ZERO, first);
        let p0 = v[start as usize];
        let mut prev = start;
        for _ in 0..open.len() {
            sum += (v[prev as usize] - p0).cross(v[at as usize] - p0);
            if at == start {
                break;
            }
            prev = at;
            match next.get_mut(&at).and_then(Vec::pop) {
                Some(n) => at = n,
                None => break,
            }
        }
        holes += 0.5 * sum.length();
    }
    Piece {
        triangles,
        area,
        holes,
        volume,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DMat3;

    #[test]
    fn a_closed_box_is_one_solid_piece_and_an_open_one_a_shell() {
        let b = shapes::ellipsoid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY, 12);
        let p = pieces(&b);
        assert_eq!(p.len(), 1);
        assert!(p[0].holes < 1e-9 * p[0].area);
        assert!(p[0].is_solid(0.01));
        // Drop a quarter of the triangles: a bowl with a wide rim.
        let keep: Vec<[u32; 3]> = b.triangles()[..b.triangles().len() * 3 / 4].to_vec();
        let open = Mesh::new(b.vertices().to_vec(), keep).unwrap();
        let p = pieces(&open);
        assert!(
            p.iter().all(|p| !p.is_solid(0.01)),
            "{:?}",
            p.iter().map(|p| p.holes / p.area).collect::<Vec<_>>()
        );
    }

    #[test]
    fn two_apart_boxes_are_two_pieces() {
        let a = shapes::ellipsoid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY, 8);
        let n = a.vertices().len() as u32;
        let mut v = a.vertices().to_vec();
        v.extend(a.vertices().iter().map(|p| *p + DVec3::X * 5.0));
        let mut t = a.triangles().to_vec();
        t.extend(a.triangles().iter().map(|t| t.map(|i| i + n)));
        let m = Mesh::new(v, t).unwrap();
        let p = pieces(&m);
        assert_eq!(p.len(), 2);
        assert!((p[0].volume - p[1].volume).abs() < 1e-9);
    }
}
