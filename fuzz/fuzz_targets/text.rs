#![no_main]
//! The host's text decoders (candump log lines, candump logs to replay, TOML scenarios, robot
//! files) on arbitrary text: no panic, and what they accept is consistent.

libfuzzer_sys::fuzz_target!(|data: &[u8]| walk_fuzz::text_one(data));
