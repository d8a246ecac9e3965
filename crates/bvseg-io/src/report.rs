//! What a user should know about a loaded mesh: its size, its pieces, its defects.
use std::collections::{HashMap, HashSet};

use bvseg_core::Mesh;
use glam::DVec3;

/// Facts about a loaded (welded) mesh. The defects listed here are warnings: the core's
/// inside test tolerates small holes, duplicated faces and either orientation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshReport {
    /// Triangles after welding and dropping degenerate ones.
    pub triangles: usize,
    /// Vertices after welding.
    pub vertices: usize,
    /// Edge-connected pieces of the surface.
    pub components: usize,
    /// Distinct edges.
    pub edges: usize,
    /// Edges used by a single triangle (borders of holes).
    pub open_edges: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Triangles that repeat another one's three vertices.
    pub duplicate_faces: usize,
    /// Whether the whole surface faced inward and was turned outward.
    pub flipped: bool,
    /// Enclosed volume (signed, after the flip; positive for a sound mesh).
    pub volume: f64,
    /// Lower corner of the bounding box.
    pub bbox_min: DVec3,
    /// Upper corner of the bounding box.
    pub bbox_max: DVec3,
}

impl MeshReport {
    /// Measures `mesh`; `flipped` says whether loading reversed its orientation.
    pub fn of(mesh: &Mesh, flipped: bool) -> Self {
        let tris = mesh.triangles();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3 / 2);
        let mut faces: HashSet<[u32; 3]> = HashSet::with_capacity(tris.len());
        let mut duplicate_faces = 0;
        let mut parent: Vec<u32> = (0..mesh.vertices().len() as u32).collect();
        for t in tris {
            let mut key = *t;
            key.sort_unstable();
            if !faces.insert(key) {
                duplicate_faces += 1;
            }
            for j in 0..3 {
                let (a, b) = (t[j], t[(j + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
                union(&mut parent, a, b);
            }
        }
        let used: HashSet<u32> = tris
            .iter()
            .flatten()
            .map(|&v| find(&mut parent, v))
            .collect();
        let (bbox_min, bbox_max) = mesh.bbox();
        Self {
            triangles: tris.len(),
            vertices: mesh.vertices().len(),
            components: used.len(),
            edges: edges.len(),
            open_edges: edges.values().filter(|&&c| c == 1).count(),
            non_manifold_edges: edges.values().filter(|&&c| c > 2).count(),
            duplicate_faces,
            flipped,
            volume: mesh.signed_volume(),
            bbox_min,
            bbox_max,
        }
    }

    /// One line per defect worth telling the user about, empty for a clean closed mesh.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.open_edges > 0 {
            w.push(format!(
                "{} open edges (the surface has holes; small ones are tolerated)",
                self.open_edges
            ));
        }
        if self.non_manifold_edges > 0 {
            w.push(format!(
                "{} non-manifold edges (used by more than two triangles)",
                self.non_manifold_edges
            ));
        }
        if self.duplicate_faces > 0 {
            w.push(format!("{} duplicate faces", self.duplicate_faces));
        }
        if self.flipped {
            w.push("the surface faced inward; its orientation was reversed".into());
        }
        w
    }
}

fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        // Path halving keeps the trees shallow without recursion.
        let p = parent[v as usize];
        parent[v as usize] = parent[p as usize];
        v = p;
    }
    v
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        // The smaller root wins, so the result does not depend on the order of unions.
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}
