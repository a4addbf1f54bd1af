//! libFuzzer target: [`rigport_fuzz::json_pose`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::json_pose(data));
