//! libFuzzer target: [`rigport_fuzz::csci520`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::csci520(data));
