#![no_main]
//! `raylab::fuzzing::scene_file` on arbitrary bytes (see fuzz/README.md).

libfuzzer_sys::fuzz_target!(|data: &[u8]| raylab::fuzzing::scene_file(data));
