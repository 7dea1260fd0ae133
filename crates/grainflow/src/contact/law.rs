//! Contact forces and torques (reference: MFIX-DEM model §4).
//!
//! One function, [`contact_force`], serves particle–particle and particle–wall contacts; it is
//! generic over the normal and the tangential sub-model types ([`super::normal`], [`super::tangential`]) so that
//! the force loop is monomorphised once per law. It forms what every law shares (the normal
//! and tangential velocities, the history in the tangent plane, the Coulomb cap's choice) and
//! asks the sub-models for the rest.

use super::geometry::ContactGeometry;
use super::normal::NormalSubModel;
use super::submodel::mark_formed;
use super::tangential::TangentialSubModel;
use super::{ContactCoeffs, ContactLaw, CoulombCap, HistoryFrame, NormalModel};
use crate::math::{Vec3, pick};

/// The forces of one contact on particle i (particle j, if any, gets the opposite force).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce {
    /// Normal force on i, N.
    pub normal: Vec3,
    /// Tangential force on i, N.
    pub tangential: Vec3,
    /// The elastic part of the normal force (k_n·δ, K_n·δ^1.5, or JKR's with its adhesion,
    /// negative where that wins), N.
    pub elastic_normal: f64,
    /// The normal load of the rolling torque: `elastic_normal`, or for JKR the critical force
    /// |F_ne + 2F_c|, N.
    pub rolling_load: f64,
    /// The Coulomb limit μ·F_c, N: the tangential force's magnitude never exceeds it (to
    /// rounding).
    pub limit: f64,
    /// An upper bound of the total force's magnitude (to rounding), |F_n| + the Coulomb
    /// limit, N.
    pub bound: f64,
}

impl ContactForce {
    /// Total force on i.
    #[inline(always)]
    pub fn total(&self) -> Vec3 {
        self.normal + self.tangential
    }

    /// Torque of the tangential force on i about its centre, for lever arm `a_i`:
    /// a_i·(n × F_t). Particle j gets a_j·(n × F_t) (same sign).
    #[inline(always)]
    pub fn torque(&self, lever: f64, n: Vec3) -> Vec3 {
        lever * n.cross(self.tangential)
    }
}

/// The optional parts of a contact law, as bits of the `PARTS` parameter of
/// [`contact_force_for`]. A loop that runs one law compiles only the parts that law can pick
/// (a branch-free law otherwise computes every variant's value — several square roots and
/// divisions each — and picks one); the values it picks are the same either way.
pub mod parts {
    use crate::contact::{ContactLaw, CoulombCap, HistoryFrame, LeverArm};

    /// The history rescaled to its stored length ([`HistoryFrame::Rotate`]).
    pub const ROTATE: u8 = 1;
    /// MFIX's Coulomb cap ([`CoulombCap::Mfix`]).
    pub const MFIX_CAP: u8 = 2;
    /// LAMMPS's Coulomb cap ([`CoulombCap::Lammps`]).
    pub const LAMMPS_CAP: u8 = 4;
    /// Rolling friction (some μ_r ≠ 0).
    pub const ROLLING: u8 = 8;
    /// Damping ∝ √m_eff ([`Tsuji`](crate::contact::NormalDamping::Tsuji),
    /// [`Liggghts`](crate::contact::NormalDamping::Liggghts)).
    pub const TSUJI: u8 = 16;
    /// Lever arms to the radical plane ([`LeverArm::RadicalPlane`]).
    pub const RADICAL: u8 = 32;
    /// Each contact's coefficients formed from its own size: the coefficients are per unit
    /// size ([`CoeffTable::sized`](crate::contact::CoeffTable::sized)). A property of the
    /// table, not of the law's settings, so not in [`ALL`].
    pub const SIZED: u8 = 64;
    /// LIGGGHTS's Coulomb cap ([`CoulombCap::Liggghts`]).
    pub const LIGGGHTS_CAP: u8 = 128;
    /// Every part the law's settings can pick: the law for any settings.
    pub const ALL: u8 = ROTATE | MFIX_CAP | LAMMPS_CAP | ROLLING | TSUJI | RADICAL | LIGGGHTS_CAP;

    /// The parts `law` needs; `rolling` if some contact has rolling friction, `sized` if the
    /// coefficients are per unit size.
    pub fn needed(law: &ContactLaw, rolling: bool, sized: bool) -> u8 {
        let bit = |on: bool, b: u8| if on { b } else { 0 };
        bit(sized, SIZED)
            | bit(law.history == HistoryFrame::Rotate, ROTATE)
            | bit(law.coulomb == CoulombCap::Mfix, MFIX_CAP)
            | bit(law.coulomb == CoulombCap::Lammps, LAMMPS_CAP)
            | bit(law.coulomb == CoulombCap::Liggghts, LIGGGHTS_CAP)
            | bit(rolling, ROLLING)
            | bit(law.damping.per_root_mass(), TSUJI)
            | bit(law.lever == LeverArm::RadicalPlane, RADICAL)
    }
}

/// Normal and tangential force of one contact, updating the stored tangential `history`.
///
/// `clip` floors the normal force at zero (no attraction at the end of a contact); `cap`
/// chooses MFIX's or LAMMPS's treatment of a force beyond the Coulomb limit.
/// `N` is the normal sub-model (force, stiffness and damping scaling, the Coulomb limit's
/// normal force); `T` the tangential one (MFIX's total displacement, history = tangential
/// displacement s, or the incremental Mindlin spring, history = elastic tangential force).
///
/// Per MFIX: trial s = h + Δt·v_t; F_t = −k·s − c·v_t; if |F_t| > μ·|F_n| then
/// F_t = −μ·|F_n|·s/|s| and s ← (μ·|F_n|/k)·s/|s|; h ← s after every contact step.
///
/// Written without data-dependent branches: every case's value is formed and the right one
/// picked, so that a loop over contacts compiles to vector instructions
/// (see `forces`). The picked values are the same operations in the same order as a branching
/// form, so the results do not depend on how the function is compiled.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn contact_force<N: NormalSubModel, T: TangentialSubModel>(
    frame: HistoryFrame,
    clip: bool,
    cap: CoulombCap,
    c: &ContactCoeffs,
    g: &ContactGeometry,
    v_r: Vec3,
    history: &mut Vec3,
    dt: f64,
) -> ContactForce {
    contact_force_for::<N, T, { parts::ALL }>(frame, clip, cap, c, g, v_r, history, dt)
}

/// [`contact_force`] with only the optional [`parts`] in `PARTS` compiled: `frame` and `cap`
/// must be among them (the others' values are never formed). The same result, to the bit.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn contact_force_for<N: NormalSubModel, T: TangentialSubModel, const PARTS: u8>(
    frame: HistoryFrame,
    clip: bool,
    cap: CoulombCap,
    c: &ContactCoeffs,
    g: &ContactGeometry,
    v_r: Vec3,
    history: &mut Vec3,
    dt: f64,
) -> ContactForce {
    debug_assert!(PARTS & parts::ROTATE != 0 || frame != HistoryFrame::Rotate);
    debug_assert!(PARTS & parts::MFIX_CAP != 0 || cap != CoulombCap::Mfix);
    debug_assert!(PARTS & parts::LAMMPS_CAP != 0 || cap != CoulombCap::Lammps);
    debug_assert!(PARTS & parts::LIGGGHTS_CAP != 0 || cap != CoulombCap::Liggghts);
    let n = g.normal;
    let delta = g.overlap;
    let v_n = v_r.dot(n);
    let v_t = v_r - v_n * n;

    // Normal force and the tangential stiffness/damping in use.
    let np = N::parts(c, delta, v_n);
    let (fn_el, k, damp_t) = (np.elastic, np.k_t, np.eta_t);
    let fn_total = fn_el + np.damping;
    let fn_total = if clip && fn_total < 0.0 { 0.0 } else { fn_total };
    let f_n = -fn_total * n;
    let critical = N::critical(c, fn_el, fn_total);

    // The history in the current tangent plane: as stored (MFIX), projected, or projected
    // and rescaled to its stored length (rotated).
    let h = *history;
    let projected = h - h.dot(n) * n;
    let rotated = if PARTS & parts::ROTATE != 0 {
        let (len, plen) = (h.length(), projected.length());
        pick(plen > 0.0, projected * (len / plen), projected)
    } else {
        projected // never picked
    };
    let h = pick(frame == HistoryFrame::Mfix, h, pick(frame.projected(), projected, rotated));

    let limit = c.mu * critical;
    // Constants where only one cap is compiled, so that the others are never formed.
    let only = |bit: u8| PARTS & (parts::MFIX_CAP | parts::LAMMPS_CAP | parts::LIGGGHTS_CAP) == bit;
    let chosen = |bit: u8, this: CoulombCap| PARTS & bit != 0 && (only(bit) || cap == this);
    let lammps = chosen(parts::LAMMPS_CAP, CoulombCap::Lammps);
    let liggghts = chosen(parts::LIGGGHTS_CAP, CoulombCap::Liggghts);
    let (f_t, stored) = T::force(h, n, v_t, k, damp_t, limit, lammps, liggghts, frame, dt);
    // A cohesive contact is known by its history where it has no contact flag (module doc of
    // `submodel`).
    *history = if N::REACHES { mark_formed(stored) } else { stored };
    ContactForce {
        normal: f_n,
        tangential: f_t,
        elastic_normal: fn_el,
        rolling_load: N::rolling_load(fn_el, critical),
        limit,
        bound: fn_total.abs() + limit,
    }
}

/// Dispatches [`contact_force`] on a runtime [`ContactLaw`]. For tests and one-off use; the
/// force loop dispatches once, outside the loop.
pub fn contact_force_dyn(
    law: &ContactLaw,
    c: &ContactCoeffs,
    g: &ContactGeometry,
    v_r: Vec3,
    history: &mut Vec3,
    dt: f64,
) -> ContactForce {
    crate::with_submodels!(law, |N, T| contact_force::<N, T>(
        law.history,
        law.clip_attraction,
        law.coulomb,
        c,
        g,
        v_r,
        history,
        dt
    ))
}

/// Rolling-friction torque on a particle spinning at ω: −μ_r·|F_n,elastic|·ω̂ (zero at ω = 0
/// or μ_r = 0). Branch-free, like [`contact_force`].
#[inline(always)]
pub fn rolling_torque(mu_roll: f64, elastic_normal: f64, omega: Vec3) -> Vec3 {
    let w = omega.length();
    pick(mu_roll != 0.0 && w > 0.0, (-mu_roll * elastic_normal / w) * omega, Vec3::ZERO)
}

/// Energy stored in the normal contact: ½·k_n·δ² (LSD), (2/5)·K_n·δ^2.5 (Hertz), or JKR's
/// ∫₀^δ F_ne (zero at touch), J.
#[inline]
pub fn normal_spring_energy(normal: NormalModel, c: &ContactCoeffs, delta: f64) -> f64 {
    crate::with_normal_submodel!(normal, |N| <N as NormalSubModel>::energy(c, delta))
}
