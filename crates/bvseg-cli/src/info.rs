//! `bvseg info`: what the loader sees in a mesh, without segmenting it.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use serde_json::json;

use crate::common::{self, InputArgs};
use crate::segment::write_stdout;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file (.obj, .gltf, .glb, .stl).
    #[arg(value_name = "MESH")]
    pub mesh: PathBuf,

    #[command(flatten)]
    pub input: InputArgs,

    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &InfoArgs) -> anyhow::Result<ExitCode> {
    let (name, loaded) = common::load(Some(&args.mesh), &args.input, true)?;
    let (s, r) = (loaded.stats, loaded.report);
    let mut warnings = loaded.warnings();
    if loaded.encloses_no_volume() {
        warnings.push("encloses no volume (flat or open): it cannot be segmented".into());
    }
    if args.json {
        let doc = json!({
            "mesh": name,
            "triangles": r.triangles,
            "vertices": r.vertices,
            "vertices_read": s.vertices_read,
            "welded": s.welded,
            "triangles_read": s.triangles_read,
            "degenerate": s.degenerate,
            "components": r.components,
            "open_edges": r.open_edges,
            "non_manifold_edges": r.non_manifold_edges,
            "duplicate_faces": r.duplicate_faces,
            "flipped": r.flipped,
            "volume": r.volume,
            "bbox": [r.bbox_min.to_array(), r.bbox_max.to_array()],
            "warnings": warnings,
        });
        let mut doc = doc;
        if let Some(c) = loaded.character {
            doc["skins"] = c.skins.into();
            doc["joints"] = c.joints.into();
            doc["animations"] = c.animations.into();
            doc["poses"] = c.poses.into();
        }
        write_stdout(&format!("{doc}\n"))?;
    } else {
        let mut t = format!(
            "mesh          {name}\n\
             triangles     {} ({} read, {} degenerate dropped)\n\
             vertices      {} ({} read, {} welded)\n\
             components    {}\n\
             open edges    {}\n\
             non-manifold  {}\n\
             duplicates    {}\n\
             orientation   {}\n\
             volume        {}\n\
             bbox          [{} {} {}] .. [{} {} {}]\n",
            r.triangles,
            s.triangles_read,
            s.degenerate,
            r.vertices,
            s.vertices_read,
            s.welded,
            r.components,
            r.open_edges,
            r.non_manifold_edges,
            r.duplicate_faces,
            if r.flipped {
                "inward, reversed"
            } else {
                "outward"
            },
            r.volume,
            r.bbox_min.x,
            r.bbox_min.y,
            r.bbox_min.z,
            r.bbox_max.x,
            r.bbox_max.y,
            r.bbox_max.z,
        );
        if let Some(c) = loaded.character {
            t.push_str(&format!(
                "skins         {}\njoints        {}\nanimations    {} ({} poses sampled)\n",
                c.skins, c.joints, c.animations, c.poses
            ));
        }
        for w in &warnings {
            t.push_str(&format!("warning       {w}\n"));
        }
        write_stdout(&t)?;
    }
    Ok(ExitCode::SUCCESS)
}
