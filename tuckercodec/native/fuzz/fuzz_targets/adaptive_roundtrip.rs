//! libFuzzer target: see `tuckercodec_core::fuzzing::adaptive_roundtrip` for the input framing and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| tuckercodec_core::fuzzing::adaptive_roundtrip(data));
