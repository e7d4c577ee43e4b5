#![no_main]
//! `raylab::fuzzing::exr_part` on arbitrary bytes (see fuzz/README.md).

libfuzzer_sys::fuzz_target!(|data: &[u8]| raylab::fuzzing::exr_part(data));
