//! The browser entry point and the page contract.
//!
//! `index.html?mesh=NAME&autorun=1` loads the bundled mesh `NAME` and runs it with the default
//! settings; `&bv=KINDS` sets the kinds of volume first (a comma list such as `obb,capsule` or
//! `mixed`, or a target such as `parry` or `mujoco-hull`: see [`crate::kinds::parse_kinds`]).
//! When a run ends, its summary (JSON, see [`crate::app::summary_json`]) is written into
//! `<pre id="bvseg-result">` and `document.title` starts with `bvseg: done`; on an error
//! the title is `bvseg: error: <message>`. Scripts wait for the title, and find the controls
//! to click with [`widget_rect`]. Without `autorun`, the threaded build starts a small run
//! that nobody sees as it loads, and stops it at the first Run (see
//! [`crate::session::Session::warm_up`]).
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

use crate::app::{StartMesh, StartOptions, ViewerApp};
use crate::meshes::BUNDLED;
use crate::platform::Report;

fn set_title(title: &str) {
    if let Some(d) = web_sys::window().and_then(|w| w.document()) {
        d.set_title(title);
    }
}

fn set_result(text: &str) {
    if let Some(el) = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.get_element_by_id("bvseg-result"))
    {
        el.set_text_content(Some(text));
    }
}

fn report(r: &Report) {
    match r {
        Report::Done(json) => {
            set_result(json);
            set_title("bvseg: done");
        }
        Report::Error(msg) => {
            set_result(msg);
            set_title(&format!("bvseg: error: {msg}"));
        }
    }
}

/// Where the widget called `label` (such as `Run`, `Boxes`, `Fixed k`) was last drawn, as
/// `[x, y, width, height]` in CSS pixels of the canvas, for scripts that click it.
#[wasm_bindgen(js_name = widgetRect)]
pub fn widget_rect(label: &str) -> Option<Vec<f32>> {
    crate::platform::widget_rect(label).map(|r| r.to_vec())
}

/// Starts the viewer in the canvas with id `canvas_id`, reading `mesh`, `autorun` and `bv` from
/// the page's query string. `software_renderer`: WebGL draws on the CPU (see
/// [`StartOptions::software_renderer`]); left out, it is taken to be a GPU.
#[wasm_bindgen]
pub async fn start(canvas_id: String, software_renderer: Option<bool>) -> Result<(), JsValue> {
    let window = web_sys::window().ok_or("no window")?;
    let document = window.document().ok_or("no document")?;
    let canvas: web_sys::HtmlCanvasElement = document
        .get_element_by_id(&canvas_id)
        .ok_or_else(|| format!("no element #{canvas_id}"))?
        .dyn_into()
        .map_err(|_| format!("#{canvas_id} is not a canvas"))?;
    let query = web_sys::UrlSearchParams::new_with_str(&window.location().search()?)?;
    let mesh = query
        .get("mesh")
        .unwrap_or_else(|| BUNDLED[0].name.to_string());
    let autorun = matches!(query.get("autorun").as_deref(), Some("1" | "true" | "yes"));
    let runner = eframe::WebRunner::new();
    // After eframe's own panic handler (which logs), make a panic visible to page scripts.
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info.to_string().replace('\n', " ");
        if web_sys::window().is_none() {
            // A Web Worker of the threaded build (the core): the session's next look fails
            // the run. eframe's handler is not called, as it would stop the whole app.
            web_sys::console::error_1(&format!("bvseg: the core panicked: {msg}").into());
            crate::session::note_pool_panic(&msg);
            return;
        }
        set_title(&format!("bvseg: error: panic: {msg}"));
        previous(info);
    }));
    let software = software_renderer.unwrap_or(false);
    let start = StartOptions {
        mesh: StartMesh::Bundled(mesh),
        autorun,
        kinds: query.get("bv"),
        reporter: Some(Box::new(report)),
        software_renderer: software,
        // Only the threaded build runs the core beside the page; the other would take the
        // page's own thread for it.
        warm_up: cfg!(feature = "threads"),
    };
    runner
        .start(
            canvas,
            eframe::WebOptions::default(),
            Box::new(move |cc| {
                // No animations on a software renderer: each frame costs tens of milliseconds
                // of the cores the run needs, and egui's animations drew four or five frames
                // after each click and each batch of news instead of one or two (with them,
                // the threaded page's later runs of spot took 1.38-1.43 s; without, 1.28-1.36).
                if software {
                    cc.egui_ctx.all_styles_mut(|s| s.animation_time = 0.0);
                }
                Ok(Box::new(ViewerApp::new(start)))
            }),
        )
        .await
}

/// The page's threaded build: `initThreadPool(n)` starts `n` Web Workers for the core (main.js
/// calls it before [`start`] when the page is cross-origin isolated).
#[cfg(feature = "threads")]
pub use wasm_bindgen_rayon::init_thread_pool;

/// The threaded build's allocator: running out of memory aborts a Web Worker without a
/// panic, and the run waiting for it would never end; this one notes the failure first, so
/// that the run ends with an error.
#[cfg(feature = "threads")]
#[global_allocator]
static ALLOCATOR: crate::session::NotingAllocator<std::alloc::System> =
    crate::session::NotingAllocator(std::alloc::System);
