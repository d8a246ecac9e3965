//! The bvseg.volumes/1 reader, and the verifier on whatever it accepts (against a small
//! fixed mesh, on a small grid).
#![no_main]
use bvseg_core::verify::{verify, VerifyOptions};
use bvseg_core::shapes;
use glam::{DMat3, DVec3};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match bvseg_io::parse_volumes(data, "fuzz.json") {
        Ok(file) => {
            let mesh = shapes::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), DMat3::IDENTITY);
            let opts = VerifyOptions {
                points: 2000,
                fractions: Some(file.fractions.clone()),
                ..VerifyOptions::default()
            };
            let _ = verify(&mesh, &file.volumes, &opts);
        }
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
});
