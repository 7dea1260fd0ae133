//! The time step (reference: MFIX-DEM model §5).

use crate::contact::{CoeffTable, ContactLaw, NormalModel};
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

/// Number of steps MFIX takes for a run of length `span`: ceil of the single-precision quotient.
pub fn step_count(span: f64, dt: f64) -> u64 {
    let q = (span as f32) / (dt as f32);
    if q.is_finite() && q > 0.0 { q.ceil() as u64 } else { 0 }
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
            let t = collision_time(c.kn, c.eta_n, c.m_eff);
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
    Ok(TimeStepChoice { dt, steps: step_count(span, dt), tcoll, explanation })
}
