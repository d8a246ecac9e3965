//! The viewer's panels driven as a user would, through AccessKit (egui_kittest): change the
//! controls, run, and check what the app did.
use std::cell::RefCell;
use std::rc::Rc;

use bvseg_core::{BoundingKind, Shape};
use bvseg_viewer::app::{Export, StartMesh, StartOptions, Status, ViewerApp};
use bvseg_viewer::platform::Report;
use egui_kittest::kittest::{Key, Queryable};
use egui_kittest::Harness;

fn harness(mesh: &str) -> (Harness<'static, ViewerApp>, Rc<RefCell<Vec<Report>>>) {
    let reports = Rc::new(RefCell::new(Vec::new()));
    let sink = reports.clone();
    let app = ViewerApp::new(StartOptions {
        mesh: StartMesh::Bundled(mesh.into()),
        autorun: false,
        reporter: Some(Box::new(move |r: &Report| {
            sink.borrow_mut().push(r.clone())
        })),
    });
    let h = Harness::builder()
        .with_size([1280.0, 900.0])
        .build_state(|ctx, app: &mut ViewerApp| app.ui(ctx), app);
    (h, reports)
}

/// Types `text` into the DragValue labelled `label` (a click selects its text).
fn enter(h: &mut Harness<'_, ViewerApp>, label: &str, text: &str) {
    h.get_by_label(label).click();
    h.run_steps(2);
    h.get_by_label(label).type_text(text);
    h.run_steps(1);
    h.get_by_label(label).press_keys(&[Key::Enter]);
    h.run_steps(2);
}

/// Steps frames until the run is over.
fn run_to_end(h: &mut Harness<'_, ViewerApp>) {
    for _ in 0..5000 {
        if *h.state().status() != Status::Running {
            return;
        }
        h.step();
    }
    panic!("the run did not end");
}

#[test]
fn controls_change_the_run_and_the_parts_table_highlights() {
    let (mut h, reports) = harness("fourleg_2");
    h.run_steps(2);
    assert_eq!(h.state().mesh_name(), Some("fourleg_2.obj"));
    h.get_by_label("Boxes").click();
    h.get_by_label("Fixed k").click();
    h.run_steps(2);
    enter(&mut h, "k", "5");
    enter(&mut h, "Samples", "4000");
    enter(&mut h, "Seed", "7");
    let s = h.state().settings().clone();
    assert_eq!(s.bounding, BoundingKind::Obb);
    assert!(s.fixed_k);
    assert_eq!((s.k, s.samples, s.seed), (5, 4000, 7));

    h.get_by_label("Run").click();
    h.step();
    assert_eq!(*h.state().status(), Status::Running);
    run_to_end(&mut h);
    assert_eq!(*h.state().status(), Status::Done);
    let res = h.state().result().expect("a result");
    assert_eq!(res.metrics.k, 5);
    assert!(res.parts.iter().all(|p| p.volume.shape == Shape::Obb));
    assert!(res.metrics.samples > 3000 && res.metrics.samples < 5000);

    // The reporter got the page's summary for this run.
    let last = reports.borrow().last().cloned();
    let Some(Report::Done(json)) = last else {
        panic!("no summary: {last:?}");
    };
    assert!(
        json.starts_with(&format!("{{\"k\":5,\"tov\":{},", res.metrics.tov)),
        "{json}"
    );
    assert!(
        json.contains("\"kind\":\"obb\"") && json.contains("\"met\":null"),
        "{json}"
    );

    // Clicking a row of the parts table highlights that part; clicking again clears it.
    h.run_steps(2);
    h.get_by_label("Part 3").click();
    h.run_steps(2);
    assert_eq!(h.state().selected_part(), Some(3));
    h.get_by_label("Part 3").click();
    h.run_steps(2);
    assert_eq!(h.state().selected_part(), None);

    // The history slider steps back to the first step.
    let n = h.state().session().unwrap().snapshots().len();
    assert_eq!(h.state().shown_step(), Some(n - 1));
    h.get_by_label("History step").focus();
    h.run_steps(1);
    for _ in 0..n {
        h.get_by_label("History step").press_keys(&[Key::ArrowLeft]);
        h.run_steps(1);
    }
    assert_eq!(h.state().shown_step(), Some(0));
    h.get_by_label("Latest").click();
    h.run_steps(2);
    assert_eq!(h.state().shown_step(), Some(n - 1));

    // Result -> Save GLB… asks for a path and writes the file there.
    let json = h.state().export_bytes(Export::Json).unwrap();
    assert_eq!(json, bvseg_io::to_json_string(result_of(&h)).into_bytes());
    let dir = std::env::temp_dir().join(format!("bvseg-viewer-panels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("dog.glb");
    h.get_by_label("Result").click();
    h.run_steps(2);
    h.get_by_label("Save GLB…").click();
    h.run_steps(2);
    let field = "Write the mesh and the volumes (binary glTF) to:";
    h.get_by_label(field).focus();
    h.run_steps(1);
    // The field holds a default name, with the cursor at its end: clear it.
    h.get_by_label(field).press_keys(&[Key::Backspace; 40]);
    h.run_steps(1);
    h.get_by_label(field).type_text(out.to_str().unwrap());
    h.run_steps(1);
    h.get_by_label("Save").click();
    h.run_steps(2);
    let glb =
        std::fs::read(&out).unwrap_or_else(|e| panic!("no GLB ({e}): {:?}", h.state().status()));
    assert_eq!(glb, h.state().export_bytes(Export::Glb).unwrap());
    assert_eq!(&glb[..4], b"glTF");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn result_of<'a>(h: &'a Harness<'_, ViewerApp>) -> &'a bvseg_core::Segmentation {
    h.state().result().unwrap()
}

#[test]
fn cancel_stops_a_run_and_a_bad_start_mesh_is_reported() {
    let (mut h, _) = harness("bunny");
    h.run_steps(2);
    h.get_by_label("Run").click();
    h.step();
    assert_eq!(*h.state().status(), Status::Running);
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert_eq!(*h.state().status(), Status::Cancelled);
    assert!(h.state().result().is_none());

    let (mut h, reports) = harness("teapot");
    h.run_steps(2);
    let Status::Failed(msg) = h.state().status().clone() else {
        panic!("expected a failure");
    };
    assert!(msg.contains("teapot") && msg.contains("bunny"), "{msg}");
    assert_eq!(*reports.borrow(), vec![Report::Error(msg)]);
}

#[test]
fn dropped_files_are_loaded_through_the_same_reader() {
    let (mut h, _) = harness("bunny");
    h.run_steps(1);
    h.state_mut().load_bytes(
        "tiny.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    );
    h.run_steps(1);
    assert_eq!(h.state().mesh_name(), Some("tiny.obj"));
    h.state_mut().load_bytes("notes.txt", b"hello");
    h.run_steps(1);
    assert!(matches!(h.state().status(), Status::Failed(m) if m.contains("notes.txt")));
    assert_eq!(
        h.state().mesh_name(),
        Some("tiny.obj"),
        "a bad file keeps the mesh"
    );
}
