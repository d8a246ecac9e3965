//! The viewer app: controls on the left, the 3D view in the middle, statistics and parts on
//! the right. Each frame advances the running [`Session`] by a time budget, then draws.
use std::sync::{Arc, Mutex};

use bvseg_core::{BoundingKind, Mesh, Params, Segmentation, StepKind};
use eframe::egui::{self, Color32, RichText};
use eframe::{egui_glow, glow};
use web_time::Duration;

use crate::camera::OrbitCamera;
use crate::meshes::{self, BUNDLED};
use crate::platform::{Inbox, Report, Reporter};
use crate::render::{Frame, Renderer};
use crate::scene::{self, Display, Geometry, MeshGeometry, VolumeStyle};
use crate::session::{Progress, Session, Snapshot};

/// Core time per frame while a run is going: long enough that the run is not slowed much by
/// drawing, short enough that the UI stays responsive. A single core step may take longer.
pub const FRAME_BUDGET: Duration = Duration::from_millis(40);

/// The controls of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Bounding-volume kind.
    pub bounding: BoundingKind,
    /// Fixed number of parts instead of the tolerance loop.
    pub fixed_k: bool,
    /// The fixed k (when `fixed_k`).
    pub k: usize,
    /// Tolerance on TOV (sigma_G).
    pub tov: f64,
    /// Tolerance on MOV (sigma_L).
    pub mov: f64,
    /// Largest k of the tolerance loop.
    pub max_k: usize,
    /// Target number of interior samples.
    pub samples: usize,
    /// Seed of the initialisation.
    pub seed: u64,
}

impl Default for Settings {
    fn default() -> Self {
        let p = Params::default();
        Self {
            bounding: p.bounding,
            fixed_k: false,
            k: 8,
            tov: p.tov,
            mov: p.mov,
            max_k: p.max_k,
            samples: p.samples,
            seed: p.seed,
        }
    }
}

impl Settings {
    /// The core's parameters for these settings.
    pub fn params(&self) -> Params {
        Params {
            samples: self.samples,
            seed: self.seed,
            bounding: self.bounding,
            k: self.fixed_k.then_some(self.k),
            tov: self.tov,
            mov: self.mov,
            max_k: self.max_k,
            ..Params::default()
        }
    }
}

/// Where the app is.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// No run yet (or the mesh changed).
    Idle,
    /// A run is going.
    Running,
    /// The last run finished.
    Done,
    /// The last run was cancelled.
    Cancelled,
    /// Loading or running failed; the message.
    Failed(String),
}

/// The mesh the app starts with.
pub enum StartMesh {
    /// A bundled mesh, by name.
    Bundled(String),
    /// A mesh already loaded (the native command line's argument).
    Loaded {
        /// Its name (file name).
        name: String,
        /// The mesh.
        mesh: Mesh,
    },
}

/// How the app starts.
pub struct StartOptions {
    /// The first mesh.
    pub mesh: StartMesh,
    /// Run with the default settings right away.
    pub autorun: bool,
    /// Told when a run ends or fails.
    pub reporter: Option<Reporter>,
}

impl Default for StartOptions {
    fn default() -> Self {
        Self {
            mesh: StartMesh::Bundled(BUNDLED[0].name.to_string()),
            autorun: false,
            reporter: None,
        }
    }
}

/// A loaded mesh with what the view needs of it.
struct Model {
    name: String,
    mesh: Arc<Mesh>,
    geometry: Arc<MeshGeometry>,
}

/// What the current scene geometry was built from; rebuilt when this changes.
#[derive(Debug, Clone, PartialEq)]
struct SceneKey {
    model: u64,
    run: u64,
    snapshot: Option<usize>,
    final_colours: bool,
    selected: Option<usize>,
    display: Display,
}

type Gpu = Arc<Mutex<Option<Result<Renderer, String>>>>;

/// The viewer.
pub struct ViewerApp {
    settings: Settings,
    model: Option<Model>,
    model_id: u64,
    session: Option<Session>,
    run_id: u64,
    status: Status,
    /// Step shown; `None` follows the latest.
    history_pos: Option<usize>,
    selected_part: Option<usize>,
    display: Display,
    camera: OrbitCamera,
    gpu: Gpu,
    scene: Option<(SceneKey, u64, Arc<Geometry>)>,
    generation: u64,
    message: Option<String>,
    pending_run: bool,
    reporter: Option<Reporter>,
    inbox: Inbox,
    view_rect: Option<egui::Rect>,
    #[cfg(not(target_arch = "wasm32"))]
    native: NativeDialogs,
}

/// The native "open" and "save" path prompts (a file dialog crate would pull in a GUI
/// toolkit or D-Bus; a path field is enough, and drag and drop works too).
#[cfg(not(target_arch = "wasm32"))]
#[derive(Default)]
struct NativeDialogs {
    open: Option<String>,
    save: Option<String>,
}

impl ViewerApp {
    /// A new app, starting as `start` says.
    pub fn new(start: StartOptions) -> Self {
        let mut app = Self {
            settings: Settings::default(),
            model: None,
            model_id: 0,
            session: None,
            run_id: 0,
            status: Status::Idle,
            history_pos: None,
            selected_part: None,
            display: Display::default(),
            camera: OrbitCamera::framing(1.0),
            gpu: Arc::new(Mutex::new(None)),
            scene: None,
            generation: 0,
            message: None,
            pending_run: false,
            reporter: start.reporter,
            inbox: Inbox::default(),
            view_rect: None,
            #[cfg(not(target_arch = "wasm32"))]
            native: NativeDialogs::default(),
        };
        match start.mesh {
            StartMesh::Bundled(name) => match meshes::bundled(&name) {
                Some(b) => app.load_bytes(b.file, b.bytes),
                None => {
                    let names: Vec<&str> = BUNDLED.iter().map(|m| m.name).collect();
                    app.fail(format!(
                        "unknown bundled mesh '{name}' (bundled: {})",
                        names.join(", ")
                    ));
                }
            },
            StartMesh::Loaded { name, mesh } => app.set_model(name, mesh),
        }
        app.pending_run = start.autorun && app.model.is_some();
        app
    }

    /// The controls.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The controls, to change them.
    pub fn settings_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }

    /// Where the app is.
    pub fn status(&self) -> &Status {
        &self.status
    }

    /// The current (or last) run.
    pub fn session(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    /// The last run's result.
    pub fn result(&self) -> Option<&Segmentation> {
        self.session.as_ref().and_then(Session::result)
    }

    /// Name of the loaded mesh.
    pub fn mesh_name(&self) -> Option<&str> {
        self.model.as_ref().map(|m| m.name.as_str())
    }

    /// The highlighted part.
    pub fn selected_part(&self) -> Option<usize> {
        self.selected_part
    }

    /// Index of the history step shown.
    pub fn shown_step(&self) -> Option<usize> {
        let n = self.session.as_ref()?.snapshots().len();
        (n > 0).then(|| self.history_pos.unwrap_or(n - 1).min(n - 1))
    }

    /// The display settings.
    pub fn display(&self) -> Display {
        self.display
    }

    /// The 3D view's rectangle in the last frame, in points.
    pub fn view_rect(&self) -> Option<egui::Rect> {
        self.view_rect
    }

    /// Loads a mesh file's bytes (any way in: menu, dialog, drop), reporting errors in the UI.
    pub fn load_bytes(&mut self, name: &str, bytes: &[u8]) {
        match meshes::load_mesh_bytes(bytes, name) {
            Ok(mesh) => self.set_model(name.to_string(), mesh),
            Err(e) => self.fail(e),
        }
    }

    fn set_model(&mut self, name: String, mesh: Mesh) {
        let geometry = Arc::new(MeshGeometry::new(&mesh));
        self.camera = OrbitCamera::framing(geometry.radius);
        self.model = Some(Model {
            name,
            mesh: Arc::new(mesh),
            geometry,
        });
        self.model_id += 1;
        self.session = None;
        self.status = Status::Idle;
        self.history_pos = None;
        self.selected_part = None;
        self.message = None;
    }

    fn fail(&mut self, msg: String) {
        self.message = Some(msg.clone());
        self.status = Status::Failed(msg.clone());
        if let Some(r) = self.reporter.as_mut() {
            r(&Report::Error(msg));
        }
    }

    /// Starts a run of the loaded mesh with the current settings.
    pub fn run(&mut self) {
        let Some(model) = &self.model else {
            return;
        };
        self.session = Some(Session::new(model.mesh.clone(), self.settings.params()));
        self.run_id += 1;
        self.status = Status::Running;
        self.history_pos = None;
        self.selected_part = None;
        self.message = None;
    }

    /// Stops the run; what it did so far stays visible.
    pub fn cancel(&mut self) {
        if self.status == Status::Running {
            self.status = Status::Cancelled;
        }
    }

    /// Advances the running session by one frame's budget.
    fn advance(&mut self, budget: Duration) {
        if self.status != Status::Running {
            return;
        }
        let Some(s) = self.session.as_mut() else {
            return;
        };
        match s.advance(budget) {
            Progress::Running => {}
            Progress::Done => {
                self.status = Status::Done;
                if let (Some(res), Some(r)) = (s.result(), self.reporter.as_mut()) {
                    let view = self
                        .view_rect
                        .map(|v| [v.min.x, v.min.y, v.width(), v.height()]);
                    r(&Report::Done(summary_json(
                        res,
                        s.params(),
                        s.wall().as_secs_f64(),
                        view,
                    )));
                }
            }
            Progress::Failed => {
                let msg = s
                    .error()
                    .map_or_else(|| "the run failed".to_string(), |e| e.to_string());
                self.fail(msg);
            }
        }
    }

    /// One frame of the UI (without eframe, so the tests can drive it).
    pub fn ui(&mut self, ctx: &egui::Context) {
        self.take_files(ctx);
        if std::mem::take(&mut self.pending_run) {
            self.run();
        }
        self.advance(FRAME_BUDGET);
        if self.status == Status::Running {
            ctx.request_repaint();
        }
        egui::TopBottomPanel::top("menu").show(ctx, |ui| self.menu_bar(ui));
        egui::SidePanel::left("controls")
            .resizable(true)
            .default_width(250.0)
            .show(ctx, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        egui::SidePanel::right("statistics")
            .resizable(true)
            .default_width(250.0)
            .show(ctx, |ui| self.statistics(ui));
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ctx, |ui| self.view(ui));
        #[cfg(not(target_arch = "wasm32"))]
        self.native_dialogs(ctx);
    }

    fn take_files(&mut self, ctx: &egui::Context) {
        let mut files = self.inbox.take();
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        for f in dropped {
            if let Some(bytes) = f.bytes {
                files.push((f.name, bytes.to_vec()));
            } else if let Some(path) = f.path {
                let name = path.file_name().map_or_else(
                    || path.display().to_string(),
                    |n| n.to_string_lossy().into(),
                );
                match std::fs::read(&path) {
                    Ok(b) => files.push((name, b)),
                    Err(e) => self.fail(format!("{}: cannot read: {e}", path.display())),
                }
            }
        }
        // With several files dropped at once, the last one wins.
        if let Some((name, bytes)) = files.pop() {
            self.load_bytes(&name, &bytes);
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::menu::bar(ui, |ui| {
            ui.menu_button("Mesh", |ui| {
                for m in BUNDLED {
                    if ui.button(m.name).on_hover_text(m.about).clicked() {
                        self.load_bytes(m.file, m.bytes);
                        ui.close_menu();
                    }
                }
                ui.separator();
                if ui.button("Open file…").clicked() {
                    self.open_file(ui.ctx());
                    ui.close_menu();
                }
            });
            let has_result = self.result().is_some();
            ui.menu_button("Result", |ui| {
                let label = if cfg!(target_arch = "wasm32") {
                    "Download JSON"
                } else {
                    "Save JSON…"
                };
                if ui
                    .add_enabled(has_result, egui::Button::new(label))
                    .clicked()
                {
                    self.save_json();
                    ui.close_menu();
                }
            });
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
        if let Err(e) = crate::platform::pick_file(self.inbox.clone(), ctx.clone(), ".obj") {
            self.fail(e);
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let _ = ctx;
            self.native.open = Some(String::new());
        }
    }

    fn json_name(&self) -> String {
        let stem = self
            .model
            .as_ref()
            .map(|m| m.name.as_str())
            .and_then(|n| std::path::Path::new(n).file_stem())
            .map_or_else(|| "bvseg".into(), |s| s.to_string_lossy().into_owned());
        format!("{stem}.volumes.json")
    }

    fn save_json(&mut self) {
        #[cfg(target_arch = "wasm32")]
        if let Some(res) = self.result() {
            let json = bvseg_io::to_json_string(res);
            if let Err(e) =
                crate::platform::download(&self.json_name(), "application/json", json.as_bytes())
            {
                self.fail(e);
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.native.save = Some(self.json_name());
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn native_dialogs(&mut self, ctx: &egui::Context) {
        if let Some(mut path) = self.native.open.take() {
            let mut keep = true;
            let mut go = false;
            egui::Window::new("Open mesh")
                .collapsible(false)
                .show(ctx, |ui| {
                    ui.label(format!("Path of a mesh file ({}):", meshes::SUPPORTED));
                    let r = ui.text_edit_singleline(&mut path);
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
        if let Some(mut path) = self.native.save.take() {
            let mut keep = true;
            let mut go = false;
            egui::Window::new("Save JSON")
                .collapsible(false)
                .show(ctx, |ui| {
                    ui.label("Write the volumes (bvseg.volumes/1) to:");
                    ui.text_edit_singleline(&mut path);
                    ui.horizontal(|ui| {
                        go = ui.button("Save").clicked();
                        keep = !ui.button("Close").clicked();
                    });
                });
            if go {
                if let Some(res) = self.result() {
                    match bvseg_io::write_json(path.trim(), res) {
                        Ok(()) => self.message = Some(format!("wrote {}", path.trim())),
                        Err(e) => self.fail(e.to_string()),
                    }
                }
            } else if keep {
                self.native.save = Some(path);
            }
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        let idle = self.status != Status::Running;
        ui.heading("Segmentation");
        ui.add_enabled_ui(idle, |ui| {
            ui.label("Bounding volumes");
            ui.horizontal_wrapped(|ui| {
                let s = &mut self.settings;
                ui.radio_value(&mut s.bounding, BoundingKind::Ellipsoid, "Ellipsoids");
                ui.radio_value(&mut s.bounding, BoundingKind::Obb, "Boxes");
                ui.radio_value(&mut s.bounding, BoundingKind::Mixed, "Mixed");
            });
            ui.horizontal(|ui| {
                let s = &mut self.settings;
                ui.radio_value(&mut s.fixed_k, false, "Tolerances");
                ui.radio_value(&mut s.fixed_k, true, "Fixed k");
            });
            egui::Grid::new("params").num_columns(2).show(ui, |ui| {
                let s = &mut self.settings;
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
                        "σL (MOV)",
                        egui::DragValue::new(&mut s.mov)
                            .speed(0.01)
                            .range(0.0..=10.0),
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
            if ui
                .add_enabled(idle && self.model.is_some(), egui::Button::new("Run"))
                .clicked()
            {
                self.run();
            }
            if ui.add_enabled(!idle, egui::Button::new("Cancel")).clicked() {
                self.cancel();
            }
        });
        ui.separator();
        self.history(ui);
        ui.separator();
        ui.heading("View");
        ui.checkbox(&mut self.display.colour_by_part, "Colour mesh by part");
        ui.checkbox(&mut self.display.translucent_mesh, "Translucent mesh");
        ui.horizontal_wrapped(|ui| {
            ui.label("Volumes:");
            let d = &mut self.display;
            ui.radio_value(&mut d.volumes, VolumeStyle::Translucent, "Translucent");
            ui.radio_value(&mut d.volumes, VolumeStyle::Wireframe, "Wireframe");
            ui.radio_value(&mut d.volumes, VolumeStyle::Hidden, "Hidden");
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

    fn history(&mut self, ui: &mut egui::Ui) {
        ui.heading("Refinement");
        let Some(session) = &self.session else {
            ui.label(RichText::new("TOV and MOV against k appear here during a run.").weak());
            return;
        };
        let history: Vec<_> = session.snapshots().iter().map(|s| s.step).collect();
        let p = session.params();
        let tol = p.k.is_none().then_some((p.tov, p.mov));
        let shown = self.shown_step();
        if let Some(i) = crate::plot::show(ui, &history, tol, shown) {
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

    fn shown_snapshot(&self) -> Option<&Snapshot> {
        let i = self.shown_step()?;
        self.session.as_ref()?.snapshots().get(i)
    }

    /// Whether the shown step is the result's final step (so the parts' figures are final).
    fn showing_result(&self) -> bool {
        let (Some(s), Some(i)) = (&self.session, self.shown_step()) else {
            return false;
        };
        s.result().is_some() && i + 1 == s.snapshots().len()
    }

    fn statistics(&mut self, ui: &mut egui::Ui) {
        ui.heading("Statistics");
        let snap = self.shown_snapshot().cloned();
        let tol = self.session.as_ref().and_then(|s| {
            s.params()
                .k
                .is_none()
                .then_some((s.params().tov, s.params().mov))
        });
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
                }
                if let Some(s) = &self.session {
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
                    row("MOV", mark(st.mov, tol.map(|t| t.1)));
                    if st.kind == StepKind::Backtrack {
                        row("", "rejected split (view: kept state)".into());
                    }
                }
            });
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
                .num_columns(4)
                .striped(true)
                .show(ui, |ui| {
                    ui.label("");
                    ui.label("shape");
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

    fn scene_geometry(&mut self) -> Option<(u64, Arc<Geometry>)> {
        let model = self.model.as_ref()?;
        let snap = self.shown_snapshot();
        let key = SceneKey {
            model: self.model_id,
            run: self.run_id,
            snapshot: self.shown_step(),
            final_colours: self.showing_result(),
            selected: self.selected_part,
            display: self.display,
        };
        if let Some((k, generation, g)) = &self.scene {
            if *k == key {
                return Some((*generation, g.clone()));
            }
        }
        let g = Arc::new(scene::build(
            &model.geometry,
            snap,
            self.selected_part,
            self.display,
        ));
        self.generation += 1;
        self.scene = Some((key, self.generation, g.clone()));
        Some((self.generation, g))
    }

    fn view(&mut self, ui: &mut egui::Ui) {
        let (rect, response) =
            ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        self.view_rect = Some(rect);
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_rgb(32, 34, 40));
        let shift = ui.input(|i| i.modifiers.shift);
        let d = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && !shift {
            self.camera.orbit(d.x, d.y);
        } else if response.dragged() {
            self.camera.pan(d.x, d.y, rect.height());
        }
        if response.hovered() {
            let (scroll, zoom) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
            self.camera.zoom(zoom * (scroll * 0.002).exp());
        }
        if response.double_clicked() {
            self.camera.reset();
        }
        if let Some((generation, geometry)) = self.scene_geometry() {
            let frame = Arc::new(Frame {
                generation,
                geometry,
                view_projection: self.camera.view_projection(rect.aspect_ratio()),
                light: (self.camera.eye() - self.camera.target).normalize_or_zero(),
            });
            let gpu = self.gpu.clone();
            let callback = egui_glow::CallbackFn::new(move |_info, painter| {
                let Ok(mut gpu) = gpu.lock() else {
                    return;
                };
                let r = gpu.get_or_insert_with(|| Renderer::new(painter.gl()));
                if let Ok(r) = r {
                    r.paint(painter.gl(), &frame);
                }
            });
            painter.add(egui::PaintCallback {
                rect,
                callback: Arc::new(callback),
            });
        }
        let note = |text: &str| {
            painter.text(
                rect.center_top() + egui::vec2(0.0, 12.0),
                egui::Align2::CENTER_TOP,
                text,
                egui::FontId::proportional(14.0),
                Color32::from_gray(200),
            );
        };
        if let Ok(gpu) = self.gpu.lock() {
            if let Some(Err(e)) = gpu.as_ref() {
                note(e);
            }
        }
        if self.model.is_none() {
            note("Pick a mesh in the Mesh menu, or drop a mesh file here");
        }
        if ui.ctx().input(|i| !i.raw.hovered_files.is_empty()) {
            painter.rect_filled(rect, 0.0, Color32::from_black_alpha(120));
            note("Drop to load");
        }
    }

    /// Frees the GPU objects (the app is closing).
    pub fn destroy_gpu(&mut self, gl: Option<&glow::Context>) {
        if let (Some(gl), Ok(mut gpu)) = (gl, self.gpu.lock()) {
            if let Some(Ok(r)) = gpu.take() {
                r.destroy(gl);
            }
        }
    }
}

/// A control with a label that names it (for screen readers and the tests).
fn labelled(ui: &mut egui::Ui, label: &str, widget: impl egui::Widget) {
    let l = ui.label(label);
    ui.add(widget).labelled_by(l.id);
    ui.end_row();
}

impl eframe::App for ViewerApp {
    fn update(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.ui(ctx);
    }

    fn on_exit(&mut self, gl: Option<&glow::Context>) {
        self.destroy_gpu(gl);
    }
}

/// The summary of a finished run as one JSON object: `k`, `tov`, `mov`, `f` (the page
/// contract), then `samples`, `kind`, `met` (the tolerances were met; `null` with a fixed k),
/// `time_s` (wall time of the run) and `view` (the 3D view's rectangle in CSS pixels, so that
/// a browser test knows where to look).
pub fn summary_json(
    res: &Segmentation,
    params: &Params,
    seconds: f64,
    view: Option<[f32; 4]>,
) -> String {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x}")
        } else {
            "null".into()
        }
    };
    let m = res.metrics;
    let met = match params.k {
        Some(_) => "null".to_string(),
        None => (m.tov < params.tov && m.mov < params.mov).to_string(),
    };
    let view = view.map_or("null".into(), |v| {
        format!("[{},{},{},{}]", v[0], v[1], v[2], v[3])
    });
    format!(
        "{{\"k\":{},\"tov\":{},\"mov\":{},\"f\":{},\"samples\":{},\"kind\":\"{}\",\"met\":{},\"time_s\":{},\"view\":{}}}",
        m.k,
        num(m.tov),
        num(m.mov),
        num(m.f),
        m.samples,
        res.kind.as_str(),
        met,
        num(seconds),
        view
    )
}
