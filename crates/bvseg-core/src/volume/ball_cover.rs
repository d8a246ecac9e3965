//! A convex polyhedron around the unit ball, for engines that collide an ellipsoid only as a
//! convex mesh (UsdPhysics has no ellipsoid; PhysX cooks hulls of at most 64 vertices and
//! simplifies larger ones, which may cut into the solid). Every face plane of the polyhedron
//! is at distance >= 1 from the origin, so it holds the unit ball, and any affine image of it
//! holds the same image of the ball: mapped by an ellipsoid's frame, it encloses the
//! ellipsoid.
use std::sync::OnceLock;

use glam::DVec3;

use super::Polytope;
use crate::math;

/// The number of vertices of [`Polytope::around_unit_ball`]: PhysX's default limit on a
/// convex mesh.
pub const BALL_COVER_VERTICES: usize = 64;

/// Repulsion steps and their size: enough for the points to settle (more changes the
/// volume by less than 1%), few enough to build in milliseconds.
const RELAX_STEPS: usize = 1000;
const RELAX_STEP: f64 = 0.05;

impl Polytope {
    /// A convex polyhedron of at most [`BALL_COVER_VERTICES`] vertices holding the unit
    /// ball: every face plane is at distance >= 1 from the origin, and its volume is about
    /// 1.05 times the ball's. Built once, from a fixed point set (a Fibonacci spiral spread
    /// evenly over the sphere by repulsion, its hull pushed out until the nearest face
    /// touches the ball), so it is the same on every platform.
    pub fn around_unit_ball() -> &'static Polytope {
        static COVER: OnceLock<Polytope> = OnceLock::new();
        COVER.get_or_init(|| build().unwrap_or_else(Polytope::octahedron_around_unit_ball))
    }
}

/// The cover of [`Polytope::around_unit_ball`]; `None` only if the hull of the fixed points
/// were to fail, which the tests rule out.
fn build() -> Option<Polytope> {
    let points = relax(fibonacci(BALL_COVER_VERTICES));
    let hull = Polytope::new(&points)?;
    // Every face of the hull, slivers included (`planes` skips them, but they bound too).
    let nearest = hull
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| hull.vertices()[i as usize]);
            (b - a).cross(c - a).normalize().dot(a)
        })
        .fold(f64::INFINITY, math::min);
    if !(nearest > 0.0 && nearest.is_finite()) {
        return None;
    }
    // A few ulps more than 1 / nearest, so that the scaled planes' distances, rounded, are
    // still >= 1.
    let scale = (1.0 + 1e-12) / nearest;
    let scaled: Vec<DVec3> = hull.vertices().iter().map(|&p| p * scale).collect();
    Polytope::new(&scaled)
}

/// `n` points on the unit sphere along a Fibonacci spiral: nearly even, and deterministic.
fn fibonacci(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).sqrt();
            let (s, c) = math::sin_cos(golden * i as f64);
            DVec3::new(r * c, r * s, z)
        })
        .collect()
}

/// The points moved apart on the sphere by inverse-square repulsion (Thomson's problem),
/// which evens out the gaps the spiral leaves near its poles: the largest gap decides how far
/// the hull must be pushed out.
fn relax(mut p: Vec<DVec3>) -> Vec<DVec3> {
    let n = p.len();
    for _ in 0..RELAX_STEPS {
        let forces: Vec<DVec3> = (0..n)
            .map(|i| {
                (0..n)
                    .filter(|&j| j != i)
                    .map(|j| {
                        let d = p[i] - p[j];
                        let l2 = d.length_squared();
                        d / (l2 * l2.sqrt())
                    })
                    .sum()
            })
            .collect();
        for (q, f) in p.iter_mut().zip(forces) {
            let tangent = f - *q * f.dot(*q);
            *q = (*q + tangent * (RELAX_STEP / n as f64)).normalize();
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_face_plane_is_at_least_one_from_the_origin() {
        let p = Polytope::around_unit_ball();
        assert!(p.vertices().len() <= BALL_COVER_VERTICES);
        assert!(p.vertices().len() >= 60, "{}", p.vertices().len());
        for t in p.triangles() {
            let [a, b, c] = t.map(|i| p.vertices()[i as usize]);
            let d = (b - a).cross(c - a).normalize().dot(a);
            assert!(d >= 1.0, "{d}");
        }
        assert!(p.min_offset() >= 1.0);
        // Tight: within 7% of the ball's volume, its nearest face touching the ball.
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        let ratio = p.volume() / ball;
        assert!(ratio > 1.0 && ratio < 1.07, "{ratio}");
        assert!(p.min_offset() < 1.0 + 1e-9);
    }

    #[test]
    fn points_of_the_sphere_are_inside() {
        let p = Polytope::around_unit_ball();
        for u in fibonacci(2000) {
            assert!(p.gauge(u) <= 1.0, "{u}: {}", p.gauge(u));
        }
    }

    #[test]
    fn the_fallback_holds_the_ball_too() {
        let o = Polytope::octahedron_around_unit_ball();
        assert_eq!(o.vertices().len(), 6);
        assert!(o.planes().iter().all(|&(_, d)| d >= 1.0));
        for (t, &(n, _)) in o.triangles().iter().zip(o.planes()) {
            let [a, b, c] = t.map(|i| o.vertices()[i as usize]);
            assert!(
                (b - a).cross(c - a).normalize().dot(n) > 1.0 - 1e-12,
                "{t:?}"
            );
        }
        assert!((o.volume() - 4.0 / 3.0 * 3f64.sqrt().powi(3)).abs() < 1e-9);
        for u in fibonacci(500) {
            assert!(o.gauge(u) <= 1.0 + 1e-12);
        }
    }
}
