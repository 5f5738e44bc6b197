#![no_main]
//! `Command::decode` on arbitrary frames; accepted commands must survive `encode` → `decode`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| walk_fuzz::decode_one(data));
