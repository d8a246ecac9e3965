//! Segment a mesh, build the parry3d compound of its volumes and count the mesh vertices
//! inside it: `cargo run --release --features parry --example parry_compound -- MESH [KINDS]`
//! (KINDS: a `--bv` list or a `--target` name; default: the parry target's kinds).
use std::process::ExitCode;

use parry3d::math::{Pose, Vector};

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("parry_compound: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<ExitCode, Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: parry_compound MESH [KINDS or TARGET]")?;
    let kinds = match args.next() {
        None => bvseg::Target::Parry.kinds(),
        Some(s) => match bvseg::Target::kinds_of(&s) {
            Some(k) => k,
            None => s.parse::<bvseg::Kinds>()?,
        },
    };
    let loaded = bvseg::io::load(&path, &bvseg::io::LoadOptions::default())?;
    let params = bvseg::Params {
        kinds,
        ..Default::default()
    };
    let seg = bvseg::segment(&loaded.mesh, &params)?;
    let compound = bvseg::parry::to_compound(&seg);

    let vertices = loaded.mesh.vertices();
    let inside = vertices
        .iter()
        .filter(|v| {
            let p = v.as_vec3();
            compound.contains_point(&Pose::IDENTITY, Vector::new(p.x, p.y, p.z))
        })
        .count();
    println!(
        "{path}: {} parts ({}), compound of {} shapes",
        seg.parts.len(),
        kinds,
        bvseg::parry::to_shapes(&seg).len()
    );
    println!("inside: {inside} of {} vertices", vertices.len());
    Ok(if inside == vertices.len() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
