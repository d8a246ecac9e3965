//! The step every reader ends with: check the raw triangles, weld, drop degenerate
//! triangles, turn an inward-facing surface outward, and describe the result.

use bvseg_core::{weld, Mesh};
use glam::DVec3;

use crate::report::MeshReport;
use crate::IoError;

/// Upper bound on the triangles a file may yield. A glTF scene can instance one mesh many
/// times, so its triangle count is not bounded by the file's size; this bound is.
pub const MAX_TRIANGLES: usize = 50_000_000;

/// Raw geometry as a reader produced it, before welding.
#[derive(Default)]
pub(crate) struct RawMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[usize; 3]>,
}

impl RawMesh {
    /// Fails once the triangle budget would be exceeded by `more` triangles.
    pub fn reserve_triangles(&self, more: usize, name: &str) -> Result<(), IoError> {
        if self.triangles.len().saturating_add(more) > MAX_TRIANGLES {
            return Err(IoError::Parse {
                name: name.to_owned(),
                line: None,
                message: format!("more than {MAX_TRIANGLES} triangles; refusing to load"),
            });
        }
        Ok(())
    }
}

/// A loaded mesh with what was changed on the way in, for the caller to report.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMesh {
    /// The welded, validated mesh.
    pub mesh: Mesh,
    /// What loading did to the file's data.
    pub stats: LoadStats,
    /// What the user should know about the mesh (pieces, holes, volume, ...).
    pub report: MeshReport,
    /// Indices, among the triangles read (after fanning polygons), of those dropped as
    /// degenerate, in increasing order: with them, per-triangle results can be mapped back
    /// to the file's triangles.
    pub dropped: Vec<usize>,
    /// What a skinned glTF file holds (joints, skins, animations, sampled poses); `None`
    /// for any other file. The mesh then carries its rig ([`bvseg_core::Mesh::rig`]).
    pub character: Option<crate::CharacterInfo>,
    /// A skinned glTF file's skins, skinning data and animations, for the GLB writer to
    /// write the mesh skinned and animated ([`crate::export::ExportOptions::skinning`]);
    /// `None` for any other file.
    pub skinning: Option<std::sync::Arc<crate::Skinning>>,
    /// The names of a skinned file's animations, indexed by [`bvseg_core::Pose::animation`]
    /// (a glTF animation without a name is called `animation N`, N its index in the file);
    /// empty for any other file.
    pub animations: Vec<String>,
}

impl LoadedMesh {
    /// Whether the surface encloses (next to) no volume, relative to its bounding box so
    /// that the test does not depend on units. Such a mesh cannot be segmented.
    pub fn encloses_no_volume(&self) -> bool {
        let r = &self.report;
        let size = r.bbox_max - r.bbox_min;
        let s = size.max_element();
        r.volume.abs() <= 1e-9 * s * s * s
    }

    /// What loading changed or found that a user should know, one line each: welded
    /// vertices and dropped triangles, then the report's warnings (see
    /// [`MeshReport::warnings`]).
    pub fn warnings(&self) -> Vec<String> {
        let s = self.stats;
        let mut w = Vec::new();
        if s.welded > 0 || s.degenerate > 0 {
            w.push(format!(
                "welded {} coincident vertices, dropped {} degenerate triangles",
                s.welded, s.degenerate
            ));
        }
        w.extend(self.report.warnings());
        w
    }
}

/// What loading changed, so that a front end can tell the user.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LoadStats {
    /// Vertices referenced by faces, before welding.
    pub vertices_read: usize,
    /// Vertices removed by welding exactly coincident positions.
    pub welded: usize,
    /// Triangles read, after fanning polygons.
    pub triangles_read: usize,
    /// Triangles dropped because two of their corners are the same vertex after welding.
    pub degenerate: usize,
}

/// Builds a [`LoadedMesh`] from vertex positions and vertex-index triangles held in memory,
/// by the same last step as the file readers ([`crate::load`]): exactly coincident
/// positions are welded, triangles degenerate after welding are dropped (and listed in
/// [`LoadedMesh::dropped`]), a mostly closed surface facing inward is turned outward, and the
/// report is made. The positions are kept in the order given, which the result depends on
/// (bit for bit) as a file's does: the OBJ reader passes the vertices the faces use, in the
/// order they first use them; the STL reader three per triangle; the glTF reader the
/// accessors' in buffer order. A loaded mesh fed back through this is unchanged. `name` is
/// what error messages call the mesh.
///
/// # Errors
///
/// [`IoError::Parse`] for a triangle that refers to a vertex that does not exist, a
/// non-finite coordinate or more than [`MAX_TRIANGLES`] triangles; [`IoError::NoTriangles`]
/// when no triangle is left; [`IoError::Mesh`] when [`bvseg_core::Mesh::new`] refuses the
/// result (a coordinate beyond [`bvseg_core::MAX_COORDINATE`]).
pub fn load_arrays(
    positions: Vec<DVec3>,
    triangles: Vec<[usize; 3]>,
    name: &str,
) -> Result<LoadedMesh, IoError> {
    let raw = RawMesh::default();
    raw.reserve_triangles(triangles.len(), name)?;
    let n = positions.len();
    for (index, t) in triangles.iter().enumerate() {
        if let Some(&vertex) = t.iter().find(|&&i| i >= n) {
            return Err(IoError::Parse {
                name: name.to_owned(),
                line: None,
                message: format!(
                    "triangle {index} refers to vertex {vertex}, but the mesh has only {n} vertices"
                ),
            });
        }
    }
    finish(
        RawMesh {
            positions,
            triangles,
        },
        name,
    )
}

/// Welds, validates and reports; see the module docs.
pub(crate) fn finish(raw: RawMesh, name: &str) -> Result<LoadedMesh, IoError> {
    let RawMesh {
        positions,
        triangles,
    } = raw;
    if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
        return Err(IoError::Parse {
            name: name.to_owned(),
            line: None,
            message: format!(
                "a vertex has a non-finite coordinate ({} {} {})",
                p.x, p.y, p.z
            ),
        });
    }
    // Indices become u32 in the mesh; a file within the size limit cannot exceed that, but an
    // in-memory reader is not bound by a file system.
    if positions.len() > u32::MAX as usize {
        return Err(IoError::Parse {
            name: name.to_owned(),
            line: None,
            message: "too many vertices (more than 2^32)".into(),
        });
    }
    let vertices_read = positions.len();
    let triangles_read = triangles.len();
    let (vertices, remap) = weld(&positions);
    let welded = vertices_read - vertices.len();
    let mut tris = Vec::with_capacity(triangles.len());
    let mut dropped = Vec::new();
    for (k, t) in triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| remap[i]);
        if a != b && b != c && a != c {
            tris.push([a, b, c]);
        } else {
            dropped.push(k);
        }
    }
    let degenerate = triangles_read - tris.len();
    if tris.is_empty() {
        return Err(IoError::NoTriangles {
            name: name.to_owned(),
            degenerate,
        });
    }
    let mut mesh = Mesh::new(vertices, tris).map_err(|source| IoError::Mesh {
        name: name.to_owned(),
        source,
    })?;
    let mut report = MeshReport::of(&mesh, false);
    // The core accepts either orientation, but engines and the `--with-mesh` output expect
    // outward faces; a mostly closed surface facing inward is almost always an export
    // mistake. An open sheet has no inside, so its "volume" says nothing about orientation.
    if report.volume < 0.0 && report.open_edges * 10 <= report.edges {
        let (v, t) = (mesh.vertices().to_vec(), mesh.triangles().to_vec());
        let t = t.into_iter().map(|[a, b, c]| [a, c, b]).collect();
        mesh = Mesh::new(v, t).map_err(|source| IoError::Mesh {
            name: name.to_owned(),
            source,
        })?;
        report.volume = -report.volume;
        report.flipped = true;
    }
    Ok(LoadedMesh {
        mesh,
        stats: LoadStats {
            vertices_read,
            welded,
            triangles_read,
            degenerate,
        },
        report,
        dropped,
        character: None,
        skinning: None,
        animations: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> (Vec<DVec3>, Vec<[usize; 3]>) {
        let (v, t) = bvseg_testkit::geometry::unit_cube();
        (
            v.into_iter().map(DVec3::from_array).collect(),
            t.iter().map(|t| t.map(|i| i as usize)).collect(),
        )
    }

    #[test]
    fn arrays_take_the_readers_path() {
        let (v, t) = cube();
        // Inward-facing, with a repeated vertex and a degenerate triangle: welded, dropped,
        // turned outward, as a file would be.
        let mut v2 = v.clone();
        v2.push(v[7]);
        let mut t2: Vec<[usize; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        t2[3] = [5, 6, 8];
        t2.push([0, 0, 1]);
        let loaded = load_arrays(v2, t2, "cube").unwrap();
        assert_eq!(loaded.stats.welded, 1);
        assert_eq!(loaded.stats.degenerate, 1);
        assert_eq!(loaded.dropped, [12]);
        assert!(loaded.report.flipped && loaded.report.volume > 0.0);
        // A loaded mesh fed back is unchanged.
        let again = load_arrays(
            loaded.mesh.vertices().to_vec(),
            loaded
                .mesh
                .triangles()
                .iter()
                .map(|t| t.map(|i| i as usize))
                .collect(),
            "cube",
        )
        .unwrap();
        assert_eq!(again.mesh, loaded.mesh);
        assert_eq!(
            load_arrays(v.clone(), t.clone(), "cube").unwrap().mesh,
            again.mesh
        );
    }

    #[test]
    fn bad_arrays_are_errors() {
        let (v, mut t) = cube();
        t[4] = [0, 1, 8];
        let e = load_arrays(v.clone(), t, "m").unwrap_err().to_string();
        assert_eq!(
            e,
            "m: triangle 4 refers to vertex 8, but the mesh has only 8 vertices"
        );
        let e = load_arrays(v.clone(), Vec::new(), "m")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "m: no triangles");
        let mut bad = v;
        bad[2].y = f64::NAN;
        let e = load_arrays(bad, cube().1, "m").unwrap_err().to_string();
        assert!(
            e.starts_with("m: a vertex has a non-finite coordinate"),
            "{e}"
        );
    }
}
