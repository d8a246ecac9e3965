//! The viewer's panels driven as a user would, through AccessKit (egui_kittest): change the
//! controls, run, and check what the app did.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::cell::RefCell;
use std::rc::Rc;

use bvseg_core::{Kinds, Params, Shape, Target};
use bvseg_viewer::app::{Export, StartMesh, StartOptions, Status, ViewerApp};
use bvseg_viewer::platform::Report;
use eframe::egui::accesskit::Role;
use eframe::egui::Key;
use egui_kittest::kittest::Queryable;
use egui_kittest::{Harness, Node};

fn harness(mesh: &str) -> (Harness<'static, ViewerApp>, Rc<RefCell<Vec<Report>>>) {
    let reports = Rc::new(RefCell::new(Vec::new()));
    let sink = reports.clone();
    let app = ViewerApp::new(StartOptions {
        mesh: StartMesh::Bundled(mesh.into()),
        autorun: false,
        kinds: None,
        reporter: Some(Box::new(move |r: &Report| {
            sink.borrow_mut().push(r.clone())
        })),
        ..StartOptions::default()
    });
    let h = Harness::builder()
        .with_size([1280.0, 900.0])
        .build_ui_state(|ui, app: &mut ViewerApp| app.ui(ui), app);
    (h, reports)
}

/// Types `text` into the widget labelled `label`, focusing it first.
fn type_into(h: &Harness<'_, ViewerApp>, label: &str, text: &str) {
    let node = h.get_by_label(label);
    node.focus();
    node.type_text(text);
}

/// Presses `keys` one after the other in the widget `node`, focusing it first.
fn press_keys(h: &Harness<'_, ViewerApp>, node: Node<'_>, keys: &[Key]) {
    node.focus();
    for &key in keys {
        h.key_press(key);
    }
}

/// The slider labelled `label` (egui labels the slider and the value field beside it alike).
fn slider<'h>(h: &'h Harness<'_, ViewerApp>, label: &'h str) -> Node<'h> {
    h.get_by_role_and_label(Role::Slider, label)
}

/// Types `text` into the DragValue labelled `label` (a click selects its text).
fn enter(h: &mut Harness<'_, ViewerApp>, label: &str, text: &str) {
    h.get_by_label(label).click();
    h.run_steps(2);
    type_into(h, label, text);
    h.run_steps(1);
    press_keys(h, h.get_by_label(label), &[Key::Enter]);
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
    // Boxes only: untick the other kinds of the default.
    for label in ["Ellipsoids", "Spheres", "Capsules", "Cylinders"] {
        h.get_by_label(label).click();
        h.run_steps(1);
    }
    h.get_by_label("Fixed k").click();
    h.run_steps(2);
    enter(&mut h, "k", "5");
    enter(&mut h, "Samples", "4000");
    enter(&mut h, "Seed", "7");
    let s = h.state().settings().clone();
    assert_eq!(s.kinds, Kinds::OBB);
    assert_eq!(s.params().kinds, Kinds::OBB);
    assert!(s.fixed_k);
    assert_eq!((s.k, s.samples, s.seed), (5, 4000, 7));

    h.get_by_label("Run").click();
    h.step();
    // Started: a run of 4000 samples in the background may already be over on an idle
    // machine.
    assert!(
        matches!(*h.state().status(), Status::Running | Status::Done),
        "{:?}",
        h.state().status()
    );
    run_to_end(&mut h);
    assert_eq!(*h.state().status(), Status::Done);
    let res = h.state().result().expect("a result");
    assert_eq!(res.metrics.k, 5);
    assert!(res.parts.iter().all(|p| p.volume.shape == Shape::Obb));
    assert!(res.metrics.samples > 3000 && res.metrics.samples < 5000);

    // The statistics name the run's kinds, the parts table each part's shape and size.
    h.get_by_label("Kinds");
    assert!(!h.query_all_by_label("obb").collect::<Vec<_>>().is_empty());
    h.get_by_label("5 obb");

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
    slider(&h, "History step").focus();
    h.run_steps(1);
    for _ in 0..n {
        press_keys(&h, slider(&h, "History step"), &[Key::ArrowLeft]);
        h.run_steps(1);
    }
    assert_eq!(h.state().shown_step(), Some(0));
    h.get_by_label("Latest").click();
    h.run_steps(2);
    assert_eq!(h.state().shown_step(), Some(n - 1));

    // Result -> Save GLB… asks for a path and writes the file there.
    // The app runs without the hierarchy; the JSON export builds it.
    assert!(result_of(&h).hierarchy.is_empty());
    let json = h.state_mut().export_bytes(Export::Json).unwrap();
    let nodes = 2 * result_of(&h).parts.len() - 1;
    assert_eq!(result_of(&h).hierarchy.len(), nodes);
    assert_eq!(json, bvseg_io::to_json_string(result_of(&h)).into_bytes());
    let dir = bvseg_testkit::scratch("controls_change_the_run_and_the_parts_table_highlights");
    let out = dir.join("dog.glb");
    h.get_by_label("Result").click();
    h.run_steps(2);
    h.get_by_label("Save GLB…").click();
    h.run_steps(2);
    let field = "Write the mesh and the volumes (binary glTF) to:";
    h.get_by_label(field).focus();
    h.run_steps(1);
    // The field holds a default name, with the cursor at its end: clear it.
    press_keys(&h, h.get_by_label(field), &[Key::Backspace; 40]);
    h.run_steps(1);
    type_into(&h, field, out.to_str().unwrap());
    h.run_steps(1);
    h.get_by_label("Save").click();
    h.run_steps(2);
    let glb =
        std::fs::read(&out).unwrap_or_else(|e| panic!("no GLB ({e}): {:?}", h.state().status()));
    assert_eq!(glb, h.state_mut().export_bytes(Export::Glb).unwrap());
    assert_eq!(&glb[..4], b"glTF");
    // The GLB holds the segmented mesh, which reads back whole.
    let options = bvseg_io::LoadOptions {
        mesh: Some("input_mesh".into()),
        ..Default::default()
    };
    let back = bvseg_io::load_bytes(&glb, "dog.glb", &options).unwrap();
    assert_eq!(
        back.mesh.triangles().len(),
        h.state().result().unwrap().triangle_parts.len()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_kinds_control_sets_the_runs_kinds() {
    let (mut h, _) = harness("bunny");
    h.run_steps(2);
    // The default is the core's.
    let s = h.state().settings().clone();
    assert_eq!(s.kinds, Params::default().kinds);
    assert_eq!(s.kinds, Kinds::PRIMITIVES);
    assert_eq!(
        s.params(),
        Params {
            hierarchy: false,
            ..Params::default()
        },
        "the default settings are the core's defaults (but for the hierarchy, built on export)"
    );
    assert!(
        h.query_by_label("Max hull vertices").is_none(),
        "no hulls, no slider"
    );
    assert_eq!(preset_shown(&h), "primitives (default)");

    // Ticking hulls adds them and shows their vertex limit.
    h.get_by_label("Hulls").click();
    h.run_steps(2);
    let p = h.state().settings().params();
    assert_eq!(p.kinds, Kinds::PRIMITIVES.with(Shape::Hull));
    assert_eq!(p.max_hull_vertices, 32);
    assert_eq!(preset_shown(&h), "primitives + hull");
    slider(&h, "Max hull vertices").focus();
    h.run_steps(1);
    for _ in 0..3 {
        press_keys(&h, slider(&h, "Max hull vertices"), &[Key::ArrowRight]);
        h.run_steps(1);
    }
    assert_eq!(h.state().settings().params().max_hull_vertices, 35);

    // A preset replaces the set.
    choose_preset(&mut h, "gltf / parry / physx / usd");
    assert_eq!(h.state().settings().params().kinds, Target::Parry.kinds());
    assert!(h.query_by_label("Max hull vertices").is_none());
    choose_preset(&mut h, "paper: ellipsoid");
    assert_eq!(h.state().settings().params().kinds, Kinds::ELLIPSOID);

    // The only kind ticked stays ticked.
    h.get_by_label("Ellipsoids").click();
    h.run_steps(2);
    assert_eq!(h.state().settings().kinds, Kinds::ELLIPSOID);
    h.get_by_label("Boxes").click();
    h.run_steps(2);
    assert_eq!(h.state().settings().params().kinds, Kinds::MIXED);
    assert_eq!(preset_shown(&h), "custom");
    h.get_by_label("Ellipsoids").click();
    h.run_steps(2);
    assert_eq!(h.state().settings().params().kinds, Kinds::OBB);
    choose_preset(&mut h, "mujoco + hull");
    let k = h.state().settings().params().kinds;
    assert_eq!(k, Target::Mujoco.kinds().with(Shape::Hull));
    assert!(Shape::ALL.into_iter().all(|s| k.contains(s)));

    // Settings made in code map the same way.
    let mut s = bvseg_viewer::Settings::default();
    s.set_kind(Shape::Obb, false);
    s.set_kind(Shape::Hull, true);
    s.max_hull_vertices = 64;
    let p = s.params();
    let expect: Kinds = "ellipsoid,sphere,capsule,cylinder,hull".parse().unwrap();
    assert_eq!((p.kinds, p.max_hull_vertices), (expect, 64));
    assert!(p.validate().is_ok());
}

/// The preset combo's text.
fn preset_shown(h: &Harness<'_, ViewerApp>) -> String {
    let combo = h.get_by_role_and_label(Role::ComboBox, "Preset");
    combo.value().unwrap_or_default()
}

/// Opens the preset combo and picks `name`.
fn choose_preset(h: &mut Harness<'_, ViewerApp>, name: &str) {
    // A click toggles the menu; egui may still count it open after the last choice.
    for _ in 0..2 {
        h.get_by_role_and_label(Role::ComboBox, "Preset").click();
        h.run_steps(2);
        if h.query_by_label(name).is_some() {
            break;
        }
    }
    h.get_by_label(name).click();
    h.run_steps(2);
    // The combo names the first preset of the set (mujoco's is the default's).
    let first = bvseg_viewer::kinds::preset_name(h.state().settings().kinds);
    assert_eq!(preset_shown(h), first);
    assert!(
        name == first || name.starts_with("mujoco"),
        "{name}: {first}"
    );
}

#[test]
fn the_start_kinds_are_read_as_the_cli_reads_them() {
    let app = |kinds: &str| {
        ViewerApp::new(StartOptions {
            mesh: StartMesh::Bundled("bunny".into()),
            autorun: true,
            kinds: Some(kinds.into()),
            ..StartOptions::default()
        })
    };
    assert_eq!(
        app("obb,capsule").settings().kinds,
        Kinds::OBB.with(Shape::Capsule)
    );
    assert_eq!(app("mixed").settings().kinds, Kinds::MIXED);
    assert_eq!(
        app("parry-hull").settings().kinds,
        Target::Parry.kinds().with(Shape::Hull)
    );
    let bad = app("torus");
    let Status::Failed(msg) = bad.status() else {
        panic!("expected a failure: {:?}", bad.status());
    };
    assert!(msg.contains("torus"), "{msg}");
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

/// `mesh` as a binary STL file: unshared corners, as STL stores them.
fn stl_bytes(mesh: &bvseg_core::Mesh) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(mesh.triangles().len() as u32).to_le_bytes());
    for t in mesh.triangles() {
        let p = t.map(|i| mesh.vertices()[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for v in [n, p[0], p[1], p[2]] {
            for c in v.to_array() {
                b.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

/// `mesh` as a minimal GLB file: one indexed primitive, shared vertices.
fn glb_bytes(mesh: &bvseg_core::Mesh) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    for v in mesh.vertices() {
        for c in v.to_array() {
            bin.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let positions = bin.len();
    for i in mesh.triangles().iter().flatten() {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let (lo, hi) = mesh.bbox();
    let f32s = |v: glam::DVec3| v.to_array().map(|c| c as f32);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"name": "model", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": mesh.vertices().len(), "type": "VEC3",
             "min": f32s(lo), "max": f32s(hi)},
            {"bufferView": 1, "componentType": 5125, "count": 3 * mesh.triangles().len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions},
            {"buffer": 0, "byteOffset": positions, "byteLength": bin.len() - positions}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    let mut json = serde_json::to_vec(&json).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((28 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Opens `path` as a user would natively: Mesh -> Open file…, type the path, Open.
fn open_through_dialog(h: &mut Harness<'_, ViewerApp>, path: &std::path::Path) {
    // "Mesh" also heads a row of the statistics: the menu is the button.
    h.get_by_role_and_label(Role::Button, "Mesh").click();
    h.run_steps(2);
    h.get_by_label("Open file…").click();
    h.run_steps(2);
    let field = "Path of a mesh file (.obj, .gltf, .glb, .stl):";
    h.get_by_label(field).focus();
    h.run_steps(1);
    type_into(h, field, path.to_str().unwrap());
    h.run_steps(1);
    h.get_by_label("Open").click();
    h.run_steps(2);
}

#[test]
fn glb_and_stl_files_open_through_the_dialog_and_run() {
    let bunny = bvseg_viewer::meshes::load_bundled(&bvseg_viewer::BUNDLED[0]).unwrap();
    let dir = bvseg_testkit::scratch("glb_and_stl_files_open_through_the_dialog_and_run");
    let (mut h, _) = harness("spot");
    h.run_steps(2);
    h.get_by_label("Fixed k").click();
    h.run_steps(2);
    enter(&mut h, "k", "3");
    enter(&mut h, "Samples", "3000");

    for (file, bytes) in [
        ("bunny.glb", glb_bytes(&bunny)),
        ("bunny.stl", stl_bytes(&bunny)),
    ] {
        let path = dir.join(file);
        std::fs::write(&path, bytes).unwrap();
        open_through_dialog(&mut h, &path);
        assert_eq!(
            h.state().mesh_name(),
            Some(file),
            "{:?}",
            h.state().status()
        );
        assert_eq!(*h.state().status(), Status::Idle);
        h.get_by_label("Run").click();
        h.step();
        run_to_end(&mut h);
        let res = result_of(&h);
        assert_eq!(res.metrics.k, 3, "{file}");
        assert_eq!(res.triangle_parts.len(), bunny.triangles().len(), "{file}");
        assert!(
            res.metrics.tov.is_finite() && res.metrics.tov > 0.0,
            "{file}"
        );
    }
    // STL stores every triangle's corners apart: loading welds them, and the UI says so.
    let warnings = h.state().load_warnings().to_vec();
    assert!(
        warnings.iter().any(|w| w.starts_with("welded ")),
        "{warnings:?}"
    );
    h.get_by_label_contains("Warning: welded ");

    // A glTF whose buffer is a separate file cannot be read from its bytes alone.
    let gltf = br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"bunny.bin","byteLength":12}]}"#;
    h.state_mut().load_bytes("bunny.gltf", gltf);
    h.run_steps(2);
    let Status::Failed(msg) = h.state().status().clone() else {
        panic!("expected a failure: {:?}", h.state().status());
    };
    assert!(
        msg.contains("bunny.gltf") && msg.contains("external") && msg.contains(".glb"),
        "{msg}"
    );
    h.get_by_label(&msg);
    assert_eq!(h.state().mesh_name(), Some("bunny.stl"), "the mesh is kept");
    std::fs::remove_dir_all(&dir).unwrap();
}
