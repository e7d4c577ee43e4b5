#![no_main]
//! `raylab::fuzzing::gltf` on arbitrary bytes (see fuzz/README.md).

libfuzzer_sys::fuzz_target!(|data: &[u8]| raylab::fuzzing::gltf(data));
