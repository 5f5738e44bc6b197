#![no_main]
//! A `Node<8>` fed an arbitrary sequence of frames and time steps: it never panics, publishes
//! exactly one finite reference per poll and answers every frame.

libfuzzer_sys::fuzz_target!(|data: &[u8]| walk_fuzz::node_run(data));
