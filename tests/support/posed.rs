//! The check every skinned-character test makes: each triangle's corners lie in its part's
//! volume at rest and, in every sampled pose, in that volume moved by the part's bone,
//! G(t) * G(rest)^-1.
#![allow(dead_code)]
use bvseg::{Mesh, Segmentation};

pub fn assert_enclosed_at_rest_and_in_every_pose(mesh: &Mesh, seg: &Segmentation, what: &str) {
    let skin = mesh.rig().and_then(|r| r.skin.as_ref()).expect("a skin");
    let skeleton = seg.skeleton.as_ref().expect("the parts' skeleton");
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let part = &seg.parts[seg.triangle_parts[t] as usize];
        for &v in tri {
            assert!(
                part.volume.contains(mesh.vertices()[v as usize]),
                "{what}: triangle {t} at rest"
            );
        }
    }
    for pose in &skin.poses {
        for (t, corners) in skin.corners.iter().enumerate() {
            let part = &seg.parts[seg.triangle_parts[t] as usize];
            let b = part.bone.expect("every part of a skinned mesh has a bone");
            let back = skeleton.joints[b].rest * pose.joints[b].inverse();
            for &c in corners {
                let p = back.transform_point3(pose.vertices[c as usize]);
                assert!(
                    part.volume.contains(p),
                    "{what}: triangle {t} leaves its volume at t = {}",
                    pose.time
                );
            }
        }
    }
}
