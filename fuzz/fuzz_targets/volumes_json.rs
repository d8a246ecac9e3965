//! The bvseg.volumes/1 reader, and the verifier on whatever it accepts (against a small
//! fixed mesh, on a small grid).
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../../tests/support/fuzz_input.rs"]
mod fuzz_input;

fuzz_target!(|data: &[u8]| fuzz_input::check_volumes_json(data));
