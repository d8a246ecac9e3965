//! The volumes to check, and this crate's own reader of `bvseg.volumes` documents (the
//! schema of `shared/tools/README.md`), independent of `bvseg-io`'s.
//!
//! Schema 1 (`bvseg.volumes/1`) has ellipsoids and oriented boxes; schema 2
//! (`bvseg.volumes/2`) adds spheres, capsules, cylinders and convex hulls. [`Volume`] tables
//! the shapes, their fields and inside tests.
use glam::DVec3;
use serde_json::{Map, Value};

use crate::hull::convex_hull;
use crate::{VerifyError, MAX_COORDINATE};

/// Schema 1: ellipsoids and oriented boxes.
pub const SCHEMA_V1: &str = "bvseg.volumes/1";

/// Schema 2: schema 1 plus spheres, capsules, cylinders and convex hulls.
pub const SCHEMA_V2: &str = "bvseg.volumes/2";

/// Most volumes a document may list.
pub const MAX_VOLUMES: usize = 1 << 20;

/// The shapes of schema 1.
const SHAPES_V1: [&str; 2] = ["ellipsoid", "obb"];

/// The shapes of schema 2.
const SHAPES_V2: [&str; 6] = ["ellipsoid", "obb", "sphere", "capsule", "cylinder", "hull"];

/// Largest deviation of a capsule's or a cylinder's `|axis|` from 1 (as of `|A Aᵀ − I|`).
const UNIT_TOLERANCE: f64 = 1e-6;

/// One bounding volume, a convex solid: the shapes of `bvseg.volumes/1` (ellipsoid, obb)
/// and `bvseg.volumes/2` (also sphere, capsule, cylinder, hull, the collider kinds that
/// physics engines take natively). In a document each volume has a `shape`, the shape's
/// fields and a `fraction`:
///
///
/// | `shape` | fields | x inside iff |
/// |---|---|---|
/// | `ellipsoid` | `center`, `axes` (orthonormal rows), `radii` > 0 | `Σ t_j² ≤ 1`, `t_j = axes[j]·(x − center) / radii[j]` |
/// | `obb` | `center`, `axes`, `radii` (half extents) > 0 | `max_j \|t_j\| ≤ 1` |
/// | `sphere` | `center`, `radius` > 0 | `\|x − center\| ≤ radius` |
/// | `capsule` | `center`, `axis` (unit), `half_length` ≥ 0, `radius` > 0 | distance from x to the segment `center ± half_length·axis` ≤ `radius` |
/// | `cylinder` | `center`, `axis` (unit), `half_length` > 0, `radius` > 0 | `\|axis·(x − center)\| ≤ half_length` and distance from x to the axis line ≤ `radius` |
/// | `hull` | `points` (at least 4 `[x, y, z]`, spanning a volume) | x in the convex hull of the points |
///
/// The inside tests allow a slack of 1e-9: on `t` (ellipsoid, box), on distance over radius
/// (sphere, capsule, cylinder: also on the axial ratio), on a hull's plane offsets over the
/// hull's size (the largest coordinate difference of a hull vertex from their mean).
///
/// `axes` are the rows of the file: orthonormal unit vectors, the volume's frame.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Volume {
    /// An ellipsoid.
    Ellipsoid {
        /// Centre.
        center: [f64; 3],
        /// Principal axes, one unit row each.
        axes: [[f64; 3]; 3],
        /// Semi-axes along `axes`.
        radii: [f64; 3],
    },
    /// An oriented box.
    Obb {
        /// Centre.
        center: [f64; 3],
        /// Edge directions, one unit row each.
        axes: [[f64; 3]; 3],
        /// Half the edge lengths along `axes` (the file's `radii`).
        half_extents: [f64; 3],
    },
    /// A ball (schema 2's `sphere`): `|x − center| ≤ radius`.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius, > 0.
        radius: f64,
    },
    /// A capsule: the points within `radius` of the segment `center ± half_length · axis`.
    Capsule {
        /// Centre (the segment's midpoint).
        center: [f64; 3],
        /// Direction of the segment, a unit vector (`|axis|` within 1e-6 of 1; the solid is
        /// about its direction).
        axis: [f64; 3],
        /// Half the segment's length, ≥ 0 (0: a ball).
        half_length: f64,
        /// Radius, > 0.
        radius: f64,
    },
    /// A cylinder with flat ends: `|axis·(x − center)| ≤ half_length` and distance from x to
    /// the axis line ≤ `radius`.
    Cylinder {
        /// Centre (the axis's midpoint).
        center: [f64; 3],
        /// Direction of the axis, a unit vector (`|axis|` within 1e-6 of 1).
        axis: [f64; 3],
        /// Half the length, > 0.
        half_length: f64,
        /// Radius, > 0.
        radius: f64,
    },
    /// The convex hull of some points (at least 4, spanning a volume); any of them may be
    /// inside the hull.
    Hull {
        /// The points, as in the file.
        points: Vec<[f64; 3]>,
    },
}

impl Volume {
    /// The shape's name in the schema.
    pub fn shape_name(&self) -> &'static str {
        match self {
            Self::Ellipsoid { .. } => "ellipsoid",
            Self::Obb { .. } => "obb",
            Self::Sphere { .. } => "sphere",
            Self::Capsule { .. } => "capsule",
            Self::Cylinder { .. } => "cylinder",
            Self::Hull { .. } => "hull",
        }
    }

    /// The checks of [`crate::verify`] on the fields: finite, within 1e100 in magnitude
    /// (coordinates, radii and lengths), radii positive, a capsule's `half_length` ≥ 0 and
    /// a cylinder's > 0, unit axes, at least 4 hull points. (Orthonormal `axes` and hulls
    /// spanning a volume are left to the reader and to the hull's construction.)
    pub(crate) fn check_values(&self) -> Result<(), String> {
        let range = "non-finite or out-of-range value";
        let ok = |x: f64| x.is_finite() && x.abs() <= MAX_COORDINATE;
        match self {
            Self::Ellipsoid {
                center,
                axes,
                radii,
            }
            | Self::Obb {
                center,
                axes,
                half_extents: radii,
            } => {
                let finite = center.iter().chain(axes.iter().flatten()).chain(radii);
                if !finite.clone().all(|x| x.is_finite())
                    || center.iter().any(|x| x.abs() > MAX_COORDINATE)
                    || radii.iter().any(|&r| r > MAX_COORDINATE)
                {
                    return Err(range.into());
                }
                if radii.iter().any(|&r| r <= 0.0) {
                    return Err("radii must be positive".into());
                }
            }
            Self::Sphere { center, radius } => {
                if !(center.iter().all(|&x| ok(x)) && ok(*radius)) {
                    return Err(range.into());
                }
                if *radius <= 0.0 {
                    return Err("radius must be positive".into());
                }
            }
            Self::Capsule {
                center,
                axis,
                half_length,
                radius,
            }
            | Self::Cylinder {
                center,
                axis,
                half_length,
                radius,
            } => {
                if !(center.iter().chain(axis).all(|&x| ok(x)) && ok(*half_length) && ok(*radius)) {
                    return Err(range.into());
                }
                check_round(*axis, *half_length, *radius, self.shape_name())?;
            }
            Self::Hull { points } => {
                if !points.iter().flatten().all(|&x| ok(x)) {
                    return Err(range.into());
                }
                if points.len() < 4 {
                    return Err(format!(
                        "a hull needs at least 4 points, got {}",
                        points.len()
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A capsule's or a cylinder's axis (unit), half length (≥ 0, a cylinder's > 0) and radius
/// (> 0), all finite.
fn check_round(axis: [f64; 3], half_length: f64, radius: f64, shape: &str) -> Result<(), String> {
    let len = DVec3::from_array(axis).length();
    if len.is_nan() || (len - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!(
            "axis must be a unit vector (|axis| = {len:.9}, more than 1e-6 from 1)"
        ));
    }
    if radius.is_nan() || radius <= 0.0 {
        return Err(format!("radius must be > 0, got {radius}"));
    }
    if shape == "cylinder" && (half_length.is_nan() || half_length <= 0.0) {
        return Err(format!("half_length must be > 0, got {half_length}"));
    }
    if half_length.is_nan() || half_length < 0.0 {
        return Err(format!("half_length must be >= 0, got {half_length}"));
    }
    Ok(())
}

/// The volumes to check, with each one's share of the solid when known.
#[derive(Debug, Clone, PartialEq)]
pub struct Volumes {
    /// The volumes, in file order.
    pub volumes: Vec<Volume>,
    /// `fraction_i = vol(S_i) / vol(S)` per volume, for the per-volume outside volumes
    /// `OV_i` and `MOV`; `None` reports only `vol(V_i \ S) / vol(S)`.
    pub fractions: Option<Vec<f64>>,
}

impl Volumes {
    /// Volumes without fractions.
    pub fn new(volumes: Vec<Volume>) -> Self {
        Self {
            volumes,
            fractions: None,
        }
    }

    /// Reads a `bvseg.volumes/1` or `bvseg.volumes/2` document, checked as the schema says
    /// (see [`Volume`] for the shapes):
    ///
    /// - `schema`: [`SCHEMA_V1`] or [`SCHEMA_V2`];
    /// - `kind`: a shape of the schema (schema 1: `"ellipsoid"`, `"obb"`; schema 2 also
    ///   `"sphere"`, `"capsule"`, `"cylinder"`, `"hull"`), `"mixed"`, or a comma-separated
    ///   list of the schema's shapes (`"ellipsoid,obb,capsule"`: the set a producer used).
    ///   Under a single shape every volume must have that shape; under `"mixed"` or a list,
    ///   any shape of the schema is accepted;
    /// - `volumes`: a non-empty list (at most [`MAX_VOLUMES`]) of objects, each with a
    ///   `shape` of the schema, that shape's fields and `fraction` (> 0), the fractions
    ///   summing to 1 within 1e-3, every number finite:
    ///   - `ellipsoid`, `obb`: `center`, `axes` (three orthonormal unit rows,
    ///     `|A Aᵀ − I| ≤ 1e-6`), `radii` (three, > 0);
    ///   - `sphere`: `center`, `radius` (> 0);
    ///   - `capsule`: `center`, `axis` (`|axis|` within 1e-6 of 1), `half_length` (≥ 0),
    ///     `radius` (> 0);
    ///   - `cylinder`: the same with `half_length` > 0;
    ///   - `hull`: `points`, at least 4 `[x, y, z]` that span a volume (not all within
    ///     1e-12 of their size from one plane, their size being the largest
    ///     coordinate difference from their mean).
    ///
    /// Other fields (`metrics`, `generator`, ...) are ignored.
    ///
    /// # Errors
    ///
    /// [`VerifyError::Document`] when the text is not such a document; the message is one
    /// line and names the field and the volume (`volume 3: radius must be > 0, got 0`).
    pub fn from_json(text: &str) -> Result<Self, VerifyError> {
        let fail = |m: String| VerifyError::Document(m);
        let doc: Value = serde_json::from_str(text)
            .map_err(|e| fail(format!("not valid JSON: {e}").replace(['\n', '\r'], " ")))?;
        let obj = doc
            .as_object()
            .ok_or_else(|| fail("the document must be a JSON object".into()))?;
        let shapes: &[&str] = match obj.get("schema") {
            Some(Value::String(s)) if s == SCHEMA_V1 => &SHAPES_V1,
            Some(Value::String(s)) if s == SCHEMA_V2 => &SHAPES_V2,
            other => {
                return Err(fail(format!(
                    "schema must be \"{SCHEMA_V1}\" or \"{SCHEMA_V2}\", got {}",
                    show(other)
                )))
            }
        };
        let names = shapes
            .iter()
            .map(|s| format!("\"{s}\""))
            .collect::<Vec<_>>()
            .join(", ");
        let (kind, only) = match obj.get("kind") {
            Some(Value::String(s)) => match parse_kind(s, shapes) {
                Some(only) => (s.as_str(), only),
                None => {
                    return Err(fail(format!(
                        "kind must be one of {names}, \"mixed\" or a comma-separated list of \
                         shapes, got {}",
                        show(obj.get("kind"))
                    )))
                }
            },
            other => {
                return Err(fail(format!(
                    "kind must be one of {names}, \"mixed\" or a comma-separated list of \
                     shapes, got {}",
                    show(other)
                )))
            }
        };
        let list = match obj.get("volumes") {
            Some(Value::Array(a)) if !a.is_empty() => a,
            _ => return Err(fail("volumes must be a non-empty list".into())),
        };
        if list.len() > MAX_VOLUMES {
            return Err(fail(format!(
                "{} volumes; at most {MAX_VOLUMES} are accepted",
                list.len()
            )));
        }
        let mut volumes = Vec::with_capacity(list.len());
        let mut fractions = Vec::with_capacity(list.len());
        for (index, v) in list.iter().enumerate() {
            let o = v
                .as_object()
                .ok_or_else(|| fail(format!("volume {index}: must be an object")))?;
            let shape = match o.get("shape") {
                Some(Value::String(s)) if shapes.contains(&s.as_str()) => s.as_str(),
                other => {
                    return Err(fail(format!(
                        "volume {index}: shape must be one of {names}, got {}",
                        show(other)
                    )));
                }
            };
            if only.is_some_and(|k| k != shape) {
                return Err(fail(format!(
                    "volume {index}: shape \"{shape}\" in a document of kind \"{kind}\""
                )));
            }
            let (vol, fraction) =
                read_volume(o, shape).map_err(|m| fail(format!("volume {index}: {m}")))?;
            volumes.push(vol);
            fractions.push(fraction);
        }
        let sum: f64 = fractions.iter().sum();
        if (sum - 1.0).abs() > 1e-3 {
            return Err(fail(format!("fractions sum to {sum}, not 1")));
        }
        Ok(Self {
            volumes,
            fractions: Some(fractions),
        })
    }
}

/// The shape every volume must have under `kind` (`Some(None)`: any of `shapes`), or `None`
/// when `kind` is not `"mixed"`, a shape or a comma-separated list of shapes.
fn parse_kind<'a>(kind: &'a str, shapes: &[&str]) -> Option<Option<&'a str>> {
    if kind == "mixed" {
        return Some(None);
    }
    let parts: Vec<&str> = kind.split(',').map(str::trim).collect();
    if !parts.iter().all(|p| shapes.contains(p)) {
        return None;
    }
    match parts[..] {
        [one] => Some(Some(one)),
        _ => Some(None),
    }
}

/// A JSON value for an error message, shortened.
fn show(v: Option<&Value>) -> String {
    match v {
        None => "nothing".into(),
        Some(v) => {
            let s = v.to_string();
            if s.len() > 40 {
                let cut = (0..=40).rev().find(|&i| s.is_char_boundary(i)).unwrap_or(0);
                format!("{}...", &s[..cut])
            } else {
                s
            }
        }
    }
}

/// A volume's fields, checked, and its fraction.
fn read_volume(o: &Map<String, Value>, shape: &str) -> Result<(Volume, f64), String> {
    if shape == "ellipsoid" || shape == "obb" {
        return ellipsoid_or_obb(o, shape);
    }
    let volume = match shape {
        "sphere" => {
            let center = vec3(o.get("center"), "center")?;
            let radius = number(o, "radius")?;
            if radius <= 0.0 {
                return Err(format!("radius must be > 0, got {radius}"));
            }
            Volume::Sphere { center, radius }
        }
        "capsule" | "cylinder" => {
            let center = vec3(o.get("center"), "center")?;
            let axis = vec3(o.get("axis"), "axis")?;
            let half_length = number(o, "half_length")?;
            let radius = number(o, "radius")?;
            check_round(axis, half_length, radius, shape)?;
            if shape == "capsule" {
                Volume::Capsule {
                    center,
                    axis,
                    half_length,
                    radius,
                }
            } else {
                Volume::Cylinder {
                    center,
                    axis,
                    half_length,
                    radius,
                }
            }
        }
        _ => {
            let list = match o.get("points") {
                None => return Err("missing field \"points\"".into()),
                Some(Value::Array(a)) if a.len() >= 4 => a,
                Some(_) => return Err("points must be a list of at least 4 [x, y, z]".into()),
            };
            let points = list
                .iter()
                .map(|p| vec3(Some(p), "points"))
                .collect::<Result<Vec<_>, _>>()?;
            let pts: Vec<DVec3> = points.iter().map(|&p| DVec3::from_array(p)).collect();
            convex_hull(&pts).map_err(|e| format!("points: {e}"))?;
            Volume::Hull { points }
        }
    };
    let fraction = number(o, "fraction")?;
    if fraction <= 0.0 {
        return Err(format!("fraction must be > 0, got {fraction}"));
    }
    Ok((volume, fraction))
}

/// A finite number.
fn number(o: &Map<String, Value>, field: &str) -> Result<f64, String> {
    let x = match o.get(field) {
        None => return Err(format!("missing field \"{field}\"")),
        Some(f) => f
            .as_f64()
            .ok_or_else(|| format!("{field} must be a number"))?,
    };
    if !x.is_finite() {
        return Err(format!("NaN or infinite value in {field}"));
    }
    Ok(x)
}

/// An ellipsoid's or a box's fields, checked, and its fraction.
fn ellipsoid_or_obb(o: &Map<String, Value>, shape: &str) -> Result<(Volume, f64), String> {
    let center = vec3(o.get("center"), "center")?;
    let axes = match o.get("axes") {
        Some(Value::Array(rows)) if rows.len() == 3 => [
            vec3(Some(&rows[0]), "axes")?,
            vec3(Some(&rows[1]), "axes")?,
            vec3(Some(&rows[2]), "axes")?,
        ],
        None => return Err("missing field \"axes\"".into()),
        _ => return Err("axes must be three rows of three numbers".into()),
    };
    let radii = vec3(o.get("radii"), "radii")?;
    let fraction = match o.get("fraction") {
        None => return Err("missing field \"fraction\"".into()),
        Some(f) => f.as_f64().ok_or("fraction must be a number")?,
    };
    if !fraction.is_finite() {
        return Err("NaN or infinite value".into());
    }
    if radii.iter().any(|&r| r <= 0.0) {
        return Err(format!("radii must be > 0, got {radii:?}"));
    }
    let mut dev = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot = DVec3::from_array(axes[i]).dot(DVec3::from_array(axes[j]));
            let want = if i == j { 1.0 } else { 0.0 };
            dev = dev.max((dot - want).abs());
        }
    }
    if dev.is_nan() || dev > 1e-6 {
        return Err(format!(
            "axes are not orthonormal unit rows (|A A^T - I| = {dev:.3e})"
        ));
    }
    if fraction <= 0.0 {
        return Err(format!("fraction must be > 0, got {fraction}"));
    }
    let volume = if shape == "obb" {
        Volume::Obb {
            center,
            axes,
            half_extents: radii,
        }
    } else {
        Volume::Ellipsoid {
            center,
            axes,
            radii,
        }
    };
    Ok((volume, fraction))
}

/// Three finite numbers.
fn vec3(v: Option<&Value>, field: &str) -> Result<[f64; 3], String> {
    let a = match v {
        None => return Err(format!("missing field \"{field}\"")),
        Some(Value::Array(a)) if a.len() == 3 => a,
        Some(_) => return Err(format!("{field} must hold three numbers")),
    };
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x
            .as_f64()
            .ok_or_else(|| format!("{field} must hold three numbers"))?;
        if !o.is_finite() {
            return Err("NaN or infinite value".into());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"{"schema":"bvseg.volumes/1","kind":"mixed",
        "metrics":{"k":2,"tov":0.25,"mov":0.5,"samples":100},
        "volumes":[
        {"shape":"obb","center":[1,2,3],"axes":[[0,1,0],[-1,0,0],[0,0,1]],"radii":[1,2,3],"fraction":0.25},
        {"shape":"ellipsoid","center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"radii":[1,1,1],"fraction":0.75}]}"#;

    #[test]
    fn reads_a_good_document() {
        let v = Volumes::from_json(GOOD).unwrap();
        assert_eq!(v.fractions, Some(vec![0.25, 0.75]));
        assert_eq!(
            v.volumes,
            vec![
                Volume::Obb {
                    center: [1.0, 2.0, 3.0],
                    axes: [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
                    half_extents: [1.0, 2.0, 3.0],
                },
                Volume::Ellipsoid {
                    center: [0.0; 3],
                    axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                    radii: [1.0; 3],
                },
            ]
        );
        assert_eq!(v.volumes[0].shape_name(), "obb");
        // Schema 2 with only ellipsoids and boxes reads the same.
        let v2 = Volumes::from_json(&GOOD.replace("volumes/1", "volumes/2")).unwrap();
        assert_eq!(v2, v);
    }

    #[test]
    fn numbers_read_back_bit_for_bit() {
        let x = 0.1f64 + 0.2;
        let doc = GOOD.replace("[1,2,3],\"axes\"", &format!("[{x},2,3],\"axes\""));
        let v = Volumes::from_json(&doc).unwrap();
        let Volume::Obb { center, .. } = v.volumes[0] else {
            panic!("{:?}", v.volumes[0])
        };
        assert_eq!(center[0].to_bits(), x.to_bits());
    }

    /// A schema-2 document of one volume `body` (the fields after `"shape"`), of `kind`.
    fn doc2(kind: &str, shape: &str, body: &str) -> String {
        format!(
            r#"{{"schema":"bvseg.volumes/2","kind":"{kind}","volumes":[{{"shape":"{shape}",{body},"fraction":1}}]}}"#
        )
    }

    const SPHERE: &str = r#""center":[1,2,3],"radius":0.5"#;
    const CAPSULE: &str = r#""center":[1,2,3],"axis":[0,0.6,0.8],"half_length":2,"radius":0.5"#;
    const HULL: &str = r#""points":[[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0.1,0.1,0.1]]"#;

    #[test]
    fn reads_every_shape_of_schema_2() {
        let one = |shape: &str, body: &str| {
            let v = Volumes::from_json(&doc2(shape, shape, body)).unwrap();
            assert_eq!(v.fractions, Some(vec![1.0]));
            assert_eq!(v.volumes[0].shape_name(), shape);
            // Under "mixed" too.
            assert_eq!(Volumes::from_json(&doc2("mixed", shape, body)).unwrap(), v);
            v.volumes[0].clone()
        };
        assert_eq!(
            one("sphere", SPHERE),
            Volume::Sphere {
                center: [1.0, 2.0, 3.0],
                radius: 0.5
            }
        );
        assert_eq!(
            one("capsule", CAPSULE),
            Volume::Capsule {
                center: [1.0, 2.0, 3.0],
                axis: [0.0, 0.6, 0.8],
                half_length: 2.0,
                radius: 0.5
            }
        );
        assert_eq!(
            one("cylinder", CAPSULE),
            Volume::Cylinder {
                center: [1.0, 2.0, 3.0],
                axis: [0.0, 0.6, 0.8],
                half_length: 2.0,
                radius: 0.5
            }
        );
        // A capsule of length 0 is a ball; an axis within 1e-6 of unit length is accepted.
        let ball = CAPSULE
            .replace("\"half_length\":2", "\"half_length\":0")
            .replace("0.8]", "0.8000004]");
        assert!(matches!(
            one("capsule", &ball),
            Volume::Capsule {
                half_length: 0.0,
                ..
            }
        ));
        let Volume::Hull { points } = one("hull", HULL) else {
            unreachable!()
        };
        assert_eq!(points.len(), 5);
        assert_eq!(points[4], [0.1, 0.1, 0.1]);
    }

    #[test]
    fn kinds_are_a_shape_mixed_or_a_list() {
        let mut vols = String::new();
        for (shape, body) in [("sphere", SPHERE), ("capsule", CAPSULE), ("hull", HULL)] {
            vols += &format!(r#"{{"shape":"{shape}",{body},"fraction":0.25}},"#);
        }
        vols += r#"{"shape":"obb","center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"radii":[1,1,1],"fraction":0.25}"#;
        let doc = |kind: &str, schema: u8| {
            format!(r#"{{"schema":"bvseg.volumes/{schema}","kind":"{kind}","volumes":[{vols}]}}"#)
        };
        let v = Volumes::from_json(&doc("mixed", 2)).unwrap();
        let names: Vec<&str> = v.volumes.iter().map(Volume::shape_name).collect();
        assert_eq!(names, ["sphere", "capsule", "hull", "obb"]);
        // The set of kinds a producer used, with or without spaces: anything goes.
        for kind in [
            "sphere,capsule,hull,obb",
            "ellipsoid, obb ,capsule",
            "obb,obb",
        ] {
            assert_eq!(Volumes::from_json(&doc(kind, 2)).unwrap(), v, "{kind}");
        }
        // A single shape must be every volume's.
        let e = Volumes::from_json(&doc("sphere", 2))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("volume 1: shape \"capsule\" in a document of kind \"sphere\""),
            "{e}"
        );
        let e = Volumes::from_json(&doc(" sphere ", 2))
            .unwrap_err()
            .to_string();
        assert!(e.contains("volume 1: shape \"capsule\""), "{e}");
        for kind in [
            "torus",
            "sphere,torus",
            "ellipsoid,",
            "",
            "mixed,obb",
            "Sphere",
        ] {
            let e = Volumes::from_json(&doc(kind, 2)).unwrap_err().to_string();
            assert!(e.contains("kind must be one of"), "{kind}: {e}");
        }
        // Schema 1 knows only ellipsoids and boxes, in its kind and its shapes.
        for kind in ["sphere", "obb,sphere"] {
            let e = Volumes::from_json(&doc(kind, 1)).unwrap_err().to_string();
            assert!(
                e.contains("kind must be one of \"ellipsoid\", \"obb\","),
                "{e}"
            );
        }
        let e = Volumes::from_json(&doc("ellipsoid,obb", 1)).unwrap_err();
        assert!(
            e.to_string().contains("volume 0: shape must be one of"),
            "{e}"
        );
    }

    #[test]
    fn unknown_shapes_are_refused_as_documents() {
        for schema in ["bvseg.volumes/1", "bvseg.volumes/2"] {
            let doc = GOOD
                .replace("bvseg.volumes/1", schema)
                .replace("\"obb\",\"center\"", "\"torus\",\"center\"");
            let e = Volumes::from_json(&doc).unwrap_err();
            assert!(matches!(e, VerifyError::Document(_)), "{e:?}");
            assert!(
                e.to_string()
                    .contains("volume 0: shape must be one of \"ellipsoid\", \"obb\""),
                "{e}"
            );
            assert!(e.to_string().ends_with("got \"torus\""), "{e}");
        }
    }

    #[test]
    fn rejects_each_malformed_field_of_schema_2() {
        let hull = |pts: &str| format!(r#""points":{pts}"#);
        let cases: Vec<(&str, String, &str)> = vec![
            (
                "sphere",
                SPHERE.replace("0.5", "0"),
                "volume 0: radius must be > 0, got 0",
            ),
            ("sphere", SPHERE.replace("0.5", "-1"), "radius must be > 0"),
            (
                "sphere",
                SPHERE.replace("0.5", "\"r\""),
                "radius must be a number",
            ),
            ("sphere", SPHERE.replace("0.5", "1e999"), "out of range"),
            (
                "sphere",
                SPHERE.replace(",\"radius\":0.5", ""),
                "missing field \"radius\"",
            ),
            (
                "sphere",
                SPHERE.replace("[1,2,3]", "[1,2]"),
                "center must hold three",
            ),
            (
                "sphere",
                SPHERE.replace("\"center\"", "\"centre\""),
                "missing field \"center\"",
            ),
            (
                "capsule",
                CAPSULE.replace("0.8]", "0.81]"),
                "axis must be a unit vector",
            ),
            (
                "capsule",
                CAPSULE.replace("[0,0.6,0.8]", "[0,0,0]"),
                "axis must be a unit",
            ),
            (
                "capsule",
                CAPSULE.replace("[0,0.6,0.8]", "[0,1]"),
                "axis must hold three",
            ),
            (
                "capsule",
                CAPSULE.replace("\"axis\"", "\"axes\""),
                "missing field \"axis\"",
            ),
            (
                "capsule",
                CAPSULE.replace(":2,", ":-1,"),
                "half_length must be >= 0, got -1",
            ),
            (
                "capsule",
                CAPSULE.replace(":2,", ":[2],"),
                "half_length must be a number",
            ),
            (
                "capsule",
                CAPSULE.replace("\"half_length\"", "\"h\""),
                "missing field \"half_length\"",
            ),
            ("capsule", CAPSULE.replace("0.5", "0"), "radius must be > 0"),
            (
                "cylinder",
                CAPSULE.replace(":2,", ":0,"),
                "half_length must be > 0, got 0",
            ),
            (
                "cylinder",
                CAPSULE.replace("0.5", "-0.5"),
                "radius must be > 0",
            ),
            (
                "cylinder",
                CAPSULE.replace("[0,0.6,0.8]", "[0,0,2]"),
                "|axis| = 2.000000000",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,0,0],[0,1,0]]"),
                "points must be a list of at least 4",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,0,0],[0,1,0],[0,0]]"),
                "points must hold three",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,0,0],[0,1,0],[0,0,\"z\"]]"),
                "points must hold three",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,0,0],[0,1,0],[1,1,0]]"),
                "volume 0: points: the points span no volume",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,1,1],[2,2,2],[3,3,3],[4,4,4]]"),
                "span no volume",
            ),
            (
                "hull",
                hull("[[1,2,3],[1,2,3],[1,2,3],[1,2,3]]"),
                "span no volume",
            ),
            (
                "hull",
                hull("[[0,0,0],[1,0,0],[0,1,0],[1,1,1e-14]]"),
                "span no volume",
            ),
            ("hull", hull("{\"a\":1}"), "points must be a list"),
            ("hull", "\"vertices\":[]".into(), "missing field \"points\""),
        ];
        for (shape, body, want) in &cases {
            let doc = doc2(shape, shape, body);
            let e = Volumes::from_json(&doc).unwrap_err();
            assert!(matches!(e, VerifyError::Document(_)), "{doc}: {e:?}");
            let e = e.to_string();
            assert!(e.contains(want), "{doc}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        // The fraction, for each shape.
        for (shape, body) in [
            ("sphere", SPHERE),
            ("capsule", CAPSULE),
            ("cylinder", CAPSULE),
            ("hull", HULL),
        ] {
            let good = doc2(shape, shape, body);
            for (from, to, want) in [
                (
                    "\"fraction\":1",
                    "\"fraction\":0",
                    "volume 0: fraction must be > 0",
                ),
                (
                    "\"fraction\":1",
                    "\"fraction\":\"1\"",
                    "fraction must be a number",
                ),
                (",\"fraction\":1", "", "missing field \"fraction\""),
                ("\"fraction\":1", "\"fraction\":0.5", "fractions sum to 0.5"),
            ] {
                let e = Volumes::from_json(&good.replace(from, to)).unwrap_err();
                assert!(e.to_string().contains(want), "{shape}: {e}");
            }
        }
    }

    #[test]
    fn rejects_bad_documents_with_one_line() {
        let cases = [
            ("", "not valid JSON"),
            ("[]", "JSON object"),
            (r#"{"schema":"bvseg.volumes/0"}"#, "schema"),
            (&GOOD.replace("\"mixed\"", "\"sphere\""), "kind"),
            (&GOOD.replace("\"mixed\"", "\"obb\""), "volume 1: shape"),
            (
                &GOOD.replace("\"obb\",\"center\"", "\"ball\",\"center\""),
                "volume 0: shape",
            ),
            (
                &GOOD.replace("[1,2,3],\"axes\"", "[1,2],\"axes\""),
                "center",
            ),
            (
                &GOOD.replace("[1,2,3],\"fraction\"", "[1,0,3],\"fraction\""),
                "radii",
            ),
            (&GOOD.replace("[0,1,0],[-1", "[0,1.1,0],[-1"), "orthonormal"),
            (
                &GOOD.replace("[[0,1,0],[-1,0,0],", "[[0,1,0],"),
                "axes must be",
            ),
            (&GOOD.replace("0.25}", "0.5}"), "sum"),
            (&GOOD.replace("0.25}", "-0.25}"), "fraction must be > 0"),
            (
                &GOOD.replace("0.25}", "\"a\"}"),
                "fraction must be a number",
            ),
            (
                &GOOD.replace("[1,2,3],\"axes\"", "[1e999,2,3],\"axes\""),
                "out of range",
            ),
            (
                &GOOD.replace("\"fraction\":0.25", "\"fractio\":0.25"),
                "missing",
            ),
            (
                r#"{"schema":"bvseg.volumes/1","kind":"obb","volumes":[]}"#,
                "non-empty",
            ),
            (
                r#"{"schema":"bvseg.volumes/1","kind":"obb","volumes":[3]}"#,
                "volume 0: must be an object",
            ),
        ];
        for (doc, want) in cases {
            let e = Volumes::from_json(doc).unwrap_err();
            assert!(matches!(e, VerifyError::Document(_)), "{doc}: {e:?}");
            let e = e.to_string();
            assert!(
                e.starts_with("invalid volumes document: ") && e.contains(want),
                "{doc}: {e}"
            );
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let doc = "[".repeat(100_000);
        assert!(Volumes::from_json(&doc).is_err());
    }
}
