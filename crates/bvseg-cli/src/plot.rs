//! `--plot FILE.svg`: TOV and the protrusion (relative to the box diagonal) against k over the
//! refinement, with the tolerance lines, as a self-contained SVG written by hand.
use std::fmt::Write;

use bvseg_core::{Params, Segmentation};

const W: f64 = 640.0;
const H: f64 = 400.0;
const LEFT: f64 = 60.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;
const TOV_COLOR: &str = "#1f77b4";
const MOV_COLOR: &str = "#d62728";

/// The plot of `seg.history`, titled with `name`.
pub fn svg(seg: &Segmentation, params: &Params, name: &str) -> String {
    let steps = &seg.history;
    let k_max = steps.iter().map(|s| s.k).max().unwrap_or(1).max(2) as f64;
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    // The protrusion is drawn as a fraction of the box diagonal.
    let diag = seg.metrics.diagonal.max(f64::MIN_POSITIVE);
    let rel = |st: &bvseg_core::Step| st.protrusion / diag;
    let pr_tol = params.protrusion_tolerance_rel(diag);
    let mut y_max = steps
        .iter()
        .map(|s| finite(s.tov).max(finite(rel(s))))
        .fold(0.0f64, f64::max);
    if params.k.is_none() {
        y_max = y_max.max(params.tov).max(pr_tol);
    }
    let y_max = nice_ceiling(y_max.max(1e-3));
    let x = |k: f64| LEFT + (k - 1.0) / (k_max - 1.0) * (W - LEFT - RIGHT);
    let y = |v: f64| TOP + (1.0 - finite(v).min(y_max) / y_max) * (H - TOP - BOTTOM);

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{} — TOV and MOV over the refinement</text>"#,
        W / 2.0,
        escape(name)
    );
    // Axes with ticks.
    let (x0, x1, y0, y1) = (LEFT, W - RIGHT, TOP, H - BOTTOM);
    let _ = writeln!(
        s,
        r#"<path d="M{x0} {y0} V{y1} H{x1}" fill="none" stroke="black"/>"#
    );
    for i in 0..=5 {
        let v = y_max * i as f64 / 5.0;
        let yy = y(v);
        let _ = writeln!(
            s,
            r##"<line x1="{x0}" y1="{yy:.1}" x2="{x1}" y2="{yy:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            x0 - 6.0,
            yy + 4.0,
            trim(v)
        );
    }
    let k_step = ((k_max - 1.0) / 10.0).ceil().max(1.0) as usize;
    for k in (1..=k_max as usize).step_by(k_step) {
        let xx = x(k as f64);
        let _ = writeln!(
            s,
            r#"<line x1="{xx:.1}" y1="{y1}" x2="{xx:.1}" y2="{}" stroke="black"/><text x="{xx:.1}" y="{}" text-anchor="middle">{k}</text>"#,
            y1 + 5.0,
            y1 + 18.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">number of parts k</text>"#,
        (x0 + x1) / 2.0,
        H - 10.0
    );
    // Tolerance lines.
    if params.k.is_none() {
        for (v, color, label) in [
            (params.tov, TOV_COLOR, "TOV tolerance"),
            (pr_tol, MOV_COLOR, "protrusion tolerance"),
        ] {
            let yy = y(v);
            let _ = writeln!(
                s,
                r#"<line x1="{x0}" y1="{yy:.1}" x2="{x1}" y2="{yy:.1}" stroke="{color}" stroke-dasharray="6 4"/><text x="{}" y="{:.1}" text-anchor="end" fill="{color}">{label} {}</text>"#,
                x1 - 4.0,
                yy - 4.0,
                trim(v)
            );
        }
    }
    // The curves, in step order (a backtrack returns to a smaller k).
    for (pick, color, label, ly) in [
        (0, TOV_COLOR, "TOV", TOP + 4.0),
        (1, MOV_COLOR, "protrusion / diagonal", TOP + 20.0),
    ] {
        let pts: Vec<String> = steps
            .iter()
            .map(|st| {
                let v = if pick == 0 { st.tov } else { rel(st) };
                format!("{:.1},{:.1}", x(st.k as f64), y(v))
            })
            .collect();
        if !pts.is_empty() {
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"/>"#,
                pts.join(" ")
            );
            for p in &pts {
                let (px, py) = p.split_once(',').unwrap_or(("0", "0"));
                let _ = writeln!(s, r#"<circle cx="{px}" cy="{py}" r="3" fill="{color}"/>"#);
            }
        }
        let _ = writeln!(
            s,
            r#"<rect x="{}" y="{}" width="14" height="4" fill="{color}"/><text x="{}" y="{}">{label}</text>"#,
            x0 + 12.0,
            ly,
            x0 + 32.0,
            ly + 6.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// 1, 2 or 5 times a power of ten, at least `v`.
fn nice_ceiling(v: f64) -> f64 {
    let p = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&c| c >= v)
        .unwrap_or(10.0 * p)
}

fn trim(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ceilings() {
        assert_eq!(nice_ceiling(0.3), 0.5);
        assert_eq!(nice_ceiling(1.2), 2.0);
        assert_eq!(nice_ceiling(0.05), 0.05);
        assert_eq!(trim(0.5), "0.5");
    }
}
