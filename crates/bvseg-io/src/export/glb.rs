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
//!
//! For a character, the skeleton's joints are nodes under the root and each part's two nodes
//! hang under its bone's joint; with the file's [`Skinning`], the joints are the file's own
//! nodes, its animations move them, and `input_mesh` is the mesh skinned (a scene root of its
//! own, as glTF wants skinned meshes).
use bvseg_core::{Mesh, Segmentation, Shape};
use glam::DVec3;
use serde_json::{json, Value};

use crate::character::{Interp, Local, Path};
use crate::Skinning;

use super::proxy::{
    capsule_mesh, enclosing_sphere_hull, hull_mesh, hull_vertices, part_color, unit_cube,
    unit_cylinder, unit_sphere, volume_rotation, y_up_rotation, UnitMesh,
};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_BYTE: u32 = 5121;

/// Accumulates the binary chunk with its buffer views and accessors.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// A buffer view of `bytes`; `target` 0 for data that is no vertex attribute or index
    /// (inverse bind matrices, animation keys).
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let mut view =
            json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if target != 0 {
            view["target"] = json!(target);
        }
        self.views.push(view);
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// An accessor of `count` elements of `kind` (`"VEC4"`, ...) of floats, from `values`
    /// (count times the kind's components), with bounds when asked.
    fn floats(
        &mut self,
        values: &[f32],
        kind: &str,
        count: usize,
        target: u32,
        with_bounds: bool,
    ) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|c| c.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut acc = json!({
            "bufferView": view, "componentType": FLOAT, "count": count, "type": kind
        });
        if with_bounds && count > 0 {
            let comps = values.len() / count;
            let bound = |f: fn(f32, f32) -> f32| -> Vec<f32> {
                (0..comps)
                    .map(|c| {
                        values
                            .iter()
                            .skip(c)
                            .step_by(comps)
                            .copied()
                            .reduce(f)
                            .unwrap_or(0.0)
                    })
                    .collect()
            };
            acc["min"] = json!(bound(f32::min));
            acc["max"] = json!(bound(f32::max));
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// A VEC4 accessor of joint indices (unsigned bytes when they fit, else shorts).
    fn joints(&mut self, joints: &[[u16; 4]]) -> usize {
        let wide = joints.iter().flatten().any(|&j| j > u16::from(u8::MAX));
        let bytes: Vec<u8> = if wide {
            joints
                .iter()
                .flatten()
                .flat_map(|j| j.to_le_bytes())
                .collect()
        } else {
            joints.iter().flatten().map(|&j| j as u8).collect()
        };
        let view = self.view(&bytes, ARRAY_BUFFER);
        let kind = if wide { UNSIGNED_SHORT } else { UNSIGNED_BYTE };
        self.accessors.push(json!({
            "bufferView": view, "componentType": kind, "count": joints.len(), "type": "VEC4"
        }));
        self.accessors.len() - 1
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
    glb(seg, mesh, None)
}

/// [`to_glb`] for a skinned character read with its [`Skinning`]
/// ([`crate::LoadedMesh::skinning`]): the joints are the file's nodes with their own
/// transforms, its animations move them, and `mesh` (the loaded mesh, with its rig) is
/// written skinned, so that an engine playing an animation moves the mesh and the colliders
/// together. A `skinning` that does not belong to `seg` and `mesh` (a joint or a vertex it
/// lacks) is left out, as by [`to_glb`].
pub fn to_glb_skinned(seg: &Segmentation, mesh: Option<&Mesh>, skinning: &Skinning) -> Vec<u8> {
    glb(seg, mesh, Some(skinning))
}

fn glb(seg: &Segmentation, mesh: Option<&Mesh>, skinning: Option<&Skinning>) -> Vec<u8> {
    let mut b = Builder::default();
    // Created on first use, so that a file with one kind of shape has no unused accessors.
    let (mut sphere, mut cube, mut cylinder) = (None, None, None);
    let hull = enclosing_sphere_hull(12);

    let mut materials = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes: Vec<Value> = vec![json!({"name": "bvseg", "children": []})];
    // Each node's children, by node index (node 0's are the scene's under the root).
    let mut kids: Vec<Vec<usize>> = vec![Vec::new()];
    let mut shapes = Vec::new();
    // Nodes that hold the hull meshes; outside the scene, appended after the scene's nodes.
    let mut hull_nodes = Vec::new();
    // A character's joints as nodes: each part's nodes hang under its bone's joint, so that
    // an engine moving the joints moves the colliders.
    let skeleton = seg
        .skeleton
        .as_ref()
        .filter(|_| seg.parts.iter().any(|p| p.bone.is_some()));
    let skinning = skinning.filter(|s| fits(s, seg, mesh));
    // The output node of each skeleton joint.
    let mut joint_node: Vec<usize> = Vec::new();
    // The output node of each of the skinning's nodes.
    let mut skin_node: Vec<usize> = Vec::new();
    if let Some(s) = skinning {
        let animated: std::collections::BTreeSet<usize> = s
            .animations
            .iter()
            .flat_map(|a| a.channels.iter().map(|c| c.node))
            .collect();
        // In the file's order, which may put a child before its parent.
        skin_node = (0..s.nodes.len()).map(|i| nodes.len() + i).collect();
        for (i, n) in s.nodes.iter().enumerate() {
            let mut node = json!({
                "name": n.name.clone().unwrap_or_else(|| format!("node {}", n.file_index))
            });
            set_local(&mut node, n.local, animated.contains(&i));
            nodes.push(node);
            kids.push(Vec::new());
        }
        for (i, n) in s.nodes.iter().enumerate() {
            kids[n.parent.map_or(0, |p| skin_node[p])].push(skin_node[i]);
        }
        if let Some(sk) = skeleton {
            joint_node = sk
                .joints
                .iter()
                .map(|j| {
                    j.node
                        .and_then(|f| s.node_of(f))
                        .map_or(0, |i| skin_node[i])
                })
                .collect();
        }
    } else if let Some(sk) = skeleton {
        for j in &sk.joints {
            let local = match j.parent {
                Some(p) => sk.joints[p].rest.inverse() * j.rest,
                None => j.rest,
            };
            joint_node.push(nodes.len());
            nodes.push(json!({"name": j.name, "matrix": local.to_cols_array().map(round)}));
            kids.push(Vec::new());
        }
        for (i, j) in sk.joints.iter().enumerate() {
            let parent = j.parent.map_or(0, |p| joint_node[p]);
            kids[parent].push(joint_node[i]);
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
                    kids[joint_node[b]].push(nodes.len());
                }
                None => kids[0].push(nodes.len()),
            }
            nodes.push(node);
            kids.push(Vec::new());
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

    // Skinned mesh nodes are roots of the scene: their parents' transforms would not apply.
    let mut scene_roots = vec![0];
    let mut skins = Vec::new();
    if let Some(m) = mesh {
        materials.push(json!({
            "name": "input_mesh",
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0},
            "doubleSided": true
        }));
        let material = materials.len() - 1;
        let corners = skinning
            .and_then(|_| m.rig()?.skin.as_ref())
            .map(|s| &s.corners);
        match (skinning, corners) {
            (Some(s), Some(corners)) => {
                for (k, skin) in s.skins.iter().enumerate() {
                    let tris: Vec<usize> = (0..corners.len())
                        .filter(|&t| s.vertices[corners[t][0] as usize].skin == k)
                        .collect();
                    if tris.is_empty() {
                        continue;
                    }
                    let mut pos = Vec::with_capacity(9 * tris.len());
                    let mut col = Vec::with_capacity(9 * tris.len());
                    let mut joints = Vec::with_capacity(3 * tris.len());
                    let mut weights = Vec::with_capacity(12 * tris.len());
                    for &t in &tris {
                        let part = seg.triangle_parts.get(t).copied().unwrap_or(0) as usize;
                        for &c in &corners[t] {
                            let v = &s.vertices[c as usize];
                            pos.extend(v.position.as_vec3().to_array());
                            col.extend(part_color(part).map(|x| x as f32));
                            joints.push(v.joints);
                            weights.extend(v.weights);
                        }
                    }
                    let n = 3 * tris.len();
                    let attributes = json!({
                        "POSITION": b.floats(&pos, "VEC3", n, ARRAY_BUFFER, true),
                        "COLOR_0": b.floats(&col, "VEC3", n, ARRAY_BUFFER, false),
                        "JOINTS_0": b.joints(&joints),
                        "WEIGHTS_0": b.floats(&weights, "VEC4", n, ARRAY_BUFFER, false),
                    });
                    let ibm: Vec<f32> = skin
                        .inverse_bind
                        .iter()
                        .flat_map(|m| m.as_mat4().to_cols_array())
                        .collect();
                    let ibm = b.floats(&ibm, "MAT4", skin.joints.len(), 0, false);
                    let joints: Vec<usize> = skin.joints.iter().map(|&j| skin_node[j]).collect();
                    skins.push(json!({"joints": joints, "inverseBindMatrices": ibm}));
                    let name = match scene_roots.len() {
                        1 => "input_mesh".to_owned(),
                        r => format!("input_mesh_{}", r - 1),
                    };
                    meshes.push(json!({
                        "name": name,
                        "primitives": [{"attributes": attributes, "material": material}]
                    }));
                    scene_roots.push(nodes.len());
                    nodes.push(
                        json!({"name": name, "mesh": meshes.len() - 1, "skin": skins.len() - 1}),
                    );
                    kids.push(Vec::new());
                }
            }
            _ => {
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
                    "primitives": [{"attributes": {"POSITION": pa, "COLOR_0": ca}, "material": material}]
                }));
                kids[0].push(nodes.len());
                nodes.push(json!({"name": "input_mesh", "mesh": meshes.len() - 1}));
                kids.push(Vec::new());
            }
        }
    }
    let animations = skinning.map(|s| animations_json(&mut b, s, &skin_node));

    for (i, c) in kids.into_iter().enumerate() {
        if i == 0 || !c.is_empty() {
            nodes[i]["children"] = json!(c);
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
        "scenes": [{"name": "bvseg", "nodes": scene_roots}],
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
    if !skins.is_empty() {
        doc["skins"] = json!(skins);
    }
    if let Some(a) = animations.filter(|a| !a.is_empty()) {
        doc["animations"] = json!(a);
    }
    if !shapes.is_empty() {
        doc["extensionsUsed"] = json!(["KHR_implicit_shapes", "KHR_physics_rigid_bodies"]);
        doc["extensions"] = json!({"KHR_implicit_shapes": {"shapes": shapes}});
    }
    // serde_json's map keeps keys sorted, so the text is deterministic.
    let text = serde_json::to_vec(&doc).unwrap_or_default();
    container(text, b.bin)
}

/// Whether `s` belongs to `seg` and `mesh`: every joint of the skeleton is one of its nodes,
/// and the mesh's rig has a skin whose posed vertices are its vertices.
fn fits(s: &Skinning, seg: &Segmentation, mesh: Option<&Mesh>) -> bool {
    let joints = seg.skeleton.as_ref().is_none_or(|sk| {
        sk.joints
            .iter()
            .all(|j| j.node.is_some_and(|f| s.node_of(f).is_some()))
    });
    let vertices = mesh.is_none_or(|m| {
        m.rig().and_then(|r| r.skin.as_ref()).is_some_and(|skin| {
            skin.corners.len() == m.triangles().len()
                && skin
                    .corners
                    .iter()
                    .flatten()
                    .all(|&c| (c as usize) < s.vertices.len())
        })
    });
    joints && vertices
}

/// A node's transform as the input file gave it, in full f64 (the joints' transforms must
/// compose to the rest frames the volumes were placed in). An animated node must not have a
/// matrix: one that does is written as its translation, rotation and scale.
fn set_local(node: &mut Value, local: Local, animated: bool) {
    let (t, r, s) = match local {
        Local::Matrix(m) if !animated => {
            node["matrix"] = json!(m.to_cols_array());
            return;
        }
        Local::Matrix(m) => {
            let (s, r, t) = m.to_scale_rotation_translation();
            (t, r, s)
        }
        Local::Trs(t, r, s) => (t, r, s),
    };
    if t != DVec3::ZERO {
        node["translation"] = json!(t.to_array());
    }
    if r != glam::DQuat::IDENTITY {
        node["rotation"] = json!(r.to_array());
    }
    if s != DVec3::ONE {
        node["scale"] = json!(s.to_array());
    }
}

/// The skinning's animations, each channel with a sampler of its own, on the output nodes
/// `skin_node`.
fn animations_json(b: &mut Builder, s: &Skinning, skin_node: &[usize]) -> Vec<Value> {
    s.animations
        .iter()
        .map(|a| {
            let mut samplers = Vec::new();
            let mut channels = Vec::new();
            for c in &a.channels {
                let times: Vec<f32> = c.times.iter().map(|&t| t as f32).collect();
                let input = b.floats(&times, "SCALAR", times.len(), 0, true);
                let (comps, kind, path) = match c.path {
                    Path::T => (3, "VEC3", "translation"),
                    Path::R => (4, "VEC4", "rotation"),
                    Path::S => (3, "VEC3", "scale"),
                };
                let values: Vec<f32> = c
                    .values
                    .iter()
                    .flat_map(|v| v[..comps].iter().map(|&x| x as f32))
                    .collect();
                let output = b.floats(&values, kind, c.values.len(), 0, false);
                let interpolation = match c.interp {
                    Interp::Step => "STEP",
                    Interp::Linear => "LINEAR",
                    Interp::Cubic => "CUBICSPLINE",
                };
                channels.push(json!({
                    "sampler": samplers.len(),
                    "target": {"node": skin_node[c.node], "path": path}
                }));
                samplers.push(
                    json!({"input": input, "output": output, "interpolation": interpolation}),
                );
            }
            let mut anim = json!({"channels": channels, "samplers": samplers});
            if let Some(name) = &a.name {
                anim["name"] = json!(name);
            }
            anim
        })
        .collect()
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
