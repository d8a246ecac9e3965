//! The result as a binary glTF 2.0 file (`.glb`): the mesh and one translucent node per
//! bounding volume (`part 0`, `part 1`, ...), in the mesh's coordinates, coloured as in the
//! viewer, so that any glTF viewer shows what the app shows.
use bvseg_core::BoundingVolume;
use glam::DVec3;

use crate::scene::{self, MeshGeometry, MESH_COLOR, VERTEX_FLOATS};

/// Opacity of the volumes in the file.
pub const VOLUME_ALPHA: f32 = 0.35;

/// One glTF primitive: flat triangles with normals.
struct Primitive {
    name: String,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    color: [f32; 4],
}

/// Builds the `.glb` bytes for `mesh` and its `volumes`.
pub fn glb(mesh: &MeshGeometry, volumes: &[BoundingVolume]) -> Vec<u8> {
    let c = mesh.center.as_vec3();
    let mut prims = vec![Primitive {
        name: "mesh".into(),
        positions: mesh.corners.iter().map(|p| (*p + c).to_array()).collect(),
        normals: mesh
            .normals
            .iter()
            .flat_map(|n| [n.to_array(); 3])
            .collect(),
        color: [MESH_COLOR[0], MESH_COLOR[1], MESH_COLOR[2], 1.0],
    }];
    for (i, v) in volumes.iter().enumerate() {
        let [r, g, b] = scene::part_color(i);
        let mut verts = Vec::new();
        scene::volume_surface(&mut verts, v, DVec3::ZERO, [r, g, b], VOLUME_ALPHA);
        let chunks = verts.chunks_exact(VERTEX_FLOATS);
        prims.push(Primitive {
            name: format!("part {i}"),
            positions: chunks.clone().map(|x| [x[0], x[1], x[2]]).collect(),
            normals: chunks.map(|x| [x[3], x[4], x[5]]).collect(),
            color: [r, g, b, VOLUME_ALPHA],
        });
    }
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes, mut materials) =
        (vec![], vec![], vec![], vec![], vec![]);
    for (i, p) in prims.iter().enumerate() {
        let (lo, hi) = p.positions.iter().fold(
            ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(lo, hi), q| {
                (
                    [lo[0].min(q[0]), lo[1].min(q[1]), lo[2].min(q[2])],
                    [hi[0].max(q[0]), hi[1].max(q[1]), hi[2].max(q[2])],
                )
            },
        );
        for (k, data) in [&p.positions, &p.normals].into_iter().enumerate() {
            let bytes: &[u8] = bytemuck::cast_slice(data.as_slice());
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{},"byteLength":{},"target":34962}}"#,
                bin.len(),
                bytes.len()
            ));
            bin.extend_from_slice(bytes);
            let bounds = if k == 0 {
                format!(r#","min":{},"max":{}"#, json_vec(&lo), json_vec(&hi))
            } else {
                String::new()
            };
            accessors.push(format!(
                r#"{{"bufferView":{},"componentType":5126,"count":{},"type":"VEC3"{bounds}}}"#,
                views.len() - 1,
                data.len()
            ));
        }
        let blend = if p.color[3] < 1.0 {
            r#","alphaMode":"BLEND""#
        } else {
            ""
        };
        materials.push(format!(
            r#"{{"name":"{}","pbrMetallicRoughness":{{"baseColorFactor":{},"metallicFactor":0,"roughnessFactor":0.8}},"doubleSided":true{blend}}}"#,
            p.name,
            json_vec(&p.color)
        ));
        meshes.push(format!(
            r#"{{"name":"{}","primitives":[{{"attributes":{{"POSITION":{},"NORMAL":{}}},"material":{i},"mode":4}}]}}"#,
            p.name,
            2 * i,
            2 * i + 1
        ));
        nodes.push(format!(r#"{{"name":"{}","mesh":{i}}}"#, p.name));
    }
    let node_ids: Vec<String> = (0..prims.len()).map(|i| i.to_string()).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"{}"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"materials":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{}}}]}}"#,
        bvseg_io::GENERATOR,
        node_ids.join(","),
        nodes.join(","),
        meshes.join(","),
        materials.join(","),
        accessors.join(","),
        views.join(","),
        bin.len()
    );
    let mut json = json.into_bytes();
    while json.len() & 3 != 0 {
        json.push(b' ');
    }
    while bin.len() & 3 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// A float array as JSON (glTF wants plain numbers; non-finite values cannot occur here, but
/// are written as 0 rather than as invalid JSON).
fn json_vec(v: &[f32]) -> String {
    let items: Vec<String> = v
        .iter()
        .map(|x| {
            if x.is_finite() {
                format!("{x}")
            } else {
                "0".into()
            }
        })
        .collect();
    format!("[{}]", items.join(","))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshes::{load_bundled, BUNDLED};
    use bvseg_core::Shape;
    use glam::DMat3;

    fn u32_at(b: &[u8], i: usize) -> usize {
        u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]) as usize
    }

    #[test]
    fn glb_holds_the_mesh_and_one_node_per_volume() {
        let mesh = load_bundled(&BUNDLED[0]).unwrap();
        let geometry = MeshGeometry::new(&mesh);
        let vols: Vec<BoundingVolume> = [Shape::Ellipsoid, Shape::Obb]
            .iter()
            .map(|&shape| BoundingVolume {
                shape,
                center: DVec3::new(0.5, 1.0, -2.0),
                axes: DMat3::IDENTITY,
                radii: DVec3::new(1.0, 2.0, 3.0),
            })
            .collect();
        let b = glb(&geometry, &vols);
        assert_eq!(&b[0..4], b"glTF");
        assert_eq!(u32_at(&b, 4), 2);
        assert_eq!(u32_at(&b, 8), b.len());
        let json_len = u32_at(&b, 12);
        assert_eq!(&b[16..20], b"JSON");
        let json: serde_json::Value = serde_json::from_slice(&b[20..20 + json_len]).unwrap();
        let bin_at = 20 + json_len;
        assert_eq!(&b[bin_at + 4..bin_at + 8], b"BIN\0");
        let bin_len = u32_at(&b, bin_at);
        assert_eq!(bin_at + 8 + bin_len, b.len());
        assert_eq!(
            json["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
            bin_len
        );

        let names: Vec<&str> = json["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["mesh", "part 0", "part 1"]);
        let acc = json["accessors"].as_array().unwrap();
        assert_eq!(
            acc[0]["count"].as_u64().unwrap() as usize,
            3 * mesh.triangles().len()
        );
        // The mesh keeps its own coordinates: its bounds are the mesh's bounding box.
        let (lo, hi) = mesh.bbox();
        for j in 0..3 {
            assert!((acc[0]["min"][j].as_f64().unwrap() - lo[j]).abs() < 1e-4);
            assert!((acc[0]["max"][j].as_f64().unwrap() - hi[j]).abs() < 1e-4);
        }
        // The box's bounds are its corners; every view lies inside the binary chunk.
        let boxb = &acc[4];
        assert_eq!(boxb["count"].as_u64(), Some(36));
        assert!((boxb["min"][2].as_f64().unwrap() + 5.0).abs() < 1e-5);
        assert!((boxb["max"][0].as_f64().unwrap() - 1.5).abs() < 1e-5);
        for v in json["bufferViews"].as_array().unwrap() {
            let end = v["byteOffset"].as_u64().unwrap() + v["byteLength"].as_u64().unwrap();
            assert!(end as usize <= bin_len);
        }
        let mats = json["materials"].as_array().unwrap();
        assert_eq!(mats[1]["alphaMode"], "BLEND");
        assert!(mats[0].get("alphaMode").is_none());
    }
}
