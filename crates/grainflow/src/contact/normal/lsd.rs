//! The linear spring–dashpot: MFIX's default normal model (`LSD`), LAMMPS's `hooke`.

use super::{
    NormalParts, NormalSubModel, SizeScales, StabilityRule, common_checks, mass_velocity, normal_damping,
    set_up_mass_scale,
};
use crate::contact::params::{ContactCoeffs, ContactParams, ElasticPair};
use crate::contact::{ContactLaw, NormalDamping, NormalModel, limits};
use crate::error::EngineError;

/// The linear spring–dashpot (MFIX `LSD`, LAMMPS `hooke`): F_n = k_n·δ + η_n·v_n, k_t = κ·k_n.
#[derive(Debug, Clone, Copy, Default)]
pub struct LinearSpringDashpot;

impl NormalSubModel for LinearSpringDashpot {
    const MODEL: NormalModel = NormalModel::LinearSpringDashpot;
    const NAME: &'static str = "lsd";
    const DESCRIPTION: &'static str = "linear spring-dashpot, MFIX's default: F_n = k_n·δ + η_n·v_n";
    const REACHES: bool = false;
    const HISTORY: usize = 0;
    const ELASTIC: bool = false;
    const FORCE_EXPONENT: f64 = 1.0;
    const DAMPING_EXPONENT: f64 = 0.0;
    const STABILITY: StabilityRule = StabilityRule::CollisionTime;
    const COLLISION_STIFFNESS: &'static str = "linear spring-dashpot k_n";

    /// k_n given (`kn`), k_t = `kt_fac`·k_n; η_n from e_n by the damping rule (or γ_n),
    /// η_t = `etat_fac`·η_n (or γ_t).
    fn coefficients(
        law: &ContactLaw,
        what: &str,
        p: &ContactParams,
        m_eff: f64,
        _elastic: Option<ElasticPair>,
    ) -> Result<ContactCoeffs, EngineError> {
        common_checks(what, p)?;
        limits::KT_FAC.check(what, "kt_fac", p.kt_fac)?;
        limits::ETAT_FAC.check(what, "etat_fac", p.etat_fac)?;
        let kn = p.kn.ok_or_else(|| EngineError::MissingParameter {
            what: format!("{what} kn (normal stiffness, N/m)"),
            model: "lsd".into(),
        })?;
        limits::KN.check(what, "kn", kn)?;
        let (eta_n, eta_t) = match law.damping {
            NormalDamping::MassVelocity => mass_velocity(what, p)?,
            _ => {
                let eta_n = normal_damping::<Self>(law, kn, m_eff, p.en);
                (eta_n, p.etat_fac * eta_n)
            }
        };
        Ok(ContactCoeffs {
            kn,
            kt: p.kt_fac * kn,
            eta_n,
            eta_t,
            mu: p.mu,
            mu_roll: p.mu_roll,
            m_eff,
            ..Default::default()
        })
    }

    #[inline(always)]
    fn parts(c: &ContactCoeffs, delta: f64, v_n: f64) -> NormalParts {
        NormalParts { elastic: c.kn * delta, damping: c.eta_n * v_n, k_t: c.kt, eta_t: c.eta_t }
    }

    #[inline]
    fn energy(c: &ContactCoeffs, delta: f64) -> f64 {
        0.5 * c.kn * delta * delta
    }

    /// k_n is given, not derived: only a damping formed from √(k_n·m_eff) scales, by √m_eff.
    #[inline(always)]
    fn size_scales(damping: NormalDamping, _r_star: f64, m_eff: f64) -> SizeScales {
        SizeScales { stiffness: 1.0, damping: set_up_mass_scale(damping, m_eff) }
    }
}
