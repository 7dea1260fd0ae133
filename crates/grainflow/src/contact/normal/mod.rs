//! The normal contact models, one file each: [`lsd`] (the linear spring–dashpot), [`hertz`]
//! and [`jkr`]. Each is a zero-sized type implementing [`NormalSubModel`], which holds every
//! fact the engine needs of it: its case-file name and description, its coefficients and
//! their checks, its force, touch and pull-off condition, the normal force of its Coulomb
//! limit, its energy, whether it is elastic (takes E and ν), the exponents of its force and
//! dashpot (for the exact restitution damping and the order-free sums' floor), the stiffness
//! MFIX's collision time takes and its stability rule.
//!
//! [`normal_models!`](crate::normal_models) is the registry: the one list of the models. The
//! enum [`NormalModel`] (with [`ALL`](NormalModel::ALL), [`NAMES`](NormalModel::NAMES) and
//! [`CHOICES`](NormalModel::CHOICES), the case layer's table), the dispatch from a value to
//! its type (`with_normal_submodel!`, and through it `with_submodels!`) and the
//! instruction-set test of the force stage's batches are generated from it; nothing else
//! lists the models.
//!
//! **A new normal model** needs: its file here (the type, its `NormalSubModel` impl and the
//! unit tests of its closed forms); its line in [`normal_models!`](crate::normal_models); in
//! the case layer, the keys it ignores or requires (`check_params`, `layer`: the compiler names
//! them); its name in `docs/case-file.md` and a section in `docs/models.md` (a test checks
//! both against [`NormalModel::NAMES`]). New per-contact constants also take a field of
//! [`ContactCoeffs`] and a lane in `forces::lanes`; new keys a field of [`ContactParams`],
//! `raw.rs` and their ranges in `limits`.

pub mod hertz;
pub mod jkr;
pub mod lsd;

pub use hertz::Hertz;
pub use jkr::Jkr;
pub use lsd::LinearSpringDashpot;

use super::geometry::pair_touching;
use super::params::{
    ContactCoeffs, ContactParams, ElasticPair, damping_coefficient, liggghts_beta, tsuji_alpha,
};
use super::{ContactLaw, NormalDamping, limits};
use crate::error::EngineError;

/// What a normal model gives the rest of the law for one contact of overlap δ and normal
/// approach speed v_n.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalParts {
    /// The elastic (and, for a cohesive model, adhesive) normal force, N, positive repulsive.
    pub elastic: f64,
    /// The dashpot's normal force, N, positive repulsive.
    pub damping: f64,
    /// The tangential stiffness in use (k_t, K_t√δ, 8G*·a), N/m.
    pub k_t: f64,
    /// The tangential damping in use, kg/s.
    pub eta_t: f64,
}

/// The factors a contact's coefficients take from its own size ([`NormalSubModel::size_scales`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizeScales {
    /// Of the normal and tangential stiffness.
    pub stiffness: f64,
    /// Of the normal and tangential damping.
    pub damping: f64,
}

/// √m_eff where the damping rule forms η from √(K·m_eff) at set-up (MFIX's and the exact
/// restitution rules), else 1: `MassVelocity` and `Tsuji` take the contact's mass already.
#[inline(always)]
pub(super) fn set_up_mass_scale(damping: NormalDamping, m_eff: f64) -> f64 {
    if matches!(damping, NormalDamping::Mfix | NormalDamping::ExactRestitution) { m_eff.sqrt() } else { 1.0 }
}

/// The coefficients per unit size (R* = 1 m, m_eff = 1 kg) of `c`, derived at the reference
/// effective radius `r_ref` and mass `m_ref`: [`sized`] of them at (`r_ref`, `m_ref`) gives
/// `c` back to rounding.
pub fn per_unit_size<N: NormalSubModel>(
    c: &ContactCoeffs,
    damping: NormalDamping,
    r_ref: f64,
    m_ref: f64,
) -> ContactCoeffs {
    let s = N::size_scales(damping, r_ref, m_ref);
    ContactCoeffs {
        kn: c.kn / s.stiffness,
        kt: c.kt / s.stiffness,
        eta_n: c.eta_n / s.damping,
        eta_t: c.eta_t / s.damping,
        pull_off: c.pull_off / N::pull_off_scale(r_ref),
        ..*c
    }
}

/// The coefficients of one contact of effective radius `r_star` and mass `m_eff` from the
/// coefficients per unit size `c` ([`per_unit_size`]): its stiffness, damping and R* (the
/// pull-off distance is the contact test's: [`NormalSubModel::pull_off_scale`]). Branch-free.
#[inline(always)]
pub fn sized<N: NormalSubModel>(
    c: &ContactCoeffs,
    damping: NormalDamping,
    r_star: f64,
    m_eff: f64,
) -> ContactCoeffs {
    let s = N::size_scales(damping, r_star, m_eff);
    ContactCoeffs {
        kn: c.kn * s.stiffness,
        kt: c.kt * s.stiffness,
        eta_n: c.eta_n * s.damping,
        eta_t: c.eta_t * s.damping,
        r_star,
        ..*c
    }
}

/// A normal contact model. Implemented by zero-sized types; the force stage is generic over
/// one of them.
pub trait NormalSubModel: Copy + Default + Send + Sync + 'static {
    /// The setting this type implements.
    const MODEL: NormalModel;
    /// Its name in a case file (`[contact] model`) and in messages, e.g. "hertz".
    const NAME: &'static str;
    /// One line on what it is, for listings.
    const DESCRIPTION: &'static str;
    /// The exponent p of its elastic force, F ∝ δ^p (1 linear, 3/2 Hertzian): of the
    /// dimensionless impact the exact restitution damping solves ([`damping`](super::damping)),
    /// and of the reference force the order-free sums' floor is formed from (k_n·R^p).
    const FORCE_EXPONENT: f64;
    /// The exponent q of its dashpot, F ∝ δ^q·v (0 linear, 1/4 Hertzian), of that impact.
    const DAMPING_EXPONENT: f64;
    /// How the largest stable time step follows from its inputs ([`StabilityRule`]).
    const STABILITY: StabilityRule;
    /// What [`collision_stiffness`](Self::collision_stiffness) is, for the time step's
    /// explanation.
    const COLLISION_STIFFNESS: &'static str;
    /// True if a formed contact holds to a negative overlap (its pull-off distance, the
    /// coefficients' `pull_off`): the contact test and the neighbour cut-off must reach there.
    const REACHES: bool;
    /// History values the model stores beside the tangential model's (see the module doc).
    const HISTORY: usize;
    /// True if the model needs the phases' (and walls') Young's modulus and Poisson's ratio.
    const ELASTIC: bool;

    /// Its coefficients for one phase pair or phase–wall pair from the inputs `p` (`what`
    /// names the contact in messages; `m_eff` the phases' effective mass; `elastic` the
    /// bodies' constants if [`ELASTIC`](Self::ELASTIC)), with its own checks.
    fn coefficients(
        law: &ContactLaw,
        what: &str,
        p: &ContactParams,
        m_eff: f64,
        elastic: Option<ElasticPair>,
    ) -> Result<ContactCoeffs, EngineError>;

    /// The normal force's parts and the tangential stiffness and damping at overlap `delta`
    /// and normal approach speed `v_n`. Branch-free.
    fn parts(c: &ContactCoeffs, delta: f64, v_n: f64) -> NormalParts;

    /// The normal force the Coulomb limit μ·F takes, from the elastic part and the total
    /// (after clipping) normal force: |F_n| for a non-cohesive model.
    #[inline(always)]
    fn critical(_c: &ContactCoeffs, _elastic: f64, total: f64) -> f64 {
        total.abs()
    }

    /// The normal load of the rolling torque, from the elastic force and [`critical`](Self::critical).
    #[inline(always)]
    fn rolling_load(elastic: f64, _critical: f64) -> f64 {
        elastic
    }

    /// Energy stored in the normal contact at overlap `delta`, J (zero at first touch).
    fn energy(c: &ContactCoeffs, delta: f64) -> f64;

    /// The stiffness MFIX's collision time π/√(K/m_eff − (η_n/2m_eff)²) takes for a contact
    /// of coefficients `c` (a Hertzian K_n as if it were linear, as MFIX does).
    fn collision_stiffness(c: &ContactCoeffs) -> f64 {
        c.kn
    }

    /// How its stiffness and damping scale with a contact's own effective radius R* and mass
    /// m_eff under the damping rule `damping` (beyond what the rule's own ×m_eff or ×√m_eff
    /// does), for [`ContactSizes::Own`](super::ContactSizes::Own). Branch-free.
    fn size_scales(damping: NormalDamping, r_star: f64, m_eff: f64) -> SizeScales;

    /// How its pull-off distance scales with R* (1 for a model that does not reach beyond
    /// the touch).
    #[inline(always)]
    fn pull_off_scale(_r_star: f64) -> f64 {
        1.0
    }

    /// Whether a pair at centre distance² `d2`, radii `ri`, `rj`, is in contact; `touched` if
    /// it was at the last evaluation, `reach` its pull-off distance (used where
    /// [`REACHES`](Self::REACHES)).
    #[inline(always)]
    fn touching(d2: f64, ri: f64, rj: f64, _reach: f64, _touched: bool) -> bool {
        pair_touching(d2, ri, rj)
    }

    /// Whether a particle at overlap `overlap` with a wall is in contact (as
    /// [`touching`](Self::touching)).
    #[inline(always)]
    fn wall_touching(overlap: f64, _reach: f64, _touched: bool) -> bool {
        // Not `overlap >= 0`: a NaN distance counts as touching, as for pairs (the health
        // check reports it).
        overlap.is_nan() | (overlap >= 0.0)
    }
}

/// How a normal model's largest stable time step follows from its inputs
/// (`timestep::stability_limit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StabilityRule {
    /// Δt ≤ t_c/5 (ω·Δt ≤ 0.63, well inside the explicit schemes' ω·Δt < 2), t_c the collision
    /// time of the stiffest contact over all phase pairs **and** phase–wall pairs (MFIX's rule
    /// leaves the walls out); the suggestion is t_c/50, MFIX's default.
    CollisionTime,
    /// Δt ≤ 0.3·T_R with the Rayleigh time T_R = πR√(ρ/G)/(0.1631ν + 0.8766) of the smallest
    /// phase (Thornton's and Li et al.'s criterion); the suggestion is 0.1·T_R.
    RayleighTime,
}

/// The checks and restitution-based damping shared by the models that take e_n, μ and μ_r.
pub(super) fn common_checks(what: &str, p: &ContactParams) -> Result<(), EngineError> {
    limits::EN.check(what, "en", p.en)?;
    limits::MU.check(what, "mu", p.mu)?;
    limits::MU_ROLL.check(what, "mu_roll", p.mu_roll)
}

/// η_n for stiffness `k`, effective mass `m` and restitution `e`, by the law's damping rule
/// (for `Tsuji` and `Liggghts`, per √mass: α√k; `MassVelocity` is set from γ_n by the caller).
pub(super) fn normal_damping<N: NormalSubModel>(law: &ContactLaw, k: f64, m: f64, e: f64) -> f64 {
    match law.damping {
        NormalDamping::Mfix => damping_coefficient(k, m, e),
        NormalDamping::ExactRestitution => {
            let (p, q) = (N::FORCE_EXPONENT, N::DAMPING_EXPONENT);
            super::damping::exact_damping_ratio(p, q, e, law.clip_attraction) * (k * m).sqrt()
        }
        NormalDamping::Tsuji => tsuji_alpha(e) * k.sqrt(),
        // `model hertz`: −2√(5/6)·β·√(S_n) with S_n = (3/2)·K_n·√δ (the √δ goes with δ^¼);
        // `model hooke`: −2β·√k_n.
        NormalDamping::Liggghts if N::MODEL == NormalModel::Hertz => {
            2.0 * (5.0f64 / 6.0).sqrt() * liggghts_beta(e) * (1.5 * k).sqrt()
        }
        NormalDamping::Liggghts => 2.0 * liggghts_beta(e) * k.sqrt(),
        NormalDamping::MassVelocity => 0.0,
    }
}

/// (γ_n, γ_t) per unit mass for `MassVelocity` damping; γ_t defaults to γ_n/2 (LAMMPS).
pub(super) fn mass_velocity(what: &str, p: &ContactParams) -> Result<(f64, f64), EngineError> {
    let gn = p.gamma_n.ok_or_else(|| EngineError::MissingParameter {
        what: format!("{what} gamma_n (normal damping per unit mass, 1/s)"),
        model: "mass_velocity damping".into(),
    })?;
    limits::GAMMA.check(what, "gamma_n", gn)?;
    let gt = p.gamma_t.unwrap_or(0.5 * gn);
    limits::GAMMA.check(what, "gamma_t", gt)?;
    Ok((gn, gt))
}

/// The elastic constants a model with [`NormalSubModel::ELASTIC`] needs, or why not.
pub(super) fn elastic_given(
    what: &str,
    elastic: Option<ElasticPair>,
    model: &str,
) -> Result<ElasticPair, EngineError> {
    elastic.ok_or_else(|| EngineError::MissingParameter {
        what: format!("{what} elastic constants"),
        model: model.into(),
    })
}

/// The registry of normal models: each once, as its [`NormalModel`] variant (with the
/// variant's doc) and its type in this module's files. It calls the macro `$then` (one of the
/// crate's, by name) with `$args` and the list; everything that lists the models is made so.
#[macro_export]
#[doc(hidden)]
macro_rules! normal_models {
    ($then:ident! $args:tt) => {
        $crate::$then! { $args
            /// Linear spring–dashpot (MFIX `DES_COLL_MODEL = 'LSD'`, the default):
            /// F_n = −(k_n·δ + η_n·v_n)·n.
            LinearSpringDashpot = lsd::LinearSpringDashpot,
            /// Hertzian (MFIX `DES_COLL_MODEL = 'HERTZIAN'`):
            /// F_n = −(K_n·δ^1.5 + η_n·δ^0.25·v_n)·n.
            Hertz = hertz::Hertz,
            /// JKR cohesion, as LAMMPS `pair granular … jkr … damping tsuji`: Hertz-like elasticity
            /// on the JKR contact radius a(δ) with adhesion, F_n = −((4/3)E*a³/R* − 4√(πγE*)·a^1.5 +
            /// η_n·√a·v_n)·n; a contact formed at touch holds until the pull-off distance
            /// ([`Jkr`](crate::contact::normal::Jkr)).
            Jkr = jkr::Jkr,
        }
    };
}

crate::normal_models!(submodel_registry! {
    /// The normal force law: one variant per model of the registry
    /// ([`normal_models!`](crate::normal_models)).
    NormalModel: NormalSubModel in normal
});

/// Calls `$body` with the type `$n: NormalSubModel` of a [`NormalModel`] value: `$body` is
/// expanded once per model of the registry, so each is monomorphised.
#[macro_export]
#[doc(hidden)]
macro_rules! with_normal_submodel {
    ($normal:expr, |$n:ident| $body:expr) => {
        $crate::normal_models!(submodel_dispatch! { NormalModel in normal, $normal, $n, $body })
    };
}

impl NormalModel {
    /// True if the model derives its stiffness from Young's moduli and Poisson's ratios.
    pub fn elastic(&self) -> bool {
        crate::with_normal_submodel!(*self, |N| N::ELASTIC)
    }

    /// True if a formed contact holds to a negative overlap (the model's pull-off distance).
    pub fn reaches(&self) -> bool {
        crate::with_normal_submodel!(*self, |N| N::REACHES)
    }

    /// The exponents (p, q) of its elastic force δ^p and dashpot δ^q·v
    /// ([`NormalSubModel::FORCE_EXPONENT`], [`NormalSubModel::DAMPING_EXPONENT`]).
    pub fn exponents(&self) -> (f64, f64) {
        crate::with_normal_submodel!(*self, |N| (N::FORCE_EXPONENT, N::DAMPING_EXPONENT))
    }

    /// Its stability rule ([`NormalSubModel::STABILITY`]).
    pub fn stability(&self) -> StabilityRule {
        crate::with_normal_submodel!(*self, |N| N::STABILITY)
    }

    /// The stiffness MFIX's collision time takes for coefficients `c`
    /// ([`NormalSubModel::collision_stiffness`]).
    pub fn collision_stiffness(&self, c: &ContactCoeffs) -> f64 {
        crate::with_normal_submodel!(*self, |N| N::collision_stiffness(c))
    }

    /// What [`collision_stiffness`](Self::collision_stiffness) is, for messages
    /// ([`NormalSubModel::COLLISION_STIFFNESS`]).
    pub fn collision_stiffness_is(&self) -> &'static str {
        crate::with_normal_submodel!(*self, |N| N::COLLISION_STIFFNESS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry's tables agree with the types: each variant dispatches to the type that
    /// implements it, and the names are the types' and distinct.
    #[test]
    fn the_registry_maps_each_model_to_its_own_type() {
        assert_eq!(NormalModel::ALL.len(), NormalModel::NAMES.len());
        for (k, &m) in NormalModel::ALL.iter().enumerate() {
            assert_eq!(crate::with_normal_submodel!(m, |N| N::MODEL), m);
            assert_eq!(m.name(), NormalModel::NAMES[k]);
            assert_eq!(NormalModel::CHOICES[k], (m.name(), m));
            assert!(!m.description().is_empty());
            assert!(NormalModel::NAMES[..k].iter().all(|n| *n != m.name()), "{} twice", m.name());
        }
    }
}
