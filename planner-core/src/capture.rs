//! The divergent component of motion and the step that captures a deviation from the plan.
//!
//! # The divergent component
//! For the pendulum `ẍ = ω²(x − p)` (one horizontal coordinate; `x` the COG, `p` the ZMP,
//! `ω = √(g/z_c)`), the divergent component of motion (DCM, Englsberger et al., IROS 2011; the
//! instantaneous capture point of Pratt et al., Humanoids 2006) is
//!
//! ```text
//! ξ = x + ẋ/ω,        ξ̇ = ω (ξ − p).
//! ```
//!
//! Its stable companion `x − ẋ/ω` converges to the ZMP by itself; `ξ` runs away from it.
//!
//! # A deviation from the plan, at touch-down
//! Let the plan have the DCM `ξ_plan(t)` under its ZMP `p_plan(t)`, and the robot's measured
//! state give `ξ_meas(t)`. While the robot follows the plan's ZMP (`p = p_plan`), the
//! deviation `e = ξ_meas − ξ_plan` obeys `ė = ω e`, whatever the plan is, so at the end of the
//! single support, `T_r` from now,
//!
//! ```text
//! e(T_r) = e(t) · e^{ω T_r}.                                             (predicted error)
//! ```
//!
//! A stabilizer moves the ZMP inside the sole to reduce `e`; what it cannot absorb in time
//! reaches the touch-down. The plan's next landing was chosen for `ξ_plan`; landing instead
//! at the planned pose moved by `e(T_r)` puts the foot where it stands to the measured DCM as
//! the planned foot stands to the planned one: the walk after it is the plan, shifted (the
//! step-adjustment law of Englsberger et al. 2011, sec. IV, and of Khadiv et al., Humanoids
//! 2016, without its timing adaptation: eq. 18 of the paper adjusts the timing after the
//! modification).
//!
//! # What the stabilizer absorbs
//! A stabilizer moves the ZMP off the plan's inside the sole, by up to a margin `m` \[m\] in
//! the direction of the deviation. With the ZMP held at that margin, `ė = ω (e − m)`, so
//!
//! ```text
//! e(T_r) − m = (e − m) · e^{ω T_r}:                                   (capture offset)
//! ```
//!
//! a deviation within the margin is captured without a step (it decays), and what exceeds it
//! grows and must be stepped for: the landing moves by `(e − m) e^{ω T_r}` along the
//! deviation's direction (the two coordinates together), so that the foot lands where the
//! stabilizer, again with its margin `m`, can hold the robot. [`capture_offset`] is the law
//! (the margin applied to the deviation *now*: a small deviation, even a rounding of the
//! measurement, is never amplified into a step); [`touchdown_error`] is its prediction without
//! a stabilizer (`m = 0`), and [`step_offset`] the dead band on any vector. The node clamps the
//! result to its reach limits and sends it through its modification path (eq. 17's check,
//! eq. 18, the shaping).

use crate::real::Real;

/// The DCM `ξ = x + ẋ/ω` of one coordinate \[m\].
#[inline]
pub fn dcm<T: Real>(cog: T, cog_vel: T, omega: T) -> T {
    cog + cog_vel / omega
}

/// The predicted deviation of the DCM from the plan's at the end of the single support,
/// `remaining` \[s\] from now, for the measured and the planned COG positions and velocities
/// (each `[x, y]`): `e(T_r) = (ξ_meas − ξ_plan) e^{ω T_r}` per coordinate. A negative
/// `remaining` counts as zero.
pub fn touchdown_error<T: Real>(
    measured: ([T; 2], [T; 2]),
    planned: ([T; 2], [T; 2]),
    omega: T,
    remaining: T,
) -> [T; 2] {
    let grow = (omega * remaining.max(T::ZERO)).exp();
    let e = |k: usize| {
        (dcm(measured.0[k], measured.1[k], omega) - dcm(planned.0[k], planned.1[k], omega)) * grow
    };
    [e(0), e(1)]
}

/// The move of the next landing for a predicted touch-down error `error` \[m\] (`[x, y]`) with
/// the dead band `dead_band` \[m\]: zero inside it, else the error less the dead band along
/// its own direction.
pub fn step_offset<T: Real>(error: [T; 2], dead_band: T) -> [T; 2] {
    let norm = (error[0] * error[0] + error[1] * error[1]).sqrt();
    let d = dead_band.max(T::ZERO);
    // `!(norm > d)`: a norm that is not a number moves nothing.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(norm > d) {
        return [T::ZERO; 2];
    }
    let k = T::ONE - d / norm;
    [error[0] * k, error[1] * k]
}

/// The move of the next landing for the deviation `error` = `ξ_meas − ξ_plan` \[m\] now
/// (`[x, y]`), a stabilizer margin `margin` \[m\] and the landing `remaining` \[s\] from now:
/// `(e − m) e^{ω T_r}` along the deviation's direction, zero within the margin (see the module
/// docs). A negative `remaining` counts as zero.
pub fn capture_offset<T: Real>(error: [T; 2], margin: T, omega: T, remaining: T) -> [T; 2] {
    let grow = (omega * remaining.max(T::ZERO)).exp();
    let o = step_offset(error, margin);
    [o[0] * grow, o[1] * grow]
}

/// The part of the deviation `error` = `ξ_meas − ξ_plan` \[m\] (`[x, y]`) that a landing
/// moved by `moved` \[m\] (`[x, y]`) captures, with the stabilizer margin `margin` \[m\] and
/// the landing `remaining` \[s\] from now: along the deviation's direction `ê`, of length
/// `min(|e|, m + max(0, moved·ê) e^{−ω T_r})` (only the part of the move along the deviation
/// captures it). It inverts [`capture_offset`]: a landing moved by the whole
/// `capture_offset(e)` captures all of `e`, one moved less (the reach cut it) the part its
/// move accounts for. Zero for a zero deviation, and when an input is not a finite number; a
/// negative `remaining` counts as zero.
pub fn captured_deviation<T: Real>(
    error: [T; 2],
    moved: [T; 2],
    margin: T,
    omega: T,
    remaining: T,
) -> [T; 2] {
    let norm = (error[0] * error[0] + error[1] * error[1]).sqrt();
    let along = (moved[0] * error[0] + moved[1] * error[1]) / norm;
    let finite = norm.is_finite() && along.is_finite() && margin.is_finite();
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(norm > T::ZERO) || !finite {
        return [T::ZERO; 2];
    }
    let shrink = (-(omega * remaining.max(T::ZERO))).exp();
    let length = (margin.max(T::ZERO) + along.max(T::ZERO) * shrink).min(norm);
    let k = length / norm;
    [error[0] * k, error[1] * k]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RK4 of `ẍ = ω²(x − p(t))` from `(x, v)` over `t` with a ZMP `p(t)`.
    fn integrate(x: f64, v: f64, omega: f64, t: f64, p: impl Fn(f64) -> f64) -> (f64, f64) {
        let n = 2_000; // h ≤ 0.4 ms: RK4's error (ωh)⁴ e^{ωt} ≈ 4e-11, far inside the tolerance
        let h = t / n as f64;
        let (mut x, mut v, mut s) = (x, v, 0.0);
        let f = |s: f64, x: f64| omega * omega * (x - p(s));
        for _ in 0..n {
            let (k1x, k1v) = (v, f(s, x));
            let (k2x, k2v) = (v + 0.5 * h * k1v, f(s + 0.5 * h, x + 0.5 * h * k1x));
            let (k3x, k3v) = (v + 0.5 * h * k2v, f(s + 0.5 * h, x + 0.5 * h * k2x));
            let (k4x, k4v) = (v + h * k3v, f(s + h, x + h * k3x));
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            s += h;
        }
        (x, v)
    }

    /// The closed form agrees with integrating the plan and the deviated state under the same
    /// (moving) ZMP: the deviation's growth does not depend on the plan.
    #[test]
    fn touchdown_error_matches_integration() {
        let omega = crate::omega(9.8, 0.814);
        let zmp = |s: f64| 0.02 + 0.05 * s - 0.03 * s * s;
        let mut u = crate::test_uniform(7);
        // (a few cases under Miri, the interpreter being slow; every case otherwise)
        for _ in 0..if cfg!(miri) { 3 } else { 50 } {
            let t = 0.05 + 0.7 * u();
            let (px, pv) = (0.1 * u() - 0.05, 0.4 * u() - 0.2);
            let (dx, dv) = (0.02 * u() - 0.01, 0.2 * u() - 0.1);
            let e = touchdown_error(
                ([px + dx, 0.0], [pv + dv, 0.0]),
                ([px, 0.0], [pv, 0.0]),
                omega,
                t,
            );
            let plan = integrate(px, pv, omega, t, zmp);
            let meas = integrate(px + dx, pv + dv, omega, t, zmp);
            let oracle = dcm(meas.0, meas.1, omega) - dcm(plan.0, plan.1, omega);
            assert!((e[0] - oracle).abs() < 1e-9, "{} vs {oracle}", e[0]);
            assert_eq!(e[1], 0.0);
        }
    }

    /// The capture offset is what a pendulum whose ZMP is held at the margin in the deviation's
    /// direction (integrated, RK4) has left beyond the margin at touch-down; a deviation within
    /// the margin needs no step.
    #[test]
    fn the_capture_offset_is_what_the_margin_cannot_hold() {
        let omega = crate::omega(9.8, 0.814);
        let mut u = crate::test_uniform(11);
        for _ in 0..if cfg!(miri) { 2 } else { 30 } {
            let (t, m) = (0.05 + 0.7 * u(), 0.01 + 0.05 * u());
            let e = [0.2 * u() - 0.1, 0.2 * u() - 0.1];
            let o = capture_offset(e, m, omega, t);
            let n = (e[0] * e[0] + e[1] * e[1]).sqrt();
            if n <= m {
                assert_eq!(o, [0.0, 0.0]);
                continue;
            }
            // The deviation's own coordinate along its direction, with the ZMP at the margin
            // (the plan's ZMP at 0: the deviation is the state).
            let (x, v) = integrate(n, 0.0, omega, t, |_| m);
            let beyond = x - m; // ξ = x at v = 0 … the DCM of (x, v)
            let beyond = beyond + v / omega;
            let want = [e[0] / n * beyond, e[1] / n * beyond];
            assert!(
                (o[0] - want[0]).abs() < 1e-9 && (o[1] - want[1]).abs() < 1e-9,
                "{o:?} vs {want:?}"
            );
        }
    }

    /// The captured deviation inverts the capture offset (a whole move captures the whole
    /// deviation); for a shorter move it is the state from which a pendulum with its ZMP held
    /// at the margin (integrated, RK4) reaches the moved landing at touch-down; it never
    /// exceeds the deviation, and nothing is captured of no deviation.
    #[test]
    fn the_captured_deviation_is_what_the_move_accounts_for() {
        let omega = crate::omega(9.8, 0.814);
        let mut u = crate::test_uniform(13);
        for _ in 0..if cfg!(miri) { 2 } else { 30 } {
            let (t, m) = (0.05 + 0.7 * u(), 0.01 + 0.05 * u());
            let e = [0.2 * u() - 0.1, 0.2 * u() - 0.1];
            let n = (e[0] * e[0] + e[1] * e[1]).sqrt();
            let o = capture_offset(e, m, omega, t);
            let whole = (o[0] * o[0] + o[1] * o[1]).sqrt();
            let c = captured_deviation(e, o, m, omega, t);
            if n > m {
                assert!((c[0] - e[0]).abs() < 1e-12 && (c[1] - e[1]).abs() < 1e-12);
            }
            // A move cut to a fraction of the whole (the reach).
            let moved = whole * u();
            let c = captured_deviation(e, [e[0] / n * moved, e[1] / n * moved], m, omega, t);
            let len = (c[0] * c[0] + c[1] * c[1]).sqrt();
            assert!(len <= n + 1e-15, "{len} > {n}");
            assert!(
                (c[0] * e[1] - c[1] * e[0]).abs() < 1e-15,
                "off the direction"
            );
            if len < n {
                let (x, v) = integrate(len, 0.0, omega, t, |_| m);
                let beyond = x + v / omega - m;
                assert!((beyond - moved).abs() < 1e-9, "{beyond} vs {moved}");
            }
        }
        // Only the part of the move along the deviation captures it: a move across it, or
        // against it, captures the margin's part alone.
        let (e, m, t) = ([0.0, 0.05], 0.02, 0.4);
        let margin_only = captured_deviation(e, [0.0; 2], m, omega, t);
        assert!((margin_only[1] - m).abs() < 1e-15 && margin_only[0] == 0.0);
        for moved in [[0.08, 0.0], [-0.08, 0.0], [0.0, -0.08], [0.05, -0.01]] {
            assert_eq!(captured_deviation(e, moved, m, omega, t), margin_only);
        }
        let part = captured_deviation(e, [0.08, 0.01], m, omega, t);
        assert!((part[1] - (m + 0.01 * (-omega * t).exp())).abs() < 1e-15);
        for (e, moved) in [
            ([0.0; 2], [0.1, 0.0]),
            ([f64::NAN, 0.0], [0.1, 0.0]),
            ([f64::INFINITY, 0.0], [0.1, 0.0]),
            ([0.05, 0.0], [f64::NAN, 0.0]),
            ([0.05, 0.0], [f64::INFINITY, 0.0]),
        ] {
            assert_eq!(captured_deviation(e, moved, 0.02, omega, 0.5), [0.0; 2]);
        }
    }

    /// No deviation, no move; inside the dead band, no move; outside, the excess along the
    /// error's direction.
    #[test]
    fn the_offset_is_the_excess_over_the_dead_band() {
        assert_eq!(step_offset([0.0, 0.0], 0.02), [0.0, 0.0]);
        assert_eq!(step_offset([0.01, -0.015], 0.02), [0.0, 0.0]);
        let o = step_offset([0.03, 0.04], 0.02);
        assert!(
            (o[0] - 0.018).abs() < 1e-15 && (o[1] - 0.024).abs() < 1e-15,
            "{o:?}"
        );
        assert_eq!(step_offset([0.03, 0.04], 0.0), [0.03, 0.04]);
        assert_eq!(step_offset([f64::NAN, 0.0], 0.02), [0.0, 0.0]);
    }

    /// The touch-down error grows with the time left, and a state on the plan has none.
    #[test]
    fn on_the_plan_nothing_to_capture() {
        let omega = crate::omega(9.8, 0.814);
        let s = ([0.1, -0.05], [0.3, 0.1]);
        assert_eq!(touchdown_error(s, s, omega, 0.4), [0.0, 0.0]);
        let m = ([0.11, -0.05], [0.3, 0.1]);
        let early = touchdown_error(m, s, omega, 0.4)[0];
        let late = touchdown_error(m, s, omega, 0.1)[0];
        assert!(early > late && late > 0.01, "{early} {late}");
        assert!((touchdown_error(m, s, omega, -1.0)[0] - 0.01).abs() < 1e-15);
    }
}
