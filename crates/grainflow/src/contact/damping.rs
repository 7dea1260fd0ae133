//! Normal damping from a coefficient of restitution.
//!
//! MFIX's formula η = 2√(KM)·|ln e|/√(π² + ln²e) is exact for the linear spring–dashpot whose
//! force may turn attractive at the end of contact. For the Hertzian law with a δ^¼ dashpot
//! (F = K δ^1.5 + η δ^¼ δ̇, Tsuji et al. 1992) or with the attractive end of contact clipped,
//! the restitution it produces differs from the input (e.g. 0.54 instead of 0.5 for Hertz).
//! [`exact_damping_ratio`] instead finds the damping that reproduces e exactly.
//!
//! Scaling: with δ* = (M v²/K)^(1/(p+1)) and τ = δ*/v, both laws become x″ = −x^p − α x^q x′,
//! x(0) = 0, x′(0) = 1 (p = 1, q = 0 linear; p = 3/2, q = 1/4 Hertz), with α = η/√(MK): the
//! restitution depends on α alone, not on the impact speed. α(e) is found by bisection on a
//! fourth-order Runge–Kutta integration of that equation. The exponents (p, q) are the normal
//! model's own (`NormalSubModel::FORCE_EXPONENT`, `DAMPING_EXPONENT`; [`NormalModel::exponents`]).
//!
//! [`NormalModel::exponents`]: super::NormalModel::exponents

/// Restitution −x′(end) of the dimensionless impact x″ = −x^`p` − `alpha`·x^`q`·x′; `clip`
/// ends the contact when the normal force would turn attractive (it then flies off freely).
pub fn restitution(p: f64, q: f64, alpha: f64, clip: bool) -> f64 {
    // Repulsive force (positive pushes the bodies apart).
    let force = |x: f64, v: f64| {
        let x = x.max(0.0);
        x.powf(p) + alpha * x.powf(q) * v
    };
    let rhs = |x: f64, v: f64| -force(x, v);
    let h = 1e-4;
    let (mut x, mut v) = (0.0f64, 1.0f64);
    let mut t = 0.0;
    // An undamped impact lasts π (linear) or 3.218 (Hertz) in these units; a heavily damped one
    // may never separate: past t = 200 the rebound is taken as zero.
    while t < 200.0 {
        let (k1x, k1v) = (v, rhs(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, rhs(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, rhs(x + h * k3x, v + h * k3v));
        let xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t += h;
        if t > h && xn <= 0.0 {
            // Separation between the two points: interpolate the velocity at x = 0.
            let s = x / (x - xn);
            return -(v + s * (vn - v));
        }
        if clip && t > h && vn < 0.0 && force(xn, vn) <= 0.0 {
            return -vn;
        }
        x = xn;
        v = vn;
    }
    0.0
}

/// The damping ratio α = η/√(MK) that gives restitution `e` in (0, 1] exactly, for a force
/// δ^`p` and a dashpot δ^`q`·v.
///
/// α depends only on (p, q, e, clipping), and solving for it takes some 60 integrations, so
/// solutions are remembered for the life of the process.
pub fn exact_damping_ratio(p: f64, q: f64, e: f64, clip: bool) -> f64 {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    /// (bits of p, q and e, clipped?) → α.
    type Solved = HashMap<(u64, u64, u64, bool), f64>;
    static SOLVED: OnceLock<Mutex<Solved>> = OnceLock::new();
    let key = (p.to_bits(), q.to_bits(), e.to_bits(), clip);
    let memo = SOLVED.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(alpha) = memo.lock().ok().and_then(|m| m.get(&key).copied()) {
        return alpha;
    }
    let alpha = solve_damping_ratio(p, q, e, clip);
    if let Ok(mut m) = memo.lock() {
        m.insert(key, alpha);
    }
    alpha
}

fn solve_damping_ratio(p: f64, q: f64, e: f64, clip: bool) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let mut hi = 1.0;
    while restitution(p, q, hi, clip) > e && hi < 1e6 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if restitution(p, q, mid, clip) > e {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{NormalModel, damping_coefficient};

    #[test]
    fn linear_unclipped_matches_the_closed_form() {
        // For the linear oscillator without clipping, MFIX's formula is exact:
        // α = 2|ln e|/√(π² + ln²e). The RK4 step 1e-4 over a contact of length ~π gives a
        // relative error far below 1e-6.
        for e in [0.1, 0.3, 0.5, 0.7, 0.9, 0.99] {
            let closed = damping_coefficient(1.0, 1.0, e);
            let (p, q) = NormalModel::LinearSpringDashpot.exponents();
            let exact = exact_damping_ratio(p, q, e, false);
            assert!((exact - closed).abs() <= 1e-6 * closed, "e = {e}: {exact} vs {closed}");
        }
    }

    #[test]
    fn undamped_impacts_are_elastic_and_damping_lowers_restitution() {
        for m in [NormalModel::LinearSpringDashpot, NormalModel::Hertz] {
            let (p, q) = m.exponents();
            for clip in [false, true] {
                assert!((restitution(p, q, 0.0, clip) - 1.0).abs() < 1e-9);
                let (a, b) = (restitution(p, q, 0.1, clip), restitution(p, q, 0.5, clip));
                assert!(1.0 > a && a > b && b > 0.0, "{m:?} clip {clip}: {a} {b}");
                let alpha = exact_damping_ratio(p, q, 0.5, clip);
                assert!((restitution(p, q, alpha, clip) - 0.5).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn clipping_the_attraction_raises_restitution() {
        // The attractive tail decelerates the separating body; without it, it leaves faster.
        for m in [NormalModel::LinearSpringDashpot, NormalModel::Hertz] {
            let (p, q) = m.exponents();
            assert!(restitution(p, q, 0.5, true) > restitution(p, q, 0.5, false));
        }
    }
}
