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
