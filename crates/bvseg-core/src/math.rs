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

/// The larger of `a` and `b`; the other one when either is NaN; `a` when they are equal (so a
/// tie of zeros keeps `a`'s sign). The fits' inner loops use this instead of `f64::max`, which
/// is this rule in three instructions on x86-64 but a call to libm's `fmax` in a WebAssembly
/// build (wasm's own `f64.max` propagates NaN), where those calls took 6.6 % of a run under
/// Node.js, and which settles ties of zeros the other way there and on ARM. So x86-64 takes
/// `f64::max` and every other target [`max_by_select`]: the same answers on all of them, and
/// fast. The core's `clippy.toml` keeps `f64::max` and `f64::min` out of everything else.
#[inline(always)]
#[allow(clippy::disallowed_methods)]
pub(crate) fn max(a: f64, b: f64) -> f64 {
    if cfg!(target_arch = "x86_64") {
        a.max(b)
    } else {
        max_by_select(a, b)
    }
}

/// The smaller of `a` and `b` (see [`max`]: NaN loses, a tie gives `a`).
#[inline(always)]
#[allow(clippy::disallowed_methods)]
pub(crate) fn min(a: f64, b: f64) -> f64 {
    if cfg!(target_arch = "x86_64") {
        a.min(b)
    } else {
        min_by_select(a, b)
    }
}

/// [`max`]'s rule as a compare and a select.
#[inline(always)]
fn max_by_select(a: f64, b: f64) -> f64 {
    if b > a || a.is_nan() {
        b
    } else {
        a
    }
}

/// [`min`]'s rule as a compare and a select.
#[inline(always)]
fn min_by_select(a: f64, b: f64) -> f64 {
    if b < a || a.is_nan() {
        b
    } else {
        a
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

    #[test]
    fn min_and_max_ignore_nan_and_keep_the_first_of_a_tie() {
        let mut xs = vec![0.0, -0.0, 1.0, -1.0, 2.5, f64::INFINITY, f64::NEG_INFINITY];
        let mut rng = Rng::new(11);
        xs.extend((0..200).map(|_| (rng.next_f64() - 0.5) * 1e3));
        let bits = |x: f64| x.to_bits();
        for &a in &xs {
            for &b in &xs {
                let (hi, lo) = (max(a, b), min(a, b));
                assert!(hi >= a && hi >= b && (hi == a || hi == b), "max({a}, {b})");
                assert!(lo <= a && lo <= b && (lo == a || lo == b), "min({a}, {b})");
                if a == b {
                    assert_eq!((bits(hi), bits(lo)), (bits(a), bits(a)), "tie {a}, {b}");
                }
                // On x86-64, where `max` is `f64::max`, this checks that it follows the rule.
                assert_eq!(
                    (bits(hi), bits(lo)),
                    (bits(max_by_select(a, b)), bits(min_by_select(a, b))),
                    "{a}, {b}"
                );
            }
            for (x, y) in [(a, f64::NAN), (f64::NAN, a)] {
                assert_eq!(bits(max(x, y)), bits(a), "max with NaN");
                assert_eq!(bits(min(x, y)), bits(a), "min with NaN");
            }
        }
        assert!(max(f64::NAN, f64::NAN).is_nan() && min(f64::NAN, f64::NAN).is_nan());
    }
}
