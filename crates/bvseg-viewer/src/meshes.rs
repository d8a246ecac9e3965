//! The bundled sample meshes, and turning file bytes into a mesh.
use bvseg_core::Mesh;

/// A sample mesh compiled into the viewer (licences in `assets/meshes/README.md`).
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
];

/// The bundled mesh called `name` (its stem, or its file name).
pub fn bundled(name: &str) -> Option<&'static BundledMesh> {
    BUNDLED.iter().find(|m| m.name == name || m.file == name)
}

/// Loads a bundled mesh; the bundled files are valid, but the error path is kept honest.
pub fn load_bundled(m: &BundledMesh) -> Result<Mesh, String> {
    load_mesh_bytes(m.bytes, m.file)
}

/// The formats [`load_mesh_bytes`] reads, as a hint for the user.
pub const SUPPORTED: &str = ".obj";

/// Turns the bytes of a mesh file into a mesh, choosing the reader by `name`'s extension.
/// Every way into the viewer (bundled meshes, open file, drag and drop, the command line) goes
/// through here, so adding a format is a change in this one place. The error is one line
/// naming the file.
pub fn load_mesh_bytes(bytes: &[u8], name: &str) -> Result<Mesh, String> {
    let ext = std::path::Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("obj") => bvseg_io::load_obj_from_bytes(bytes, name).map_err(|e| e.to_string()),
        Some(e) => Err(format!(
            "{name}: unsupported mesh format .{e} (supported: {SUPPORTED})"
        )),
        None => Err(format!(
            "{name}: no file extension, cannot tell the format (supported: {SUPPORTED})"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bundled_mesh_loads() {
        for m in BUNDLED {
            let mesh = load_bundled(m).unwrap();
            assert!(mesh.triangles().len() > 1000, "{}", m.name);
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
    }
}
