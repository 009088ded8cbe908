#![no_main]

#[path = "../checks/rig_file.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::rig_file(data));
