//! Outputs of a run beside its CSV and JSON: the PNG plots ([`plot`]) and the MCAP file for
//! robotics viewers ([`mcap`]).
pub mod mcap;
pub mod plot;
