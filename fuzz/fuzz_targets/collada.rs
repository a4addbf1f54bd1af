//! libFuzzer target: [`rigport_fuzz::collada`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rigport_fuzz::collada(data));
