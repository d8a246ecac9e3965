//! What the 3D view draws, as plain vertex arrays: the mesh (plain or coloured by part) and the
//! bounding volumes (translucent surfaces or wireframes), one colour per part. Building them on
//! the CPU keeps the renderer a dumb uploader, and lets the tests check the geometry.
use std::sync::OnceLock;

use bvseg_core::{BoundingVolume, Mesh, Pose, Shape, Skin};
use glam::{DMat3, DMat4, DVec3, Vec3};

use crate::session::{Snapshot, UNKNOWN_PART};

/// Floats per vertex: position (3), normal (3), colour RGBA (4).
pub const VERTEX_FLOATS: usize = 10;

/// The plain mesh colour (a warm light grey).
pub const MESH_COLOR: [f32; 3] = [0.80, 0.77, 0.70];

/// Colour of part `i`: the palette of `bvseg_io`'s exports, so that a saved GLB shows the
/// parts in the colours of the view.
pub fn part_color(i: usize) -> [f32; 3] {
    bvseg_io::export::part_color(i).map(|c| c as f32)
}

/// How the bounding volumes are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VolumeStyle {
    /// Translucent surfaces.
    Translucent,
    /// Outlines (see [`volume_edges`]): principal ellipses, edges, rims.
    Wireframe,
    /// Not drawn.
    Hidden,
}

/// The view's display settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Display {
    /// Colour the mesh by part (otherwise one plain colour).
    pub colour_by_part: bool,
    /// Draw the mesh translucent, to see the volumes inside.
    pub translucent_mesh: bool,
    /// How the volumes are drawn.
    pub volumes: VolumeStyle,
}

impl Default for Display {
    fn default() -> Self {
        Self {
            colour_by_part: true,
            translucent_mesh: false,
            volumes: VolumeStyle::Translucent,
        }
    }
}

/// A mesh prepared for drawing: flat-shaded corners relative to its centre, in `f32`.
#[derive(Debug, Clone)]
pub struct MeshGeometry {
    /// The mesh's bounding-box centre, subtracted from every position.
    pub center: DVec3,
    /// Radius of the bounding sphere around `center`.
    pub radius: f32,
    /// Three corners per triangle.
    pub corners: Vec<Vec3>,
    /// One unit normal per triangle.
    pub normals: Vec<Vec3>,
}

impl MeshGeometry {
    /// Prepares `mesh` in its rest pose. The radius of a rigged mesh covers its sampled poses
    /// too, so that the view frames the whole animation.
    pub fn new(mesh: &Mesh) -> Self {
        let (lo, hi) = mesh.bbox();
        let center = (lo + hi) * 0.5;
        let mut radius = (hi - lo).length() * 0.5;
        if let Some(skin) = mesh.rig().and_then(|r| r.skin.as_ref()) {
            for p in skin.poses.iter().flat_map(|p| &p.vertices) {
                radius = radius.max((*p - center).length());
            }
        }
        let triangles = (0..mesh.triangles().len()).map(|t| mesh.corners(t));
        Self::from_triangles(center, radius as f32, triangles)
    }

    /// This rest-pose geometry of a rigged mesh in one of its sampled poses: the corners the
    /// loader skinned there ([`Pose::vertices`] through [`Skin::corners`]), around the rest
    /// pose's centre so that the view stays where it is.
    pub fn posed(&self, skin: &Skin, pose: &Pose) -> Self {
        let triangles = skin
            .corners
            .iter()
            .map(|c| c.map(|i| pose.vertices.get(i as usize).copied().unwrap_or_default()));
        Self::from_triangles(self.center, self.radius, triangles)
    }

    fn from_triangles(
        center: DVec3,
        radius: f32,
        triangles: impl ExactSizeIterator<Item = [DVec3; 3]>,
    ) -> Self {
        let mut corners = Vec::with_capacity(triangles.len() * 3);
        let mut normals = Vec::with_capacity(triangles.len());
        for t in triangles {
            let c = t.map(|p| (p - center).as_vec3());
            normals.push((c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero());
            corners.extend_from_slice(&c);
        }
        Self {
            center,
            radius,
            corners,
            normals,
        }
    }
}

/// Vertex arrays for the three passes of the renderer.
#[derive(Debug, Clone, Default)]
pub struct Geometry {
    /// Opaque triangles (depth-written).
    pub opaque: Vec<f32>,
    /// Lines (depth-tested, unlit).
    pub lines: Vec<f32>,
    /// Translucent triangles (blended, drawn last without depth writes).
    pub translucent: Vec<f32>,
}

impl Geometry {
    /// Number of vertices in each pass: opaque, lines, translucent.
    pub fn counts(&self) -> [usize; 3] {
        [
            self.opaque.len() / VERTEX_FLOATS,
            self.lines.len() / VERTEX_FLOATS,
            self.translucent.len() / VERTEX_FLOATS,
        ]
    }
}

fn push(out: &mut Vec<f32>, p: Vec3, n: Vec3, c: [f32; 3], a: f32) {
    out.extend_from_slice(&[p.x, p.y, p.z, n.x, n.y, n.z, c[0], c[1], c[2], a]);
}

/// Greys `c` out, for what is not highlighted.
fn dim(c: [f32; 3]) -> [f32; 3] {
    let g = 0.3 * c[0] + 0.5 * c[1] + 0.2 * c[2];
    [
        0.35 * c[0] + 0.65 * g,
        0.35 * c[1] + 0.65 * g,
        0.35 * c[2] + 0.65 * g,
    ]
    .map(|x| x * 0.8)
}

/// Builds what the view draws: `mesh` coloured by `snapshot`'s parts (when given and asked
/// for), the snapshot's volumes, volume `i` moved by `moves[i]` when given (a character's
/// pose: see [`crate::animation`]; empty at rest), and `selected`'s part highlighted.
pub fn build(
    mesh: &MeshGeometry,
    snapshot: Option<&Snapshot>,
    moves: &[DMat4],
    selected: Option<usize>,
    display: Display,
) -> Geometry {
    let mut g = Geometry::default();
    let parts = snapshot.map(|s| s.triangle_parts.as_slice()).unwrap_or(&[]);
    let colour_parts = display.colour_by_part && parts.len() == mesh.normals.len();
    let (mesh_out, mesh_alpha) = if display.translucent_mesh {
        (&mut g.translucent, 0.35)
    } else {
        (&mut g.opaque, 1.0)
    };
    for (t, &n) in mesh.normals.iter().enumerate() {
        let part = if colour_parts { parts[t] } else { UNKNOWN_PART };
        let mut c = if part == UNKNOWN_PART {
            MESH_COLOR
        } else {
            part_color(part as usize)
        };
        if selected.is_some_and(|s| s != part as usize) {
            c = dim(c);
        }
        for p in &mesh.corners[3 * t..3 * t + 3] {
            push(mesh_out, *p, n, c, mesh_alpha);
        }
    }
    let Some(snap) = snapshot else {
        return g;
    };
    for (i, v) in snap.volumes.iter().enumerate() {
        let motion = moves.get(i).map(|&m| Motion::new(m));
        let lit = selected.is_none_or(|s| s == i);
        let c = if lit {
            part_color(i)
        } else {
            dim(part_color(i))
        };
        match display.volumes {
            VolumeStyle::Translucent => {
                let a = match selected {
                    Some(s) if s == i => 0.5,
                    Some(_) => 0.06,
                    None => 0.22,
                };
                volume_surface(&mut g.translucent, v, motion, mesh.center, c, a);
            }
            VolumeStyle::Wireframe => volume_outline(&mut g.lines, v, motion, mesh.center, c),
            VolumeStyle::Hidden => {}
        }
    }
    g
}

/// Latitude and longitude divisions of a drawn ellipsoid (and of a capsule's two ends).
const LAT: usize = 10;
const LON: usize = 20;

/// Segments of a drawn outline's full circle.
const SEG: usize = 48;

/// A corner of a volume's drawn surface: its position and unit outward normal, in mesh
/// coordinates.
pub type Corner = (DVec3, DVec3);

/// Unit-sphere triangles (three points each, outward), computed once.
fn sphere_triangles() -> &'static [[DVec3; 3]] {
    static SPHERE: OnceLock<Vec<[DVec3; 3]>> = OnceLock::new();
    SPHERE.get_or_init(|| {
        let at = |i: usize, j: usize| {
            let th = std::f64::consts::PI * i as f64 / LAT as f64;
            // The last meridian is the first: the seam is closed exactly.
            let ph = std::f64::consts::TAU * (j % LON) as f64 / LON as f64;
            DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
        };
        let mut out = Vec::with_capacity(2 * LAT * LON);
        for i in 0..LAT {
            for j in 0..LON {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                if i > 0 {
                    out.push([a, b, d]);
                }
                if i + 1 < LAT {
                    out.push([b, c, d]);
                }
            }
        }
        out
    })
}

/// A point of the profile of a surface of revolution about a volume's axis: distance from the
/// axis, height along it, and the outward normal in those two directions.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ProfilePoint {
    rho: f64,
    z: f64,
    n_rho: f64,
    n_z: f64,
}

/// A capsule's profile, from the top pole to the bottom one: two quarter circles (the
/// hemispherical ends) joined by the straight side.
fn capsule_profile(r: f64, h: f64) -> Vec<ProfilePoint> {
    (0..=LAT)
        .flat_map(|i| {
            let th = std::f64::consts::PI * i as f64 / LAT as f64;
            let (mut s, c) = th.sin_cos();
            if i == LAT {
                // On the axis exactly (sin pi is not 0 in floating point).
                s = 0.0;
            }
            let at = |z0: f64| ProfilePoint {
                rho: r * s,
                z: z0 + r * c,
                n_rho: s,
                n_z: c,
            };
            // The equator (i = LAT / 2) is on both ends: the side joins them.
            let mut ring = Vec::with_capacity(2);
            if 2 * i <= LAT {
                ring.push(at(h));
            }
            if 2 * i >= LAT {
                ring.push(at(-h));
            }
            ring
        })
        .collect()
}

/// A cylinder's profile, from the top cap's centre round to the bottom one's (each rim
/// twice, for the caps' and the side's normals).
fn cylinder_profile(r: f64, h: f64) -> Vec<ProfilePoint> {
    let p = |rho, z, n_rho, n_z| ProfilePoint { rho, z, n_rho, n_z };
    vec![
        p(0.0, h, 0.0, 1.0),
        p(r, h, 0.0, 1.0),
        p(r, h, 1.0, 0.0),
        p(r, -h, 1.0, 0.0),
        p(r, -h, 0.0, -1.0),
        p(0.0, -h, 0.0, -1.0),
    ]
}

/// The outward triangles of the surface swept by `profile` (top to bottom) about `v`'s axis
/// through its centre, `LON` meridians round.
fn revolve(v: &BoundingVolume, profile: &[ProfilePoint]) -> Vec<[Corner; 3]> {
    let (x, y, a) = (v.axes.x_axis, v.axes.y_axis, v.axes.z_axis);
    let at = |p: &ProfilePoint, j: usize| {
        let (s, c) = (std::f64::consts::TAU * (j % LON) as f64 / LON as f64).sin_cos();
        let radial = x * c + y * s;
        (
            v.center + radial * p.rho + a * p.z,
            (radial * p.n_rho + a * p.n_z).normalize_or_zero(),
        )
    };
    let mut out = Vec::with_capacity(2 * LON * profile.len());
    for w in profile.windows(2) {
        let (p, q) = (&w[0], &w[1]);
        if p.rho == q.rho && p.z == q.z {
            // Only the normal changes here (a rim, or a capsule's side of length 0).
            continue;
        }
        for j in 0..LON {
            let (a, b, c, d) = (at(p, j), at(q, j), at(q, j + 1), at(p, j + 1));
            if p.rho > 0.0 {
                out.push([a, b, d]);
            }
            if q.rho > 0.0 {
                out.push([b, c, d]);
            }
        }
    }
    out
}

/// The outward triangles of `v`'s drawn surface with a normal at each corner, in mesh
/// coordinates: a closed mesh whose corners all lie on `v`'s boundary (so that it is inside
/// `v`, every kind being convex). Ellipsoids and spheres are a latitude-longitude sphere
/// mapped onto them, boxes their six faces, capsules a cylinder side with hemispherical ends,
/// cylinders a side and two flat caps, hulls their polyhedron with flat faces.
pub fn volume_triangles(v: &BoundingVolume) -> Vec<[Corner; 3]> {
    match v.shape {
        Shape::Ellipsoid | Shape::Sphere => sphere_triangles()
            .iter()
            .map(|tri| {
                // The normal of the ellipsoid at axes * (radii * u) is axes * (u / radii).
                tri.map(|u| (v.world(u), (v.axes * (u / v.radii)).normalize_or_zero()))
            })
            .collect(),
        Shape::Obb => {
            let mut out = Vec::with_capacity(12);
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut n = DVec3::ZERO;
                    n[axis] = sign;
                    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                    let corner = |su: f64, sw: f64| {
                        let mut t = n;
                        t[u] = su;
                        t[w] = sw;
                        (v.world(t), v.axes * n)
                    };
                    let q = [
                        corner(-1.0, -1.0),
                        corner(1.0, -1.0),
                        corner(1.0, 1.0),
                        corner(-1.0, 1.0),
                    ];
                    // Counter-clockwise seen from outside.
                    if sign > 0.0 {
                        out.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        out.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
            out
        }
        Shape::Capsule => revolve(v, &capsule_profile(v.radius(), v.half_length())),
        Shape::Cylinder => revolve(v, &cylinder_profile(v.radius(), v.half_length())),
        Shape::Hull => {
            let points = v.hull_points();
            let Some(poly) = v.polytope() else {
                return Vec::new();
            };
            poly.triangles()
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| points[i as usize]);
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    [(a, n), (b, n), (c, n)]
                })
                .collect()
        }
    }
}

/// The segments of `v`'s outline, in mesh coordinates, all on `v`'s boundary: an ellipsoid's
/// (or sphere's) three principal ellipses, a box's twelve edges, a capsule's or cylinder's two
/// rims and four side lines (with a capsule's ends' arcs in two planes through the axis), a
/// hull's edges between faces that are not coplanar.
pub fn volume_edges(v: &BoundingVolume) -> Vec<[DVec3; 2]> {
    let mut out = Vec::new();
    let circle = |s: usize| {
        let a = std::f64::consts::TAU * s as f64 / SEG as f64;
        a.sin_cos()
    };
    match v.shape {
        Shape::Ellipsoid | Shape::Sphere => {
            for (x, y) in [(0, 1), (1, 2), (0, 2)] {
                let at = |s: usize| {
                    let (sin, cos) = circle(s);
                    let mut t = DVec3::ZERO;
                    t[x] = cos;
                    t[y] = sin;
                    v.world(t)
                };
                out.extend((0..SEG).map(|s| [at(s), at(s + 1)]));
            }
        }
        Shape::Obb => {
            for axis in 0..3 {
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                for (su, sw) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let mut a = DVec3::ZERO;
                    a[u] = su;
                    a[w] = sw;
                    let mut b = a;
                    a[axis] = -1.0;
                    b[axis] = 1.0;
                    out.push([v.world(a), v.world(b)]);
                }
            }
        }
        Shape::Capsule | Shape::Cylinder => {
            let (r, h) = (v.radius(), v.half_length());
            let (x, y, a) = (v.axes.x_axis, v.axes.y_axis, v.axes.z_axis);
            for z in [-h, h] {
                let at = |s: usize| {
                    let (sin, cos) = circle(s);
                    v.center + (x * cos + y * sin) * r + a * z
                };
                out.extend((0..SEG).map(|s| [at(s), at(s + 1)]));
            }
            if h > 0.0 {
                for e in [x, y, -x, -y] {
                    out.push([v.center + e * r - a * h, v.center + e * r + a * h]);
                }
            }
            if v.shape == Shape::Capsule {
                // Half circles over each end, in the planes of x and of y with the axis.
                for e in [x, y] {
                    for end in [-1.0, 1.0] {
                        let at = |s: usize| {
                            let (sin, cos) = circle(s);
                            v.center + e * (r * cos) + a * end * (h + r * sin)
                        };
                        out.extend((0..SEG / 2).map(|s| [at(s), at(s + 1)]));
                    }
                }
            }
        }
        Shape::Hull => {
            let points = v.hull_points();
            let Some(poly) = v.polytope() else {
                return out;
            };
            let normals: Vec<DVec3> = poly.planes().iter().map(|p| p.0).collect();
            // Each edge with the faces on either side.
            let mut edges: Vec<([u32; 2], usize)> = poly
                .triangles()
                .iter()
                .enumerate()
                .flat_map(|(f, t)| {
                    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
                        .map(|(i, j)| ([i.min(j), i.max(j)], f))
                })
                .collect();
            edges.sort_unstable();
            let mut k = 0;
            while k < edges.len() {
                let (e, f) = edges[k];
                let mut m = k + 1;
                while m < edges.len() && edges[m].0 == e {
                    m += 1;
                }
                // A fold (or a border, which a closed hull has not): faces that meet at an
                // angle.
                let fold = m - k != 2 || normals[f].dot(normals[edges[k + 1].1]) < 1.0 - 1e-9;
                if fold {
                    out.push([points[e[0] as usize], points[e[1] as usize]]);
                }
                k = m;
            }
        }
    }
    out
}

/// How a volume moves from the rest pose to the pose drawn: points by an affine matrix,
/// normals by the inverse transpose of its linear part (a bone's matrix may scale).
#[derive(Debug, Clone, Copy)]
struct Motion {
    points: DMat4,
    normals: DMat3,
}

impl Motion {
    fn new(points: DMat4) -> Self {
        Self {
            points,
            normals: DMat3::from_mat4(points).inverse().transpose(),
        }
    }

    fn point(m: Option<Self>, p: DVec3) -> DVec3 {
        m.map_or(p, |m| m.points.transform_point3(p))
    }

    fn normal(m: Option<Self>, n: DVec3) -> DVec3 {
        m.map_or(n, |m| (m.normals * n).normalize_or_zero())
    }
}

/// Appends the triangles of `v`'s surface, moved by `motion`, relative to `origin`, in colour
/// `c` with alpha `a`.
fn volume_surface(
    out: &mut Vec<f32>,
    v: &BoundingVolume,
    motion: Option<Motion>,
    origin: DVec3,
    c: [f32; 3],
    a: f32,
) {
    for tri in volume_triangles(v) {
        for (p, n) in tri {
            let p = Motion::point(motion, p) - origin;
            push(out, p.as_vec3(), Motion::normal(motion, n).as_vec3(), c, a);
        }
    }
}

fn volume_outline(
    out: &mut Vec<f32>,
    v: &BoundingVolume,
    motion: Option<Motion>,
    origin: DVec3,
    c: [f32; 3],
) {
    for [a, b] in volume_edges(v) {
        for p in [a, b] {
            push(
                out,
                (Motion::point(motion, p) - origin).as_vec3(),
                Vec3::ZERO,
                c,
                1.0,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvseg_core::{Kinds, Params, Step, StepKind};
    use glam::DMat3;
    use std::collections::HashMap;
    use std::sync::Arc;

    /// The unit cube `[0, 1]^3`.
    fn cube() -> Mesh {
        bvseg_core::shapes::cuboid(DVec3::splat(0.5), DVec3::splat(0.5), DMat3::IDENTITY)
    }

    /// A volume of each kind, centred in the unit cube, turned off the world axes.
    fn volume(shape: Shape) -> BoundingVolume {
        let c = DVec3::splat(0.5);
        let axes = DMat3::from_euler(glam::EulerRot::XYZ, 0.4, 0.2, -0.7);
        let axis = axes.z_axis;
        match shape {
            Shape::Ellipsoid | Shape::Obb => {
                BoundingVolume::frame(shape, c, axes, DVec3::new(0.5, 1.0, 2.0))
            }
            Shape::Sphere => BoundingVolume::sphere(c, 0.7),
            Shape::Capsule => BoundingVolume::capsule(c, axis, 0.8, 0.3),
            Shape::Cylinder => BoundingVolume::cylinder(c, axis, 0.8, 0.3),
            Shape::Hull => {
                // Corners of a slanted prism, and some points inside it.
                let mut points: Vec<DVec3> = (0..8)
                    .map(|i| {
                        let t = DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64);
                        c + axes * (t - 0.5 + DVec3::new(0.3 * t.z, 0.0, 0.0))
                    })
                    .collect();
                points.extend([c, c + DVec3::splat(0.1)]);
                BoundingVolume::hull(&points).unwrap()
            }
        }
    }

    fn snapshot_of(volumes: Vec<BoundingVolume>, triangles: usize) -> Snapshot {
        let n = volumes.len();
        Snapshot {
            step: Step {
                kind: StepKind::Final,
                k: n,
                f: 1.0,
                tov: 0.1,
                mov: 0.1,
                protrusion: 0.1,
            },
            volumes: Arc::new(volumes),
            triangle_parts: Arc::new(vec![0; triangles]),
            fractions: Arc::new(vec![1.0 / n as f64; n]),
        }
    }

    fn snapshot(shape: Shape) -> Snapshot {
        snapshot_of(vec![volume(shape)], 12)
    }

    /// The volume of a closed triangle mesh, by the divergence theorem (positive when outward).
    fn enclosed(tris: &[[Corner; 3]], about: DVec3) -> f64 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|c| c.0 - about);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Checks that `tris` is a closed, consistently oriented mesh whose corners are inside or
    /// on `v`, with outward normals, enclosing most of `v` (at least `fill` of its volume).
    fn check_mesh(v: &BoundingVolume, tris: &[[Corner; 3]], fill: f64) {
        let shape = v.shape;
        assert!(!tris.is_empty(), "{shape:?}");
        let scale = v.radii.max_element();
        let key = |p: DVec3| {
            ((p - v.center) / scale * 1e9)
                .round()
                .as_i64vec3()
                .to_array()
        };
        let mut directed: HashMap<_, i32> = HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (p, n) = t[k];
                assert!(
                    v.gauge(p) <= 1.0 + 1e-9,
                    "{shape:?}: {p} at gauge {}",
                    v.gauge(p)
                );
                assert!((n.length() - 1.0).abs() < 1e-9, "{shape:?}: normal {n}");
                // Convex around its centre: the outward normal points away from it.
                assert!(n.dot(p - v.center) > 0.0, "{shape:?}: normal {n} at {p}");
                let e = (key(p), key(t[(k + 1) % 3].0));
                *directed.entry(e).or_default() += 1;
            }
            let [a, b, c] = t.map(|c| c.0);
            let face = (b - a).cross(c - a);
            assert!(face.length() > 0.0, "{shape:?}: a degenerate triangle");
            // Wound counter-clockwise seen from outside, as its normals say.
            assert!(face.dot(t[0].1 + t[1].1 + t[2].1) > 0.0, "{shape:?}");
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{shape:?}: edge used twice the same way");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{shape:?}: open or flipped edge"
            );
        }
        let vol = enclosed(tris, v.center);
        let exact = v.volume();
        assert!(vol > 0.0, "{shape:?}: volume {vol}");
        assert!(
            vol <= exact * (1.0 + 1e-9) && vol >= fill * exact,
            "{shape:?}: {vol} of {exact}"
        );
    }

    #[test]
    fn every_kind_is_a_closed_outward_mesh_on_its_volume() {
        for shape in Shape::ALL {
            let v = volume(shape);
            let tris = volume_triangles(&v);
            // Polyhedra are exact; curved kinds are inscribed, within a few per cent.
            let fill = if matches!(shape, Shape::Obb | Shape::Hull) {
                1.0 - 1e-9
            } else {
                0.9
            };
            check_mesh(&v, &tris, fill);
            for [a, b] in volume_edges(&v) {
                for p in [a, b] {
                    assert!((v.gauge(p) - 1.0).abs() < 1e-9, "{shape:?} outline {p}");
                }
            }
        }
        // A capsule as short as a ball, a flat cylinder and a long capsule.
        let c = DVec3::new(1.0, -2.0, 3.0);
        for v in [
            BoundingVolume::capsule(c, DVec3::Y, 0.0, 0.5),
            BoundingVolume::cylinder(c, DVec3::X, 0.01, 2.0),
            BoundingVolume::capsule(c, DVec3::new(1.0, 1.0, 0.0).normalize(), 5.0, 0.1),
        ] {
            check_mesh(&v, &volume_triangles(&v), 0.9);
        }
        // A hull draws its faces as they are: as many triangles as its polyhedron.
        let hull = volume(Shape::Hull);
        let poly = hull.polytope().unwrap();
        assert_eq!(volume_triangles(&hull).len(), poly.triangles().len());
        // The slanted prism: 12 edges, not the diagonals of its quadrilateral faces.
        assert_eq!(volume_edges(&hull).len(), 12);
        let cap = volume_edges(&volume(Shape::Capsule)).len();
        let cyl = volume_edges(&volume(Shape::Cylinder)).len();
        assert_eq!((cap, cyl), (2 * SEG + 4 + 2 * SEG, 2 * SEG + 4));
    }

    #[test]
    fn volumes_are_placed_on_their_surface() {
        let mesh = MeshGeometry::new(&cube());
        assert!((mesh.radius - 3f32.sqrt() / 2.0).abs() < 1e-6);
        for shape in Shape::ALL {
            let snap = snapshot(shape);
            let g = build(&mesh, Some(&snap), &[], None, Display::default());
            assert_eq!(g.counts()[0], 36, "the cube, opaque");
            let v = &snap.volumes[0];
            assert_eq!(g.counts()[2], 3 * volume_triangles(v).len(), "{shape:?}");
            for vert in g.translucent.chunks(VERTEX_FLOATS) {
                // Back in mesh coordinates, every drawn point is on the volume's boundary.
                let p = Vec3::new(vert[0], vert[1], vert[2]).as_dvec3() + mesh.center;
                assert!((v.gauge(p) - 1.0).abs() < 1e-5, "{shape:?} {p}");
                assert!((vert[9] - 0.22).abs() < 1e-6);
            }
            let w = Display {
                volumes: VolumeStyle::Wireframe,
                ..Display::default()
            };
            let g = build(&mesh, Some(&snap), &[], None, w);
            assert!(g.translucent.is_empty() && g.counts()[1] > 0);
            for vert in g.lines.chunks(VERTEX_FLOATS) {
                let p = Vec3::new(vert[0], vert[1], vert[2]).as_dvec3() + mesh.center;
                assert!((v.gauge(p) - 1.0).abs() < 1e-5, "{shape:?} {p}");
            }
        }
    }

    #[test]
    fn moved_volumes_are_drawn_on_their_moved_surface() {
        let mesh = MeshGeometry::new(&cube());
        // A bone's turn and shift, with some stretch along one axis.
        let m = DMat4::from_translation(DVec3::new(0.3, -1.0, 2.0))
            * DMat4::from_rotation_y(0.7)
            * DMat4::from_scale(DVec3::new(1.0, 1.3, 1.0));
        let back = m.inverse();
        for shape in Shape::ALL {
            let snap = snapshot(shape);
            let v = &snap.volumes[0];
            for style in [VolumeStyle::Translucent, VolumeStyle::Wireframe] {
                let d = Display {
                    volumes: style,
                    ..Display::default()
                };
                let rest = build(&mesh, Some(&snap), &[], None, d);
                let g = build(&mesh, Some(&snap), &[m], None, d);
                assert_eq!(g.counts(), rest.counts(), "{shape:?}");
                assert_eq!(
                    g.opaque, rest.opaque,
                    "the mesh is not moved by the volumes"
                );
                let drawn = if style == VolumeStyle::Wireframe {
                    &g.lines
                } else {
                    &g.translucent
                };
                for vert in drawn.chunks(VERTEX_FLOATS) {
                    let p = Vec3::new(vert[0], vert[1], vert[2]).as_dvec3() + mesh.center;
                    let q = back.transform_point3(p);
                    assert!((v.gauge(q) - 1.0).abs() < 1e-5, "{shape:?} {p}");
                    if style == VolumeStyle::Translucent {
                        // Outward: the moved centre is behind the surface.
                        let n = Vec3::new(vert[3], vert[4], vert[5]).as_dvec3();
                        assert!(n.dot(p - m.transform_point3(v.center)) > 0.0, "{shape:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_look_of_ellipsoids_and_boxes_is_kept() {
        // As drawn before the other kinds came: 360 sphere triangles, 12 box triangles, three
        // ellipses of 48 segments, twelve box edges.
        let e = volume(Shape::Ellipsoid);
        let b = volume(Shape::Obb);
        assert_eq!(volume_triangles(&e).len(), 2 * LAT * LON - 2 * LON);
        assert_eq!(volume_triangles(&b).len(), 12);
        assert_eq!(volume_edges(&e).len(), 3 * SEG);
        assert_eq!(volume_edges(&b).len(), 12);
        // A box face's normal is its axis, the same on its four corners.
        for t in volume_triangles(&b) {
            assert!(t.iter().all(|c| c.1 == t[0].1));
            assert!([b.axes.x_axis, b.axes.y_axis, b.axes.z_axis]
                .iter()
                .any(|a| (a.dot(t[0].1).abs() - 1.0).abs() < 1e-12));
        }
    }

    #[test]
    fn a_segmentation_of_each_kind_draws_inside_its_volumes() {
        // A capsule and a box side by side: every kind has something to fit.
        let mesh = bvseg_core::shapes::union(&[
            bvseg_core::shapes::capsule(DVec3::ZERO, DVec3::new(2.0, 0.5, 0.0), 0.4, 16),
            bvseg_core::shapes::cuboid(
                DVec3::new(0.0, 1.5, 0.0),
                DVec3::new(0.6, 0.4, 0.3),
                DMat3::from_rotation_z(0.3),
            ),
        ]);
        let geometry = MeshGeometry::new(&mesh);
        for shape in Shape::ALL {
            let params = Params {
                samples: 1500,
                k: Some(2),
                kinds: Kinds::only(shape),
                ..Params::default()
            };
            let seg = bvseg_core::segment(&mesh, &params).unwrap();
            assert_eq!(seg.kinds, Kinds::only(shape));
            let volumes: Vec<BoundingVolume> = seg.parts.iter().map(|p| p.volume.clone()).collect();
            assert!(!volumes.is_empty());
            let snap = snapshot_of(volumes.clone(), mesh.triangles().len());
            let g = build(&geometry, Some(&snap), &[], None, Display::default());
            let mut drawn = 0;
            for v in &volumes {
                assert_eq!(v.shape, shape);
                let tris = volume_triangles(v);
                // The fitted volume's own mesh, in f64: closed, outward, inside or on it.
                check_mesh(v, &tris, 0.9);
                drawn += 3 * tris.len();
            }
            assert_eq!(g.counts()[2], drawn, "{shape:?}");
            // What the renderer gets (f32, relative to the mesh's centre) is on the volumes
            // to f32 precision.
            let mut at = 0;
            for v in &volumes {
                let n = 3 * volume_triangles(v).len();
                let size = v.radii.max_element().max(geometry.radius as f64);
                // How far in the volume's thinnest direction a gauge of 1 + 1 is.
                let thickness = match v.polytope() {
                    Some(p) => p.min_offset() * v.radii.x,
                    None => v.radii.min_element(),
                };
                for vert in g.translucent[at * VERTEX_FLOATS..(at + n) * VERTEX_FLOATS]
                    .chunks(VERTEX_FLOATS)
                {
                    let p = Vec3::new(vert[0], vert[1], vert[2]).as_dvec3() + geometry.center;
                    let slack = 1e-6 * size / thickness;
                    assert!(
                        v.gauge(p) <= 1.0 + slack,
                        "{shape:?}: {p} at {}",
                        v.gauge(p)
                    );
                }
                at += n;
            }
        }
    }

    #[test]
    fn colours_follow_parts_and_selection() {
        let mesh = MeshGeometry::new(&cube());
        let snap = snapshot(Shape::Obb);
        let colour = |g: &Geometry| [g.opaque[6], g.opaque[7], g.opaque[8]];
        let g = build(&mesh, Some(&snap), &[], None, Display::default());
        assert_eq!(colour(&g), part_color(0));
        let plain = Display {
            colour_by_part: false,
            volumes: VolumeStyle::Hidden,
            ..Display::default()
        };
        let g = build(&mesh, Some(&snap), &[], None, plain);
        assert_eq!(colour(&g), MESH_COLOR);
        assert_eq!(g.counts(), [36, 0, 0]);
        let g = build(&mesh, Some(&snap), &[], Some(3), Display::default());
        assert_ne!(colour(&g), part_color(0), "parts not selected are dimmed");
        let see_through = Display {
            translucent_mesh: true,
            ..Display::default()
        };
        let g = build(&mesh, None, &[], None, see_through);
        assert_eq!(g.counts(), [0, 0, 36]);
        assert_ne!(part_color(0), part_color(1));
    }
}
