//! Scalars as Rust constant expressions with exactly their bits (feature `robot`, std): what the
//! build-time writers ([`crate::robot::node_config_source`], [`PreviewGains::source`](crate::shaping::PreviewGains::source)) emit so
//! that the firmware compiles exactly the values the host computed.
//!
//! `v.literal()` is `f64::from_bits(0x…)` or `f32::from_bits(0x…)`: reading it back gives `v`
//! bit for bit (NaN payloads and the sign of zero included), which a decimal print need not.

use std::string::String;

/// A scalar that the build-time writers can write as a Rust constant expression with exactly
/// its bits.
pub trait Literal: crate::real::Real {
    /// `self` as `f64::from_bits(…)` or `f32::from_bits(…)`.
    fn literal(self) -> String;
}

impl Literal for f64 {
    fn literal(self) -> String {
        std::format!("f64::from_bits({:#018x})", self.to_bits())
    }
}

impl Literal for f32 {
    fn literal(self) -> String {
        std::format!("f32::from_bits({:#010x})", self.to_bits())
    }
}

#[cfg(test)]
mod tests {
    use super::Literal;

    #[test]
    fn literals_name_the_bits() {
        assert_eq!(1.0_f64.literal(), "f64::from_bits(0x3ff0000000000000)");
        assert_eq!((-0.0_f32).literal(), "f32::from_bits(0x80000000)");
    }
}
