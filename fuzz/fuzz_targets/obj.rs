#![no_main]
//! `raylab::fuzzing::obj` on arbitrary bytes (see fuzz/README.md).

libfuzzer_sys::fuzz_target!(|data: &[u8]| raylab::fuzzing::obj(data));
