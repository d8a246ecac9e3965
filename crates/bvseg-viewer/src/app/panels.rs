//! The side panels and the menu bar: controls, refinement plot and history, statistics, parts
//! table, and the ways in and out (bundled meshes, open, save or download).
use bvseg_core::{Shape, StepKind};
use eframe::egui::{self, Color32, RichText};

use super::{Export, Status, ViewerApp};
use crate::kinds;
use crate::meshes::BUNDLED;
use crate::platform::note_widget;
use crate::scene::{self, VolumeStyle};

impl ViewerApp {
    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            let menu = ui.menu_button("Mesh", |ui| {
                for m in BUNDLED {
                    if ui.button(m.name).on_hover_text(m.about).clicked() {
                        self.load_bytes(m.file, m.bytes);
                        ui.close();
                    }
                }
                ui.separator();
                let open = ui.button("Open file…");
                note_widget("Open file…", open.rect);
                if open.clicked() {
                    self.open_file(ui.ctx());
                    ui.close();
                }
            });
            note_widget("Mesh", menu.response.rect);
            let has_result = self.result().is_some();
            let menu = ui.menu_button("Result", |ui| {
                for export in [Export::Json, Export::Glb] {
                    let label = export.menu_label();
                    let button = ui.add_enabled(has_result, egui::Button::new(label));
                    note_widget(label, button.rect);
                    if button.clicked() {
                        self.export(export);
                        ui.close();
                    }
                }
            });
            note_widget("Result", menu.response.rect);
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.label(self.status_line());
            });
        });
    }

    fn status_line(&self) -> RichText {
        if let Some(m) = &self.message {
            let colour = if matches!(self.status, Status::Failed(_)) {
                Color32::from_rgb(255, 110, 100)
            } else {
                Color32::GRAY
            };
            return RichText::new(m.as_str()).color(colour);
        }
        let t = match &self.status {
            Status::Idle => "ready: press Run".to_string(),
            Status::Running => {
                let n = self.session.as_ref().map_or(0, |s| s.snapshots().len());
                if n == 0 {
                    "sampling…".into()
                } else {
                    format!("running: step {n}")
                }
            }
            Status::Done => "done".into(),
            Status::Cancelled => "cancelled".into(),
            Status::Failed(m) => m.clone(),
        };
        RichText::new(t)
    }

    fn open_file(&mut self, ctx: &egui::Context) {
        #[cfg(target_arch = "wasm32")]
        if let Err(e) =
            crate::platform::pick_file(self.inbox.clone(), ctx.clone(), crate::meshes::SUPPORTED)
        {
            self.fail(e);
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let _ = ctx;
            self.native.open = Some(String::new());
        }
    }

    fn export_name(&self, export: Export) -> String {
        let stem = self
            .model
            .as_ref()
            .map(|m| m.name.as_str())
            .and_then(|n| std::path::Path::new(n).file_stem())
            .map_or_else(|| "bvseg".into(), |s| s.to_string_lossy().into_owned());
        format!("{stem}.volumes.{}", export.extension())
    }

    /// The file content of `export` for the current result.
    pub fn export_bytes(&mut self, export: Export) -> Option<Vec<u8>> {
        Some(match export {
            Export::Json => {
                let res = self.session.as_mut()?.result_with_hierarchy()?;
                bvseg_io::to_json_string(res).into_bytes()
            }
            Export::Glb => {
                bvseg_io::export::to_glb(self.result()?, Some(&self.model.as_ref()?.mesh))
            }
        })
    }

    /// Downloads the result (web) or asks where to save it (native).
    fn export(&mut self, export: Export) {
        #[cfg(target_arch = "wasm32")]
        if let Some(bytes) = self.export_bytes(export) {
            let name = self.export_name(export);
            if let Err(e) = crate::platform::download(&name, export.mime(), &bytes) {
                self.fail(e);
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.native.save = Some((self.export_name(export), export));
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    pub(super) fn native_dialogs(&mut self, ctx: &egui::Context) {
        if let Some(mut path) = self.native.open.take() {
            let mut keep = true;
            let mut go = false;
            egui::Window::new("Open mesh")
                .collapsible(false)
                .show(ctx, |ui| {
                    let l = ui.label(format!(
                        "Path of a mesh file ({}):",
                        crate::meshes::SUPPORTED
                    ));
                    let r = ui.text_edit_singleline(&mut path).labelled_by(l.id);
                    go = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    ui.horizontal(|ui| {
                        go |= ui.button("Open").clicked();
                        keep = !ui.button("Close").clicked();
                    });
                });
            if go {
                let p = std::path::PathBuf::from(path.trim());
                let name = p
                    .file_name()
                    .map_or_else(|| path.clone(), |n| n.to_string_lossy().into_owned());
                match std::fs::read(&p) {
                    Ok(bytes) => self.load_bytes(&name, &bytes),
                    Err(e) => self.fail(format!("{}: cannot read: {e}", p.display())),
                }
            } else if keep {
                self.native.open = Some(path);
            }
        }
        if let Some((mut path, export)) = self.native.save.take() {
            let mut keep = true;
            let mut go = false;
            egui::Window::new(export.menu_label())
                .collapsible(false)
                .show(ctx, |ui| {
                    let l = ui.label(export.what());
                    ui.text_edit_singleline(&mut path).labelled_by(l.id);
                    ui.horizontal(|ui| {
                        go = ui.button("Save").clicked();
                        keep = !ui.button("Close").clicked();
                    });
                });
            if go {
                if let Some(bytes) = self.export_bytes(export) {
                    match bvseg_io::write_atomic(path.trim(), &bytes) {
                        Ok(()) => self.message = Some(format!("wrote {}", path.trim())),
                        Err(e) => self.fail(e.to_string()),
                    }
                }
            } else if keep {
                self.native.save = Some((path, export));
            }
        }
    }

    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        let idle = self.status != Status::Running;
        ui.heading("Segmentation");
        ui.add_enabled_ui(idle, |ui| {
            ui.label("Bounding volumes");
            self.kinds_control(ui);
            ui.horizontal(|ui| {
                let s = &mut self.settings;
                for (fixed, label) in [(false, "Tolerances"), (true, "Fixed k")] {
                    let r = ui.radio_value(&mut s.fixed_k, fixed, label);
                    note_widget(label, r.rect);
                }
            });
            egui::Grid::new("params").num_columns(2).show(ui, |ui| {
                let s = &mut self.settings;
                if s.kinds.contains(Shape::Hull) {
                    labelled(
                        ui,
                        "Max hull vertices",
                        egui::Slider::new(
                            &mut s.max_hull_vertices,
                            4..=bvseg_core::MAX_HULL_VERTICES,
                        )
                        .step_by(1.0),
                    );
                }
                if s.fixed_k {
                    labelled(ui, "k", egui::DragValue::new(&mut s.k).range(1..=4096));
                } else {
                    labelled(
                        ui,
                        "σG (TOV)",
                        egui::DragValue::new(&mut s.tov)
                            .speed(0.01)
                            .range(0.0..=10.0),
                    );
                    labelled(
                        ui,
                        "Protrusion (× diagonal)",
                        egui::DragValue::new(&mut s.max_protrusion)
                            .speed(0.001)
                            .range(0.001..=1.0),
                    );
                    labelled(
                        ui,
                        "Max k",
                        egui::DragValue::new(&mut s.max_k).range(1..=4096),
                    );
                }
                labelled(
                    ui,
                    "Samples",
                    egui::DragValue::new(&mut s.samples)
                        .speed(100.0)
                        .range(100..=bvseg_core::MAX_SAMPLES),
                );
                labelled(ui, "Seed", egui::DragValue::new(&mut s.seed));
            });
        });
        ui.horizontal(|ui| {
            let run = ui.add_enabled(idle && self.model.is_some(), egui::Button::new("Run"));
            note_widget("Run", run.rect);
            if run.clicked() {
                self.run();
            }
            let cancel = ui.add_enabled(!idle, egui::Button::new("Cancel"));
            note_widget("Cancel", cancel.rect);
            if cancel.clicked() {
                self.cancel();
            }
        });
        // Above the refinement plot, which appears with a run: the controls stay in place.
        if self.player.is_some() {
            ui.separator();
            self.animation(ui);
        }
        ui.separator();
        self.history(ui);
        ui.separator();
        ui.heading("View");
        let d = &mut self.display;
        for (value, label) in [
            (&mut d.colour_by_part, "Colour mesh by part"),
            (&mut d.translucent_mesh, "Translucent mesh"),
        ] {
            let r = ui.checkbox(value, label);
            note_widget(label, r.rect);
        }
        ui.horizontal_wrapped(|ui| {
            ui.label("Volumes:");
            let d = &mut self.display;
            for (style, label) in [
                (VolumeStyle::Translucent, "Translucent"),
                (VolumeStyle::Wireframe, "Wireframe"),
                (VolumeStyle::Hidden, "Hidden"),
            ] {
                let r = ui.radio_value(&mut d.volumes, style, label);
                note_widget(label, r.rect);
            }
        });
        if ui.button("Reset view").clicked() {
            self.camera.reset();
        }
        ui.label(
            RichText::new(
                "Drag: turn · right drag or shift: pan · wheel: zoom · double click: reset",
            )
            .small()
            .weak(),
        );
    }

    /// A checkbox per kind (the only one ticked cannot be unticked) and the presets.
    fn kinds_control(&mut self, ui: &mut egui::Ui) {
        let s = &mut self.settings;
        ui.horizontal_wrapped(|ui| {
            for shape in Shape::ALL {
                let label = kinds::checkbox_label(shape);
                let mut on = s.kinds.contains(shape);
                let last = on && s.kinds.single().is_some();
                let r = ui
                    .add_enabled(!last, egui::Checkbox::new(&mut on, label))
                    .on_disabled_hover_text("A run needs one kind at least");
                note_widget(label, r.rect);
                if r.changed() {
                    s.set_kind(shape, on);
                }
            }
        });
        let current = kinds::preset_name(s.kinds);
        let combo = egui::ComboBox::from_label("Preset")
            .selected_text(current)
            .show_ui(ui, |ui| {
                for (name, k) in kinds::presets() {
                    let r = ui.selectable_label(current == name, name);
                    note_widget(name, r.rect);
                    if r.clicked() {
                        s.kinds = k;
                    }
                }
            });
        // The preset shown, for screen readers (and the tests).
        let enabled = ui.is_enabled();
        combo.response.widget_info(|| egui::WidgetInfo {
            current_text_value: Some(current.into()),
            ..egui::WidgetInfo::labeled(egui::Role::ComboBox, enabled, "Preset")
        });
        note_widget("Preset", combo.response.rect);
    }

    fn history(&mut self, ui: &mut egui::Ui) {
        ui.heading("Refinement");
        let Some(session) = &self.session else {
            ui.label(
                RichText::new("TOV and the protrusion against k appear here during a run.").weak(),
            );
            return;
        };
        let history: Vec<_> = session.snapshots().iter().map(|s| s.step).collect();
        let p = session.params();
        let tol = p.k.is_none().then_some((p.tov, p.max_protrusion));
        let shown = self.shown_step();
        let diagonal = session.diagonal();
        if let Some(i) = crate::plot::show(ui, &history, tol, diagonal, shown) {
            self.history_pos = Some(i);
        }
        let n = history.len();
        if n == 0 {
            return;
        }
        let mut pos = shown.unwrap_or(n - 1);
        ui.horizontal(|ui| {
            let label = ui.label("History step");
            let r = ui
                .add(egui::Slider::new(&mut pos, 0..=n - 1))
                .labelled_by(label.id);
            if r.changed() {
                self.history_pos = Some(pos);
            }
        });
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.history_pos.is_some(), egui::Button::new("Latest"))
                .clicked()
            {
                self.history_pos = None;
            }
            let s = history[pos];
            ui.label(format!("{} · k = {}", s.kind.as_str(), s.k));
        });
    }

    /// The animation controls of a character: which animation, play or pause, the time, the
    /// rest pose.
    fn animation(&mut self, ui: &mut egui::Ui) {
        let follow = self.volumes_follow().is_some();
        let Some(player) = self.player.as_mut() else {
            return;
        };
        ui.heading("Animation");
        let names: Vec<String> = player.clips().iter().map(|c| c.name.clone()).collect();
        if names.len() > 1 {
            let mut chosen = player.clip();
            let combo = egui::ComboBox::from_label("Animation")
                .selected_text(names[chosen].as_str())
                .show_ui(ui, |ui| {
                    for (i, name) in names.iter().enumerate() {
                        ui.selectable_value(&mut chosen, i, name.as_str());
                    }
                });
            note_widget("Animation", combo.response.rect);
            player.set_clip(chosen);
        } else {
            ui.label(names[0].as_str());
        }
        ui.horizontal(|ui| {
            let label = if player.playing() { "Pause" } else { "Play" };
            let play = ui.button(label);
            note_widget(label, play.rect);
            if play.clicked() {
                if player.playing() {
                    player.pause();
                } else {
                    player.play();
                }
            }
            let rest = ui.add_enabled(!player.at_rest(), egui::Button::new("Rest pose"));
            note_widget("Rest pose", rest.rect);
            if rest.clicked() {
                player.rest();
            }
        });
        let clip = &player.clips()[player.clip()];
        let (start, end, poses) = (clip.start(), clip.end(), clip.len());
        let mut time = player.time();
        ui.horizontal(|ui| {
            let label = ui.label("Time");
            let r = ui
                .add(egui::Slider::new(&mut time, start..=end).suffix(" s"))
                .labelled_by(label.id);
            note_widget("Time", r.rect);
            if r.changed() {
                player.set_time(time);
            }
        });
        let shown = match player.pose_in_clip() {
            None => "rest pose (as loaded)".to_string(),
            Some(i) => format!("sampled pose {} of {poses}", i + 1),
        };
        ui.label(shown);
        if !player.at_rest() && !follow {
            ui.label(
                RichText::new(
                    "The volumes follow the animation once a run is done (at its last step).",
                )
                .small()
                .weak(),
            );
        }
    }

    pub(super) fn statistics(&mut self, ui: &mut egui::Ui) {
        ui.heading("Statistics");
        let snap = self.shown_snapshot().cloned();
        let tol = self.session.as_ref().and_then(|s| {
            s.params()
                .k
                .is_none()
                .then_some((s.params().tov, s.params().max_protrusion))
        });
        let diagonal = self.session.as_ref().map_or(1.0, |s| s.diagonal());
        egui::Grid::new("stats")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let mut row = |k: &str, v: String| {
                    ui.label(k);
                    ui.label(v);
                    ui.end_row();
                };
                if let Some(m) = &self.model {
                    row("Mesh", m.name.clone());
                    row("Triangles", m.mesh.triangles().len().to_string());
                    if let Some(rig) = m.mesh.rig() {
                        let poses = rig.skin.as_ref().map_or(0, |s| s.poses.len());
                        let animations = self.player.as_ref().map_or(0, |p| p.clips().len());
                        let s = |n: usize| if n == 1 { "" } else { "s" };
                        let joints = rig.skeleton.joints.len();
                        row(
                            "Rig",
                            format!(
                                "{joints} joint{} · {animations} animation{} · {poses} pose{}",
                                s(joints),
                                s(animations),
                                s(poses)
                            ),
                        );
                    }
                }

                if let Some(s) = &self.session {
                    row("Kinds", s.params().kinds.to_string());
                    if s.samples() > 0 {
                        row("Samples", s.samples().to_string());
                    }
                    row(
                        "Time",
                        format!(
                            "{:.2} s (core {:.2} s)",
                            s.wall().as_secs_f64(),
                            s.busy().as_secs_f64()
                        ),
                    );
                }
                if let Some(snap) = &snap {
                    let st = snap.step;
                    let n = self.session.as_ref().map_or(0, |s| s.snapshots().len());
                    let i = self.shown_step().unwrap_or(0);
                    row("Step", format!("{} of {n}: {}", i + 1, st.kind.as_str()));
                    row("k", st.k.to_string());
                    row("F", format!("{:.4}", st.f));
                    let mark = |v: f64, t: Option<f64>| match t {
                        Some(t) if v < t => format!("{v:.4}  (< {t})"),
                        Some(t) => format!("{v:.4}  (≥ {t})"),
                        None => format!("{v:.4}"),
                    };
                    row("TOV", mark(st.tov, tol.map(|t| t.0)));
                    row(
                        "Protrusion",
                        mark(st.protrusion / diagonal, tol.map(|t| t.1)) + " × diagonal",
                    );
                    row("MOV", mark(st.mov, None));
                    row("Shapes", shape_counts(&snap.volumes));
                    if st.kind == StepKind::Backtrack {
                        row("", "rejected split (view: kept state)".into());
                    }
                }
            });
        for w in self.load_warnings() {
            ui.label(RichText::new(format!("Warning: {w}")).color(WARNING));
        }
        ui.separator();
        ui.heading("Parts");
        let Some(snap) = snap else {
            return;
        };
        let ov: Option<Vec<f64>> = self
            .showing_result()
            .then(|| {
                self.result()
                    .map(|r| r.parts.iter().map(|p| p.ov).collect())
            })
            .flatten();
        egui::ScrollArea::vertical().show(ui, |ui| {
            egui::Grid::new("parts")
                .num_columns(5)
                .striped(true)
                .show(ui, |ui| {
                    ui.label("");
                    ui.label("shape");
                    ui.label("size");
                    ui.label("volume");
                    ui.label("OV");
                    ui.end_row();
                    for (i, v) in snap.volumes.iter().enumerate() {
                        let c = scene::part_color(i).map(|x| (x * 255.0) as u8);
                        let selected = self.selected_part == Some(i);
                        let r = ui.selectable_label(
                            selected,
                            RichText::new(format!("Part {i}"))
                                .color(Color32::from_rgb(c[0], c[1], c[2])),
                        );
                        if r.clicked() {
                            self.selected_part = if selected { None } else { Some(i) };
                        }
                        ui.label(v.shape.as_str());
                        let (size, detail) = kinds::size_text(v);
                        ui.label(size).on_hover_text(detail);
                        let frac = snap.fractions.get(i).copied().unwrap_or(f64::NAN);
                        ui.label(format!("{:.1} %", 100.0 * frac));
                        ui.label(
                            ov.as_ref()
                                .and_then(|o| o.get(i))
                                .map_or("–".into(), |x| format!("{x:.3}")),
                        );
                        ui.end_row();
                    }
                });
        });
    }
}

/// How many volumes of each shape there are, as `2 capsule · 1 obb` (in [`Shape::ALL`]'s order).
fn shape_counts(volumes: &[bvseg_core::BoundingVolume]) -> String {
    let counts: Vec<String> = Shape::ALL
        .into_iter()
        .filter_map(|shape| {
            let n = volumes.iter().filter(|v| v.shape == shape).count();
            (n > 0).then(|| format!("{n} {}", shape.as_str()))
        })
        .collect();
    if counts.is_empty() {
        "–".into()
    } else {
        counts.join(" · ")
    }
}

/// Colour of the mesh's load warnings.
const WARNING: Color32 = Color32::from_rgb(240, 190, 80);

/// A control with a label that names it (for screen readers and the tests).
fn labelled(ui: &mut egui::Ui, label: &str, widget: impl egui::Widget) {
    let l = ui.label(label);
    ui.add(widget).labelled_by(l.id);
    ui.end_row();
}
