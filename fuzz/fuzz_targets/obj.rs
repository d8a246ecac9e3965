//! OBJ loading: any bytes give a mesh or a one-line error, never a panic or a hang.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match bvseg_io::load_obj_from_bytes(data, "fuzz.obj") {
        Ok(mesh) => {
            // What the pipeline does first with a loaded mesh must not panic either.
            let _ = mesh.bbox();
            let _ = mesh.signed_volume();
        }
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
});
