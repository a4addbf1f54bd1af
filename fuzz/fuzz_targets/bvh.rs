//! libFuzzer target: [`rigport_fuzz::bvh`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::bvh(data));
