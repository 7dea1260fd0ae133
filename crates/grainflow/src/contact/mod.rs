//! Contact detection and contact laws.
//!
//! - [`geometry`]: overlap, normal and lever arms of a particle pair or a particle and a wall.
//! - [`params`]: the plain types of a contact's inputs and derived coefficients.
//! - [`coefficients`]: stiffness and damping derived from the inputs, per phase pair and per
//!   phase–wall-material pair (MFIX's formulas).
//! - [`normal`], [`tangential`]: the sub-models, one file each (normal: linear, Hertz, JKR;
//!   tangential: MFIX's total displacement, incremental Mindlin), each with every fact the
//!   engine needs of it, and each category's registry; [`submodel`]: what they share.
//! - [`law`]: normal force, tangential spring with the Coulomb cap, torques, generic over the
//!   sub-models.
//! - `pair`: the law applied to one pair or wall contact as the force stage gathers it, and the
//!   effective masses, scaled damping and lever-arm geometry it and the diagnostics share.
//!
//! A contact law is chosen once, at set-up, as a [`ContactLaw`]; its normal and tangential
//! settings name the sub-model types the force loop is then monomorphised for (no dynamic
//! dispatch per contact).

pub mod coefficients;
pub mod damping;
pub mod geometry;
pub mod law;
pub mod limits;
pub mod normal;
pub(crate) mod pair;
pub mod params;
pub mod submodel;
pub mod tangential;

pub use coefficients::CoeffTable;
pub use normal::NormalModel;
pub use params::{ContactCoeffs, ContactParams, damping_coefficient, liggghts_beta, tsuji_alpha};
pub use tangential::TangentialModel;

/// What happens to the stored tangential history when the contact frame turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryFrame {
    /// MFIX 21.3: neither rotated nor projected.
    Mfix,
    /// Project onto the current tangent plane: s ← s − (s·n)·n.
    Project,
    /// Rotate into the current tangent plane: project, then restore the stored magnitude.
    Rotate,
    /// LIGGGHTS: projected as `Project`, and kept when the pair separates (LIGGGHTS resets it
    /// only within a `contact_distance_factor` > 1), so that a pair that touches again
    /// resumes its old displacement; kept while the pair stays in the neighbour list, through
    /// its rebuilds (wall contacts lose theirs apart, as in LIGGGHTS).
    Liggghts,
}

impl HistoryFrame {
    /// True when a pair's history is kept while it is apart ([`HistoryFrame::Liggghts`]).
    #[inline(always)]
    pub fn kept_apart(self) -> bool {
        self == HistoryFrame::Liggghts
    }

    /// True when the history is projected onto the tangent plane without rescaling.
    #[inline(always)]
    pub fn projected(self) -> bool {
        matches!(self, HistoryFrame::Project | HistoryFrame::Liggghts)
    }
}

/// Where the tangential force acts, i.e. the lever arm of its torque and of the spin's
/// contribution to the contact-point velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LeverArm {
    /// MFIX: the distance from the centre to the radical plane (R − δ/2 for equal spheres,
    /// R − δ against a wall). Conserves angular momentum about the contact point.
    RadicalPlane,
    /// The particle radius R, as in the rigid-body analysis of oblique impact (Maw, Barber &
    /// Fawcett; Chung & Ooi). Makes K·R·ω′ = (1 − e_t)·v_t0 exact for a wall impact.
    Radius,
    /// LAMMPS `pair granular` (2021): the contact-point velocity uses R; the torque R − δ/2
    /// between particles and R at walls (`fix wall/gran`).
    LammpsGranular,
    /// LIGGGHTS: R − δ/2 for both the contact-point velocity and the torque, between
    /// particles and at walls (`surface_model_default`).
    Liggghts,
}

/// How the normal damping coefficient follows from the restitution coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalDamping {
    /// MFIX: η_n = 2√(K_n M)·|ln e|/√(π² + ln²e) for both laws (exact only for the linear law
    /// without clipping).
    Mfix,
    /// η_n = α(e)·√(K_n M), with α solved so that a normal impact rebounds with exactly e,
    /// for the chosen law and clipping (see [`damping`]).
    ExactRestitution,
    /// LAMMPS `gran/hooke/history` and `granular … damping mass_velocity`: η_n = γ_n·m_eff and
    /// η_t = γ_t·m_eff, with γ_n, γ_t (1/s) given and m_eff = m_i m_j/(m_i + m_j) of the two
    /// particles in contact (the other particle's mass if one is held fixed; m_i at a wall).
    MassVelocity,
    /// LAMMPS `granular … damping tsuji`: η_n = α(e)·√(m_eff K_n) with LAMMPS's polynomial
    /// α(e) (Tsuji et al. 1992), m_eff of the two particles as for `MassVelocity`, and
    /// η_t = `etat_fac`·η_n.
    Tsuji,
    /// LIGGGHTS's damping from restitution, β = ln e/√(ln²e + π²), with m_eff of the two
    /// particles as for `MassVelocity`: `model hertz` γ_n = −2√(5/6)·β·√(S_n m_eff),
    /// γ_t = −2√(5/6)·β·√(S_t m_eff) with S_n = 2E*√(R*δ), S_t = 8G*√(R*δ) (so
    /// η_n = √5|β|·√(K_n m_eff)·δ^¼ and η_t = √(10/3)|β|·√(K_t m_eff)·δ^¼, times `etat_fac`);
    /// `model hooke` γ_n = √(4 m_eff k_n ln²e/(ln²e + π²)) = −2β√(k_n m_eff) and
    /// γ_t = `etat_fac`·γ_n.
    Liggghts,
}

impl NormalDamping {
    /// True when the damping depends on the masses of the particles in contact.
    pub fn per_particle_mass(&self) -> bool {
        matches!(self, NormalDamping::MassVelocity | NormalDamping::Tsuji | NormalDamping::Liggghts)
    }

    /// True when the damping is formed per √m_eff at set-up and scaled by the contact's
    /// √m_eff in the force loop (`Tsuji`, `Liggghts`).
    pub fn per_root_mass(&self) -> bool {
        matches!(self, NormalDamping::Tsuji | NormalDamping::Liggghts)
    }
}

/// What happens when the tangential force exceeds the Coulomb limit μ|F_n|.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoulombCap {
    /// MFIX: F_t = −μ|F_n|·ŝ along the spring, and the spring is set to μ|F_n|/k.
    Mfix,
    /// LAMMPS: the whole trial force (spring and dashpot) is scaled down to μ|F_n|, and the
    /// spring is set so that spring plus dashpot give that force.
    Lammps,
    /// LIGGGHTS (`tangential history`): the spring force alone is compared with μ|F_n|; beyond
    /// it the spring force is scaled down to μ|F_n| with no dashpot and the spring set to give
    /// it; within it the dashpot is added.
    Liggghts,
}

/// A complete contact law: normal model, tangential model and history treatment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContactLaw {
    /// Normal force law.
    pub normal: NormalModel,
    /// Tangential spring form.
    pub tangential: TangentialModel,
    /// Tangential history frame treatment.
    pub history: HistoryFrame,
    /// Lever arm of the tangential force.
    pub lever: LeverArm,
    /// Normal damping from restitution.
    pub damping: NormalDamping,
    /// Clip the normal force at zero, so that the dashpot never pulls the bodies together at
    /// the end of a contact (MFIX does not clip).
    pub clip_attraction: bool,
    /// Coulomb cap of the tangential force.
    pub coulomb: CoulombCap,
    /// Whose radii and masses a contact's stiffness and damping take.
    pub sizes: ContactSizes,
}

/// Whose radii and masses set a contact's coefficients (Hertz's R*, the damping's effective
/// mass, JKR's R* and pull-off distance), for beds whose particles differ from their phase's
/// reference diameter or density.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ContactSizes {
    /// Each contact's own: R* = R_iR_j/(R_i + R_j) (R_i at a wall) and m_eff = m_im_j/(m_i + m_j)
    /// (m_i at a wall) of the two particles in contact, as LAMMPS and LIGGGHTS do; the time step
    /// from the smallest particle. The default of native cases.
    #[default]
    Own,
    /// The phases' reference diameters and densities, as MFIX does (`des_etan`, `kn_des` per
    /// phase pair): every contact of a phase pair has the same coefficients, whatever the sizes
    /// of its particles. The form of MFIX decks.
    Phase,
}

impl ContactLaw {
    /// MFIX 21.3's form of the given normal model.
    pub fn mfix(normal: NormalModel) -> Self {
        ContactLaw {
            normal,
            tangential: TangentialModel::MfixTotal,
            history: HistoryFrame::Mfix,
            lever: LeverArm::RadicalPlane,
            damping: NormalDamping::Mfix,
            clip_attraction: false,
            coulomb: CoulombCap::Mfix,
            sizes: ContactSizes::Phase,
        }
    }

    /// A short name for messages, e.g. "hertz": the normal model's case-file name.
    pub fn normal_name(&self) -> &'static str {
        self.normal.name()
    }
}
