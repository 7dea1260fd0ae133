//! JKR cohesion, as LAMMPS's `pair granular … jkr … damping tsuji`.

use super::{
    NormalParts, NormalSubModel, SizeScales, StabilityRule, common_checks, elastic_given, normal_damping,
};
use crate::contact::geometry::pair_touching;
use crate::contact::params::{ContactCoeffs, ContactParams, ElasticPair};
use crate::contact::{ContactLaw, NormalDamping, NormalModel, limits};
use crate::error::EngineError;

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
    const NAME: &'static str = "jkr";
    const DESCRIPTION: &'static str = "JKR cohesion, as LAMMPS's pair granular jkr: Hertz on the JKR contact radius with adhesion, held to the pull-off distance";
    const REACHES: bool = true;
    const HISTORY: usize = 0;
    const ELASTIC: bool = true;
    /// Its elastic part's far from the pull-off, Hertz's (its damping is Tsuji's, never the
    /// exact restitution's; the sums' floor ignores the cohesion and takes (4/3)E* as K_n).
    const FORCE_EXPONENT: f64 = 1.5;
    const DAMPING_EXPONENT: f64 = 0.25;
    const STABILITY: StabilityRule = StabilityRule::RayleighTime;
    const COLLISION_STIFFNESS: &'static str =
        "JKR's Hertzian (4/3)E*√R* taken as a linear stiffness, as MFIX does for Hertz";

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
        let eta_n = normal_damping::<Self>(law, kn, m_eff, p.en);
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

    /// The Hertz K_n = (4/3)E*·√R* of its elastic part.
    fn collision_stiffness(c: &ContactCoeffs) -> f64 {
        c.kn * c.r_star.sqrt()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::submodel::{formed, mark_formed};
    use crate::math::Vec3;
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
