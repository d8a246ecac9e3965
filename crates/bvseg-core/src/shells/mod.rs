//! The surface route: volumes fitted to clusters of triangles, for meshes whose interior the
//! lattice cannot sample (open pieces, planes, thin walls, stacks of intersecting pieces:
//! the low-poly props and characters games are made of) and for skinned characters.
//!
//! 1. **Pieces** ([`pieces`]): each connected piece is a solid (closed up to small holes,
//!    thicker than the protrusion tolerance) or a shell. A solid piece that one volume holds
//!    within the tolerance is an atom, never cut (its volume then holds its interior too);
//!    every other triangle is an atom of its own.
//! 2. **Split** ([`split`]): from one cluster (one per bone that moves triangles, for a
//!    skinned mesh), the cluster that protrudes most is cut in two until every volume keeps
//!    within the protrusion tolerance, at most [`Params::max_k`] clusters (and
//!    [`Params::per_bone`] a bone).
//! 3. **Merge** ([`merge`]): neighbouring clusters become one while the one volume keeps
//!    within the tolerance, then down to the budget.
//!
//! Every volume holds every corner of its triangles (in every sampled pose, carried back by
//! its bone), and is convex, so every triangle is enclosed. Nothing is sampled inside: the
//! result's TOV, MOV and F are not measured (0), its protrusion is.
mod bound;
mod merge;
mod pieces;
mod split;

use glam::DVec3;

use crate::error::Error;
use crate::hierarchy;
use crate::mesh::Mesh;
use crate::params::{Params, Route};
use crate::result::{Metrics, Part, Segmentation, Step, StepKind};
use crate::Cancel;
use bound::Bounder;
use split::Cluster;

/// The default cap of volumes per bone for a skinned mesh (see [`Params::per_bone`]).
pub const DEFAULT_PER_BONE: usize = 3;

/// Triangles that stay together: a solid piece one volume holds, or one triangle.
#[derive(Debug, Clone)]
pub struct Atom {
    pub triangles: Vec<u32>,
    pub centroid: DVec3,
    pub area: f64,
    pub bone: Option<usize>,
}

/// The skeleton and skin the volumes follow: a skinned mesh's, whichever start is chosen.
fn skin_of(mesh: &Mesh) -> Option<(&crate::Skeleton, &crate::Skin)> {
    let rig = mesh.rig()?;
    Some((&rig.skeleton, rig.skin.as_ref()?))
}

/// Which route a run takes (see [`Route`]); never [`Route::Auto`].
pub fn route(mesh: &Mesh, params: &Params) -> Route {
    match params.route {
        Route::Auto => {}
        r => return r,
    }
    if params.k.is_some() {
        return Route::Lattice;
    }
    if skin_of(mesh).is_some() {
        return Route::Surface;
    }
    let pieces = pieces::pieces(mesh);
    if pieces.iter().any(|p| !p.is_closed()) {
        return Route::Surface;
    }
    // Closed pieces, one of them too thin for the lattice: the surface route when each is one
    // volume within the tolerance (a building of thin boxes), the lattice otherwise.
    let h = pieces::cell_size(&pieces, params.samples);
    if pieces.len() == 1 || pieces.iter().all(|p| p.is_solid(h)) {
        return Route::Lattice;
    }
    let b = Bounder::new(mesh, params, None);
    let fits = crate::parallel::map(&pieces, |p| {
        b.fit(&p.triangles, None).within_in_parallel(&b)
    });
    if fits.iter().all(|&f| f) {
        Route::Surface
    } else {
        Route::Lattice
    }
}

/// The surface route's segmentation of `mesh` (see the module's docs).
pub fn segment(mesh: &Mesh, params: &Params, cancel: &Cancel) -> Result<Segmentation, Error> {
    let skin = skin_of(mesh);
    let b = Bounder::new(mesh, params, skin).counting();
    let atoms = atoms(mesh, &b);
    cancel.check()?;
    // One cluster per bone (or one in all).
    let mut by_bone: std::collections::BTreeMap<Option<usize>, Vec<usize>> = Default::default();
    for (i, a) in atoms.iter().enumerate() {
        by_bone.entry(a.bone).or_default().push(i);
    }
    let groups: Vec<(Option<usize>, Vec<usize>)> = by_bone.into_iter().collect();
    let mut clusters: Vec<Cluster> = crate::parallel::map(&groups, |(bone, members)| {
        Cluster::new(&b, &atoms, members.clone(), *bone)
    });
    let per_bone = if skin.is_some() {
        params.per_bone.unwrap_or(DEFAULT_PER_BONE)
    } else {
        usize::MAX
    };
    // Split the cluster that protrudes most, while one is out of tolerance.
    let mut unsplittable: Vec<bool> = vec![false; clusters.len()];
    while clusters.len() < params.max_k {
        cancel.check()?;
        let count = |bone: Option<usize>| clusters.iter().filter(|c| c.bone == bone).count();
        let worst = (0..clusters.len())
            .filter(|&i| {
                !unsplittable[i]
                    && clusters[i].fit.protrusion(&b) > b.tol
                    && count(clusters[i].bone) < per_bone
            })
            .max_by(|&i, &j| {
                clusters[i]
                    .fit
                    .protrusion(&b)
                    .total_cmp(&clusters[j].fit.protrusion(&b))
                    .then(j.cmp(&i))
            });
        let Some(i) = worst else { break };
        match split::split(&b, &atoms, &clusters[i]) {
            Some([x, y]) => {
                clusters[i] = x;
                clusters.push(y);
                unsplittable.push(false);
            }
            None => unsplittable[i] = true,
        }
    }
    cancel.check()?;
    let clusters = merge::merge(&b, &atoms, clusters, params.max_k);
    cancel.check()?;
    Ok(assemble(mesh, params, &b, &atoms, clusters, skin.is_some()))
}

/// The atoms of `mesh` (see the module's docs), each bound to the bone that moves most of
/// its corners' weight.
fn atoms(mesh: &Mesh, b: &Bounder) -> Vec<Atom> {
    let area_of = |t: u32| {
        let [p, q, r] = mesh.corners(t as usize);
        0.5 * (q - p).cross(r - p).length()
    };
    let centroid_of = |t: u32| mesh.corners(t as usize).iter().sum::<DVec3>() / 3.0;
    let bone_of = |t: u32| -> Option<usize> {
        let (_, skin) = b.skin?;
        let mut w: Vec<(u32, f64)> = Vec::new();
        for v in mesh.triangles()[t as usize] {
            for &(j, x) in &skin.weights[v as usize] {
                match w.iter_mut().find(|e| e.0 == j) {
                    Some(e) => e.1 += f64::from(x),
                    None => w.push((j, f64::from(x))),
                }
            }
        }
        w.iter()
            .max_by(|a, c| a.1.total_cmp(&c.1).then(c.0.cmp(&a.0)))
            .map(|e| e.0 as usize)
    };
    let single = |t: u32| Atom {
        triangles: vec![t],
        centroid: centroid_of(t),
        area: area_of(t),
        bone: bone_of(t),
    };
    if b.skin.is_some() {
        return (0..mesh.triangles().len() as u32).map(single).collect();
    }
    let pieces = pieces::pieces(mesh);
    let h = pieces::cell_size(&pieces, b.params.samples);
    let whole: Vec<bool> = crate::parallel::map(&pieces, |p| {
        p.is_solid(h) && b.fit(&p.triangles, None).within_in_parallel(b)
    });
    let mut out = Vec::new();
    for (p, whole) in pieces.iter().zip(whole) {
        if whole {
            let area: f64 = p.triangles.iter().map(|&t| area_of(t)).sum();
            let centroid = p
                .triangles
                .iter()
                .map(|&t| area_of(t) * centroid_of(t))
                .sum::<DVec3>()
                / crate::math::max(area, f64::MIN_POSITIVE);
            out.push(Atom {
                triangles: p.triangles.clone(),
                centroid,
                area,
                bone: None,
            });
        } else {
            out.extend(p.triangles.iter().map(|&t| single(t)));
        }
    }
    out
}

/// The result of the final `clusters`.
fn assemble(
    mesh: &Mesh,
    params: &Params,
    b: &Bounder,
    atoms: &[Atom],
    clusters: Vec<Cluster>,
    skinned: bool,
) -> Segmentation {
    let k = clusters.len();
    let volumes: Vec<_> = clusters
        .iter()
        .map(|c| c.fit.volume.clone().grown(params.margin))
        .collect();
    let total: f64 = volumes.iter().map(|v| v.volume()).sum();
    // Each part's protrusion on the union's boundary: its points inside another volume do
    // not count.
    // In order, counted against the run's bound on the searches (see `bound::Bounder`).
    let pr: Vec<f64> = (0..k)
        .map(|i| {
            let others: Vec<_> = volumes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, v)| v.clone())
                .collect();
            b.union_protrusion(&volumes[i], &others, &clusters[i].fit.hull)
        })
        .collect();
    let protrusion = pr.iter().copied().fold(0.0, crate::math::max);
    let mut triangle_parts = vec![0u32; mesh.triangles().len()];
    for (i, c) in clusters.iter().enumerate() {
        for t in split::triangles(atoms, &c.atoms) {
            triangle_parts[t as usize] = i as u32;
        }
    }
    let parts: Vec<Part> = clusters
        .iter()
        .zip(&volumes)
        .zip(&pr)
        .map(|((c, v), &p)| Part {
            volume: v.clone(),
            fraction: if total > 0.0 {
                v.volume() / total
            } else {
                1.0 / k as f64
            },
            samples: 0,
            ov: 0.0,
            e: 1.0,
            protrusion: p,
            bone: c.bone,
        })
        .collect();
    let hierarchy = if params.hierarchy && !skinned {
        let hulls: Vec<Vec<DVec3>> = clusters.iter().map(|c| c.fit.hull.clone()).collect();
        let boxes: Vec<_> = volumes.iter().map(|v| v.aabb()).collect();
        let mut touching = Vec::new();
        for i in 0..k {
            for j in i + 1..k {
                let (p, q) = (boxes[i], boxes[j]);
                if (p.0 - q.1).max(q.0 - p.1).max_element() <= 2.0 * b.tol {
                    touching.push((i as u32, j as u32));
                }
            }
        }
        // Pieces far apart still get a root: chain the rest by index.
        for i in 1..k {
            touching.push((i as u32 - 1, i as u32));
        }
        touching.sort_unstable();
        touching.dedup();
        hierarchy::build(hulls, &volumes, &touching, |p| {
            bound::smallest(params, p, bound::MIN_R_REL * b.diagonal).grown(params.margin)
        })
    } else {
        Vec::new()
    };
    let step = Step {
        kind: StepKind::Final,
        k,
        f: 0.0,
        tov: 0.0,
        mov: 0.0,
        protrusion,
    };
    Segmentation {
        kinds: params.kinds,
        parts,
        metrics: Metrics {
            k,
            f: 0.0,
            tov: 0.0,
            mov: 0.0,
            protrusion,
            protrusion_rel: protrusion / crate::math::max(b.diagonal, f64::MIN_POSITIVE),
            diagonal: b.diagonal,
            samples: 0,
        },
        history: vec![step],
        hierarchy,
        triangle_parts,
        sample_parts: Vec::new(),
        cell_size: 0.0,
        budget_exhausted: false,
        skeleton: if skinned {
            mesh.rig().map(|r| r.skeleton.clone())
        } else {
            None
        },
        route: Route::Surface,
    }
}
