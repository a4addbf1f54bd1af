//! libFuzzer target: [`rigport_fuzz::usd`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::usd(data));
