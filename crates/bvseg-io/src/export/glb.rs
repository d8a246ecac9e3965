//! glTF 2.0 binary output.
//!
//! Scene layout, under one root node `bvseg`:
//! - `part_<i>`: the volume drawn, coloured per part: a unit sphere (ellipsoid, sphere), the
//!   cube [-1, 1]^3 (box) or a unit cylinder under the node's translation, rotation and
//!   non-uniform scale, or a capsule's or hull's own mesh under translation and rotation;
//!   `extras` hold the exact parameters (as in the JSON file).
//! - `part_<i>_collider`: translation and rotation only (physics engines want colliders
//!   unscaled), with a `KHR_physics_rigid_bodies` collider: a `KHR_implicit_shapes` sphere,
//!   box, capsule or cylinder of the exact size (capsules and cylinders along the node's Y,
//!   as the extension has them); for a hull, a `convexHull` collider over its vertices; for
//!   an ellipsoid, which those extensions cannot express, a convex hull of a polyhedron that
//!   encloses it. The hull meshes are referenced by node, outside the scene, so that viewers
//!   do not draw them; `extras` hold the exact volume.
//! - `input_mesh` (optional): the segmented mesh with vertex colours by part.
use bvseg_core::{Mesh, Segmentation, Shape};
use glam::DVec3;
use serde_json::{json, Value};

use super::proxy::{
    capsule_mesh, enclosing_sphere_hull, hull_mesh, hull_vertices, part_color, unit_cube,
    unit_cylinder, unit_sphere, volume_rotation, y_up_rotation, UnitMesh,
};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Accumulates the binary chunk with its buffer views and accessors.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len(), "target": target
        }));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn vec3(&mut self, data: &[DVec3], with_bounds: bool) -> usize {
        let f: Vec<[f32; 3]> = data.iter().map(|p| p.as_vec3().to_array()).collect();
        let bytes: Vec<u8> = f.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let view = self.view(&bytes, ARRAY_BUFFER);
        let mut acc = json!({
            "bufferView": view, "componentType": FLOAT, "count": data.len(), "type": "VEC3"
        });
        if with_bounds {
            // Bounds of the f32 values actually stored, as the spec requires.
            let lo = f.iter().fold([f32::INFINITY; 3], |m, p| {
                std::array::from_fn(|j| m[j].min(p[j]))
            });
            let hi = f.iter().fold([f32::NEG_INFINITY; 3], |m, p| {
                std::array::from_fn(|j| m[j].max(p[j]))
            });
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let view = self.view(&bytes, ELEMENT_ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * tris.len(), "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// Positions, normals and indices of a unit mesh: (position, normal, indices) accessors.
    fn unit(&mut self, m: &UnitMesh) -> (usize, usize, usize) {
        (
            self.vec3(&m.positions, true),
            self.vec3(&m.normals, false),
            self.indices(&m.triangles),
        )
    }
}

fn round(x: f64) -> f64 {
    // f32 precision is all glTF readers keep; printing the f64 would only add noise digits
    // that differ between platforms' f32 conversions. Going through f32 is exact and stable.
    x as f32 as f64
}

fn vec(v: DVec3) -> [f64; 3] {
    v.to_array().map(round)
}

/// The segmentation as a GLB file; `mesh`, when given, is added with vertex colours by part
/// (it must be the mesh whose triangles `seg.triangle_parts` labels).
pub fn to_glb(seg: &Segmentation, mesh: Option<&Mesh>) -> Vec<u8> {
    let mut b = Builder::default();
    // Created on first use, so that a file with one kind of shape has no unused accessors.
    let (mut sphere, mut cube, mut cylinder) = (None, None, None);
    let hull = enclosing_sphere_hull(12);

    let mut materials = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes: Vec<Value> = vec![json!({"name": "bvseg", "children": []})];
    let mut children = Vec::new();
    let mut shapes = Vec::new();
    // Nodes that hold the hull meshes; outside the scene, appended after the scene's nodes.
    let mut hull_nodes = Vec::new();
    // A skinned character's joints, as nodes 1..: each part's nodes hang under its bone's
    // joint, so that an engine moving the joints moves the colliders.
    let skeleton = seg
        .skeleton
        .as_ref()
        .filter(|_| seg.parts.iter().any(|p| p.bone.is_some()));
    let mut joint_children: Vec<Vec<usize>> = Vec::new();
    if let Some(sk) = skeleton {
        for j in &sk.joints {
            let local = match j.parent {
                Some(p) => sk.joints[p].rest.inverse() * j.rest,
                None => j.rest,
            };
            if j.parent.is_none() {
                children.push(nodes.len());
            }
            nodes.push(json!({"name": j.name, "matrix": local.to_cols_array().map(round)}));
        }
        joint_children = vec![Vec::new(); sk.joints.len()];
        for (i, j) in sk.joints.iter().enumerate() {
            if let Some(p) = j.parent {
                joint_children[p].push(1 + i);
            }
        }
    }

    for (i, part) in seg.parts.iter().enumerate() {
        let v = &part.volume;
        let [r, g, bl] = part_color(i);
        materials.push(json!({
            "name": format!("part_{i}"),
            "pbrMetallicRoughness": {
                "baseColorFactor": [round(r), round(g), round(bl), 0.6],
                "metallicFactor": 0.0, "roughnessFactor": 0.8
            },
            "alphaMode": "BLEND", "doubleSided": true
        }));
        let (rot, scale) = match v.shape {
            Shape::Capsule | Shape::Cylinder => (y_up_rotation(v), v.radii),
            Shape::Hull => (glam::DQuat::IDENTITY, DVec3::ONE),
            _ => (volume_rotation(v), v.radii),
        };
        let (pos, nrm, idx) = match v.shape {
            Shape::Ellipsoid | Shape::Sphere => {
                *sphere.get_or_insert_with(|| b.unit(&unit_sphere(32)))
            }
            Shape::Obb => *cube.get_or_insert_with(|| b.unit(&unit_cube())),
            Shape::Cylinder => *cylinder.get_or_insert_with(|| b.unit(&unit_cylinder(32))),
            Shape::Capsule => b.unit(&capsule_mesh(v.radius(), v.half_length(), 32)),
            Shape::Hull => b.unit(&hull_mesh(v)),
        };
        meshes.push(json!({
            "name": format!("part_{i}"),
            "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": i}]
        }));
        let rotation = [rot.x, rot.y, rot.z, rot.w].map(round);
        let mut exact = crate::json::volume_json(v);
        exact["fraction"] = json!(part.fraction);
        let mut display = json!({
            "name": format!("part_{i}"),
            "mesh": meshes.len() - 1,
            "translation": vec(v.center),
            "rotation": rotation,
            "extras": exact,
        });
        match v.shape {
            // Cylinder meshes are unit ones scaled (radius, half-height, radius) along Y.
            Shape::Cylinder => display["scale"] = json!(vec(DVec3::new(scale.x, scale.z, scale.x))),
            Shape::Capsule | Shape::Hull => {}
            _ => display["scale"] = json!(vec(scale)),
        }
        let bone = skeleton.zip(part.bone);
        let mut place = |nodes: &mut Vec<Value>, mut node: Value| {
            match bone {
                Some((sk, b)) => {
                    under_joint(&mut node, sk.joints[b].rest.inverse());
                    joint_children[b].push(nodes.len());
                }
                None => children.push(nodes.len()),
            }
            nodes.push(node);
        };
        place(&mut nodes, display);
        let (r, h) = (round(v.radius()), round(v.radii.z));
        let mut implicit = |shape: Value| {
            shapes.push(shape);
            json!({"shape": shapes.len() - 1})
        };
        let geometry = match v.shape {
            Shape::Obb => implicit(json!({"type": "box", "box": {"size": vec(2.0 * v.radii)}})),
            Shape::Sphere => implicit(json!({"type": "sphere", "sphere": {"radius": r}})),
            // `height` is the distance between the end balls' centres (above 0: a capsule as
            // short as a ball keeps its tiny segment).
            Shape::Capsule => implicit(json!({"type": "capsule", "capsule":
                {"height": round(2.0 * v.radii.z), "radiusTop": r, "radiusBottom": r}})),
            Shape::Cylinder => implicit(json!({"type": "cylinder", "cylinder":
                {"height": 2.0 * h, "radiusTop": r, "radiusBottom": r}})),
            Shape::Ellipsoid | Shape::Hull => {
                let (points, triangles) = if v.shape == Shape::Hull {
                    hull_vertices(v)
                } else {
                    let scaled = hull.positions.iter().map(|&p| p * v.radii).collect();
                    (scaled, hull.triangles.clone())
                };
                let pa = b.vec3(&points, true);
                let ia = b.indices(&triangles);
                meshes.push(json!({
                    "name": format!("part_{i}_hull"),
                    "primitives": [{"attributes": {"POSITION": pa}, "indices": ia}]
                }));
                hull_nodes.push((i, nodes.len(), meshes.len() - 1));
                // Patched below, once the scene's node count is known.
                json!({"node": Value::Null, "convexHull": true})
            }
        };
        let collider = json!({
            "name": format!("part_{i}_collider"),
            "translation": vec(v.center),
            "rotation": rotation,
            "extensions": {"KHR_physics_rigid_bodies": {"collider": {"geometry": geometry}}},
            "extras": exact,
        });
        place(&mut nodes, collider);
    }

    if let Some(m) = mesh {
        materials.push(json!({
            "name": "input_mesh",
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0},
            "doubleSided": true
        }));
        // Unshared corners, so that each triangle takes its part's colour.
        let mut pos = Vec::with_capacity(3 * m.triangles().len());
        let mut col = Vec::with_capacity(3 * m.triangles().len());
        for (t, tri) in m.triangles().iter().enumerate() {
            let part = seg.triangle_parts.get(t).copied().unwrap_or(0) as usize;
            let c = DVec3::from_array(part_color(part));
            for &k in tri {
                pos.push(m.vertices()[k as usize]);
                col.push(c);
            }
        }
        let pa = b.vec3(&pos, true);
        let ca = b.vec3(&col, false);
        meshes.push(json!({
            "name": "input_mesh",
            "primitives": [{"attributes": {"POSITION": pa, "COLOR_0": ca}, "material": materials.len() - 1}]
        }));
        children.push(nodes.len());
        nodes.push(json!({"name": "input_mesh", "mesh": meshes.len() - 1}));
    }

    nodes[0]["children"] = json!(children);
    for (j, c) in joint_children.into_iter().enumerate() {
        if !c.is_empty() {
            nodes[1 + j]["children"] = json!(c);
        }
    }
    for (i, collider, mesh_index) in hull_nodes {
        let node = nodes.len();
        nodes.push(json!({"name": format!("part_{i}_hull"), "mesh": mesh_index}));
        nodes[collider]["extensions"]["KHR_physics_rigid_bodies"]["collider"]["geometry"]["node"] =
            json!(node);
    }

    while b.bin.len() % 4 != 0 {
        b.bin.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": crate::GENERATOR},
        "extensionsUsed": ["KHR_physics_rigid_bodies"],
        "scene": 0,
        "scenes": [{"name": "bvseg", "nodes": [0]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": b.bin.len()}],
        "extras": {"schema": crate::json::schema_and_kind(seg.parts.iter().map(|p| &p.volume)).0,
                   "kind": crate::json::schema_and_kind(seg.parts.iter().map(|p| &p.volume)).1,
                   "kinds": seg.kinds.to_string(), "k": seg.parts.len(),
                   "tov": seg.metrics.tov, "mov": seg.metrics.mov},
    });
    if !shapes.is_empty() {
        doc["extensionsUsed"] = json!(["KHR_implicit_shapes", "KHR_physics_rigid_bodies"]);
        doc["extensions"] = json!({"KHR_implicit_shapes": {"shapes": shapes}});
    }
    // serde_json's map keeps keys sorted, so the text is deterministic.
    let text = serde_json::to_vec(&doc).unwrap_or_default();
    container(text, b.bin)
}

/// Turns a node placed in model space (translation, rotation, scale) into one under a joint
/// whose rest world matrix is `inverse`'s inverse: its `matrix` is `inverse` times its
/// model-space transform, so that at rest it sits where it did.
fn under_joint(node: &mut Value, inverse: glam::DMat4) {
    let get = |key: &str, default: [f64; 4]| {
        node.get(key)
            .and_then(|v| serde_json::from_value::<Vec<f64>>(v.clone()).ok())
            .map_or(default, |v| {
                std::array::from_fn(|i| v.get(i).copied().unwrap_or(default[i]))
            })
    };
    let t = get("translation", [0.0; 4]);
    let r = get("rotation", [0.0, 0.0, 0.0, 1.0]);
    let s = get("scale", [1.0; 4]);
    let model = glam::DMat4::from_scale_rotation_translation(
        DVec3::new(s[0], s[1], s[2]),
        glam::DQuat::from_xyzw(r[0], r[1], r[2], r[3]),
        DVec3::new(t[0], t[1], t[2]),
    );
    if let Some(o) = node.as_object_mut() {
        o.remove("translation");
        o.remove("rotation");
        o.remove("scale");
        o.insert(
            "matrix".into(),
            json!((inverse * model).to_cols_array().map(round)),
        );
    }
}

fn container(mut json: Vec<u8>, bin: Vec<u8>) -> Vec<u8> {
    while json.len() % 4 != 0 {
        json.push(b' ');
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
