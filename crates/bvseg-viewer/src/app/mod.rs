//! The viewer app: controls on the left, the 3D view in the middle, statistics and parts on
//! the right. Each frame advances the running [`Session`] by a time budget, then draws.
use std::sync::{Arc, Mutex};

use bvseg_core::{Kinds, Mesh, Params, Segmentation, Shape};
use eframe::egui;
use eframe::glow;
use web_time::{Duration, Instant};

use crate::animation::Player;
use crate::budget::{news_interval, FrameBudget};
use crate::camera::OrbitCamera;
use crate::meshes::{self, BUNDLED};
use crate::platform::{Inbox, Report, Reporter};
use crate::render::Renderer;
use crate::scene::{Display, Geometry, MeshGeometry};
use crate::session::{failure_message, Progress, Session, Snapshot};

mod panels;
mod view;

/// The controls of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The kinds of volume a part may get (never empty: the controls keep one ticked).
    pub kinds: Kinds,
    /// Most vertices of a hull volume (used when `kinds` has hulls).
    pub max_hull_vertices: usize,
    /// Fixed number of parts instead of the tolerance loop.
    pub fixed_k: bool,
    /// The fixed k (when `fixed_k`).
    pub k: usize,
    /// Tolerance on TOV (sigma_G).
    pub tov: f64,
    /// Tolerance on the protrusion, as a fraction of the box diagonal.
    pub max_protrusion: f64,
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
            kinds: p.kinds,
            max_hull_vertices: p.max_hull_vertices,
            fixed_k: false,
            k: 8,
            tov: p.tov,
            max_protrusion: p.max_protrusion,
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
            kinds: self.kinds,
            max_hull_vertices: self.max_hull_vertices,
            k: self.fixed_k.then_some(self.k),
            tov: self.tov,
            max_protrusion: self.max_protrusion,
            max_k: self.max_k,
            // Only the JSON export carries the hierarchy: it is built then.
            hierarchy: false,
            ..Params::default()
        }
    }

    /// Ticks (`on`) or unticks the kind `shape`; unticking the only kind ticked does nothing.
    pub fn set_kind(&mut self, shape: Shape, on: bool) {
        self.kinds = crate::kinds::toggled(self.kinds, shape, on);
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
        /// What loading changed or found wrong, shown with the mesh's statistics.
        warnings: Vec<String>,
        /// The names of a character's animations (see [`crate::LoadedFile::animations`]).
        animations: Vec<String>,
    },
}

/// How the app starts.
pub struct StartOptions {
    /// The first mesh.
    pub mesh: StartMesh,
    /// Run right away (with the default settings, or `kinds`).
    pub autorun: bool,
    /// The kinds of volume to start with instead of the default, by name as
    /// [`crate::kinds::parse_kinds`] reads it (`obb,capsule`, `mixed`, `parry-hull`, ...): the
    /// page's `?bv=` and the native `--bv`. A name it cannot read fails the start.
    pub kinds: Option<String>,
    /// Told when a run ends or fails.
    pub reporter: Option<Reporter>,
    /// WebGL draws on the CPU (the page detects a software renderer): a run in the background
    /// then takes its news less often, as each frame costs it more (see
    /// [`crate::budget::news_interval`]). Default `false`.
    pub software_renderer: bool,
    /// Without `autorun`, start a small run in the background at once and drop it at the
    /// first real run (see [`Session::warm_up`]): the page's threaded build sets it, for the
    /// browser's sake. Default `false`.
    pub warm_up: bool,
}

impl Default for StartOptions {
    fn default() -> Self {
        Self {
            mesh: StartMesh::Bundled(BUNDLED[0].name.to_string()),
            autorun: false,
            kinds: None,
            reporter: None,
            software_renderer: false,
            warm_up: false,
        }
    }
}

/// A loaded mesh with what the view needs of it.
struct Model {
    name: String,
    mesh: Arc<Mesh>,
    geometry: Arc<MeshGeometry>,
    warnings: Vec<String>,
}

/// What the current scene geometry was built from; rebuilt when this changes.
#[derive(Debug, Clone, PartialEq)]
struct SceneKey {
    model: u64,
    run: u64,
    snapshot: Option<usize>,
    final_colours: bool,
    /// The character's sampled pose shown, `None` at rest.
    pose: Option<usize>,
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
    /// The run of [`StartOptions::warm_up`], until the first real run.
    warm_up: Option<Session>,
    run_id: u64,
    status: Status,
    /// Step shown; `None` follows the latest.
    history_pos: Option<usize>,
    selected_part: Option<usize>,
    display: Display,
    /// The animation controls, for a mesh whose rig has poses.
    player: Option<Player>,
    camera: OrbitCamera,
    gpu: Gpu,
    scene: Option<(SceneKey, u64, Arc<Geometry>)>,
    generation: u64,
    message: Option<String>,
    pending_run: bool,
    reporter: Option<Reporter>,
    inbox: Inbox,
    view_rect: Option<egui::Rect>,
    budget: FrameBudget,
    /// While a run in the background is live: how long the next frame may wait (see
    /// [`Self::advance`]).
    next_frame: Option<Duration>,
    /// When the news of the run in the background was last taken.
    last_news: Option<Instant>,
    /// How often to take it (see [`crate::budget::news_interval`]).
    news_interval: Duration,
    /// The run and its status as the last pass drew them (see [`Self::show`]).
    drawn: (u64, Status),
    #[cfg(not(target_arch = "wasm32"))]
    native: NativeDialogs,
}

/// The native "open" and "save" path prompts (a file dialog crate would pull in a GUI
/// toolkit or D-Bus; a path field is enough, and drag and drop works too).
#[cfg(not(target_arch = "wasm32"))]
#[derive(Default)]
struct NativeDialogs {
    open: Option<String>,
    save: Option<(String, Export)>,
}

/// What the Result menu writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Export {
    /// The `bvseg.volumes/1` JSON document.
    Json,
    /// The mesh and the volumes as binary glTF.
    Glb,
}

impl Export {
    fn extension(self) -> &'static str {
        match self {
            Export::Json => "json",
            Export::Glb => "glb",
        }
    }

    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    fn mime(self) -> &'static str {
        match self {
            Export::Json => "application/json",
            Export::Glb => "model/gltf-binary",
        }
    }

    fn menu_label(self) -> &'static str {
        match (self, cfg!(target_arch = "wasm32")) {
            (Export::Json, true) => "Download JSON",
            (Export::Json, false) => "Save JSON…",
            (Export::Glb, true) => "Download GLB",
            (Export::Glb, false) => "Save GLB…",
        }
    }

    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    fn what(self) -> &'static str {
        match self {
            Export::Json => "Write the volumes (bvseg.volumes/1 JSON) to:",
            Export::Glb => "Write the mesh and the volumes (binary glTF) to:",
        }
    }
}

impl ViewerApp {
    /// A new app, starting as `start` says.
    pub fn new(start: StartOptions) -> Self {
        let mut app = Self {
            settings: Settings::default(),
            model: None,
            model_id: 0,
            session: None,
            warm_up: None,
            run_id: 0,
            status: Status::Idle,
            history_pos: None,
            selected_part: None,
            display: Display::default(),
            player: None,
            camera: OrbitCamera::framing(1.0),
            gpu: Arc::new(Mutex::new(None)),
            scene: None,
            generation: 0,
            message: None,
            pending_run: false,
            reporter: start.reporter,
            inbox: Inbox::default(),
            view_rect: None,
            budget: FrameBudget::default(),
            next_frame: None,
            last_news: None,
            news_interval: news_interval(start.software_renderer),
            drawn: (0, Status::Idle),
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
            StartMesh::Loaded {
                name,
                mesh,
                warnings,
                animations,
            } => app.set_model(name, mesh, warnings, &animations),
        }
        let mut kinds_ok = true;
        if let Some(name) = start.kinds {
            match crate::kinds::parse_kinds(&name) {
                Ok(k) => app.settings.kinds = k,
                Err(e) => {
                    app.fail(format!("bounding volumes {name:?}: {e}"));
                    kinds_ok = false;
                }
            }
        }
        app.pending_run = start.autorun && app.model.is_some() && kinds_ok;
        if start.warm_up && !app.pending_run {
            app.warm_up = app
                .model
                .as_ref()
                .and_then(|m| Session::warm_up(m.mesh.clone(), &app.settings.params()));
        }
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

    /// What loading the mesh changed or found wrong, one line each (shown in the UI).
    pub fn load_warnings(&self) -> &[String] {
        self.model.as_ref().map_or(&[], |m| m.warnings.as_slice())
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

    /// The animation controls' state, for a mesh whose rig has sampled poses (a skinned
    /// glTF character with animations); `None` for any other mesh.
    pub fn player(&self) -> Option<&Player> {
        self.player.as_ref()
    }

    /// The vertex arrays the 3D view drew in the last frame (`None` before the first, or
    /// without a mesh).
    pub fn drawn(&self) -> Option<&Geometry> {
        self.scene.as_ref().map(|s| s.2.as_ref())
    }

    /// The 3D view's rectangle in the last frame, in points.
    pub fn view_rect(&self) -> Option<egui::Rect> {
        self.view_rect
    }

    /// Loads a mesh file's bytes (any way in: menu, dialog, drop), reporting errors in the UI.
    pub fn load_bytes(&mut self, name: &str, bytes: &[u8]) {
        match meshes::load_mesh_bytes(bytes, name) {
            Ok(f) => self.set_model(name.to_string(), f.mesh, f.warnings, &f.animations),
            Err(e) => self.fail(e),
        }
    }

    fn set_model(
        &mut self,
        name: String,
        mesh: Mesh,
        warnings: Vec<String>,
        animations: &[String],
    ) {
        let geometry = Arc::new(MeshGeometry::new(&mesh));
        self.player = Player::new(mesh.rig(), animations);
        self.camera = OrbitCamera::framing(geometry.radius);
        self.model = Some(Model {
            name,
            mesh: Arc::new(mesh),
            geometry,
            warnings,
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
        // Stopped, so that the run has every core.
        self.warm_up = None;
        self.session = Some(Session::new(model.mesh.clone(), self.settings.params()));
        self.run_id += 1;
        self.last_news = None;
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

    /// Advances the running session by one frame's budget (see [`crate::budget`]).
    fn advance(&mut self) {
        let Some(s) = self
            .session
            .as_mut()
            .filter(|_| self.status == Status::Running)
        else {
            self.budget.idle();
            return;
        };
        let t0 = Instant::now();
        let progress = if s.is_background() {
            // The run needs no frames; a frame that shows news costs the drawing of a few
            // (egui lays out again the panels that changed), so news is taken only so often.
            // Its end is taken at once (see `platform::repaint_when_set`).
            let since = self.last_news.map(|l| t0.saturating_duration_since(l));
            if let Some(since) = since.filter(|&d| d < self.news_interval && !s.has_ended()) {
                self.next_frame = Some(self.news_interval - since);
                return;
            }
            self.last_news = Some(t0);
            self.next_frame = Some(self.news_interval);
            s.advance(Duration::ZERO)
        } else {
            let progress = s.advance(self.budget.start(t0));
            self.budget.worked(t0.elapsed());
            self.next_frame = None;
            progress
        };
        match progress {
            Progress::Running => {}
            Progress::Done => {
                self.status = Status::Done;
                let mesh = self.model.as_ref().map_or("", |m| m.name.as_str());
                let view = self
                    .view_rect
                    .map(|v| [v.min.x, v.min.y, v.width(), v.height()]);
                if let (Some(json), Some(r)) = (summary_json(mesh, s, view), self.reporter.as_mut())
                {
                    r(&Report::Done(json));
                }
            }
            Progress::Failed => {
                let msg = s
                    .error()
                    .map_or_else(|| "the run failed".to_string(), failure_message);
                self.fail(msg);
            }
        }
    }

    /// One frame (without eframe, so the tests can drive it): [`Self::logic`], then the
    /// panels in `ui`, which should cover the window.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        self.logic(ui.ctx());
        self.show(ui);
    }

    /// The work of a frame that draws nothing: starts a pending run and advances the running
    /// one. eframe also calls it while the window is hidden (minimised), so a run goes on.
    pub fn logic(&mut self, ctx: &egui::Context) {
        if std::mem::take(&mut self.pending_run) {
            self.run();
        }
        if let Some(ended) = self.session.as_mut().and_then(Session::take_end_signal) {
            crate::platform::repaint_when_set(ended, ctx.clone());
        }
        self.advance();
        if let Some(p) = self.player.as_mut().filter(|p| p.playing()) {
            // egui's frame time: the same clock natively and in the page, and steady in the
            // tests (no wall clock).
            p.advance(f64::from(ctx.input(|i| i.stable_dt)));
            ctx.request_repaint();
        }
        if self.status == Status::Running {
            match self.next_frame {
                Some(wait) => ctx.request_repaint_after(wait),
                None => ctx.request_repaint(),
            }
        }
    }

    /// The panels: menu bar, controls, statistics, and the 3D view in the middle.
    fn show(&mut self, ui: &mut egui::Ui) {
        self.take_files(ui.ctx());
        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(250.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        egui::Panel::right("statistics")
            .resizable(true)
            .default_size(250.0)
            .show(ui, |ui| self.statistics(ui));
        egui::CentralPanel::no_frame().show(ui, |ui| self.view(ui));
        #[cfg(not(target_arch = "wasm32"))]
        self.native_dialogs(ui.ctx());
        // A run that starts or ends changes the panels, and egui draws a widget new to it in
        // a default style and asks for two more frames to draw it right. Laying the panels out
        // again in the same frame instead (a discarded pass) costs no drawing, which a software
        // renderer does on the cores the run needs.
        if self.drawn.0 != self.run_id || self.drawn.1 != self.status {
            self.drawn = (self.run_id, self.status.clone());
            ui.ctx().request_discard("a run started or ended");
        }
    }

    /// Loads the files that arrived: picked in the browser's dialog, or dropped on the window.
    /// With several at once, the last one wins.
    fn take_files(&mut self, ctx: &egui::Context) {
        for msg in self.inbox.take_failures() {
            self.fail(msg);
        }
        let mut files = self.inbox.take();
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        for f in dropped {
            let path = f.path();
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into(),
            );
            // Natively the file is read here; in the browser it arrives in the inbox later.
            #[cfg(not(target_arch = "wasm32"))]
            match f.bytes() {
                Ok(b) => files.push((name, b)),
                Err(e) => self.fail(format!("{}: cannot read: {e}", path.display())),
            }
            #[cfg(target_arch = "wasm32")]
            crate::platform::read_dropped(self.inbox.clone(), ctx.clone(), name, f.clone());
        }
        if let Some((name, bytes)) = files.pop() {
            self.load_bytes(&name, &bytes);
        }
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

    /// Frees the GPU objects (the app is closing).
    pub fn destroy_gpu(&mut self, gl: Option<&glow::Context>) {
        if let (Some(gl), Ok(mut gpu)) = (gl, self.gpu.lock()) {
            if let Some(Ok(r)) = gpu.take() {
                r.destroy(gl);
            }
        }
    }
}

impl eframe::App for ViewerApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        ViewerApp::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }

    fn on_exit(&mut self, gl: Option<&glow::Context>) {
        self.destroy_gpu(gl);
    }
}

/// The summary of a finished run (`None` before the end) as one JSON object
/// ([`bvseg_io::RunSummary`] with the viewer's fields): `k`, `tov`, `mov`, `f` (the page
/// contract), then `mesh` (its name), `samples`, `kind`, `met` (the tolerances were met;
/// `null` with a fixed k), `time_s` and `core_s` (the run's wall time, and the part of it
/// spent in the core rather than drawing), `frames` (frames of the run) and `view` (the 3D
/// view's rectangle in CSS pixels, so that a browser test knows where to look).
pub fn summary_json(mesh: &str, s: &Session, view: Option<[f32; 4]>) -> Option<String> {
    let res = s.result()?;
    let summary = PageSummary {
        run: bvseg_io::RunSummary::new(mesh, res),
        met: res.tolerances_met(s.params()),
        time_s: s.wall().as_secs_f64(),
        core_s: s.busy().as_secs_f64(),
        frames: s.calls(),
        view,
    };
    Some(summary.to_json())
}

/// What the viewer reports of a run: the summary every front end has, then the viewer's own
/// fields (its page contract, read by the browser test).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
struct PageSummary {
    /// The shared figures, first.
    #[serde(flatten)]
    run: bvseg_io::RunSummary,
    /// Whether the tolerances were met; `null` with a fixed k.
    met: Option<bool>,
    /// Wall time of the run, in seconds.
    time_s: f64,
    /// The part of `time_s` spent in the core rather than drawing.
    core_s: f64,
    /// Frames the run took.
    frames: usize,
    /// The 3D view's rectangle `[x, y, width, height]` in CSS pixels, when known.
    view: Option<[f32; 4]>,
}

impl PageSummary {
    /// One line of JSON with the keys in the order of the fields: the page contract (`k`,
    /// `tov`, `mov`, `f`) first.
    // Strings, numbers (non-finite ones become null) and arrays: serde_json cannot fail on
    // them.
    #[allow(clippy::expect_used)]
    fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a PageSummary always serializes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshes::{load_bundled, BUNDLED};
    use crate::session::Progress;
    use web_time::Duration;

    #[test]
    fn summary_is_json_with_the_page_contract_first() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 2000,
            k: Some(3),
            ..Params::default()
        };
        let mut s = Session::new(mesh, params);
        assert!(summary_json("x", &s, None).is_none());
        while s.advance(Duration::from_secs(1)) == Progress::Running {}
        let name = "odd \"name\"\\\n.obj";
        let text = summary_json(name, &s, Some([1.0, 2.0, 3.0, 4.0])).unwrap();
        assert!(text.starts_with("{\"k\":3,\"tov\":"), "{text}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let m = s.result().unwrap().metrics;
        assert_eq!(v["tov"].as_f64(), Some(m.tov));
        assert_eq!(v["mov"].as_f64(), Some(m.mov));
        assert_eq!(v["f"].as_f64(), Some(m.f));
        assert_eq!(v["mesh"].as_str(), Some(name));
        assert_eq!(v["met"], serde_json::Value::Null);
        assert_eq!(v["frames"].as_u64(), Some(s.calls() as u64));
        assert_eq!(v["view"][3].as_f64(), Some(4.0));
    }

    #[test]
    fn page_summary_keys_come_in_the_contract_order_and_nan_is_null() {
        let mesh = load_bundled(&BUNDLED[0]).unwrap();
        let params = Params {
            samples: 2000,
            k: Some(2),
            ..Params::default()
        };
        let seg = bvseg_core::segment(&mesh, &params).unwrap();
        let page = PageSummary {
            run: bvseg_io::RunSummary::new("bunny.obj", &seg),
            met: seg.tolerances_met(&params),
            time_s: 2.0,
            core_s: f64::NAN,
            frames: 7,
            view: Some([1.0, 2.0, 3.5, 4.0]),
        };
        let text = page.to_json();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        // serde_json's map is sorted here, so the order is read from the text itself.
        let mut keys: Vec<(usize, String)> = v
            .as_object()
            .unwrap()
            .keys()
            .map(|k| (text.find(&format!("\"{k}\":")).unwrap(), k.clone()))
            .collect();
        keys.sort();
        let keys: Vec<String> = keys.into_iter().map(|(_, k)| k).collect();
        assert_eq!(
            keys,
            [
                "k",
                "tov",
                "mov",
                "f",
                "protrusion",
                "protrusion_rel",
                "mesh",
                "samples",
                "kind",
                "met",
                "time_s",
                "core_s",
                "frames",
                "view"
            ]
        );
        let start = format!("{{\"k\":2,\"tov\":{},", seg.metrics.tov);
        assert!(text.starts_with(&start), "{text}");
        assert!(
            text.contains("\"met\":null") && text.contains("\"core_s\":null"),
            "{text}"
        );
    }

    #[test]
    fn a_warm_up_runs_a_small_job_until_the_first_run() {
        let start = |autorun| {
            ViewerApp::new(StartOptions {
                autorun,
                warm_up: true,
                ..StartOptions::default()
            })
        };
        assert!(
            start(true).warm_up.is_none(),
            "a run at once needs no warm-up"
        );
        assert!(ViewerApp::new(StartOptions::default()).warm_up.is_none());
        let mut app = start(false);
        let warm = app.warm_up.as_mut().expect("a warm-up");
        let t0 = Instant::now();
        while warm.advance(Duration::ZERO) == Progress::Running {
            assert!(
                t0.elapsed() < Duration::from_secs(120),
                "the warm-up never ends"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        let k = warm.result().expect("the warm-up's result").parts.len();
        assert!(k > 1 && k <= crate::session::WARM_UP_MAX_K, "k = {k}");
        let samples = warm.samples();
        assert!(
            samples.abs_diff(crate::session::WARM_UP_SAMPLES) * 10
                < crate::session::WARM_UP_SAMPLES,
            "{samples} samples"
        );
        app.run();
        assert!(app.warm_up.is_none(), "the first run drops the warm-up");
        assert_eq!(
            app.session.as_ref().unwrap().params(),
            &app.settings.params()
        );
    }

    #[test]
    fn a_run_in_the_background_takes_news_as_often_as_the_renderer_allows() {
        use crate::budget::{NEWS_INTERVAL, SOFTWARE_NEWS_INTERVAL};
        for (software_renderer, interval) in
            [(false, NEWS_INTERVAL), (true, SOFTWARE_NEWS_INTERVAL)]
        {
            let mut app = ViewerApp::new(StartOptions {
                software_renderer,
                ..StartOptions::default()
            });
            let mesh = app.model.as_ref().unwrap().mesh.clone();
            // Dropped at the end of the test, the session cancels the run.
            app.session = Some(Session::in_background(mesh, app.settings.params()));
            app.status = Status::Running;
            let t0 = Instant::now();
            app.advance();
            assert_eq!(
                app.next_frame,
                Some(interval),
                "the first look takes the news"
            );
            app.advance();
            let waited = t0.elapsed();
            let next = app.next_frame.unwrap();
            assert!(
                next <= interval && next + waited >= interval,
                "the next look waits out the interval: {next:?} after {waited:?}"
            );
        }
    }

    #[test]
    fn a_run_that_starts_or_ends_is_laid_out_again_within_its_frame() {
        let mut app = ViewerApp::new(StartOptions::default());
        let ctx = egui::Context::default();
        let passes = |app: &mut ViewerApp| {
            ctx.run_ui(egui::RawInput::default(), |ui| app.show(ui))
                .platform_output
                .num_completed_passes
        };
        // egui lays some widgets out twice on the first frames.
        for _ in 0..3 {
            passes(&mut app);
        }
        assert_eq!(passes(&mut app), 1);
        app.run();
        assert_eq!(app.status, Status::Running);
        assert_eq!(passes(&mut app), 2, "the run's start");
        assert_eq!(passes(&mut app), 1);
        app.cancel();
        assert_eq!(passes(&mut app), 2, "the run's end");
        assert_eq!(passes(&mut app), 1);
    }

    #[test]
    fn the_end_of_a_run_in_the_background_is_taken_without_waiting_for_news() {
        let mut app = ViewerApp::new(StartOptions {
            software_renderer: true,
            ..StartOptions::default()
        });
        let mesh = app.model.as_ref().unwrap().mesh.clone();
        let params = Params {
            samples: 2000,
            max_k: 4,
            ..app.settings.params()
        };
        app.session = Some(Session::in_background(mesh, params));
        app.status = Status::Running;
        let ctx = egui::Context::default();
        let asked = Arc::new(Mutex::new(None));
        let noted = asked.clone();
        ctx.set_request_repaint_callback(move |info| {
            if info.delay.is_zero() {
                noted.lock().unwrap().get_or_insert(Instant::now());
            }
        });
        // The first frame takes the news, hands the end signal to a watcher, and waits for
        // the next news (2 s with a software renderer).
        app.logic(&ctx);
        assert_eq!(app.status, Status::Running);
        let t0 = Instant::now();
        let asked_at = loop {
            if let Some(at) = *asked.lock().unwrap() {
                break at;
            }
            assert!(t0.elapsed() < Duration::from_secs(60), "no frame asked for");
            std::thread::sleep(Duration::from_millis(1));
        };
        // That frame finds the end, however recent the last news.
        app.last_news = Some(asked_at);
        app.logic(&ctx);
        assert_eq!(app.status, Status::Done);
    }
}
