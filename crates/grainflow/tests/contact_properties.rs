//! Invariants of the contact laws, as property tests over random geometry, kinematics,
//! coefficients and stored history, for all four (normal × tangential) models and all three
//! history frames:
//!
//! - i ↔ j symmetry: computing the contact from j's side (normal and relative velocity flip,
//!   and so does the stored tangential history, a vector) gives exactly minus i's force and
//!   minus i's new history;
//! - invariance under a rigid rotation and translation of the whole configuration (positions,
//!   velocities, spins, history and walls): forces and history rotate with it;
//! - no force without overlap;
//! - the Coulomb cap |F_t| ≤ μ|F_n|;
//! - the elastic normal force is −dU/dδ of the spring energy the diagnostics report;
//! - at the `Simulation` level: Newton's third law, and the torque balance about the contact
//!   point, T_i + T_j + (x_i − c)×F_i + (x_j − c)×F_j = 0 with c = x_i + a_i·n on the radical
//!   plane (and T + (x − c)×F = 0 for a wall, c = x + d·n), with rolling friction off; and the
//!   same trajectory whichever particle has the lower id.
//!
//! ## Tolerances
//! The two sides of each identity are evaluated with different rounding (j's lever arm is
//! (d² + R_j² − R_i²)/(2d), not d − a_i; rotated coordinates round differently), so they agree
//! to a few ulps of the *largest term* of the force, not of the (possibly cancelling) result.
//! The translation loses at most ε·|T|/δ ≈ 2e-16·0.01 m/1e-6 m = 2e-12 relative precision in
//! δ (|T| ≤ 0.01 m, δ ≥ 1e-6 m). So every comparison uses |a − b| ≤ 1e-9·S, with S the sum of
//! the magnitudes of the terms that make the force (spring, dashpot, tangential spring and
//! damper): three orders of magnitude above the worst rounding, and far below any real
//! violation (a wrong sign or lever arm is an O(1) error in S).

mod common;

use common::*;
use glam::DQuat;
use grainflow::contact::geometry::{pair_contact, relative_velocity, wall_contact};
use grainflow::contact::law::{contact_force_dyn, normal_spring_energy};
use grainflow::contact::{ContactCoeffs, ContactParams};
use grainflow::{ContactLaw, HistoryFrame, Integrator, LeverArm, NormalModel, TangentialModel, Vec3, Wall};
use proptest::prelude::*;

const REL_TOL: f64 = 1e-9;

/// Law number k: normal model, tangential model, history frame and (k ≥ 12) the lever arm.
// The struct update keeps this compiling if the engine adds fields to `ContactLaw`.
#[allow(clippy::needless_update)]
fn law_of(k: usize) -> ContactLaw {
    let normal = [NormalModel::LinearSpringDashpot, NormalModel::Hertz][k % 2];
    let tangential = [TangentialModel::MfixTotal, TangentialModel::IncrementalMindlin][(k / 2) % 2];
    let history = [HistoryFrame::Mfix, HistoryFrame::Project, HistoryFrame::Rotate][(k / 4) % 3];
    let lever = [LeverArm::RadicalPlane, LeverArm::Radius][(k / 12) % 2];
    ContactLaw { normal, tangential, history, lever, ..ContactLaw::mfix(normal) }
}

/// The 12 force laws (the lever arm is a matter of the geometry, not of the force law).
fn any_law() -> impl Strategy<Value = ContactLaw> {
    (0usize..12).prop_map(law_of)
}

/// All 24 laws of a whole simulation.
fn any_sim_law() -> impl Strategy<Value = ContactLaw> {
    (0usize..24).prop_map(law_of)
}

fn vec3(scale: f64) -> impl Strategy<Value = Vec3> {
    prop::array::uniform3(-1.0f64..1.0).prop_map(move |a| scale * Vec3::from_array(a))
}

fn unit() -> impl Strategy<Value = Vec3> {
    prop::array::uniform3(-1.0f64..1.0)
        .prop_filter("non-degenerate direction", |a| Vec3::from_array(*a).length() > 0.1)
        .prop_map(|a| Vec3::from_array(a).normalize())
}

fn rotation() -> impl Strategy<Value = DQuat> {
    (unit(), -3.2f64..3.2).prop_map(|(axis, angle)| DQuat::from_axis_angle(axis, angle))
}

/// Random raw coefficients; their scale is set per normal model in [`coeffs_for`].
#[derive(Debug, Clone, Copy)]
struct RawCoeffs {
    log_kn: f64,
    kt_ratio: f64,
    zeta_n: f64,
    zeta_t: f64,
    mu: f64,
}

fn raw_coeffs() -> impl Strategy<Value = RawCoeffs> {
    (0.0f64..1.0, 0.0f64..1.5, 0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0)
        .prop_map(|(log_kn, kt_ratio, zeta_n, zeta_t, mu)| RawCoeffs { log_kn, kt_ratio, zeta_n, zeta_t, mu })
}

/// Coefficients of realistic size: LSD k_n in 1e3…1e8 N/m, Hertz K_n in 1e8…1e11 N/m^1.5,
/// damping up to critical for a 1e-4 kg particle.
fn coeffs_for(law: &ContactLaw, r: RawCoeffs) -> ContactCoeffs {
    let kn = match law.normal {
        NormalModel::LinearSpringDashpot => 10f64.powf(3.0 + 5.0 * r.log_kn),
        NormalModel::Hertz => 10f64.powf(8.0 + 3.0 * r.log_kn),
        NormalModel::Jkr => unreachable!("JKR is not among the laws this test draws"),
    };
    let m = 1e-4;
    let crit = 2.0 * (kn * m).sqrt();
    ContactCoeffs {
        kn,
        kt: r.kt_ratio * kn,
        eta_n: r.zeta_n * crit,
        eta_t: r.zeta_t * crit,
        mu: r.mu,
        mu_roll: 0.0,
        m_eff: m,
        ..Default::default()
    }
}

/// A random pair configuration in contact.
#[derive(Debug, Clone, Copy)]
struct PairState {
    xi: Vec3,
    ri: f64,
    rj: f64,
    n: Vec3,
    /// Overlap as a fraction of the smaller radius.
    overlap_frac: f64,
    vi: Vec3,
    vj: Vec3,
    wi: Vec3,
    wj: Vec3,
    /// Direction and size (fraction of δ) of the stored tangential history.
    h_dir: Vec3,
    h_frac: f64,
    log_dt: f64,
}

impl PairState {
    fn xj(&self) -> Vec3 {
        self.xi + (self.ri + self.rj - self.delta()) * self.n
    }
    fn delta(&self) -> f64 {
        self.overlap_frac * self.ri.min(self.rj)
    }
    fn dt(&self) -> f64 {
        10f64.powf(self.log_dt)
    }
    /// A stored history of plausible size: a displacement up to δ, or (incremental model) the
    /// elastic force of such a displacement.
    fn history(&self, law: &ContactLaw, c: &ContactCoeffs) -> Vec3 {
        let s = self.h_frac * self.delta() * self.h_dir;
        match (law.tangential, law.normal) {
            (TangentialModel::MfixTotal, _) => s,
            (TangentialModel::IncrementalMindlin, NormalModel::LinearSpringDashpot) => c.kt * s,
            (TangentialModel::IncrementalMindlin, NormalModel::Hertz) => c.kt * self.delta().sqrt() * s,
            (_, NormalModel::Jkr) => unreachable!("JKR is not among the laws this test draws"),
        }
    }
}

fn pair_state() -> impl Strategy<Value = PairState> {
    (
        (vec3(0.01), 0.5e-3f64..1.5e-3, 0.5e-3f64..1.5e-3, unit(), 1e-3f64..0.2),
        (vec3(2.0), vec3(2.0), vec3(1000.0), vec3(1000.0)),
        (vec3(1.0), 0.0f64..1.0, -8.0f64..-5.0),
    )
        .prop_map(|((xi, ri, rj, n, overlap_frac), (vi, vj, wi, wj), (h_dir, h_frac, log_dt))| {
            PairState { xi, ri, rj, n, overlap_frac, vi, vj, wi, wj, h_dir, h_frac, log_dt }
        })
}

/// The sum of the magnitudes of the terms that make up a contact force: the scale its rounding
/// errors are relative to.
fn force_scale(law: &ContactLaw, c: &ContactCoeffs, delta: f64, v_r: Vec3, h: Vec3, dt: f64) -> f64 {
    let (p, q, k) = match law.normal {
        NormalModel::LinearSpringDashpot => (delta, 1.0, c.kt),
        NormalModel::Hertz => (delta.powf(1.5), delta.powf(0.25), c.kt * delta.sqrt()),
        NormalModel::Jkr => unreachable!("JKR is not among the laws this test draws"),
    };
    let v = v_r.length();
    let tangential_spring = match law.tangential {
        TangentialModel::MfixTotal => k * (h.length() + dt * v),
        TangentialModel::IncrementalMindlin => h.length() + k * dt * v,
    };
    c.kn * p + c.eta_n * q * v + tangential_spring + c.eta_t * q * v + f64::MIN_POSITIVE
}

/// The scale of the rounding errors of a new tangential history: for MFIX's total spring the
/// terms it is made of, the stored history and the step's increment Δt·|v_r|, and the history
/// itself, which the Coulomb cap rescales to μ|F_n|/k_t (far larger than both when k_t is
/// small); for the incremental spring, which stores a force, the force scale.
fn history_scale(model: TangentialModel, force_scale: f64, h0: Vec3, h: Vec3, increment: f64) -> f64 {
    match model {
        TangentialModel::MfixTotal => h0.length() + increment + h.length() + f64::MIN_POSITIVE,
        TangentialModel::IncrementalMindlin => force_scale,
    }
}

fn assert_close(what: &str, a: Vec3, b: Vec3, scale: f64) -> Result<(), TestCaseError> {
    let diff = (a - b).length();
    prop_assert!(
        diff <= REL_TOL * scale,
        "{}: {:?} vs {:?}, |diff| = {:e} > {:e}",
        what,
        a,
        b,
        diff,
        REL_TOL * scale
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Seen from j, the same contact gives minus the force and minus the new history; the
    /// torque on j computed as "i" equals the torque on j computed as "j"; F_t obeys Coulomb.
    #[test]
    fn swapping_i_and_j_flips_force_and_history(
        law in any_law(), raw in raw_coeffs(), s in pair_state()
    ) {
        let c = coeffs_for(&law, raw);
        let (xi, xj, dt) = (s.xi, s.xj(), s.dt());
        let h0 = s.history(&law, &c);

        let g = pair_contact(xi, xj, s.ri, s.rj).expect("in contact");
        let v_r = relative_velocity(&g, s.vi, s.vj, s.wi, s.wj);
        let mut h = h0;
        let f = contact_force_dyn(&law, &c, &g, v_r, &mut h, dt);

        let g2 = pair_contact(xj, xi, s.rj, s.ri).expect("in contact");
        let v_r2 = relative_velocity(&g2, s.vj, s.vi, s.wj, s.wi);
        let mut h2 = -h0;
        let f2 = contact_force_dyn(&law, &c, &g2, v_r2, &mut h2, dt);

        let scale = force_scale(&law, &c, g.overlap, v_r, h0, dt);
        assert_close("normal force", f2.normal, -f.normal, scale)?;
        assert_close("tangential force", f2.tangential, -f.tangential, scale)?;
        let h_scale = history_scale(law.tangential, scale, h0, h, dt * v_r.length());
        assert_close("new history", h2, -h, h_scale)?;
        let arm = s.ri + s.rj;
        assert_close(
            "torque on j",
            f2.torque(g2.lever_i, g2.normal),
            f.torque(g.lever_j, g.normal),
            arm * scale,
        )?;
        assert_close(
            "torque on i",
            f2.torque(g2.lever_j, g2.normal),
            f.torque(g.lever_i, g.normal),
            arm * scale,
        )?;
        // Coulomb: |F_t| ≤ μ|F_n| (up to rounding of the cap itself).
        prop_assert!(
            f.tangential.length() <= c.mu * f.normal.length() + REL_TOL * scale,
            "|F_t| = {:e} > mu|F_n| = {:e}",
            f.tangential.length(),
            c.mu * f.normal.length()
        );
    }

    /// Rotating and translating the whole configuration rotates the forces and the history.
    #[test]
    fn pair_force_is_invariant_under_rigid_motion(
        law in any_law(), raw in raw_coeffs(), s in pair_state(),
        q in rotation(), t in vec3(0.01)
    ) {
        let c = coeffs_for(&law, raw);
        let dt = s.dt();
        let h0 = s.history(&law, &c);
        let g = pair_contact(s.xi, s.xj(), s.ri, s.rj).expect("in contact");
        let v_r = relative_velocity(&g, s.vi, s.vj, s.wi, s.wj);
        let mut h = h0;
        let f = contact_force_dyn(&law, &c, &g, v_r, &mut h, dt);

        let gr = pair_contact(q * s.xi + t, q * s.xj() + t, s.ri, s.rj).expect("in contact");
        let v_rr = relative_velocity(&gr, q * s.vi, q * s.vj, q * s.wi, q * s.wj);
        let mut hr = q * h0;
        let fr = contact_force_dyn(&law, &c, &gr, v_rr, &mut hr, dt);

        let scale = force_scale(&law, &c, g.overlap, v_r, h0, dt);
        assert_close("rotated normal force", fr.normal, q * f.normal, scale)?;
        assert_close("rotated tangential force", fr.tangential, q * f.tangential, scale)?;
        let h_scale = history_scale(law.tangential, scale, h0, h, dt * v_r.length());
        assert_close("rotated history", hr, q * h, h_scale)?;
        prop_assert!((fr.elastic_normal - f.elastic_normal).abs() <= REL_TOL * scale);
    }

    /// The same for a particle against a wall (the wall moves with the configuration).
    #[test]
    fn wall_force_is_invariant_under_rigid_motion(
        law in any_law(), raw in raw_coeffs(), s in pair_state(),
        q in rotation(), t in vec3(0.01), point in vec3(0.01)
    ) {
        let c = coeffs_for(&law, raw);
        let dt = s.dt();
        let h0 = s.history(&law, &c);
        // The wall's normal points from the wall into the particle space, i.e. along −n.
        let wall_n = -s.n;
        let x = point + (s.ri - s.delta()) * wall_n;
        let g = wall_contact(x, s.ri, point, wall_n).expect("in contact");
        prop_assert!((g.overlap - s.delta()).abs() <= 1e-9 * s.delta());
        let v_r = relative_velocity(&g, s.vi, Vec3::ZERO, s.wi, Vec3::ZERO);
        let mut h = h0;
        let f = contact_force_dyn(&law, &c, &g, v_r, &mut h, dt);

        let gr = wall_contact(q * x + t, s.ri, q * point + t, q * wall_n).expect("in contact");
        let v_rr = relative_velocity(&gr, q * s.vi, Vec3::ZERO, q * s.wi, Vec3::ZERO);
        let mut hr = q * h0;
        let fr = contact_force_dyn(&law, &c, &gr, v_rr, &mut hr, dt);

        let scale = force_scale(&law, &c, g.overlap, v_r, h0, dt);
        assert_close("rotated wall normal force", fr.normal, q * f.normal, scale)?;
        assert_close("rotated wall tangential force", fr.tangential, q * f.tangential, scale)?;
        assert_close(
            "rotated wall torque",
            fr.torque(gr.lever_i, gr.normal),
            q * f.torque(g.lever_i, g.normal),
            s.ri * scale,
        )?;
    }

    /// Apart by any positive gap (down to 1e-9 of the radii), there is no contact at all.
    #[test]
    fn no_contact_without_overlap(s in pair_state(), gap_frac in -9.0f64..-1.0, point in vec3(0.01)) {
        let gap = 10f64.powf(gap_frac) * (s.ri + s.rj);
        let xj = s.xi + (s.ri + s.rj + gap) * s.n;
        prop_assert!(pair_contact(s.xi, xj, s.ri, s.rj).is_none());
        prop_assert!(pair_contact(xj, s.xi, s.rj, s.ri).is_none());
        let x = point + (s.ri + gap) * s.n;
        prop_assert!(wall_contact(x, s.ri, point, s.n).is_none());
        // And just inside, there is.
        let xj_in = s.xi + (s.ri + s.rj - gap) * s.n;
        prop_assert!(pair_contact(s.xi, xj_in, s.ri, s.rj).is_some());
        let x_in = point + (s.ri - gap) * s.n;
        prop_assert!(wall_contact(x_in, s.ri, point, s.n).is_some());
    }

    /// F_el(δ) = dU/dδ for U the spring energy in the diagnostics (½k_nδ², or (2/5)K_nδ^{5/2}).
    /// Central difference with h = 1e-4·δ: truncation U'''h²/6 is (h/δ)²/8 = 1.25e-9 of U′ for
    /// Hertz and 0 for LSD; rounding ε·U/h ≈ 1e-12 of U′. Tolerance 1e-8.
    #[test]
    fn elastic_force_is_energy_gradient(law in any_law(), raw in raw_coeffs(), s in pair_state()) {
        let c = coeffs_for(&law, raw);
        let delta = s.delta();
        let x = Vec3::ZERO;
        let g = wall_contact(x + (s.ri - delta) * Vec3::Y, s.ri, x, Vec3::Y).expect("contact");
        let mut h = Vec3::ZERO;
        let f = contact_force_dyn(&law, &c, &g, Vec3::ZERO, &mut h, s.dt());
        let hstep = 1e-4 * delta;
        let du = (normal_spring_energy(law.normal, &c, delta + hstep)
            - normal_spring_energy(law.normal, &c, delta - hstep))
            / (2.0 * hstep);
        prop_assert!(
            rel_err(du, f.elastic_normal) <= 1e-8,
            "dU/ddelta = {:e}, elastic force {:e}", du, f.elastic_normal
        );
        // At rest the whole normal force is elastic and repulsive.
        prop_assert!((f.normal + f.elastic_normal * g.normal).length() <= 1e-12 * f.elastic_normal);
    }
}

/// Contact inputs for the whole-`Simulation` tests, drawn from `raw`.
fn sim_params(law: &ContactLaw, raw: RawCoeffs) -> ContactParams {
    match law.normal {
        NormalModel::LinearSpringDashpot => ContactParams {
            kn: Some(10f64.powf(3.0 + 4.0 * raw.log_kn)),
            kt_fac: raw.kt_ratio.min(1.0),
            etat_fac: raw.zeta_t,
            en: 0.05 + 0.95 * raw.zeta_n,
            et: None,
            mu: raw.mu,
            mu_roll: 0.0,
            ..Default::default()
        },
        NormalModel::Hertz => ContactParams {
            kn: None,
            kt_fac: 2.0 / 7.0,
            etat_fac: 0.5,
            en: 0.05 + 0.95 * raw.zeta_n,
            et: Some(0.05 + 0.95 * raw.zeta_t),
            mu: raw.mu,
            mu_roll: 0.0,
            ..Default::default()
        },
        NormalModel::Jkr => unreachable!("JKR is not among the laws this test draws"),
    }
}

/// A two-particle simulation (radii R_i, R_j, phases 0 and 1), with the ids given.
fn pair_sim(
    law: ContactLaw,
    raw: RawCoeffs,
    s: &PairState,
    ids: [u32; 2],
    integrator: Integrator,
) -> grainflow::Simulation {
    let p = sim_params(&law, raw);
    let phases = vec![
        elastic_phase("a", 2.0 * s.ri, 2500.0, 7e10, 0.25),
        elastic_phase("b", 2.0 * s.rj, 4000.0, 2e11, 0.3),
    ];
    let cfg = config(
        law,
        phases,
        vec![wall_material("w", Some(7e10), Some(0.25))],
        Vec::new(),
        vec![p; 3],
        vec![p; 2],
        integrator,
        1e-8,
    );
    let mut a = particle(ids[0], 0, s.ri, 2500.0, s.xi, s.vi);
    a.omega = s.wi;
    let mut b = particle(ids[1], 1, s.rj, 4000.0, s.xj(), s.vj);
    b.omega = s.wj;
    // The lower id takes the lower slot.
    if ids[0] < ids[1] { simulation(cfg, &[a, b]) } else { simulation(cfg, &[b, a]) }
}

fn any_integrator() -> impl Strategy<Value = Integrator> {
    prop_oneof![Just(Integrator::Euler), Just(Integrator::AdamsBashforth), Just(Integrator::VelocityVerlet)]
}

/// After a few steps of a real simulation: F_i + F_j = 0; each particle's torque is the
/// moment of its contact force applied at its contact point c_k = x_k ± a_k·n (a_k the lever
/// arm of the law: radical plane, or the radius); with the radical-plane lever both contact
/// points coincide, so the total torque about the contact point vanishes. And swapping the
/// particles' slots (so that the contact is evaluated from the other side, with the history
/// stored from that side) does not change the trajectory.
fn check_pair_simulation(
    law: ContactLaw,
    raw: RawCoeffs,
    s: PairState,
    steps: usize,
    integrator: Integrator,
) -> Result<(), TestCaseError> {
    let mut a = pair_sim(law, raw, &s, [1, 2], integrator);
    let mut b = pair_sim(law, raw, &s, [2, 1], integrator);
    for _ in 0..steps {
        a.step();
        b.step();
    }
    a.compute_forces();
    b.compute_forces();
    let p = a.particles();
    let (xi, xj) = (p.position[0], p.position[1]);
    let (fi, fj) = (p.force[0], p.force[1]);
    let (ti, tj) = (p.torque[0], p.torque[1]);
    prop_assert_eq!(fi + fj, Vec3::ZERO);
    let d = (xj - xi).length();
    let n = (xj - xi) / d;
    let (a_i, a_j) = match law.lever {
        LeverArm::RadicalPlane => {
            let a_i = (d * d + s.ri * s.ri - s.rj * s.rj) / (2.0 * d);
            (a_i, d - a_i)
        }
        LeverArm::Radius => (s.ri, s.rj),
        // Both take the torque about R − δ/2.
        LeverArm::LammpsGranular | LeverArm::Liggghts => {
            let half = 0.5 * (s.ri + s.rj - d);
            (s.ri - half, s.rj - half)
        }
    };
    let (ci, cj) = (xi + a_i * n, xj - a_j * n);
    let scale = d * fi.length() + ti.length() + tj.length() + f64::MIN_POSITIVE;
    let moment_i = ti + (xi - ci).cross(fi);
    let moment_j = tj + (xj - cj).cross(fj);
    prop_assert!(
        moment_i.length() <= REL_TOL * scale && moment_j.length() <= REL_TOL * scale,
        "torques are not the moments of the contact force at the contact points: {:?} {:?} (scale {:e})",
        moment_i,
        moment_j,
        scale
    );
    if law.lever == LeverArm::RadicalPlane {
        let balance = ti + tj + (xi - ci).cross(fi) + (xj - ci).cross(fj);
        prop_assert!(
            balance.length() <= REL_TOL * scale,
            "torque balance about the contact point {:?} (scale {:e})",
            balance,
            scale
        );
    }
    // Swapped run: same forces, torques and state on every particle; history flipped.
    let q = b.particles();
    let fscale = fi.length() + f64::MIN_POSITIVE;
    for k in 0..2 {
        assert_close("swapped force", q.force[1 - k], p.force[k], fscale)?;
        assert_close("swapped torque", q.torque[1 - k], p.torque[k], scale)?;
    }
    let (ha, hb) = (a.neighbors().pair_history(), b.neighbors().pair_history());
    prop_assert_eq!(ha.len(), 1);
    prop_assert_eq!(hb.len(), 1);
    let hs = ha[0].length() + f64::MIN_POSITIVE;
    assert_close("swapped history", hb[0], -ha[0], hs)?;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// [`check_pair_simulation`] with MFIX's radical-plane lever arm, all 12 force laws.
    #[test]
    fn simulation_pair_balances_force_and_torque(
        law in any_law(), raw in raw_coeffs(), s in pair_state(),
        steps in 0usize..6, integrator in any_integrator()
    ) {
        check_pair_simulation(law, raw, s, steps, integrator)?;
    }

    /// [`check_pair_simulation`] with `LeverArm::Radius`: the torque on each particle must be
    /// R_k·(n × F_t), the moment about its centre of the force applied at x_k ± R_k·n.
    #[test]
    fn simulation_pair_torque_uses_radius_lever(
        k in 12usize..24, raw in raw_coeffs(), s in pair_state(),
        steps in 0usize..6, integrator in any_integrator()
    ) {
        check_pair_simulation(law_of(k), raw, s, steps, integrator)?;
    }

    /// A spinning particle pressed obliquely into a wall: its torque is the moment of the
    /// contact force applied at c = x + a·n, a = d (radical plane) or R (radius).
    #[test]
    fn simulation_wall_balances_torque(
        law in any_sim_law(), raw in raw_coeffs(), s in pair_state(),
        steps in 0usize..6, integrator in any_integrator()
    ) {
        let p = sim_params(&law, raw);
        let point = Vec3::new(0.001, -0.002, 0.0005);
        let wall_n = s.n;
        let cfg = config(
            law,
            vec![elastic_phase("a", 2.0 * s.ri, 2500.0, 7e10, 0.25)],
            vec![wall_material("w", Some(2e11), Some(0.3))],
            vec![Wall::plane("w", point, wall_n, 0)],
            vec![p],
            vec![p],
            integrator,
            1e-8,
        );
        let mut init = particle(1, 0, s.ri, 2500.0, point + (s.ri - s.delta()) * wall_n, s.vi);
        init.omega = s.wi;
        let mut sim = simulation(cfg, &[init]);
        for _ in 0..steps {
            sim.step();
        }
        sim.compute_forces();
        let q = sim.particles();
        let (x, f, t) = (q.position[0], q.force[0], q.torque[0]);
        let d = (x - point).dot(wall_n);
        let lever = match law.lever {
            LeverArm::RadicalPlane => d,
            LeverArm::Radius | LeverArm::LammpsGranular => s.ri,
            LeverArm::Liggghts => s.ri - 0.5 * (s.ri - d),
        };
        let cpt = x - lever * wall_n;
        let balance = t + (x - cpt).cross(f);
        let scale = d * f.length() + t.length() + f64::MIN_POSITIVE;
        prop_assert!(
            balance.length() <= REL_TOL * scale,
            "wall torque balance {:?} (scale {:e})", balance, scale
        );
    }
}

/// Particles apart (even approaching fast) feel nothing, in a whole simulation.
#[test]
fn simulation_no_force_without_overlap() {
    for k in 0..24 {
        let law = law_of(k);
        let raw = RawCoeffs { log_kn: 0.5, kt_ratio: 0.5, zeta_n: 0.5, zeta_t: 0.5, mu: 0.5 };
        let s = PairState {
            xi: Vec3::new(0.001, 0.002, 0.003),
            ri: 1e-3,
            rj: 0.7e-3,
            n: Vec3::new(1.0, 1.0, 0.0).normalize(),
            overlap_frac: -1e-6,
            vi: Vec3::new(1.0, 1.0, 0.0),
            vj: Vec3::new(-1.0, -1.0, 0.0),
            wi: Vec3::new(0.0, 0.0, 100.0),
            wj: Vec3::new(10.0, 0.0, 100.0),
            h_dir: Vec3::ZERO,
            h_frac: 0.0,
            log_dt: -8.0,
        };
        let mut sim = pair_sim(law, raw, &s, [1, 2], Integrator::Euler);
        sim.compute_forces();
        let p = sim.particles();
        assert_eq!(p.force, vec![Vec3::ZERO; 2], "law {law:?}");
        assert_eq!(p.torque, vec![Vec3::ZERO; 2], "law {law:?}");
        assert_eq!(sim.diagnostics().contacts, 0);
        assert_eq!(sim.diagnostics().elastic, 0.0);
    }
}
