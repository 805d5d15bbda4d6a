//! Every C entry point of coray, driven with hostile arenas, parameters
//! and rays by `coray_fuzz_harness::run` (see its documentation for the
//! input format and the properties checked).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    coray_fuzz_harness::run(data);
});
