//! libFuzzer target: [`rigport_fuzz::obj`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::obj(data));
