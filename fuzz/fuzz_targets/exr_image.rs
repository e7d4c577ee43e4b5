#![no_main]
//! `raylab::fuzzing::exr_image` on arbitrary bytes (see fuzz/README.md).

libfuzzer_sys::fuzz_target!(|data: &[u8]| raylab::fuzzing::exr_image(data));
