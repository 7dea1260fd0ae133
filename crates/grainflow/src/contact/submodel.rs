//! The contact law's sub-models, one type per category, in the spirit of LAMMPS's `pair
//! granular`: a normal model ([`NormalSubModel`]: [`LinearSpringDashpot`], [`Hertz`],
//! [`Jkr`]) and a tangential model ([`TangentialSubModel`]: [`MfixTotal`],
//! [`IncrementalMindlin`]). Each declares what the rest of the engine needs of it: its
//! parameters and how they are mixed for a pair (`coefficients`, at set-up), its force, its
//! touch and pull-off condition (`touching`, `wall_touching`, `REACHES`), the normal force its
//! Coulomb limit takes (`critical`), its stored energy and its history size (`HISTORY`).
//!
//! The force stage is generic over one normal and one tangential type: it is monomorphised
//! once per pair of them, the law chosen once at set-up (`Simulation`'s dispatch), never a
//! dynamic call per contact; every sub-model's functions are `#[inline(always)]` and
//! branch-free, so the batch loop over contacts (and its AVX2 and AVX-512 copies) still
//! compiles to vector code for each law.
//!
//! **Damping and rolling stay selectors** ([`NormalDamping`], [`LeverArm`](super::LeverArm), `law::parts`)
//! rather than types. Their variants differ in a scale (×m_eff, ×√m_eff, ×1) or a lever arm,
//! formed for every variant and picked without a branch, and the `parts` bits already compile
//! out the costly ones (a square root for Tsuji, the rolling torque) where a law cannot pick
//! them. As type parameters they would multiply the compiled copies of the force stage (×4
//! damping × 3 lever arms on top of 3 normal × 2 tangential models, each with its pair, wall
//! and instruction-set copies) for no speed: the picks cost nothing measurable (bench/results).
//! How a damping depends on the overlap belongs to the normal model (Hertz's δ^¼, JKR's √a),
//! which is where it is.
//!
//! **History.** A contact stores one `Vec3` (in the neighbour list, for pairs and walls alike):
//! the tangential model's `HISTORY` = 3 values. A normal model may use what is left
//! ([`NormalSubModel::HISTORY`]; none needs any today). A cohesive model's contact outlives
//! the touch, so whether it has formed must be known at a negative overlap: for a pair that is
//! the list's contact flag, and for a wall pair (which has none) and after a checkpoint
//! restore (which derives the flag from the history) it is the history being non-zero. A
//! cohesive model therefore stores a zero history as −0.0 ([`mark_formed`]): the sign of a
//! zero changes no sum, product or comparison the law makes, and a history of +0.0 in every
//! component keeps meaning "no contact" everywhere.

use super::coefficients::{ContactCoeffs, ContactParams, damping_coefficient};
use super::geometry::pair_touching;
use super::{ContactLaw, HistoryFrame, NormalDamping, NormalModel, TangentialModel, limits};
use crate::error::EngineError;
use crate::math::{Vec3, pick};

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

/// The elastic constants of the two bodies of a contact and its effective radius, for the
/// normal models that derive their stiffness from them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticPair {
    /// Young's modulus and Poisson's ratio of body 1, Pa and –.
    pub e1: f64,
    /// Poisson's ratio of body 1.
    pub nu1: f64,
    /// Young's modulus of body 2 (a wall's for a wall contact), Pa.
    pub e2: f64,
    /// Poisson's ratio of body 2.
    pub nu2: f64,
    /// R* = R₁R₂/(R₁ + R₂) of the phases' radii (R of the phase at a wall), m.
    pub r_star: f64,
}

impl ElasticPair {
    /// E* = 1/((1 − ν₁²)/E₁ + (1 − ν₂²)/E₂), Pa.
    pub fn e_star(&self) -> f64 {
        1.0 / ((1.0 - self.nu1 * self.nu1) / self.e1 + (1.0 - self.nu2 * self.nu2) / self.e2)
    }

    /// G* = 1/((2 − ν₁)/G₁ + (2 − ν₂)/G₂), G = E/(2(1 + ν)), Pa.
    pub fn g_star(&self) -> f64 {
        let g1 = self.e1 / (2.0 * (1.0 + self.nu1));
        let g2 = self.e2 / (2.0 * (1.0 + self.nu2));
        1.0 / ((2.0 - self.nu1) / g1 + (2.0 - self.nu2) / g2)
    }
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
fn set_up_mass_scale(damping: NormalDamping, m_eff: f64) -> f64 {
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

/// A tangential contact model: the spring and dashpot, its history and the Coulomb cap.
pub trait TangentialSubModel: Copy + Default + Send + Sync + 'static {
    /// The setting this type implements.
    const MODEL: TangentialModel;
    /// History values it stores: the tangential displacement or force, 3.
    const HISTORY: usize;

    /// The tangential force and the history to store, from the stored history `h` already in
    /// the tangent plane as `frame` asks, the normal `n`, the tangential velocity `v_t`, the
    /// stiffness `k` and damping `damp_t` in use, the Coulomb limit `limit`, `lammps` for
    /// LAMMPS's cap (else MFIX's) and the step `dt`. Branch-free.
    #[allow(clippy::too_many_arguments)]
    fn force(
        h: Vec3,
        n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3);
}

/// A cohesive contact's stored history with its zero marked as −0.0 (see the module doc), so
/// that a formed contact is told from none by its history alone. Branch-free; other values
/// unchanged.
#[inline(always)]
pub fn mark_formed(h: Vec3) -> Vec3 {
    let zero = (h.x.to_bits() | h.y.to_bits() | h.z.to_bits()) == 0;
    Vec3::new(f64::from_bits(h.x.to_bits() | ((zero as u64) << 63)), h.y, h.z)
}

/// Whether a stored history says the contact had formed: any component other than +0.0.
#[inline(always)]
pub fn formed(h: Vec3) -> bool {
    (h.x.to_bits() | h.y.to_bits() | h.z.to_bits()) != 0
}

/// The checks and restitution-based damping shared by the models that take e_n, μ and μ_r.
fn common_checks(what: &str, p: &ContactParams) -> Result<(), EngineError> {
    limits::EN.check(what, "en", p.en)?;
    limits::MU.check(what, "mu", p.mu)?;
    limits::MU_ROLL.check(what, "mu_roll", p.mu_roll)
}

/// η_n for stiffness `k`, effective mass `m` and restitution `e`, by the law's damping rule
/// (for `Tsuji`, per √mass: α√k; `MassVelocity` is set from γ_n by the caller).
fn normal_damping(law: &ContactLaw, k: f64, m: f64, e: f64) -> f64 {
    match law.damping {
        NormalDamping::Mfix => damping_coefficient(k, m, e),
        NormalDamping::ExactRestitution => {
            super::damping::exact_damping_ratio(law.normal, e, law.clip_attraction) * (k * m).sqrt()
        }
        NormalDamping::Tsuji => super::coefficients::tsuji_alpha(e) * k.sqrt(),
        NormalDamping::MassVelocity => 0.0,
    }
}

/// (γ_n, γ_t) per unit mass for `MassVelocity` damping; γ_t defaults to γ_n/2 (LAMMPS).
fn mass_velocity(what: &str, p: &ContactParams) -> Result<(f64, f64), EngineError> {
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
fn elastic_given(what: &str, elastic: Option<ElasticPair>, model: &str) -> Result<ElasticPair, EngineError> {
    elastic.ok_or_else(|| EngineError::MissingParameter {
        what: format!("{what} elastic constants"),
        model: model.into(),
    })
}

/// The linear spring–dashpot (MFIX `LSD`, LAMMPS `hooke`): F_n = k_n·δ + η_n·v_n, k_t = κ·k_n.
#[derive(Debug, Clone, Copy, Default)]
pub struct LinearSpringDashpot;

impl NormalSubModel for LinearSpringDashpot {
    const MODEL: NormalModel = NormalModel::LinearSpringDashpot;
    const REACHES: bool = false;
    const HISTORY: usize = 0;
    const ELASTIC: bool = false;

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
                let eta_n = normal_damping(law, kn, m_eff, p.en);
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

/// Hertz (MFIX `HERTZIAN`, LAMMPS `hertz/material`): F_n = K_n·δ^1.5 + η_n·δ^¼·v_n with
/// K_n = (4/3)E*√R*, tangential stiffness K_t·√δ with K_t = 8G*√R*.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hertz;

impl NormalSubModel for Hertz {
    const MODEL: NormalModel = NormalModel::Hertz;
    const REACHES: bool = false;
    const HISTORY: usize = 0;
    const ELASTIC: bool = true;

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
            NormalDamping::MassVelocity | NormalDamping::Tsuji => 1.0,
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
                _ => normal_damping(law, kn, m_eff, p.en),
            },
            eta_t: match law.damping {
                NormalDamping::Mfix | NormalDamping::ExactRestitution => {
                    damping_coefficient(kt, 2.0 / 7.0 * m_eff, et)
                }
                NormalDamping::Tsuji => p.etat_fac * normal_damping(law, kn, m_eff, p.en),
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

/// JKR cohesion (Johnson, Kendall & Roberts 1971), as LAMMPS's `pair granular … jkr` with
/// `damping tsuji` (LAMMPS's example `in.pour.drum` pairs them):
///
/// - contact radius a(δ) from δ = a²/R* − 2√(πγa/E*) (the stable branch);
/// - F_n = (4/3)E*·a³/R* − 4√(πγE*)·a^{3/2} + α(e_n)·√((4/3)E*·a·m_eff)·v_n;
/// - tangential stiffness 8G*·a, damping `etat_fac` times the normal one;
/// - a contact forms at touch (δ ≥ 0) and holds until δ = −δ_c, δ_c = a_c²/(3R*),
///   a_c = (9πγR*²/(4E*))^{1/3}: where the tensile force is largest, F_n = −F_c with the
///   pull-off force F_c = 3πγR* (LAMMPS's `pulloff_distance`, and the force-controlled
///   pull-off of JKR's theory);
/// - Coulomb limit μ·|F_ne + 2F_c| (LAMMPS's critical force: the elastic force measured from
///   the pull-off state), which is also the load of the rolling torque.
///
/// γ is LAMMPS's surface energy (J/m²): the work of adhesion is w = 2γ, so that F_c =
/// (3/2)πwR*.
#[derive(Debug, Clone, Copy, Default)]
pub struct Jkr;

impl Jkr {
    /// The contact radius a and √a at overlap `delta` (≥ −δ_c) for E* = `e_star`, R* =
    /// `r_star`, γ = `gamma` > 0: the largest root of the quartic in x = √a,
    /// x⁴ − p·x − q = 0, p = R*√(4πγ/E*), q = R*δ, by Ferrari's method (its resolvent cubic
    /// m³ + q·m − p²/8 = 0 by Cardano's, written without cancellation on either sign of q).
    /// Branch-free.
    #[inline(always)]
    pub fn contact_radius(e_star: f64, r_star: f64, gamma: f64, delta: f64) -> (f64, f64) {
        let p = r_star * (4.0 * std::f64::consts::PI * gamma / e_star).sqrt();
        let q = r_star * delta;
        let a0 = p * p / 16.0;
        let q3 = q / 3.0;
        // The cubic's discriminant; ≥ 0 down to the pull-off (and below, to the smallest
        // overlap the branch reaches), rounding aside.
        let disc = (a0 * a0 + q3 * q3 * q3).max(0.0);
        let u = (a0 + disc.sqrt()).cbrt();
        let v = -q3 / u;
        // m = u + v: for q ≥ 0 as (u³ + v³)/(u² − uv + v²), whose terms are all positive.
        let m_pos = (2.0 * a0) / (u * u + q3 + v * v);
        let m = if q >= 0.0 { m_pos } else { u + v };
        let s = (2.0 * m).sqrt();
        let x = 0.5 * (s + (2.0 * p / s - s * s).max(0.0).sqrt());
        (x * x, x)
    }

    /// The pull-off force F_c = 3πγR*, N.
    #[inline(always)]
    pub fn pull_off_force(c: &ContactCoeffs) -> f64 {
        3.0 * std::f64::consts::PI * c.surface_energy * c.r_star
    }

    /// The pull-off distance δ_c = a_c²/(3R*), a_c = (9πγR*²/(4E*))^{1/3}, m: the contact
    /// ends at δ = −δ_c.
    pub fn pull_off_distance(e_star: f64, r_star: f64, gamma: f64) -> f64 {
        let a_c = (9.0 * std::f64::consts::PI * gamma * r_star * r_star / (4.0 * e_star)).cbrt();
        a_c * a_c / (3.0 * r_star)
    }

    /// G(a) = 8E*a⁵/(15R*²) − (8/3)E*·c·a^{7/2}/R* + 2E*c²a², c = √(πγ/E*): the work
    /// ∫F_ne dδ along the branch as a function of the contact radius.
    fn work(e_star: f64, r_star: f64, gamma: f64, a: f64) -> f64 {
        let c = (std::f64::consts::PI * gamma / e_star).sqrt();
        e_star
            * (8.0 * a.powi(5) / (15.0 * r_star * r_star) - 8.0 / 3.0 * c * a.powf(3.5) / r_star
                + 2.0 * c * c * a * a)
    }
}

impl NormalSubModel for Jkr {
    const MODEL: NormalModel = NormalModel::Jkr;
    const REACHES: bool = true;
    const HISTORY: usize = 0;
    const ELASTIC: bool = true;

    /// kn = (4/3)E*, kt = 8G* (or `hertz_kt`/√R*: not offered), R*, γ = `surface_energy`
    /// (given per contact table, as LAMMPS's `pair_coeff` gives it per type pair), the
    /// pull-off distance; η_n = α(e_n)·√kn per √mass (Tsuji's, the only damping taken),
    /// η_t = `etat_fac`·η_n.
    fn coefficients(
        law: &ContactLaw,
        what: &str,
        p: &ContactParams,
        m_eff: f64,
        elastic: Option<ElasticPair>,
    ) -> Result<ContactCoeffs, EngineError> {
        common_checks(what, p)?;
        let h = elastic_given(what, elastic, "jkr")?;
        if law.damping != NormalDamping::Tsuji {
            return Err(EngineError::BadReference(format!(
                "{what}: the jkr model takes damping = \"tsuji\" (as LAMMPS's examples pair them), not {:?}",
                law.damping
            )));
        }
        if law.clip_attraction {
            return Err(EngineError::BadReference(format!(
                "{what}: the jkr model is attractive by design; clip_attraction = true would remove its adhesion"
            )));
        }
        let gamma = p.surface_energy.ok_or_else(|| EngineError::MissingParameter {
            what: format!("{what} surface_energy (J/m²)"),
            model: "jkr".into(),
        })?;
        limits::SURFACE_ENERGY.check(what, "surface_energy", gamma)?;
        limits::ETAT_FAC.check(what, "etat_fac", p.etat_fac)?;
        let e_star = h.e_star();
        let kn = 4.0 / 3.0 * e_star;
        let eta_n = normal_damping(law, kn, m_eff, p.en);
        Ok(ContactCoeffs {
            kn,
            kt: 8.0 * h.g_star(),
            eta_n,
            eta_t: p.etat_fac * eta_n,
            mu: p.mu,
            mu_roll: p.mu_roll,
            m_eff,
            r_star: h.r_star,
            surface_energy: gamma,
            pull_off: Jkr::pull_off_distance(e_star, h.r_star, gamma),
        })
    }

    #[inline(always)]
    fn parts(c: &ContactCoeffs, delta: f64, v_n: f64) -> NormalParts {
        let e_star = 0.75 * c.kn;
        let (a, x) = Jkr::contact_radius(e_star, c.r_star, c.surface_energy, delta);
        let hertz = c.kn * a * a * a / c.r_star;
        let adhesion = 4.0 * (std::f64::consts::PI * c.surface_energy * e_star).sqrt() * a * x;
        NormalParts {
            elastic: hertz - adhesion,
            damping: c.eta_n * x * v_n,
            k_t: c.kt * a,
            eta_t: c.eta_t * x,
        }
    }

    #[inline(always)]
    fn critical(c: &ContactCoeffs, elastic: f64, _total: f64) -> f64 {
        (elastic + 2.0 * Jkr::pull_off_force(c)).abs()
    }

    #[inline(always)]
    fn rolling_load(_elastic: f64, critical: f64) -> f64 {
        critical
    }

    /// ∫₀^δ F_ne dδ′ along the branch: zero at first touch, negative where adhesion wins.
    fn energy(c: &ContactCoeffs, delta: f64) -> f64 {
        let e_star = 0.75 * c.kn;
        let (a, _) = Jkr::contact_radius(e_star, c.r_star, c.surface_energy, delta);
        let (a0, _) = Jkr::contact_radius(e_star, c.r_star, c.surface_energy, 0.0);
        Jkr::work(e_star, c.r_star, c.surface_energy, a) - Jkr::work(e_star, c.r_star, c.surface_energy, a0)
    }

    /// (4/3)E* and 8G* do not take R* (the contact radius a does, through the coefficients'
    /// R*), and Tsuji's damping, the only one JKR takes, scales with m_eff already.
    #[inline(always)]
    fn size_scales(_damping: NormalDamping, _r_star: f64, _m_eff: f64) -> SizeScales {
        SizeScales { stiffness: 1.0, damping: 1.0 }
    }

    /// δ_c = a_c²/(3R*) with a_c ∝ R*^⅔: δ_c ∝ R*^⅓.
    #[inline(always)]
    fn pull_off_scale(r_star: f64) -> f64 {
        r_star.cbrt()
    }

    /// Touching (δ ≥ 0, MFIX's test) forms a contact; a formed one holds while the centres
    /// are closer than R_i + R_j + δ_c.
    #[inline(always)]
    fn touching(d2: f64, ri: f64, rj: f64, reach: f64, touched: bool) -> bool {
        let lim = ri + rj + reach;
        pair_touching(d2, ri, rj) | (touched & (d2 < lim * lim))
    }

    #[inline(always)]
    fn wall_touching(overlap: f64, reach: f64, touched: bool) -> bool {
        overlap.is_nan() | (overlap >= 0.0) | (touched & (overlap > -reach))
    }
}

/// MFIX 21.3's tangential spring: the history is the total tangential displacement s;
/// F_t = −k·s − η_t·v_t, capped at μ·F.
#[derive(Debug, Clone, Copy, Default)]
pub struct MfixTotal;

impl TangentialSubModel for MfixTotal {
    const MODEL: TangentialModel = TangentialModel::MfixTotal;
    const HISTORY: usize = 3;

    #[inline(always)]
    fn force(
        h: Vec3,
        n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3) {
        let s = h + dt * v_t;
        let s = pick(frame == HistoryFrame::Project, s - s.dot(n) * n, s);
        let trial = -k * s - damp_t * v_t;
        let len = s.length();
        let dir = s / len;
        let lammps_capped = (limit / trial.length()) * trial;
        let capped = pick(lammps, lammps_capped, -limit * dir);
        let capped_stored = pick(lammps, -(lammps_capped + damp_t * v_t) / k, (limit / k) * dir);
        let capped_stored = pick(k > 0.0, capped_stored, Vec3::ZERO);
        let sliding = trial.length_squared() > limit * limit;
        let stuck = s.length_squared() == 0.0;
        (
            pick(sliding, pick(stuck, Vec3::ZERO, capped), trial),
            pick(sliding, pick(stuck, Vec3::ZERO, capped_stored), s),
        )
    }
}

/// The incremental Mindlin spring: the history is the elastic tangential force, incremented
/// by −k(δ)·v_t·Δt each step; F_t = history − η_t·v_t, capped at μ·F. Identical to
/// [`MfixTotal`] for the linear law.
#[derive(Debug, Clone, Copy, Default)]
pub struct IncrementalMindlin;

impl TangentialSubModel for IncrementalMindlin {
    const MODEL: TangentialModel = TangentialModel::IncrementalMindlin;
    const HISTORY: usize = 3;

    #[inline(always)]
    fn force(
        h: Vec3,
        _n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        _frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3) {
        let f_el = h - k * dt * v_t;
        let trial = f_el - damp_t * v_t;
        let len = f_el.length();
        // Beyond the limit: LAMMPS scales the trial force down, MFIX the spring.
        let lammps_capped = (limit / trial.length()) * trial;
        let mfix_capped = (limit / len) * f_el;
        let capped = pick(lammps, lammps_capped, mfix_capped);
        let capped_stored = pick(lammps, lammps_capped + damp_t * v_t, mfix_capped);
        let sliding = trial.length_squared() > limit * limit;
        // |f_el| = 0 exactly when |f_el|² = 0: no square root where only LAMMPS's cap is used.
        let stuck = f_el.length_squared() == 0.0;
        (
            pick(sliding, pick(stuck, Vec3::ZERO, capped), trial),
            pick(sliding, pick(stuck, Vec3::ZERO, capped_stored), f_el),
        )
    }
}

/// Calls `$body` with the types `$n: NormalSubModel` and `$t: TangentialSubModel` of the
/// law's settings (`$law`): the one place a runtime law becomes types. `$body` is expanded
/// once per combination, so each is monomorphised.
#[macro_export]
#[doc(hidden)]
macro_rules! with_submodels {
    ($law:expr, |$n:ident, $t:ident| $body:expr) => {{
        use $crate::contact::submodel as sm;
        use $crate::contact::{NormalModel as NM, TangentialModel as TM};
        match ($law.normal, $law.tangential) {
            (NM::LinearSpringDashpot, TM::MfixTotal) => {
                type $n = sm::LinearSpringDashpot;
                type $t = sm::MfixTotal;
                $body
            }
            (NM::LinearSpringDashpot, TM::IncrementalMindlin) => {
                type $n = sm::LinearSpringDashpot;
                type $t = sm::IncrementalMindlin;
                $body
            }
            (NM::Hertz, TM::MfixTotal) => {
                type $n = sm::Hertz;
                type $t = sm::MfixTotal;
                $body
            }
            (NM::Hertz, TM::IncrementalMindlin) => {
                type $n = sm::Hertz;
                type $t = sm::IncrementalMindlin;
                $body
            }
            (NM::Jkr, TM::MfixTotal) => {
                type $n = sm::Jkr;
                type $t = sm::MfixTotal;
                $body
            }
            (NM::Jkr, TM::IncrementalMindlin) => {
                type $n = sm::Jkr;
                type $t = sm::IncrementalMindlin;
                $body
            }
        }
    }};
}

/// Calls `$body` with the type `$n: NormalSubModel` of a [`NormalModel`] value.
#[macro_export]
#[doc(hidden)]
macro_rules! with_normal_submodel {
    ($normal:expr, |$n:ident| $body:expr) => {{
        use $crate::contact::NormalModel as NM;
        use $crate::contact::submodel as sm;
        match $normal {
            NM::LinearSpringDashpot => {
                type $n = sm::LinearSpringDashpot;
                $body
            }
            NM::Hertz => {
                type $n = sm::Hertz;
                $body
            }
            NM::Jkr => {
                type $n = sm::Jkr;
                $body
            }
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Coefficients of a JKR contact: E* = 1e7 Pa, G* from ν = 0.3, R* = 1 mm, γ = 0.05 J/m².
    fn jkr(gamma: f64) -> ContactCoeffs {
        let law = ContactLaw { damping: NormalDamping::Tsuji, ..ContactLaw::mfix(NormalModel::Jkr) };
        let e = 2.0e7 * (1.0 - 0.09);
        let el = ElasticPair { e1: e, nu1: 0.3, e2: e, nu2: 0.3, r_star: 1e-3 };
        let p = ContactParams { surface_energy: Some(gamma), en: 0.5, ..Default::default() };
        Jkr::coefficients(&law, "test", &p, 1e-6, Some(el)).expect("valid")
    }

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// The contact radius solves the JKR relation δ = a²/R − 2√(πγa/E*) on the stable branch
    /// (da/dδ > 0), from the pull-off to deep overlap. Tolerance 1e-12 relative to the
    /// overlap scale: the closed form takes a cube root, a handful of square roots and
    /// divisions, each within half an ulp, and the relation itself is evaluated with a few
    /// more roundings; nothing amplifies them by more than a few units away from the branch's
    /// end, where the two roots meet (not reached before the pull-off).
    #[test]
    fn contact_radius_solves_the_jkr_relation() {
        for gamma in [1e-3, 0.05, 2.0] {
            let c = jkr(gamma);
            let e = 0.75 * c.kn;
            let dc = c.pull_off;
            let scale = dc.max(1e-9);
            let mut last = 0.0;
            for k in 0..=400 {
                let delta = -dc + k as f64 * (50.0 * dc) / 400.0;
                let (a, x) = Jkr::contact_radius(e, c.r_star, gamma, delta);
                assert!((x * x - a).abs() <= 1e-15 * a);
                let back = a * a / c.r_star - 2.0 * (PI * gamma * a / e).sqrt();
                assert!(
                    (back - delta).abs() <= 1e-12 * scale.max(delta.abs()),
                    "γ {gamma}, δ {delta:e}: {back:e}"
                );
                assert!(a > last, "stable branch: a grows with δ");
                last = a;
            }
        }
    }

    /// The closed forms: at δ = −δ_c the force is −F_c = −3πγR*, and it is the largest
    /// tension on the branch; δ_c = a_c²/(3R*) with a_c³ = 9πγR*²/(4E*); at touch (δ = 0),
    /// F = −(8/9)F_c. Tolerance 1e-12 relative: the force at −δ_c is an extremum in a as in
    /// δ, so an error in the contact radius enters only squared; what remains is the rounding
    /// of a dozen operations (≈1e-15 each) in the closed form of a and the force. The contact
    /// radius itself carries its roundings amplified by |da/dδ|·δ/a, a few units here (the two
    /// roots of the quartic meet only at −2.08 δ_c, beyond the pull-off).
    #[test]
    fn pull_off_force_and_distance_match_the_closed_forms() {
        for gamma in [1e-3, 0.05, 2.0] {
            let c = jkr(gamma);
            let e = 0.75 * c.kn;
            let f_c = 3.0 * PI * gamma * c.r_star;
            assert!(rel(Jkr::pull_off_force(&c), f_c) < 1e-15);
            let a_c = (9.0 * PI * gamma * c.r_star * c.r_star / (4.0 * e)).cbrt();
            assert!(rel(c.pull_off, a_c * a_c / (3.0 * c.r_star)) < 1e-15);
            let f = |d: f64| Jkr::parts(&c, d, 0.0).elastic;
            assert!(rel(f(-c.pull_off), -f_c) < 1e-12, "F(−δ_c) = {:e}, −F_c = {:e}", f(-c.pull_off), -f_c);
            // The largest tension: the neighbours on both sides pull less.
            for s in [1e-3, 1e-2, 0.1] {
                assert!(f(-c.pull_off * (1.0 - s)) > f(-c.pull_off));
            }
            // The contact radius at pull-off is a_c.
            let (a, _) = Jkr::contact_radius(e, c.r_star, gamma, -c.pull_off);
            assert!(rel(a, a_c) < 1e-12, "a(−δ_c) = {a:e}, a_c = {a_c:e}");
            // At touch, a³ = 4πγR*²/E* and the tension is (8/9)·F_c.
            assert!(rel(f(0.0), -8.0 / 9.0 * f_c) < 1e-12, "F(0) = {:e}", f(0.0));
        }
    }

    /// JKR tends to Hertz far from the pull-off (adhesion ∝ a^{3/2}, elasticity ∝ a³), and the
    /// energy is the integral of the force (central differences, relative 1e-6: the
    /// truncation error of a step of 1e-4·δ_c against a curvature of order F/δ_c).
    #[test]
    fn energy_is_the_integral_of_the_force_and_large_overlaps_are_hertzian() {
        let c = jkr(0.05);
        let dc = c.pull_off;
        for delta in [-0.9 * dc, -0.3 * dc, 0.0, 0.5 * dc, 3.0 * dc, 40.0 * dc] {
            let h = 1e-4 * dc;
            let du = (Jkr::energy(&c, delta + h) - Jkr::energy(&c, delta - h)) / (2.0 * h);
            let f = Jkr::parts(&c, delta, 0.0).elastic;
            assert!((du - f).abs() <= 1e-6 * Jkr::pull_off_force(&c), "δ {delta:e}: dU/dδ {du:e}, F {f:e}");
        }
        assert_eq!(Jkr::energy(&c, 0.0), 0.0);
        let delta = 1e4 * dc;
        let hertz = c.kn * c.r_star.sqrt() * delta.powf(1.5);
        let f = Jkr::parts(&c, delta, 0.0).elastic;
        assert!(rel(f, hertz) < 0.05, "{f:e} vs Hertz {hertz:e}");
    }

    /// A formed contact holds to −δ_c and no further; a fresh one needs δ ≥ 0.
    #[test]
    fn touch_and_pull_off_conditions() {
        let c = jkr(0.05);
        let (r, dc) = (1e-3, c.pull_off);
        let d2 = |delta: f64| (2.0 * r - delta).powi(2);
        assert!(Jkr::touching(d2(1e-9), r, r, dc, false));
        assert!(!Jkr::touching(d2(-0.5 * dc), r, r, dc, false));
        assert!(Jkr::touching(d2(-0.5 * dc), r, r, dc, true));
        assert!(!Jkr::touching(d2(-1.01 * dc), r, r, dc, true));
        assert!(Jkr::wall_touching(-0.5 * dc, dc, true) && !Jkr::wall_touching(-0.5 * dc, dc, false));
        assert!(!Jkr::wall_touching(-1.01 * dc, dc, true));
        // The marked zero history says "formed" and still acts as zero.
        let h = mark_formed(Vec3::ZERO);
        assert!(formed(h) && h == Vec3::ZERO && !formed(Vec3::ZERO));
        assert_eq!(mark_formed(Vec3::X), Vec3::X);
    }
}
