//! The bundled sample meshes, and turning file bytes into a mesh.
use bvseg_core::Mesh;

/// A sample mesh compiled into the viewer (licences in `assets/meshes/README.md` and
/// `assets/characters/README.md`).
#[derive(Debug, Clone, Copy)]
pub struct BundledMesh {
    /// Name used in the menu and in the page's `?mesh=NAME` parameter (the file stem).
    pub name: &'static str,
    /// File name, which also selects the reader.
    pub file: &'static str,
    /// What it shows and where it comes from.
    pub about: &'static str,
    /// The file's content.
    pub bytes: &'static [u8],
}

/// Every bundled mesh; the first is the default.
pub const BUNDLED: &[BundledMesh] = &[
    BundledMesh {
        name: "bunny",
        file: "bunny.obj",
        about: "Stanford bunny, low resolution (public domain)",
        bytes: include_bytes!("../../../assets/meshes/bunny.obj"),
    },
    BundledMesh {
        name: "spot",
        file: "spot.obj",
        about: "Spot the cow, by Keenan Crane (public domain)",
        bytes: include_bytes!("../../../assets/meshes/spot.obj"),
    },
    BundledMesh {
        name: "fourleg_2",
        file: "fourleg_2.obj",
        about: "Dog, Princeton Segmentation Benchmark model 398",
        bytes: include_bytes!("../../../assets/meshes/fourleg_2.obj"),
    },
    // The small one of the bundled characters. The other, CesiumMan (665 KB), is opened as a
    // file: compiled in, every visitor of the page would download it.
    BundledMesh {
        name: "RiggedSimple",
        file: "RiggedSimple.glb",
        about:
            "A skinned, animated cylinder: glTF sample model Rigged Simple (CC-BY 4.0, © Cesium)",
        bytes: include_bytes!("../../../assets/characters/RiggedSimple.glb"),
    },
];

/// The bundled mesh called `name` (its stem, or its file name).
pub fn bundled(name: &str) -> Option<&'static BundledMesh> {
    BUNDLED.iter().find(|m| m.name == name || m.file == name)
}

/// Loads a bundled mesh; the bundled files are valid, but the error path is kept honest.
///
/// # Errors
///
/// As [`load_mesh_bytes`].
pub fn load_bundled(m: &BundledMesh) -> Result<Mesh, String> {
    load_mesh_bytes(m.bytes, m.file).map(|l| l.mesh)
}

/// The formats [`load_mesh_bytes`] reads, as a hint for the user and as the `accept`
/// attribute of the browser's file dialog (`bvseg_io::MESH_EXTENSIONS`, checked by a test).
pub const SUPPORTED: &str = ".obj, .gltf, .glb, .stl";

/// A mesh read from a file, with what the user should know about it.
#[derive(Debug, Clone)]
pub struct LoadedFile {
    /// The welded, validated mesh.
    pub mesh: Mesh,
    /// One line per thing loading changed or found wrong (welded vertices, holes, ...).
    pub warnings: Vec<String>,
    /// The names of a skinned glTF character's animations (indexed by
    /// [`bvseg_core::Pose::animation`]); empty for any other file.
    pub animations: Vec<String>,
}

/// Turns the bytes of a mesh file into a mesh through [`bvseg_io::load_bytes`] (OBJ, glTF,
/// GLB, STL), choosing the reader by `name`'s extension, with the load warnings and whether
/// the mesh encloses no volume as one list of lines for the UI. Every way into the viewer
/// (bundled meshes, open file, drag and drop, the command line) goes through here. The error
/// is one line naming the file; a `.gltf` whose buffers are separate files cannot be read
/// from bytes alone, and its error says to use `.glb` or embedded buffers.
///
/// # Errors
///
/// The reader's error ([`bvseg_io::IoError`]) as one line naming the file.
pub fn load_mesh_bytes(bytes: &[u8], name: &str) -> Result<LoadedFile, String> {
    let loaded = bvseg_io::load_bytes(bytes, name, &bvseg_io::LoadOptions::default())
        .map_err(|e| e.to_string())?;
    let mut warnings = loaded.warnings();
    if loaded.encloses_no_volume() {
        warnings.push("the mesh encloses no volume (flat or open): it cannot be segmented".into());
    }
    Ok(LoadedFile {
        mesh: loaded.mesh,
        warnings,
        animations: loaded.animations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bundled_mesh_loads() {
        for m in BUNDLED {
            let mesh = load_bundled(m).unwrap();
            assert!(mesh.triangles().len() > 800, "{}", m.name);
            // The character comes with its skeleton and its animation's poses.
            let poses = mesh
                .rig()
                .and_then(|r| r.skin.as_ref())
                .map_or(0, |s| s.poses.len());
            assert_eq!(poses > 0, m.file.ends_with(".glb"), "{}", m.name);
            assert!(bundled(m.name).is_some() && bundled(m.file).is_some());
        }
        assert!(bundled("nope").is_none());
    }

    #[test]
    fn bad_input_gives_one_line_errors_naming_the_file() {
        let e = load_mesh_bytes(b"v 0 0 0\nf 1 2 3\n", "broken.obj").unwrap_err();
        assert!(e.contains("broken.obj") && !e.contains('\n'), "{e}");
        let e = load_mesh_bytes(b"solid", "model.xyz").unwrap_err();
        assert!(e.contains("model.xyz") && e.contains(".xyz"), "{e}");
        let e = load_mesh_bytes(b"", "README").unwrap_err();
        assert!(e.contains("README"), "{e}");
        let e = load_mesh_bytes(b"solid x\nendsolid x\n", "empty.stl").unwrap_err();
        assert!(e.contains("empty.stl") && !e.contains('\n'), "{e}");
    }

    #[test]
    fn the_dialog_accepts_every_format_the_library_reads() {
        let listed: Vec<&str> = SUPPORTED.split(", ").collect();
        let expected: Vec<String> = bvseg_io::MESH_EXTENSIONS
            .iter()
            .map(|e| format!(".{e}"))
            .collect();
        assert_eq!(listed, expected);
    }

    #[test]
    fn ascii_stl_loads_with_its_welding_reported() {
        // A tetrahedron, each triangle with its own corners.
        let p = ["0 0 0", "1 0 0", "0 1 0", "0 0 1"];
        let mut stl = String::from("solid t\n");
        for t in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            stl.push_str("facet normal 0 0 0\nouter loop\n");
            for i in t {
                stl.push_str(&format!("vertex {}\n", p[i]));
            }
            stl.push_str("endloop\nendfacet\n");
        }
        stl.push_str("endsolid t\n");
        let f = load_mesh_bytes(stl.as_bytes(), "TET.STL").unwrap();
        assert_eq!(f.mesh.vertices().len(), 4);
        assert_eq!(f.mesh.triangles().len(), 4);
        assert_eq!(
            f.warnings,
            ["welded 8 coincident vertices, dropped 0 degenerate triangles"]
        );
        // A single triangle encloses nothing: said, not refused (the run will fail).
        let flat = "solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid f\n";
        let f = load_mesh_bytes(flat.as_bytes(), "flat.stl").unwrap();
        assert!(
            f.warnings.iter().any(|w| w.contains("encloses no volume")),
            "{:?}",
            f.warnings
        );
    }
}
