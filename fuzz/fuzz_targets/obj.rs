//! OBJ loading: any bytes give a mesh or a one-line error, never a panic or a hang.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../../tests/support/fuzz_input.rs"]
mod fuzz_input;

fuzz_target!(|data: &[u8]| fuzz_input::check_obj(data));
