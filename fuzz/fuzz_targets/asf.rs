//! libFuzzer target: [`rigport_fuzz::asf`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::asf(data));
