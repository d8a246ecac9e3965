//! glTF / GLB loading: any bytes give a mesh with finite coordinates and indices in range, or a
//! one-line error; never a panic, a hang or an unbounded allocation.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../../tests/support/fuzz_input.rs"]
mod fuzz_input;

fuzz_target!(|data: &[u8]| fuzz_input::check_gltf(data));
