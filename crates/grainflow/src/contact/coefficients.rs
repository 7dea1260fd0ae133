//! Contact coefficients derived from the inputs (reference: MFIX-DEM model §3).

use super::ContactLaw;
#[cfg(test)]
use super::NormalModel;
use super::normal::{NormalSubModel, per_unit_size};
use super::params::{ContactCoeffs, ContactParams, ElasticPair};
use crate::error::EngineError;
use crate::material::{Phase, WallMaterial};

/// Coefficients for every phase pair and every phase–wall-material pair.
#[derive(Debug, Clone, PartialEq)]
pub struct CoeffTable {
    n_phases: usize,
    n_wall_materials: usize,
    pairs: Vec<ContactCoeffs>,
    walls: Vec<ContactCoeffs>,
    /// The coefficients of every phase pair, when they are all the same.
    uniform_pair: Option<ContactCoeffs>,
    /// Some pair or wall contact has rolling friction (μ_r ≠ 0).
    rolling: bool,
    /// The coefficients are per unit size ([`CoeffTable::per_unit_size`]): each contact's are
    /// [`sized`](super::normal::sized) by its own R* and m_eff.
    sized: bool,
    /// The largest pull-off distance a contact can have, m.
    reach: f64,
}

/// Index of phase pair (m, l), m ≤ l, in MFIX's upper-triangle order 1-1, 1-2, …, 1-M, 2-2, …
pub fn upper_triangle_index(m: usize, l: usize, n: usize) -> usize {
    let (a, b) = if m <= l { (m, l) } else { (l, m) };
    a * n - a * (a + 1) / 2 + b
}

/// The most solids phases a case may define: 100 (MFIX allows 10). The coefficient table
/// holds every phase pair, so its size grows as the square of the count.
pub const MAX_PHASES: usize = 100;

/// The most wall materials a case may define: 100.
pub const MAX_WALL_MATERIALS: usize = 100;

/// Every derived coefficient must be a finite number and the effective mass positive:
/// finite inputs can overflow (a density of 1e308) or underflow (a diameter of 1e-300).
fn usable(what: &str, c: ContactCoeffs) -> Result<ContactCoeffs, EngineError> {
    // The mass first: when it underflows the damping is NaN too, and the mass says why.
    if !(c.m_eff.is_finite() && c.m_eff >= f64::MIN_POSITIVE) {
        return Err(EngineError::BadReference(format!(
            "{what}: the effective mass is {:e} kg: the diameter or density is beyond what double precision can hold (are they in SI units: m, kg/m³?)",
            c.m_eff
        )));
    }
    let fields = [
        ("stiffness K_n", c.kn),
        ("tangential stiffness", c.kt),
        ("normal damping", c.eta_n),
        ("tangential damping", c.eta_t),
    ];
    if let Some((name, v)) = fields.iter().find(|(_, v)| !v.is_finite()) {
        return Err(EngineError::BadReference(format!(
            "{what}: the derived {name} is {v}: the diameter, density or stiffness is beyond what double precision can hold (are they in SI units: m, kg/m³, N/m, Pa?)"
        )));
    }
    Ok(c)
}

impl CoeffTable {
    /// Derives the coefficients.
    ///
    /// `pair_params` are in upper-triangle order (see [`upper_triangle_index`]),
    /// `wall_params[p * n_wall_materials + w]` is phase p against wall material w.
    pub fn build(
        law: &ContactLaw,
        phases: &[Phase],
        wall_materials: &[WallMaterial],
        pair_params: &[ContactParams],
        wall_params: &[ContactParams],
    ) -> Result<Self, EngineError> {
        let n = phases.len();
        let nw = wall_materials.len();
        if n > MAX_PHASES {
            return Err(EngineError::BadReference(format!(
                "{n} phases; at most {MAX_PHASES} are allowed (MFIX allows 10)"
            )));
        }
        if nw > MAX_WALL_MATERIALS {
            return Err(EngineError::BadReference(format!(
                "{nw} wall materials; at most {MAX_WALL_MATERIALS} are allowed"
            )));
        }
        if pair_params.len() != n * (n + 1) / 2 {
            return Err(EngineError::BadReference(format!(
                "{} phase-pair parameter sets given for {n} phases; {} are needed",
                pair_params.len(),
                n * (n + 1) / 2
            )));
        }
        if wall_params.len() != n * nw {
            return Err(EngineError::BadReference(format!(
                "{} phase-wall parameter sets given for {n} phases and {nw} wall materials; {} are needed",
                wall_params.len(),
                n * nw
            )));
        }
        // E and ν of phase k, for the models that take them.
        let phase_elastic = |k: usize| {
            let ph = &phases[k];
            elastic_of(&ph.name, ph.youngs_modulus, ph.poisson_ratio, "phase", law.normal_name())
        };
        let mut pairs = vec![ContactCoeffs::default(); n * n];
        for m in 0..n {
            for l in m..n {
                let p = &pair_params[upper_triangle_index(m, l, n)];
                let what = format!("contact '{}'-'{}'", phases[m].name, phases[l].name);
                let (ma, mb) = (phases[m].mass(), phases[l].mass());
                let m_eff = ma * mb / (ma + mb);
                let elastic = if law.normal.elastic() {
                    let ((ea, na), (eb, nb)) = (phase_elastic(m)?, phase_elastic(l)?);
                    let (ra, rb) = (phases[m].radius(), phases[l].radius());
                    Some(ElasticPair { e1: ea, nu1: na, e2: eb, nu2: nb, r_star: ra * rb / (ra + rb) })
                } else {
                    None
                };
                let c = usable(&what, derive(law, &what, p, m_eff, elastic)?)?;
                pairs[m * n + l] = c;
                pairs[l * n + m] = c;
            }
        }
        let mut walls = vec![ContactCoeffs::default(); n * nw];
        for m in 0..n {
            for w in 0..nw {
                let p = &wall_params[m * nw + w];
                let what = format!("contact '{}'-wall '{}'", phases[m].name, wall_materials[w].name);
                let elastic = if law.normal.elastic() {
                    let (ea, na) = phase_elastic(m)?;
                    let wm = &wall_materials[w];
                    let model = law.normal_name();
                    let (eb, nb) =
                        elastic_of(&wm.name, wm.youngs_modulus, wm.poisson_ratio, "wall material", model)?;
                    Some(ElasticPair { e1: ea, nu1: na, e2: eb, nu2: nb, r_star: phases[m].radius() })
                } else {
                    None
                };
                walls[m * nw + w] = usable(&what, derive(law, &what, p, phases[m].mass(), elastic)?)?;
            }
        }
        Ok(CoeffTable::of(n, nw, pairs, walls, false, |c| c.pull_off))
    }

    fn of(
        n_phases: usize,
        n_wall_materials: usize,
        pairs: Vec<ContactCoeffs>,
        walls: Vec<ContactCoeffs>,
        sized: bool,
        reach: impl Fn(&ContactCoeffs) -> f64,
    ) -> CoeffTable {
        let uniform_pair = pairs.first().filter(|c0| pairs.iter().all(|c| c == *c0)).copied();
        let rolling = pairs.iter().chain(&walls).any(|c| c.mu_roll != 0.0);
        let reach = pairs.iter().chain(&walls).map(reach).fold(0.0, f64::max);
        CoeffTable { n_phases, n_wall_materials, pairs, walls, uniform_pair, rolling, sized, reach }
    }

    /// The table per unit size, for [`ContactSizes::Own`](super::ContactSizes::Own): this
    /// table's coefficients (derived at the `phases`' reference diameters and masses) divided
    /// by their [`size_scales`](super::normal::NormalSubModel::size_scales) there, so that
    /// [`sized`](super::normal::sized) gives each contact its own. `r_max` is the largest
    /// particle radius of the run, which bounds the pull-off distance ([`reach`](Self::reach)).
    pub fn per_unit_size(&self, law: &ContactLaw, phases: &[Phase], r_max: f64) -> CoeffTable {
        crate::with_normal_submodel!(law.normal, |N| self.per_unit_size_for::<N>(law, phases, r_max))
    }

    fn per_unit_size_for<N: NormalSubModel>(
        &self,
        law: &ContactLaw,
        phases: &[Phase],
        r_max: f64,
    ) -> CoeffTable {
        let (n, nw) = (self.n_phases, self.n_wall_materials);
        let unit = |c: &ContactCoeffs, r_ref: f64| per_unit_size::<N>(c, law.damping, r_ref, c.m_eff);
        let mut pairs = self.pairs.clone();
        for m in 0..n {
            for l in 0..n {
                let (ra, rb) = (phases[m].radius(), phases[l].radius());
                pairs[m * n + l] = unit(&self.pairs[m * n + l], ra * rb / (ra + rb));
            }
        }
        let mut walls = self.walls.clone();
        for m in 0..n {
            for w in 0..nw {
                walls[m * nw + w] = unit(&self.walls[m * nw + w], phases[m].radius());
            }
        }
        // A wall contact's R* is the particle's radius, above any pair's.
        CoeffTable::of(n, nw, pairs, walls, true, |c| c.pull_off * N::pull_off_scale(r_max))
    }

    /// Coefficients of the phase pair (a, b).
    #[inline(always)]
    pub fn pair(&self, a: usize, b: usize) -> &ContactCoeffs {
        &self.pairs[a * self.n_phases + b]
    }

    /// The coefficients of every phase pair, if they are all the same (one phase, or phases
    /// that differ in nothing the contact law uses): a force loop need not look them up.
    #[inline(always)]
    pub fn uniform_pair(&self) -> Option<&ContactCoeffs> {
        self.uniform_pair.as_ref()
    }

    /// True if some pair or wall contact has rolling friction (μ_r ≠ 0): a force loop without
    /// it need not compute the rolling torques.
    #[inline(always)]
    pub fn rolling(&self) -> bool {
        self.rolling
    }

    /// Coefficients of phase `a` against wall material `w`.
    #[inline(always)]
    pub fn wall(&self, a: usize, w: usize) -> &ContactCoeffs {
        &self.walls[a * self.n_wall_materials + w]
    }

    /// Every phase pair's and phase–wall-material pair's coefficients.
    pub fn all(&self) -> impl Iterator<Item = &ContactCoeffs> {
        self.pairs.iter().chain(&self.walls)
    }

    /// The largest pull-off distance of any contact, m (0 unless the normal model holds
    /// formed contacts beyond the touch): the neighbour skin must exceed it.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// True if the coefficients are per unit size and each contact's are formed from its own
    /// R* and m_eff ([`per_unit_size`](Self::per_unit_size)).
    #[inline(always)]
    pub fn sized(&self) -> bool {
        self.sized
    }

    /// Number of phases.
    pub fn n_phases(&self) -> usize {
        self.n_phases
    }
}

fn elastic_of(
    name: &str,
    e: Option<f64>,
    nu: Option<f64>,
    kind: &str,
    model: &str,
) -> Result<(f64, f64), EngineError> {
    let e = e.ok_or_else(|| EngineError::MissingParameter {
        what: format!("{kind} '{name}' youngs_modulus"),
        model: model.into(),
    })?;
    let nu = nu.ok_or_else(|| EngineError::MissingParameter {
        what: format!("{kind} '{name}' poisson_ratio"),
        model: model.into(),
    })?;
    Ok((e, nu))
}

/// The coefficients of one contact type by the law's normal sub-model, which declares its
/// parameters, their checks and how the two bodies' values combine.
fn derive(
    law: &ContactLaw,
    what: &str,
    p: &ContactParams,
    m_eff: f64,
    elastic: Option<ElasticPair>,
) -> Result<ContactCoeffs, EngineError> {
    crate::with_normal_submodel!(law.normal, |N| <N as NormalSubModel>::coefficients(
        law, what, p, m_eff, elastic
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phase(name: String, diameter: f64, density: f64) -> Phase {
        Phase { name, diameter, density, youngs_modulus: None, poisson_ratio: None }
    }

    /// Coefficients per unit size, formed for another pair of sizes, are those derived for
    /// phases of those sizes directly: the scalings of each normal model (K ∝ √R*, η ∝
    /// √(K·m_eff), JKR's δ_c ∝ R*^⅓) are those of its formulas. Both are the same formulas
    /// evaluated in another order: equal to a few roundings (1e-14).
    #[test]
    fn coefficients_per_unit_size_formed_for_a_size_are_those_derived_at_it() {
        use crate::contact::normal::{NormalSubModel, sized};
        use crate::contact::{NormalDamping as D, NormalModel as M};
        let elastic = |name: &str, d: f64, rho: f64| Phase {
            name: name.into(),
            diameter: d,
            density: rho,
            youngs_modulus: Some(7e7),
            poisson_ratio: Some(0.3),
        };
        let wall =
            [WallMaterial { name: "steel".into(), youngs_modulus: Some(2e8), poisson_ratio: Some(0.25) }];
        let p = ContactParams {
            kn: Some(2e3),
            en: 0.7,
            et: Some(0.8),
            mu: 0.4,
            gamma_n: Some(500.0),
            surface_energy: Some(0.05),
            etat_fac: 0.5,
            ..Default::default()
        };
        let rel = |a: f64, b: f64| if a == b { 0.0 } else { (a - b).abs() / b.abs() };
        let cases = [
            (M::LinearSpringDashpot, D::Mfix),
            (M::LinearSpringDashpot, D::ExactRestitution),
            (M::LinearSpringDashpot, D::MassVelocity),
            (M::Hertz, D::Mfix),
            (M::Hertz, D::Tsuji),
            (M::Hertz, D::MassVelocity),
            (M::Jkr, D::Tsuji),
        ];
        for (normal, damping) in cases {
            let law = ContactLaw { damping, ..ContactLaw::mfix(normal) };
            let reference = [elastic("a", 0.002, 2500.0), elastic("b", 0.003, 7800.0)];
            let other = [elastic("a", 0.0013, 2500.0), elastic("b", 0.0047, 7800.0)];
            let build =
                |phases: &[Phase]| CoeffTable::build(&law, phases, &wall, &[p; 3], &[p; 2]).expect("table");
            let unit = build(&reference).per_unit_size(&law, &reference, 0.01);
            let direct = build(&other);
            assert!(unit.sized() && !direct.sized());
            let (ra, rb) = (other[0].radius(), other[1].radius());
            let (ma, mb) = (other[0].mass(), other[1].mass());
            // A pair of the two phases and phase b at the wall.
            for (u, d, r_star, m_eff) in [
                (unit.pair(0, 1), direct.pair(0, 1), ra * rb / (ra + rb), ma * mb / (ma + mb)),
                (unit.wall(1, 0), direct.wall(1, 0), rb, mb),
            ] {
                let (s, pull_off) = crate::with_normal_submodel!(normal, |N| (
                    sized::<N>(u, damping, r_star, m_eff),
                    u.pull_off * <N as NormalSubModel>::pull_off_scale(r_star)
                ));
                let what = format!("{normal:?} {damping:?}");
                for (name, a, b) in [
                    ("kn", s.kn, d.kn),
                    ("kt", s.kt, d.kt),
                    ("eta_n", s.eta_n, d.eta_n),
                    ("eta_t", s.eta_t, d.eta_t),
                    ("pull_off", pull_off, d.pull_off),
                ] {
                    assert!(rel(a, b) < 1e-14, "{what} {name}: {a:e} formed, {b:e} derived");
                }
                if normal == M::Jkr {
                    assert!(rel(s.r_star, d.r_star) < 1e-15, "{what} R*");
                }
            }
        }
    }

    #[test]
    fn too_many_phases_or_wall_materials_are_refused_before_the_table() {
        let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
        let p = ContactParams { kn: Some(1000.0), ..Default::default() };
        let phases: Vec<Phase> = (0..=MAX_PHASES).map(|k| phase(format!("p{k}"), 0.004, 2500.0)).collect();
        // 101 phases: refused although the parameter list is also wrong (the count comes first).
        let e = CoeffTable::build(&law, &phases, &[], &[p], &[]).expect_err("101 phases").to_string();
        assert!(e.contains("101 phases; at most 100"), "{e}");
        let n = MAX_PHASES;
        let ok = CoeffTable::build(&law, &phases[..n], &[], &vec![p; n * (n + 1) / 2], &[]);
        assert!(ok.is_ok(), "100 phases are allowed");
        let walls: Vec<WallMaterial> = (0..=MAX_WALL_MATERIALS)
            .map(|k| WallMaterial { name: format!("w{k}"), youngs_modulus: None, poisson_ratio: None })
            .collect();
        let e = CoeffTable::build(&law, &phases[..1], &walls, &[p], &[]).expect_err("101 walls").to_string();
        assert!(e.contains("101 wall materials"), "{e}");
    }

    #[test]
    fn coefficients_that_overflow_from_finite_inputs_are_refused() {
        let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
        let p = ContactParams { kn: Some(1000.0), en: 0.9, ..Default::default() };
        // ρ = 1e308: the mass (3e300 kg) is finite, √(k·m) is not the problem, but
        // k·m overflows for k_n = 1e10 and so does the damping.
        let big = [phase("heavy".into(), 0.004, 1e308)];
        let pk = ContactParams { kn: Some(1e10), ..p };
        let e = CoeffTable::build(&law, &big, &[], &[pk], &[]).expect_err("overflow").to_string();
        assert!(e.contains("contact 'heavy'-'heavy'") && e.contains("double precision"), "{e}");
        // d = 1e-300: the mass underflows to 0 and the effective mass with it.
        let tiny = [phase("dust".into(), 1e-300, 2500.0)];
        let e = CoeffTable::build(&law, &tiny, &[], &[p], &[]).expect_err("underflow").to_string();
        assert!(e.contains("effective mass"), "{e}");
    }
}
