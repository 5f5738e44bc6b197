//! Outputs of a run: the trajectory's CSV ([`csv`]), the PNG plots ([`plot`]) and the MCAP
//! file for robotics viewers ([`mcap`]), the commanded and walked velocity ([`velocity`]).
pub mod csv;
pub mod dbc;
pub mod live;
pub mod mcap;
pub mod plot;
pub mod velocity;
