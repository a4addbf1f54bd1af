//! libFuzzer target: [`rigport_fuzz::amc`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::amc(data));
