//! What differs between the desktop and the browser: how a finished run is reported, how a
//! file is picked, how a result leaves the app, and how the end of a run in the background
//! wakes the app.
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use eframe::egui;

use crate::budget::END_WATCH_INTERVAL;

/// What the app tells its host when a run ends.
#[derive(Debug, Clone, PartialEq)]
pub enum Report {
    /// The run finished; the summary as JSON, `{"k":..,"tov":..,"mov":..,"f":..,...}`.
    Done(String),
    /// Loading or running failed; a one-line message.
    Error(String),
}

/// Receives the app's [`Report`]s (the page writes them into the document; tests collect them).
pub type Reporter = Box<dyn FnMut(&Report)>;

/// Files picked in a browser file dialog or dropped on the page, which arrive asynchronously,
/// for the app to take on a later frame; and what could not be read.
#[derive(Clone, Default)]
pub struct Inbox(Rc<RefCell<InboxContents>>);

#[derive(Default)]
struct InboxContents {
    files: Vec<NamedBytes>,
    failures: Vec<String>,
}

/// A file's name and content.
pub type NamedBytes = (String, Vec<u8>);

impl Inbox {
    /// Adds a file (name, bytes).
    pub fn push(&self, name: String, bytes: Vec<u8>) {
        self.0.borrow_mut().files.push((name, bytes));
    }

    /// Takes every file that has arrived.
    pub fn take(&self) -> Vec<NamedBytes> {
        std::mem::take(&mut self.0.borrow_mut().files)
    }

    /// Adds the one-line message of a file that could not be read.
    pub fn push_failure(&self, msg: String) {
        self.0.borrow_mut().failures.push(msg);
    }

    /// Takes the messages of the files that could not be read.
    pub fn take_failures(&self) -> Vec<String> {
        std::mem::take(&mut self.0.borrow_mut().failures)
    }
}

#[cfg(target_arch = "wasm32")]
pub use web::{download, pick_file, read_dropped, widget_rect};

/// Asks `ctx` for a frame as soon as `ended` is set (a run in the background has ended, see
/// [`crate::session::Session::take_end_signal`]), looking every [`END_WATCH_INTERVAL`]; stops
/// then, or once nobody else holds the flag (the run and its session are gone). Without it the
/// end would show only at the next news frame. The run's thread cannot ask for the frame
/// itself: in the page it is a Web Worker, and eframe's repaint request reads the page's
/// clock, which only the main thread has. So the page's main thread looks, on a timer;
/// natively, a thread of its own.
pub fn repaint_when_set(ended: Arc<AtomicBool>, ctx: egui::Context) {
    let look = move || {
        if ended.load(Ordering::Acquire) {
            ctx.request_repaint();
            return false;
        }
        Arc::strong_count(&ended) > 1
    };
    #[cfg(target_arch = "wasm32")]
    web::every(END_WATCH_INTERVAL, look);
    #[cfg(not(target_arch = "wasm32"))]
    std::thread::spawn(move || {
        while look() {
            std::thread::sleep(END_WATCH_INTERVAL);
        }
    });
}

/// Remembers where the widget called `label` was drawn in this frame. eframe's web backend has
/// no accessibility tree, so a browser test finds the widgets it clicks through this record
/// (natively, AccessKit does that and this does nothing).
pub fn note_widget(label: &str, rect: eframe::egui::Rect) {
    #[cfg(target_arch = "wasm32")]
    web::note_widget(label, rect);
    #[cfg(not(target_arch = "wasm32"))]
    let _ = (label, rect);
}

#[cfg(target_arch = "wasm32")]
mod web {
    use eframe::egui;
    use wasm_bindgen::{JsCast, JsValue};

    use super::Inbox;

    thread_local! {
        static WIDGETS: std::cell::RefCell<Vec<(String, [f32; 4])>> =
            const { std::cell::RefCell::new(Vec::new()) };
    }

    pub fn note_widget(label: &str, r: egui::Rect) {
        let rect = [r.min.x, r.min.y, r.width(), r.height()];
        WIDGETS.with(|w| {
            let mut w = w.borrow_mut();
            match w.iter_mut().find(|(l, _)| l == label) {
                Some(entry) => entry.1 = rect,
                None => w.push((label.to_string(), rect)),
            }
        });
    }

    /// Where the widget called `label` was last drawn: `[x, y, width, height]` in CSS pixels
    /// of the canvas.
    pub fn widget_rect(label: &str) -> Option<[f32; 4]> {
        WIDGETS.with(|w| w.borrow().iter().find(|(l, _)| l == label).map(|e| e.1))
    }

    /// Calls `look` on the page's main thread every `interval` while it returns `true`.
    pub fn every(interval: web_time::Duration, mut look: impl FnMut() -> bool + 'static) {
        let ms = i32::try_from(interval.as_millis()).unwrap_or(i32::MAX);
        wasm_bindgen_futures::spawn_local(async move {
            while look() {
                let wait = js_sys::Promise::new(&mut |resolve, _| {
                    if let Some(w) = web_sys::window() {
                        let _ =
                            w.set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, ms);
                    }
                });
                if wasm_bindgen_futures::JsFuture::from(wait).await.is_err() {
                    return;
                }
            }
        });
    }

    fn js_err(e: JsValue) -> String {
        e.as_string().unwrap_or_else(|| format!("{e:?}"))
    }

    /// Offers `contents` as a file download named `name`.
    ///
    /// # Errors
    ///
    /// What the browser refused (no document, no blob URL), as one line.
    pub fn download(name: &str, mime: &str, contents: &[u8]) -> Result<(), String> {
        let window = web_sys::window().ok_or("no window")?;
        let document = window.document().ok_or("no document")?;
        let parts = js_sys::Array::new();
        parts.push(&js_sys::Uint8Array::from(contents));
        let options = web_sys::BlobPropertyBag::new();
        options.set_type(mime);
        let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options)
            .map_err(js_err)?;
        let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(js_err)?;
        let a: web_sys::HtmlAnchorElement = document
            .create_element("a")
            .map_err(js_err)?
            .dyn_into()
            .map_err(|_| "not an anchor".to_string())?;
        a.set_href(&url);
        a.set_download(name);
        a.click();
        web_sys::Url::revoke_object_url(&url).map_err(js_err)?;
        Ok(())
    }

    /// Opens the browser's file dialog; the chosen file arrives in `inbox`, and `ctx` is asked
    /// to repaint so the app sees it.
    ///
    /// # Errors
    ///
    /// What the browser refused (no document, no file input), as one line.
    pub fn pick_file(inbox: Inbox, ctx: egui::Context, accept: &str) -> Result<(), String> {
        let document = web_sys::window()
            .and_then(|w| w.document())
            .ok_or("no document")?;
        let input: web_sys::HtmlInputElement = document
            .create_element("input")
            .map_err(js_err)?
            .dyn_into()
            .map_err(|_| "not an input".to_string())?;
        input.set_type("file");
        input.set_accept(accept);
        let target = input.clone();
        let on_change = wasm_bindgen::closure::Closure::once(move || {
            let Some(file) = target.files().and_then(|f| f.get(0)) else {
                return;
            };
            wasm_bindgen_futures::spawn_local(async move {
                let name = file.name();
                match wasm_bindgen_futures::JsFuture::from(file.array_buffer()).await {
                    Ok(buf) => inbox.push(name, js_sys::Uint8Array::new(&buf).to_vec()),
                    Err(e) => log_error(&format!("{name}: cannot read the file: {}", js_err(e))),
                }
                ctx.request_repaint();
            });
        });
        input.set_onchange(Some(on_change.as_ref().unchecked_ref()));
        // The dialog may never report back (cancel): the closure lives as long as the page.
        on_change.forget();
        input.click();
        Ok(())
    }

    /// Reads a file dropped on the page (the browser reads files asynchronously): its bytes, or
    /// what went wrong, arrive in `inbox`, and `ctx` is asked to repaint so the app sees them.
    pub fn read_dropped(
        inbox: Inbox,
        ctx: egui::Context,
        name: String,
        file: egui::DroppedFileHandle,
    ) {
        wasm_bindgen_futures::spawn_local(async move {
            match file.bytes_async().await {
                Ok(bytes) => inbox.push(name, bytes),
                Err(e) => inbox.push_failure(format!("{name}: cannot read the file: {e}")),
            }
            ctx.request_repaint();
        });
    }

    fn log_error(msg: &str) {
        web_sys::console::error_1(&msg.into());
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicUsize;
    use std::time::{Duration, Instant};

    use super::*;

    #[test]
    fn the_end_of_a_run_asks_for_a_frame_at_once() {
        let ctx = egui::Context::default();
        let requests = Arc::new(AtomicUsize::new(0));
        let counted = requests.clone();
        ctx.set_request_repaint_callback(move |_| {
            counted.fetch_add(1, Ordering::SeqCst);
        });
        let ended = Arc::new(AtomicBool::new(false));
        repaint_when_set(ended.clone(), ctx);
        std::thread::sleep(5 * END_WATCH_INTERVAL);
        assert_eq!(requests.load(Ordering::SeqCst), 0, "asked before the end");
        ended.store(true, Ordering::Release);
        let t0 = Instant::now();
        while requests.load(Ordering::SeqCst) == 0 {
            assert!(t0.elapsed() < Duration::from_secs(10), "no frame asked for");
            std::thread::sleep(Duration::from_millis(1));
        }
        // It stops looking once it has asked: the watcher's copy of the flag goes.
        while Arc::strong_count(&ended) > 1 {
            assert!(t0.elapsed() < Duration::from_secs(10), "still looking");
            std::thread::sleep(Duration::from_millis(1));
        }
        assert_eq!(requests.load(Ordering::SeqCst), 1);
    }

    #[test]
    fn a_run_that_is_gone_is_no_longer_watched() {
        let ended = Arc::new(AtomicBool::new(false));
        let watched = Arc::downgrade(&ended);
        repaint_when_set(ended, egui::Context::default());
        // Only the watcher holds the flag now: it lets go without asking for anything.
        let t0 = Instant::now();
        while watched.strong_count() > 0 {
            assert!(t0.elapsed() < Duration::from_secs(10), "still looking");
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}
