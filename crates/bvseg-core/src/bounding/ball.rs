//! The minimum enclosing ball (Welzl's algorithm, iterative with move-to-front order) and its
//! planar twin, the minimum enclosing circle, which the capsule and cylinder fits use.
use crate::math;
use glam::{DVec2, DVec3};

use crate::volume::BoundingVolume;

/// Relative slack of the "is inside" tests of the algorithms (round-off of the
/// circumscribed balls); the result is scaled to hold every point exactly afterwards.
const SLACK: f64 = 1e-12;

/// The points in a fixed pseudo-random order: Welzl's expected linear time needs an order
/// unrelated to the input's (hull vertices come sorted), and a fixed one keeps the result
/// deterministic.
pub fn shuffled<T: Copy>(points: &[T]) -> Vec<T> {
    let mut v = points.to_vec();
    let mut rng = crate::rng::Rng::new(0x5eed_ba11);
    for i in (1..v.len()).rev() {
        v.swap(i, rng.below(i + 1));
    }
    v
}

/// The finite points of `points`, [`shuffled`].
pub fn finite_shuffled(points: &[DVec3]) -> Vec<DVec3> {
    let finite: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    shuffled(&finite)
}

/// The smallest ball holding `points` (finite ones), radius at least `min_r`; a ball of radius
/// `min_r` at the origin when there is none.
pub fn min_ball(points: &[DVec3], min_r: f64) -> BoundingVolume {
    let p: Vec<DVec3> = finite_shuffled(points);
    let Some(&first) = p.first() else {
        return BoundingVolume::sphere(DVec3::ZERO, min_r);
    };
    let inside = |(c, r2): (DVec3, f64), q: DVec3| (q - c).length_squared() <= r2 * (1.0 + SLACK);
    let mut b = (first, 0.0);
    for i in 1..p.len() {
        if inside(b, p[i]) {
            continue;
        }
        b = (p[i], 0.0);
        for j in 0..i {
            if inside(b, p[j]) {
                continue;
            }
            b = ball2(p[i], p[j]);
            for k in 0..j {
                if inside(b, p[k]) {
                    continue;
                }
                b = ball3(p[i], p[j], p[k]);
                for l in 0..k {
                    if inside(b, p[l]) {
                        continue;
                    }
                    b = ball4(p[i], p[j], p[k], p[l]);
                }
            }
        }
    }
    BoundingVolume::sphere(b.0, math::max(b.1.sqrt(), min_r)).scaled_to_contain(p)
}

fn ball2(a: DVec3, b: DVec3) -> (DVec3, f64) {
    let c = 0.5 * (a + b);
    (c, (a - c).length_squared())
}

/// The smallest ball with three points on its boundary (its centre in their plane): the
/// circumscribed ball, or the widest pair's when they are collinear.
fn ball3(a: DVec3, b: DVec3, c: DVec3) -> (DVec3, f64) {
    let (u, v) = (b - a, c - a);
    let n = u.cross(v);
    let nn = n.length_squared();
    if nn <= 1e-24 * u.length_squared() * v.length_squared() || !nn.is_finite() {
        let pairs = [ball2(a, b), ball2(a, c), ball2(b, c)];
        return pairs
            .into_iter()
            .fold(pairs[0], |m, x| if x.1 > m.1 { x } else { m });
    }
    let off = (n.cross(u) * v.length_squared() + v.cross(n) * u.length_squared()) / (2.0 * nn);
    (a + off, off.length_squared())
}

/// The smallest ball with four points on or in it, given that the last one is outside the
/// ball of the first three: the circumsphere, or for a degenerate tetrahedron the smallest of
/// the three-point balls that holds all four.
fn ball4(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> (DVec3, f64) {
    let (u, v, w) = (b - a, c - a, d - a);
    let det = u.dot(v.cross(w));
    let scale = u.length() * v.length() * w.length();
    let holds = |(c0, r2): (DVec3, f64), q: DVec3| (q - c0).length_squared() <= r2 * (1.0 + 1e-9);
    if det.abs() > 1e-12 * scale && det.is_finite() {
        let off = (v.cross(w) * u.length_squared()
            + w.cross(u) * v.length_squared()
            + u.cross(v) * w.length_squared())
            / (2.0 * det);
        return (a + off, off.length_squared());
    }
    let cands = [
        (ball3(a, b, d), c),
        (ball3(a, c, d), b),
        (ball3(b, c, d), a),
        (ball3(a, b, c), d),
    ];
    cands
        .iter()
        .filter(|&&(bl, q)| holds(bl, q))
        .map(|x| x.0)
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .unwrap_or_else(|| {
            cands
                .iter()
                .map(|x| x.0)
                .fold(cands[0].0, |m, x| if x.1 > m.1 { x } else { m })
        })
}

/// The smallest circle holding the planar `points`: centre and radius (0 and the origin for
/// none).
#[cfg(test)]
pub fn min_circle(points: &[DVec2]) -> (DVec2, f64) {
    let (c, r, _) = min_circle_in_order(&shuffled(points));
    (c, r)
}

/// [`min_circle`] of points already in an order unrelated to their geometry (see
/// [`shuffled`]), for callers that fit many projections of one point set. Also returns the
/// indices of the (up to three, repeated when fewer) points the circle was built on: their
/// own minimum circle is the same, up to round-off.
pub fn min_circle_in_order(p: &[DVec2]) -> (DVec2, f64, [usize; 3]) {
    let Some(b) = welzl(p) else {
        return (DVec2::ZERO, 0.0, [0; 3]);
    };
    enclosing(p, b)
}

/// [`min_circle_in_order`], found from the points `hint` first: the circle of a nearby
/// projection of the same points rests on the same few points or on close ones, and starting
/// from them spares most of the incremental algorithm's updates. The circle is then computed
/// again from the points it rests on, in the order [`min_circle_in_order`] would have taken
/// them, so that both give the same bits whenever they end on the same points. They always
/// do, unless more than three points lie on the circle within round-off; then either circle
/// is as good.
pub fn min_circle_hinted(p: &mut [DVec2], hint: [usize; 3]) -> (DVec2, f64, [usize; 3]) {
    // The hint's points swapped to the front (and back afterwards: `p` is the caller's). No
    // allocation: this runs for every direction the axial searches try.
    let mut swaps = [(0, 0); 3];
    let mut front = 0;
    for h in hint {
        // Where the hinted point is now, after the swaps so far.
        let at = swaps[..front].iter().fold(h, |x, &s| swapped(x, s));
        if at < p.len() && at >= front {
            p.swap(front, at);
            swaps[front] = (front, at);
            front += 1;
        }
    }
    let swaps = &swaps[..front];
    let found = welzl(p);
    for &(a, b) in swaps.iter().rev() {
        p.swap(a, b);
    }
    let Some((_, at)) = found else {
        return (DVec2::ZERO, 0.0, [0; 3]);
    };
    // The same points in the input's indices, largest first: the order in which the plain
    // algorithm's loops (`i > j > k`) would have built the circle on them.
    let mut on = at.map(|x| swaps.iter().rev().fold(x, |x, &s| swapped(x, s)));
    on.sort_unstable_by(|a, b| b.cmp(a));
    let (b, support) = match on {
        [i, _, k] if i == k => ((p[i], 0.0), [i; 3]),
        [i, j, k] if i == j || j == k => {
            let j = if i == j { k } else { j };
            let c = 0.5 * (p[i] + p[j]);
            ((c, (p[i] - c).length_squared()), [i, j, j])
        }
        [i, j, k] => (circle3(p[i], p[j], p[k]), [i, j, k]),
    };
    enclosing(p, (b, support))
}

/// Index `x` after the positions `a` and `b` swapped their contents.
fn swapped(x: usize, (a, b): (usize, usize)) -> usize {
    if x == a {
        b
    } else if x == b {
        a
    } else {
        x
    }
}

/// The incremental minimum circle of `p` in its order: the circle (centre and squared
/// radius) and the indices it rests on (`[i; 3]` for one point, `[i, j, j]` for two, with
/// `i > j > k`); `None` for no points.
fn welzl(p: &[DVec2]) -> Option<((DVec2, f64), [usize; 3])> {
    let &first = p.first()?;
    let inside = |(c, r2): (DVec2, f64), q: DVec2| (q - c).length_squared() <= r2 * (1.0 + SLACK);
    let mut b = (first, 0.0);
    let mut support = [0; 3];
    for i in 1..p.len() {
        if inside(b, p[i]) {
            continue;
        }
        b = (p[i], 0.0);
        support = [i; 3];
        for j in 0..i {
            if inside(b, p[j]) {
                continue;
            }
            let c = 0.5 * (p[i] + p[j]);
            b = (c, (p[i] - c).length_squared());
            support = [i, j, j];
            for k in 0..j {
                if inside(b, p[k]) {
                    continue;
                }
                b = circle3(p[i], p[j], p[k]);
                support = [i, j, k];
            }
        }
    }
    Some((b, support))
}

/// The circle `b` grown to hold every point of `p` exactly: round-off may leave a point a
/// hair outside.
fn enclosing(p: &[DVec2], (b, support): ((DVec2, f64), [usize; 3])) -> (DVec2, f64, [usize; 3]) {
    let r2 = p
        .iter()
        .map(|&q| (q - b.0).length_squared())
        .fold(b.1, math::max);
    (b.0, r2.sqrt(), support)
}

/// A lower bound on the radius of the smallest circle holding the three points, within a few
/// units of round-off of it: half the longest side, or the circumradius when the triangle is
/// clearly acute (computed at the largest angle, where it is well conditioned).
pub fn circle3_radius_below(t: [DVec2; 3]) -> f64 {
    let [a, b, c] = t;
    // The longest side's squared length, then the two sides at the vertex opposite it.
    let (l, s1, s2, at) = {
        let (ab, bc, ca) = (
            (b - a).length_squared(),
            (c - b).length_squared(),
            (a - c).length_squared(),
        );
        if ab >= bc && ab >= ca {
            (ab, bc, ca, (c, a, b))
        } else if bc >= ca {
            (bc, ca, ab, (a, b, c))
        } else {
            (ca, ab, bc, (b, c, a))
        }
    };
    let half_diameter = 0.5 * l.sqrt();
    if l >= (s1 + s2) * (1.0 - 1e-6) {
        return half_diameter;
    }
    // R = l^(1/2) / (2 sin C), with sin C = |u x v| / (|u| |v|) at the vertex C opposite it.
    let (u, v) = (at.1 - at.0, at.2 - at.0);
    let cross = u.perp_dot(v).abs();
    let r = l.sqrt() * (s1 * s2).sqrt() / (2.0 * cross);
    if r.is_finite() {
        math::max(r, half_diameter)
    } else {
        half_diameter
    }
}

/// The circumcircle of three points (the widest pair's circle when they are collinear).
fn circle3(a: DVec2, b: DVec2, c: DVec2) -> (DVec2, f64) {
    let (u, v) = (b - a, c - a);
    let d = 2.0 * u.perp_dot(v);
    if d.abs() <= 1e-300 || !d.is_finite() {
        let pairs = [(a, b), (a, c), (b, c)];
        let (x, y) = pairs
            .into_iter()
            .max_by(|p, q| {
                (p.0 - p.1)
                    .length_squared()
                    .total_cmp(&(q.0 - q.1).length_squared())
            })
            .unwrap_or((a, b));
        let m = 0.5 * (x + y);
        return (m, (x - m).length_squared());
    }
    let (uu, vv) = (u.length_squared(), v.length_squared());
    let off = DVec2::new(v.y * uu - u.y * vv, u.x * vv - v.x * uu) / d;
    (a + off, off.length_squared())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn cloud(n: usize, seed: u64, scale: DVec3) -> Vec<DVec3> {
        let mut r = Rng::new(seed);
        (0..n)
            .map(|_| DVec3::new(r.next_f64() - 0.5, r.next_f64() - 0.5, r.next_f64() - 0.5) * scale)
            .collect()
    }

    #[test]
    fn the_three_points_bound_is_their_circle_from_below() {
        let mut r = Rng::new(5);
        for i in 0..2000 {
            let mut t = [0; 3].map(|_| DVec2::new(r.next_f64(), r.next_f64()));
            // Thin and repeated triangles too.
            match i % 4 {
                1 => t[2] = t[0] + 1e-9 * (t[1] - t[0]).perp(),
                2 => t[2] = t[1],
                3 => t[2] = t[0].lerp(t[1], r.next_f64()) + DVec2::splat(1e-13),
                _ => {}
            }
            let exact = min_circle(&t).1;
            let below = circle3_radius_below(t);
            assert!(below <= exact * (1.0 + 1e-12), "{t:?}: {below} > {exact}");
            assert!(
                below >= exact * (1.0 - 1e-6) || i % 4 != 0,
                "{t:?}: {below} < {exact}"
            );
        }
    }

    #[test]
    fn the_ball_holds_every_point_and_touches_the_farthest_ones() {
        for seed in 0..20 {
            let p = cloud(200, seed, DVec3::new(3.0, 1.0, 0.5));
            let b = min_ball(&p, 1e-9);
            assert!(p.iter().all(|&q| b.contains(q)));
            // Optimal: no smaller ball around a nearby centre holds them (a local check).
            let r = b.radius();
            for d in [
                DVec3::X,
                DVec3::Y,
                DVec3::Z,
                -DVec3::X,
                -DVec3::Y,
                -DVec3::Z,
            ] {
                let c = b.center + d * 1e-3 * r;
                let need = p.iter().map(|&q| (q - c).length()).fold(0.0, math::max);
                assert!(need >= r * (1.0 - 1e-9), "seed {seed}: {need} < {r}");
            }
        }
        // Known cases: the cube's corners, a regular tetrahedron, one point, coplanar points.
        let cube: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let b = min_ball(&cube, 1e-9);
        assert!((b.radius() - 0.75f64.sqrt()).abs() < 1e-9);
        assert!((b.center - DVec3::splat(0.5)).length() < 1e-9);
        let flat: Vec<DVec3> = (0..50)
            .map(|i| {
                let a = i as f64 * 0.7;
                DVec3::new(a.cos(), a.sin(), 0.0) * (1.0 + 0.01 * (i % 3) as f64)
            })
            .collect();
        let b = min_ball(&flat, 1e-9);
        assert!(flat.iter().all(|&q| b.contains(q)) && b.radius() < 1.03);
        assert_eq!(min_ball(&[DVec3::ONE], 0.5).radius(), 0.5);
    }

    /// From any hint, the same circle as without one, to the bit, on points in general
    /// position (and whatever the hint, on the points it was given, left as they were).
    #[test]
    fn a_hinted_circle_is_the_plain_one() {
        let mut r = Rng::new(11);
        for n in [1, 2, 3, 4, 7, 30, 200] {
            for _ in 0..200 {
                let p: Vec<DVec2> = (0..n)
                    .map(|_| DVec2::new(r.next_f64() * 3.0, r.next_f64()))
                    .collect();
                let plain = min_circle_in_order(&p);
                let hint = [r.below(n + 1), r.below(n), r.below(n)];
                let mut q = p.clone();
                let hinted = min_circle_hinted(&mut q, hint);
                assert_eq!(q, p);
                assert_eq!(
                    (
                        hinted.0.to_array().map(f64::to_bits),
                        hinted.1.to_bits(),
                        hinted.2
                    ),
                    (
                        plain.0.to_array().map(f64::to_bits),
                        plain.1.to_bits(),
                        plain.2
                    ),
                    "n {n}, hint {hint:?}"
                );
            }
        }
    }

    #[test]
    fn the_circle_holds_every_point_and_is_minimal() {
        let mut r = Rng::new(3);
        let p: Vec<DVec2> = (0..300)
            .map(|_| DVec2::new(r.next_f64() * 4.0, r.next_f64()))
            .collect();
        let (c, rad) = min_circle(&p);
        assert!(p.iter().all(|&q| (q - c).length() <= rad * (1.0 + 1e-12)));
        for d in [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y] {
            let c2 = c + d * 1e-3 * rad;
            let need = p.iter().map(|&q| (q - c2).length()).fold(0.0, math::max);
            assert!(need >= rad * (1.0 - 1e-9));
        }
    }
}
