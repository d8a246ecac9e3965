//! Convex hulls of the `hull` shape, written for this crate: an incremental (Quickhull)
//! construction whose one predicate, the side of a point with respect to the plane of three
//! others, is exact (a floating-point filter, then Shewchuk's expansion arithmetic where the
//! filter cannot decide), so the hull's topology is always consistent, whatever the
//! degeneracies; the facets' normals are the exact cross products, rounded once.
//!
//! Everything is computed on the points scaled by a power of two to magnitude about 1 (an
//! exact change that keeps squares and products of any finite input finite).
use std::collections::HashMap;

use glam::DVec3;

/// A point farther than this from the line or the plane of the others, relative to the
/// points' size, makes them span a volume: a flat set whose coordinates were rounded stays
/// flat (its round-off is near 1e-16), and any set thicker than that is a solid whose
/// topology the exact predicates get right. (`bvseg-core` calls points within 1e-10 of its
/// box's side from a plane flat; what it accepts, this accepts.)
const FLAT: f64 = 1e-12;

/// The boundary of the convex hull of some points, as outward triangles.
#[derive(Debug)]
pub(crate) struct Hull {
    /// Triangles, as indices into the points, counter-clockwise seen from outside.
    pub(crate) triangles: Vec<[usize; 3]>,
    /// Each triangle's outward unit normal.
    pub(crate) normals: Vec<DVec3>,
}

/// The convex hull of `points` (finite, at least 4 of them).
///
/// # Errors
///
/// A one-line message when there are fewer than 4 points, or when they span no volume (all
/// within `1e-12` of the points' size from a plane).
pub(crate) fn convex_hull(points: &[DVec3]) -> Result<Hull, String> {
    if points.len() < 4 {
        return Err(format!(
            "a hull needs at least 4 points, got {}",
            points.len()
        ));
    }
    let p = scaled(points);
    let triangles = quickhull(&p)?;
    let normals = triangles
        .iter()
        .map(|&[a, b, c]| exact_cross(p[a], p[b], p[c]).normalize_or_zero())
        .collect();
    Ok(Hull { triangles, normals })
}

const SPAN_ERROR: &str = "the points span no volume (they are coplanar within 1e-12 of their size)";

/// `2^k` for any `k` (clamped to the normal range).
fn pow2(k: i32) -> f64 {
    let k = k.clamp(-1022, 1023);
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// The points times a power of two that brings their largest coordinate near 1.
fn scaled(points: &[DVec3]) -> Vec<DVec3> {
    let m = points
        .iter()
        .fold(0.0f64, |m, q| m.max(q.abs().max_element()));
    if !(m > 0.0 && m.is_finite()) {
        return points.to_vec();
    }
    let k = (-(m.log2().floor() as i32) - 1).clamp(-2000, 2000);
    let (s1, s2) = (pow2(k / 2), pow2(k - k / 2));
    points.iter().map(|&q| q * s1 * s2).collect()
}

struct Face {
    v: [usize; 3],
    alive: bool,
    /// Points strictly outside this face, not yet on the hull.
    conflict: Vec<usize>,
}

/// Whether `q` is strictly above the plane of face `v` (on its outer side).
fn above(p: &[DVec3], v: [usize; 3], q: usize) -> bool {
    orient(p[v[0]], p[v[1]], p[v[2]], p[q]) > 0.0
}

fn quickhull(p: &[DVec3]) -> Result<Vec<[usize; 3]>, String> {
    let n = p.len();
    let mean = p.iter().fold(DVec3::ZERO, |s, &q| s + q) / n as f64;
    let size = p
        .iter()
        .fold(0.0f64, |m, &q| m.max((q - mean).abs().max_element()));
    if size.is_nan() || size <= 0.0 || size.is_infinite() {
        return Err(SPAN_ERROR.into());
    }
    let tol = FLAT * size;
    // The initial tetrahedron: the farthest pair of axis-extreme points, the point farthest
    // from their line, the point farthest from the plane of the three.
    let mut ext = [0usize; 6];
    for (i, q) in p.iter().enumerate() {
        for d in 0..3 {
            if q[d] < p[ext[2 * d]][d] {
                ext[2 * d] = i;
            }
            if q[d] > p[ext[2 * d + 1]][d] {
                ext[2 * d + 1] = i;
            }
        }
    }
    let (mut i0, mut i1, mut best) = (0, 0, -1.0f64);
    for &a in &ext {
        for &b in &ext {
            let d = (p[a] - p[b]).length();
            if d > best {
                (i0, i1, best) = (a, b, d);
            }
        }
    }
    if best <= tol {
        return Err(SPAN_ERROR.into());
    }
    let dir = (p[i1] - p[i0]) / best;
    let off_line = |q: DVec3| {
        let r = q - p[i0];
        (r - dir * dir.dot(r)).length()
    };
    let i2 = argmax(p, off_line);
    if off_line(p[i2]) <= tol {
        return Err(SPAN_ERROR.into());
    }
    let normal = (p[i1] - p[i0]).cross(p[i2] - p[i0]).normalize_or_zero();
    let off_plane = |q: DVec3| normal.dot(q - p[i0]).abs();
    let i3 = argmax(p, off_plane);
    if off_plane(p[i3]) <= tol || orient(p[i0], p[i1], p[i2], p[i3]) == 0.0 {
        return Err(SPAN_ERROR.into());
    }

    let mut faces: Vec<Face> = Vec::new();
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    let add = |faces: &mut Vec<Face>, edges: &mut HashMap<(usize, usize), usize>, v: [usize; 3]| {
        let id = faces.len();
        for k in 0..3 {
            edges.insert((v[k], v[(k + 1) % 3]), id);
        }
        faces.push(Face {
            v,
            alive: true,
            conflict: Vec::new(),
        });
        id
    };
    let tet = [i0, i1, i2, i3];
    for k in 0..4 {
        let opposite = tet[k];
        let mut v = [tet[(k + 1) % 4], tet[(k + 2) % 4], tet[(k + 3) % 4]];
        if orient(p[v[0]], p[v[1]], p[v[2]], p[opposite]) > 0.0 {
            v.swap(0, 1);
        }
        add(&mut faces, &mut edges, v);
    }
    for q in 0..n {
        if tet.contains(&q) {
            continue;
        }
        if let Some(f) = (0..4).find(|&f| above(p, faces[f].v, q)) {
            faces[f].conflict.push(q);
        }
    }

    let mut stack: Vec<usize> = (0..4).filter(|&f| !faces[f].conflict.is_empty()).collect();
    // Per face: the round in which it was found visible, or found not visible.
    let mut seen_visible: Vec<usize> = vec![0; faces.len()];
    let mut seen_hidden: Vec<usize> = vec![0; faces.len()];
    let mut round = 0usize;
    while let Some(f) = stack.pop() {
        if !faces[f].alive || faces[f].conflict.is_empty() {
            continue;
        }
        round += 1;
        let [a, b, c] = faces[f].v;
        let nf = (p[b] - p[a]).cross(p[c] - p[a]);
        let apex = faces[f]
            .conflict
            .iter()
            .copied()
            .max_by(|&x, &y| nf.dot(p[x] - p[a]).total_cmp(&nf.dot(p[y] - p[a])))
            .unwrap_or(faces[f].conflict[0]);
        // The faces the apex sees, from f across edges, and the horizon around them.
        let mut visible = vec![f];
        seen_visible[f] = round;
        let mut horizon: Vec<(usize, usize)> = Vec::new();
        let mut k = 0;
        while k < visible.len() {
            let g = visible[k];
            k += 1;
            let v = faces[g].v;
            for e in 0..3 {
                let (x, y) = (v[e], v[(e + 1) % 3]);
                match edges.get(&(y, x)) {
                    Some(&h) if faces[h].alive => {
                        if seen_visible[h] == round {
                            continue;
                        }
                        if seen_hidden[h] != round && above(p, faces[h].v, apex) {
                            seen_visible[h] = round;
                            visible.push(h);
                        } else {
                            seen_hidden[h] = round;
                            horizon.push((x, y));
                        }
                    }
                    _ => horizon.push((x, y)),
                }
            }
        }
        let mut orphans: Vec<usize> = Vec::new();
        for &g in &visible {
            let face = &mut faces[g];
            face.alive = false;
            orphans.extend(face.conflict.drain(..).filter(|&q| q != apex));
            let v = face.v;
            for e in 0..3 {
                let key = (v[e], v[(e + 1) % 3]);
                if edges.get(&key) == Some(&g) {
                    edges.remove(&key);
                }
            }
        }
        let first = faces.len();
        for &(x, y) in &horizon {
            add(&mut faces, &mut edges, [x, y, apex]);
            seen_visible.push(0);
            seen_hidden.push(0);
        }
        for q in orphans {
            if let Some(g) = (first..faces.len()).find(|&g| above(p, faces[g].v, q)) {
                faces[g].conflict.push(q);
            }
        }
        stack.extend((first..faces.len()).filter(|&g| !faces[g].conflict.is_empty()));
    }

    let out: Vec<[usize; 3]> = faces.iter().filter(|f| f.alive).map(|f| f.v).collect();
    // A closed surface: every edge met once each way (always so with exact predicates; a
    // check, not a repair).
    let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
    for v in &out {
        for e in 0..3 {
            *directed.entry((v[e], v[(e + 1) % 3])).or_insert(0) += 1;
        }
    }
    let closed = out.len() >= 4
        && directed
            .iter()
            .all(|(&(x, y), &m)| m == 1 && directed.get(&(y, x)) == Some(&1));
    if !closed {
        return Err("the convex hull of the points could not be built".into());
    }
    Ok(out)
}

fn argmax(p: &[DVec3], f: impl Fn(DVec3) -> f64) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, &q) in p.iter().enumerate() {
        let x = f(q);
        if x > best.1 {
            best = (i, x);
        }
    }
    best.0
}

/// A value with the sign of `det[b − a, c − a, d − a]` (positive when `d` is on the side of
/// the plane of `a, b, c` that `(b − a) × (c − a)` points to), exactly.
pub(crate) fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (u, v, w) = (b - a, c - a, d - a);
    let det = u.x * (v.y * w.z - v.z * w.y)
        + u.y * (v.z * w.x - v.x * w.z)
        + u.z * (v.x * w.y - v.y * w.x);
    let permanent = u.x.abs() * ((v.y * w.z).abs() + (v.z * w.y).abs())
        + u.y.abs() * ((v.z * w.x).abs() + (v.x * w.z).abs())
        + u.z.abs() * ((v.x * w.y).abs() + (v.y * w.x).abs());
    // Shewchuk's bound for this evaluation is (7 + 56ε)ε · permanent, ε = 2^-53.
    let bound = 1e-15 * permanent;
    if det > bound || -det > bound {
        return det;
    }
    orient_exact(a, b, c, d)
}

fn orient_exact(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let u = [0, 1, 2].map(|k| two_diff(b[k], a[k]));
    let v = [0, 1, 2].map(|k| two_diff(c[k], a[k]));
    let w = [0, 1, 2].map(|k| two_diff(d[k], a[k]));
    let m0 = minor(&v[1], &w[2], &v[2], &w[1]);
    let m1 = minor(&v[2], &w[0], &v[0], &w[2]);
    let m2 = minor(&v[0], &w[1], &v[1], &w[0]);
    let det = sum(&sum(&mul(&u[0], &m0), &mul(&u[1], &m1)), &mul(&u[2], &m2));
    det.last().copied().unwrap_or(0.0)
}

/// `(b − a) × (c − a)`, each component exact before its one rounding.
fn exact_cross(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let u = [0, 1, 2].map(|k| two_diff(b[k], a[k]));
    let v = [0, 1, 2].map(|k| two_diff(c[k], a[k]));
    let comp = |i: usize, j: usize| approx(&minor(&u[i], &v[j], &u[j], &v[i]));
    DVec3::new(comp(1, 2), comp(2, 0), comp(0, 1))
}

/// Expansions (Shewchuk 1997): sums of non-overlapping doubles, smallest first, no zeros.
type Expansion = Vec<f64>;

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

fn two_diff(a: f64, b: f64) -> Expansion {
    let x = a - b;
    let bv = a - x;
    let av = x + bv;
    let y = (a - av) + (bv - b);
    [y, x].into_iter().filter(|&t| t != 0.0).collect()
}

fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    (x, a.mul_add(b, -x))
}

/// `e + b`.
fn grow(e: &[f64], b: f64) -> Expansion {
    let mut q = b;
    let mut out = Vec::with_capacity(e.len() + 1);
    for &x in e {
        let (s, h) = two_sum(q, x);
        if h != 0.0 {
            out.push(h);
        }
        q = s;
    }
    if q != 0.0 {
        out.push(q);
    }
    out
}

fn sum(e: &[f64], f: &[f64]) -> Expansion {
    f.iter().fold(e.to_vec(), |acc, &x| grow(&acc, x))
}

/// `e · b`.
fn scale(e: &[f64], b: f64) -> Expansion {
    let mut out = Vec::with_capacity(2 * e.len());
    let Some((&first, rest)) = e.split_first() else {
        return out;
    };
    let (mut q, h) = two_product(first, b);
    out.push(h);
    for &x in rest {
        let (hi, lo) = two_product(x, b);
        let (s, h1) = two_sum(q, lo);
        out.push(h1);
        let (s2, h2) = two_sum(hi, s);
        out.push(h2);
        q = s2;
    }
    out.push(q);
    out.retain(|&t| t != 0.0);
    out
}

fn mul(e: &[f64], f: &[f64]) -> Expansion {
    f.iter().fold(Vec::new(), |acc, &x| sum(&acc, &scale(e, x)))
}

/// `a·b − c·d`.
fn minor(a: &[f64], b: &[f64], c: &[f64], d: &[f64]) -> Expansion {
    let neg: Expansion = mul(c, d).iter().map(|x| -x).collect();
    sum(&mul(a, b), &neg)
}

/// The nearest double to an expansion, about.
fn approx(e: &[f64]) -> f64 {
    e.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::SplitMix;

    fn det_i128(p: [[i64; 3]; 4]) -> i128 {
        let d = |i: usize, k: usize| (p[i][k] - p[0][k]) as i128;
        d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1))
            + d(1, 1) * (d(2, 2) * d(3, 0) - d(2, 0) * d(3, 2))
            + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0))
    }

    #[test]
    fn orientation_is_exact_on_near_coplanar_points() {
        // Integer coordinates up to 2^40: exact as doubles, products far beyond 2^53, and
        // the determinant exact in i128.
        let mut rng = SplitMix::new(7);
        let mut r = |m: i64| (rng.next_u64() % (2 * m as u64 + 1)) as i64 - m;
        let sign = |x: f64| (x > 0.0) as i128 - (x < 0.0) as i128;
        let mut coplanar = 0;
        for _ in 0..3000 {
            let big = 1i64 << 40;
            let a = [r(big), r(big), r(big)];
            let u = [r(1 << 24), r(1 << 24), r(1 << 24)];
            let v = [r(1 << 24), r(1 << 24), r(1 << 24)];
            let (i, j) = (r(8), r(8));
            let d = [0, 1, 2].map(|k| a[k] + i * u[k] + j * v[k] + r(1));
            let b = [0, 1, 2].map(|k| a[k] + u[k]);
            let c = [0, 1, 2].map(|k| a[k] + v[k]);
            let pts = [a, b, c, d];
            let want = det_i128(pts).signum();
            let f = |q: [i64; 3]| DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64);
            assert_eq!(sign(orient(f(a), f(b), f(c), f(d))), want, "{pts:?}");
            assert_eq!(sign(orient_exact(f(a), f(b), f(c), f(d))), want, "{pts:?}");
            coplanar += (want == 0) as usize;
        }
        assert!(coplanar > 50, "{coplanar}");
    }

    fn check_hull(points: &[DVec3], want_volume: Option<f64>) -> Hull {
        let h = convex_hull(points).unwrap();
        // Euler: V - E + F = 2 for the triangulated sphere, E = 3F/2.
        let mut used: Vec<usize> = h.triangles.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        let f = h.triangles.len();
        assert_eq!(used.len() as i64 - (3 * f / 2) as i64 + f as i64, 2);
        for (t, n) in h.triangles.iter().zip(&h.normals) {
            assert!((n.length() - 1.0).abs() < 1e-12);
            let off = n.dot(points[t[0]]);
            for q in points {
                assert!(n.dot(*q) - off < 1e-12, "{q} outside");
            }
        }
        if let Some(want) = want_volume {
            let vol: f64 = h
                .triangles
                .iter()
                .map(|t| points[t[0]].dot(points[t[1]].cross(points[t[2]])) / 6.0)
                .sum();
            assert!(
                (vol - want).abs() < 1e-12 * want.max(1.0),
                "{vol} vs {want}"
            );
        }
        h
    }

    #[test]
    fn hulls_of_random_and_degenerate_point_sets() {
        let mut rng = SplitMix::new(1);
        let ball: Vec<DVec3> = (0..300)
            .map(|_| DVec3::new(rng.signed(), rng.signed(), rng.signed()))
            .collect();
        check_hull(&ball, None);
        // A cube's surface on a grid: most points coplanar, many collinear, plus repeats
        // and the centre.
        let mut grid = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                for k in 0..5 {
                    let q = DVec3::new(i as f64, j as f64, k as f64) * 0.5 - DVec3::ONE;
                    if q.abs().max_element() == 1.0 || q == DVec3::ZERO {
                        grid.push(q);
                        grid.push(q);
                    }
                }
            }
        }
        let h = check_hull(&grid, Some(8.0));
        // Only the corners can be vertices; the faces' interior points may also be, but
        // every normal is one of the six.
        for n in &h.normals {
            assert_eq!(n.abs().max_element(), 1.0, "{n}");
        }
        // Tiny and huge coordinates, far from the origin.
        let corners: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        for (s, o) in [(1e-300, 0.0), (1e300, 0.0), (1.0, 1e6)] {
            let pts: Vec<DVec3> = corners.iter().map(|&c| c * s + DVec3::splat(o)).collect();
            let h = convex_hull(&pts).unwrap();
            assert_eq!(h.triangles.len(), 12);
        }
    }

    #[test]
    fn flat_and_short_point_sets_are_refused() {
        let sq = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.5, 0.5, 1e-14),
        ];
        assert!(convex_hull(&sq[..3]).unwrap_err().contains("at least 4"));
        assert!(convex_hull(&sq[..4])
            .unwrap_err()
            .contains("span no volume"));
        assert!(convex_hull(&sq).unwrap_err().contains("span no volume"));
        let line: Vec<DVec3> = (0..6).map(|i| DVec3::X * i as f64).collect();
        assert!(convex_hull(&line).is_err());
        assert!(convex_hull(&[DVec3::ONE; 5]).is_err());
        // Thick enough, down to 1e-11 of the size (the pyramid's four sides and its base
        // in two triangles).
        for z in [1e-3, 1e-8, 1e-10, 1e-11] {
            let mut thick = sq;
            thick[4].z = z;
            assert_eq!(convex_hull(&thick).unwrap().triangles.len(), 6, "{z}");
        }
        // A rotated, hence rounded, flat lattice stays flat.
        let rot = glam::DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let lattice: Vec<DVec3> = (0..49)
            .map(|i| rot * DVec3::new((i % 7) as f64, (i / 7) as f64, 0.0) + DVec3::splat(3.0))
            .collect();
        assert!(convex_hull(&lattice)
            .unwrap_err()
            .contains("span no volume"));
    }
}
