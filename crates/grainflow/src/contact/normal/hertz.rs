//! The Hertzian normal model: MFIX's `HERTZIAN`, LAMMPS's `hertz/material`.

use super::{
    NormalParts, NormalSubModel, SizeScales, StabilityRule, common_checks, elastic_given, mass_velocity,
    normal_damping, set_up_mass_scale,
};
use crate::contact::params::{ContactCoeffs, ContactParams, ElasticPair, damping_coefficient, liggghts_beta};
use crate::contact::{ContactLaw, NormalDamping, NormalModel, limits};
use crate::error::EngineError;

/// Hertz (MFIX `HERTZIAN`, LAMMPS `hertz/material`): F_n = K_n·δ^1.5 + η_n·δ^¼·v_n with
/// K_n = (4/3)E*√R*, tangential stiffness K_t·√δ with K_t = 8G*√R*.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hertz;

impl NormalSubModel for Hertz {
    const MODEL: NormalModel = NormalModel::Hertz;
    const NAME: &'static str = "hertz";
    const DESCRIPTION: &'static str =
        "Hertzian, MFIX's HERTZIAN: F_n = K_n·δ^1.5 + η_n·δ^¼·v_n, K_n from E and ν";
    const REACHES: bool = false;
    const HISTORY: usize = 0;
    const ELASTIC: bool = true;
    const FORCE_EXPONENT: f64 = 1.5;
    const DAMPING_EXPONENT: f64 = 0.25;
    const STABILITY: StabilityRule = StabilityRule::RayleighTime;
    const COLLISION_STIFFNESS: &'static str = "Hertzian K_n taken as a linear stiffness, as MFIX does";

    /// K_n = (4/3)E*√R*, K_t = 8G*√R* (or `hertz_kn`, `hertz_kt`); η_n from e_n by the
    /// damping rule, η_t from e_t (MFIX) or `etat_fac`·η_n (Tsuji) or γ_t.
    fn coefficients(
        law: &ContactLaw,
        what: &str,
        p: &ContactParams,
        m_eff: f64,
        elastic: Option<ElasticPair>,
    ) -> Result<ContactCoeffs, EngineError> {
        common_checks(what, p)?;
        let h = elastic_given(what, elastic, "hertz")?;
        // MFIX's Hertz damping takes η_t from e_t; the LAMMPS forms do not need it.
        let et = match law.damping {
            NormalDamping::Mfix | NormalDamping::ExactRestitution => {
                let et = p.et.ok_or_else(|| EngineError::MissingParameter {
                    what: format!("{what} et (tangential restitution)"),
                    model: "hertz".into(),
                })?;
                limits::ET.check(what, "et", et)?;
                et
            }
            NormalDamping::MassVelocity | NormalDamping::Tsuji | NormalDamping::Liggghts => 1.0,
        };
        let sr = h.r_star.sqrt();
        let kn = p.hertz_kn.unwrap_or(4.0 / 3.0 * h.e_star() * sr);
        let kt = p.hertz_kt.unwrap_or(8.0 * h.g_star() * sr);
        for (key, v) in [("hertz_kn", p.hertz_kn), ("hertz_kt", p.hertz_kt)] {
            if let Some(v) = v {
                limits::KN.check(what, key, v)?;
            }
        }
        Ok(ContactCoeffs {
            kn,
            kt,
            eta_n: match law.damping {
                NormalDamping::MassVelocity => mass_velocity(what, p)?.0,
                _ => normal_damping::<Self>(law, kn, m_eff, p.en),
            },
            eta_t: match law.damping {
                NormalDamping::Mfix | NormalDamping::ExactRestitution => {
                    damping_coefficient(kt, 2.0 / 7.0 * m_eff, et)
                }
                NormalDamping::Tsuji => p.etat_fac * normal_damping::<Self>(law, kn, m_eff, p.en),
                // −2√(5/6)·β·√(S_t), S_t = K_t·√δ (the √δ goes with δ^¼).
                NormalDamping::Liggghts => {
                    p.etat_fac * 2.0 * (5.0f64 / 6.0).sqrt() * liggghts_beta(p.en) * kt.sqrt()
                }
                NormalDamping::MassVelocity => mass_velocity(what, p)?.1,
            },
            mu: p.mu,
            mu_roll: p.mu_roll,
            m_eff,
            ..Default::default()
        })
    }

    #[inline(always)]
    fn parts(c: &ContactCoeffs, delta: f64, v_n: f64) -> NormalParts {
        let sd = delta.sqrt();
        let qd = sd.sqrt();
        NormalParts {
            elastic: c.kn * delta * sd,
            damping: c.eta_n * qd * v_n,
            k_t: c.kt * sd,
            eta_t: c.eta_t * qd,
        }
    }

    #[inline]
    fn energy(c: &ContactCoeffs, delta: f64) -> f64 {
        0.4 * c.kn * delta * delta * delta.sqrt()
    }

    /// K_n, K_t ∝ √R*; a damping α√(K_n·m_eff) ∝ R*^¼ (times √m_eff where formed at set-up);
    /// γ_n·m_eff (`MassVelocity`) does not take R*.
    #[inline(always)]
    fn size_scales(damping: NormalDamping, r_star: f64, m_eff: f64) -> SizeScales {
        let root = r_star.sqrt();
        let quarter = if damping == NormalDamping::MassVelocity { 1.0 } else { root.sqrt() };
        SizeScales { stiffness: root, damping: quarter * set_up_mass_scale(damping, m_eff) }
    }
}
