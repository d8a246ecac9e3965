//! Low-poly game assets (open, thin, made of pieces) take the surface route: few volumes,
//! every triangle enclosed, a character's volumes capped per bone and following its bones.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#[path = "support/posed.rs"]
mod posed;

use bvseg::{segment, Params, Route};
use bvseg_io::{load, LoadOptions};

fn asset(name: &str) -> bvseg_io::LoadedMesh {
    let path = format!("{}/assets/game/{name}", env!("CARGO_MANIFEST_DIR"));
    load(&path, &LoadOptions::default()).unwrap()
}

/// Every triangle's corners lie in the volume of its part.
fn assert_every_triangle_enclosed(mesh: &bvseg::Mesh, seg: &bvseg::Segmentation) {
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let v = &seg.parts[seg.triangle_parts[t] as usize].volume;
        for &c in tri {
            assert!(v.contains(mesh.vertices()[c as usize]), "triangle {t}");
        }
    }
}

#[test]
fn a_building_of_open_pieces_gets_a_few_boxes_within_the_tolerance() {
    let loaded = asset("building-small-b.glb");
    let params = Params::default();
    let seg = segment(&loaded.mesh, &params).unwrap();
    assert_eq!(seg.route, Route::Surface);
    assert!(seg.parts.len() <= 8, "{} volumes", seg.parts.len());
    assert_eq!(seg.tolerances_met(&params), Some(true), "{:?}", seg.metrics);
    assert_every_triangle_enclosed(&loaded.mesh, &seg);
    let sum: f64 = seg.parts.iter().map(|p| p.fraction).sum();
    assert!((sum - 1.0).abs() < 1e-9);
}

#[test]
fn a_road_tile_is_one_volume() {
    let loaded = asset("road-straight.glb");
    let seg = segment(&loaded.mesh, &Params::default()).unwrap();
    assert_eq!(seg.parts.len(), 1);
    assert_every_triangle_enclosed(&loaded.mesh, &seg);
}

#[test]
fn max_k_is_a_hard_cap_on_the_surface_route() {
    let loaded = asset("grass-trees.glb");
    let params = Params {
        max_k: 5,
        ..Params::default()
    };
    let seg = segment(&loaded.mesh, &params).unwrap();
    assert!(seg.parts.len() <= 5, "{} volumes", seg.parts.len());
    assert_every_triangle_enclosed(&loaded.mesh, &seg);
}

#[test]
fn the_lattice_route_can_still_be_asked_for() {
    let loaded = asset("road-straight.glb");
    let params = Params {
        route: Route::Lattice,
        ..Params::default()
    };
    let seg = segment(&loaded.mesh, &params).unwrap();
    assert_eq!(seg.route, Route::Lattice);
    assert!(seg.metrics.samples > 0);
    assert_every_triangle_enclosed(&loaded.mesh, &seg);
}

/// The bones that move triangles: each triangle's, by the largest sum of its corners' weights.
fn moving_bones(mesh: &bvseg::Mesh) -> usize {
    let skin = mesh.rig().unwrap().skin.as_ref().unwrap();
    let mut bones: Vec<u32> = mesh
        .triangles()
        .iter()
        .map(|tri| {
            let mut w: Vec<(u32, f64)> = Vec::new();
            for &v in tri {
                for &(j, x) in &skin.weights[v as usize] {
                    match w.iter_mut().find(|e| e.0 == j) {
                        Some(e) => e.1 += f64::from(x),
                        None => w.push((j, f64::from(x))),
                    }
                }
            }
            w.iter()
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
                .unwrap()
                .0
        })
        .collect();
    bones.sort_unstable();
    bones.dedup();
    bones.len()
}

#[test]
fn a_character_per_bone_1_is_a_ragdoll_that_follows_every_pose() {
    let loaded = asset("character-male-b.glb");
    let bones = moving_bones(&loaded.mesh);
    assert!(bones >= 5, "{bones} moving bones");
    let params = Params {
        per_bone: Some(1),
        ..Params::default()
    };
    let seg = segment(&loaded.mesh, &params).unwrap();
    assert_eq!(seg.parts.len(), bones);
    posed::assert_enclosed_at_rest_and_in_every_pose(&loaded.mesh, &seg, "per bone 1");

    let seg = segment(&loaded.mesh, &Params::default()).unwrap();
    assert!(
        seg.parts.len() > bones && seg.parts.len() <= 3 * bones,
        "{}",
        seg.parts.len()
    );
    posed::assert_enclosed_at_rest_and_in_every_pose(&loaded.mesh, &seg, "default");
}
