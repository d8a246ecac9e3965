//! What the 3D view draws, as plain vertex arrays: the mesh (plain or coloured by part) and the
//! bounding volumes (translucent surfaces or wireframes), one colour per part. Building them on
//! the CPU keeps the renderer a dumb uploader, and lets the tests check the geometry.
use std::sync::OnceLock;

use bvseg_core::{BoundingVolume, Mesh, Shape};
use glam::{DVec3, Vec3};

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
    /// Outlines: three principal ellipses, or a box's twelve edges.
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
    /// Prepares `mesh`.
    pub fn new(mesh: &Mesh) -> Self {
        let (lo, hi) = mesh.bbox();
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5) as f32;
        let mut corners = Vec::with_capacity(mesh.triangles().len() * 3);
        let mut normals = Vec::with_capacity(mesh.triangles().len());
        for t in 0..mesh.triangles().len() {
            let c = mesh.corners(t).map(|p| (p - center).as_vec3());
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
/// for), the snapshot's volumes, and `selected`'s part highlighted.
pub fn build(
    mesh: &MeshGeometry,
    snapshot: Option<&Snapshot>,
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
                volume_surface(&mut g.translucent, v, mesh.center, c, a);
            }
            VolumeStyle::Wireframe => volume_outline(&mut g.lines, v, mesh.center, c),
            VolumeStyle::Hidden => {}
        }
    }
    g
}

/// Latitude and longitude divisions of a drawn ellipsoid.
const LAT: usize = 10;
const LON: usize = 20;

/// Unit-sphere triangles (three points each), computed once.
fn sphere_triangles() -> &'static [[Vec3; 3]] {
    static SPHERE: OnceLock<Vec<[Vec3; 3]>> = OnceLock::new();
    SPHERE.get_or_init(|| {
        let at = |i: usize, j: usize| {
            let th = std::f32::consts::PI * i as f32 / LAT as f32;
            let ph = std::f32::consts::TAU * j as f32 / LON as f32;
            Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
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

/// Maps local coordinates `t` (unit sphere or cube) into the scene.
fn place(v: &BoundingVolume, origin: DVec3, t: Vec3) -> Vec3 {
    (v.center - origin + v.axes * (v.radii * t.as_dvec3())).as_vec3()
}

/// Appends the triangles of `v`'s surface, relative to `origin`, in colour `c` with alpha `a`.
pub(crate) fn volume_surface(
    out: &mut Vec<f32>,
    v: &BoundingVolume,
    origin: DVec3,
    c: [f32; 3],
    a: f32,
) {
    match v.shape {
        Shape::Ellipsoid => {
            for tri in sphere_triangles() {
                for &u in tri {
                    // The normal of the ellipsoid at axes * (radii * u) is axes * (u / radii).
                    let n = (v.axes * (u.as_dvec3() / v.radii))
                        .as_vec3()
                        .normalize_or_zero();
                    push(out, place(v, origin, u), n, c, a);
                }
            }
        }
        Shape::Obb => {
            for axis in 0..3 {
                for sign in [-1.0f32, 1.0] {
                    let mut n = Vec3::ZERO;
                    n[axis] = sign;
                    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                    let corner = |su: f32, sw: f32| {
                        let mut t = n;
                        t[u] = su;
                        t[w] = sw;
                        place(v, origin, t)
                    };
                    let nw = (v.axes * n.as_dvec3()).as_vec3();
                    let q = [
                        corner(-1.0, -1.0),
                        corner(1.0, -1.0),
                        corner(1.0, 1.0),
                        corner(-1.0, 1.0),
                    ];
                    for k in [0, 1, 2, 0, 2, 3] {
                        push(out, q[k], nw, c, a);
                    }
                }
            }
        }
    }
}

fn volume_outline(out: &mut Vec<f32>, v: &BoundingVolume, origin: DVec3, c: [f32; 3]) {
    let mut line = |a: Vec3, b: Vec3| {
        push(out, place(v, origin, a), Vec3::ZERO, c, 1.0);
        push(out, place(v, origin, b), Vec3::ZERO, c, 1.0);
    };
    match v.shape {
        Shape::Ellipsoid => {
            const SEG: usize = 48;
            for (x, y) in [(0, 1), (1, 2), (0, 2)] {
                let at = |s: usize| {
                    let a = std::f32::consts::TAU * s as f32 / SEG as f32;
                    let mut t = Vec3::ZERO;
                    t[x] = a.cos();
                    t[y] = a.sin();
                    t
                };
                for s in 0..SEG {
                    line(at(s), at(s + 1));
                }
            }
        }
        Shape::Obb => {
            for axis in 0..3 {
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                for (su, sw) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let mut a = Vec3::ZERO;
                    a[u] = su;
                    a[w] = sw;
                    let mut b = a;
                    a[axis] = -1.0;
                    b[axis] = 1.0;
                    line(a, b);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvseg_core::{Step, StepKind};
    use glam::DMat3;
    use std::sync::Arc;

    /// The unit cube `[0, 1]^3`.
    fn cube() -> Mesh {
        bvseg_core::shapes::cuboid(DVec3::splat(0.5), DVec3::splat(0.5), DMat3::IDENTITY)
    }

    fn snapshot(shape: Shape) -> Snapshot {
        let v = BoundingVolume {
            shape,
            center: DVec3::splat(0.5),
            axes: DMat3::IDENTITY,
            radii: DVec3::new(0.5, 1.0, 2.0),
        };
        Snapshot {
            step: Step {
                kind: StepKind::Final,
                k: 1,
                f: 1.0,
                tov: 0.1,
                mov: 0.1,
                protrusion: 0.1,
            },
            volumes: Arc::new(vec![v]),
            triangle_parts: Arc::new(vec![0; 12]),
            fractions: Arc::new(vec![1.0]),
        }
    }

    #[test]
    fn volumes_are_placed_on_their_surface() {
        let mesh = MeshGeometry::new(&cube());
        assert!((mesh.radius - 3f32.sqrt() / 2.0).abs() < 1e-6);
        for shape in [Shape::Ellipsoid, Shape::Obb] {
            let snap = snapshot(shape);
            let g = build(&mesh, Some(&snap), None, Display::default());
            assert_eq!(g.counts()[0], 36, "the cube, opaque");
            let v = snap.volumes[0];
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
            let g = build(&mesh, Some(&snap), None, w);
            assert!(g.translucent.is_empty() && g.counts()[1] > 0);
            for vert in g.lines.chunks(VERTEX_FLOATS) {
                let p = Vec3::new(vert[0], vert[1], vert[2]).as_dvec3() + mesh.center;
                assert!((v.gauge(p) - 1.0).abs() < 1e-5, "{shape:?} {p}");
            }
        }
    }

    #[test]
    fn colours_follow_parts_and_selection() {
        let mesh = MeshGeometry::new(&cube());
        let snap = snapshot(Shape::Obb);
        let colour = |g: &Geometry| [g.opaque[6], g.opaque[7], g.opaque[8]];
        let g = build(&mesh, Some(&snap), None, Display::default());
        assert_eq!(colour(&g), part_color(0));
        let plain = Display {
            colour_by_part: false,
            volumes: VolumeStyle::Hidden,
            ..Display::default()
        };
        let g = build(&mesh, Some(&snap), None, plain);
        assert_eq!(colour(&g), MESH_COLOR);
        assert_eq!(g.counts(), [36, 0, 0]);
        let g = build(&mesh, Some(&snap), Some(3), Display::default());
        assert_ne!(colour(&g), part_color(0), "parts not selected are dimmed");
        let see_through = Display {
            translucent_mesh: true,
            ..Display::default()
        };
        let g = build(&mesh, None, None, see_through);
        assert_eq!(g.counts(), [0, 0, 36]);
        assert_ne!(part_color(0), part_color(1));
    }
}
