//! MJCF frames as MuJoCo compiles them: `pos` and one of `quat`, `axisangle`, `euler` (in the
//! compiler's `eulerseq`), `xyaxes`, `zaxis`, with angles in the compiler's unit.
use glam::{DAffine3, DMat3, DQuat, DVec3};

use crate::robot::geometry::{numbers, vec3};
use crate::IoError;

/// The attributes that orient an element.
pub(crate) const ORIENTATIONS: [&str; 5] = ["quat", "axisangle", "euler", "xyaxes", "zaxis"];

/// How a file writes angles (its `<compiler angle eulerseq>`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Angles {
    /// `angle="degree"` (MuJoCo's default), else radians.
    pub(crate) degrees: bool,
    /// The `eulerseq`: lower case for axes that turn with the frame, upper for fixed ones.
    pub(crate) eulerseq: [u8; 3],
}

/// A compiler `eulerseq`: three axes, lower case for axes that turn with the frame
/// (intrinsic), upper case for fixed ones (extrinsic).
pub(crate) fn euler_sequence(s: &str) -> Option<[u8; 3]> {
    match s.as_bytes() {
        &[a, b, c] if [a, b, c].iter().all(|x| b"xyzXYZ".contains(x)) => Some([a, b, c]),
        _ => None,
    }
}

impl Angles {
    /// An angle of the file in radians.
    pub(crate) fn radians(&self, x: f64) -> f64 {
        if self.degrees {
            x.to_radians()
        } else {
            x
        }
    }

    /// The frame of an element whose attributes `get` returns: its `pos` and orientation.
    pub(crate) fn frame<'a>(
        &self,
        get: impl Fn(&str) -> Option<&'a str>,
        name: &str,
    ) -> Result<DAffine3, IoError> {
        let pos = vec3(get("pos"), DVec3::ZERO, "pos", name)?;
        Ok(DAffine3::from_rotation_translation(
            self.orientation(get, name)?,
            pos,
        ))
    }

    /// The rotation of an element whose attributes `get` returns (identity without any).
    pub(crate) fn orientation<'a>(
        &self,
        get: impl Fn(&str) -> Option<&'a str>,
        name: &str,
    ) -> Result<DQuat, IoError> {
        let bad = |message: String| IoError::Robot {
            name: name.to_owned(),
            message,
        };
        let unit = |v: DVec3, what: &str| {
            let n = v.normalize_or_zero();
            if n == DVec3::ZERO {
                Err(bad(format!("{what}: a zero vector")))
            } else {
                Ok(n)
            }
        };
        if let Some(q) = get("quat") {
            return match numbers(q, "quat", name)?[..] {
                [w, x, y, z] if (w, x, y, z) != (0.0, 0.0, 0.0, 0.0) => {
                    Ok(DQuat::from_xyzw(x, y, z, w).normalize())
                }
                _ => Err(bad(format!("quat {q:?}: expected 4 numbers, not all 0"))),
            };
        }
        if let Some(aa) = get("axisangle") {
            return match numbers(aa, "axisangle", name)?[..] {
                [x, y, z, a] => Ok(DQuat::from_axis_angle(
                    unit(DVec3::new(x, y, z), "axisangle")?,
                    self.radians(a),
                )),
                _ => Err(bad(format!("axisangle {aa:?}: expected 4 numbers"))),
            };
        }
        if let Some(e) = get("euler") {
            let v = vec3(Some(e), DVec3::ZERO, "euler", name)?;
            let mut q = DQuat::IDENTITY;
            for (i, &c) in self.eulerseq.iter().enumerate() {
                let axis = match c.to_ascii_lowercase() {
                    b'x' => DVec3::X,
                    b'y' => DVec3::Y,
                    _ => DVec3::Z,
                };
                let r = DQuat::from_axis_angle(axis, self.radians(v[i]));
                // Lower case: about the turned frame's axis (intrinsic), upper: the fixed one.
                q = if c.is_ascii_lowercase() { q * r } else { r * q };
            }
            return Ok(q);
        }
        if let Some(xy) = get("xyaxes") {
            return match numbers(xy, "xyaxes", name)?[..] {
                [a, b, c, d, e, f] => {
                    let x = unit(DVec3::new(a, b, c), "xyaxes")?;
                    let y = DVec3::new(d, e, f);
                    let y = unit(y - x * x.dot(y), "xyaxes")?;
                    Ok(DQuat::from_mat3(&DMat3::from_cols(x, y, x.cross(y))).normalize())
                }
                _ => Err(bad(format!("xyaxes {xy:?}: expected 6 numbers"))),
            };
        }
        if let Some(z) = get("zaxis") {
            let z = unit(vec3(Some(z), DVec3::Z, "zaxis", name)?, "zaxis")?;
            return Ok(z_to(z));
        }
        Ok(DQuat::IDENTITY)
    }
}

/// The rotation that turns Z to the unit vector `v` about their common normal, as MuJoCo
/// makes it for `zaxis` and `fromto` (for `v = -Z`: half a turn about X), so that the frame's
/// X and Y axes are MuJoCo's too.
pub(crate) fn z_to(v: DVec3) -> DQuat {
    let axis = DVec3::Z.cross(v);
    let s = axis.length();
    if s < 1e-14 {
        return if v.z < 0.0 {
            DQuat::from_xyzw(1.0, 0.0, 0.0, 0.0)
        } else {
            DQuat::IDENTITY
        };
    }
    DQuat::from_axis_angle(axis / s, s.atan2(v.z))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    /// The body quaternions MuJoCo 4.0.0 compiles (`MjModel.body_quat`, w x y z) for
    /// `euler="10 20 30"` in degrees under each `eulerseq`, and for the other orientations.
    #[test]
    fn orientations_are_mujocos() {
        let eulers = [
            (
                "xyz",
                [
                    0.943_714_364_147_489,
                    0.127_679_440_695_780_63,
                    0.144_878_125_417_369_14,
                    0.268_535_822_751_569_2,
                ],
            ),
            (
                "zyx",
                [
                    0.951_548_524_643_788_5,
                    0.239_298_337_744_730_3,
                    0.189_307_857_412,
                    0.038_134_576_474_850_15,
                ],
            ),
            (
                "XYZ",
                [
                    0.951_548_524_643_788_5,
                    0.038_134_576_474_850_15,
                    0.189_307_857_412,
                    0.239_298_337_744_730_3,
                ],
            ),
            (
                "zYx",
                [
                    0.943_714_364_147_489,
                    0.268_535_822_751_569_2,
                    0.189_307_857_412,
                    0.038_134_576_474_850_15,
                ],
            ),
        ];
        let others = [
            (
                r#"xyaxes="0 1 0 -1 0 0""#,
                [FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2],
            ),
            (
                r#"zaxis="0 1 1""#,
                [0.923_879_532_511_286_7, -0.382_683_432_365_089_8, 0.0, 0.0],
            ),
            (
                r#"axisangle="0 1 0 20""#,
                [0.984_807_753_012_208, 0.0, 0.173_648_177_666_930_33, 0.0],
            ),
            (r#"zaxis="0 0 -1""#, [0.0, 1.0, 0.0, 0.0]),
        ];
        let cases = eulers
            .iter()
            .map(|(seq, q)| (*seq, r#"euler="10 20 30""#.to_owned(), *q))
            .chain(others.iter().map(|(a, q)| ("xyz", (*a).to_owned(), *q)));
        for (seq, attr, [w, x, y, z]) in cases {
            let xml = format!("<body {attr}/>");
            let doc = roxmltree::Document::parse(&xml).unwrap();
            let angles = Angles {
                degrees: true,
                eulerseq: euler_sequence(seq).unwrap(),
            };
            let node = doc.root_element();
            let q = angles.orientation(|a| node.attribute(a), "t.xml").unwrap();
            let want = DQuat::from_xyzw(x, y, z, w);
            // The same rotation: q and -q are one.
            let d = (q - want).length().min((q + want).length());
            assert!(d < 1e-12, "{seq} {attr}: {q} != {want}");
        }
        assert!(euler_sequence("xyw").is_none() && euler_sequence("xy").is_none());
    }
}
