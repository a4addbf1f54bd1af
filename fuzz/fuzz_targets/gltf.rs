//! libFuzzer target: [`rigport_fuzz::gltf`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::gltf(data));
