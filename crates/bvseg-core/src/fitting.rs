//! Output volumes of parts, fitted once per distinct part and cached.
//!
//! A part's volume depends only on its set of samples (through the points it must enclose,
//! see [`crate::enclosure`]), and that set is identified by the part's exact moments (integer
//! sums, see [`crate::partition`]). The refinement and the tightening try many partitions
//! that differ in a few parts; the cache makes each try cost only the parts it changed.
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use glam::DVec3;

use crate::bounding::hull::hull_points;
use crate::enclosure::Enclosure;
use crate::metrics::{
    outside_cells, outside_count, protrusion_capped, Cell, Cells, SurfaceDistance,
};
use crate::moments::Moments;
use crate::partition::Solid;
use crate::{BoundingVolume, Cancel, Kinds, Mesh, Shape};

/// Tolerance of the ellipsoid fit (relative volume excess over the optimum).
pub const MVEE_TOL: f64 = 1e-4;

/// A part's convex-hull points, fitted volume, and the lattice cells outside the solid that
/// the volume covers.
#[derive(Debug)]
pub struct Fit {
    /// Convex-hull vertices of the points the part must enclose.
    pub hull: Vec<DVec3>,
    /// The fitted volume.
    pub volume: BoundingVolume,
    /// Lattice cells outside the solid whose centres the volume contains.
    pub outside: Cells,
    /// The kinds it was chosen among, each with the number of outside cells its volume had.
    pub counts: Vec<(Shape, usize)>,
    /// The volume's own protrusion (see [`crate::metrics::protrusion`]), measured when first
    /// asked for: only the fits of states the refinement judges need it.
    protrusion: OnceLock<f64>,
}

/// Cache key: the part's exact moments and the kinds it may be fitted with.
pub type FitKey = [u64; 11];

/// The cache key of a part with moments `m` fitted with one of `kinds`.
pub fn fit_key(m: &Moments, kinds: Kinds) -> FitKey {
    [
        u64::from(kinds.bits()),
        m.n.to_bits(),
        m.s.x.to_bits(),
        m.s.y.to_bits(),
        m.s.z.to_bits(),
        m.ss[0].to_bits(),
        m.ss[1].to_bits(),
        m.ss[2].to_bits(),
        m.ss[3].to_bits(),
        m.ss[4].to_bits(),
        m.ss[5].to_bits(),
    ]
}

/// Fits volumes of a set of kinds to parts of one solid, with a cache: each part gets the
/// kind whose volume covers the fewest lattice cells outside the solid (then the smaller
/// volume, then the earlier kind). It also keeps the run's
/// account: the outside cells its fits have counted, against a bound (see
/// [`Fitter::exhausted`]), and the run's [`Cancel`] flag.
#[derive(Debug)]
pub struct Fitter {
    kinds: Kinds,
    max_hull_vertices: usize,
    enclosure: Enclosure,
    cache: FitCache,
    cancel: Cancel,
    cells: AtomicU64,
    budget: u64,
    surface: SurfaceDistance,
    /// Nodes and triangles of the surface's tree the protrusions have visited, and the
    /// bound on them (see [`crate::refine::budget::DISTANCE_PER_SAMPLE`]).
    distance_spent: AtomicU64,
    distance_budget: u64,
}

/// A two-generation cache with a memory budget: when the young generation outgrows
/// [`CACHE_BYTES`], it becomes the old one and the previous old one is dropped. Fits in use
/// stay alive through their `Arc`s; what is dropped is only refitted if asked for again.
#[derive(Debug, Default)]
struct FitCache {
    young: HashMap<FitKey, Arc<Fit>>,
    old: HashMap<FitKey, Arc<Fit>>,
    young_bytes: usize,
}

/// Outside cells that any kind may have beyond the best one's and stay in contention (see
/// [`Fit::contenders`]): parts with almost none differ by a handful of cells.
const FEW_CELLS: f64 = 4.0;

/// Memory budget of one cache generation. Runs of the default size never fill it; at a million
/// samples a larger one raised the peak memory for no gain in time (BENCHMARKS.md has the
/// peaks of such runs today).
const CACHE_BYTES: usize = 64 << 20;

impl Fit {
    /// The kinds it was chosen among whose volumes had at most `1 + slack` times the chosen
    /// one's outside cells, and a few more: the kinds in contention for the part when it
    /// changes a little.
    pub fn contenders(&self, slack: f64) -> Kinds {
        let best = self.counts.iter().map(|c| c.1).min().unwrap_or(0);
        let limit = best as f64 * (1.0 + slack) + FEW_CELLS;
        self.counts
            .iter()
            .filter(|c| c.1 as f64 <= limit)
            .fold(Kinds::only(self.volume.shape), |k, c| k.with(c.0))
    }

    /// The fit's size for the cache's budget. Its outside cells count one [`Cell`] each, as
    /// when they were stored one by one: what the cache keeps, and so the results of runs
    /// that fill it, do not depend on how the cells are stored (their runs take less).
    fn bytes(&self) -> usize {
        std::mem::size_of::<Fit>()
            + self.hull.len() * std::mem::size_of::<DVec3>()
            + self.outside.len() * std::mem::size_of::<Cell>()
    }
}

impl FitCache {
    fn get(&self, k: &FitKey) -> Option<&Arc<Fit>> {
        self.young.get(k).or_else(|| self.old.get(k))
    }

    fn contains_key(&self, k: &FitKey) -> bool {
        self.get(k).is_some()
    }

    fn insert(&mut self, k: FitKey, f: Arc<Fit>) {
        if self.young.contains_key(&k) {
            return;
        }
        if self.young_bytes > CACHE_BYTES {
            self.old = std::mem::take(&mut self.young);
            self.young_bytes = 0;
        }
        self.young_bytes += f.bytes();
        self.young.insert(k, f);
    }
}

impl Fitter {
    /// A fitter for `mesh` sampled as `solid`, of the `kinds` (hulls of at most 32 vertices).
    pub fn new(mesh: &Mesh, solid: &Solid, kinds: Kinds) -> Self {
        Self::with_budget(mesh, solid, (kinds, 32), [u64::MAX; 2], Cancel::new())
    }

    /// A fitter of `kinds` with hulls of at most `max_hull_vertices`, whose [`Fitter::exhausted`] says so once its fits have counted `budget[0]`
    /// outside cells, or `cancel` is set, and whose protrusions search the surface exactly
    /// until they have visited `budget[1]` nodes and triangles of its tree.
    pub fn with_budget(
        mesh: &Mesh,
        solid: &Solid,
        (kinds, max_hull_vertices): (Kinds, usize),
        [budget, distance_budget]: [u64; 2],
        cancel: Cancel,
    ) -> Self {
        Self {
            kinds,
            max_hull_vertices,
            enclosure: Enclosure::new(mesh, solid),
            cache: FitCache::default(),
            cancel,
            cells: AtomicU64::new(0),
            budget,
            surface: SurfaceDistance::new(mesh),
            distance_spent: AtomicU64::new(0),
            distance_budget,
        }
    }

    /// Whether the optional work of the run should stop: its fits have counted more outside
    /// cells than the budget allows (volumes far larger than their parts, as around many
    /// scattered specks), or the run was cancelled.
    pub fn exhausted(&self) -> bool {
        self.cancel.is_cancelled() || self.cells.load(Ordering::Relaxed) > self.budget
    }

    /// The enclosure data (which triangles each part holds).
    pub fn enclosure(&self) -> &Enclosure {
        &self.enclosure
    }

    /// Fit a volume of this fitter's kinds to `points`, the vertices of a convex hull (from
    /// [`hull_points`]): the ellipsoid fit does not compute their hull again. Any other point
    /// set still gets a correct fit, only a slower one.
    pub fn fit_points(&self, solid: &Solid, points: &[DVec3]) -> BoundingVolume {
        self.choose(solid, points, self.kinds).0
    }

    /// The fits to `points` (convex-hull vertices, as for [`Fitter::fit_points`]) of each of
    /// this fitter's kinds but `except`, in the kinds' order, fitted in parallel.
    pub fn fits_of_other_kinds(
        &self,
        solid: &Solid,
        points: &[DVec3],
        except: Shape,
    ) -> Vec<BoundingVolume> {
        let min_r = 0.5 * solid.grid.h;
        let shapes: Vec<Shape> = self.kinds.shapes().filter(|&s| s != except).collect();
        crate::bounding::fit_each(&shapes, points, min_r, self.max_hull_vertices)
    }

    /// This fitter's kinds.
    pub fn kinds(&self) -> Kinds {
        self.kinds
    }

    /// The best of the kinds' volumes for `points` (see the type's docs) and each kind's
    /// number of outside cells. The kinds are judged by their counts; only the chosen one's
    /// cells are listed, by the caller that needs them.
    fn choose(
        &self,
        solid: &Solid,
        points: &[DVec3],
        kinds: Kinds,
    ) -> (BoundingVolume, Vec<(Shape, usize)>) {
        let min_r = 0.5 * solid.grid.h;
        let shapes: Vec<Shape> = kinds.shapes().collect();
        let fits = crate::bounding::fit_each(&shapes, points, min_r, self.max_hull_vertices);
        let counts = crate::parallel::map(&fits, |v| outside_count(&solid.grid, v));
        let each: Vec<(Shape, usize)> = shapes.iter().copied().zip(counts).collect();
        let mut best: Option<(BoundingVolume, usize)> = None;
        for (v, &(_, cells)) in fits.into_iter().zip(&each) {
            let better = best
                .as_ref()
                .is_none_or(|(b, bc)| (cells, v.volume()) < (*bc, b.volume()));
            if better {
                best = Some((v, cells));
            }
        }
        match best {
            Some((v, _)) => (v, each),
            // `Params::validate` keeps the set non-empty; an empty one still gets a volume.
            None => {
                let v = crate::bounding::fit(Shape::Ellipsoid, points, min_r, 32);
                let cells = outside_count(&solid.grid, &v);
                (v, vec![(Shape::Ellipsoid, cells)])
            }
        }
    }

    fn make(&self, solid: &Solid, points: &[DVec3], kinds: Kinds) -> Fit {
        let hull = hull_points(points);
        let (volume, counts) = self.choose(solid, &hull, kinds);
        let outside = outside_cells(&solid.grid, &volume);
        crate::work::add(points.len() + outside.len());
        self.cells
            .fetch_add(outside.len() as u64, Ordering::Relaxed);
        Fit {
            hull,
            volume,
            outside,
            counts,
            protrusion: OnceLock::new(),
        }
    }

    /// Each fit's own protrusion: the largest distance to the surface of its boundary outside
    /// the solid (measured in parallel where not yet known, then kept with the fit). Exact
    /// while the run's bound on the searches lasts, an upper bound beyond it (see
    /// [`crate::metrics::protrusion_capped`]).
    pub fn protrusions(&self, solid: &Solid, fits: &[Arc<Fit>]) -> Vec<f64> {
        self.protrusions_of(
            solid,
            fits.iter()
                .map(|f| (&f.volume, f.hull.as_slice(), Some(&f.protrusion)))
                .collect(),
            &[],
        )
    }

    /// The protrusions of `volumes` (each with the points of the solid it holds, and where to
    /// keep the figure, if anywhere) on the union's boundary with `others[i]` (empty: the
    /// volume's own), within the run's bound on the searches. The bound is checked once per
    /// call, and each volume's search has its own cap, so the figures do not depend on the
    /// thread count.
    #[allow(clippy::type_complexity)]
    pub fn protrusions_of(
        &self,
        solid: &Solid,
        volumes: Vec<(&BoundingVolume, &[DVec3], Option<&OnceLock<f64>>)>,
        others: &[Vec<BoundingVolume>],
    ) -> Vec<f64> {
        let exact = self.distance_spent.load(Ordering::Relaxed) <= self.distance_budget;
        let cap = if exact {
            crate::refine::budget::DISTANCE_PER_FIT
        } else {
            0
        };
        let idx: Vec<usize> = (0..volumes.len()).collect();
        let out = crate::parallel::map(&idx, |&i| {
            let (v, points, keep) = volumes[i];
            let none = Vec::new();
            let o = others.get(i).unwrap_or(&none);
            let measure = || protrusion_capped(v, &self.surface, &solid.grid, o, points, cap);
            match keep {
                Some(cell) => {
                    let mut spent = 0;
                    let value = *cell.get_or_init(|| {
                        let (value, s) = measure();
                        spent = s;
                        value
                    });
                    (value, spent)
                }
                None => measure(),
            }
        });
        let spent: u64 = out.iter().map(|o| o.1).sum();
        self.distance_spent.fetch_add(spent, Ordering::Relaxed);
        out.into_iter().map(|o| o.0).collect()
    }

    /// The cached fit of a part with moments `m`, if any.
    pub fn get(&self, m: &Moments) -> Option<Arc<Fit>> {
        self.get_as(m, self.kinds)
    }

    /// The cached fit of a part with moments `m` among `kinds`, if any.
    pub fn get_as(&self, m: &Moments, kinds: Kinds) -> Option<Arc<Fit>> {
        self.cache.get(&fit_key(m, kinds)).cloned()
    }

    /// Fit every part of a labelling: `parts[i]` are the moments of part `i`, `labels` the
    /// part of each sample. Only parts missing from the cache are fitted (in parallel).
    pub fn fit_all(
        &mut self,
        mesh: &Mesh,
        solid: &Solid,
        labels: &[u32],
        parts: &[Moments],
    ) -> Vec<Arc<Fit>> {
        let keys: Vec<FitKey> = parts.iter().map(|m| fit_key(m, self.kinds)).collect();
        let missing: Vec<usize> = (0..parts.len())
            .filter(|&i| !self.cache.contains_key(&keys[i]))
            .collect();
        if !missing.is_empty() {
            let mut members = vec![Vec::new(); parts.len()];
            for (s, &l) in labels.iter().enumerate() {
                members[l as usize].push(s as u32);
            }
            let one = |&i: &usize| {
                let pts = self
                    .enclosure
                    .points(mesh, solid, labels, &members[i], i as u32);
                self.make(solid, &pts, self.kinds)
            };
            let new: Vec<Fit> = crate::parallel::map(&missing, one);
            for (&i, f) in missing.iter().zip(new) {
                self.cache.insert(keys[i], Arc::new(f));
            }
        }
        // Everything asked for is in the cache now: fitted above or found before. Reading it
        // back cannot miss, but fitting again is the safe answer if it ever did.
        keys.iter()
            .enumerate()
            .map(|(i, k)| match self.cache.get(k) {
                Some(f) => f.clone(),
                None => {
                    let mem: Vec<u32> = (0..labels.len() as u32)
                        .filter(|&s| labels[s as usize] == i as u32)
                        .collect();
                    let pts = self.enclosure.points(mesh, solid, labels, &mem, i as u32);
                    Arc::new(self.make(solid, &pts, self.kinds))
                }
            })
            .collect()
    }

    /// Fit parts given directly by their enclosure points, keyed by their moments (for
    /// candidate parts that are not in any labelling yet). Runs in parallel.
    pub fn fit_candidates(&mut self, solid: &Solid, cands: Vec<(Moments, Vec<DVec3>)>) {
        let kinds = self.kinds;
        self.fit_candidates_as(
            solid,
            cands.into_iter().map(|(m, p)| (m, p, kinds)).collect(),
        );
    }

    /// [`Fitter::fit_candidates`], each candidate with the kinds it may be fitted with (the
    /// tightening keeps each part's kind: see [`crate::tightening`]).
    pub fn fit_candidates_as(&mut self, solid: &Solid, cands: Vec<(Moments, Vec<DVec3>, Kinds)>) {
        let todo: Vec<(FitKey, Vec<DVec3>, Kinds)> = cands
            .into_iter()
            .map(|(m, p, k)| (fit_key(&m, k), p, k))
            .filter(|(k, _, _)| !self.cache.contains_key(k))
            .collect();
        let one = |(k, p, kinds): &(FitKey, Vec<DVec3>, Kinds)| (*k, self.make(solid, p, *kinds));
        let new: Vec<(FitKey, Fit)> = crate::parallel::map(&todo, one);
        for (k, f) in new {
            self.cache.insert(k, Arc::new(f));
        }
    }
}
