//! Quickhull on the snapped points: the initial simplex, the point partition and the
//! expansion, with the sign-exact orientation test that keeps its topology consistent.
use crate::math;
use glam::DVec3;

use super::cull::{DirMap, InnerEllipsoid};
use super::{Raw, DIRMAP_MIN_POINTS, GRID, ORIENT_ERR};

pub(super) const NONE: u32 = u32::MAX;

pub(super) struct Face {
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

pub(super) struct QuickHull<'a> {
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
    pub(super) fn new(q: &'a [DVec3], eps: f64) -> Self {
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
        (math::max(d, 0.0).to_bits(), f)
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

    pub(super) fn run(&mut self) -> Raw {
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

/// The element maximising `key` (the first one on ties).
pub(super) fn argmax(it: impl Iterator<Item = usize>, key: impl Fn(usize) -> f64) -> usize {
    let mut best = (f64::NEG_INFINITY, 0);
    for i in it {
        let k = key(i);
        if k > best.0 {
            best = (k, i);
        }
    }
    best.1
}

pub(super) fn edge_index(v: &[u32; 3], a: u32, b: u32) -> Option<usize> {
    (0..3).find(|&k| v[k] == a && v[(k + 1) % 3] == b)
}

/// Sign-exact orientation of `p` against the plane through `a, b, c` (positive above, that is
/// on the side of `(b - a) x (c - a)`), for integer-valued coordinates below 2^40.
pub(super) fn orient_i128(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> i128 {
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
pub(super) fn polygon(q: &[DVec3], nrm: DVec3, eps: f64) -> Vec<usize> {
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
