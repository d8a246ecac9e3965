//! The volume kinds a run may use, as the controls show them: one checkbox per kind, a few
//! presets (the paper's, the default, engines' native sets), names on the command line and in
//! the page's query string, and each part's size as the parts table shows it.
use bvseg_core::{BoundingVolume, Kinds, Shape, Target};

/// The label of `shape`'s checkbox (also what a script clicks in the page).
pub fn checkbox_label(shape: Shape) -> &'static str {
    match shape {
        Shape::Ellipsoid => "Ellipsoids",
        Shape::Obb => "Boxes",
        Shape::Sphere => "Spheres",
        Shape::Capsule => "Capsules",
        Shape::Cylinder => "Cylinders",
        Shape::Hull => "Hulls",
    }
}

/// The presets of the kinds control, in the order of its menu: each named set, then the same
/// set with hulls.
pub fn presets() -> [(&'static str, Kinds); 8] {
    let hull = |k: Kinds| k.with(Shape::Hull);
    let mujoco = Target::Mujoco.kinds();
    // glTF, parry, PhysX and USD take the same primitives.
    let engines = Target::Parry.kinds();
    [
        ("paper: ellipsoid", Kinds::ELLIPSOID),
        ("paper: ellipsoid + hull", hull(Kinds::ELLIPSOID)),
        ("primitives (default)", Kinds::PRIMITIVES),
        ("primitives + hull", hull(Kinds::PRIMITIVES)),
        ("mujoco", mujoco),
        ("mujoco + hull", hull(mujoco)),
        ("gltf / parry / physx / usd", engines),
        ("gltf / parry / physx / usd + hull", hull(engines)),
    ]
}

/// The name of the first preset that is `kinds`, or `custom`.
pub fn preset_name(kinds: Kinds) -> &'static str {
    presets()
        .into_iter()
        .find(|&(_, k)| k == kinds)
        .map_or("custom", |(name, _)| name)
}

/// `kinds` with `shape` ticked (`on`) or unticked; unticking the only kind leaves the set as it
/// was (a run needs one kind at least).
#[must_use]
pub fn toggled(kinds: Kinds, shape: Shape, on: bool) -> Kinds {
    if on {
        return kinds.with(shape);
    }
    let mut rest = kinds.shapes().filter(|&s| s != shape);
    match rest.next() {
        Some(first) => rest.fold(Kinds::only(first), Kinds::with),
        None => kinds,
    }
}

/// The kinds named by `name`: a comma list of kinds (`obb,capsule`, `mixed`, as the CLI's
/// `--bv`), or an engine's name as the CLI's `--target` takes it (`parry`, `mujoco-hull`, ...),
/// or `primitives` / `primitives-hull`.
///
/// # Errors
///
/// A one-line message naming what is accepted.
pub fn parse_kinds(name: &str) -> Result<Kinds, String> {
    let name = name.trim();
    if let Some(k) = Target::kinds_of(name) {
        return Ok(k);
    }
    match name {
        "primitives" => return Ok(Kinds::PRIMITIVES),
        "primitives-hull" => return Ok(Kinds::PRIMITIVES.with(Shape::Hull)),
        _ => {}
    }
    name.parse::<Kinds>().map_err(|e| {
        let targets: Vec<&str> = Target::ALL.iter().map(|t| t.as_str()).collect();
        format!(
            "{e}; or a target: {}, primitives (each optionally with -hull)",
            targets.join(", ")
        )
    })
}

/// A length with three significant digits.
pub fn length(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = 2 - x.abs().log10().floor() as i32;
    if (0..=6).contains(&digits) {
        format!("{x:.0$}", digits as usize)
    } else {
        format!("{x:.2e}")
    }
}

/// The size of `v` in the parts table: a short text (what fits the shape: semi-axes, half
/// extents, a radius and a half-length, a vertex count) and a longer one for its tooltip.
pub fn size_text(v: &BoundingVolume) -> (String, String) {
    let r = v.radii;
    let three = || format!("{} × {} × {}", length(r.x), length(r.y), length(r.z));
    match v.shape {
        Shape::Ellipsoid => (three(), format!("semi-axes {}", three())),
        Shape::Obb => (three(), format!("half-extents {}", three())),
        Shape::Sphere => (
            format!("r {}", length(v.radius())),
            format!("radius {}", length(v.radius())),
        ),
        Shape::Capsule | Shape::Cylinder => (
            format!("r {} · h {}", length(v.radius()), length(v.half_length())),
            format!(
                "radius {}, half-length {} (axis {:.2}, {:.2}, {:.2})",
                length(v.radius()),
                length(v.half_length()),
                v.axis().x,
                v.axis().y,
                v.axis().z
            ),
        ),
        Shape::Hull => {
            let (n, faces) = v
                .polytope()
                .map_or((0, 0), |p| (p.vertices().len(), p.triangles().len()));
            (
                format!("{n} vertices"),
                format!("convex hull: {n} vertices, {faces} triangles"),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn presets_and_ticking() {
        assert_eq!(preset_name(Kinds::PRIMITIVES), "primitives (default)");
        assert_eq!(preset_name(Kinds::default()), "primitives (default)");
        assert_eq!(preset_name(Kinds::ELLIPSOID), "paper: ellipsoid");
        assert_eq!(
            preset_name(Target::Usd.kinds().with(Shape::Hull)),
            "gltf / parry / physx / usd + hull"
        );
        assert_eq!(preset_name(Kinds::OBB), "custom");
        for t in Target::ALL {
            assert_ne!(preset_name(t.kinds()), "custom", "{}", t.as_str());
            assert_ne!(preset_name(t.kinds().with(Shape::Hull)), "custom");
        }
        let k = toggled(Kinds::MIXED, Shape::Ellipsoid, false);
        assert_eq!(k, Kinds::OBB);
        assert_eq!(toggled(k, Shape::Obb, false), Kinds::OBB, "one kind stays");
        assert_eq!(toggled(k, Shape::Ellipsoid, true), Kinds::MIXED);
        assert_eq!(toggled(k, Shape::Sphere, false), Kinds::OBB);
    }

    #[test]
    fn names_parse_as_the_cli_takes_them() {
        assert_eq!(parse_kinds("mixed"), Ok(Kinds::MIXED));
        assert_eq!(
            parse_kinds("obb,capsule"),
            Ok(Kinds::OBB.with(Shape::Capsule))
        );
        assert_eq!(parse_kinds("box"), Ok(Kinds::OBB));
        assert_eq!(parse_kinds("parry"), Ok(Target::Parry.kinds()));
        assert_eq!(
            parse_kinds("avian-hull"),
            Ok(Target::Parry.kinds().with(Shape::Hull))
        );
        assert_eq!(parse_kinds("primitives"), Ok(Kinds::PRIMITIVES));
        let e = parse_kinds("torus").unwrap_err();
        assert!(e.contains("torus") && e.contains("parry"), "{e}");
        assert!(parse_kinds("").is_err());
    }

    #[test]
    fn sizes_fit_the_shape() {
        assert_eq!(length(0.012345), "0.0123");
        assert_eq!(length(123.45), "123");
        assert_eq!(length(1.0), "1.00");
        assert_eq!(length(1.5e9), "1.50e9");
        let c = DVec3::ZERO;
        let cap = BoundingVolume::capsule(c, DVec3::Z, 2.0, 0.5);
        assert_eq!(size_text(&cap).0, "r 0.500 · h 2.00");
        assert!(size_text(&cap).1.contains("half-length 2.00"));
        let cyl = BoundingVolume::cylinder(c, DVec3::X, 1.0, 0.25);
        assert_eq!(size_text(&cyl).0, "r 0.250 · h 1.00");
        assert_eq!(size_text(&BoundingVolume::sphere(c, 3.0)).0, "r 3.00");
        let corners: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64))
            .collect();
        let hull = BoundingVolume::hull(&corners).unwrap();
        assert_eq!(size_text(&hull).0, "8 vertices");
    }
}
