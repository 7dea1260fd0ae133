//! The physics of one contact as the force stage computes it: the law's load of a touching
//! pair or of a particle touching a wall, from the inputs gathered for it ([`PairInput`]), and
//! the helpers the stage and the diagnostics share (effective masses, damping scaled by them,
//! geometry with the law's lever arms, a history kept or cleared).
//!
//! Everything here is written without data-dependent branches: a value is formed for every
//! setting and one picked, so that the force stage's batch loop compiles to vector
//! instructions and a contact's load has the same bits however it is computed.

use crate::boundary::Periodic;
use crate::contact::geometry::{
    ContactGeometry, pair_contact_separation, pair_geometry, pair_geometry_without_levers,
    relative_velocity_of_centres, wall_contact,
};
use crate::contact::law::{ContactForce, contact_force_for, parts, rolling_torque};
use crate::contact::normal::{NormalSubModel, sized};
use crate::contact::tangential::TangentialSubModel;
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw, LeverArm, NormalDamping, NormalModel};
use crate::math::Vec3;
use crate::wall::Wall;

/// What one contact adds: the force on the lower slot a (b gets its opposite) and the torques
/// on a and b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairLoad {
    pub f: Vec3,
    pub ta: Vec3,
    pub tb: Vec3,
}

/// Upper bounds of the magnitudes of a contact's force and of each of its torques (to
/// rounding), N and N·m: what the sums' quanta are chosen from (`forces::sum`), cheaper to
/// track than the largest components themselves.
pub(crate) type LoadBound = [f64; 2];

/// The torque bound of a contact with force `f` and torque levers `levers`: the longer lever
/// times the Coulomb limit, plus the rolling torque's size where `PARTS` has rolling friction.
#[inline(always)]
fn torque_bound<const PARTS: u8>(f: &ContactForce, mu_roll: f64, levers: [f64; 2]) -> f64 {
    let (a, b) = (levers[0].abs(), levers[1].abs());
    let lever = if a > b { a } else { b };
    let rolling = if PARTS & parts::ROLLING != 0 { mu_roll.abs() * f.rolling_load.abs() } else { 0.0 };
    lever * f.limit + rolling
}

/// What the force law needs of one touching pair (a, b), gathered from the particle arrays.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairInput {
    /// x_b − x_a, the nearest image on periodic axes, m.
    pub d: Vec3,
    pub ra: f64,
    pub rb: f64,
    /// v_a − v_b: what the law needs of the velocities (one vector instead of two in the batch
    /// lanes: 0.93-0.99 of the chute's time, in one process alternating both forms).
    pub dv: Vec3,
    pub wa: Vec3,
    pub wb: Vec3,
    /// The stored tangential history.
    pub h: Vec3,
    pub c: ContactCoeffs,
    /// The contact's effective mass (0 if the damping does not use it).
    pub m_eff: f64,
}

/// The load of a touching pair and its advanced tangential history. Branch-free (see
/// [`contact_force`](crate::contact::law::contact_force)).
#[inline(always)]
pub(crate) fn pair_law<N: NormalSubModel, T: TangentialSubModel, const PARTS: u8>(
    law: &ContactLaw,
    dt: f64,
    p: &PairInput,
) -> (PairLoad, Vec3, LoadBound) {
    debug_assert!(PARTS & parts::RADICAL != 0 || law.lever != LeverArm::RadicalPlane);
    let mut g = if PARTS & parts::RADICAL != 0 {
        pair_geometry(p.d, p.ra, p.rb)
    } else {
        // The radical plane's lever arms (a division) are never picked.
        pair_geometry_without_levers(p.d, p.ra, p.rb)
    };
    let radical = law.lever == LeverArm::RadicalPlane;
    // LIGGGHTS's lever R − δ/2 serves the contact-point velocity and the torque alike.
    let shorten = if law.lever == LeverArm::Liggghts { 0.5 * g.overlap } else { 0.0 };
    g.lever_i = if radical { g.lever_i } else { p.ra - shorten };
    g.lever_j = if radical { g.lever_j } else { p.rb - shorten };
    let v_r = relative_velocity_of_centres(&g, p.dv, p.wa, p.wb);
    // Coefficients per unit size formed for the pair's own R* and mass (not formed otherwise).
    let sized_input;
    let p = if PARTS & parts::SIZED != 0 {
        let r_star = p.ra * p.rb / (p.ra + p.rb);
        sized_input = PairInput { c: sized::<N>(&p.c, law.damping, r_star, p.m_eff), ..*p };
        &sized_input
    } else {
        p
    };
    let (f, h) = law_force::<N, T, PARTS>(law, dt, p, &g, v_r);
    let levers =
        [torque_lever(law.lever, g.lever_i, g.overlap), torque_lever(law.lever, g.lever_j, g.overlap)];
    let load = PairLoad {
        f: f.total(),
        ta: f.torque(levers[0], g.normal) + rolling::<PARTS>(p.c.mu_roll, f.rolling_load, p.wa),
        tb: f.torque(levers[1], g.normal) + rolling::<PARTS>(p.c.mu_roll, f.rolling_load, p.wb),
    };
    (load, h, [f.bound, torque_bound::<PARTS>(&f, p.c.mu_roll, levers)])
}

/// The rolling torque, or zero where no contact has rolling friction (`PARTS` without
/// [`parts::ROLLING`]): [`rolling_torque`] is zero then, and adding a zero keeps the bits of
/// the sum as they are with it.
#[inline(always)]
fn rolling<const PARTS: u8>(mu_roll: f64, load: f64, omega: Vec3) -> Vec3 {
    debug_assert!(PARTS & parts::ROLLING != 0 || mu_roll == 0.0);
    if PARTS & parts::ROLLING != 0 { rolling_torque(mu_roll, load, omega) } else { Vec3::ZERO }
}

/// The law's force for a contact of geometry `g` and relative velocity `v_r`, with the
/// input's coefficients and its damping scaled by the effective mass as the law asks; and the
/// advanced history.
#[inline(always)]
fn law_force<N: NormalSubModel, T: TangentialSubModel, const PARTS: u8>(
    law: &ContactLaw,
    dt: f64,
    p: &PairInput,
    g: &ContactGeometry,
    v_r: Vec3,
) -> (ContactForce, Vec3) {
    let c = scaled_damping_for::<PARTS>(&p.c, law.damping, p.m_eff);
    let mut h = p.h;
    let f = contact_force_for::<N, T, PARTS>(
        law.history,
        law.clip_attraction,
        law.coulomb,
        &c,
        g,
        v_r,
        &mut h,
        dt,
    );
    (f, h)
}

/// The load of a particle touching a wall (its force in `f`, its torque in `ta`) and the
/// advanced history, from a [`PairInput`] that holds the wall geometry: the normal in `d`, the
/// overlap in `ra`, the lever arm in `rb`, the particle's velocity and spin in `dv`, `wa`, its
/// mass in `m_eff`, and the coefficients of this contact (formed for its size by
/// [`contact_coeffs`] where the table is per unit size: [`parts::SIZED`] is for pairs).
/// Branch-free.
#[inline(always)]
pub(crate) fn wall_law<N: NormalSubModel, T: TangentialSubModel, const PARTS: u8>(
    law: &ContactLaw,
    dt: f64,
    p: &PairInput,
) -> (PairLoad, Vec3, LoadBound) {
    let shorten = if law.lever == LeverArm::Liggghts { 0.5 * p.ra } else { 0.0 };
    let g = ContactGeometry { normal: p.d, overlap: p.ra, lever_i: p.rb - shorten, lever_j: 0.0 };
    // v − 0 = v: the same bits as the pair form with the wall at rest.
    let v_r = relative_velocity_of_centres(&g, p.dv, p.wa, Vec3::ZERO);
    let (f, h) = law_force::<N, T, PARTS>(law, dt, p, &g, v_r);
    let torque = f.torque(g.lever_i, g.normal) + rolling::<PARTS>(p.c.mu_roll, f.rolling_load, p.wa);
    let bound = [f.bound, torque_bound::<PARTS>(&f, p.c.mu_roll, [g.lever_i, 0.0])];
    (PairLoad { f: f.total(), ta: torque, tb: Vec3::ZERO }, h, bound)
}

/// The coefficients of a contact of effective radius `r_star` (R_iR_j/(R_i + R_j), or R_i at
/// a wall) and mass `m_eff` from the table's `c` for its phases: formed for them
/// ([`sized`]) where the table is per unit size, else `c`.
#[inline]
pub(crate) fn contact_coeffs(
    table: &CoeffTable,
    law: &ContactLaw,
    c: &ContactCoeffs,
    r_star: f64,
    m_eff: f64,
) -> ContactCoeffs {
    if !table.sized() {
        return *c;
    }
    crate::with_normal_submodel!(law.normal, |N| sized::<N>(c, law.damping, r_star, m_eff))
}

/// The pull-off distance of a contact of effective radius `r_star` from the table's `c`, as
/// [`contact_coeffs`].
#[inline(always)]
pub(crate) fn contact_reach<N: NormalSubModel>(table: &CoeffTable, c: &ContactCoeffs, r_star: f64) -> f64 {
    if table.sized() { c.pull_off * N::pull_off_scale(r_star) } else { c.pull_off }
}

/// `h` if `keep`, else zero: a history kept or cleared by a bit mask (a select here compiles
/// to a branch, which would mispredict as often as the contact test it follows).
#[inline(always)]
pub(crate) fn kept_or_zero(h: Vec3, keep: bool) -> Vec3 {
    let mask = (keep as u64).wrapping_neg();
    let masked = |v: f64| f64::from_bits(v.to_bits() & mask);
    Vec3::new(masked(h.x), masked(h.y), masked(h.z))
}

/// Effective mass of the particles in slots i and j: m_i m_j/(m_i + m_j), or the other one's
/// mass if one of them is held fixed (as LAMMPS does for frozen particles).
#[inline(always)]
pub(crate) fn pair_mass(mass: &[f64], held: &[bool], i: usize, j: usize) -> f64 {
    let (mi, mj) = (mass[i], mass[j]);
    let both = mi * mj / (mi + mj);
    if held.is_empty() {
        return both;
    }
    pick(held[i], mj, pick(held[j], mi, both))
}

/// The mass `m` every particle has and the effective mass `both` = m·m/(m + m) of two of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CommonMass {
    pub m: f64,
    pub both: f64,
}

impl CommonMass {
    pub fn of(m: f64) -> Self {
        CommonMass { m, both: m * m / (m + m) }
    }
}

/// [`pair_mass`] of two particles of the same mass `m`, given `both` = m·m/(m + m): the same
/// bits, without a division.
#[inline(always)]
pub(crate) fn common_pair_mass(m: f64, both: f64, held_i: bool, held_j: bool) -> f64 {
    pick(held_i | held_j, m, both)
}

/// `a` if `c`, else `b`: picked, not branched on (contacts with held particles come and go
/// unpredictably).
#[inline(always)]
fn pick(c: bool, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & (c as u64).wrapping_neg()) | (b.to_bits() & (!c as u64).wrapping_neg()))
}

/// The coefficients with damping that depends on the contact's masses applied: ×m_eff
/// (`MassVelocity`), ×√m_eff (`Tsuji`, `Liggghts`); unchanged otherwise.
#[inline(always)]
pub(crate) fn scaled_damping(c: &ContactCoeffs, damping: NormalDamping, m_eff: f64) -> ContactCoeffs {
    scaled_damping_for::<{ parts::ALL }>(c, damping, m_eff)
}

/// [`scaled_damping`] with the square root formed only if `PARTS` has [`parts::TSUJI`].
#[inline(always)]
fn scaled_damping_for<const PARTS: u8>(
    c: &ContactCoeffs,
    damping: NormalDamping,
    m_eff: f64,
) -> ContactCoeffs {
    debug_assert!(PARTS & parts::TSUJI != 0 || !damping.per_root_mass());
    // Both scales are formed and one picked (×1 is exact): no branch in a contact loop.
    let root = if PARTS & parts::TSUJI != 0 { m_eff.sqrt() } else { 1.0 };
    let s = if damping == NormalDamping::MassVelocity {
        m_eff
    } else if damping.per_root_mass() {
        root
    } else {
        1.0
    };
    ContactCoeffs { eta_n: c.eta_n * s, eta_t: c.eta_t * s, ..*c }
}

/// Pair geometry of slots i, j with lever arm `lever`, if they touch.
#[inline(always)]
pub(crate) fn pair_geometry_of(
    position: &[Vec3],
    radius: &[f64],
    i: usize,
    j: usize,
    lever: LeverArm,
    per: &Periodic,
) -> Option<ContactGeometry> {
    let d = position[j] - position[i];
    let d = per.nearest(d);
    let mut g = pair_contact_separation(d, radius[i], radius[j])?;
    if lever != LeverArm::RadicalPlane {
        (g.lever_i, g.lever_j) = (radius[i], radius[j]);
    }
    Some(g)
}

/// [`pair_geometry_of`] for the law's normal model `normal`: a model that holds a formed
/// contact (`formed`: its history says so) to its pull-off distance `reach` keeps the pair in
/// contact there. For the others, [`pair_geometry_of`] itself.
#[allow(clippy::too_many_arguments)]
pub(crate) fn pair_geometry_in_contact(
    normal: NormalModel,
    position: &[Vec3],
    radius: &[f64],
    i: usize,
    j: usize,
    lever: LeverArm,
    per: &Periodic,
    reach: f64,
    formed: bool,
) -> Option<ContactGeometry> {
    crate::with_normal_submodel!(normal, |N| {
        if !N::REACHES {
            return pair_geometry_of(position, radius, i, j, lever, per);
        }
        let d = per.nearest(position[j] - position[i]);
        let d2 = d.length_squared();
        if !(N::touching(d2, radius[i], radius[j], reach, formed) && d2 != 0.0) {
            return None;
        }
        let mut g = pair_geometry(d, radius[i], radius[j]);
        if lever != LeverArm::RadicalPlane {
            (g.lever_i, g.lever_j) = (radius[i], radius[j]);
        }
        Some(g)
    })
}

/// [`wall_geometry`] for the law's normal model, as [`pair_geometry_in_contact`].
pub(crate) fn wall_geometry_in_contact(
    normal: NormalModel,
    x: Vec3,
    r: f64,
    wall: &Wall,
    lever: LeverArm,
    reach: f64,
    formed: bool,
) -> Option<ContactGeometry> {
    crate::with_normal_submodel!(normal, |N| {
        let g = wall_geometry_for::<N>(x, r, wall, lever)?;
        N::wall_touching(g.overlap, reach, formed).then_some(g)
    })
}

/// The lever of the tangential force's torque: the geometry's lever, less half the overlap
/// for LAMMPS's `pair granular` convention.
#[inline(always)]
pub(crate) fn torque_lever(lever: LeverArm, geometric: f64, overlap: f64) -> f64 {
    let shortened = geometric - 0.5 * overlap;
    if lever == LeverArm::LammpsGranular { shortened } else { geometric }
}

/// Geometry of a particle at `x` with radius `r` against a wall with the law's lever arm, if
/// they touch.
#[inline(always)]
pub(crate) fn wall_geometry(x: Vec3, r: f64, wall: &Wall, lever: LeverArm) -> Option<ContactGeometry> {
    let mut g = wall_contact(x, r, wall.point, wall.normal)?;
    if lever != LeverArm::RadicalPlane {
        g.lever_i = r;
    }
    Some(g)
}

/// [`wall_geometry`] for the normal model `N`: where a formed contact holds to a negative
/// overlap (`N::REACHES`), the geometry whatever the overlap's sign (the contact test has
/// decided that it is in contact).
#[inline(always)]
pub(crate) fn wall_geometry_for<N: NormalSubModel>(
    x: Vec3,
    r: f64,
    wall: &Wall,
    lever: LeverArm,
) -> Option<ContactGeometry> {
    if !N::REACHES {
        return wall_geometry(x, r, wall, lever);
    }
    let d = (x - wall.point).dot(wall.normal);
    let lever_i = if lever != LeverArm::RadicalPlane { r } else { d };
    Some(ContactGeometry { normal: -wall.normal, overlap: r - d, lever_i, lever_j: 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_common_mass_gives_pair_mass_to_the_bit() {
        // Masses of the yardstick cases and awkward ones (m·m/(m + m) rounds differently
        // from m/2 for some of them); every combination of held particles.
        for m in [1.0, 1.909859 * std::f64::consts::PI / 6.0, 0.1, 3.0e-9, 7.77e-4, 1.0e300] {
            let CommonMass { both, .. } = CommonMass::of(m);
            for (hi, hj) in [(false, false), (true, false), (false, true), (true, true)] {
                let want = pair_mass(&[m, m], &[hi, hj], 0, 1);
                assert_eq!(
                    common_pair_mass(m, both, hi, hj).to_bits(),
                    want.to_bits(),
                    "m = {m}, held {hi} {hj}"
                );
            }
            assert_eq!(pair_mass(&[m, m], &[], 0, 1).to_bits(), both.to_bits());
        }
    }
}
