//! The skeleton-seeded start: "we assign a seed point to each link … a CVT is used as an
//! initial partition". The seed of a link is the whole link: each sample goes to the link
//! nearest it (the Voronoi cells of the segments, which follow a limb along its length
//! where point seeds would cut it across), each part keeps one connected region, and the
//! partition is then optimised for that k like any other start.
use super::{nearest, Link};
use crate::flooding::make_connected;
use crate::initialization::drop_empty_parts;
use crate::optimization::optimize;
use crate::partition::{Partition, Solid};

/// Fewest samples a link's cell needs to start a part of its own: fewer cannot be fitted
/// well, and such links (a finger's last joint on a coarse lattice) join their neighbours.
const MIN_SAMPLES: usize = 8;

/// The start seeded by `links`, optimised with up to `max_sweeps` Lloyd sweeps and the
/// boundary moves; `None` when no link is nearest to enough samples (a tiny solid), so
/// that the caller falls back to the unseeded start.
///
/// `bones`, when not empty, gives a sample the bone its skin moves it with: it then goes to
/// the nearest link of that bone, so that a part starts on one bone's skin, whose volume stays
/// small in every pose, where the nearest link may be another bone's (a plate of a robot's
/// shoulder nearer the arm's link than its own).
pub fn seeded_partition(
    solid: &Solid,
    links: &[Link],
    bones: &[Option<usize>],
    max_sweeps: usize,
) -> Option<Partition> {
    if links.is_empty() || solid.is_empty() {
        return None;
    }
    let samples: Vec<usize> = (0..solid.q.len()).collect();
    let nearest_of: Vec<usize> = crate::parallel::map(&samples, |&s| {
        let q = solid.q[s];
        match bones.get(s).copied().flatten() {
            Some(b) => nearest_of_bone(links, b, q).unwrap_or_else(|| nearest(links, q)),
            None => nearest(links, q),
        }
    });
    let mut count = vec![0usize; links.len()];
    for &l in &nearest_of {
        count[l] += 1;
    }
    // Links with too few samples hand theirs to the nearest link that has enough.
    let kept: Vec<usize> = (0..links.len())
        .filter(|&l| count[l] >= MIN_SAMPLES)
        .collect();
    if kept.is_empty() {
        return None;
    }
    let kept_links: Vec<Link> = kept.iter().map(|&l| links[l]).collect();
    let mut label_of_link = vec![u32::MAX; links.len()];
    for (i, &l) in kept.iter().enumerate() {
        label_of_link[l] = i as u32;
    }
    let mut labels: Vec<u32> = solid
        .q
        .iter()
        .zip(&nearest_of)
        .map(|(&q, &l)| match label_of_link[l] {
            u32::MAX => nearest(&kept_links, q) as u32,
            i => i,
        })
        .collect();
    make_connected(&solid.grid, &mut labels, &solid.components, None, |s, j| {
        kept_links[j as usize].dist2(solid.q[s])
    });
    let mut part = Partition::from_labels(solid, labels, kept.len());
    drop_empty_parts(&mut part);
    optimize(solid, &mut part, None, None, max_sweeps);
    Some(part)
}

/// The index into `links` of the link of `bone` nearest `q`, if it has one.
fn nearest_of_bone(links: &[Link], bone: usize, q: glam::DVec3) -> Option<usize> {
    let mut best: Option<(f64, usize)> = None;
    for (i, l) in links.iter().enumerate().filter(|(_, l)| l.bone == bone) {
        let d = l.dist2(q);
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, i));
        }
    }
    best.map(|b| b.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flooding::is_connected;
    use crate::sampling::Grid;
    use glam::DVec3;

    #[test]
    fn an_l_shaped_solid_seeded_by_its_two_links_gets_its_two_arms() {
        // Two boxes meeting at the origin: one along x, one along y.
        let g = Grid::from_inside_fn(DVec3::splat(-0.3), DVec3::new(3.0, 3.0, 0.3), 0.05, |p| {
            let arm_x = p.x > -0.25 && p.x < 2.9 && p.y.abs() < 0.25 && p.z.abs() < 0.25;
            let arm_y = p.y > -0.25 && p.y < 2.9 && p.x.abs() < 0.25 && p.z.abs() < 0.25;
            arm_x || arm_y
        });
        let solid = Solid::new(g);
        let to_q = |p: DVec3| {
            let off = DVec3::new(
                solid.offset[0] as f64,
                solid.offset[1] as f64,
                solid.offset[2] as f64,
            );
            (p - solid.grid.origin) / solid.grid.h - off
        };
        let links = [
            Link {
                bone: 0,
                a: to_q(DVec3::ZERO),
                b: to_q(DVec3::new(2.8, 0.0, 0.0)),
            },
            Link {
                bone: 0,
                a: to_q(DVec3::ZERO),
                b: to_q(DVec3::new(0.0, 2.8, 0.0)),
            },
        ];
        let part = seeded_partition(&solid, &links, &[], 20).unwrap();
        assert_eq!(part.k(), 2);
        assert!(is_connected(&solid.grid, &part.labels, &solid.components));
        // Far along each arm, every sample is in that arm's part.
        for (s, p) in solid.grid.points.iter().enumerate() {
            if p.x > 1.0 {
                assert_eq!(
                    part.labels[s],
                    part.labels[solid.grid.points.iter().position(|p| p.x > 2.0).unwrap()]
                );
            }
        }
        let far_x = solid.grid.points.iter().position(|p| p.x > 2.0).unwrap();
        let far_y = solid.grid.points.iter().position(|p| p.y > 2.0).unwrap();
        assert_ne!(part.labels[far_x], part.labels[far_y]);
        // Samples whose skin moves them all with the first arm's bone start on its link: the
        // other link keeps no samples, and one part is left.
        let links = [
            links[0],
            Link {
                bone: 1,
                ..links[1]
            },
        ];
        let bones = vec![Some(0); solid.len()];
        assert_eq!(
            seeded_partition(&solid, &links, &bones, 20).map(|p| p.k()),
            Some(1)
        );
        assert_eq!(
            seeded_partition(&solid, &links, &[], 20).map(|p| p.k()),
            Some(2)
        );
        // A skeleton far outside the solid seeds nothing.
        let away = [Link {
            bone: 0,
            a: to_q(DVec3::splat(100.0)),
            b: to_q(DVec3::splat(101.0)),
        }];
        assert!(seeded_partition(&solid, &away, &[], 20).is_some_and(|p| p.k() == 1));
    }
}
