//! Skinned glTF characters: the mesh as its skin poses it with the file's rest node
//! transforms (linear blend skinning), its skeleton (the skins' joints), and the poses of
//! its animations, which the core's volumes then follow (see `bvseg_core::Rig`).
//!
//! Poses are taken at every key of every animation and at the midpoints between keys: the
//! core grows each volume by an estimate of how far a corner strays from the chord between
//! two sampled poses (see the core's `posing` module), which the midpoints make measurable.
use std::collections::BTreeSet;

use bvseg_core::{weld, Joint, Pose, Rig, Skeleton, Skin};
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};

use crate::IoError;

/// Most posed vertex positions kept over all poses (24 bytes each): beyond it the poses of
/// each animation are thinned evenly, keys first.
const MAX_POSED_VERTICES: usize = 1 << 24;

/// What a character file holds, for `bvseg info` and the front ends.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CharacterInfo {
    /// Joints over all skins (a node used by two skins counts once).
    pub joints: usize,
    /// Skins.
    pub skins: usize,
    /// Animations.
    pub animations: usize,
    /// Poses sampled from the animations, besides the rest pose.
    pub poses: usize,
}

/// How one raw vertex moves.
#[derive(Clone)]
pub(crate) enum Influence {
    /// Skinned: its local position, up to four (skin joint matrix index, weight), and the
    /// file's own JOINTS_0 and WEIGHTS_0 values, which the GLB writer carries over.
    Skinned {
        local: DVec3,
        skin: usize,
        joints: [(usize, f64); 4],
        file: ([u16; 4], [f32; 4]),
    },
    /// Rigidly with a node (an unskinned mesh): its position in the node's frame.
    Rigid { local: DVec3, node: usize },
}

/// The nodes of a document: parents, rest transforms, and an order with parents first.
pub(crate) struct Nodes {
    parent: Vec<Option<usize>>,
    rest: Vec<Local>,
    order: Vec<usize>,
}

/// A node's local transform as the file gives it, in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Local {
    Matrix(DMat4),
    Trs(DVec3, DQuat, DVec3),
}

impl Local {
    pub(crate) fn matrix(self) -> DMat4 {
        match self {
            Local::Matrix(m) => m,
            Local::Trs(t, r, s) => DMat4::from_scale_rotation_translation(s, r, t),
        }
    }
}

impl Nodes {
    /// The node tree of `doc`, with `rest` the nodes' local transforms ([`node_locals`]).
    pub(crate) fn new(doc: &gltf::Document, rest: Vec<Local>, name: &str) -> Result<Self, IoError> {
        let n = doc.nodes().count();
        let mut parent = vec![None; n];
        for node in doc.nodes() {
            for c in node.children() {
                if parent[c.index()].is_some() {
                    return Err(parse(name, format!("node {} has two parents", c.index())));
                }
                parent[c.index()] = Some(node.index());
            }
        }
        // Parents before children: depth-first from the roots; a node on a cycle has no root.
        let mut children = vec![Vec::new(); n];
        for (c, p) in parent.iter().enumerate() {
            if let Some(p) = p {
                children[*p].push(c);
            }
        }
        let mut order = Vec::with_capacity(n);
        let mut stack: Vec<usize> = (0..n).filter(|&i| parent[i].is_none()).rev().collect();
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(children[i].iter().rev());
        }
        if order.len() != n {
            return Err(parse(name, "the node hierarchy has a cycle"));
        }
        Ok(Self {
            parent,
            rest,
            order,
        })
    }

    /// Every node's world matrix, with `locals` for the local transforms.
    fn worlds(&self, locals: &[Local]) -> Vec<DMat4> {
        let mut w = vec![DMat4::IDENTITY; locals.len()];
        for &i in &self.order {
            let l = locals[i].matrix();
            w[i] = match self.parent[i] {
                Some(p) => w[p] * l,
                None => l,
            };
        }
        w
    }
}

fn unit(q: DQuat) -> DQuat {
    if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// Every node's local transform, read from the JSON text in f64: the `gltf` crate reads
/// numbers as f32, and exporters that print their f64 transforms in full (three.js) would
/// otherwise put the rest pose a few 1e-8 away from where any f64 reader of the file puts it.
/// Rotations are normalised.
pub(crate) fn node_locals(json: &[u8], doc: &gltf::Document) -> Vec<Local> {
    #[derive(serde::Deserialize)]
    struct Root {
        #[serde(default)]
        nodes: Vec<Node>,
    }
    #[derive(serde::Deserialize)]
    struct Node {
        matrix: Option<[f64; 16]>,
        translation: Option<[f64; 3]>,
        rotation: Option<[f64; 4]>,
        scale: Option<[f64; 3]>,
    }
    let raw = serde_json::from_slice::<Root>(json)
        .ok()
        .filter(|r| r.nodes.len() == doc.nodes().count());
    doc.nodes()
        .map(|node| {
            let (matrix, t, r, s) = match raw.as_ref().map(|r| &r.nodes[node.index()]) {
                Some(n) => (n.matrix, n.translation, n.rotation, n.scale),
                // The document parsed, so this cannot happen; the crate's f32 values then.
                None => match node.transform() {
                    gltf::scene::Transform::Matrix { matrix } => (
                        Some(std::array::from_fn(|i| f64::from(matrix[i / 4][i % 4]))),
                        None,
                        None,
                        None,
                    ),
                    gltf::scene::Transform::Decomposed {
                        translation,
                        rotation,
                        scale,
                    } => (
                        None,
                        Some(translation.map(f64::from)),
                        Some(rotation.map(f64::from)),
                        Some(scale.map(f64::from)),
                    ),
                },
            };
            match matrix {
                Some(m) => Local::Matrix(DMat4::from_cols_array(&m)),
                None => Local::Trs(
                    DVec3::from_array(t.unwrap_or([0.0; 3])),
                    unit(DQuat::from_array(r.unwrap_or([0.0, 0.0, 0.0, 1.0]))),
                    DVec3::from_array(s.unwrap_or([1.0; 3])),
                ),
            }
        })
        .collect()
}

fn parse(name: &str, message: impl Into<String>) -> IoError {
    IoError::Parse {
        name: name.to_owned(),
        line: None,
        message: message.into(),
    }
}

/// Reads `count` elements of `comps` components of accessor `acc` as f64: floats as they
/// are, normalized integers scaled to [0, 1] (or [-1, 1]), other integers as integers.
pub(crate) fn read_f64s(
    acc: &gltf::Accessor,
    comps: usize,
    buffers: &[Vec<u8>],
    name: &str,
) -> Result<Vec<f64>, IoError> {
    let want = match comps {
        1 => Dimensions::Scalar,
        3 => Dimensions::Vec3,
        _ => Dimensions::Vec4,
    };
    if acc.dimensions() != want {
        return Err(parse(
            name,
            format!("accessor {}: expected {want:?} elements", acc.index()),
        ));
    }
    let size = match acc.data_type() {
        DataType::U8 | DataType::I8 => 1,
        DataType::U16 | DataType::I16 => 2,
        DataType::U32 | DataType::F32 => 4,
    };
    let (data, off, stride) = crate::gltf_in::accessor_bytes(acc, size * comps, buffers, name)?;
    let norm = acc.normalized();
    let mut out = Vec::with_capacity(acc.count() * comps);
    for k in 0..acc.count() {
        for c in 0..comps {
            let o = off + k * stride + c * size;
            let b = &data[o..o + size];
            let v = match acc.data_type() {
                DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::U8 => b[0] as f64 / if norm { 255.0 } else { 1.0 },
                DataType::I8 => (b[0] as i8 as f64 / if norm { 127.0 } else { 1.0 }).max(-1.0),
                DataType::U16 => {
                    u16::from_le_bytes([b[0], b[1]]) as f64 / if norm { 65535.0 } else { 1.0 }
                }
                DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f64
                    / if norm { 32767.0 } else { 1.0 })
                .max(-1.0),
            };
            if !v.is_finite() {
                return Err(parse(
                    name,
                    format!("accessor {}: a value is not finite", acc.index()),
                ));
            }
            out.push(v);
        }
    }
    Ok(out)
}

/// The influences of a skinned primitive's `n` vertices (JOINTS_0 and WEIGHTS_0, weights
/// normalised to sum 1).
pub(crate) fn skinned_influences(
    prim: &gltf::Primitive,
    skin: &gltf::Skin,
    local: &[DVec3],
    buffers: &[Vec<u8>],
    name: &str,
) -> Result<Vec<Influence>, IoError> {
    let n = local.len();
    let (Some(ja), Some(wa)) = (
        prim.get(&gltf::Semantic::Joints(0)),
        prim.get(&gltf::Semantic::Weights(0)),
    ) else {
        return Err(parse(
            name,
            "a primitive of a skinned mesh has no JOINTS_0 or WEIGHTS_0",
        ));
    };
    if ja.count() != n || wa.count() != n {
        return Err(parse(
            name,
            format!(
                "accessors {} and {}: {} joints and {} weights for {n} vertices",
                ja.index(),
                wa.index(),
                ja.count(),
                wa.count()
            ),
        ));
    }
    if ja.normalized() || matches!(ja.data_type(), DataType::F32) {
        return Err(parse(
            name,
            format!(
                "accessor {}: JOINTS_0 must be unsigned integers",
                ja.index()
            ),
        ));
    }
    let joints = read_f64s(&ja, 4, buffers, name)?;
    let weights = read_f64s(&wa, 4, buffers, name)?;
    let count = skin.joints().count();
    let mut out = Vec::with_capacity(n);
    for v in 0..n {
        let mut js = [(0usize, 0.0f64); 4];
        let mut file = ([0u16; 4], [0f32; 4]);
        let mut sum = 0.0;
        for c in 0..4 {
            let (j, w) = (joints[4 * v + c] as usize, weights[4 * v + c]);
            // An unused slot may name any joint; written back, it names the first.
            file.0[c] = u16::try_from(j).ok().filter(|_| j < count).unwrap_or(0);
            file.1[c] = w as f32;
            if w < 0.0 {
                return Err(parse(
                    name,
                    format!("accessor {}: vertex {v} has a negative weight", wa.index()),
                ));
            }
            if w > 0.0 && j >= count {
                return Err(parse(
                    name,
                    format!(
                        "accessor {}: vertex {v} uses joint {j}, but skin {} has {count}",
                        ja.index(),
                        skin.index()
                    ),
                ));
            }
            js[c] = (j.min(count.saturating_sub(1)), w);
            sum += w;
        }
        if sum <= 0.0 {
            return Err(parse(
                name,
                format!(
                    "accessor {}: vertex {v}'s skin weights are all zero",
                    wa.index()
                ),
            ));
        }
        for j in &mut js {
            j.1 /= sum;
        }
        out.push(Influence::Skinned {
            local: local[v],
            skin: skin.index(),
            joints: js,
            file,
        });
    }
    Ok(out)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Path {
    T,
    R,
    S,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Interp {
    Step,
    Linear,
    Cubic,
}

/// One animation channel as read: its node's TRS path, keys and values.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Channel {
    pub(crate) node: usize,
    pub(crate) path: Path,
    pub(crate) interp: Interp,
    pub(crate) times: Vec<f64>,
    /// Per key one value (LINEAR, STEP) or in-tangent, value, out-tangent (CUBICSPLINE),
    /// each of 3 or 4 components padded to 4.
    pub(crate) values: Vec<[f64; 4]>,
}

impl Channel {
    fn at(&self, t: f64) -> [f64; 4] {
        let per = if self.interp == Interp::Cubic { 3 } else { 1 };
        let value = |k: usize| self.values[k * per + per / 2];
        let last = self.times.len() - 1;
        if t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[last] {
            return value(last);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let u = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        let (a, b) = (value(k), value(k + 1));
        match self.interp {
            Interp::Step => a,
            Interp::Linear if self.path == Path::R => {
                let q0 = DQuat::from_array(a);
                let q1 = DQuat::from_array(b);
                q0.slerp(q1, u).to_array()
            }
            Interp::Linear => std::array::from_fn(|c| a[c] + (b[c] - a[c]) * u),
            Interp::Cubic => {
                let (m0, m1) = (self.values[k * 3 + 2], self.values[(k + 1) * 3]);
                let (u2, u3) = (u * u, u * u * u);
                let h = [
                    2.0 * u3 - 3.0 * u2 + 1.0,
                    (u3 - 2.0 * u2 + u) * dt,
                    -2.0 * u3 + 3.0 * u2,
                    (u3 - u2) * dt,
                ];
                std::array::from_fn(|c| h[0] * a[c] + h[1] * m0[c] + h[2] * b[c] + h[3] * m1[c])
            }
        }
    }
}

struct Animation {
    /// The glTF animation's name, if it has one.
    name: Option<String>,
    /// Its index in the file, which names it when it has no name (`animation N`).
    index: usize,
    channels: Vec<Channel>,
    keys: Vec<f64>,
}

fn read_animations(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    name: &str,
) -> Result<Vec<Animation>, IoError> {
    let mut out = Vec::new();
    for anim in doc.animations() {
        let mut channels = Vec::new();
        let mut keys = BTreeSet::new();
        for (ci, ch) in anim.channels().enumerate() {
            use gltf::animation::{Interpolation, Property};
            let path = match ch.target().property() {
                Property::Translation => Path::T,
                Property::Rotation => Path::R,
                Property::Scale => Path::S,
                Property::MorphTargetWeights => continue,
            };
            let sampler = ch.sampler();
            let interp = match sampler.interpolation() {
                Interpolation::Step => Interp::Step,
                Interpolation::Linear => Interp::Linear,
                Interpolation::CubicSpline => Interp::Cubic,
            };
            let times = read_f64s(&sampler.input(), 1, buffers, name)?;
            let comps = if path == Path::R { 4 } else { 3 };
            let raw = read_f64s(&sampler.output(), comps, buffers, name)?;
            let per = if interp == Interp::Cubic { 3 } else { 1 };
            let where_ = format!("animation {} channel {ci}", anim.index());
            if times.is_empty() || raw.len() != times.len() * per * comps {
                return Err(parse(
                    name,
                    format!(
                        "{where_}: {} input times but {} output values (expected {})",
                        times.len(),
                        raw.len() / comps,
                        times.len() * per
                    ),
                ));
            }
            if times.windows(2).any(|w| w[1] < w[0]) {
                return Err(parse(
                    name,
                    format!("{where_}: input times are not increasing"),
                ));
            }
            let values = raw
                .chunks_exact(comps)
                .map(|c| {
                    let mut v = [0.0; 4];
                    v[..comps].copy_from_slice(c);
                    v
                })
                .collect();
            keys.extend(times.iter().map(|t| t.to_bits()));
            channels.push(Channel {
                node: ch.target().node().index(),
                path,
                interp,
                times,
                values,
            });
        }
        let mut keys: Vec<f64> = keys.into_iter().map(f64::from_bits).collect();
        keys.sort_by(f64::total_cmp);
        if !channels.is_empty() {
            out.push(Animation {
                name: anim.name().map(str::to_owned),
                index: anim.index(),
                channels,
                keys,
            });
        }
    }
    Ok(out)
}

/// Every node's local transform at time `t` of `anim`.
fn locals_at(nodes: &Nodes, anim: &Animation, t: f64) -> Vec<Local> {
    let mut locals = nodes.rest.clone();
    for ch in &anim.channels {
        let v = ch.at(t);
        let (mut tr, mut r, mut s) = match locals[ch.node] {
            Local::Trs(tr, r, s) => (tr, r, s),
            // Animated nodes must not have matrices; take the matrix apart if one does.
            Local::Matrix(m) => {
                let (s, r, tr) = m.to_scale_rotation_translation();
                (tr, r, s)
            }
        };
        match ch.path {
            Path::T => tr = DVec3::new(v[0], v[1], v[2]),
            Path::R => r = unit(DQuat::from_array(v)),
            Path::S => s = DVec3::new(v[0], v[1], v[2]),
        }
        locals[ch.node] = Local::Trs(tr, r, s);
    }
    locals
}

/// A skinned document's rig, built while its meshes are read.
pub(crate) struct Character {
    nodes: Nodes,
    /// Per skin: its joints' nodes and inverse bind matrices.
    skins: Vec<(Vec<usize>, Vec<DMat4>)>,
    /// The skeleton's joints' nodes, ascending.
    joint_nodes: Vec<usize>,
    rest_worlds: Vec<DMat4>,
    /// [`Character::joint_matrices`] at rest.
    rest_matrices: Vec<Vec<DMat4>>,
    pub(crate) influences: Vec<Influence>,
    animations: Vec<Animation>,
}

impl Character {
    /// `None` for a document without skins: it is read as before, with no rig.
    pub(crate) fn new(
        doc: &gltf::Document,
        rest: &[Local],
        buffers: &[Vec<u8>],
        name: &str,
    ) -> Result<Option<Self>, IoError> {
        if doc.skins().next().is_none() {
            return Ok(None);
        }
        let nodes = Nodes::new(doc, rest.to_vec(), name)?;
        let mut skins = Vec::new();
        let mut joint_nodes = BTreeSet::new();
        for skin in doc.skins() {
            let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
            if joints.is_empty() {
                return Err(parse(name, format!("skin {} has no joints", skin.index())));
            }
            let ibm = match skin.inverse_bind_matrices() {
                None => vec![DMat4::IDENTITY; joints.len()],
                Some(acc) => {
                    if acc.dimensions() != Dimensions::Mat4 || acc.count() != joints.len() {
                        return Err(parse(
                            name,
                            format!(
                                "skin {}: {} inverse bind matrices for {} joints",
                                skin.index(),
                                acc.count(),
                                joints.len()
                            ),
                        ));
                    }
                    let (data, off, stride) =
                        crate::gltf_in::accessor_bytes(&acc, 64, buffers, name)?;
                    (0..acc.count())
                        .map(|k| {
                            let o = off + k * stride;
                            let f: [f64; 16] = std::array::from_fn(|c| {
                                let b = &data[o + 4 * c..o + 4 * c + 4];
                                f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64
                            });
                            DMat4::from_cols_array(&f)
                        })
                        .collect()
                }
            };
            joint_nodes.extend(joints.iter().copied());
            skins.push((joints, ibm));
        }
        let rest_worlds = nodes.worlds(&nodes.rest);
        let animations = read_animations(doc, buffers, name)?;
        let mut character = Self {
            nodes,
            skins,
            joint_nodes: joint_nodes.into_iter().collect(),
            rest_worlds,
            rest_matrices: Vec::new(),
            influences: Vec::new(),
            animations,
        };
        character.rest_matrices = character.joint_matrices(&character.rest_worlds);
        Ok(Some(character))
    }

    /// Each skin's joint matrices (joint world times inverse bind matrix) when the nodes'
    /// world matrices are `worlds`: computed once per pose, not once per vertex.
    fn joint_matrices(&self, worlds: &[DMat4]) -> Vec<Vec<DMat4>> {
        self.skins
            .iter()
            .map(|(nodes, ibm)| {
                nodes
                    .iter()
                    .zip(ibm)
                    .map(|(&n, m)| worlds[n] * *m)
                    .collect()
            })
            .collect()
    }

    /// Where a vertex is when the nodes' world matrices are `worlds` and the skins' joint
    /// matrices `matrices` ([`Character::joint_matrices`]).
    fn place(inf: &Influence, worlds: &[DMat4], matrices: &[Vec<DMat4>]) -> DVec3 {
        match *inf {
            Influence::Rigid { local, node } => worlds[node].transform_point3(local),
            Influence::Skinned {
                local,
                skin,
                joints,
                ..
            } => joints
                .iter()
                .filter(|j| j.1 > 0.0)
                .map(|&(j, w)| matrices[skin][j].transform_point3(local) * w)
                .sum(),
        }
    }

    /// The rest position of a vertex, recorded with its influence.
    pub(crate) fn add(&mut self, inf: Influence) -> DVec3 {
        let p = Self::place(&inf, &self.rest_worlds, &self.rest_matrices);
        self.influences.push(inf);
        p
    }

    /// The skeleton joint a node moves with: itself or its nearest joint ancestor, else the
    /// first joint.
    fn joint_of(&self, mut node: usize) -> usize {
        loop {
            if let Ok(j) = self.joint_nodes.binary_search(&node) {
                return j;
            }
            match self.nodes.parent[node] {
                Some(p) => node = p,
                None => return 0,
            }
        }
    }

    /// The rig of the loaded mesh: `positions` are the raw (rest) vertices the reader
    /// produced, `triangles` its raw triangles, `dropped` and `flipped` what finishing did.
    pub(crate) fn rig(
        &self,
        doc: &gltf::Document,
        positions: &[DVec3],
        triangles: &[[usize; 3]],
        dropped: &[usize],
        flipped: bool,
    ) -> (Rig, CharacterInfo) {
        let joints: Vec<Joint> = self
            .joint_nodes
            .iter()
            .map(|&node| {
                let mut up = self.nodes.parent[node];
                let parent = loop {
                    match up {
                        Some(p) => match self.joint_nodes.binary_search(&p) {
                            Ok(j) => break Some(j),
                            Err(_) => up = self.nodes.parent[p],
                        },
                        None => break None,
                    }
                };
                Joint {
                    name: doc
                        .nodes()
                        .nth(node)
                        .and_then(|n| n.name().map(str::to_owned))
                        .unwrap_or_else(|| format!("node {node}")),
                    parent,
                    rest: self.rest_worlds[node],
                    node: Some(node),
                }
            })
            .collect();
        // Weights per welded vertex: the first raw vertex at its position.
        let (welded, remap) = weld(positions);
        let mut weights = vec![[(0u32, 0.0f32); 4]; welded.len()];
        let mut set = vec![false; welded.len()];
        for (i, inf) in self.influences.iter().enumerate() {
            let w = remap[i] as usize;
            if std::mem::replace(&mut set[w], true) {
                continue;
            }
            weights[w] = match *inf {
                Influence::Rigid { node, .. } => [
                    (self.joint_of(node) as u32, 1.0),
                    (0, 0.0),
                    (0, 0.0),
                    (0, 0.0),
                ],
                Influence::Skinned { skin, joints, .. } => {
                    joints.map(|(j, x)| (self.joint_of(self.skins[skin].0[j]) as u32, x as f32))
                }
            };
        }
        let mut dropped = dropped.iter().peekable();
        let corners = triangles
            .iter()
            .enumerate()
            .filter(|(k, _)| dropped.next_if_eq(&k).is_none())
            .map(|(_, &[a, b, c])| {
                let t = if flipped { [a, c, b] } else { [a, b, c] };
                t.map(|i| i as u32)
            })
            .collect();
        let poses = self.poses();
        let info = CharacterInfo {
            joints: joints.len(),
            skins: self.skins.len(),
            animations: self.animations.len(),
            poses: poses.len(),
        };
        let rig = Rig {
            skeleton: Skeleton { joints },
            skin: Some(Skin {
                weights,
                corners,
                poses,
            }),
        };
        (rig, info)
    }

    /// The animations' names, in the order [`Pose::animation`] numbers them (animations
    /// with no transform channel are left out, as they pose nothing).
    pub(crate) fn animation_names(&self) -> Vec<String> {
        self.animations
            .iter()
            .map(|a| {
                a.name
                    .clone()
                    .unwrap_or_else(|| format!("animation {}", a.index))
            })
            .collect()
    }

    /// The sampled poses: every key and the midpoints between keys, thinned evenly when
    /// they would hold more than [`MAX_POSED_VERTICES`] positions.
    fn poses(&self) -> Vec<Pose> {
        let n = self.influences.len().max(1);
        let mut times: Vec<(usize, f64)> = Vec::new();
        for (a, anim) in self.animations.iter().enumerate() {
            for (i, &t) in anim.keys.iter().enumerate() {
                times.push((a, t));
                if let Some(&next) = anim.keys.get(i + 1) {
                    times.push((a, 0.5 * (t + next)));
                }
            }
        }
        let budget = (MAX_POSED_VERTICES / n).max(1);
        if times.len() > budget {
            let step = times.len() as f64 / budget as f64;
            times = (0..budget)
                .map(|i| times[(i as f64 * step) as usize])
                .collect();
        }
        times
            .into_iter()
            .map(|(a, t)| {
                let worlds = self
                    .nodes
                    .worlds(&locals_at(&self.nodes, &self.animations[a], t));
                let matrices = self.joint_matrices(&worlds);
                Pose {
                    animation: a,
                    time: t,
                    joints: self.joint_nodes.iter().map(|&j| worlds[j]).collect(),
                    vertices: self
                        .influences
                        .iter()
                        .map(|inf| Self::place(inf, &worlds, &matrices))
                        .collect(),
                }
            })
            .collect()
    }
}

/// A skinned file's skins, skinning data and animations, carried from the reader to the GLB
/// writer ([`crate::LoadedMesh::skinning`], [`crate::export::ExportOptions::skinning`]), so
/// that the output's mesh moves with its joints as the input's did, and so do the colliders
/// hanging under them. Everything is kept as the file has it (node transforms, inverse bind
/// matrices, JOINTS_0 and WEIGHTS_0, keys), with node indices into [`Skinning`]'s own nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct Skinning {
    /// Every skin joint, every node of an unskinned mesh that was read, and all their
    /// ancestors, in the file's order.
    pub(crate) nodes: Vec<SkinNode>,
    /// The skins (equal ones of the file merged), then, when unskinned meshes were read, one
    /// more whose joints are their nodes (identity inverse bind matrices).
    pub(crate) skins: Vec<OutSkin>,
    /// Per vertex the reader produced (the indices of [`bvseg_core::Skin::corners`]).
    pub(crate) vertices: Vec<SkinnedVertex>,
    /// The animations, with only their channels that move [`Skinning::nodes`].
    pub(crate) animations: Vec<OutAnimation>,
}

/// One node of a [`Skinning`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SkinNode {
    /// Its index in the file: what the core's [`bvseg_core::Joint::node`] names.
    pub(crate) file_index: usize,
    pub(crate) name: Option<String>,
    /// Index into [`Skinning::nodes`].
    pub(crate) parent: Option<usize>,
    pub(crate) local: Local,
}

/// One skin of a [`Skinning`]: joints as indices into [`Skinning::nodes`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OutSkin {
    pub(crate) joints: Vec<usize>,
    pub(crate) inverse_bind: Vec<DMat4>,
}

/// One vertex of a [`Skinning`]: its position in its mesh's frame (as the file has it, in
/// bind space), its skin, and JOINTS_0 (into that skin's joints) and WEIGHTS_0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SkinnedVertex {
    pub(crate) skin: usize,
    pub(crate) position: DVec3,
    pub(crate) joints: [u16; 4],
    pub(crate) weights: [f32; 4],
}

/// One animation of a [`Skinning`], channels on [`Skinning::nodes`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OutAnimation {
    pub(crate) name: Option<String>,
    pub(crate) channels: Vec<Channel>,
}

impl Skinning {
    /// The index into [`Skinning::nodes`] of the file's node `file_index`.
    pub(crate) fn node_of(&self, file_index: usize) -> Option<usize> {
        self.nodes
            .binary_search_by_key(&file_index, |n| n.file_index)
            .ok()
    }
}

impl Character {
    /// What the GLB writer needs to write the mesh skinned and the animations (see
    /// [`Skinning`]).
    pub(crate) fn skinning(&self, doc: &gltf::Document) -> Skinning {
        let n = self.nodes.parent.len();
        let mut rigid_nodes = BTreeSet::new();
        for inf in &self.influences {
            if let Influence::Rigid { node, .. } = *inf {
                rigid_nodes.insert(node);
            }
        }
        let mut keep = vec![false; n];
        for &start in self.skins.iter().flat_map(|s| &s.0).chain(&rigid_nodes) {
            let mut at = Some(start);
            while let Some(i) = at.filter(|&i| !keep[i]) {
                keep[i] = true;
                at = self.nodes.parent[i];
            }
        }
        let mut index = vec![usize::MAX; n];
        let mut nodes = Vec::new();
        for (i, node) in doc.nodes().enumerate().filter(|(i, _)| keep[*i]) {
            index[i] = nodes.len();
            nodes.push(SkinNode {
                file_index: i,
                name: node.name().map(str::to_owned),
                parent: self.nodes.parent[i].map(|p| index[p]),
                local: self.nodes.rest[i],
            });
        }
        // A parent may come after its child in the file: fill parents in a second pass.
        for node in &mut nodes {
            node.parent = self.nodes.parent[node.file_index].map(|p| index[p]);
        }
        let mut skins: Vec<OutSkin> = Vec::new();
        let out_skin: Vec<usize> = self
            .skins
            .iter()
            .map(|(joints, ibm)| {
                let skin = OutSkin {
                    joints: joints.iter().map(|&j| index[j]).collect(),
                    inverse_bind: ibm.clone(),
                };
                skins.iter().position(|s| *s == skin).unwrap_or_else(|| {
                    skins.push(skin);
                    skins.len() - 1
                })
            })
            .collect();
        let rigid: Vec<usize> = rigid_nodes.into_iter().collect();
        let rigid_skin = skins.len();
        if !rigid.is_empty() {
            skins.push(OutSkin {
                joints: rigid.iter().map(|&j| index[j]).collect(),
                inverse_bind: vec![DMat4::IDENTITY; rigid.len()],
            });
        }
        let vertices = self
            .influences
            .iter()
            .map(|inf| match *inf {
                Influence::Skinned {
                    local, skin, file, ..
                } => SkinnedVertex {
                    skin: out_skin[skin],
                    position: local,
                    joints: file.0,
                    weights: file.1,
                },
                Influence::Rigid { local, node } => SkinnedVertex {
                    skin: rigid_skin,
                    position: local,
                    joints: [rigid.binary_search(&node).unwrap_or(0) as u16, 0, 0, 0],
                    weights: [1.0, 0.0, 0.0, 0.0],
                },
            })
            .collect();
        let animations = self
            .animations
            .iter()
            .map(|a| OutAnimation {
                name: a.name.clone(),
                channels: a
                    .channels
                    .iter()
                    .filter(|c| keep[c.node])
                    .map(|c| Channel {
                        node: index[c.node],
                        ..c.clone()
                    })
                    .collect(),
            })
            .filter(|a| !a.channels.is_empty())
            .collect();
        Skinning {
            nodes,
            skins,
            vertices,
            animations,
        }
    }
}
