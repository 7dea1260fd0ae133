//! MFIX verification case DEM01: freely falling particle with wall collision (linear
//! spring–dashpot). Source: MFIX's verification manual, case DEM01 (MFIX's `tests/dem/DEM01`); set-up and
//! closed form in docs/verification.md.
//!
//! A ball (d = 0.2 m, ρ = 2600 kg/m³, m = 10.890855 kg) is released at rest from h₀ = 0.5 m,
//! falls onto the floor y = 0, bounces once and flies until t = 0.5 s. Both of MFIX's
//! integrators (EULER, ADAMS_BASHFORTH) are run for k_n = k_n,w = 1e4 N/m with
//! e_n ∈ {0.9, 0.8, 0.7, 0.6} and k_n ∈ {2.5e4, 5e4, 1e5} N/m with e_n ∈ {1.0, …, 0.6}:
//! 19 runs per integrator, each with MFIX's time step DTSOLID = TCOLL/50 of the 1-1 phase pair
//! (m_eff = m/2), e.g. 1.4670332e-3 s for k_n = 1e4 N/m, e_n = 0.9.
//!
//! ## Physics
//! While the ball touches the floor (y < R) it is a damped linear oscillator under gravity:
//! y″ = −g − ω₀²(y − R) − 2bω₀·y′, with ω₀ = √(k_n/m) and b = η_n,w/(2√(k_n·m)) (the wall
//! damping uses m_eff = m). With V = √(2g(h₀ − R)) the impact speed, t_c = √(2(h₀ − R)/g) the
//! impact time and ω_d = ω₀√(1 − b²), the solution has three stages:
//! 1. free fall, t < t_c: y = h₀ − g·t²/2, v = −g·t;
//! 2. contact, τ = t − t_c: y = e^(−bω₀τ)[(g/ω₀²)cos ω_dτ + ((bg/ω₀ − V)/ω_d) sin ω_dτ] + R − g/ω₀²,
//!    and its derivative;
//! 3. rebound after t_r, the first root of y₂ = R: y = R + v_r(t − t_r) − g(t − t_r)²/2.
//!
//! The model separates exactly at y = R (the damping force −η·v_n is not clipped, as in MFIX),
//! so the closed form is the model's own exact solution; every difference is time stepping.
//!
//! ## How the simulation is sampled
//! MFIX's Δt does not divide the output interval 5e-3 s. Each output is the first step at or
//! after the output time, and it is compared with the closed form at that step's own simulated
//! time (t = n·Δt): the fair comparison, with no interpolation error added. The CSV's `time`
//! column is that simulated time.
//!
//! ## Accuracy to expect (the tolerances)
//! With MFIX's rule Δt = π/(50·ω_d,pair) and ω_pair = √(2k_n/m), the product z = ω₀Δt is the
//! same for every k_n: z = π/(50√2·√(1 − b²)) ≈ 0.0444.
//! - Free fall is integrated exactly by Adams–Bashforth (constant acceleration; its first step
//!   takes a_prev = a). Semi-implicit Euler (MFIX's EULER: v first, then x with the new v) gives
//!   v_n = −g·t_n exactly and y_n = y(t_n) − g·t_n·Δt/2: its positions lead by half a step, an
//!   O(Δt) error V·Δt/2 at impact, while its velocities are those of Störmer–Verlet, second
//!   order.
//! - The damping force η·v jumps at touch-down (η·V) and at lift-off (η·v_r). Where the jump
//!   falls inside a step is not resolved; both integrators then err by at most half a step of
//!   the jump (Adams–Bashforth weighs it 3/2 on its first step, Euler's half-step lead shifts
//!   it), i.e. b·z·V and b·z·v_r in velocity (η/m = 2bω₀). This first-order term dominates for
//!   e_n < 1 and vanishes for e_n = 1.
//! - The elastic force k_n·δ is continuous but kinked at touch-down and lift-off (≤ z²/2 each,
//!   relative) and Adams–Bashforth's truncation over a contact adds about (5π/12)·z².
//!
//! The velocity tolerance is therefore b·z·(1 + e_n) + 2.5·z² (relative to V); a lift-off
//! error then grows in flight into a position error of at most that × V × (t_stop − t_c),
//! plus Euler's lead V·Δt/2.

use crate::check::Check;
use crate::error::VerifyError;
use crate::plot::{self, Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions, case_dir, summary_markdown, write_file};
use grainflow::contact::damping_coefficient;
use grainflow::{Integrator, Simulation, TimeStepRule};
use grainflow_case::Case;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The shipped case file (k_n = 1e4 N/m, e_n = 0.9, EULER).
pub const CASE: &str = include_str!("../cases/dem01/dem01.toml");
/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.80665;
/// Release height of the centre, m.
pub const H0: f64 = 0.5;
/// Ball radius, m.
pub const RADIUS: f64 = 0.1;
/// MFIX's DTSOLID for k_n = 1e4 N/m, e_n = 0.9 (docs/verification.md, DEM01), s.
pub const MFIX_DT_1E4_09: f64 = 1.4670332e-3;
/// The (k_n, e_n) grid of the case, N/m: 19 runs per integrator.
pub const GRID: [(f64, &[f64]); 4] = [
    (1.0e4, &[0.9, 0.8, 0.7, 0.6]),
    (2.5e4, &[1.0, 0.9, 0.8, 0.7, 0.6]),
    (5.0e4, &[1.0, 0.9, 0.8, 0.7, 0.6]),
    (1.0e5, &[1.0, 0.9, 0.8, 0.7, 0.6]),
];
/// MFIX's two integrators, in the order of the CSV.
pub const INTEGRATORS: [Integrator; 2] = [Integrator::Euler, Integrator::AdamsBashforth];

/// The shipped case, parsed.
pub fn case() -> Result<Case, VerifyError> {
    crate::report::shipped_case("dem01/dem01.toml", CASE, &[])
}

/// Sets k_n and e_n of every phase pair and every phase–wall pair of `case`.
pub fn set_kn_en(case: &mut Case, kn: f64, en: f64) {
    for p in case.config.pair_params.iter_mut().chain(case.config.wall_params.iter_mut()) {
        p.kn = Some(kn);
        p.en = en;
    }
}

/// Damping ratio b = η/(2√(k·m)) = |ln e|/√(π² + ln²e) of MFIX's damping formula.
pub fn damping_ratio(kn: f64, mass: f64, en: f64) -> f64 {
    damping_coefficient(kn, mass, en) / (2.0 * (kn * mass).sqrt())
}

/// One contact of a linear spring–dashpot sphere with an immovable floor under gravity, in
/// closed form: y″ = −g − ω₀²(y − R) − 2bω₀y′ while y < R.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorContact {
    /// ω₀ = √(k_n/m), rad/s.
    pub omega0: f64,
    /// Damping ratio b = η_n/(2√(k_n·m)).
    pub b: f64,
    /// Gravity, m/s² (positive).
    pub g: f64,
}

impl FloorContact {
    /// The contact of a ball of mass `mass` on a floor of stiffness `kn` and restitution `en`
    /// (damping from MFIX's formula with m_eff = m).
    pub fn new(kn: f64, mass: f64, en: f64, g: f64) -> Self {
        FloorContact { omega0: (kn / mass).sqrt(), b: damping_ratio(kn, mass, en), g }
    }

    /// Damped frequency ω_d = ω₀√(1 − b²), rad/s.
    pub fn omega_d(&self) -> f64 {
        self.omega0 * (1.0 - self.b * self.b).sqrt()
    }

    /// Static sag g/ω₀² = m·g/k_n, m.
    pub fn sag(&self) -> f64 {
        self.g / (self.omega0 * self.omega0)
    }

    /// (y − R, v) a time τ after touching down at speed `v_in` (> 0, downwards).
    pub fn state(&self, v_in: f64, tau: f64) -> (f64, f64) {
        let (w0, b, g) = (self.omega0, self.b, self.g);
        let wd = self.omega_d();
        let decay = (-b * w0 * tau).exp();
        let (s, c) = (wd * tau).sin_cos();
        let y = decay * ((g / (w0 * w0)) * c + ((b * g / w0 - v_in) / wd) * s) - g / (w0 * w0);
        let v = decay * (-v_in * c + ((b * w0 * v_in - g) / wd) * s);
        (y, v)
    }

    /// Lift-off: the first τ > 0 at which y returns to R, and the rebound speed there. `None`
    /// if the ball never leaves the floor (impact speed too small against the sag).
    pub fn lift_off(&self, v_in: f64) -> Option<(f64, f64)> {
        // The lift-off lies within one damped period: scan it, then bisect the sign change.
        let period = 2.0 * std::f64::consts::PI / self.omega_d();
        let n = 4000;
        let h = period / n as f64;
        let f = |tau: f64| self.state(v_in, tau).0;
        let mut lo = h;
        if f(lo) >= 0.0 {
            return None;
        }
        for k in 2..=n {
            let hi = k as f64 * h;
            if f(hi) >= 0.0 {
                let mut hi = hi;
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if f(mid) >= 0.0 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some((hi, self.state(v_in, hi).1));
            }
            lo = hi;
        }
        None
    }
}

/// The three-stage closed-form solution of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Analytic {
    /// The contact.
    pub contact: FloorContact,
    /// Impact speed V = √(2g(h₀ − R)), m/s.
    pub v_impact: f64,
    /// Impact time t_c, s.
    pub t_c: f64,
    /// Lift-off time t_r, s.
    pub t_r: f64,
    /// Rebound speed v_r, m/s.
    pub v_r: f64,
}

impl Analytic {
    /// The solution for a ball of `mass` on a floor (k_n, e_n).
    pub fn new(kn: f64, en: f64, mass: f64) -> Self {
        let contact = FloorContact::new(kn, mass, en, GRAVITY);
        let v_impact = (2.0 * GRAVITY * (H0 - RADIUS)).sqrt();
        let t_c = (2.0 * (H0 - RADIUS) / GRAVITY).sqrt();
        let (tau_r, v_r) = contact.lift_off(v_impact).unwrap_or((f64::INFINITY, f64::NAN));
        Analytic { contact, v_impact, t_c, t_r: t_c + tau_r, v_r }
    }

    /// (stage, y, v) at time t; stage 1 free fall, 2 contact, 3 rebound (valid until the second
    /// impact, t_r + 2v_r/g, after the end of the run for every run of the case).
    pub fn at(&self, t: f64) -> (u8, f64, f64) {
        if t < self.t_c {
            (1, H0 - 0.5 * GRAVITY * t * t, -GRAVITY * t)
        } else if t < self.t_r {
            let (y, v) = self.contact.state(self.v_impact, t - self.t_c);
            (2, RADIUS + y, v)
        } else {
            let s = t - self.t_r;
            (3, RADIUS + self.v_r * s - 0.5 * GRAVITY * s * s, self.v_r - GRAVITY * s)
        }
    }
}

/// One run of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSpec {
    /// Integrator.
    pub integrator: Integrator,
    /// k_n = k_n,w, N/m.
    pub kn: f64,
    /// e_n of the wall (and of the 1-1 pair, for the time step).
    pub en: f64,
}

/// Every run of the case: 19 per integrator, EULER first.
pub fn runs() -> Vec<RunSpec> {
    INTEGRATORS
        .iter()
        .flat_map(|&integrator| {
            GRID.iter().flat_map(move |&(kn, ens)| ens.iter().map(move |&en| RunSpec { integrator, kn, en }))
        })
        .collect()
}

/// One output of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Simulated time of the step, s.
    pub time: f64,
    /// Stage of the closed form at that time (1, 2, 3).
    pub stage: u8,
    /// Closed-form centre height, m.
    pub y_analytic: f64,
    /// Simulated centre height, m.
    pub y_sim: f64,
    /// Closed-form vertical velocity, m/s.
    pub v_analytic: f64,
    /// Simulated vertical velocity, m/s.
    pub v_sim: f64,
}

/// The outcome of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// What was run.
    pub spec: RunSpec,
    /// Δt, s.
    pub dt: f64,
    /// Steps of the run (MFIX's count).
    pub steps: u64,
    /// ω₀Δt of the wall contact.
    pub z: f64,
    /// The closed form.
    pub analytic: Analytic,
    /// The outputs, one per output time.
    pub samples: Vec<Sample>,
}

impl RunResult {
    /// Largest |y_sim − y_an|/(h₀ − R) over the outputs, and the time where it occurs.
    pub fn position_error(&self) -> (f64, f64) {
        worst(&self.samples, |s| (s.y_sim - s.y_analytic).abs() / (H0 - RADIUS))
    }

    /// Largest |v_sim − v_an|/V over the outputs, and the time where it occurs.
    pub fn velocity_error(&self) -> (f64, f64) {
        worst(&self.samples, |s| (s.v_sim - s.v_analytic).abs() / self.analytic.v_impact)
    }

    /// Tolerance on the velocity error |δv|/V (module docs): b·z·(1 + e_n) for the two damping
    /// jumps (at most half a step of each: η·V at touch-down, η·v_r ≤ η·e_n·V at lift-off, with
    /// η/m = 2bω₀) plus 2.5·z² for the second-order errors (two force kinks, ≤ z²/2 each, and
    /// Adams–Bashforth's truncation over a contact, (5π/12)·z² ≈ 1.3·z²). The same bound holds
    /// for semi-implicit Euler, whose velocities are those of Störmer–Verlet (second order).
    pub fn velocity_tolerance(&self) -> f64 {
        let (z, b, e) = (self.z, self.analytic.contact.b, self.spec.en);
        b * z * (1.0 + e) + 2.5 * z * z
    }

    /// Tolerance on the position error |δy|/(h₀ − R): the velocity tolerance carried through
    /// the flight after lift-off (at most t_stop − t_c), plus, for Euler, its half-step lead of
    /// the position, V·Δt/2 (in free fall exactly y_n = y(t_n) − g·t_n·Δt/2).
    pub fn position_tolerance(&self) -> f64 {
        let t_stop = self.samples.last().map_or(0.0, |s| s.time);
        let v = self.analytic.v_impact;
        let flight = (t_stop - self.analytic.t_c).max(0.0);
        let euler_lead = match self.spec.integrator {
            Integrator::Euler => 0.5 * v * self.dt,
            _ => 0.0,
        };
        (self.velocity_tolerance() * v * flight + euler_lead) / (H0 - RADIUS)
    }

    /// Largest departure in free fall (stage 1) from the integrator's exact discrete solution,
    /// normalised by h₀ − R and V: Adams–Bashforth is exact for a constant acceleration (its
    /// first step takes a_prev = a), semi-implicit Euler gives v_n = −g·t_n exactly and
    /// y_n = h₀ − g·t_n²/2 − g·t_n·Δt/2.
    pub fn free_fall_error(&self) -> (f64, f64) {
        let lead = if self.spec.integrator == Integrator::Euler { 0.5 * GRAVITY * self.dt } else { 0.0 };
        let v = self.analytic.v_impact;
        let stage1: Vec<Sample> = self.samples.iter().filter(|s| s.stage == 1).copied().collect();
        worst(&stage1, |s| {
            ((s.y_sim - (s.y_analytic - lead * s.time)).abs() / (H0 - RADIUS))
                .max((s.v_sim - s.v_analytic).abs() / v)
        })
    }
}

/// Largest value of `err` over the samples and the time it occurs (NaN errors win).
pub fn worst(samples: &[Sample], err: impl Fn(&Sample) -> f64) -> (f64, f64) {
    samples.iter().fold((0.0, f64::NAN), |(e0, t0), s| {
        let e = err(s);
        if e > e0 || e.is_nan() && !e0.is_nan() { (e, s.time) } else { (e0, t0) }
    })
}

/// Runs one (integrator, k_n, e_n).
pub fn run(spec: RunSpec) -> Result<RunResult, VerifyError> {
    let mut case = case()?;
    set_kn_en(&mut case, spec.kn, spec.en);
    case.config.integrator = spec.integrator;
    let interval = case.output.interval.unwrap_or(5e-3);
    let t_stop = case.config.t_stop;
    let mut sim = Simulation::new(case.config, case.particles)?;
    let i = sim.particles().index_of(1).unwrap_or(0);
    let mass = sim.particles().mass[i];
    let analytic = Analytic::new(spec.kn, spec.en, mass);
    let samples = sample_outputs(&mut sim, t_stop, interval, |sim, t| {
        let (stage, y_an, v_an) = analytic.at(t);
        let p = sim.particles();
        Sample {
            time: t,
            stage,
            y_analytic: y_an,
            y_sim: p.position[i].y,
            v_analytic: v_an,
            v_sim: p.velocity[i].y,
        }
    });
    Ok(RunResult {
        spec,
        dt: sim.dt(),
        steps: sim.total_steps(),
        z: analytic.contact.omega0 * sim.dt(),
        analytic,
        samples,
    })
}

/// Steps `sim` through its run and records `sample(sim, t)` at the first step at or after
/// every output time t_k = t₀ + k·interval, k = 0, …, ⌊(t_stop − t₀)/interval⌋, with `t` the
/// step's own simulated time. MFIX takes ceil((t_stop − t₀)/Δt) steps, so the last output time
/// is reached; one extra step is allowed for rounding.
pub fn sample_outputs<T>(
    sim: &mut Simulation,
    t_stop: f64,
    interval: f64,
    mut sample: impl FnMut(&Simulation, f64) -> T,
) -> Vec<T> {
    let t0 = sim.time();
    let n_out = ((t_stop - t0) / interval + 1e-9).floor().max(0.0) as usize;
    let slack = 1e-9 * sim.dt();
    let mut out = Vec::with_capacity(n_out + 1);
    let mut k = 0;
    loop {
        let t = sim.time();
        while k <= n_out && t >= t0 + k as f64 * interval - slack {
            out.push(sample(sim, t));
            k += 1;
        }
        if k > n_out || sim.step_index() > sim.total_steps() {
            break;
        }
        sim.step();
    }
    out
}

/// The runs, the checks and the wall time.
#[derive(Debug, Clone)]
pub struct Report {
    /// Every run, in [`runs`] order.
    pub runs: Vec<RunResult>,
    /// The checks.
    pub checks: Vec<Check>,
    /// Wall-clock seconds of the runs.
    pub wall_seconds: f64,
}

/// Runs the 38 runs (in parallel) and evaluates the checks; writes nothing.
pub fn evaluate() -> Result<Report, VerifyError> {
    let start = Instant::now();
    let runs: Vec<RunResult> = runs().into_par_iter().map(run).collect::<Result<_, _>>()?;
    let wall_seconds = start.elapsed().as_secs_f64();
    let checks = checks(&runs)?;
    Ok(Report { runs, checks, wall_seconds })
}

/// MFIX's DTSOLID of the case file as shipped (k_n = 1e4 N/m, e_n = 0.9) against MFIX's
/// printed value, and the time step of the 1-1 pair computed here from the closed form.
fn time_step_checks() -> Result<Vec<Check>, VerifyError> {
    let case = case()?;
    let pair = case.config.pair_params.first().copied().unwrap_or_default();
    let (kn, en) = (pair.kn.unwrap_or(f64::NAN), pair.en);
    let rule_ok = matches!(case.config.time_step, TimeStepRule::Mfix { factor } if factor == 50.0);
    let phase_mass = case.config.phases.first().map_or(f64::NAN, |p| p.mass());
    let sim = Simulation::new(case.config, case.particles)?;
    let dt = sim.dt();
    // TCOLL of the 1-1 pair: m_eff = m/2, damping η(k_n, m/2, e_n).
    let m_eff = 0.5 * phase_mass;
    let eta = damping_coefficient(kn, m_eff, en);
    let own = std::f64::consts::PI / (kn / m_eff - (eta / m_eff).powi(2) / 4.0).sqrt() / 50.0;
    Ok(vec![
        Check::assert(
            "time step equals MFIX's DTSOLID (k_n = 1e4 N/m, e_n = 0.9)",
            (dt - MFIX_DT_1E4_09).abs(),
            5e-11,
            format!(
                "dt = {dt:.10e} s vs MFIX 1.4670332e-3 s, printed to 8 digits: tolerance half a unit of the last digit; MFIX rule with factor 50: {rule_ok}"
            ),
        ),
        Check::assert(
            "time step is TCOLL/50 of the 1-1 pair with m_eff = m/2",
            ((dt - own) / own).abs(),
            1e-12,
            format!(
                "relative difference from π/√(k/m_eff − (η/m_eff)²/4)/50 = {own:.10e} s, m_eff = {m_eff:.7} kg (rounding only)"
            ),
        ),
        Check::assert(
            "phase mass equals MFIX's 10.890855 kg",
            (phase_mass - 10.890855).abs(),
            5e-7,
            format!("m = {phase_mass:.9} kg; printed to 8 digits"),
        ),
    ])
}

fn checks(runs: &[RunResult]) -> Result<Vec<Check>, VerifyError> {
    let mut out = time_step_checks()?;
    for integrator in INTEGRATORS {
        let of: Vec<&RunResult> = runs.iter().filter(|r| r.spec.integrator == integrator).collect();
        let name = integrator.name();
        // MFIX takes ceil(t_stop/Δt) steps: every output time must be reached.
        let complete = of.iter().filter(|r| r.samples.len() == 101).count();
        out.push(Check::assert(
            format!("{name}: every run reaches all 101 output times"),
            (of.len() - complete) as f64,
            0.0,
            format!("{complete} of {} runs have 101 outputs (t = 0 to 0.5 s every 5e-3 s)", of.len()),
        ));
        let (e, r) = of.iter().map(|r| (r.free_fall_error().0, r)).fold((0.0, None), |acc, (e, r)| {
            if acc.1.is_none() || e > acc.0 || e.is_nan() { (e, Some(r)) } else { acc }
        });
        out.push(Check::assert(
            format!("{name}: free fall equals the integrator's exact discrete solution"),
            e,
            1e-12,
            format!(
                "largest of |δy|/(h₀ − R), |δv|/V over the free-fall outputs of all runs{}; {}; tolerance: rounding",
                r.map(|r| format!(" (k_n = {:.1e} N/m, e_n = {})", r.spec.kn, r.spec.en)).unwrap_or_default(),
                if integrator == Integrator::Euler {
                    "semi-implicit Euler: v_n = −g·t_n, y_n = h₀ − g·t_n²/2 − g·t_n·Δt/2"
                } else {
                    "Adams–Bashforth is exact for a constant acceleration (first step a_prev = a)"
                }
            ),
        ));
        for (what, err, tol, unit, tol_text) in [
            (
                "velocity",
                RunResult::velocity_error as fn(&RunResult) -> (f64, f64),
                RunResult::velocity_tolerance as fn(&RunResult) -> f64,
                "|v_sim − v_an|/V",
                "b·z·(1 + e_n) + 2.5·z², z = ω₀Δt: at most half a step of each damping-force jump (touch-down η·V, lift-off η·v_r; η/m = 2bω₀), plus the second-order errors (two kinks of the elastic force, ≤ z²/2 each; truncation over a contact, (5π/12)·z²)",
            ),
            (
                "position",
                RunResult::position_error,
                RunResult::position_tolerance,
                "|y_sim − y_an|/(h₀ − R)",
                if integrator == Integrator::Euler {
                    "the velocity tolerance × V × (t_stop − t_c)/(h₀ − R), a lift-off error carried through the flight, plus Euler's half-step lead of the position V·Δt/2/(h₀ − R)"
                } else {
                    "the velocity tolerance × V × (t_stop − t_c)/(h₀ − R): a lift-off error carried through the flight"
                },
            ),
        ] {
            // Each run has its own tolerance: the run with the largest error/tolerance decides.
            let worst_run = of.iter().max_by(|a, b| {
                let ra = err(a).0 / tol(a);
                let rb = err(b).0 / tol(b);
                ra.partial_cmp(&rb).unwrap_or(std::cmp::Ordering::Greater)
            });
            match worst_run {
                Some(r) => {
                    let (e, t) = err(r);
                    out.push(Check::assert(
                        format!("{name}: {what} vs the three-stage closed form, all 19 runs"),
                        e,
                        tol(r),
                        format!(
                            "{unit} at the outputs; worst relative to its tolerance: k_n = {:.1e} N/m, e_n = {}, at t = {t:.4} s (z = ω₀Δt = {:.4}, b = {:.4}); tolerance {tol_text}",
                            r.spec.kn, r.spec.en, r.z, r.analytic.contact.b
                        ),
                    ));
                }
                None => out.push(Check::assert(
                    format!("{name}: {what} vs the three-stage closed form"),
                    f64::NAN,
                    0.0,
                    "no runs",
                )),
            }
        }
        // Stage by stage, for the report (MFIX reports percent of the value).
        for stage in 1..=3u8 {
            let (e, r, t) = of
                .iter()
                .flat_map(|r| r.samples.iter().filter(move |s| s.stage == stage).map(move |s| (r, s)))
                .map(|(r, s)| ((s.v_sim - s.v_analytic).abs() / r.analytic.v_impact, r, s.time))
                .fold((0.0, None, f64::NAN), |acc, (e, r, t)| if e > acc.0 { (e, Some(r), t) } else { acc });
            let detail = match r {
                Some(r) => format!(
                    "largest |v_sim − v_an|/V in stage {stage} ({}): k_n = {:.1e} N/m, e_n = {} at t = {t:.4} s",
                    ["free fall", "contact", "rebound"][stage as usize - 1],
                    r.spec.kn,
                    r.spec.en
                ),
                None => format!("no output in stage {stage}"),
            };
            out.push(Check::report(format!("{name}: velocity error in stage {stage}"), e, detail));
        }
    }
    Ok(out)
}

/// `dem01.csv`: `integrator,kn,en,time,stage,y_analytic,y_sim,v_analytic,v_sim`.
pub fn csv(runs: &[RunResult]) -> String {
    let mut s = String::from("integrator,kn,en,time,stage,y_analytic,y_sim,v_analytic,v_sim\n");
    for r in runs {
        for p in &r.samples {
            let _ = writeln!(
                s,
                "{},{},{},{:.9e},{},{:.9e},{:.9e},{:.9e},{:.9e}",
                r.spec.integrator.name(),
                r.spec.kn,
                r.spec.en,
                p.time,
                p.stage,
                p.y_analytic,
                p.y_sim,
                p.v_analytic,
                p.v_sim
            );
        }
    }
    s
}

fn figure(runs: &[RunResult], integrator: Integrator) -> Figure {
    let shown: Vec<&RunResult> =
        runs.iter().filter(|r| r.spec.integrator == integrator && r.spec.kn == 1.0e4).collect();
    let mut y_panel = Panel::new("Height of the centre, k_n = 1e4 N/m", "time (s)", "y (m)");
    let mut v_panel = Panel::new("Vertical velocity, k_n = 1e4 N/m", "time (s)", "v (m/s)");
    let mut e_panel =
        Panel::new("Error, k_n = 1e4 N/m: |Δv|/V solid, |Δy|/(h₀−R) dashed", "time (s)", "normalised error");
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle, MarkerShape::Square, MarkerShape::Cross];
    for (k, r) in shown.iter().enumerate() {
        let color = Color::palette(k);
        let shape = shapes[k % shapes.len()];
        let fine: Vec<f64> = (0..=1000).map(|i| i as f64 * 5e-4).collect();
        let label = format!("e_n = {}", r.spec.en);
        y_panel.series.push(Series::line(
            "",
            fine.iter().map(|&t| (t, r.analytic.at(t).1)).collect(),
            LineStyle::Thin,
            Color::BLACK,
        ));
        y_panel.series.push(Series::markers(
            label.clone(),
            r.samples.iter().step_by(2).map(|s| (s.time, s.y_sim)).collect(),
            shape,
            color,
        ));
        v_panel.series.push(Series::line(
            "",
            fine.iter().map(|&t| (t, r.analytic.at(t).2)).collect(),
            LineStyle::Thin,
            Color::BLACK,
        ));
        v_panel.series.push(Series::markers(
            label.clone(),
            r.samples.iter().step_by(2).map(|s| (s.time, s.v_sim)).collect(),
            shape,
            color,
        ));
        let v = r.analytic.v_impact;
        e_panel.series.push(Series::line(
            label,
            r.samples.iter().map(|s| (s.time, (s.v_sim - s.v_analytic).abs() / v)).collect(),
            LineStyle::Solid,
            color,
        ));
        e_panel.series.push(Series::line(
            "",
            r.samples.iter().map(|s| (s.time, (s.y_sim - s.y_analytic).abs() / (H0 - RADIUS))).collect(),
            LineStyle::Dashed,
            color,
        ));
    }
    y_panel.series.push(Series::line("closed form", Vec::new(), LineStyle::Thin, Color::BLACK));
    v_panel.series.push(Series::line("closed form", Vec::new(), LineStyle::Thin, Color::BLACK));
    // Every run: its worst errors over their tolerances.
    let all: Vec<&RunResult> = runs.iter().filter(|r| r.spec.integrator == integrator).collect();
    let mut ratio_panel = Panel::new(
        "All 19 runs: largest error / tolerance",
        "k_n (1e4 N/m)",
        "error / tolerance (≤ 1 passes)",
    );
    ratio_panel.series.push(Series::markers(
        "velocity",
        all.iter().map(|r| (r.spec.kn / 1e4, r.velocity_error().0 / r.velocity_tolerance())).collect(),
        MarkerShape::Circle,
        Color::BLUE,
    ));
    ratio_panel.series.push(Series::markers(
        "position",
        all.iter().map(|r| (r.spec.kn / 1e4, r.position_error().0 / r.position_tolerance())).collect(),
        MarkerShape::Triangle,
        Color::ORANGE,
    ));
    ratio_panel.series.push(Series::line(
        "tolerance",
        vec![(0.0, 1.0), (11.0, 1.0)],
        LineStyle::Thin,
        Color::RED,
    ));
    ratio_panel.x_range = Some((0.0, 11.0));
    ratio_panel.y_range = Some((0.0, 1.2));
    let dt = shown.first().map_or(f64::NAN, |r| r.dt);
    Figure {
        title: format!(
            "DEM01 falling ball, {} (MFIX's Δt = TCOLL/50: {dt:.4e} s at k_n = 1e4 N/m)",
            if integrator == Integrator::Euler { "EULER" } else { "ADAMS_BASHFORTH" }
        ),
        panels: vec![y_panel, v_panel, e_panel, ratio_panel],
        note: Some(
            "Markers: grainflow at the first step at or after every other output time (0.01 s; the CSV has every 5e-3 s); thin black lines: the three-stage closed form (free fall, damped contact, rebound). Errors at every output."
                .into(),
        ),
    }
}

/// The suite entry: runs the case and writes `DIR/dem01/`: dem01.csv, one figure per integrator
/// (PNG + SVG), summary.md.
pub fn run_case(dir: &Path, _options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let start = Instant::now();
    let report = evaluate()?;
    let out = case_dir(dir, "dem01")?;
    let mut files = Vec::new();
    write_file(out.join("dem01.csv"), &csv(&report.runs), &mut files)?;
    let drawn: Vec<Result<[PathBuf; 2], VerifyError>> = INTEGRATORS
        .into_par_iter()
        .map(|integrator| {
            let png = out.join(format!("dem01_{}.png", integrator.name()));
            let svg = out.join(format!("dem01_{}.svg", integrator.name()));
            plot::write_figure(&figure(&report.runs, integrator), &png, &svg)?;
            Ok([png, svg])
        })
        .collect();
    let mut figures = Vec::new();
    for d in drawn {
        let [png, svg] = d?;
        figures.push(png.clone());
        files.extend([png, svg]);
    }
    let title = "freely falling particle with wall collision (MFIX DEM01)";
    write_file(out.join("summary.md"), &summary_markdown(title, &report.checks), &mut files)?;
    let z = report.runs.first().map_or(f64::NAN, |r| r.z);
    Ok(CaseOutcome {
        name: "dem01",
        title: title.into(),
        checks: report.checks,
        files,
        figures,
        notes: vec![
            "A 0.2 m ball falls 0.4 m onto the floor, bounces once (linear spring–dashpot, k_n = 1e4 to 1e5 N/m, e_n = 0.6 to 1) and flies until 0.5 s; 19 runs per integrator with MFIX's time step TCOLL/50. The closed form is the model's own exact solution (free fall, damped oscillation under gravity until the centre is back at y = R, ballistic rebound), so every difference is time stepping. Outputs are the first step at or after each 5e-3 s, compared with the closed form at the step's own time.".into(),
            format!(
                "With MFIX's rule ω₀Δt = {z:.4} for every k_n (the step is set by the 1-1 pair with m_eff = m/2, the wall contact uses m). ADAMS_BASHFORTH integrates the free fall exactly; EULER (semi-implicit: v first, then x with the new v) gets the free-fall velocity exactly but its positions lead by half a step (V·Δt/2 at impact, its largest position error). Both are otherwise second order except where the damping force η·v jumps (touch-down and lift-off), which no fixed step resolves: that O(b·ω₀Δt) term, b the damping ratio, dominates their velocity error for e_n < 1 and vanishes for e_n = 1. A velocity error at lift-off grows linearly into a position error during the flight."
            ),
        ],
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form satisfies its ODE and starts at (R, −V).
    #[test]
    fn floor_contact_solves_its_ode() {
        let c = FloorContact::new(1e4, 10.890855, 0.7, GRAVITY);
        let v = 2.8;
        let (y0, v0) = c.state(v, 0.0);
        assert!(y0.abs() < 1e-15 && (v0 + v).abs() < 1e-12);
        let h = 1e-5;
        for k in 1..50 {
            let t = k as f64 * 2e-3;
            let (ym, _) = c.state(v, t - h);
            let (y, vy) = c.state(v, t);
            let (yp, _) = c.state(v, t + h);
            let vfd = (yp - ym) / (2.0 * h);
            let afd = (yp - 2.0 * y + ym) / (h * h);
            let rhs = -c.g - c.omega0 * c.omega0 * y - 2.0 * c.b * c.omega0 * vy;
            assert!((vfd - vy).abs() < 1e-6, "v at {t}: {vfd} vs {vy}");
            assert!((afd - rhs).abs() < 1e-3 * c.omega0 * c.omega0 * 0.03, "a at {t}: {afd} vs {rhs}");
        }
    }

    /// Without gravity the rebound speed is exactly e_n·V after half a damped period.
    #[test]
    fn lift_off_without_gravity_gives_restitution() {
        for e in [1.0, 0.9, 0.6, 0.3] {
            let c = FloorContact { g: 0.0, ..FloorContact::new(5e4, 10.890855, e, GRAVITY) };
            let (tau, v) = c.lift_off(2.0).expect("lifts off");
            assert!((v - 2.0 * e).abs() < 1e-9, "e = {e}: {v}");
            assert!((tau - std::f64::consts::PI / c.omega_d()).abs() < 1e-9);
        }
    }

    /// MFIX's time step of the shipped case, and the grid of 38 runs.
    #[test]
    fn time_step_and_runs() {
        let checks = time_step_checks().expect("case");
        assert!(checks.iter().all(Check::passed), "{checks:?}");
        assert_eq!(runs().len(), 38);
    }
}
