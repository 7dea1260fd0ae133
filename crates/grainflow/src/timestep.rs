//! The time step (reference: MFIX-DEM model §5).

use crate::contact::normal::StabilityRule;
use crate::contact::{CoeffTable, ContactLaw, NormalDamping};
use crate::error::EngineError;
use crate::material::Phase;

/// How the time step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStepRule {
    /// MFIX's rule: DTSOLID = TCOLL / factor (MFIX `DTSOLID_FACTOR`, default 50, at least 10),
    /// TCOLL the shortest collision time over all phase pairs.
    Mfix {
        /// `DTSOLID_FACTOR`.
        factor: f64,
    },
    /// An explicit time step, s.
    Fixed(f64),
}

/// The time step in use, the number of steps, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeStepChoice {
    /// Δt, s.
    pub dt: f64,
    /// Number of steps, ceil((t_stop − t_0)/Δt) (quotient in single precision, as MFIX).
    pub steps: u64,
    /// TCOLL, s, when MFIX's rule was evaluated.
    pub tcoll: Option<f64>,
    /// One sentence saying which rule gave Δt.
    pub explanation: String,
}

/// MFIX's collision time of a phase pair: π/√(K/m_eff − (η_n/m_eff)²/4), with K = k_n (LSD) or
/// K = K_n (Hertz, used as if it were linear, as MFIX does).
pub fn collision_time(kn: f64, eta_n: f64, m_eff: f64) -> f64 {
    std::f64::consts::PI / (kn / m_eff - (eta_n / m_eff).powi(2) / 4.0).sqrt()
}

/// The stiffness MFIX's collision time takes: k_n, or K_n (Hertz, as if linear); for JKR the
/// Hertz K_n = (4/3)E*·√R* of its elastic part (the normal model's own
/// `NormalSubModel::collision_stiffness`).
fn linear_stiffness(law: &ContactLaw, c: &crate::contact::ContactCoeffs) -> f64 {
    law.normal.collision_stiffness(c)
}

/// η_n in kg/s for the phase pair's effective mass, whatever the damping's scaling.
fn absolute_eta(law: &ContactLaw, c: &crate::contact::ContactCoeffs) -> f64 {
    match law.damping {
        NormalDamping::MassVelocity => c.eta_n * c.m_eff,
        NormalDamping::Tsuji | NormalDamping::Liggghts => c.eta_n * c.m_eff.sqrt(),
        NormalDamping::Mfix | NormalDamping::ExactRestitution => c.eta_n,
    }
}

impl TimeStepRule {
    /// The steps of a run of length `span` at `dt` under this rule: MFIX's count
    /// ([`step_count`]) under MFIX's rule, [`fixed_step_count`] for an explicit step.
    pub fn steps(&self, span: f64, dt: f64) -> u64 {
        match self {
            TimeStepRule::Mfix { .. } => step_count(span, dt),
            TimeStepRule::Fixed(_) => fixed_step_count(span, dt),
        }
    }
}

/// Number of steps MFIX takes for a run of length `span`: ceil of the single-precision quotient.
pub fn step_count(span: f64, dt: f64) -> u64 {
    let q = (span as f32) / (dt as f32);
    if q.is_finite() && q > 0.0 { q.ceil() as u64 } else { 0 }
}

/// Number of steps for an explicit Δt: the run length divided by Δt, rounded to the nearest
/// whole number when it is one to within 1e-9 (so t_stop = 0.1, Δt = 1e-4 gives 1 000 steps
/// despite rounding), else rounded up.
pub fn fixed_step_count(span: f64, dt: f64) -> u64 {
    let q = span / dt;
    if !(q.is_finite() && q > 0.0) {
        return 0;
    }
    let r = q.round();
    if (q - r).abs() <= 1e-9 * q { r as u64 } else { q.ceil() as u64 }
}

/// The most steps a run may take: 10¹⁰. At the engine's fastest, some 10⁷ particle-steps a
/// second on one core, that is a quarter of an hour for a single particle and four months for
/// a bed of 10 000; a count above it comes from a mistyped time, time step or stiffness
/// (`dt = 1e-300`, `t_stop = 1e300`, `kn = 1e300`), and is refused before the run.
pub const MAX_STEPS: f64 = 1e10;

/// Fraction of the Rayleigh time that is the default step of a Hertz case without `dt`:
/// 0.2, the largest step LIGGGHTS accepts without a warning (`check_timestep/gran`) and the
/// low end of EDEM's 20-40 % guidance; the explicit schemes are stable up to about 0.3·T_R
/// ([`stability_limit`]).
pub const HERTZ_DEFAULT_RAYLEIGH_FRACTION: f64 = 0.2;

/// The Rayleigh time T_R = πR√(ρ/G)/(0.1631ν + 0.8766) of the phase with the smallest one,
/// s, with that phase's index; `None` if no phase has E and ν.
pub fn rayleigh_time(phases: &[Phase]) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for (k, ph) in phases.iter().enumerate() {
        if let (Some(e), Some(nu)) = (ph.youngs_modulus, ph.poisson_ratio) {
            let g = e / (2.0 * (1.0 + nu));
            let t = std::f64::consts::PI * ph.radius() * (ph.density / g).sqrt() / (0.1631 * nu + 0.8766);
            if best.is_none_or(|b| t < b.0) {
                best = Some((t, k));
            }
        }
    }
    best
}

/// The default Δt of a Hertz case that gives none: [`HERTZ_DEFAULT_RAYLEIGH_FRACTION`] of the
/// smallest Rayleigh time. `None` if no phase has E and ν or the result is not a positive
/// finite time.
pub fn hertz_default_dt(phases: &[Phase]) -> Option<f64> {
    let (t, _) = rayleigh_time(phases)?;
    let dt = HERTZ_DEFAULT_RAYLEIGH_FRACTION * t;
    (dt.is_finite() && dt > 0.0).then_some(dt)
}

/// The most a particle or a mesh's fastest point may move in one step, as a fraction of a
/// particle radius: 0.1. A moving wall's overlap with a particle grows by its travel each step,
/// and a sheet (a mesh touched from either side) is passed through once a step carries a
/// particle's centre across it: a step carrying a point more than a radius cannot resolve a
/// contact at all. A tenth keeps the first step of a contact within a tenth of the radius,
/// far inside the health check's default overlap limit (0.5), as MFIX's TCOLL/50 keeps an
/// ordinary impact in some 25 steps.
pub const TRAVEL_FRACTION: f64 = 0.1;

/// The first mesh of `meshes` whose fastest point ([`MeshWall::fastest_point_speed`]) moves
/// more than [`TRAVEL_FRACTION`] of `smallest_radius` in a step of `dt`: its index and a
/// sentence naming it (by `names`), its speed and the largest safe step.
///
/// [`MeshWall::fastest_point_speed`]: crate::mesh::MeshWall::fastest_point_speed
pub fn mesh_travel_problem(
    meshes: &[crate::mesh::MeshWall],
    names: &[String],
    smallest_radius: f64,
    dt: f64,
) -> Option<(usize, String)> {
    meshes.iter().zip(names).enumerate().find_map(|(k, (m, name))| {
        let (speed, how) = m.fastest_point_speed();
        let travel = speed * dt;
        (travel > TRAVEL_FRACTION * smallest_radius).then(|| {
            (
                k,
                format!(
                    "mesh '{name}' is {how}: its fastest point moves at {speed:.4e} m/s, {travel:.4e} m in a step of dt = {dt:.4e} s, {:.3} of the smallest particle radius {smallest_radius:.4e} m, above the limit of {TRAVEL_FRACTION} of it (a particle it meets would pass through it or be hit far harder than the contact can resolve); a safe time step is dt <= {:.4e} s",
                    travel / smallest_radius,
                    TRAVEL_FRACTION * smallest_radius / speed
                ),
            )
        })
    })
}

/// The speed a Hertz collision time is stated at, m/s, and what it is: the fastest of the
/// particles at the start, the insertions' velocities and the meshes' fastest points
/// ([`MeshWall::fastest_point_speed`](crate::mesh::MeshWall::fastest_point_speed)); 1 m/s,
/// said so, when none of them moves.
pub fn characteristic_speed(
    particles: &crate::state::Particles,
    insertions: &[crate::insertion::Insertion],
    meshes: &[crate::mesh::MeshWall],
) -> (f64, String) {
    speed_of(fastest(particles), insertions, meshes)
}

/// The fastest of `particles` at the start, m/s.
pub fn fastest(particles: &crate::state::Particles) -> f64 {
    particles.velocity.iter().map(|v| v.length()).fold(0.0, f64::max)
}

/// [`characteristic_speed`] with the fastest particle at the start given (`start`, m/s).
pub fn speed_of(
    start: f64,
    insertions: &[crate::insertion::Insertion],
    meshes: &[crate::mesh::MeshWall],
) -> (f64, String) {
    let inserted = insertions.iter().map(|i| i.velocity.length()).fold(0.0, f64::max);
    let mesh = meshes.iter().map(|m| m.fastest_point_speed().0).fold(0.0, f64::max);
    let v = start.max(inserted).max(mesh);
    if !(v.is_finite() && v > 0.0) {
        return (1.0, "1 m/s, as nothing moves at the start".into());
    }
    let what = if v == start {
        "the fastest particle at the start"
    } else if v == inserted {
        "the fastest insertion velocity"
    } else {
        "the fastest point of a moving mesh"
    };
    (v, format!("{v:.4e} m/s, {what}"))
}

/// The Hertz collision time of two phases meeting at speed `v`, s:
/// 2.87·(m*²/(R*·E*²·v))^(1/5), with m* = m₁m₂/(m₁ + m₂), R* = R₁R₂/(R₁ + R₂) and
/// 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂ (Johnson, Contact Mechanics §11.4); `None` without
/// E and ν.
pub fn hertz_collision_time(a: &Phase, b: &Phase, v: f64) -> Option<f64> {
    let (ea, na, eb, nb) = (a.youngs_modulus?, a.poisson_ratio?, b.youngs_modulus?, b.poisson_ratio?);
    let m = a.mass() * b.mass() / (a.mass() + b.mass());
    let r = a.radius() * b.radius() / (a.radius() + b.radius());
    let e = 1.0 / ((1.0 - na * na) / ea + (1.0 - nb * nb) / eb);
    let t = 2.87 * (m * m / (r * e * e * v)).powf(0.2);
    (t.is_finite() && t > 0.0).then_some(t)
}

/// For an elastic law (Hertz, JKR) with E and ν given: the step `dt` against the Rayleigh
/// time and the shortest Hertz collision time over the phase pairs at `speed`, as a clause.
fn elastic_statement(dt: f64, phases: &[Phase], speed: &(f64, String)) -> Option<String> {
    let (tr, k) = rayleigh_time(phases)?;
    let mut th: Option<(f64, usize, usize)> = None;
    for m in 0..phases.len() {
        for l in m..phases.len() {
            if let Some(t) = hertz_collision_time(&phases[m], &phases[l], speed.0)
                && th.is_none_or(|b| t < b.0)
            {
                th = Some((t, m, l));
            }
        }
    }
    let (th, m, l) = th?;
    Some(format!(
        "dt/T_R = {:.3} against the Rayleigh time T_R = {tr:.4e} s of phase '{}' (stable to about 0.3), and T_H/dt = {:.1} against the Hertz collision time T_H = 2.87 (m*^2/(R* E*^2 v))^(1/5) = {th:.4e} s of phase pair '{}'-'{}' at v = {}",
        dt / tr,
        phases[k].name,
        th / dt,
        phases[m].name,
        phases[l].name,
        speed.1
    ))
}

/// Refuses a run whose step count is absurd or cannot be formed (see [`MAX_STEPS`]).
pub fn check_step_count(span: f64, dt: f64) -> Result<(), EngineError> {
    let q = span / dt;
    let advice = "check t_stop, t_start and dt, and the stiffness (kn, youngs_modulus) and masses that set the time step";
    if !q.is_finite() {
        return Err(EngineError::BadReference(format!(
            "the run's step count (t_stop - t_start)/dt = {span:e} s / {dt:e} s overflows: more than the limit of {MAX_STEPS:e} steps; {advice}"
        )));
    }
    if q > MAX_STEPS {
        return Err(EngineError::BadReference(format!(
            "the run would take {q:.3e} steps (t_stop - t_start = {span:e} s at dt = {dt:e} s), more than the limit of {MAX_STEPS:e} steps; {advice}"
        )));
    }
    Ok(())
}

/// Applies the rule. For an elastic law (Hertz, JKR) the explanation states the step against
/// the Rayleigh time and the Hertz collision time at `speed` ([`characteristic_speed`]),
/// not against MFIX's TCOLL, which takes K_n as a linear stiffness.
pub fn choose(
    rule: TimeStepRule,
    law: &ContactLaw,
    phases: &[Phase],
    table: &CoeffTable,
    span: f64,
    speed: &(f64, String),
) -> Result<TimeStepChoice, EngineError> {
    let model = law.normal.collision_stiffness_is();
    if phases.is_empty() {
        return Err(EngineError::BadReference("at least one phase is needed".into()));
    }
    // TCOLL is always evaluated: even with an explicit Δt it is worth reporting.
    let mut tcoll = f64::INFINITY;
    let mut limiting = (0, 0);
    for m in 0..phases.len() {
        for l in m..phases.len() {
            let c = table.pair(m, l);
            let t = collision_time(linear_stiffness(law, c), absolute_eta(law, c), c.m_eff);
            if t < tcoll {
                tcoll = t;
                limiting = (m, l);
            }
        }
    }
    let (dt, tcoll, explanation) = match rule {
        TimeStepRule::Mfix { factor } => {
            if !(factor.is_finite() && factor >= 10.0) {
                return Err(EngineError::invalid(
                    "dtsolid_factor",
                    factor,
                    "MFIX's DTSOLID_FACTOR must be at least 10",
                ));
            }
            let dt = tcoll / factor;
            if !(dt.is_finite() && dt > 0.0) {
                let c = table.pair(limiting.0, limiting.1);
                return Err(EngineError::BadReference(format!(
                    "MFIX's time-step rule gives no usable step: the collision time TCOLL of phase pair '{}'-'{}' is {tcoll:e} s (K = {:e}, effective mass {:e} kg, eta_n = {:e}); the stiffness, diameter or density is outside what double precision can hold (are they in SI units?); give an explicit dt",
                    phases[limiting.0].name,
                    phases[limiting.1].name,
                    c.kn,
                    c.m_eff,
                    absolute_eta(law, c)
                )));
            }
            let mut text = format!(
                "dt = {dt:.7e} s from MFIX's rule: TCOLL = {tcoll:.7e} s (phase pair '{}'-'{}', {model}) / DTSOLID_FACTOR {factor}",
                phases[limiting.0].name, phases[limiting.1].name
            );
            if let Some(e) = elastic_statement(dt, phases, speed).filter(|_| law.normal.elastic()) {
                text = format!("{text}; {e}");
            }
            (dt, Some(tcoll), text)
        }
        TimeStepRule::Fixed(dt) => {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(EngineError::invalid("dt", dt, "the time step must be a positive time in s"));
            }
            let hertz_default =
                law.normal.elastic() && hertz_default_dt(phases).is_some_and(|d| d.to_bits() == dt.to_bits());
            let text = if hertz_default {
                // The step a Hertz case without dt gets (the case layer puts it here).
                let (tr, k) = rayleigh_time(phases).unwrap_or((f64::NAN, 0));
                let mfix = if tcoll.is_finite() {
                    format!(
                        "; MFIX's rule, TCOLL/50 with K_n taken as a linear stiffness, would give {:.7e} s",
                        tcoll / 50.0
                    )
                } else {
                    String::new()
                };
                let hertz = elastic_statement(dt, phases, speed).map_or(String::new(), |e| format!("; {e}"));
                format!(
                    "dt = {dt:.7e} s = {HERTZ_DEFAULT_RAYLEIGH_FRACTION} x the Rayleigh time {tr:.7e} s of phase '{}', the default for Hertz contacts when dt is not given (stable to about 0.3 x T_R{mfix}){hertz}",
                    phases[k].name
                )
            } else if let Some(e) = elastic_statement(dt, phases, speed).filter(|_| law.normal.elastic()) {
                format!("dt = {dt:.7e} s given explicitly: {e}")
            } else if tcoll.is_finite() {
                let ratio = tcoll / dt;
                // Plain in the usual range; with an exponent when a soft spring or a tiny step
                // would print dozens of digits.
                let ratio = if ratio < 1e6 { format!("{ratio:.1}") } else { format!("{ratio:.3e}") };
                format!(
                    "dt = {dt:.7e} s given explicitly (MFIX's rule would give TCOLL/50 = {:.7e} s; TCOLL/dt = {ratio})",
                    tcoll / 50.0
                )
            } else {
                format!("dt = {dt:.7e} s given explicitly")
            };
            (dt, tcoll.is_finite().then_some(tcoll), text)
        }
    };
    check_step_count(span, dt)?;
    let steps = rule.steps(span, dt);
    if steps == 0 {
        // Below single precision (MFIX's step count): span and dt both tiny.
        return Err(EngineError::BadReference(format!(
            "the step count of a run of {span:e} s at dt = {dt:e} s cannot be formed (MFIX counts steps in single precision, which these times are below); check t_stop, t_start and dt"
        )));
    }
    Ok(TimeStepChoice { dt, steps, tcoll, explanation })
}

/// The largest time step the contact law tolerates, and the contact that sets it.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityLimit {
    /// Largest safe Δt, s.
    pub dt_max: f64,
    /// A time step comfortably inside it, s (what to suggest).
    pub dt_safe: f64,
    /// Which contact or phase sets the limit, and by which rule.
    pub reason: String,
}

/// Stability limit of explicit integration for the contact law, by its normal model's rule
/// ([`StabilityRule`]):
/// - [`CollisionTime`](StabilityRule::CollisionTime) (linear spring–dashpot): Δt ≤ t_c/5
///   (ω·Δt ≤ 0.63, well inside the explicit schemes' ω·Δt < 2), t_c the collision time of the
///   stiffest contact over all phase pairs **and** phase–wall pairs (MFIX's rule leaves the
///   walls out); the suggestion is t_c/50, MFIX's default;
/// - [`RayleighTime`](StabilityRule::RayleighTime) (Hertz, JKR): Δt ≤ 0.3·T_R with the
///   Rayleigh time T_R = πR√(ρ/G)/(0.1631ν + 0.8766) of the smallest phase (Thornton's and Li
///   et al.'s criterion); the suggestion is 0.1·T_R.
pub fn stability_limit(
    law: &ContactLaw,
    phases: &[Phase],
    wall_materials: &[crate::material::WallMaterial],
    table: &CoeffTable,
) -> StabilityLimit {
    match law.normal.stability() {
        StabilityRule::CollisionTime => {
            let mut best = (f64::INFINITY, String::new());
            for m in 0..phases.len() {
                for l in m..phases.len() {
                    let c = table.pair(m, l);
                    let t = collision_time(linear_stiffness(law, c), absolute_eta(law, c), c.m_eff);
                    if t < best.0 {
                        best = (t, format!("contact '{}'-'{}'", phases[m].name, phases[l].name));
                    }
                }
                for (w, wm) in wall_materials.iter().enumerate() {
                    let c = table.wall(m, w);
                    let t = collision_time(linear_stiffness(law, c), absolute_eta(law, c), c.m_eff);
                    if t < best.0 {
                        best = (t, format!("contact '{}'-wall '{}'", phases[m].name, wm.name));
                    }
                }
            }
            StabilityLimit {
                dt_max: best.0 / 5.0,
                dt_safe: best.0 / 50.0,
                reason: format!("collision time {:.4e} s of the {} (limit t_c/5)", best.0, best.1),
            }
        }
        StabilityRule::RayleighTime => {
            let mut best = (f64::INFINITY, String::new());
            for ph in phases {
                if let (Some(e), Some(nu)) = (ph.youngs_modulus, ph.poisson_ratio) {
                    let g = e / (2.0 * (1.0 + nu));
                    let t =
                        std::f64::consts::PI * ph.radius() * (ph.density / g).sqrt() / (0.1631 * nu + 0.8766);
                    if t < best.0 {
                        best = (t, format!("phase '{}'", ph.name));
                    }
                }
            }
            StabilityLimit {
                dt_max: 0.3 * best.0,
                dt_safe: 0.1 * best.0,
                reason: format!("Rayleigh time {:.4e} s of {} (limit 0.3·T_R)", best.0, best.1),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactLaw, ContactParams, NormalModel};

    fn glass() -> Phase {
        Phase {
            name: "glass".into(),
            diameter: 0.004,
            density: 2500.0,
            youngs_modulus: Some(6.0e10),
            poisson_ratio: Some(0.25),
        }
    }

    fn at_1() -> (f64, String) {
        (1.0, "1 m/s".into())
    }

    fn table(law: &ContactLaw, phases: &[Phase], kn: f64) -> CoeffTable {
        let p = ContactParams { kn: Some(kn), en: 0.9, et: Some(0.9), ..Default::default() };
        CoeffTable::build(law, phases, &[], &[p], &[]).expect("valid")
    }

    #[test]
    fn step_counts_above_the_limit_or_not_formed_are_refused() {
        // span/dt exactly 1e10 (0.5 and 5e9 are exact in binary) is the limit and allowed.
        assert!(check_step_count(5e9, 0.5).is_ok());
        let e = check_step_count(5e9 + 1.0, 0.5).expect_err("one step over").to_string();
        assert!(e.contains("1.000e10 steps") && e.contains("more than the limit of 1e10"), "{e}");
        assert!(check_step_count(0.01, 5e-324).expect_err("overflows").to_string().contains("overflows"));
        let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
        let phases = [glass()];
        let t = table(&law, &phases, 1000.0);
        // dt = 1e-300 for 0.01 s used to run for ever; t_stop = 1e300 overflowed to 0 steps.
        for (rule, span) in
            [(TimeStepRule::Fixed(1e-300), 0.01), (TimeStepRule::Mfix { factor: 50.0 }, 1e300)]
        {
            let e = choose(rule, &law, &phases, &t, span, &at_1()).expect_err("refused").to_string();
            assert!(e.contains("more than the limit"), "{e}");
        }
        // The MFIX rule's single-precision count: k_n = 1e300 gives dt ~ 1e-156 s; a run of
        // 1e-150 s is some 10^5 steps in double precision, but both times are 0 in single.
        let stiff = table(&law, &phases, 1e300);
        let e = choose(TimeStepRule::Mfix { factor: 50.0 }, &law, &phases, &stiff, 1e-150, &at_1())
            .expect_err("no count")
            .to_string();
        assert!(e.contains("single precision"), "{e}");
        // An ordinary run is unaffected: 0.01 s at MFIX's 1.2867e-5 s is 778 steps (cli.rs).
        assert_eq!(
            choose(TimeStepRule::Mfix { factor: 50.0 }, &law, &phases, &t, 0.01, &at_1()).unwrap().steps,
            778
        );
    }

    #[test]
    fn the_hertz_default_is_a_fifth_of_the_rayleigh_time_and_says_so() {
        let law = ContactLaw::mfix(NormalModel::Hertz);
        let phases = [glass()];
        let t = table(&law, &phases, 1.0);
        let limit = stability_limit(&law, &phases, &[], &t);
        let dt = hertz_default_dt(&phases).expect("E and ν given");
        // 0.2·T_R against the 0.3·T_R limit: exactly two thirds of it (to rounding).
        assert!((dt / limit.dt_max - 2.0 / 3.0).abs() < 1e-12, "{dt} vs {}", limit.dt_max);
        let c = choose(TimeStepRule::Fixed(dt), &law, &phases, &t, 0.01, &at_1()).unwrap();
        assert!(c.explanation.contains("0.2 x the Rayleigh time"), "{}", c.explanation);
        assert!(c.explanation.contains("MFIX's rule"), "{}", c.explanation);
        // Any other explicit step is reported as given.
        let c = choose(TimeStepRule::Fixed(0.5 * dt), &law, &phases, &t, 0.01, &at_1()).unwrap();
        assert!(c.explanation.contains("given explicitly"), "{}", c.explanation);
        // No elastic constants: no default.
        let lsd = Phase { youngs_modulus: None, ..glass() };
        assert_eq!(hertz_default_dt(&[lsd]), None);
    }

    /// Issue 38: a Hertz step was judged against MFIX's TCOLL ("TCOLL/dt = 4.3") although
    /// it was 5 % of the Rayleigh time. It is stated against the Rayleigh time and the Hertz
    /// collision time, both from their closed forms here.
    #[test]
    fn a_hertz_step_is_stated_against_the_rayleigh_and_hertz_times() {
        let law = ContactLaw::mfix(NormalModel::Hertz);
        let phases = [glass()];
        let t = table(&law, &phases, 1.0);
        let (r, rho, e, nu): (f64, f64, f64, f64) = (0.002, 2500.0, 6.0e10, 0.25);
        let g = e / (2.0 * (1.0 + nu));
        let tr = std::f64::consts::PI * r * (rho / g).sqrt() / (0.1631 * nu + 0.8766);
        // Two equal spheres: m* = m/2, R* = R/2, E* = E/(2(1 − ν²)); at v = 2 m/s.
        let m = rho * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        let (ms, rs, es, v) = (m / 2.0, r / 2.0, e / (2.0 * (1.0 - nu * nu)), 2.0);
        let th = 2.87 * (ms * ms / (rs * es * es * v)).powf(0.2);
        let dt = 0.05 * tr;
        let speed = (v, "2 m/s".to_string());
        for rule in [TimeStepRule::Fixed(dt), TimeStepRule::Mfix { factor: 50.0 }] {
            let c = choose(rule, &law, &phases, &t, 0.01, &speed).unwrap();
            // The printed figures: 3 decimals of dt/T_R, 1 of T_H/dt, 5 digits of the times
            // (the closed forms here and the engine's differ in rounding only, ~1e-16).
            let why = &c.explanation;
            for part in [
                format!(
                    "dt/T_R = {:.3} against the Rayleigh time T_R = {tr:.4e} s of phase 'glass'",
                    c.dt / tr
                ),
                format!("T_H/dt = {:.1} against the Hertz collision time", th / c.dt),
                format!("= {th:.4e} s of phase pair 'glass'-'glass' at v = 2 m/s"),
            ] {
                assert!(why.contains(&part), "'{part}' not in: {why}");
            }
            assert!(!why.contains("TCOLL/dt"), "{why}");
        }
        let c = choose(TimeStepRule::Fixed(dt), &law, &phases, &t, 0.01, &speed).unwrap();
        assert!(c.explanation.contains("dt/T_R = 0.050"), "{}", c.explanation);
        // The linear law keeps MFIX's ratio.
        let lsd = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
        let tl = table(&lsd, &phases, 1000.0);
        let c = choose(TimeStepRule::Fixed(1e-6), &lsd, &phases, &tl, 0.01, &speed).unwrap();
        assert!(c.explanation.contains("TCOLL/dt"), "{}", c.explanation);
    }

    #[test]
    fn an_unusable_collision_time_names_the_pair_not_the_phase_count() {
        let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
        // k_n at the float maximum: TCOLL underflows far below a usable step.
        let phases = [glass()];
        let t = table(&law, &phases, f64::MAX);
        let e = choose(TimeStepRule::Mfix { factor: 50.0 }, &law, &phases, &t, 0.01, &at_1())
            .expect_err("refused")
            .to_string();
        assert!(!e.contains("at least one phase"), "{e}");
        assert!(e.contains("steps") || e.contains("'glass'-'glass'"), "{e}");
    }
}
