//! Numbers and rotations as robot files write them.
use glam::{DMat3, DQuat, DVec3};

use crate::IoError;

/// `x y z` numbers, or `default` when absent (a scale may be one number for all three).
pub(crate) fn vec3(
    s: Option<&str>,
    default: DVec3,
    what: &str,
    name: &str,
) -> Result<DVec3, IoError> {
    let Some(s) = s else { return Ok(default) };
    let v = numbers(s, what, name)?;
    match v[..] {
        [x, y, z] => Ok(DVec3::new(x, y, z)),
        [x] if what.ends_with("scale") => Ok(DVec3::splat(x)),
        _ => Err(IoError::Robot {
            name: name.to_owned(),
            message: format!("{what} {s:?}: expected 3 numbers"),
        }),
    }
}

/// Whitespace-separated finite numbers.
pub(crate) fn numbers(s: &str, what: &str, name: &str) -> Result<Vec<f64>, IoError> {
    s.split_whitespace()
        .map(|t| match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(IoError::Robot {
                name: name.to_owned(),
                message: format!("{what} {s:?}: {t:?} is not a finite number"),
            }),
        })
        .collect()
}

/// URDF's roll-pitch-yaw: about fixed X, then Y, then Z.
pub(crate) fn rpy_quat(rpy: DVec3) -> DQuat {
    DQuat::from_rotation_z(rpy.z) * DQuat::from_rotation_y(rpy.y) * DQuat::from_rotation_x(rpy.x)
}

/// The roll-pitch-yaw of a rotation matrix (the inverse of [`rpy_quat`]).
pub(crate) fn matrix_rpy(m: DMat3) -> DVec3 {
    let r = |row: usize, col: usize| m.col(col)[row];
    let sp = (-r(2, 0)).clamp(-1.0, 1.0);
    let pitch = sp.asin();
    if sp.abs() > 1.0 - 1e-12 {
        // Gimbal lock: roll and yaw turn about the same axis; put it all in yaw.
        return DVec3::new(0.0, pitch, (-r(0, 1)).atan2(r(1, 1)));
    }
    DVec3::new(r(2, 1).atan2(r(2, 2)), pitch, r(1, 0).atan2(r(0, 0)))
}

/// The rotation of a volume's axes, made proper (see [`crate::export::volume_rotation`]).
pub(crate) fn proper_axes(axes: DMat3) -> DMat3 {
    let mut axes = axes;
    if axes.determinant() < 0.0 {
        axes.z_axis = -axes.z_axis;
    }
    axes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_round_trips() {
        for rpy in [
            DVec3::new(0.1, -0.4, 2.0),
            DVec3::new(-3.0, 1.2, 0.3),
            DVec3::ZERO,
        ] {
            let m = DMat3::from_quat(rpy_quat(rpy));
            let back = DMat3::from_quat(rpy_quat(matrix_rpy(m)));
            assert!((m - back).abs().to_cols_array().iter().all(|&d| d < 1e-12));
        }
    }
}
