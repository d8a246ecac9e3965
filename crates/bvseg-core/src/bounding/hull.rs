//! 3D convex hull (quickhull) with exact orientation tests.
//!
//! The points are first snapped to an integer grid of 2^40 steps across their bounding box.
//! On that grid the orientation of four points is an exact `i128` determinant, so the
//! visibility decisions that shape the hull's topology are always consistent: the horizon is
//! always one simple loop and the algorithm can neither corrupt its mesh nor loop. A point is
//! only *added* to the hull when it lies more than a small relative tolerance outside a face;
//! points closer than that (the many coplanar ties of lattice inputs, or round-off noise on a
//! rotated lattice) are dropped. Dropped points are at most that tolerance outside the hull,
//! which the callers absorb by rescaling their volumes over all the input points.
use glam::{DMat3, DVec3};

/// A convex hull: its vertices and outward-facing triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hull {
    /// The hull's vertices (a subset of the input points), in increasing input order.
    pub vertices: Vec<DVec3>,
    /// For each vertex, its index in the input slice.
    pub indices: Vec<usize>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside. Empty when
    /// the hull is a point or a segment. A flat hull (`dim == 2`) lists each triangle once per
    /// side, so the surface is still closed. Also empty, with all the finite input points as
    /// `vertices`, in the never observed case that the construction fails (or that the
    /// points' extent overflows `f64`).
    pub faces: Vec<[u32; 3]>,
    /// Affine dimension of the hull: 0 (one point, or none), 1 (segment), 2 (polygon) or 3.
    pub dim: usize,
}

impl Hull {
    /// The enclosed volume (0 for a flat or smaller hull).
    pub fn volume(&self) -> f64 {
        if self.dim < 3 {
            return 0.0;
        }
        let Some(&o) = self.vertices.first() else {
            return 0.0;
        };
        let six: f64 = self
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| self.vertices[i as usize] - o);
                a.dot(b.cross(c))
            })
            .sum();
        (six / 6.0).max(0.0)
    }

    /// Unit outward normal and area of face `f` (zero normal for a degenerate triangle).
    pub fn face_normal_area(&self, f: usize) -> (DVec3, f64) {
        let [a, b, c] = self.faces[f].map(|i| self.vertices[i as usize]);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len > 0.0 && len.is_finite() {
            (n / len, 0.5 * len)
        } else {
            (DVec3::ZERO, 0.0)
        }
    }
}

/// The vertices of the convex hull of `points`, in increasing input order.
///
/// Degenerate inputs return what their hull has: the polygon's corners for coplanar points,
/// the two ends of a collinear set, one point for duplicates of one point, nothing for an empty
/// input. Non-finite points are ignored.
pub fn hull_points(points: &[DVec3]) -> Vec<DVec3> {
    hull(points, false).vertices
}

/// Relative tolerance (of the bounding box's largest side) below which a point outside a face
/// counts as on it. Far above round-off in the inputs, far below any geometric feature.
const EPS_REL: f64 = 1e-10;
/// Grid resolution: coordinates become integers in `0..=2^40`, so that a 3x3 determinant of
/// coordinate differences (< 2^123) fits in an `i128`.
const GRID: f64 = (1u64 << 40) as f64;
/// Bound on the relative error of the floating-point orientation (a few ulps of the
/// determinant's permanent), above which its sign is certain.
const ORIENT_ERR: f64 = 1e-15;
/// Inputs up to this many points skip the [`DirMap`].
const DIRMAP_MIN_POINTS: usize = 2000;

/// The convex hull of `points` (see `Hull`). Deterministic: the same input gives the same
/// output, vertex and face order included. Non-finite points are ignored.
pub fn convex_hull(points: &[DVec3]) -> Hull {
    hull(points, true)
}

/// [`convex_hull`], without the 3D faces unless `with_faces`.
fn hull(points: &[DVec3], with_faces: bool) -> Hull {
    let idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].is_finite())
        .collect();
    let Some(&first) = idx.first() else {
        return Hull::default();
    };
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &i in &idx {
        lo = lo.min(points[i]);
        hi = hi.max(points[i]);
    }
    let ext = (hi - lo).max_element();
    if ext.is_nan() || ext <= 0.0 {
        return single(points, first);
    }
    if !ext.is_finite() {
        // The extent overflows: no grid can hold these points; all of them are a superset.
        return Hull {
            vertices: idx.iter().map(|&i| points[i]).collect(),
            indices: idx,
            faces: Vec::new(),
            dim: 3,
        };
    }
    let scale = GRID / ext;
    // Truncation of a non-negative value plus one half rounds it, without a libm call.
    let q: Vec<DVec3> = idx
        .iter()
        .map(|&i| {
            let t = (points[i] - lo) * scale + 0.5;
            DVec3::new(t.x as i64 as f64, t.y as i64 as f64, t.z as i64 as f64)
        })
        .collect();
    // Round-off already present in the input grows with the coordinates' magnitude, not just
    // with the extent; the grid snapping adds at most one unit.
    let mag = lo.abs().max(hi.abs()).max_element();
    let eps = GRID * EPS_REL + 64.0 * f64::EPSILON * mag * scale + 2.0;
    let mut qh = QuickHull::new(&q, eps);
    let raw = qh.run();
    let mut out = match raw {
        Raw::Point(a) => single(points, idx[a]),
        Raw::Segment(a, b) => from_vertices(points, &idx, &[a, b], &[], 1),
        Raw::Polygon(poly) => {
            // Fan triangulation, once per side.
            let mut faces = Vec::new();
            for k in 1..poly.len().saturating_sub(1) {
                faces.push([poly[0], poly[k], poly[k + 1]]);
                faces.push([poly[0], poly[k + 1], poly[k]]);
            }
            from_vertices(points, &idx, &poly, &faces, 2)
        }
        Raw::Polytope(faces) => {
            let verts: Vec<usize> = faces.iter().flatten().copied().collect();
            let faces = if with_faces { &faces[..] } else { &[] };
            from_vertices(points, &idx, &verts, faces, 3)
        }
        Raw::Cloud(verts) => from_vertices(points, &idx, &verts, &[], 3),
    };
    out.vertices.shrink_to_fit();
    out
}

fn single(points: &[DVec3], i: usize) -> Hull {
    Hull {
        vertices: vec![points[i]],
        indices: vec![i],
        faces: Vec::new(),
        dim: 0,
    }
}

/// Builds the output from hull vertices and faces given as indices into the filtered points.
fn from_vertices(
    points: &[DVec3],
    idx: &[usize],
    verts: &[usize],
    faces: &[[usize; 3]],
    dim: usize,
) -> Hull {
    // Position of each used vertex among the used ones, in increasing index order.
    let mut remap = vec![u32::MAX; idx.len()];
    for &v in verts {
        remap[v] = 0;
    }
    let mut used: Vec<usize> = Vec::with_capacity(verts.len().min(idx.len()));
    for (v, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = used.len() as u32;
            used.push(v);
        }
    }
    let remap = |v: usize| remap[v];
    Hull {
        vertices: used.iter().map(|&v| points[idx[v]]).collect(),
        indices: used.iter().map(|&v| idx[v]).collect(),
        faces: faces.iter().map(|f| f.map(remap)).collect(),
        dim,
    }
}

/// What the hull computation found, as indices into the snapped points.
enum Raw {
    Point(usize),
    Segment(usize, usize),
    Polygon(Vec<usize>),
    Polytope(Vec<[usize; 3]>),
    /// Vertices without faces (only if the mesh were ever found inconsistent).
    Cloud(Vec<usize>),
}

const NONE: u32 = u32::MAX;

struct Face {
    v: [u32; 3],
    /// `nb[i]` is the face across edge `(v[i], v[i+1])`.
    nb: [u32; 3],
    /// Unnormalised outward normal, `(v1 - v0) x (v2 - v0)` rounded.
    n: DVec3,
    /// Per component, the sum of the absolute products behind `n`: bounds its rounding error.
    na: DVec3,
    /// `eps * |n|`: the threshold on `n . (p - v0)` for a point to count as outside.
    thr: f64,
    /// First and last point of the conflict list (linked through [`QuickHull::next`]), or
    /// [`NONE`].
    head: u32,
    tail: u32,
    /// The conflict point farthest outside and its `n . (p - v0)`.
    far: u32,
    far_d: f64,
    /// Stamp of the last apex this face was found visible from (deleted) or hidden from.
    mark: u32,
    hidden: bool,
    alive: bool,
}

struct QuickHull<'a> {
    q: &'a [DVec3],
    eps: f64,
    faces: Vec<Face>,
    stamp: u32,
    /// Scratch for [`QuickHull::assign`].
    planes: Vec<(DVec3, DVec3, DVec3, f64)>,
    /// Per point, the next point of the conflict list it is on: one flat array instead of a
    /// growing vector per face, as each point is on at most one list.
    next: Vec<u32>,
    /// Per point, the stamp of the last apex whose horizon it was found on.
    seen: Vec<u32>,
}

impl<'a> QuickHull<'a> {
    fn new(q: &'a [DVec3], eps: f64) -> Self {
        Self {
            q,
            eps,
            // Transient faces (later buried) come to a few times the points on lattice inputs;
            // growing this vector of large faces costs more than the spare capacity.
            faces: Vec::with_capacity(4 * q.len() + 64),
            stamp: 0,
            planes: Vec::new(),
            next: vec![NONE; q.len()],
            seen: vec![0; q.len()],
        }
    }

    fn make_face(&mut self, v: [u32; 3]) -> u32 {
        let [a, b, c] = v.map(|i| self.q[i as usize]);
        let (s, t) = (b - a, c - a);
        let n = s.cross(t);
        let na = DVec3::new(
            (s.y * t.z).abs() + (s.z * t.y).abs(),
            (s.z * t.x).abs() + (s.x * t.z).abs(),
            (s.x * t.y).abs() + (s.y * t.x).abs(),
        );
        self.faces.push(Face {
            v,
            nb: [NONE; 3],
            n,
            na,
            thr: self.eps * n.length(),
            head: NONE,
            tail: NONE,
            far: NONE,
            far_d: 0.0,
            mark: 0,
            hidden: false,
            alive: true,
        });
        (self.faces.len() - 1) as u32
    }

    /// Priority of face `f` in [`QuickHull::expand`]: the distance of its farthest conflict
    /// point (as ordered bits of a non-negative float), then its index, so that the order is
    /// total and deterministic.
    fn key(&self, f: u32) -> (u64, u32) {
        let face = &self.faces[f as usize];
        // `thr` is `eps |n|`, so this is the distance over `eps`.
        let d = face.far_d / face.thr;
        (d.max(0.0).to_bits(), f)
    }

    /// Exact test of `p` strictly above the plane of face `f`.
    fn above_exact(&self, f: u32, p: u32) -> bool {
        let face = &self.faces[f as usize];
        let a = self.q[face.v[0] as usize];
        let d = self.q[p as usize] - a;
        let h = face.n.dot(d);
        if h.abs() > ORIENT_ERR * face.na.dot(d.abs()) {
            return h > 0.0;
        }
        let [_, b, c] = face.v.map(|i| self.q[i as usize]);
        orient_i128(a, b, c, self.q[p as usize]) > 0
    }

    fn run(&mut self) -> Raw {
        let q = self.q;
        // Extreme points along the axes and the four diagonals (sums only, so cheap); their
        // hull starts the first polytope.
        let key = |p: &DVec3| {
            [
                p.x,
                p.y,
                p.z,
                p.x + p.y + p.z,
                p.x + p.y - p.z,
                p.x - p.y + p.z,
                -p.x + p.y + p.z,
            ]
        };
        let mut lo = [(f64::INFINITY, 0usize); 7];
        let mut hi = [(f64::NEG_INFINITY, 0usize); 7];
        for (i, p) in q.iter().enumerate() {
            for (k, t) in key(p).into_iter().enumerate() {
                if t < lo[k].0 {
                    lo[k] = (t, i);
                }
                if t > hi[k].0 {
                    hi[k] = (t, i);
                }
            }
        }
        let mut ext: Vec<usize> = lo.iter().chain(hi.iter()).map(|e| e.1).collect();
        ext.sort_unstable();
        ext.dedup();

        let (mut i0, mut i1, mut best) = (0, 0, -1.0);
        for (k, &a) in ext.iter().enumerate() {
            for &b in &ext[k + 1..] {
                let d = q[a].distance_squared(q[b]);
                if d > best {
                    (i0, i1, best) = (a, b, d);
                }
            }
        }
        if best <= 0.0 {
            return Raw::Point(i0);
        }
        let dir = q[i1] - q[i0];
        let off_line = |i: usize| dir.cross(q[i] - q[i0]).length_squared();
        // Look among the extremes first; only a (nearly) flat set needs the full scan.
        let mut i2 = argmax(ext.iter().copied(), off_line);
        if off_line(i2).sqrt() <= self.eps * dir.length() {
            i2 = argmax(0..q.len(), off_line);
        }
        if off_line(i2).sqrt() <= self.eps * dir.length() {
            // Collinear: the ends along the line.
            let a = argmax(0..q.len(), |i| -dir.dot(q[i] - q[i0]));
            let b = argmax(0..q.len(), |i| dir.dot(q[i] - q[i0]));
            return Raw::Segment(a.min(b), a.max(b));
        }
        let nrm = dir.cross(q[i2] - q[i0]);
        let off_plane = |i: usize| nrm.dot(q[i] - q[i0]).abs();
        let mut i3 = argmax(ext.iter().copied(), off_plane);
        if off_plane(i3) <= self.eps * nrm.length() {
            i3 = argmax(0..q.len(), off_plane);
        }
        if off_plane(i3) <= self.eps * nrm.length() {
            return Raw::Polygon(polygon(q, nrm, self.eps));
        }
        let simplex = [i0, i1, i2, i3].map(|i| i as u32);
        match self.polytope(simplex, &ext) {
            Some(()) => Raw::Polytope(
                self.faces
                    .iter()
                    .filter(|f| f.alive)
                    .map(|f| f.v.map(|i| i as usize))
                    .collect(),
            ),
            // Should the mesh ever be inconsistent: every point, a superset of the hull.
            None => Raw::Cloud((0..q.len()).collect()),
        }
    }

    /// The hull of the extremes, then of everything. `None` if the mesh broke.
    fn polytope(&mut self, s: [u32; 4], ext: &[usize]) -> Option<()> {
        let q = self.q;
        let [a, mut b, mut c, d] = s;
        if orient_i128(q[a as usize], q[b as usize], q[c as usize], q[d as usize]) > 0 {
            std::mem::swap(&mut b, &mut c);
        }
        // d is below (a, b, c); the other three faces follow from the shared edges.
        let f = [
            self.make_face([a, b, c]),
            self.make_face([b, a, d]),
            self.make_face([c, b, d]),
            self.make_face([a, c, d]),
        ];
        for &x in &f {
            for e in 0..3 {
                let (u, v) = (
                    self.faces[x as usize].v[e],
                    self.faces[x as usize].v[(e + 1) % 3],
                );
                for &y in &f {
                    if y != x && edge_index(&self.faces[y as usize].v, v, u).is_some() {
                        self.faces[x as usize].nb[e] = y;
                    }
                }
            }
        }
        // First the hull of the extremes (all of them hull vertices): a polytope that already
        // holds many points, which one cheap pass then discards.
        let n = q.len();
        let mut first: Vec<u32> = ext.iter().map(|&i| i as u32).collect();
        first.retain(|p| !s.contains(p));
        self.assign(&first, &f);
        self.expand(f.iter().rev().copied().collect())?;

        let alive: Vec<u32> = (0..self.faces.len() as u32)
            .filter(|&f| self.faces[f as usize].alive)
            .collect();
        let mut verts: Vec<u32> = alive
            .iter()
            .flat_map(|&f| self.faces[f as usize].v)
            .collect();
        verts.sort_unstable();
        verts.dedup();
        let c = verts.iter().map(|&v| q[v as usize]).sum::<DVec3>() / verts.len() as f64;
        let inner = InnerEllipsoid::new(
            &verts.iter().map(|&v| q[v as usize]).collect::<Vec<_>>(),
            c,
            alive.iter().map(|&f| {
                (
                    self.faces[f as usize].n,
                    q[self.faces[f as usize].v[0] as usize],
                )
            }),
        );
        // The direction map pays off only when many points are tested: on a few hundred,
        // building it costs more than testing every point against every face.
        let all: Vec<u32> = (0..alive.len() as u32).collect();
        let map = (n > DIRMAP_MIN_POINTS).then(|| {
            DirMap::new(
                c,
                alive
                    .iter()
                    .map(|&f| self.faces[f as usize].v.map(|v| q[v as usize])),
            )
        });
        // Compact planes for the hot loop below, with a bound on the rounding error of the
        // height over the whole grid (|d| <= 2^40 per component), so that the exact error
        // term is only needed within that bound of the plane.
        let planes: Vec<[f64; 8]> = alive
            .iter()
            .map(|&f| {
                let face = &self.faces[f as usize];
                let a = q[face.v[0] as usize];
                let err = ORIENT_ERR * face.na.element_sum() * GRID;
                [a.x, a.y, a.z, face.n.x, face.n.y, face.n.z, err, face.thr]
            })
            .collect();
        let mut unsure: Vec<u32> = Vec::new();
        for p in 0..n as u32 {
            let x = q[p as usize];
            if inner.contains(x) {
                continue;
            }
            let mut below = true;
            let mut outside = None;
            let listed = match &map {
                Some(m) => m.faces(x - c),
                None => &all[..],
            };
            for &k in listed {
                let [ax, ay, az, nx, ny, nz, err, thr] = planes[k as usize];
                let d = x - DVec3::new(ax, ay, az);
                let h = nx * d.x + ny * d.y + nz * d.z;
                if h < -err {
                    continue;
                }
                let f = alive[k as usize];
                let face = &self.faces[f as usize];
                let err = ORIENT_ERR * face.na.dot(d.abs());
                if h - err > thr {
                    outside = Some((f, h));
                    break;
                }
                if h + err >= 0.0 {
                    below = false;
                }
            }
            // The ray from `c` through `x` leaves through one of the listed faces, so being
            // below all of them means inside; a point clearly above one is handed to it, and
            // the rare point in between gets the full test.
            match outside {
                Some((f, h)) => self.push_conflict(f, p, x, h),
                None if !below => unsure.push(p),
                None => {}
            }
        }
        self.assign(&unsure, &alive);
        let todo: Vec<u32> = alive
            .iter()
            .rev()
            .copied()
            .filter(|&f| self.faces[f as usize].head != NONE)
            .collect();
        self.expand(todo)
    }

    /// Quickhull proper: adds conflict points as apexes until no face has any. The farthest
    /// apex overall goes first (rather than depth first from the newest faces): fewer apexes
    /// are later buried by farther ones, which saves most of the work on lattice inputs.
    fn expand(&mut self, todo0: Vec<u32>) -> Option<()> {
        let mut todo = std::collections::BinaryHeap::new();
        for f in todo0 {
            todo.push(self.key(f));
        }
        let mut visible: Vec<u32> = Vec::with_capacity(64);
        // Horizon edges `(u, v, face outside)`.
        let mut horizon: Vec<(u32, u32, u32)> = Vec::with_capacity(64);
        let mut stack: Vec<(u32, usize, usize, usize)> = Vec::with_capacity(64);
        let mut orphans: Vec<u32> = Vec::with_capacity(self.q.len());
        let mut new_faces: Vec<u32> = Vec::with_capacity(64);
        while let Some((_, f0)) = todo.pop() {
            let face = &self.faces[f0 as usize];
            if !face.alive || face.head == NONE {
                continue;
            }
            let apex = face.far;
            self.stamp += 1;
            let stamp = self.stamp;
            // Depth-first walk over the faces the apex sees, collecting the horizon edges in
            // order around it.
            visible.clear();
            horizon.clear();
            stack.clear();
            self.faces[f0 as usize].mark = stamp;
            self.faces[f0 as usize].hidden = false;
            visible.push(f0);
            stack.push((f0, 0, 0, 3));
            while let Some(top) = stack.last_mut() {
                if top.2 == top.3 {
                    stack.pop();
                    continue;
                }
                let (g, e) = (top.0, (top.1 + top.2) % 3);
                top.2 += 1;
                let nb = self.faces[g as usize].nb[e];
                let seen = self.faces[nb as usize].mark == stamp;
                let hidden = if seen {
                    self.faces[nb as usize].hidden
                } else {
                    let h = !self.above_exact(nb, apex);
                    let fb = &mut self.faces[nb as usize];
                    fb.mark = stamp;
                    fb.hidden = h;
                    if !h {
                        visible.push(nb);
                    }
                    h
                };
                let gv = self.faces[g as usize].v;
                if hidden {
                    horizon.push((gv[e], gv[(e + 1) % 3], nb));
                } else if !seen {
                    let j = edge_index(&self.faces[nb as usize].v, gv[(e + 1) % 3], gv[e]);
                    let j = j?;
                    stack.push((nb, (j + 1) % 3, 0, 2));
                }
            }
            // The horizon must be one simple closed loop; with exact visibility it always is,
            // but a broken mesh must never propagate.
            let ok = horizon.len() >= 3
                && (0..horizon.len()).all(|k| horizon[k].1 == horizon[(k + 1) % horizon.len()].0);
            // Each horizon vertex once (the loop is simple).
            let simple = horizon.iter().all(|h| {
                let s = &mut self.seen[h.0 as usize];
                let fresh = *s != stamp;
                *s = stamp;
                fresh
            });
            if !ok || !simple {
                return None;
            }
            new_faces.clear();
            for &(u, v, out) in horizon.iter() {
                let nf = self.make_face([u, v, apex]);
                self.faces[nf as usize].nb[0] = out;
                let j = edge_index(&self.faces[out as usize].v, v, u)?;
                self.faces[out as usize].nb[j] = nf;
                new_faces.push(nf);
            }
            let m = new_faces.len();
            for k in 0..m {
                let nf = new_faces[k] as usize;
                self.faces[nf].nb[1] = new_faces[(k + 1) % m];
                self.faces[nf].nb[2] = new_faces[(k + m - 1) % m];
            }
            orphans.clear();
            for &g in visible.iter() {
                let face = &mut self.faces[g as usize];
                face.alive = false;
                let mut p = std::mem::replace(&mut face.head, NONE);
                face.tail = NONE;
                while p != NONE {
                    if p != apex {
                        orphans.push(p);
                    }
                    p = self.next[p as usize];
                }
            }
            let nf = std::mem::take(&mut new_faces);
            self.assign(&orphans, &nf);
            for &x in &nf {
                if self.faces[x as usize].head != NONE {
                    todo.push(self.key(x));
                }
            }
            new_faces = nf;
        }
        Some(())
    }

    /// Adds `p` (at `x`) to the conflict list of face `f`, which it is above by more than
    /// `eps` (its height `h = n . (x - v0)`), keeping track of the farthest such point.
    fn push_conflict(&mut self, f: u32, p: u32, x: DVec3, h: f64) {
        let face = &self.faces[f as usize];
        let thr = face.thr;
        // The next apex is the farthest point, but among points equally far up to `eps` (a
        // lattice row parallel to the face) the one farthest from the face: a corner of that
        // row, never a point in its middle that would stay on the hull as a spurious vertex
        // once the corners are added.
        let better = if face.far == NONE || h > face.far_d + thr {
            true
        } else if h >= face.far_d - thr {
            let [a, b, c] = face.v.map(|i| self.q[i as usize]);
            let g = (a + b + c) / 3.0;
            x.distance_squared(g) > self.q[face.far as usize].distance_squared(g)
        } else {
            false
        };
        let face = &mut self.faces[f as usize];
        self.next[p as usize] = NONE;
        match face.tail {
            NONE => face.head = p,
            t => self.next[t as usize] = p,
        }
        face.tail = p;
        if better {
            face.far_d = h;
            face.far = p;
        }
    }

    /// Gives each point to the first face it is clearly outside of; the rest are inside.
    fn assign(&mut self, pts: &[u32], faces: &[u32]) {
        // The planes are copied into one small contiguous array: this loop is the hull's hot
        // spot, and the faces themselves are large and scattered.
        let mut planes = std::mem::take(&mut self.planes);
        planes.clear();
        planes.extend(faces.iter().map(|&f| {
            let face = &self.faces[f as usize];
            (self.q[face.v[0] as usize], face.n, face.na, face.thr)
        }));
        for &p in pts {
            let x = self.q[p as usize];
            for (k, &(a, n, na, thr)) in planes.iter().enumerate() {
                let d = x - a;
                // The rounding-error term is only needed when the point may be outside.
                if n.dot(d) <= thr {
                    continue;
                }
                // A lower bound on the exact height: its rounding error scales with the
                // permanent `na`, not with `|n|`, so on a sliver face it can exceed `eps * |n|`
                // and a point below the sliver would otherwise become an apex.
                let h = n.dot(d);
                if h - ORIENT_ERR * na.dot(d.abs()) <= thr {
                    continue;
                }
                self.push_conflict(faces[k], p, x, h);
                break;
            }
        }
        self.planes = planes;
    }
}

/// An ellipsoid inside a polytope: centred at `c`, shaped like the covariance of the polytope's
/// vertices, as large as the nearest face plane allows. Membership costs a few multiplications.
struct InnerEllipsoid {
    c: DVec3,
    /// Rows of the whitening map `Lambda^-1/2 V^T`.
    w: [DVec3; 3],
    /// Squared scale, with a margin; negative when unusable.
    s2: f64,
}

impl InnerEllipsoid {
    fn new(verts: &[DVec3], c: DVec3, planes: impl Iterator<Item = (DVec3, DVec3)>) -> Self {
        let mut cov = DMat3::ZERO;
        for &v in verts {
            let d = v - c;
            cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (vals, vecs) = crate::linalg::sym_eigen(cov);
        let unusable = Self {
            c,
            w: [DVec3::ZERO; 3],
            s2: -1.0,
        };
        if vals.z.is_nan() || vals.z <= vals.x * 1e-12 {
            return unusable;
        }
        let w = [0, 1, 2].map(|k| vecs.col(k) / vals[k].sqrt());
        let mut s2 = f64::INFINITY;
        for (n, a) in planes {
            // Support of the unit ellipsoid in direction n is |Lambda^1/2 V^T n|.
            let vn = vecs.transpose() * n;
            let support = (vn * vals.map(f64::sqrt)).length();
            let t = n.dot(a - c) / support;
            if t.is_nan() || t <= 0.0 {
                return unusable;
            }
            s2 = s2.min(t * t);
        }
        // A relative margin far above the rounding of `contains`.
        Self {
            c,
            w,
            s2: s2 * (1.0 - 1e-9),
        }
    }

    #[inline]
    fn contains(&self, x: DVec3) -> bool {
        let d = x - self.c;
        let t = DVec3::new(self.w[0].dot(d), self.w[1].dot(d), self.w[2].dot(d));
        t.length_squared() < self.s2
    }
}

/// For rays from a point `c` strictly inside a polytope: a cube map of directions whose cells
/// list every face the ray may leave through. Seen from `c`, a face covers a convex cone of
/// directions; within one side of the cube that cone is the face clipped to the side's cone,
/// and its central projection on the side's plane is the convex polygon of the clipped
/// corners' projections. The face is listed in every cell of that polygon's bounding box,
/// widened by a margin far above rounding, which is conservative.
struct DirMap {
    g: usize,
    start: Vec<u32>,
    list: Vec<u32>,
}

impl DirMap {
    /// Relative widening of the side cones and of the projected boxes.
    const MARGIN: f64 = 1e-7;

    fn new(c: DVec3, faces: impl ExactSizeIterator<Item = [DVec3; 3]>) -> Self {
        // Cells about as many as the faces, so that few faces are listed in each.
        let g = ((faces.len() as f64 / 6.0).sqrt() * 2.0)
            .ceil()
            .clamp(1.0, 32.0) as usize;
        let ncell = 6 * g * g;
        let gh = 0.5 * g as f64;
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        // Faces too close to `c` to project reliably: listed for every direction.
        let mut global = Vec::new();
        for (k, t) in faces.enumerate() {
            let t = t.map(|v| v - c);
            // A face whose plane passes (nearly) through `c` would project to infinity.
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let scale = t.iter().map(|v| v.length()).fold(0.0f64, f64::max);
            let dist = n.dot(t[0]);
            let far_enough = dist.abs() > 1e-6 * n.length() * scale;
            if !far_enough {
                global.push(k as u32);
                continue;
            }
            // A triangle whose corners are well inside one side's cone stays in it (the cone
            // is convex); any other is clipped to each side's slightly widened cone.
            let sides = t.map(Self::side_of);
            let one = (sides[0].is_some() && sides[0] == sides[1] && sides[1] == sides[2])
                .then_some(sides[0])
                .flatten();
            for side in 0..6 {
                let mut poly = [DVec3::ZERO; 8];
                let len = match one {
                    Some(s) if s == side => {
                        poly[..3].copy_from_slice(&t);
                        3
                    }
                    Some(_) => 0,
                    None => Self::clip(&t, side, &mut poly),
                };
                if len == 0 {
                    continue;
                }
                let (m, sg) = (side / 2, if side & 1 == 0 { 1.0 } else { -1.0 });
                let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for p in &poly[..len] {
                    let w = sg * p[m];
                    for (a, ax) in [(m + 1) % 3, (m + 2) % 3].into_iter().enumerate() {
                        let u = p[ax] / w;
                        lo[a] = lo[a].min(u);
                        hi[a] = hi[a].max(u);
                    }
                }
                if !(lo.iter().chain(&hi).all(|x| x.is_finite())) {
                    global.push(k as u32);
                    break;
                }
                let cell = |u: f64| ((u + 1.0) * gh).clamp(0.0, (g - 1) as f64) as usize;
                let (i0, i1) = (cell(lo[0] - Self::MARGIN), cell(hi[0] + Self::MARGIN));
                let (j0, j1) = (cell(lo[1] - Self::MARGIN), cell(hi[1] + Self::MARGIN));
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        pairs.push((((side * g + i) * g + j) as u32, k as u32));
                    }
                }
            }
        }
        global.dedup();
        for &k in &global {
            pairs.extend((0..ncell as u32).map(|cell| (cell, k)));
        }
        // Bucket by cell (a stable counting sort keeps each cell's faces in face order).
        let mut start = vec![0u32; ncell + 1];
        for &(cell, _) in &pairs {
            start[cell as usize + 1] += 1;
        }
        for i in 0..ncell {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; pairs.len()];
        for &(cell, f) in &pairs {
            list[fill[cell as usize] as usize] = f;
            fill[cell as usize] += 1;
        }
        Self { g, start, list }
    }

    /// The cube side whose (widened) cone alone holds direction `d`, if exactly one does.
    fn side_of(d: DVec3) -> Option<usize> {
        let a = d.abs();
        let m = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (b, c) = (a[(m + 1) % 3], a[(m + 2) % 3]);
        // Near a side's edge, the widened cones of both sides hold it.
        (b < a[m] * (1.0 - 4.0 * Self::MARGIN) && c < a[m] * (1.0 - 4.0 * Self::MARGIN))
            .then_some(2 * m + usize::from(d[m] < 0.0))
    }

    /// Clips triangle `t` to the cone of cube side `side`, widened by `MARGIN`: the polygon's
    /// length in `out`.
    fn clip(t: &[DVec3; 3], side: usize, out: &mut [DVec3; 8]) -> usize {
        let (m, sg) = (side / 2, if side & 1 == 0 { 1.0 } else { -1.0 });
        let mut cur = [DVec3::ZERO; 8];
        cur[..3].copy_from_slice(t);
        let mut n = 3;
        for (ax, s) in [
            ((m + 1) % 3, 1.0),
            ((m + 1) % 3, -1.0),
            ((m + 2) % 3, 1.0),
            ((m + 2) % 3, -1.0),
        ] {
            // Keep sg * p[m] * (1 + MARGIN) - s * p[ax] >= 0.
            let f = |p: &DVec3| sg * p[m] * (1.0 + Self::MARGIN) - s * p[ax];
            let mut k = 0;
            for i in 0..n {
                let (p, q) = (cur[i], cur[(i + 1) % n]);
                let (fp, fq) = (f(&p), f(&q));
                if fp >= 0.0 {
                    out[k] = p;
                    k += 1;
                }
                if (fp >= 0.0) != (fq >= 0.0) && k < 8 {
                    out[k] = p + (q - p) * (fp / (fp - fq));
                    k += 1;
                }
            }
            n = k;
            if n == 0 {
                return 0;
            }
            cur[..n].copy_from_slice(&out[..n]);
        }
        n
    }

    #[inline]
    fn cell_of(g: usize, d: DVec3) -> usize {
        let a = d.abs();
        let m = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let s = a[m];
        if s.is_nan() || s <= 0.0 {
            return 0;
        }
        let side = 2 * m + usize::from(d[m] < 0.0);
        let k = 0.5 * g as f64 / s;
        let i = ((d[(m + 1) % 3] * k + 0.5 * g as f64) as usize).min(g - 1);
        let j = ((d[(m + 2) % 3] * k + 0.5 * g as f64) as usize).min(g - 1);
        (side * g + i) * g + j
    }

    /// The faces a ray from `c` in direction `d` may leave through.
    #[inline]
    fn faces(&self, d: DVec3) -> &[u32] {
        let cell = Self::cell_of(self.g, d);
        &self.list[self.start[cell] as usize..self.start[cell + 1] as usize]
    }
}

/// The element maximising `key` (the first one on ties).
fn argmax(it: impl Iterator<Item = usize>, key: impl Fn(usize) -> f64) -> usize {
    let mut best = (f64::NEG_INFINITY, 0);
    for i in it {
        let k = key(i);
        if k > best.0 {
            best = (k, i);
        }
    }
    best.1
}

fn edge_index(v: &[u32; 3], a: u32, b: u32) -> Option<usize> {
    (0..3).find(|&k| v[k] == a && v[(k + 1) % 3] == b)
}

/// Sign-exact orientation of `p` against the plane through `a, b, c` (positive above, that is
/// on the side of `(b - a) x (c - a)`), for integer-valued coordinates below 2^40.
fn orient_i128(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> i128 {
    let i = |x: f64| x as i64 as i128;
    let (s, t, u) = (b - a, c - a, p - a);
    let nx = i(s.y) * i(t.z) - i(s.z) * i(t.y);
    let ny = i(s.z) * i(t.x) - i(s.x) * i(t.z);
    let nz = i(s.x) * i(t.y) - i(s.y) * i(t.x);
    (nx * i(u.x) + ny * i(u.y) + nz * i(u.z)).signum()
}

/// Convex polygon (counter-clockwise about `nrm`) of nearly coplanar snapped points, by the
/// monotone chain on the coordinate plane most parallel to theirs. Like the 3D hull, it drops
/// corners that are within `eps` of the segment joining their neighbours.
fn polygon(q: &[DVec3], nrm: DVec3, eps: f64) -> Vec<usize> {
    let a = nrm.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (ax, ay) = ((k + 1) % 3, (k + 2) % 3);
    let xy = |i: usize| (q[i][ax] as i64, q[i][ay] as i64);
    let mut order: Vec<usize> = (0..q.len()).collect();
    order.sort_by_key(|&i| (xy(i), i));
    // Whether `a` is not clearly left of `o -> b`: exact, with the margin `eps * |b - o|`.
    let flat = |o: usize, a: usize, b: usize| {
        let (o, a, b) = (xy(o), xy(a), xy(b));
        let c =
            (a.0 - o.0) as i128 * (b.1 - o.1) as i128 - (a.1 - o.1) as i128 * (b.0 - o.0) as i128;
        let (dx, dy) = ((b.0 - o.0) as f64, (b.1 - o.1) as f64);
        let len = (dx * dx + dy * dy).sqrt();
        c <= 0 || (c as f64) <= eps * len
    };
    let mut hull: Vec<usize> = Vec::with_capacity(64);
    let chain = |hull: &mut Vec<usize>, i: usize, start: usize| {
        while hull.len() >= start + 2 && flat(hull[hull.len() - 2], hull[hull.len() - 1], i) {
            hull.pop();
        }
        hull.push(i);
    };
    for &i in &order {
        chain(&mut hull, i, 0);
    }
    // The last point of each chain starts the other one.
    hull.pop();
    let start = hull.len();
    for &i in order.iter().rev() {
        chain(&mut hull, i, start);
    }
    hull.pop();
    if nrm[k] < 0.0 {
        hull.reverse();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::DMat3;

    fn lattice(n: usize, h: f64) -> Vec<DVec3> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    v.push(DVec3::new(i as f64, j as f64, k as f64) * h);
                }
            }
        }
        v
    }

    fn sorted(mut v: Vec<DVec3>) -> Vec<[f64; 3]> {
        let mut a: Vec<[f64; 3]> = v.drain(..).map(|p| p.to_array()).collect();
        a.sort_by(|x, y| x.partial_cmp(y).unwrap_or(std::cmp::Ordering::Equal));
        a
    }

    fn corners(lo: f64, hi: f64) -> Vec<[f64; 3]> {
        let v = (0..8)
            .map(|i| {
                let s = |b: usize| if i & b == 0 { lo } else { hi };
                DVec3::new(s(1), s(2), s(4))
            })
            .collect();
        sorted(v)
    }

    /// Every input point is on the inner side of every face, and the surface is a closed
    /// triangulated sphere (V - E + F = 2 with E = 3F/2).
    fn check_hull(points: &[DVec3], h: &Hull) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &p in points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let tol = 1e-9 * (hi - lo).max_element();
        for f in 0..h.faces.len() {
            let (n, area) = h.face_normal_area(f);
            assert!(area > 0.0);
            let a = h.vertices[h.faces[f][0] as usize];
            for &p in points {
                assert!(
                    n.dot(p - a) <= tol,
                    "point outside face by {}",
                    n.dot(p - a)
                );
            }
        }
        if h.dim == 3 {
            assert_eq!(h.faces.len(), 2 * h.vertices.len() - 4);
            let mut edges: Vec<(u32, u32)> = Vec::new();
            for f in &h.faces {
                for e in 0..3 {
                    edges.push((f[e], f[(e + 1) % 3]));
                }
            }
            edges.sort_unstable();
            let n = edges.len();
            edges.dedup();
            assert_eq!(n, edges.len(), "an oriented edge is used twice");
            for &(a, b) in &edges {
                assert!(edges.binary_search(&(b, a)).is_ok(), "open edge");
            }
        }
        for (v, &i) in h.vertices.iter().zip(&h.indices) {
            assert_eq!(*v, points[i]);
        }
    }

    #[test]
    fn cube_lattice_gives_corners() {
        let pts = lattice(6, 0.2);
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.dim, 3);
        assert_eq!(sorted(h.vertices.clone()), corners(0.0, 1.0));
        assert_eq!(h.faces.len(), 12);
    }

    #[test]
    fn rotated_offset_lattice_gives_corners() {
        let r = DMat3::from_euler(glam::EulerRot::ZYX, 0.3, -0.7, 1.1);
        let t = DVec3::new(1e5, -3e4, 2e5);
        let pts: Vec<DVec3> = lattice(9, 0.125).iter().map(|&p| r * p + t).collect();
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.vertices.len(), 8);
    }

    #[test]
    fn random_points_are_inside_every_face() {
        let mut rng = Rng::new(7);
        for n in [5, 50, 2000] {
            let pts: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(rng.next_f64(), rng.next_f64() * 3.0, rng.next_f64() - 2.0))
                .collect();
            let h = convex_hull(&pts);
            check_hull(&pts, &h);
            assert_eq!(h.dim, 3);
        }
    }

    #[test]
    fn points_on_a_sphere_are_all_vertices() {
        let mut rng = Rng::new(3);
        let pts: Vec<DVec3> = (0..500)
            .map(|_| {
                let z = 2.0 * rng.next_f64() - 1.0;
                let a = std::f64::consts::TAU * rng.next_f64();
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * a.cos(), r * a.sin(), z)
            })
            .collect();
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.vertices.len(), 500);
    }

    #[test]
    fn round_off_below_tolerance_is_flat() {
        // A square lattice whose points are off its plane by round-off only.
        let mut rng = Rng::new(5);
        let pts: Vec<DVec3> = (0..100)
            .map(|i| {
                let z = 1e-14 * (rng.next_f64() - 0.5);
                DVec3::new((i % 10) as f64, (i / 10) as f64, z) + DVec3::splat(100.0)
            })
            .collect();
        let h = convex_hull(&pts);
        assert_eq!((h.dim, h.vertices.len()), (2, 4));
        check_hull(&pts, &h);
    }

    #[test]
    fn deterministic_and_order_independent_vertex_set() {
        let mut rng = Rng::new(11);
        let mut pts: Vec<DVec3> = (0..3000)
            .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
            .collect();
        pts.extend(lattice(5, 0.25));
        let a = convex_hull(&pts);
        assert_eq!(a, convex_hull(&pts));
        let mut rev = pts.clone();
        rev.reverse();
        assert_eq!(sorted(a.vertices), sorted(convex_hull(&rev).vertices));
    }

    #[test]
    fn degenerate_inputs() {
        assert!(hull_points(&[]).is_empty());
        let p = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(hull_points(&[p]), vec![p]);
        assert_eq!(hull_points(&[p, p, p]), vec![p]);
        assert_eq!(hull_points(&[p, DVec3::NAN, p]), vec![p]);
        // Collinear with duplicates: the two ends.
        let line: Vec<DVec3> = (0..20)
            .map(|i| p + DVec3::new(1.0, -2.0, 0.5) * ((i % 7) as f64))
            .collect();
        let h = convex_hull(&line);
        assert_eq!(h.dim, 1);
        assert_eq!(
            sorted(h.vertices),
            sorted(vec![p, p + DVec3::new(6.0, -12.0, 3.0)])
        );
        // A tilted square lattice: its four corners, and a closed two-sided surface.
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.2, 0.9, -0.4);
        let sq: Vec<DVec3> = (0..49)
            .map(|i| r * DVec3::new((i % 7) as f64, (i / 7) as f64, 0.0) + p)
            .chain([r * DVec3::new(3.0, 3.0, 0.0) + p; 3])
            .collect();
        let h = convex_hull(&sq);
        check_hull(&sq, &h);
        assert_eq!(h.dim, 2);
        assert_eq!(h.vertices.len(), 4);
        assert_eq!(h.faces.len(), 4);
        // A triangle and a tetrahedron.
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(convex_hull(&tri).vertices.len(), 3);
        let tet = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let h = convex_hull(&tet);
        check_hull(&tet, &h);
        assert_eq!((h.vertices.len(), h.faces.len()), (4, 4));
    }

    /// The ray from the centre in any direction leaves through a face that the direction
    /// map lists for that direction.
    #[test]
    fn direction_map_lists_the_exit_face() {
        let mut rng = Rng::new(5);
        for n in [6usize, 20, 100, 400] {
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    let d = DVec3::new(
                        rng.next_f64() - 0.5,
                        rng.next_f64() * 3.0 - 1.5,
                        rng.next_f64() - 0.5,
                    );
                    d.normalize() * (1.0 + rng.next_f64())
                })
                .collect();
            let h = convex_hull(&pts);
            let c = h.vertices.iter().copied().sum::<DVec3>() / h.vertices.len() as f64;
            let map = DirMap::new(c, h.faces.iter().map(|f| f.map(|i| h.vertices[i as usize])));
            for _ in 0..5000 {
                let d = DVec3::new(
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                );
                // The exit face: the first face plane the ray meets.
                let mut exit = (f64::INFINITY, 0);
                for (k, f) in h.faces.iter().enumerate() {
                    let [a, b, e] = f.map(|i| h.vertices[i as usize]);
                    let nrm = (b - a).cross(e - a);
                    if nrm.dot(d) > 0.0 {
                        let t = nrm.dot(a - c) / nrm.dot(d);
                        if t < exit.0 {
                            exit = (t, k as u32);
                        }
                    }
                }
                assert!(map.faces(d).contains(&exit.1), "n {n}, direction {d}");
            }
        }
    }

    /// Cell centres and cell-face centres of a voxelised ball, plus points on its sphere:
    /// the many coplanar and collinear ties of the pipeline's inputs. The hull of the returned
    /// vertices is the same polytope (up to the tolerance).
    #[test]
    fn lattice_ball_with_surface_points() {
        let mut rng = Rng::new(17);
        let h = 0.1;
        let inside = |i: i32, j: i32, k: i32| (i * i + j * j + k * k) as f64 * h * h <= 1.0;
        let mut pts = Vec::new();
        for i in -11..=11 {
            for j in -11..=11 {
                for k in -11..=11 {
                    if !inside(i, j, k) {
                        continue;
                    }
                    let p = DVec3::new(i as f64, j as f64, k as f64) * h;
                    pts.push(p);
                    if !inside(i + 1, j, k) {
                        pts.push(p + DVec3::X * (0.5 * h));
                    }
                    if !inside(i, j, k - 1) {
                        pts.push(p - DVec3::Z * (0.5 * h));
                    }
                }
            }
        }
        for _ in 0..300 {
            let d = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            if d.z > 0.0 {
                pts.push(d.normalize() * 1.02);
            }
        }
        let hull = convex_hull(&pts);
        check_hull(&pts, &hull);
        assert_eq!(hull.dim, 3);
        // Hulling the vertices again keeps their hull: it may only drop vertices within the
        // tolerance of the others' hull (which ones depends on the order points are added).
        let again = convex_hull(&hull.vertices);
        check_hull(&hull.vertices, &again);
        assert!(again.vertices.iter().all(|v| hull.vertices.contains(v)));
        assert!(again.vertices.len() + 4 >= hull.vertices.len());
        assert_eq!(hull, convex_hull(&pts));
    }
}
