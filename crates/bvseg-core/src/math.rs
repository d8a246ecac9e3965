//! The transcendental functions the core uses, from `libm` rather than the platform's maths
//! library. `sqrt`, `floor`, `mul_add` and the arithmetic operators are exactly rounded by
//! IEEE 754 on every target, but `ln`, `exp`, `cbrt`, `powf` and `sin_cos` come from a
//! different library on each (glibc, the wasm runtime's, a vendor's) and may differ in the
//! last bit, which a long run can turn into a different partition. With one implementation
//! everywhere, the same input, parameters and seed give byte-identical output on native and
//! wasm alike.

/// Natural logarithm.
#[inline]
pub(crate) fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// `e^x`.
#[inline]
pub(crate) fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// Cube root.
#[inline]
pub(crate) fn cbrt(x: f64) -> f64 {
    libm::cbrt(x)
}

/// `x^y`.
#[inline]
pub(crate) fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// `(sin x, cos x)`.
#[inline]
pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// `x.floor() as i64`, without the call into the maths library that `floor` is on targets
/// without SSE4.1 (x86-64's baseline): the lattice scans take it twice per column.
/// Equal to it for every `x`, NaN and infinities included.
#[inline]
pub(crate) fn floor_i64(x: f64) -> i64 {
    // Truncation toward zero saturates and sends NaN to 0, as the cast after `floor` does.
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.ceil() as i64` (see [`floor_i64`]).
#[inline]
pub(crate) fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn integer_floor_and_ceil_are_the_casts_of_floor_and_ceil() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - f64::EPSILON,
            -1.0 + f64::EPSILON,
            2f64.powi(52) + 0.5,
            2f64.powi(53),
            -(2f64.powi(53)) - 2.0,
            2f64.powi(63),
            -(2f64.powi(63)),
            -(2f64.powi(63)) - 4096.0,
            2f64.powi(63) - 1024.0,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut rng = Rng::new(7);
        for _ in 0..100_000 {
            let scale = 10f64.powi((rng.next_f64() * 20.0) as i32 - 4);
            xs.push((rng.next_f64() - 0.5) * scale);
        }
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x:e}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x:e}");
        }
    }
}
