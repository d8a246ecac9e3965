//! A character's animation played in the viewer as a user would play it (egui_kittest): open
//! the character, run, press Play, move the time slider; the view draws the mesh in the pose
//! shown and every volume moved with its bone, and the posed surface stays inside the moved
//! volumes.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use bvseg_core::Mesh;
use bvseg_viewer::animation::motions;
use bvseg_viewer::app::{StartMesh, StartOptions, Status, ViewerApp};
use bvseg_viewer::scene::{volume_triangles, VERTEX_FLOATS};
use eframe::egui::accesskit::Role;
use eframe::egui::Key;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::{DMat4, DVec3, Vec3};

const CESIUM_MAN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../assets/characters/CesiumMan.glb"
);

fn harness(mesh: &str) -> Harness<'static, ViewerApp> {
    let app = ViewerApp::new(StartOptions {
        mesh: StartMesh::Bundled(mesh.into()),
        ..StartOptions::default()
    });
    Harness::builder()
        .with_size([1280.0, 900.0])
        .build_ui_state(|ui, app: &mut ViewerApp| app.ui(ui), app)
}

/// Types `text` into the DragValue labelled `label` (a click selects its text).
fn enter(h: &mut Harness<'_, ViewerApp>, label: &str, text: &str) {
    h.get_by_label(label).click();
    h.run_steps(2);
    let node = h.get_by_label(label);
    node.focus();
    node.type_text(text);
    h.run_steps(1);
    h.get_by_label(label).focus();
    h.key_press(Key::Enter);
    h.run_steps(2);
}

/// Runs with `samples` and steps frames until the run is over.
fn run(h: &mut Harness<'_, ViewerApp>, samples: &str) {
    enter(h, "Samples", samples);
    h.get_by_label("Run").click();
    h.step();
    for _ in 0..5000 {
        if *h.state().status() != Status::Running {
            assert_eq!(*h.state().status(), Status::Done);
            return;
        }
        h.step();
    }
    panic!("the run did not end");
}

/// What the view drew in the last frame, against what it should show: the mesh in the pose
/// shown (or at rest), each volume moved by its bone. Returns each volume's drawn centroid.
fn check_drawn(app: &ViewerApp) -> Vec<DVec3> {
    let mesh: &Mesh = app.session().expect("a run").mesh();
    let res = app.result().expect("a result");
    let rig = mesh.rig().expect("a rig");
    let skin = rig.skin.as_ref().expect("a skin");
    let pose = app.player().expect("animation controls").pose();
    let g = app.drawn().expect("a frame");
    let (lo, hi) = mesh.bbox();
    let (center, diagonal) = ((lo + hi) * 0.5, (hi - lo).length());
    let at = |data: &[f32], i: usize| {
        let v = &data[i * VERTEX_FLOATS..];
        Vec3::new(v[0], v[1], v[2]).as_dvec3() + center
    };

    // The mesh: three corners per triangle, as the loader posed them (or at rest).
    let corner = |t: usize, k: usize| match pose {
        Some(p) => skin.poses[p].vertices[skin.corners[t][k] as usize],
        None => mesh.corners(t)[k],
    };
    let triangles = mesh.triangles().len();
    assert_eq!(g.counts()[0], 3 * triangles, "the mesh, opaque");
    for t in 0..triangles {
        for k in 0..3 {
            let d = (at(&g.opaque, 3 * t + k) - corner(t, k)).length();
            assert!(d < 1e-6 * diagonal, "triangle {t} drawn {d} away");
        }
    }

    // Each volume: its drawn surface is the result's volume moved by its bone.
    let moves = match pose {
        Some(p) => motions(
            res.parts.iter().map(|p| p.bone),
            &rig.skeleton,
            &skin.poses[p],
        ),
        None => vec![DMat4::IDENTITY; res.parts.len()],
    };
    let mut first = 0;
    let mut centroids = Vec::new();
    for (part, m) in res.parts.iter().zip(&moves) {
        let v = &part.volume;
        let n = 3 * volume_triangles(v).len();
        let back = m.inverse();
        let mut sum = DVec3::ZERO;
        for i in first..first + n {
            let p = at(&g.translucent, i);
            let q = back.transform_point3(p);
            // f32 positions: on the boundary to within a few millionths of the size.
            let slack = 1e-5 * diagonal / v.radii.min_element().max(1e-9);
            assert!(
                (v.gauge(q) - 1.0).abs() < slack,
                "{:?}: a drawn point at gauge {}",
                v.shape,
                v.gauge(q)
            );
            sum += p;
        }
        centroids.push(sum / n as f64);
        first += n;
    }
    assert_eq!(
        first,
        g.counts()[2],
        "the volumes and nothing else, translucent"
    );

    // Every posed corner lies in its triangle's part's moved volume (the core's guarantee at
    // the sampled poses).
    for t in 0..triangles {
        let part = res.triangle_parts[t] as usize;
        let back = moves[part].inverse();
        for k in 0..3 {
            assert!(
                res.parts[part]
                    .volume
                    .contains(back.transform_point3(corner(t, k))),
                "pose {pose:?}: a corner of triangle {t} is outside part {part}'s volume"
            );
        }
    }
    centroids
}

/// How far the drawn mesh's corners are, at most, from those of `before`.
fn mesh_moved(app: &ViewerApp, before: &[f32]) -> f64 {
    let now = &app.drawn().unwrap().opaque;
    now.chunks(VERTEX_FLOATS)
        .zip(before.chunks(VERTEX_FLOATS))
        .map(|(a, b)| {
            Vec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2])
                .length()
                .into()
        })
        .fold(0.0, f64::max)
}

/// How many of `a`'s points are more than `d` away from `b`'s.
fn moved(a: &[DVec3], b: &[DVec3], d: f64) -> usize {
    a.iter()
        .zip(b)
        .filter(|(p, q)| (**p - **q).length() > d)
        .count()
}

#[test]
fn cesium_man_walks_and_its_volumes_walk_with_it() {
    let mut h = harness("bunny");
    h.run_steps(2);
    // A mesh without a rig has no animation controls.
    assert!(h.state().player().is_none());
    assert!(h.query_by_label("Play").is_none());

    // Mesh -> Open file…, as a user opens the character natively.
    h.get_by_role_and_label(Role::Button, "Mesh").click();
    h.run_steps(2);
    h.get_by_label("Open file…").click();
    h.run_steps(2);
    let field = "Path of a mesh file (.obj, .gltf, .glb, .stl):";
    h.get_by_label(field).focus();
    h.run_steps(1);
    h.get_by_label(field).type_text(CESIUM_MAN);
    h.run_steps(1);
    h.get_by_label("Open").click();
    h.run_steps(2);
    assert_eq!(h.state().mesh_name(), Some("CesiumMan.glb"));
    h.get_by_label("19 joints · 1 animation · 95 poses");
    // Its one animation has no name in the file.
    h.get_by_label("animation 0");
    h.get_by_label("rest pose (as loaded)");

    run(&mut h, "3000");
    let rest_mesh = h.state().drawn().unwrap().opaque.clone();
    let rest = check_drawn(h.state());

    // Play: at real time (egui's frame time; the harness steps a quarter second a frame),
    // through the sampled poses, each drawn as it should be.
    h.get_by_label("Play").click();
    h.run_steps(1);
    assert!(h.state().player().unwrap().playing());
    let t0 = h.state().player().unwrap().time();
    let mut poses = Vec::new();
    let mut most = 0;
    for _ in 0..4 {
        h.step();
        let pose = h.state().player().unwrap().pose().expect("a pose");
        poses.push(pose);
        let centroids = check_drawn(h.state());
        assert!(mesh_moved(h.state(), &rest_mesh) > 0.01, "the mesh walks");
        most = most.max(moved(&centroids, &rest, 0.01));
    }
    let t1 = h.state().player().unwrap().time();
    assert!((t1 - t0 - 1.0).abs() < 1e-6, "{t0} -> {t1}: four frames");
    poses.dedup();
    assert_eq!(poses.len(), 4, "a new pose each quarter second: {poses:?}");
    // The walk swings the limbs: most of the volumes move by more than a centimetre.
    let k = rest.len();
    assert!(most * 2 > k, "{most} of {k} volumes moved");

    // Pause: the pose stays.
    h.get_by_label("Pause").click();
    h.run_steps(1);
    let paused = h.state().player().unwrap().clone();
    h.run_steps(3);
    assert_eq!(*h.state().player().unwrap(), paused);
    assert!(!paused.playing());

    // The time slider picks the pose.
    let slider = h.get_by_role_and_label(Role::Slider, "Time");
    slider.focus();
    h.run_steps(1);
    for _ in 0..10 {
        h.get_by_role_and_label(Role::Slider, "Time").focus();
        h.key_press(Key::ArrowLeft);
        h.run_steps(1);
    }
    let p = h.state().player().unwrap();
    assert!(
        p.time() < paused.time(),
        "{} -> {}",
        paused.time(),
        p.time()
    );
    assert_ne!(p.pose(), paused.pose());
    check_drawn(h.state());

    // Rest pose: the mesh as loaded and the volumes as fitted, again.
    h.get_by_label("Rest pose").click();
    h.run_steps(2);
    assert_eq!(h.state().player().unwrap().pose(), None);
    assert_eq!(h.state().drawn().unwrap().opaque, rest_mesh);
    assert_eq!(check_drawn(h.state()), rest);
}

#[test]
fn the_bundled_character_plays_before_and_after_a_run() {
    let mut h = harness("bunny");
    h.run_steps(2);
    h.get_by_role_and_label(Role::Button, "Mesh").click();
    h.run_steps(2);
    h.get_by_label("RiggedSimple").click();
    h.run_steps(2);
    assert_eq!(h.state().mesh_name(), Some("RiggedSimple.glb"));
    h.get_by_label("Anim_0_Armature");
    let rest_mesh = h.state().drawn().unwrap().opaque.clone();

    // Before a run the mesh plays alone: no volume yet.
    h.get_by_label("Play").click();
    h.run_steps(3);
    assert!(h.state().player().unwrap().pose().is_some());
    assert!(
        mesh_moved(h.state(), &rest_mesh) > 0.1,
        "the cylinder bends"
    );
    assert_eq!(h.state().drawn().unwrap().counts()[2], 0);

    // A run leaves the animation playing; the volumes hide in a pose while it runs (they
    // follow their bones only once it is done), then follow.
    enter(&mut h, "Samples", "2000");
    h.get_by_label("Run").click();
    h.step();
    assert_eq!(*h.state().status(), Status::Running);
    h.get_by_label_contains("The volumes follow the animation once a run is done");
    for _ in 0..5000 {
        if *h.state().status() != Status::Running {
            break;
        }
        // Whatever step the run is at, its volumes are not drawn in a pose.
        assert_eq!(h.state().drawn().unwrap().counts()[2], 0);
        h.step();
    }
    assert_eq!(*h.state().status(), Status::Done);
    h.step();
    assert!(h.state().player().unwrap().playing());
    assert!(h.state().player().unwrap().pose().is_some());
    for _ in 0..3 {
        h.step();
        check_drawn(h.state());
    }
}
