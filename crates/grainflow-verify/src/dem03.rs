//! MFIX verification case DEM03: two stacked, compressed particles between walls (linear
//! spring–dashpot). Source: MFIX's verification manual, case DEM03 (MFIX's
//! `tests/dem/DEM03`); set-up in docs/verification.md.
//!
//! In a box 1 × 0.0018 × 1 m, a 1 mm sphere of density 2e4 kg/m³ sits on the floor (centre
//! y = 0.45 mm) under a 1 mm sphere of density 1e4 kg/m³ (y = 1.35 mm) that touches the ceiling
//! y = H = 1.8 mm. Each overlaps its wall by 0.05 mm and the other sphere by 0.1 mm; released at
//! rest, they oscillate on three contacts that never open. k_n = k_n,w = 1000 N/m,
//! KT_FAC = DES_ETAT_FAC = 1, ADAMS_BASHFORTH, MFIX's time step, t_stop = 1e-3 s, outputs every
//! 1e-5 s, e_n ∈ {1.0, 0.9, 0.8, 0.7, 0.6, 0.5} for all pairs and walls (6 runs).
//!
//! ## Reference
//! With all three contacts closed the motion is linear and one-dimensional (δ₁₂ = 2R − (y₂ − y₁)):
//!   y₁″ = −g − (k_w/m₁)(y₁ − R) − (η_w1/m₁)y₁′ − (k/m₁)δ₁₂ − (η₁₂/m₁)(y₁′ − y₂′)
//!   y₂″ = −g − (k_w/m₂)(R − (H − y₂)) − (η_w2/m₂)y₂′ + (k/m₂)δ₁₂ + (η₁₂/m₂)(y₁′ − y₂′)
//! with η₁₂ from m_eff = m₁m₂/(m₁ + m₂) and η_wi from m_i (MFIX's damping formula,
//! [`grainflow::contact::damping_coefficient`]). It is integrated here by classical RK4
//! ([`rk4_step`], tested below: fourth order, exact to O(h⁴) for the harmonic oscillator) with
//! at most [`REFERENCE_STEP`] = 1e-7 s, straight to each simulated output time; its error,
//! (ω_max·h)⁴·ω_max·t/120 ≈ 4e-12 relative, is negligible.
//!
//! ## Accuracy to expect
//! The two modes have ω² = (3 ± √3)/2 · k/m₂ (k = k_w, m₁ = 2m₂): ω_max ≈ 2.13e4 rad/s. MFIX's
//! step, TCOLL/50 of the lightest pair (2-2, m_eff = m₂/2), gives z = ω_max·Δt ≈ 0.068. The
//! forces are smooth (no contact opens or closes), so Adams–Bashforth is second order here: its
//! phase error grows as (5/12)·z²·ω_max·t, its start-up (first step a_prev = a) adds about z²/2.
//! The tolerance on the error relative to the largest excursion of the reference is
//! (5/12)·z²·ω_max·t_stop + z² (all of the excursion taken in the fast mode, no credit for
//! damping: a bound, loose for the damped runs). The sharp check is the step-halving study: at
//! Δt/2 and Δt/4 the error must fall by 4 each time (observed order 2 ± 0.1).

use crate::check::Check;
use crate::error::VerifyError;
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions};
use grainflow::contact::damping_coefficient;
use grainflow::{Simulation, TimeStepRule};
use grainflow_case::Case;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The shipped case file (e_n = 1).
pub const CASE: &str = include_str!("../cases/dem03/dem03.toml");
/// Restitution coefficients of the case (all pairs and walls).
pub const RESTITUTIONS: [f64; 6] = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5];
/// Largest RK4 step of the reference, s.
pub const REFERENCE_STEP: f64 = 1e-7;

/// The shipped case, parsed.
pub fn case() -> Result<Case, VerifyError> {
    crate::report::shipped_case("dem03/dem03.toml", CASE, &[])
}

/// One classical Runge–Kutta (RK4) step of y′ = f(t, y) from t to t + h.
pub fn rk4_step<const N: usize>(
    f: &impl Fn(f64, &[f64; N]) -> [f64; N],
    t: f64,
    y: &[f64; N],
    h: f64,
) -> [f64; N] {
    let add = |a: &[f64; N], b: &[f64; N], s: f64| -> [f64; N] { std::array::from_fn(|i| a[i] + s * b[i]) };
    let k1 = f(t, y);
    let k2 = f(t + 0.5 * h, &add(y, &k1, 0.5 * h));
    let k3 = f(t + 0.5 * h, &add(y, &k2, 0.5 * h));
    let k4 = f(t + h, &add(y, &k3, h));
    std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// Integrates y′ = f(t, y) from (t0, y0) to t1 with RK4 in equal steps of at most `h_max`.
pub fn rk4_integrate<const N: usize>(
    f: &impl Fn(f64, &[f64; N]) -> [f64; N],
    t0: f64,
    y0: [f64; N],
    t1: f64,
    h_max: f64,
) -> [f64; N] {
    let span = t1 - t0;
    let valid = span > 0.0 && h_max > 0.0;
    if !valid {
        return y0;
    }
    let n = (span / h_max).ceil().max(1.0) as usize;
    let h = span / n as f64;
    let mut y = y0;
    for k in 0..n {
        y = rk4_step(f, t0 + k as f64 * h, &y, h);
    }
    y
}

/// The 1-D two-particle system of the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StackedPair {
    /// Masses of the bottom and the top particle, kg.
    pub m1: f64,
    /// Mass of the top particle, kg.
    pub m2: f64,
    /// Radius of both, m.
    pub radius: f64,
    /// Height of the box (ceiling), m.
    pub height: f64,
    /// Particle–particle stiffness k, N/m.
    pub k: f64,
    /// Particle–wall stiffness k_w, N/m.
    pub k_w: f64,
    /// Pair damping η₁₂, kg/s.
    pub eta_12: f64,
    /// Wall damping of particle 1 and 2, kg/s.
    pub eta_w1: f64,
    /// Wall damping of particle 2, kg/s.
    pub eta_w2: f64,
    /// Gravity, m/s² (positive, along −y).
    pub g: f64,
}

impl StackedPair {
    /// y″ of both particles for the state [y₁, v₁, y₂, v₂].
    pub fn derivative(&self, s: &[f64; 4]) -> [f64; 4] {
        let [y1, v1, y2, v2] = *s;
        let r = self.radius;
        let d12 = 2.0 * r - (y2 - y1);
        let pair = self.k * d12 + self.eta_12 * (v1 - v2);
        let a1 = -self.g - (self.k_w * (y1 - r) + self.eta_w1 * v1) / self.m1 - pair / self.m1;
        let a2 =
            -self.g - (self.k_w * (r - (self.height - y2)) + self.eta_w2 * v2) / self.m2 + pair / self.m2;
        [v1, a1, v2, a2]
    }

    /// The largest angular frequency of the undamped system, rad/s.
    pub fn omega_max(&self) -> f64 {
        // M⁻¹K = [[(k_w + k)/m₁, −k/m₁], [−k/m₂, (k_w + k)/m₂]]: largest eigenvalue.
        let (a, b, c, d) = (
            (self.k_w + self.k) / self.m1,
            -self.k / self.m1,
            -self.k / self.m2,
            (self.k_w + self.k) / self.m2,
        );
        let tr = a + d;
        let det = a * d - b * c;
        (0.5 * (tr + (tr * tr - 4.0 * det).max(0.0).sqrt())).sqrt()
    }
}

/// One output of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Simulated time of the step, s.
    pub time: f64,
    /// Reference y₁, m.
    pub y1_ref: f64,
    /// Simulated y₁, m.
    pub y1_sim: f64,
    /// Reference y₂, m.
    pub y2_ref: f64,
    /// Simulated y₂, m.
    pub y2_sim: f64,
}

/// One run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// e_n of every contact.
    pub en: f64,
    /// Δt, s.
    pub dt: f64,
    /// Steps.
    pub steps: u64,
    /// TCOLL/50 over the phase pairs computed here from MFIX's formula, s.
    pub mfix_dt: f64,
    /// The reference system.
    pub system: StackedPair,
    /// The outputs.
    pub samples: Vec<Sample>,
    /// Steps at which one of the three contacts was open (the reference assumes none).
    pub open_contact_steps: u64,
    /// Smallest overlap of the three contacts over the run, m.
    pub min_overlap: f64,
}

impl RunResult {
    /// Largest excursion of the reference from its start, for y₁ and y₂, m.
    pub fn excursions(&self) -> (f64, f64) {
        let first = self.samples.first().copied();
        self.samples.iter().fold((0.0f64, 0.0f64), |(a, b), s| match first {
            Some(f) => (a.max((s.y1_ref - f.y1_ref).abs()), b.max((s.y2_ref - f.y2_ref).abs())),
            None => (a, b),
        })
    }

    /// Largest |y_sim − y_ref| / excursion over both particles and all outputs, with its time.
    pub fn error(&self) -> (f64, f64) {
        let (a1, a2) = self.excursions();
        self.samples.iter().fold((0.0, f64::NAN), |(e0, t0), s| {
            let e = ((s.y1_sim - s.y1_ref).abs() / a1).max((s.y2_sim - s.y2_ref).abs() / a2);
            if e > e0 || e.is_nan() { (e, s.time) } else { (e0, t0) }
        })
    }

    /// Largest |y_sim − y_ref| of both particles over the outputs, m.
    pub fn max_abs_error(&self) -> f64 {
        self.samples
            .iter()
            .map(|s| (s.y1_sim - s.y1_ref).abs().max((s.y2_sim - s.y2_ref).abs()))
            .fold(0.0, f64::max)
    }

    /// (5/12)·z²·ω_max·t_stop + z², z = ω_max·Δt (module docs).
    pub fn tolerance(&self) -> f64 {
        let w = self.system.omega_max();
        let z = w * self.dt;
        let t_stop = self.samples.last().map_or(0.0, |s| s.time);
        5.0 / 12.0 * z * z * w * t_stop + z * z
    }
}

/// The shipped case with e_n set for every pair and wall.
pub fn case_with(en: f64) -> Result<Case, VerifyError> {
    let mut case = case()?;
    for p in case.config.pair_params.iter_mut().chain(case.config.wall_params.iter_mut()) {
        p.en = en;
    }
    Ok(case)
}

/// Runs one e_n with MFIX's time step.
pub fn run(en: f64) -> Result<RunResult, VerifyError> {
    run_with_dt(en, None)
}

/// Runs one e_n, with MFIX's time step or an explicit one.
pub fn run_with_dt(en: f64, dt: Option<f64>) -> Result<RunResult, VerifyError> {
    let mut case = case_with(en)?;
    let mfix_rule = case.config.time_step;
    if let Some(dt) = dt {
        case.config.time_step = TimeStepRule::Fixed(dt);
    }
    let interval = case.output.interval.unwrap_or(1e-5);
    let t_stop = case.config.t_stop;
    let g = -case.config.gravity.y;
    let height = case.config.walls.iter().map(|w| w.point.y).fold(f64::NAN, f64::max);
    let factor = match mfix_rule {
        TimeStepRule::Mfix { factor } => factor,
        TimeStepRule::Fixed(_) => f64::NAN,
    };
    let phases = case.config.phases.clone();
    let kn = case.config.pair_params.first().and_then(|p| p.kn).unwrap_or(f64::NAN);
    let kw = case.config.wall_params.first().and_then(|p| p.kn).unwrap_or(f64::NAN);
    let mut sim = Simulation::new(case.config, case.particles)?;
    let p = sim.particles();
    let (i1, i2) = (p.index_of(1).unwrap_or(0), p.index_of(2).unwrap_or(1));
    let (m1, m2, radius) = (p.mass[i1], p.mass[i2], p.radius[i1]);
    let m12 = m1 * m2 / (m1 + m2);
    let system = StackedPair {
        m1,
        m2,
        radius,
        height,
        k: kn,
        k_w: kw,
        eta_12: damping_coefficient(kn, m12, en),
        eta_w1: damping_coefficient(kw, m1, en),
        eta_w2: damping_coefficient(kw, m2, en),
        g,
    };
    // MFIX's TCOLL over the phase pairs 1-1, 1-2, 2-2 (from the phase masses).
    let mut tcoll = f64::INFINITY;
    for a in 0..phases.len() {
        for b in a..phases.len() {
            let (ma, mb) = (phases[a].mass(), phases[b].mass());
            let me = ma * mb / (ma + mb);
            let eta = damping_coefficient(kn, me, en);
            tcoll = tcoll.min(std::f64::consts::PI / (kn / me - (eta / me).powi(2) / 4.0).sqrt());
        }
    }
    let p = sim.particles();
    let start = [p.position[i1].y, p.velocity[i1].y, p.position[i2].y, p.velocity[i2].y];
    let f = |_t: f64, s: &[f64; 4]| system.derivative(s);
    let mut reference = (sim.time(), start);
    let mut open_contact_steps = 0;
    let mut min_overlap = f64::INFINITY;
    let samples = crate::dem01::sample_outputs(&mut sim, t_stop, interval, |sim, t| {
        reference = (t, rk4_integrate(&f, reference.0, reference.1, t, REFERENCE_STEP));
        let p = sim.particles();
        Sample {
            time: t,
            y1_ref: reference.1[0],
            y1_sim: p.position[i1].y,
            y2_ref: reference.1[2],
            y2_sim: p.position[i2].y,
        }
    });
    // The three overlaps along the whole run, from a second pass (sampling sees outputs only).
    let mut again_case = case_with(en)?;
    again_case.config.time_step = case_time_step(mfix_rule, dt);
    let mut again = Simulation::new(again_case.config, again_case.particles)?;
    while !again.finished() {
        again.step();
        let p = again.particles();
        let (y1, y2) = (p.position[i1].y, p.position[i2].y);
        let overlaps = [radius - y1, 2.0 * radius - (y2 - y1), radius - (height - y2)];
        let least = overlaps.iter().copied().fold(f64::INFINITY, f64::min);
        min_overlap = min_overlap.min(least);
        if least.is_nan() || least < 0.0 {
            open_contact_steps += 1;
        }
    }
    Ok(RunResult {
        en,
        dt: sim.dt(),
        steps: sim.total_steps(),
        mfix_dt: tcoll / factor,
        system,
        samples,
        open_contact_steps,
        min_overlap,
    })
}

fn case_time_step(mfix_rule: TimeStepRule, dt: Option<f64>) -> TimeStepRule {
    dt.map_or(mfix_rule, TimeStepRule::Fixed)
}

/// The largest error of one e_n at MFIX's Δt, Δt/2 and Δt/4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Convergence {
    /// e_n.
    pub en: f64,
    /// MFIX's Δt, s.
    pub dt: f64,
    /// Largest |y_sim − y_ref| at Δt, Δt/2, Δt/4, m.
    pub errors: [f64; 3],
}

impl Convergence {
    /// Observed orders log2(E(Δt)/E(Δt/2)) and log2(E(Δt/2)/E(Δt/4)).
    pub fn orders(&self) -> [f64; 2] {
        [(self.errors[0] / self.errors[1]).log2(), (self.errors[1] / self.errors[2]).log2()]
    }
}

/// The runs, the checks and the wall time.
#[derive(Debug, Clone)]
pub struct Report {
    /// Every run, in [`RESTITUTIONS`] order.
    pub runs: Vec<RunResult>,
    /// Step-halving study of every e_n.
    pub convergence: Vec<Convergence>,
    /// The checks.
    pub checks: Vec<Check>,
    /// Wall-clock seconds of the runs.
    pub wall_seconds: f64,
}

/// Runs the 6 runs and the step-halving study (Δt/2, Δt/4; in parallel) and evaluates the
/// checks; writes nothing.
pub fn evaluate() -> Result<Report, VerifyError> {
    let start = Instant::now();
    let runs: Vec<RunResult> = RESTITUTIONS.par_iter().map(|&en| run(en)).collect::<Result<_, _>>()?;
    let halved: Vec<(f64, f64, f64)> = runs
        .iter()
        .flat_map(|r| [2.0, 4.0].map(|d| (r.en, r.dt, d)))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(en, dt, d)| run_with_dt(en, Some(dt / d)).map(|r| (en, d, r.max_abs_error())))
        .collect::<Result<_, VerifyError>>()?;
    let convergence = runs
        .iter()
        .map(|r| {
            let at = |d: f64| halved.iter().find(|h| h.0 == r.en && h.1 == d).map_or(f64::NAN, |h| h.2);
            Convergence { en: r.en, dt: r.dt, errors: [r.max_abs_error(), at(2.0), at(4.0)] }
        })
        .collect::<Vec<_>>();
    let wall_seconds = start.elapsed().as_secs_f64();
    let checks = checks(&runs, &convergence);
    Ok(Report { runs, convergence, checks, wall_seconds })
}

fn checks(runs: &[RunResult], convergence: &[Convergence]) -> Vec<Check> {
    let mut out = Vec::new();
    let worst_dt = runs.iter().map(|r| (((r.dt - r.mfix_dt) / r.mfix_dt).abs(), r)).fold(
        (f64::NAN, None),
        |acc: (f64, Option<&RunResult>), (e, r)| {
            if acc.1.is_none() || e > acc.0 || e.is_nan() { (e, Some(r)) } else { acc }
        },
    );
    out.push(Check::assert(
        "time step is MFIX's TCOLL/50 over the phase pairs 1-1, 1-2, 2-2",
        worst_dt.0,
        1e-12,
        match worst_dt.1 {
            Some(r) => format!(
                "relative difference, all runs; e.g. e_n = {}: dt = {:.7e} s, limited by the light 2-2 pair (m_eff = m₂/2); tolerance: rounding",
                r.en, r.dt
            ),
            None => "no runs".into(),
        },
    ));
    let open: u64 = runs.iter().map(|r| r.open_contact_steps).sum();
    let least = runs.iter().map(|r| r.min_overlap).fold(f64::INFINITY, f64::min);
    out.push(Check::assert(
        "the three contacts stay closed in every run (as the reference assumes)",
        open as f64,
        0.0,
        format!("steps with an open contact, all runs; smallest overlap {:.3e} m", least),
    ));
    for r in runs {
        let (e, t) = r.error();
        let z = r.system.omega_max() * r.dt;
        out.push(Check::assert(
            format!("e_n = {}: y₁ and y₂ vs the RK4 reference", r.en),
            e,
            r.tolerance(),
            format!(
                "largest |y_sim − y_ref| / (largest excursion of the reference), both particles, at t = {t:.3e} s; tolerance (5/12)z²·ω_max·t_stop + z², z = ω_maxΔt = {z:.4}: Adams–Bashforth's phase error and start-up (smooth forces, second order), taking the whole excursion in the fast mode and no credit for damping"
            ),
        ));
    }
    // Step halving: smooth forces, so the error must fall as Δt².
    let worst = convergence
        .iter()
        .flat_map(|c| c.orders().into_iter().enumerate().map(move |(k, p)| (c, k, p)))
        .fold(None::<(&Convergence, usize, f64)>, |acc, (c, k, p)| match acc {
            Some((_, _, q)) if (p - 2.0).abs() <= (q - 2.0).abs() => acc,
            _ => Some((c, k, p)),
        });
    out.push(match worst {
        Some((c, k, p)) => Check::assert(
            "Adams–Bashforth converges at second order to the reference (Δt, Δt/2, Δt/4)",
            (p - 2.0).abs(),
            0.1,
            format!(
                "|log2(E(h)/E(h/2)) − 2| for h = Δt, Δt/2 and every e_n, E the largest |y_sim − y_ref|; worst at e_n = {}, h = Δt/{}: order {p:.4} (E = {:.3e}, {:.3e}, {:.3e} m). Tolerance 0.1: the next term of the error is O(ω_maxΔt) ≈ 0.07 relative to the leading one, which moves a measured order by ≤ log2(1.07) ≈ 0.1. The reference (RK4, 1e-7 s) is accurate far below the smallest E",
                c.en,
                1 << k,
                c.errors[0],
                c.errors[1],
                c.errors[2]
            ),
        ),
        None => Check::assert(
            "Adams–Bashforth converges at second order to the reference (Δt, Δt/2, Δt/4)",
            f64::NAN,
            0.1,
            "no runs",
        ),
    });
    out
}

/// `dem03.csv`: `en,time,y1_ref,y1_sim,y2_ref,y2_sim`.
pub fn csv(runs: &[RunResult]) -> String {
    let mut s = String::from("en,time,y1_ref,y1_sim,y2_ref,y2_sim\n");
    for r in runs {
        for p in &r.samples {
            let _ = writeln!(
                s,
                "{},{:.9e},{:.12e},{:.12e},{:.12e},{:.12e}",
                r.en, p.time, p.y1_ref, p.y1_sim, p.y2_ref, p.y2_sim
            );
        }
    }
    s
}

fn figure(runs: &[RunResult], convergence: &[Convergence]) -> Figure {
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle, MarkerShape::Square, MarkerShape::Cross];
    let us = 1e6;
    let ms = 1e3;
    let mut panels = Vec::new();
    for (which, name) in [(0, "bottom particle y₁"), (1, "top particle y₂")] {
        let mut p =
            Panel::new(name.to_string(), "time (ms)", format!("y{} − y{}(0) (µm)", which + 1, which + 1));
        for (j, r) in runs.iter().enumerate().filter(|(j, _)| j % 2 == 0) {
            let color = Color::palette(j);
            let get = |s: &Sample| if which == 0 { (s.y1_ref, s.y1_sim) } else { (s.y2_ref, s.y2_sim) };
            let y0 = r.samples.first().map_or(0.0, |s| get(s).0);
            p.series.push(Series::line(
                "",
                r.samples.iter().map(|s| (s.time * ms, (get(s).0 - y0) * us)).collect(),
                LineStyle::Thin,
                color,
            ));
            p.series.push(Series::markers(
                format!("e_n = {}", r.en),
                r.samples.iter().step_by(2).map(|s| (s.time * ms, (get(s).1 - y0) * us)).collect(),
                shapes[(j / 2) % shapes.len()],
                color,
            ));
        }
        p.series.push(Series::line("RK4 reference (thin)", Vec::new(), LineStyle::Thin, Color::BLACK));
        panels.push(p);
    }
    let mut p = Panel::new(
        "Error / largest excursion (solid y₁, dashed y₂)",
        "time (ms)",
        "|y_sim − y_ref| / excursion",
    );
    for (j, r) in runs.iter().enumerate() {
        let (a1, a2) = r.excursions();
        p.series.push(Series::line(
            format!("e_n = {}", r.en),
            r.samples.iter().map(|s| (s.time * ms, (s.y1_sim - s.y1_ref).abs() / a1)).collect(),
            LineStyle::Solid,
            Color::palette(j),
        ));
        p.series.push(Series::line(
            "",
            r.samples.iter().map(|s| (s.time * ms, (s.y2_sim - s.y2_ref).abs() / a2)).collect(),
            LineStyle::Dashed,
            Color::palette(j),
        ));
    }
    panels.push(p);
    // Step halving: log–log, with a slope-2 guide through the e_n = 1 point at Δt.
    let mut p =
        Panel::new("Step halving: largest error vs Δt", "log10(Δt / s)", "log10(max |y_sim − y_ref| / m)");
    for (j, c) in convergence.iter().enumerate() {
        p.series.push(Series::markers(
            format!("e_n = {}", c.en),
            c.errors.iter().enumerate().map(|(k, e)| ((c.dt / (1 << k) as f64).log10(), e.log10())).collect(),
            shapes[j % shapes.len()],
            Color::palette(j),
        ));
    }
    if let Some(c) = convergence.first() {
        let (x0, y0) = (c.dt.log10(), c.errors[0].log10());
        p.series.push(Series::line(
            "slope 2 (second order)",
            vec![(x0, y0), (x0 - 4f64.log10(), y0 - 2.0 * 4f64.log10())],
            LineStyle::Thin,
            Color::BLACK,
        ));
    }
    panels.push(p);
    let dt = runs.first().map_or(f64::NAN, |r| r.dt);
    Figure {
        title: format!("DEM03 two stacked, compressed particles: ADAMS_BASHFORTH, MFIX's Δt ≈ {dt:.3e} s"),
        panels,
        note: Some(
            "Markers: grainflow (every other output, e_n = 1, 0.8, 0.6); thin lines: RK4 integration of the 1-D three-contact system at the same times. Error and step-halving panels: all six e_n."
                .into(),
        ),
    }
}

/// The suite entry: runs the case and writes `DIR/dem03/`: dem03.csv, the figure, summary.md.
pub fn run_case(dir: &Path, _options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let start = Instant::now();
    let report = evaluate()?;
    let title = "two stacked, compressed particles (MFIX DEM03)";
    let fig = figure(&report.runs, &report.convergence);
    let (files, png) =
        crate::report::write_case_files(dir, "dem03", title, &csv(&report.runs), &fig, &report.checks)?;
    let z = report.runs.first().map_or(f64::NAN, |r| r.system.omega_max() * r.dt);
    Ok(CaseOutcome {
        name: "dem03",
        title: title.into(),
        checks: report.checks,
        files,
        figures: vec![png],
        notes: vec![
            "Two 1 mm spheres of different density, pre-compressed between the floor and the ceiling, oscillate on three contacts that stay closed; the reference integrates the linear 1-D system (MFIX's damping from the pair's and each wall's effective mass) with RK4 at 1e-7 s to the simulated output times.".into(),
            format!(
                "The time step is set by the lightest phase pair (2-2), so the faster of the two modes is resolved with ω_max·Δt = {z:.3}: Adams–Bashforth's phase error, (5/12)(ω_maxΔt)² per radian, accumulates over the ~21 radians of the run and is the visible difference (largest for e_n = 1, where nothing damps the fast mode). No contact opens or closes, so no force jumps and the integrator keeps its second order."
            ),
        ],
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Harmonic oscillator y″ = −ω²y, y(0) = 1, y′(0) = 0: exact cos ωt.
    fn oscillator_error(h: f64) -> f64 {
        let w = 3.0;
        let f = |_t: f64, s: &[f64; 2]| [s[1], -w * w * s[0]];
        let t1 = 2.0;
        let y = rk4_integrate(&f, 0.0, [1.0, 0.0], t1, h);
        // Distance in the phase plane (y, y′/ω): the phase error of the solution.
        ((y[0] - (w * t1).cos()).powi(2) + (y[1] / w + (w * t1).sin()).powi(2)).sqrt()
    }

    #[test]
    fn rk4_is_fourth_order() {
        // Halving h divides the global error by 2⁴ = 16.
        for h in [0.02, 0.01, 0.005] {
            let ratio = oscillator_error(h) / oscillator_error(h / 2.0);
            assert!((ratio - 16.0).abs() < 0.5, "h = {h}: ratio {ratio}");
        }
    }

    #[test]
    fn rk4_oscillator_error_is_o_h4() {
        // RK4's amplification factor for y″ = −ω²y is e^(iωh) to fourth order: the phase errs
        // by (ωh)⁵/120 per step, (ωh)⁴·ω·t/120 in all (the amplitude error is O((ωh)⁶)).
        let (w, t1) = (3.0, 2.0);
        for h in [0.01, 0.001] {
            let e = oscillator_error(h);
            let leading = (w * h).powi(4) * w * t1 / 120.0;
            assert!((e / leading - 1.0).abs() < 0.1, "h = {h}: {e} vs {leading}");
        }
    }

    #[test]
    fn rk4_exact_for_cubic_polynomial() {
        // y′ = 3t² + 2t + 1 is integrated exactly (RK4 is Simpson's rule for y′ = f(t)).
        let f = |t: f64, _s: &[f64; 1]| [3.0 * t * t + 2.0 * t + 1.0];
        let y = rk4_integrate(&f, 0.0, [0.0], 1.7, 0.85);
        let exact = 1.7f64.powi(3) + 1.7f64.powi(2) + 1.7;
        assert!((y[0] - exact).abs() < 1e-13);
    }

    #[test]
    fn rk4_integrate_lands_on_the_end_time() {
        // Unequal spans are split into equal steps: integrating y′ = 1 gives the span exactly.
        let f = |_t: f64, _s: &[f64; 1]| [1.0];
        let t1 = 0.3 + 3.3e-6;
        let y = rk4_integrate(&f, 0.3, [0.0], t1, 1e-6);
        assert!((y[0] - (t1 - 0.3)).abs() < 1e-20, "{}", y[0]);
        assert_eq!(rk4_integrate(&f, 1.0, [5.0], 1.0, 1e-6), [5.0]);
    }

    #[test]
    fn stacked_pair_frequency() {
        // k = k_w, m₁ = 2m₂: ω_max² = (3 + √3)/2 · k/m₂.
        let s = StackedPair {
            m1: 2.0,
            m2: 1.0,
            radius: 0.5,
            height: 1.8,
            k: 10.0,
            k_w: 10.0,
            eta_12: 0.0,
            eta_w1: 0.0,
            eta_w2: 0.0,
            g: 0.0,
        };
        let expected = ((3.0 + 3f64.sqrt()) / 2.0 * 10.0).sqrt();
        assert!((s.omega_max() - expected).abs() < 1e-12);
    }
}
