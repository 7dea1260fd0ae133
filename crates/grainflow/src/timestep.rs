//! The time step (reference: MFIX-DEM model §5).

use crate::contact::{CoeffTable, ContactLaw, NormalDamping, NormalModel};
use crate::error::EngineError;
use crate::material::Phase;

/// How the time step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStepRule {
    /// MFIX's rule: DTSOLID = TCOLL / factor (MFIX `DTSOLID_FACTOR`, default 50, at least 10),
    /// TCOLL the shortest collision time over all phase pairs.
    Mfix {
        /// `DTSOLID_FACTOR`.
        factor: f64,
    },
    /// An explicit time step, s.
    Fixed(f64),
}

/// The time step in use, the number of steps, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeStepChoice {
    /// Δt, s.
    pub dt: f64,
    /// Number of steps, ceil((t_stop − t_0)/Δt) (quotient in single precision, as MFIX).
    pub steps: u64,
    /// TCOLL, s, when MFIX's rule was evaluated.
    pub tcoll: Option<f64>,
    /// One sentence saying which rule gave Δt.
    pub explanation: String,
}

/// MFIX's collision time of a phase pair: π/√(K/m_eff − (η_n/m_eff)²/4), with K = k_n (LSD) or
/// K = K_n (Hertz, used as if it were linear, as MFIX does).
pub fn collision_time(kn: f64, eta_n: f64, m_eff: f64) -> f64 {
    std::f64::consts::PI / (kn / m_eff - (eta_n / m_eff).powi(2) / 4.0).sqrt()
}

/// η_n in kg/s for the phase pair's effective mass, whatever the damping's scaling.
fn absolute_eta(law: &ContactLaw, c: &crate::contact::ContactCoeffs) -> f64 {
    match law.damping {
        NormalDamping::MassVelocity => c.eta_n * c.m_eff,
        NormalDamping::Tsuji => c.eta_n * c.m_eff.sqrt(),
        NormalDamping::Mfix | NormalDamping::ExactRestitution => c.eta_n,
    }
}

/// Number of steps MFIX takes for a run of length `span`: ceil of the single-precision quotient.
pub fn step_count(span: f64, dt: f64) -> u64 {
    let q = (span as f32) / (dt as f32);
    if q.is_finite() && q > 0.0 { q.ceil() as u64 } else { 0 }
}

/// Number of steps for an explicit Δt: the run length divided by Δt, rounded to the nearest
/// whole number when it is one to within 1e-9 (so t_stop = 0.1, Δt = 1e-4 gives 1 000 steps
/// despite rounding), else rounded up.
pub fn fixed_step_count(span: f64, dt: f64) -> u64 {
    let q = span / dt;
    if !(q.is_finite() && q > 0.0) {
        return 0;
    }
    let r = q.round();
    if (q - r).abs() <= 1e-9 * q { r as u64 } else { q.ceil() as u64 }
}

/// Applies the rule.
pub fn choose(
    rule: TimeStepRule,
    law: &ContactLaw,
    phases: &[Phase],
    table: &CoeffTable,
    span: f64,
) -> Result<TimeStepChoice, EngineError> {
    let model = match law.normal {
        NormalModel::LinearSpringDashpot => "linear spring-dashpot k_n",
        NormalModel::Hertz => "Hertzian K_n taken as a linear stiffness, as MFIX does",
    };
    // TCOLL is always evaluated: even with an explicit Δt it is worth reporting.
    let mut tcoll = f64::INFINITY;
    let mut limiting = (0, 0);
    for m in 0..phases.len() {
        for l in m..phases.len() {
            let c = table.pair(m, l);
            let t = collision_time(c.kn, absolute_eta(law, c), c.m_eff);
            if t < tcoll {
                tcoll = t;
                limiting = (m, l);
            }
        }
    }
    let (dt, tcoll, explanation) = match rule {
        TimeStepRule::Mfix { factor } => {
            if !(factor.is_finite() && factor >= 10.0) {
                return Err(EngineError::invalid(
                    "dtsolid_factor",
                    factor,
                    "MFIX's DTSOLID_FACTOR must be at least 10",
                ));
            }
            let dt = tcoll / factor;
            let text = format!(
                "dt = {dt:.7e} s from MFIX's rule: TCOLL = {tcoll:.7e} s (phase pair '{}'-'{}', {model}) / DTSOLID_FACTOR {factor}",
                phases[limiting.0].name, phases[limiting.1].name
            );
            (dt, Some(tcoll), text)
        }
        TimeStepRule::Fixed(dt) => {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(EngineError::invalid("dt", dt, "the time step must be a positive time in s"));
            }
            let text = if tcoll.is_finite() {
                format!(
                    "dt = {dt:.7e} s given explicitly (MFIX's rule would give TCOLL/50 = {:.7e} s; TCOLL/dt = {:.1})",
                    tcoll / 50.0,
                    tcoll / dt
                )
            } else {
                format!("dt = {dt:.7e} s given explicitly")
            };
            (dt, tcoll.is_finite().then_some(tcoll), text)
        }
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(EngineError::BadReference(
            "MFIX's time-step rule needs at least one phase; give an explicit dt".into(),
        ));
    }
    let steps = match rule {
        TimeStepRule::Mfix { .. } => step_count(span, dt),
        TimeStepRule::Fixed(_) => fixed_step_count(span, dt),
    };
    Ok(TimeStepChoice { dt, steps, tcoll, explanation })
}

/// The largest time step the contact law tolerates, and the contact that sets it.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityLimit {
    /// Largest safe Δt, s.
    pub dt_max: f64,
    /// A time step comfortably inside it, s (what to suggest).
    pub dt_safe: f64,
    /// Which contact or phase sets the limit, and by which rule.
    pub reason: String,
}

/// Stability limit of explicit integration for the contact law:
/// - linear spring–dashpot: Δt ≤ t_c/5 (ω·Δt ≤ 0.63, well inside the explicit schemes' ω·Δt < 2), t_c the collision time of the stiffest contact over
///   all phase pairs **and** phase–wall pairs (MFIX's rule leaves the walls out); the
///   suggestion is t_c/50, MFIX's default;
/// - Hertz: Δt ≤ 0.3·T_R with the Rayleigh time T_R = πR√(ρ/G)/(0.1631ν + 0.8766) of the
///   smallest phase (Thornton's and Li et al.'s criterion); the suggestion is 0.1·T_R.
pub fn stability_limit(
    law: &ContactLaw,
    phases: &[Phase],
    wall_materials: &[crate::material::WallMaterial],
    table: &CoeffTable,
) -> StabilityLimit {
    match law.normal {
        NormalModel::LinearSpringDashpot => {
            let mut best = (f64::INFINITY, String::new());
            for m in 0..phases.len() {
                for l in m..phases.len() {
                    let c = table.pair(m, l);
                    let t = collision_time(c.kn, absolute_eta(law, c), c.m_eff);
                    if t < best.0 {
                        best = (t, format!("contact '{}'-'{}'", phases[m].name, phases[l].name));
                    }
                }
                for (w, wm) in wall_materials.iter().enumerate() {
                    let c = table.wall(m, w);
                    let t = collision_time(c.kn, absolute_eta(law, c), c.m_eff);
                    if t < best.0 {
                        best = (t, format!("contact '{}'-wall '{}'", phases[m].name, wm.name));
                    }
                }
            }
            StabilityLimit {
                dt_max: best.0 / 5.0,
                dt_safe: best.0 / 50.0,
                reason: format!("collision time {:.4e} s of the {} (limit t_c/5)", best.0, best.1),
            }
        }
        NormalModel::Hertz => {
            let mut best = (f64::INFINITY, String::new());
            for ph in phases {
                if let (Some(e), Some(nu)) = (ph.youngs_modulus, ph.poisson_ratio) {
                    let g = e / (2.0 * (1.0 + nu));
                    let t =
                        std::f64::consts::PI * ph.radius() * (ph.density / g).sqrt() / (0.1631 * nu + 0.8766);
                    if t < best.0 {
                        best = (t, format!("phase '{}'", ph.name));
                    }
                }
            }
            StabilityLimit {
                dt_max: 0.3 * best.0,
                dt_safe: 0.1 * best.0,
                reason: format!("Rayleigh time {:.4e} s of {} (limit 0.3·T_R)", best.0, best.1),
            }
        }
    }
}
