//! Volumes that follow the animation: for a skinned mesh, each part's volume is fitted in
//! its bone's frame to enclose its triangles in the rest pose and in every sampled pose.
//!
//! At a pose where the bone's world matrix is `G(t)`, a volume `V` given in the rest pose
//! moves to `G(t) · G(rest)⁻¹ · V`. It encloses a triangle's corners `x(t)` there exactly
//! when `V` encloses `G(rest) · G(t)⁻¹ · x(t)`: so each part's volume is fitted, with the
//! run's kinds, to its rest points (samples, shared faces, corners) and to its triangles'
//! corners of every pose carried back into the rest pose by its bone. A convex volume that
//! holds a triangle's three corners holds the triangle, so the surface between vertices
//! stays covered in every sampled pose.
//!
//! Between two sampled times a corner moves along a curve, not along the straight line
//! between its two samples that the volume holds. How far the curve strays is estimated
//! from the samples themselves: for three consecutive poses of one animation, the middle
//! sample's distance from the line between the outer two is what a chord of twice the step
//! misses, about four times what a chord of one step does; each volume is grown by half of
//! the largest such distance among its corners, twice that estimate. This is exact at the
//! sampled times and holds between them for motions as smooth as their sampling resolves
//! (the reader samples every key and enough times between keys: see `bvseg-io`).
use crate::math;
use glam::{DMat4, DVec3};

use crate::bounding::hull::hull_points;
use crate::geometry::closest_on_segment;
use crate::pipeline::{Context, State};
use crate::{BoundingVolume, Skeleton, Skin};

/// How far, in lattice cells, a corner's sample in a pose may lie from the last sample of
/// that corner kept before it and be left out of the fit: each volume is then grown by that
/// distance, so it still holds every sample. A corner that moves rigidly with the part's bone
/// comes back to its rest position in every pose, and most corners of a character do, or
/// nearly: leaving them out keeps the fits fast (BrainStem: 491 poses of 34,000 corners),
/// and 2 % of a cell is below what the figures measured on the lattice can see.
const KEEP_CELLS: f64 = 0.02;

/// Each part's volume for a skinned mesh (see the module's docs): `bones[i]` is part `i`'s
/// bone; a part without bone or triangles keeps its rest volume.
pub fn posed_volumes(
    ctx: &Context,
    cur: &State,
    bones: &[Option<usize>],
    skeleton: &Skeleton,
    skin: &Skin,
) -> Vec<BoundingVolume> {
    let k = cur.part.k();
    let mut tris: Vec<Vec<u32>> = vec![Vec::new(); k];
    for (t, &p) in ctx
        .fitter
        .enclosure()
        .triangle_parts(&cur.part.labels)
        .iter()
        .enumerate()
    {
        tris[p as usize].push(t as u32);
    }
    let keep = KEEP_CELLS * ctx.solid.grid.h;
    let mesh = &ctx.mesh;
    let parts: Vec<usize> = (0..k).collect();
    crate::parallel::map(&parts, |&i| {
        let rest = &cur.volumes[i];
        let Some(b) = bones[i] else {
            return rest.clone();
        };
        if tris[i].is_empty() || skin.poses.is_empty() {
            return rest.clone();
        }
        let (moved, margin) = carried_back(mesh, skeleton, skin, b, &tris[i], keep);
        let mut points = cur.fits[i].hull.clone();
        points.extend(moved);
        let hull = hull_points(&points);
        let v = ctx.fitter.fit_points(&ctx.solid, &hull);
        if margin > 0.0 {
            v.grown(margin)
        } else {
            v
        }
    })
}

/// The corners of triangles `tris` in every pose of `skin`, carried back into the rest pose by
/// bone `b` (`G(rest) G(t)⁻¹ x(t)`; see the module's docs), leaving out a corner within
/// `keep` of the last of its samples kept, and the margin to grow a volume of them by: the
/// motion between sampled poses (half the largest miss of a chord of three consecutive poses)
/// plus `keep` when a sample was left out. Shared by both routes.
pub(crate) fn carried_back(
    mesh: &crate::Mesh,
    skeleton: &Skeleton,
    skin: &Skin,
    b: usize,
    tris: &[u32],
    keep: f64,
) -> (Vec<DVec3>, f64) {
    let mut points = Vec::new();
    // Each posed corner with its rest position (that of the mesh vertex it was welded
    // into), which the rest hull holds.
    let mut corners: Vec<(u32, DVec3)> = tris
        .iter()
        .flat_map(|&t| {
            let rest = mesh.triangles()[t as usize];
            let posed = skin.corners[t as usize];
            (0..3).map(move |c| (posed[c], rest[c]))
        })
        .map(|(c, v)| (c, mesh.vertices()[v as usize]))
        .collect();
    corners.sort_unstable_by_key(|c| c.0);
    corners.dedup_by_key(|c| c.0);
    let back: Vec<DMat4> = skin
        .poses
        .iter()
        .map(|p| skeleton.joints[b].rest * p.joints[b].inverse())
        .collect();
    let mut last: Vec<DVec3> = corners.iter().map(|c| c.1).collect();
    let mut left_out = false;
    // The corners carried back in this pose and the two before it, for the estimate of
    // how far they stray between samples (see the module's docs).
    let n = corners.len();
    let (mut now, mut before, mut before2) = (
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; n],
    );
    let mut worst = 0.0f64;
    for (k, (p, m)) in skin.poses.iter().zip(&back).enumerate() {
        for ((&(c, _), last), x) in corners.iter().zip(&mut last).zip(&mut now) {
            *x = m.transform_point3(p.vertices[c as usize]);
            if x.distance_squared(*last) > keep * keep {
                points.push(*x);
                *last = *x;
            } else {
                left_out = true;
            }
        }
        let poses = &skin.poses;
        if k >= 2 && (poses[k - 2].animation, poses[k - 1].animation) == (p.animation, p.animation)
        {
            for c in 0..n {
                worst = math::max(worst, segment_distance(before[c], before2[c], now[c]));
            }
        }
        std::mem::swap(&mut before2, &mut before);
        std::mem::swap(&mut before, &mut now);
    }
    let mut margin = 0.5 * worst;
    if left_out {
        margin += keep;
    }
    (points, margin)
}

/// Distance from `p` to the segment `[a, b]`.
fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    (p - closest_on_segment(p, a, b)).length()
}
