#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| rdt_fuzz::targets::xyz(data));
