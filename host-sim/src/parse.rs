//! The command line's value parsers that clap does not provide.

use host_sim::eval::faults::Walk;

/// A walk of the fault sweep by name: `plain` or `adjusting`.
pub(crate) fn walk(s: &str) -> Result<Walk, String> {
    match s {
        "plain" => Ok(Walk::Plain),
        "adjusting" => Ok(Walk::Adjusting),
        _ => Err(format!("{s:?} is not a walk: plain or adjusting")),
    }
}

/// A positive, finite number of seconds.
pub(crate) fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number of seconds")),
    }
}
