//! Helpers shared by host-sim's integration tests (each test file that needs them declares
//! `mod common;`).

pub mod figures;
