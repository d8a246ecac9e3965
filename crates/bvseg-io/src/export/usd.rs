//! USD output (`.usda`, the text form) with UsdPhysics colliders, as Isaac Sim and Isaac Lab,
//! Omniverse, Newton and Unreal's USD importer read them.
//!
//! The stage holds one root `Xform` (the stage's `defaultPrim`, optionally a
//! `PhysicsRigidBodyAPI` body) and under it one prim per volume, each with
//! `PhysicsCollisionAPI`, `purpose = "guide"` (so renderers hide it) and its `extent`:
//!
//! - a box is a `Cube` of size 2 scaled by its half-extents (non-uniform scale is allowed on
//!   a cube), placed by `translate` and `orient`;
//! - a sphere is a `Sphere` (`radius`, `translate`);
//! - a capsule or cylinder is a `Capsule` or `Cylinder` along `axis = "Z"` with its `height`
//!   (a capsule's without its caps) and `radius`, placed by `translate` and `orient` only: no
//!   scale, which PhysX and the UsdPhysics validators reject on these shapes unless uniform;
//! - a hull is a `Mesh` of its triangles with `PhysicsMeshCollisionAPI` and
//!   `physics:approximation = "convexHull"`;
//! - an ellipsoid, which UsdPhysics has no shape for, is the convex `Mesh` of
//!   [`Polytope::around_unit_ball`] (64 vertices, PhysX's limit on a hull) mapped by the
//!   ellipsoid's frame, which encloses it.
//!
//! Transforms are written in double precision (`double3`, `quatd`) so that a collider sits
//! where its volume is to the last bits; mesh points are single precision in USD
//! (`point3f[]`), so a mesh is pushed out about its centre by more than `f32` rounding can
//! move a point, and still encloses its volume. The volumes are in the mesh's coordinates:
//! the stage's `upAxis` and `metersPerUnit` declare them, they do not convert them.
//!
//! For a character (volumes bound to the bones of a skeleton), the volumes stay in model
//! space at the rest pose, and each carries the name of its bone in a custom string
//! attribute `bvseg:bone`.
use std::fmt::Write;

use bvseg_core::{BoundingVolume, Polytope, Segmentation, ShapeView};
use glam::{DQuat, DVec3};

use super::proxy::{hull_vertices, volume_rotation};

/// The stage's up axis, as USD's `upAxis` names it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// Y up: glTF's convention, and most OBJ files'.
    #[default]
    Y,
    /// Z up: URDF's and MuJoCo's convention, and many CAD exports'.
    Z,
}

impl UpAxis {
    /// The `upAxis` token.
    pub fn as_str(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }
}

/// What a USD file declares and adds beyond the volumes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UsdOptions {
    /// The stage's `upAxis`.
    pub up_axis: UpAxis,
    /// The stage's `metersPerUnit`: the length of one unit of the mesh, in meters. Finite
    /// and above 0 ([`super::write_output`] refuses others).
    pub meters_per_unit: f64,
    /// Whether the root prim is a rigid body (`PhysicsRigidBodyAPI`), whose colliders move
    /// together; without it they are static.
    pub rigid_body: bool,
}

impl Default for UsdOptions {
    fn default() -> Self {
        Self {
            up_axis: UpAxis::Y,
            meters_per_unit: 1.0,
            rigid_body: false,
        }
    }
}

/// The segmentation as a USDA document whose root prim is named after `root` (made a valid
/// USD identifier: `bunny`, `my_robot_01`; `bvseg` when nothing is left of it).
pub fn to_usda(seg: &Segmentation, root: &str, options: &UsdOptions) -> String {
    let root = identifier(root);
    let doc = format!(
        "{}: {} {} volumes, TOV {} MOV {}",
        crate::GENERATOR,
        seg.parts.len(),
        seg.kinds,
        seg.metrics.tov,
        seg.metrics.mov
    );
    let mut s = String::new();
    stage_header(&mut s, &root, &doc, options);
    let schemas: &[&str] = if options.rigid_body {
        &["PhysicsRigidBodyAPI"]
    } else {
        &[]
    };
    open_prim(&mut s, 0, "Xform", &root, schemas);
    let bones = seg.skeleton.as_ref().map(|sk| &sk.joints);
    for (i, part) in seg.parts.iter().enumerate() {
        let bone = part
            .bone
            .and_then(|b| bones.and_then(|j| j.get(b)))
            .map(|j| format!("custom string bvseg:bone = {}", quote(&j.name)));
        collider(
            &mut s,
            1,
            &part.volume,
            &format!("part_{i}"),
            bone.as_slice(),
        );
    }
    close_prim(&mut s, 0);
    s
}

/// The layer's header: `defaultPrim`, the generator's line, `metersPerUnit`, `upAxis`.
pub(crate) fn stage_header(s: &mut String, default_prim: &str, doc: &str, options: &UsdOptions) {
    s.push_str("#usda 1.0\n(\n");
    let _ = writeln!(s, "    defaultPrim = {}", quote(default_prim));
    let _ = writeln!(s, "    doc = {}", quote(doc));
    let _ = writeln!(s, "    metersPerUnit = {}", options.meters_per_unit);
    let _ = writeln!(s, "    upAxis = {}", quote(options.up_axis.as_str()));
    s.push_str(")\n\n");
}

/// `def TYPE "name" (prepend apiSchemas = [...]) {` at `depth`.
pub(crate) fn open_prim(s: &mut String, depth: usize, kind: &str, name: &str, schemas: &[&str]) {
    let pad = "    ".repeat(depth);
    let _ = write!(s, "{pad}def {kind} {}", quote(name));
    if !schemas.is_empty() {
        let list: Vec<String> = schemas.iter().map(|a| quote(a)).collect();
        let _ = write!(
            s,
            " (\n{pad}    prepend apiSchemas = [{}]\n{pad})",
            list.join(", ")
        );
    }
    let _ = writeln!(s, "\n{pad}{{");
}

/// The `}` of [`open_prim`].
pub(crate) fn close_prim(s: &mut String, depth: usize) {
    let _ = writeln!(s, "{}}}", "    ".repeat(depth));
}

/// An `Xform` prim at `depth` placed by `translate` and `orient`, left open (close it with
/// [`close_prim`]).
pub(crate) fn open_xform(s: &mut String, depth: usize, name: &str, t: DVec3, q: DQuat) {
    open_prim(s, depth, "Xform", name, &[]);
    let pad = "    ".repeat(depth + 1);
    let _ = writeln!(s, "{pad}double3 xformOp:translate = {}", double3(t));
    let _ = writeln!(s, "{pad}quatd xformOp:orient = {}", quat(q));
    let _ = writeln!(
        s,
        "{pad}uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]"
    );
}

/// What a collider prim is made of: its type, API schemas, attribute lines, extent in its
/// own frame, and the xform ops after `translate` (the volume's centre).
struct PrimSpec {
    kind: &'static str,
    schemas: &'static [&'static str],
    attrs: Vec<String>,
    extent: (DVec3, DVec3),
    /// Rotated by the volume's frame (`orient`).
    orient: bool,
    /// Scaled (`scale`): only a cube, by its half-extents.
    scale: Option<DVec3>,
}

const COLLISION: &[&str] = &["PhysicsCollisionAPI"];
const MESH_COLLISION: &[&str] = &["PhysicsCollisionAPI", "PhysicsMeshCollisionAPI"];

impl PrimSpec {
    fn of(v: &BoundingVolume) -> Self {
        let symmetric = |half: DVec3| (-half, half);
        match v.view() {
            ShapeView::Obb { half_extents, .. } => Self {
                kind: "Cube",
                schemas: COLLISION,
                attrs: vec!["double size = 2".to_owned()],
                extent: symmetric(DVec3::ONE),
                orient: true,
                scale: Some(half_extents),
            },
            ShapeView::Sphere { radius, .. } => Self::sphere(radius),
            // A capsule as short as a ball is one.
            ShapeView::Capsule {
                half_length,
                radius,
                ..
            } if half_length <= 0.0 => Self::sphere(radius),
            ShapeView::Capsule {
                half_length,
                radius,
                ..
            } => Self {
                kind: "Capsule",
                schemas: COLLISION,
                attrs: axial(half_length, radius),
                extent: symmetric(DVec3::new(radius, radius, half_length + radius)),
                orient: true,
                scale: None,
            },
            ShapeView::Cylinder {
                half_length,
                radius,
                ..
            } => Self {
                kind: "Cylinder",
                schemas: COLLISION,
                attrs: axial(half_length, radius),
                extent: symmetric(DVec3::new(radius, radius, half_length)),
                orient: true,
                scale: None,
            },
            // The hull's points around its centre, in world axes.
            ShapeView::Hull { .. } => {
                let (points, triangles) = hull_vertices(v);
                Self::convex_mesh(&points, &triangles, false)
            }
            // The cover of the unit ball scaled by the radii, in the ellipsoid's frame.
            ShapeView::Ellipsoid { radii, .. } => {
                let cover = Polytope::around_unit_ball();
                let points: Vec<DVec3> = cover.vertices().iter().map(|&p| p * radii).collect();
                Self::convex_mesh(&points, cover.triangles(), true)
            }
        }
    }

    fn sphere(radius: f64) -> Self {
        Self {
            kind: "Sphere",
            schemas: COLLISION,
            attrs: vec![format!("double radius = {radius}")],
            extent: (DVec3::splat(-radius), DVec3::splat(radius)),
            orient: false,
            scale: None,
        }
    }

    fn convex_mesh(points: &[DVec3], triangles: &[[u32; 3]], orient: bool) -> Self {
        let (attrs, extent) = convex_mesh(points, triangles);
        Self {
            kind: "Mesh",
            schemas: MESH_COLLISION,
            attrs,
            extent,
            orient,
            scale: None,
        }
    }
}

/// One volume as a collider prim named `name` at `depth`, with `extra` attribute lines.
pub(crate) fn collider(
    s: &mut String,
    depth: usize,
    v: &BoundingVolume,
    name: &str,
    extra: &[String],
) {
    let spec = PrimSpec::of(v);
    open_prim(s, depth, spec.kind, name, spec.schemas);
    let pad = "    ".repeat(depth + 1);
    let (lo, hi) = spec.extent;
    let _ = writeln!(
        s,
        "{pad}float3[] extent = [{}, {}]",
        float3(lo, f32_down),
        float3(hi, f32_up)
    );
    for a in spec.attrs.iter().chain(extra) {
        let _ = writeln!(s, "{pad}{a}");
    }
    let _ = writeln!(s, "{pad}uniform token purpose = \"guide\"");
    let mut order = vec!["\"xformOp:translate\""];
    let _ = writeln!(s, "{pad}double3 xformOp:translate = {}", double3(v.center));
    if spec.orient {
        let _ = writeln!(
            s,
            "{pad}quatd xformOp:orient = {}",
            quat(volume_rotation(v))
        );
        order.push("\"xformOp:orient\"");
    }
    if let Some(k) = spec.scale {
        let _ = writeln!(s, "{pad}double3 xformOp:scale = {}", double3(k));
        order.push("\"xformOp:scale\"");
    }
    let _ = writeln!(
        s,
        "{pad}uniform token[] xformOpOrder = [{}]",
        order.join(", ")
    );
    close_prim(s, depth);
}

/// A capsule's or cylinder's attributes: along Z, `height` twice the half-length (without
/// a capsule's caps, as UsdGeom defines it).
fn axial(half_length: f64, radius: f64) -> Vec<String> {
    vec![
        "uniform token axis = \"Z\"".to_owned(),
        format!("double height = {}", 2.0 * half_length),
        format!("double radius = {radius}"),
    ]
}

/// A convex mesh's attributes and extent, from its points around the prim's origin (which
/// lies inside) and its outward triangles. USD stores points as `f32`: each point is first
/// pushed out from the origin by a factor that moves every face plane further than rounding
/// to `f32` moves any point (at most `sqrt(3) 2^-24` of its length), so the rounded points'
/// hull still holds the exact one.
fn convex_mesh(points: &[DVec3], triangles: &[[u32; 3]]) -> (Vec<String>, (DVec3, DVec3)) {
    let far = points.iter().map(|p| p.length()).fold(0.0, f64::max);
    let near = triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|i| points.get(i as usize).copied());
            let (a, b, c) = (a?, b?, c?);
            let n = (b - a).cross(c - a).try_normalize()?;
            Some(n.dot(a))
        })
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    // 2^-21 is 4.6 times the rounding bound; a degenerate hull (no face plane with the origin
    // inside) keeps its points as they are.
    let push = if near.is_finite() {
        1.0 + 2f64.powi(-21) * far / near
    } else {
        1.0
    };
    let rounded: Vec<[f32; 3]> = points
        .iter()
        .map(|&p| (p * push).to_array().map(|x| x as f32))
        .collect();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &rounded {
        let p = DVec3::from_array(p.map(f64::from));
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let pts: Vec<String> = rounded
        .iter()
        .map(|[x, y, z]| format!("({x}, {y}, {z})"))
        .collect();
    let counts = vec!["3"; triangles.len()].join(", ");
    let indices: Vec<String> = triangles
        .iter()
        .flat_map(|t| t.iter().map(|i| i.to_string()))
        .collect();
    let attrs = vec![
        format!("int[] faceVertexCounts = [{counts}]"),
        format!("int[] faceVertexIndices = [{}]", indices.join(", ")),
        "uniform token physics:approximation = \"convexHull\"".to_owned(),
        format!("point3f[] points = [{}]", pts.join(", ")),
        // Flat faces: a renderer showing the guide should not smooth it.
        "uniform token subdivisionScheme = \"none\"".to_owned(),
    ];
    (attrs, (lo, hi))
}

/// `(x, y, z)` in double precision.
fn double3(v: DVec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

/// A quaternion as USD writes it, real part first, with `w >= 0`.
fn quat(q: DQuat) -> String {
    let q = if q.w < 0.0 { -q } else { q };
    format!("({}, {}, {}, {})", q.w, q.x, q.y, q.z)
}

/// `(x, y, z)` as `f32`, each coordinate rounded by `round` (outward for an extent).
fn float3(v: DVec3, round: fn(f64) -> f32) -> String {
    format!("({}, {}, {})", round(v.x), round(v.y), round(v.z))
}

/// The least `f32` at or above `x`.
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x {
        next_up(f)
    } else {
        f
    }
}

/// The greatest `f32` at or below `x`.
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x {
        -next_up(-f)
    } else {
        f
    }
}

/// The least `f32` above a finite `f` (`f32::next_up`, which the MSRV, 1.85, lacks).
fn next_up(f: f32) -> f32 {
    if f == 0.0 {
        f32::from_bits(1)
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f32::from_bits(f.to_bits() - 1)
    }
}

/// `s` as a USD string literal.
pub(crate) fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `s` made a USD prim name (`[A-Za-z_][A-Za-z0-9_]*`): other characters become `_`, a
/// leading digit gets a `_` before it, and an empty name is `bvseg`.
pub(crate) fn identifier(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if out.is_empty() {
        return "bvseg".to_owned();
    }
    if out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_identifiers() {
        assert_eq!(identifier("bunny"), "bunny");
        assert_eq!(identifier("my robot-01"), "my_robot_01");
        assert_eq!(identifier("1x"), "_1x");
        assert_eq!(identifier(""), "bvseg");
        assert_eq!(identifier("é"), "_");
        assert_eq!(quote("a\"b\\c\nd"), "\"a\\\"b\\\\c\\nd\"");
    }

    #[test]
    fn extents_round_outward() {
        let x = 0.1f64;
        assert!(f64::from(f32_up(x)) >= x && f64::from(f32_down(x)) <= x);
        assert!(f32_up(x) > f32_down(x));
        assert_eq!(f32_up(0.5), 0.5);
        assert_eq!(f32_down(-0.5), -0.5);
        for x in [1.0f32, -1.0, 0.0, 3.5e-40, -2.0e30] {
            let up = next_up(x);
            assert!(up > x && f32::from_bits(up.to_bits()) == up, "{x}");
            assert!(-next_up(-x) < x, "{x}");
        }
        assert_eq!(next_up(1.0), 1.0 + f32::EPSILON);
    }

    #[test]
    fn rounded_mesh_points_still_enclose_the_exact_hull() {
        // A thin slab far from the origin of its coordinates is the worst case for rounding.
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1e-3 } else { 1e-3 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                ) * DVec3::new(123.456_789, 1.0, 0.987_654_321)
            })
            .collect();
        let v = BoundingVolume::hull(&pts).unwrap();
        let (points, triangles) = hull_vertices(&v);
        let (attrs, _) = convex_mesh(&points, &triangles);
        let line = attrs.iter().find(|a| a.starts_with("point3f[]")).unwrap();
        let written: Vec<DVec3> = line
            .trim_start_matches("point3f[] points = [(")
            .trim_end_matches(")]")
            .split("), (")
            .map(|p| {
                let c: Vec<f64> = p.split(", ").map(|x| x.parse().unwrap()).collect();
                DVec3::new(c[0], c[1], c[2])
            })
            .collect();
        let back = BoundingVolume::hull(&written.iter().map(|&p| p + v.center).collect::<Vec<_>>())
            .unwrap();
        for p in v.hull_points() {
            assert!(back.gauge(p) <= 1.0, "{p}: {}", back.gauge(p));
        }
    }
}
