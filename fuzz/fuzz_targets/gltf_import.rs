#![no_main]

#[path = "../checks/gltf_import.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::gltf_import(data));
