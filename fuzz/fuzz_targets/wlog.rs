#![no_main]
//! The QEMU image's binary log decoder (`gait_loop::binlog`) on arbitrary bytes: no panic,
//! and every frame it gives satisfies the format's rules.

libfuzzer_sys::fuzz_target!(|data: &[u8]| walk_fuzz::wlog_one(data));
