//! libFuzzer target: [`rigport_fuzz::json_handles`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::json_handles(data));
