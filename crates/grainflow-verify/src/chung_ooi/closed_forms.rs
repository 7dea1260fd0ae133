//! The closed forms the tests are checked against: effective moduli, Hertz's elastic impact
//! (and an RK4 integration of it), the thresholds of sliding throughout, the onset stick of a
//! damped contact, and the gross-sliding and rigid-body oblique impacts.

/// E* = [(1 − ν₁²)/E₁ + (1 − ν₂²)/E₂]⁻¹, Pa.
pub fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

/// G* = [(2 − ν₁)/G₁ + (2 − ν₂)/G₂]⁻¹ with G = E/(2(1 + ν)), Pa.
pub fn effective_shear_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    let (g1, g2) = (e1 / (2.0 * (1.0 + nu1)), e2 / (2.0 * (1.0 + nu2)));
    1.0 / ((2.0 - nu1) / g1 + (2.0 - nu2) / g2)
}

/// κ = K_t/(1.5K_n) = 4G*/E*: the ratio of the Mindlin tangential stiffness K_t√δ to the
/// Hertz normal tangent stiffness 1.5K_n√δ.
pub fn stiffness_ratio(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    4.0 * effective_shear_modulus(e1, nu1, e2, nu2) / effective_modulus(e1, nu1, e2, nu2)
}

/// c in t_c = c·δ_max/v for an elastic Hertz impact: 2∫₀¹(1 − s^(5/2))^(−½)ds = (4/5)B(2/5, ½)
/// = 2.9432752. With s = 1 − w² the integrand 2w(1 − (1 − w²)^(5/2))^(−½) is smooth (→ 2/√2.5
/// at w = 0); Simpson's rule with 2 000 panels gives it to about 1e-13.
pub fn contact_time_constant() -> f64 {
    let f = |w: f64| {
        if w == 0.0 { 2.0 / 2.5f64.sqrt() } else { 2.0 * w / (1.0 - (1.0 - w * w).powf(2.5)).sqrt() }
    };
    let n = 2000;
    let h = 1.0 / n as f64;
    let mut sum = f(0.0) + f(1.0);
    for k in 1..n {
        sum += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    2.0 * sum * h / 3.0
}

/// The elastic Hertz impact: stiffness, largest overlap, largest force, contact time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzImpact {
    /// K_n = (4/3)E*√R*, N/m^1.5.
    pub stiffness: f64,
    /// δ_max = (15m*v²/(16E*√R*))^(2/5), m.
    pub overlap_max: f64,
    /// F_max = K_n·δ_max^1.5, N.
    pub force_max: f64,
    /// t_c = 2.943275·δ_max/v, s.
    pub contact_time: f64,
}

/// The elastic impact of effective modulus `e_star`, radius `r_star` and mass `m_star` at
/// normal approach speed `v`.
pub fn hertz_impact(e_star: f64, r_star: f64, m_star: f64, v: f64) -> HertzImpact {
    let stiffness = 4.0 / 3.0 * e_star * r_star.sqrt();
    let overlap_max = (15.0 * m_star * v * v / (16.0 * e_star * r_star.sqrt())).powf(0.4);
    HertzImpact {
        stiffness,
        overlap_max,
        force_max: stiffness * overlap_max.powf(1.5),
        contact_time: contact_time_constant() * overlap_max / v,
    }
}

/// The overlap history m*δ″ = −K_nδ^1.5, δ(0) = 0, δ′(0) = v, at times k·dt (k = 0..n), by
/// fourth-order Runge–Kutta with `sub` steps per dt; after separation δ goes on linearly.
pub fn hertz_overlap_history(stiffness: f64, m_star: f64, v: f64, dt: f64, n: usize, sub: usize) -> Vec<f64> {
    let acc = |d: f64| -stiffness / m_star * d.max(0.0).powf(1.5);
    let h = dt / sub as f64;
    let (mut d, mut u) = (0.0f64, v);
    let mut out = Vec::with_capacity(n + 1);
    out.push(d);
    for _ in 0..n {
        for _ in 0..sub {
            let (k1d, k1u) = (u, acc(d));
            let (k2d, k2u) = (u + 0.5 * h * k1u, acc(d + 0.5 * h * k1d));
            let (k3d, k3u) = (u + 0.5 * h * k2u, acc(d + 0.5 * h * k2d));
            let (k4d, k4u) = (u + h * k3u, acc(d + h * k3d));
            d += h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
            u += h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        }
        out.push(d);
    }
    out
}

/// u₀/v_n from which an elastic-law contact slides throughout: μ[3.5(1 + e) − e/κ].
pub fn gross_sliding_slip_ratio(mu: f64, e: f64, kappa: f64) -> f64 {
    mu * (3.5 * (1.0 + e) - e / kappa)
}

/// The loss of β caused by sticking at the onset of a damped contact (module docs):
/// 0.4α²x/((σ − 1)(1 + e)), σ = 3.5κ(1 + e)/x; `None` if σ ≤ 1 (the contact never reaches the
/// Coulomb limit during the onset).
pub fn onset_stick_beta_loss(alpha: f64, kappa: f64, e: f64, x: f64) -> Option<f64> {
    let sigma = 3.5 * kappa * (1.0 + e) / x;
    (sigma > 1.0).then(|| 0.4 * alpha * alpha * x / ((sigma - 1.0) * (1.0 + e)))
}

/// Gross-sliding closed forms of an impact at angle θ (from the normal) with speed V, lever R:
/// (e_t, spin ω′ in rad/s, rebound angle, contact-point rebound angle), angles in degrees.
pub fn gross_sliding_oblique(theta_deg: f64, speed: f64, radius: f64, mu: f64, e: f64) -> [f64; 4] {
    let t = theta_deg.to_radians();
    let vn = speed * t.cos();
    [
        1.0 - mu * (1.0 + e) / t.tan(),
        2.5 * mu * (1.0 + e) * vn / radius,
        ((t.tan() - mu * (1.0 + e)) / e).atan().to_degrees(),
        ((t.tan() - 3.5 * mu * (1.0 + e)) / e).atan().to_degrees(),
    ]
}

/// Rigid-body (hard-sphere) theory of the same impact: sticking (e_t = 5/7) below
/// tan θ = 3.5μ(1 + e), gross sliding above.
pub fn rigid_body_oblique(theta_deg: f64, speed: f64, radius: f64, mu: f64, e: f64) -> [f64; 4] {
    let t = theta_deg.to_radians();
    if t.tan() >= 3.5 * mu * (1.0 + e) {
        gross_sliding_oblique(theta_deg, speed, radius, mu, e)
    } else {
        let vt0 = speed * t.sin();
        [5.0 / 7.0, 5.0 / 7.0 * vt0 / radius, (5.0 / 7.0 * t.tan() / e).atan().to_degrees(), 0.0]
    }
}
