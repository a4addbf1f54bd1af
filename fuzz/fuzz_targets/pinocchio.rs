//! libFuzzer target: [`rigport_fuzz::pinocchio`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::pinocchio(data));
