//! A small plot of TOV and the protrusion (as a fraction of the box diagonal) against k over
//! the refinement history, drawn with egui's
//! painter (a plotting crate would be a large dependency for two polylines).
use bvseg_core::{Step, StepKind};
use eframe::egui::{self, Color32, Pos2, Rect, Sense, Shape, Stroke, Vec2};

/// Colour of the TOV curve.
pub const TOV_COLOR: Color32 = Color32::from_rgb(90, 160, 255);
/// Colour of the protrusion curve.
pub const PROTRUSION_COLOR: Color32 = Color32::from_rgb(255, 150, 60);

/// The value a curve plots for a step.
type Curve<'a> = &'a dyn Fn(&Step) -> f64;

/// The protrusion of `s` as a fraction of the box diagonal `diagonal`.
fn protrusion_rel(s: &Step, diagonal: f64) -> f64 {
    s.protrusion / diagonal.max(f64::MIN_POSITIVE)
}

/// The plot's data range: `(k_min, k_max, y_max)`; `tolerances` are TOV's and the
/// protrusion's (relative to `diagonal`).
pub fn ranges(history: &[Step], tolerances: Option<(f64, f64)>, diagonal: f64) -> (f64, f64, f64) {
    // Every run starts at k >= 1; the axis starts there so runs compare at a glance.
    let k_min = 1.0;
    let k_max = history.iter().map(|s| s.k as f64).fold(2.0, f64::max);
    let tol = tolerances.map_or(0.0, |(t, m)| t.max(m));
    let y_max = history
        .iter()
        .flat_map(|s| [s.tov, protrusion_rel(s, diagonal)])
        .filter(|v| v.is_finite())
        .fold(tol, f64::max);
    (k_min, k_max, (y_max * 1.1).max(0.1))
}

/// Draws the plot in the available width; `selected` is the step shown in the view. Returns
/// the step the user clicked, if any.
pub fn show(
    ui: &mut egui::Ui,
    history: &[Step],
    tolerances: Option<(f64, f64)>,
    diagonal: f64,
    selected: Option<usize>,
) -> Option<usize> {
    let size = Vec2::new(ui.available_width().max(120.0), 130.0);
    let (rect, response) = ui.allocate_exact_size(size, Sense::click());
    let painter = ui.painter_at(rect);
    let visuals = ui.visuals();
    painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
    let area = Rect::from_min_max(
        rect.min + Vec2::new(30.0, 6.0),
        rect.max - Vec2::new(6.0, 18.0),
    );
    let (k_min, k_max, y_max) = ranges(history, tolerances, diagonal);
    let to_screen = |k: f64, y: f64| {
        let x = area.left() + ((k - k_min) / (k_max - k_min)) as f32 * area.width();
        let y = area.bottom() - (y.clamp(0.0, y_max) / y_max) as f32 * area.height();
        Pos2::new(x, y)
    };
    let text = visuals.weak_text_color();
    let font = egui::FontId::proportional(10.0);
    painter.line_segment(
        [area.left_bottom(), area.right_bottom()],
        Stroke::new(1.0, text),
    );
    painter.line_segment(
        [area.left_top(), area.left_bottom()],
        Stroke::new(1.0, text),
    );
    for y in [0.0, y_max / 2.0, y_max / 1.1] {
        let p = to_screen(k_min, y);
        painter.text(
            p - Vec2::new(3.0, 0.0),
            egui::Align2::RIGHT_CENTER,
            format!("{y:.2}"),
            font.clone(),
            text,
        );
    }
    for k in [k_min, k_max] {
        painter.text(
            to_screen(k, 0.0) + Vec2::new(0.0, 2.0),
            egui::Align2::CENTER_TOP,
            format!("{k:.0}"),
            font.clone(),
            text,
        );
    }
    painter.text(
        area.center_bottom() + Vec2::new(0.0, 2.0),
        egui::Align2::CENTER_TOP,
        "k",
        font.clone(),
        text,
    );
    if let Some((t, m)) = tolerances {
        for (v, c) in [(t, TOV_COLOR), (m, PROTRUSION_COLOR)] {
            let (a, b) = (to_screen(k_min, v), to_screen(k_max, v));
            painter.extend(Shape::dashed_line(
                &[a, b],
                Stroke::new(1.0, c.gamma_multiply(0.6)),
                4.0,
                3.0,
            ));
        }
    }
    if let Some(s) = selected.and_then(|i| history.get(i)) {
        let x = to_screen(s.k as f64, 0.0).x;
        painter.line_segment(
            [Pos2::new(x, area.top()), Pos2::new(x, area.bottom())],
            Stroke::new(1.0, visuals.text_color().gamma_multiply(0.5)),
        );
    }
    let tov = |s: &Step| s.tov;
    let protrusion = |s: &Step| protrusion_rel(s, diagonal);
    let curves: [(Curve, Color32); 2] = [(&tov, TOV_COLOR), (&protrusion, PROTRUSION_COLOR)];
    for (value, colour) in curves {
        // Backtracks are rejected candidates: dots, not part of the path.
        let path: Vec<Pos2> = history
            .iter()
            .filter(|s| s.kind != StepKind::Backtrack && value(s).is_finite())
            .map(|s| to_screen(s.k as f64, value(s)))
            .collect();
        painter.add(Shape::line(path, Stroke::new(1.5, colour)));
        for (i, s) in history.iter().enumerate() {
            if !value(s).is_finite() {
                continue;
            }
            let p = to_screen(s.k as f64, value(s));
            if s.kind == StepKind::Backtrack {
                painter.circle_stroke(p, 2.0, Stroke::new(1.0, colour.gamma_multiply(0.6)));
            } else if Some(i) == selected {
                painter.circle_filled(p, 3.5, colour);
            }
        }
    }
    painter.text(
        area.right_top() + Vec2::new(-2.0, 2.0),
        egui::Align2::RIGHT_TOP,
        "TOV",
        font.clone(),
        TOV_COLOR,
    );
    painter.text(
        area.right_top() + Vec2::new(-2.0, 14.0),
        egui::Align2::RIGHT_TOP,
        "protrusion / diagonal",
        font,
        PROTRUSION_COLOR,
    );
    // A click picks the last step at the clicked k.
    let pos = response
        .interact_pointer_pos()
        .filter(|_| response.clicked())?;
    let k = k_min + ((pos.x - area.left()) / area.width()) as f64 * (k_max - k_min);
    history
        .iter()
        .enumerate()
        .min_by(|(i, a), (j, b)| {
            let da = (a.k as f64 - k).abs();
            let db = (b.k as f64 - k).abs();
            da.total_cmp(&db).then(j.cmp(i))
        })
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(k: usize, tov: f64, protrusion: f64) -> Step {
        Step {
            kind: StepKind::Split,
            k,
            f: 1.0,
            tov,
            mov: 0.0,
            protrusion,
        }
    }

    #[test]
    fn ranges_cover_the_data_and_the_tolerances() {
        // Diagonal 2: a protrusion of 1.8 is 0.9 of it.
        let h = [step(1, 0.5, 1.8), step(5, 0.2, f64::NAN)];
        let (a, b, y) = ranges(&h, Some((0.3, 0.05)), 2.0);
        assert_eq!((a, b), (1.0, 5.0));
        assert!((y - 0.99).abs() < 1e-12);
        let (_, b, y) = ranges(&[], None, 1.0);
        assert!(b > 1.0 && y > 0.0, "an empty plot still has a range");
    }
}
