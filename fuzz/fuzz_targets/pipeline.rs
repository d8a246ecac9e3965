//! The whole pipeline on small arbitrary meshes: no panic, no hang, and the union of the
//! output volumes encloses every triangle (checked by the independent verifier). The input
//! format is `pipeline_case` in `tests/support/fuzz_input.rs`, shared with the regression
//! replay.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../../tests/support/fuzz_input.rs"]
mod fuzz_input;

fuzz_target!(|data: &[u8]| {
    if let Some((mesh, params)) = fuzz_input::pipeline_case(data) {
        fuzz_input::check_pipeline(&mesh, &params);
    }
});
