//! libFuzzer target: [`rigport_fuzz::json_keys`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::json_keys(data));
