//! Bounding volumes of arbitrary small point sets: the hull, the minimum-volume ellipsoid
//! and the box never panic and always hold every point.
#![no_main]
use bvseg_core::internals::{convex_hull, min_obb, mvee};
use glam::DVec3;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    // The first byte picks a scale, the rest are coordinates (3 x i16 per point, at most 64
    // points): exact duplicates, coplanar and collinear sets come up often.
    let scale = 10f64.powi(data[0] as i32 % 25 - 12);
    let pts: Vec<DVec3> = data[1..]
        .chunks_exact(6)
        .take(64)
        .map(|c| {
            let v = |i: usize| i16::from_le_bytes([c[i], c[i + 1]]) as f64 * scale;
            DVec3::new(v(0), v(2), v(4))
        })
        .collect();
    if pts.is_empty() {
        return;
    }
    let _ = convex_hull(&pts);
    let extent = pts.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let min_r = (extent * 1e-6).max(scale * 1e-3);
    let e = mvee(&pts, 1e-4, min_r);
    let b = min_obb(&pts, min_r);
    for v in [e, b] {
        assert!(v.radii.is_finite() && v.radii.min_element() > 0.0, "{v:?}");
        for &p in &pts {
            assert!(v.gauge(p) <= 1.0 + 1e-6, "{v:?} misses {p}");
        }
    }
});
