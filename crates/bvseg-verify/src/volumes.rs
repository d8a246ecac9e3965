//! The volumes to check, and this crate's own reader of `bvseg.volumes` documents (the
//! schema of `shared/tools/README.md`), independent of `bvseg-io`'s.
use glam::DVec3;
use serde_json::{Map, Value};

use crate::VerifyError;

/// Schema 1: ellipsoids and oriented boxes.
pub const SCHEMA_V1: &str = "bvseg.volumes/1";

/// Schema 2: schema 1 plus spheres, capsules, cylinders and convex hulls (of which this
/// verifier reads the ellipsoids and boxes, and names the others in an error).
pub const SCHEMA_V2: &str = "bvseg.volumes/2";

/// Most volumes a document may list.
pub const MAX_VOLUMES: usize = 1 << 20;

/// Shapes of schema 2 that this verifier cannot check yet.
const UNSUPPORTED: [&str; 4] = ["sphere", "capsule", "cylinder", "hull"];

/// One bounding volume. `axes` are the rows of the file: orthonormal unit vectors, the
/// volume's frame; with `t_j = axes[j]·(x − center) / r_j`, x is inside an ellipsoid when
/// `Σ t_j² ≤ 1` and inside a box when `max_j |t_j| ≤ 1` (both with the schema's slack 1e-9).
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
}

impl Volume {
    /// Centre, axes (rows) and radii or half extents.
    pub(crate) fn frame(&self) -> ([f64; 3], [[f64; 3]; 3], [f64; 3]) {
        match *self {
            Self::Ellipsoid {
                center,
                axes,
                radii,
            } => (center, axes, radii),
            Self::Obb {
                center,
                axes,
                half_extents,
            } => (center, axes, half_extents),
        }
    }

    pub(crate) fn is_obb(&self) -> bool {
        matches!(self, Self::Obb { .. })
    }

    /// The shape's name in the schema.
    pub fn shape_name(&self) -> &'static str {
        match self {
            Self::Ellipsoid { .. } => "ellipsoid",
            Self::Obb { .. } => "obb",
        }
    }
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

    /// Reads a `bvseg.volumes/1` or `bvseg.volumes/2` document, checked as the schema says:
    /// `schema`, `kind` (`"ellipsoid"`, `"obb"` or `"mixed"`; schema 2 also names its other
    /// shapes) and a non-empty list of `volumes`, each with a `shape` matching the kind,
    /// `center`, `axes` (three orthonormal unit rows, `|A Aᵀ − I| ≤ 1e-6`), `radii` (> 0) and
    /// `fraction` (> 0), the fractions summing to 1 within 1e-3, every number finite. Other
    /// fields (`metrics`, `generator`, ...) are ignored.
    ///
    /// # Errors
    ///
    /// [`VerifyError::Document`] when the text is not such a document (the message names the
    /// field and the volume), [`VerifyError::UnsupportedShape`] for a schema-2 sphere,
    /// capsule, cylinder or hull.
    pub fn from_json(text: &str) -> Result<Self, VerifyError> {
        let fail = |m: String| VerifyError::Document(m);
        let doc: Value = serde_json::from_str(text)
            .map_err(|e| fail(format!("not valid JSON: {e}").replace(['\n', '\r'], " ")))?;
        let obj = doc
            .as_object()
            .ok_or_else(|| fail("the document must be a JSON object".into()))?;
        let v2 = match obj.get("schema") {
            Some(Value::String(s)) if s == SCHEMA_V1 => false,
            Some(Value::String(s)) if s == SCHEMA_V2 => true,
            other => {
                return Err(fail(format!(
                    "schema must be \"{SCHEMA_V1}\" or \"{SCHEMA_V2}\", got {}",
                    show(other)
                )))
            }
        };
        let kind = match obj.get("kind") {
            Some(Value::String(s)) if is_shape(s, v2) || s == "mixed" => s.as_str(),
            other => {
                let kinds = if v2 {
                    "\"ellipsoid\", \"obb\", \"sphere\", \"capsule\", \"cylinder\", \"hull\" or \"mixed\""
                } else {
                    "\"ellipsoid\", \"obb\" or \"mixed\""
                };
                return Err(fail(format!("kind must be {kinds}, got {}", show(other))));
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
                Some(Value::String(s)) if is_shape(s, v2) => s.as_str(),
                other => {
                    let shapes = if v2 {
                        "\"ellipsoid\", \"obb\", \"sphere\", \"capsule\", \"cylinder\" or \"hull\""
                    } else {
                        "\"ellipsoid\" or \"obb\""
                    };
                    return Err(fail(format!(
                        "volume {index}: shape must be {shapes}, got {}",
                        show(other)
                    )));
                }
            };
            if kind != "mixed" && kind != shape {
                return Err(fail(format!(
                    "volume {index}: shape \"{shape}\" in a document of kind \"{kind}\""
                )));
            }
            if UNSUPPORTED.contains(&shape) {
                return Err(VerifyError::UnsupportedShape {
                    index,
                    shape: shape.to_owned(),
                });
            }
            let (vol, fraction) =
                ellipsoid_or_obb(o, shape).map_err(|m| fail(format!("volume {index}: {m}")))?;
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

/// Whether `s` names a shape of the schema (2 when `v2`).
fn is_shape(s: &str, v2: bool) -> bool {
    s == "ellipsoid" || s == "obb" || (v2 && UNSUPPORTED.contains(&s))
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
        let (c, _, _) = v.volumes[0].frame();
        assert_eq!(c[0].to_bits(), x.to_bits());
    }

    #[test]
    fn names_the_shapes_of_schema_2_it_cannot_check() {
        let v2 = GOOD.replace("volumes/1", "volumes/2");
        for shape in ["sphere", "capsule", "cylinder", "hull"] {
            let doc = v2.replace(
                r#"{"shape":"ellipsoid","center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"radii":[1,1,1],"fraction":0.75}"#,
                &format!(r#"{{"shape":"{shape}","center":[0,0,0],"radius":1,"fraction":0.75}}"#),
            );
            let e = Volumes::from_json(&doc).unwrap_err();
            assert_eq!(
                e,
                VerifyError::UnsupportedShape {
                    index: 1,
                    shape: shape.into()
                }
            );
            assert!(e.to_string().contains(&format!("\"{shape}\"")), "{e}");
            // A document of that kind, too.
            let doc = doc.replace("\"mixed\"", &format!("\"{shape}\""));
            let e = Volumes::from_json(&doc).unwrap_err().to_string();
            assert!(
                e.contains("volume 0: shape \"obb\" in a document of kind"),
                "{e}"
            );
            // Schema 1 has no such shape.
            let doc = doc.replace("volumes/2", "volumes/1");
            let e = Volumes::from_json(&doc).unwrap_err().to_string();
            assert!(e.contains("kind must be"), "{e}");
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
