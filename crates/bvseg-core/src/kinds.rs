//! Which kinds of volume a run may use, and which engines take which natively.
use std::fmt;

use crate::volume::Shape;

/// A set of volume kinds ([`Shape`]s). Each part gets, among the kinds of the set, the volume
/// that adds the least outside volume (lattice cells outside the solid), ties going to the
/// smaller volume and then to the earlier kind in [`Shape::ALL`].
///
/// ```
/// use bvseg_core::{Kinds, Shape};
/// let k: Kinds = "obb,capsule,sphere".parse().unwrap();
/// assert!(k.contains(Shape::Capsule) && !k.contains(Shape::Ellipsoid));
/// assert_eq!(Kinds::MIXED.to_string(), "mixed");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Kinds(u8);

impl Kinds {
    /// Ellipsoids only: the paper's volumes.
    pub const ELLIPSOID: Kinds = Kinds::only(Shape::Ellipsoid);
    /// Oriented boxes only.
    pub const OBB: Kinds = Kinds::only(Shape::Obb);
    /// Spheres only.
    pub const SPHERE: Kinds = Kinds::only(Shape::Sphere);
    /// Capsules only.
    pub const CAPSULE: Kinds = Kinds::only(Shape::Capsule);
    /// Cylinders only.
    pub const CYLINDER: Kinds = Kinds::only(Shape::Cylinder);
    /// Convex hulls only.
    pub const HULL: Kinds = Kinds::only(Shape::Hull);
    /// Ellipsoids and boxes (`mixed` in schema 1).
    pub const MIXED: Kinds = Kinds::ELLIPSOID.with(Shape::Obb);
    /// Every primitive: ellipsoid, box, sphere, capsule and cylinder (no hulls).
    pub const PRIMITIVES: Kinds = Kinds::MIXED
        .with(Shape::Sphere)
        .with(Shape::Capsule)
        .with(Shape::Cylinder);

    /// The set as bits, one per [`Shape`] (for cache keys).
    pub(crate) const fn bits(self) -> u8 {
        self.0
    }

    /// The set of one kind.
    pub const fn only(s: Shape) -> Kinds {
        Kinds(1 << s as u8)
    }

    /// This set and `s`.
    #[must_use]
    pub const fn with(self, s: Shape) -> Kinds {
        Kinds(self.0 | 1 << s as u8)
    }

    /// Whether `s` is in the set.
    pub const fn contains(self, s: Shape) -> bool {
        self.0 & (1 << s as u8) != 0
    }

    /// Whether the set is empty (never true of a parsed set).
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The kinds of the set, in [`Shape::ALL`]'s order.
    pub fn shapes(self) -> impl Iterator<Item = Shape> {
        Shape::ALL.into_iter().filter(move |&s| self.contains(s))
    }

    /// The one kind of a set of one.
    pub fn single(self) -> Option<Shape> {
        let mut it = self.shapes();
        match (it.next(), it.next()) {
            (Some(s), None) => Some(s),
            _ => None,
        }
    }
}

impl Default for Kinds {
    /// [`Kinds::PRIMITIVES`]: on the shared meshes the tightest of the primitive sets
    /// (BENCHMARKS.md judges each kind against k).
    fn default() -> Self {
        Kinds::PRIMITIVES
    }
}

impl fmt::Display for Kinds {
    /// `mixed` for ellipsoids and boxes (schema 1's name), otherwise the kinds' names joined
    /// by commas.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if *self == Kinds::MIXED {
            return f.write_str("mixed");
        }
        let names: Vec<&str> = self.shapes().map(Shape::as_str).collect();
        f.write_str(&names.join(","))
    }
}

/// A kind name in a list that names no kind.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown volume kind {name:?}: expected a comma list of ellipsoid, obb (or box), sphere, \
     capsule, cylinder, hull, or mixed (ellipsoid,obb)"
)]
#[non_exhaustive]
pub struct UnknownKind {
    /// The name given.
    pub name: String,
}

impl std::str::FromStr for Kinds {
    type Err = UnknownKind;

    /// A comma list of kind names (see [`Shape::from_name`]) and the sets `mixed`
    /// (ellipsoid, box), `primitives` (all but the hull) and `all`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut k = Kinds(0);
        for name in s.split(',').map(str::trim) {
            let set = match name {
                "mixed" => Some(Kinds::MIXED),
                "primitives" => Some(Kinds::PRIMITIVES),
                "all" => Some(Kinds::PRIMITIVES.with(Shape::Hull)),
                _ => None,
            };
            if let Some(set) = set {
                k.0 |= set.0;
                continue;
            }
            let shape = Shape::from_name(name).ok_or_else(|| UnknownKind {
                name: name.to_string(),
            })?;
            k = k.with(shape);
        }
        Ok(k)
    }
}

/// An engine or format whose native collider kinds a run can be limited to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Target {
    /// MuJoCo: ellipsoid, box, capsule, cylinder and sphere geoms (and meshes for hulls).
    Mujoco,
    /// glTF `KHR_implicit_shapes` with `KHR_physics_rigid_bodies`: sphere, box, capsule and
    /// cylinder shapes (and convex-hull colliders over meshes).
    Gltf,
    /// parry3d, rapier and Avian: ball, cuboid, capsule and cylinder (and convex polyhedra).
    Parry,
    /// PhysX (and Isaac): sphere, box, capsule and convex mesh; PhysX 5 also has cylinders
    /// as convex cores.
    Physx,
    /// USD physics: sphere, cube, capsule and cylinder (and convex meshes).
    Usd,
}

impl Target {
    /// Every target, for listings.
    pub const ALL: [Target; 5] = [
        Target::Mujoco,
        Target::Gltf,
        Target::Parry,
        Target::Physx,
        Target::Usd,
    ];

    /// The target's name on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Target::Mujoco => "mujoco",
            Target::Gltf => "gltf",
            Target::Parry => "parry",
            Target::Physx => "physx",
            Target::Usd => "usd",
        }
    }

    /// The primitive kinds the target takes natively (add [`Shape::Hull`] for its convex
    /// meshes).
    pub fn kinds(self) -> Kinds {
        let engines = Kinds::OBB
            .with(Shape::Sphere)
            .with(Shape::Capsule)
            .with(Shape::Cylinder);
        match self {
            Target::Mujoco => engines.with(Shape::Ellipsoid),
            Target::Gltf | Target::Parry | Target::Physx | Target::Usd => engines,
        }
    }

    /// The kinds of a target name: `NAME` or `NAME-hull` (hulls too), also `rapier` and
    /// `avian` for parry and `isaac` for PhysX.
    pub fn kinds_of(name: &str) -> Option<Kinds> {
        let (base, hull) = match name.strip_suffix("-hull") {
            Some(b) => (b, true),
            None => (name, false),
        };
        let t = match base {
            "rapier" | "avian" => Target::Parry,
            "isaac" => Target::Physx,
            _ => Target::ALL.into_iter().find(|t| t.as_str() == base)?,
        };
        let k = t.kinds();
        Some(if hull { k.with(Shape::Hull) } else { k })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_parse_print_and_targets() {
        let k: Kinds = "obb, capsule,sphere".parse().unwrap();
        assert_eq!(k.to_string(), "obb,sphere,capsule");
        assert_eq!("mixed".parse::<Kinds>().unwrap(), Kinds::MIXED);
        assert_eq!("primitives".parse::<Kinds>().unwrap(), Kinds::PRIMITIVES);
        assert!("all".parse::<Kinds>().unwrap().contains(Shape::Hull));
        assert_eq!("ellipsoid,box".parse::<Kinds>().unwrap(), Kinds::MIXED);
        assert_eq!(
            "torus".parse::<Kinds>().unwrap_err().name,
            "torus".to_string()
        );
        assert!("".parse::<Kinds>().is_err());
        assert_eq!(Kinds::CAPSULE.single(), Some(Shape::Capsule));
        assert_eq!(Kinds::MIXED.single(), None);
        let parry = Target::kinds_of("parry").unwrap();
        assert!(!parry.contains(Shape::Ellipsoid) && !parry.contains(Shape::Hull));
        assert!(Target::kinds_of("avian-hull")
            .unwrap()
            .contains(Shape::Hull));
        assert!(Target::kinds_of("mujoco")
            .unwrap()
            .contains(Shape::Ellipsoid));
        assert_eq!(Target::kinds_of("mujoco").unwrap(), Kinds::PRIMITIVES);
        assert!(Target::kinds_of("unity").is_none());
    }
}
