//! Rolling and sliding of a sphere on a plane (friction, rotation and gravity together).
//!
//! - **Plane** (`rolling_plane`): a sphere launched with speed v₀ and spin ω₀ (rolling sense)
//!   with slip u₀ = v₀ − Rω₀ > 0 slides; friction μmg decelerates it (μg) and spins it up
//!   (2.5μg/R), so the slip falls at 3.5μg and vanishes at t* = 2u₀/(7μg), with
//!   v* = v₀ − μgt* = (5v₀ + 2Rω₀)/7. Without rolling resistance it then rolls at constant speed.
//! - **Incline** (`rolling_incline`): released from rest on an incline of angle α it rolls without
//!   slipping iff the static friction it needs, (2/7)mg·sin α, is within μmg·cos α, i.e.
//!   tan α ≤ 3.5μ; then a = (5/7)g·sin α and dω/dt = a/R. Otherwise it slides with
//!   a = g(sin α − μ·cos α) and dω/dt = 2.5μg·cos α/R. The incline is the plane y = 0 with
//!   gravity tilted by α.
//!
//! Both use a glass bead (R = 5 mm, E = 63 GPa) on a rigid plane with the Hertz law, the
//! incremental Mindlin tangential spring and the lever arm R (the rigid-body closed forms use
//! it; MFIX's lever R − δ would change t* by ~δ_s/R = 3·10⁻⁶). The closed forms do not depend on
//! the contact law: what the runs test is that the Coulomb limit, the torque and the integration
//! of translation and rotation under gravity are consistent.
//!
//! The soft contact settles with normal oscillations if released at zero overlap. Here the
//! sphere starts at its static overlap δ_s = (m·g_n/K_n)^(2/3), K_n = (4/3)E*√R, so the normal
//! force balances gravity from the first step (e_n = 1: no normal damping needed; the residual
//! oscillation is reported). When the sphere sticks, the tangential spring holds a force
//! (μmg on the plane, up to twice the static friction on the incline) that would oscillate at
//! ω_t = √(K_t√δ_s/(2m/7)), period 119 µs; e_t = 0.5 damps it (damping ratio 0.215, decay time
//! τ = 88 µs). Sliding contacts sit at the Coulomb limit, where the tangential dashpot does not
//! act, and steady rolling has no slip, so e_t changes neither closed form. Measurements of the
//! rolling phase start 30τ (e⁻³⁰) after the sphere sticks. Δt = 1.5 µs: 80 steps per
//! tangential period, below the case layer's stability limit (0.3 × the Rayleigh time, 1.6 µs).

use crate::check::Check;
use crate::chung_ooi::{effective_modulus, effective_shear_modulus};
use crate::error::VerifyError;
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions, case_dir, shipped_case, summary_markdown, write_file};
use grainflow::state::ParticleInit;
use grainflow::{Particles, Simulation, Vec3};
use grainflow_case::Case;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The plane case file.
pub const PLANE_CASE: &str = include_str!("../cases/rolling/plane.toml");
/// The incline case file.
pub const INCLINE_CASE: &str = include_str!("../cases/rolling/incline.toml");

/// Friction coefficients of the plane runs.
pub const PLANE_MU: [f64; 3] = [0.1, 0.2, 0.4];
/// Initial spins of the plane runs, rad/s, in the rolling sense (v₀ = 1 m/s, R = 5 mm: slip
/// u₀ = 1.5, 1, 0.5, 0.25 m/s; negative is backspin).
pub const PLANE_SPINS: [f64; 4] = [-100.0, 0.0, 100.0, 150.0];
/// Launch speed of the plane runs, m/s.
pub const PLANE_SPEED: f64 = 1.0;
/// Friction coefficients of the incline runs (thresholds atan(3.5μ) = 19.3°, 35.0°, 46.4°).
pub const INCLINE_MU: [f64; 3] = [0.1, 0.2, 0.3];
/// Incline angles, degrees.
pub const INCLINE_ANGLES_DEG: [f64; 12] =
    [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0];
/// Rolling-phase measurements start this many tangential decay times after the sphere sticks.
pub const SETTLE_DECAY_TIMES: f64 = 30.0;

/// The shipped plane case.
pub fn plane_case() -> Result<Case, VerifyError> {
    shipped_case("rolling/plane.toml", PLANE_CASE, &[])
}

/// The shipped incline case.
pub fn incline_case() -> Result<Case, VerifyError> {
    shipped_case("rolling/incline.toml", INCLINE_CASE, &[])
}

/// The sphere of a case and the contact quantities derived from it.
#[derive(Debug, Clone, Copy)]
struct Sphere {
    /// The shipped particle.
    template: ParticleInit,
    mass: f64,
    /// K_n = (4/3)E*√R, N/m^1.5.
    kn: f64,
    /// K_t = 8G*√R, N/m^1.5.
    kt: f64,
    /// Damping ratio of the tangential dashpot, from e_t.
    zeta_t: f64,
}

impl Sphere {
    fn of(case: &Case) -> Result<Self, VerifyError> {
        let p = &case.particles;
        let phase = p.phase.first().and_then(|&k| case.config.phases.get(k as usize)).ok_or_else(|| {
            VerifyError::Engine(grainflow::EngineError::BadReference(
                "the rolling case needs one particle of a defined phase".into(),
            ))
        })?;
        let wall = case.config.walls.first().and_then(|w| case.config.wall_materials.get(w.material));
        let (ew, nuw) = wall.map_or((f64::NAN, f64::NAN), |w| {
            (w.youngs_modulus.unwrap_or(f64::NAN), w.poisson_ratio.unwrap_or(f64::NAN))
        });
        let (e, nu) = (phase.youngs_modulus.unwrap_or(f64::NAN), phase.poisson_ratio.unwrap_or(f64::NAN));
        let r = p.radius[0];
        let params = case.config.wall_params.first().copied().unwrap_or_default();
        let et = params.et.unwrap_or(1.0);
        Ok(Sphere {
            template: ParticleInit {
                id: 1,
                phase: p.phase[0],
                radius: r,
                density: phase.density,
                position: p.position[0],
                velocity: p.velocity[0],
                omega: p.omega[0],
            },
            mass: p.mass[0],
            kn: 4.0 / 3.0 * effective_modulus(e, nu, ew, nuw) * r.sqrt(),
            kt: 8.0 * effective_shear_modulus(e, nu, ew, nuw) * r.sqrt(),
            zeta_t: et.ln().abs() / (PI * PI + et.ln().powi(2)).sqrt(),
        })
    }

    /// Static overlap under the normal load m·g_n, (m·g_n/K_n)^(2/3).
    fn static_overlap(&self, g_normal: f64) -> f64 {
        (self.mass * g_normal / self.kn).powf(2.0 / 3.0)
    }

    /// Angular frequency of the stuck tangential spring, √(K_t√δ_s/(2m/7)).
    fn tangential_frequency(&self, g_normal: f64) -> f64 {
        (self.kt * self.static_overlap(g_normal).sqrt() / (2.0 / 7.0 * self.mass)).sqrt()
    }

    /// Time after sticking from which the rolling phase is measured: 30 decay times
    /// 1/(ζω_t) of the tangential oscillation (or 30 periods without damping).
    fn settle_time(&self, g_normal: f64) -> f64 {
        let w = self.tangential_frequency(g_normal);
        SETTLE_DECAY_TIMES / if self.zeta_t > 0.0 { self.zeta_t * w } else { w / (2.0 * PI) }
    }

    /// The sphere resting on the plane y = 0 at its static overlap, at `x`, `z`.
    fn resting(&self, x: f64, z: f64, g_normal: f64) -> ParticleInit {
        let r = self.template.radius;
        ParticleInit {
            position: Vec3::new(x, r - self.static_overlap(g_normal), z),
            velocity: Vec3::ZERO,
            omega: Vec3::ZERO,
            ..self.template
        }
    }
}

/// Contact-point slip along +x of a sphere on the plane y = 0: v_x + Rω_z.
fn slip(p: &Particles, i: usize) -> f64 {
    p.velocity[i].x + p.radius[i] * p.omega[i].z
}

// ---------------------------------------------------------------------------------------------
// Plane
// ---------------------------------------------------------------------------------------------

/// One plane run.
#[derive(Debug, Clone)]
pub struct PlaneRun {
    /// Friction coefficient.
    pub mu: f64,
    /// Initial spin in the rolling sense, rad/s.
    pub omega0: f64,
    /// Initial slip u₀ = v₀ − Rω₀, m/s.
    pub slip0: f64,
    /// Roll-start time: simulated (slip crosses zero, interpolated) and 2u₀/(7μg), s.
    pub t_star_sim: f64,
    pub t_star: f64,
    /// Speed at t*: simulated and (5v₀ + 2Rω₀)/7, m/s.
    pub v_star_sim: f64,
    pub v_star: f64,
    /// max(|v − v*|, |u|)/v* over the rolling phase, from 30 decay times after t*_sim on.
    pub rolling_deviation: f64,
    /// Largest |y − y₀|/δ_s: the normal oscillation left.
    pub normal_oscillation: f64,
    /// (t, v, RΩ) every 250 steps, for the figure.
    pub series: Vec<(f64, f64, f64)>,
}

/// Everything `rolling_plane` measured.
#[derive(Debug, Clone)]
pub struct PlaneReport {
    pub runs: Vec<PlaneRun>,
    /// |g|, m/s².
    pub gravity: f64,
    /// Steps of the longest run.
    pub steps: u64,
    pub dt: f64,
    /// Steps per tangential period.
    pub steps_per_period: f64,
    /// Settling time after sticking, s.
    pub settle: f64,
    pub checks: Vec<Check>,
    pub wall_seconds: f64,
}

fn plane_sim(base: &Case, sphere: &Sphere, mu: f64) -> Result<Vec<PlaneRun>, VerifyError> {
    let g = base.config.gravity.length();
    let r = sphere.template.radius;
    let mut c = base.clone();
    for p in &mut c.config.wall_params {
        p.mu = mu;
    }
    let t_star = |w0: f64| 2.0 * (PLANE_SPEED - r * w0) / (7.0 * mu * g);
    let longest = PLANE_SPINS.iter().map(|&w| t_star(w)).fold(0.0, f64::max);
    c.config.t_stop = 1.5 * longest;
    // Side by side along z; each slides along +x, spinning about −z in the rolling sense.
    let init: Vec<ParticleInit> = PLANE_SPINS
        .iter()
        .enumerate()
        .map(|(k, &w0)| ParticleInit {
            id: k as u32 + 1,
            velocity: Vec3::new(PLANE_SPEED, 0.0, 0.0),
            omega: Vec3::new(0.0, 0.0, -w0),
            ..sphere.resting(0.0, 4.0 * r * k as f64, g)
        })
        .collect();
    let n = init.len();
    let settle = sphere.settle_time(g);
    let y0: Vec<f64> = init.iter().map(|p| p.position.y).collect();
    let mut prev: Vec<(f64, f64, f64)> =
        init.iter().map(|p| (0.0, p.velocity.x, p.velocity.x + r * p.omega.z)).collect();
    let mut stick: Vec<Option<(f64, f64)>> = vec![None; n];
    let mut deviation = vec![0.0f64; n];
    let mut oscillation = vec![0.0f64; n];
    let mut series: Vec<Vec<(f64, f64, f64)>> =
        init.iter().map(|p| vec![(0.0, p.velocity.x, -r * p.omega.z)]).collect();
    let v_star: Vec<f64> = PLANE_SPINS.iter().map(|&w| (5.0 * PLANE_SPEED + 2.0 * r * w) / 7.0).collect();
    let mut sim = Simulation::new(c.config.clone(), Particles::from_init(&init))?;
    let steps = sim.total_steps();
    sim.run_with(steps, |s| {
        let t = s.time();
        let p = s.particles();
        for i in 0..n {
            let (v, u) = (p.velocity[i].x, slip(p, i));
            let (t0, v0, u0) = prev[i];
            if stick[i].is_none() && u0 > 0.0 && u <= 0.0 {
                let f = u0 / (u0 - u);
                stick[i] = Some((t0 + f * (t - t0), v0 + f * (v - v0)));
            }
            if let Some((ts, _)) = stick[i]
                && t >= ts + settle
            {
                deviation[i] = deviation[i].max((v - v_star[i]).abs().max(u.abs()) / v_star[i]);
            }
            oscillation[i] = oscillation[i].max((p.position[i].y - y0[i]).abs());
            prev[i] = (t, v, u);
            if s.step_index() % 250 == 0 {
                series[i].push((t, v, -r * p.omega[i].z));
            }
        }
    });
    let ds = sphere.static_overlap(g);
    Ok((0..n)
        .map(|i| {
            let w0 = PLANE_SPINS[i];
            let (ts, vs) = stick[i].unwrap_or((f64::NAN, f64::NAN));
            PlaneRun {
                mu,
                omega0: w0,
                slip0: PLANE_SPEED - r * w0,
                t_star_sim: ts,
                t_star: t_star(w0),
                v_star_sim: vs,
                v_star: v_star[i],
                // NaN if it never stuck, or stuck too late to be measured.
                rolling_deviation: if ts + settle < c.config.t_stop { deviation[i] } else { f64::NAN },
                normal_oscillation: oscillation[i] / ds,
                series: std::mem::take(&mut series[i]),
            }
        })
        .collect())
}

/// Runs the plane sweep (μ in parallel) and evaluates its checks; writes nothing.
pub fn evaluate_plane() -> Result<PlaneReport, VerifyError> {
    let start = Instant::now();
    let base = plane_case()?;
    let sphere = Sphere::of(&base)?;
    let per_mu: Vec<Vec<PlaneRun>> =
        PLANE_MU.par_iter().map(|&mu| plane_sim(&base, &sphere, mu)).collect::<Result<_, _>>()?;
    let runs: Vec<PlaneRun> = per_mu.into_iter().flatten().collect();
    let g = base.config.gravity.length();
    let dt = match base.config.time_step {
        grainflow::TimeStepRule::Fixed(dt) => dt,
        grainflow::TimeStepRule::Mfix { .. } => f64::NAN,
    };
    let period = 2.0 * PI / sphere.tangential_frequency(g);
    let settle = sphere.settle_time(g);
    let longest_t_star = runs.iter().map(|r| r.t_star).fold(0.0, f64::max);
    let steps = (1.5 * longest_t_star / dt).ceil() as u64;
    let mut checks = Vec::new();
    let worst = |f: &dyn Fn(&PlaneRun) -> f64| {
        runs.iter().map(|r| (f(r), r)).fold(None, |best: Option<(f64, &PlaneRun)>, (e, r)| match best {
            Some((b, _)) if b.is_nan() || e <= b => best,
            _ => Some((e, r)),
        })
    };
    let at = |r: &PlaneRun| format!("μ = {}, ω₀ = {} rad/s", r.mu, r.omega0);
    if let Some((e, r)) = worst(&|r| (r.t_star_sim - r.t_star).abs()) {
        checks.push(Check::assert(
            "rolling starts at t* = 2u₀/(7μg)",
            e,
            dt,
            format!(
                "|t*_sim − t*| in s, worst at {}: {:.9} s vs {:.9} s. The tangential spring starts unloaded, so velocity Verlet's first half kick has no friction: t* comes Δt/2 late (the spring itself needs only μmg/(K_t√δ_s·u₀) ≈ 1 ns). Tolerance Δt = {dt:.1e} s (relative ≤ {:.1e})",
                at(r),
                r.t_star_sim,
                r.t_star,
                dt / runs.iter().map(|r| r.t_star).fold(f64::INFINITY, f64::min)
            ),
        ));
    }
    if let Some((e, r)) = worst(&|r| ((r.v_star_sim - r.v_star) / r.v_star).abs()) {
        checks.push(Check::assert(
            "rolling speed v* = (5v₀ + 2Rω₀)/7",
            e,
            1e-8,
            format!(
                "relative, worst at {}: {:.12} vs {:.12} m/s. While it slides the forces are constant (μmg at the Coulomb limit, mg normal), so Verlet is exact and the slip is linear in t: rounding over ≤ {} steps only",
                at(r),
                r.v_star_sim,
                r.v_star,
                steps
            ),
        ));
    }
    if let Some((e, r)) = worst(&|r| r.rolling_deviation) {
        checks.push(Check::assert(
            "then rolls at constant speed: max(|v − v*|, |slip|)/v* over the rolling phase",
            e,
            1e-8,
            format!(
                "worst at {}; from {settle:.2e} s (30 decay times of the tangential oscillation, e⁻³⁰) after t* to the end (1.5 t* of the slowest run); no rolling resistance: nothing acts along the plane once the spring has settled; rounding only",
                at(r)
            ),
        ));
    }
    if let Some((e, r)) = worst(&|r| r.normal_oscillation) {
        checks.push(Check::report(
            "normal oscillation left: max |y − y₀|/δ_s",
            e,
            format!(
                "worst at {}; the sphere starts at its static overlap δ_s, so only rounding of δ_s remains",
                at(r)
            ),
        ));
    }
    Ok(PlaneReport {
        runs,
        gravity: g,
        steps,
        dt,
        steps_per_period: period / dt,
        settle,
        checks,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

fn plane_figure(report: &PlaneReport) -> Figure {
    let mut series_v = Vec::new();
    let mu_shown = PLANE_MU[1];
    for (k, run) in report.runs.iter().filter(|r| r.mu == mu_shown).enumerate() {
        let color = Color::palette(k);
        // Closed form: v = v₀ − μgt, RΩ = Rω₀ + 2.5μgt until t*, then both v*.
        let g = report.gravity;
        let end = run.series.last().map_or(run.t_star, |x| x.0);
        let r_w0 = PLANE_SPEED - run.slip0;
        series_v.push(Series::line(
            if k == 0 { "closed form".to_string() } else { String::new() },
            vec![(0.0, PLANE_SPEED), (run.t_star, run.v_star), (end, run.v_star)],
            LineStyle::Thin,
            Color::BLACK,
        ));
        series_v.push(Series::line(
            String::new(),
            vec![(0.0, r_w0), (run.t_star, r_w0 + 2.5 * mu_shown * g * run.t_star), (end, run.v_star)],
            LineStyle::Thin,
            Color::BLACK,
        ));
        series_v.push(Series::markers(
            format!("v, ω₀ = {} rad/s", run.omega0),
            run.series.iter().step_by((run.series.len() / 25).max(1)).map(|x| (x.0, x.1)).collect(),
            MarkerShape::Circle,
            color,
        ));
        series_v.push(Series::markers(
            format!("RΩ, ω₀ = {} rad/s", run.omega0),
            run.series.iter().step_by((run.series.len() / 25).max(1)).map(|x| (x.0, x.2)).collect(),
            MarkerShape::Triangle,
            color,
        ));
    }
    let max_t = report.runs.iter().map(|r| r.t_star).fold(0.0, f64::max) * 1.1;
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle, MarkerShape::Square];
    let mut series_t = vec![Series::line(
        "t*_sim = 2u₀/(7μg)",
        vec![(0.0, 0.0), (max_t, max_t)],
        LineStyle::Thin,
        Color::BLACK,
    )];
    let mut series_s = vec![Series::line(
        "v*_sim = (5v₀ + 2Rω₀)/7",
        vec![(0.5, 0.5), (1.0, 1.0)],
        LineStyle::Thin,
        Color::BLACK,
    )];
    for (k, &mu) in PLANE_MU.iter().enumerate() {
        let of = |f: fn(&PlaneRun) -> (f64, f64)| report.runs.iter().filter(|r| r.mu == mu).map(f).collect();
        series_t.push(Series::markers(
            format!("μ = {mu}"),
            of(|r| (r.t_star, r.t_star_sim)),
            shapes[k],
            Color::palette(k),
        ));
        series_s.push(Series::markers(
            format!("μ = {mu}"),
            of(|r| (r.v_star, r.v_star_sim)),
            shapes[k],
            Color::palette(k),
        ));
    }
    Figure {
        title: "Sphere sliding into rolling on a plane: v₀ = 1 m/s, ω₀ = −100 … 150 rad/s".into(),
        note: Some("glass bead R = 5 mm on a rigid plane, Hertz–Mindlin, lever R; slip u = v − RΩ falls at 3.5μg until t* = 2u₀/(7μg)".into()),
        panels: vec![
            Panel {
                series: series_v,
                ..Panel::new(format!("Speed and rolling speed, μ = {mu_shown}"), "time (s)", "v, RΩ (m/s)")
            },
            Panel { series: series_t, ..Panel::new("Roll-start time", "2u₀/(7μg) (s)", "simulated t* (s)") },
            Panel {
                series: series_s,
                x_range: Some((0.5, 1.0)),
                ..Panel::new("Rolling speed (the same for every μ)", "(5v₀ + 2Rω₀)/7 (m/s)", "simulated v* (m/s)")
            },
        ],
    }
}

/// The `rolling_plane` suite entry: runs, writes `DIR/rolling_plane/` and reports.
pub fn run_plane(dir: &Path, _options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let report = evaluate_plane()?;
    let out = case_dir(dir, "rolling_plane")?;
    let mut files = Vec::new();
    let mut csv = String::from("mu,omega0,t_star_sim,t_star_analytic,v_star_sim,v_star_analytic\n");
    for r in &report.runs {
        let _ = writeln!(
            csv,
            "{},{},{:.10},{:.10},{:.12},{:.12}",
            r.mu, r.omega0, r.t_star_sim, r.t_star, r.v_star_sim, r.v_star
        );
    }
    write_file(out.join("rolling_plane.csv"), &csv, &mut files)?;
    let png = crate::report::write_figure(&out, "rolling_plane", &plane_figure(&report), &mut files)?;
    let title = "sphere sliding into rolling on a horizontal plane";
    let mut summary = summary_markdown(title, &report.checks);
    let _ = write!(
        summary,
        "\n{} runs (μ = {:?} × ω₀ = {:?} rad/s, v₀ = {PLANE_SPEED} m/s); Δt = {:.1e} s, {:.0} steps per tangential period; rolling measured from {:.2e} s after t*; {:.2} s.\n",
        report.runs.len(),
        PLANE_MU,
        PLANE_SPINS,
        report.dt,
        report.steps_per_period,
        report.settle,
        report.wall_seconds
    );
    write_file(out.join("summary.md"), &summary, &mut files)?;
    Ok(CaseOutcome {
        name: "rolling_plane",
        title: title.into(),
        checks: report.checks,
        files,
        figures: vec![png],
        notes: vec![
            "A glass bead launched with slip on a rigid plane (μ = 0.1, 0.2, 0.4; backspin to topspin): it slides with constant deceleration μg, spins up at 2.5μg/R, and rolls from t* = 2u₀/(7μg) on at v* = (5v₀ + 2Rω₀)/7, then at constant speed. Hertz–Mindlin with lever R; the sphere starts at its static overlap so that no normal oscillation starts, and e_t = 0.5 damps the tangential spring once it sticks. t* comes half a time step late: the tangential spring starts unloaded, so the first half kick of velocity Verlet has no friction.".into(),
        ],
        wall_seconds: report.wall_seconds,
    })
}

// ---------------------------------------------------------------------------------------------
// Incline
// ---------------------------------------------------------------------------------------------

/// One incline run.
#[derive(Debug, Clone)]
pub struct InclineRun {
    /// Incline angle, degrees.
    pub angle_deg: f64,
    /// Friction coefficient.
    pub mu: f64,
    /// True if tan α ≤ 3.5μ (rolls without slipping).
    pub rolls: bool,
    /// Acceleration down the slope: simulated (least squares after the settling time) and
    /// closed form, m/s².
    pub accel_sim: f64,
    pub accel: f64,
    /// Angular acceleration in the rolling sense: simulated and closed form, rad/s².
    pub alpha_sim: f64,
    pub alpha: f64,
    /// Slip at the end, m/s.
    pub slip_end: f64,
    /// Largest |y − y₀|/δ_s.
    pub normal_oscillation: f64,
}

/// Everything `rolling_incline` measured.
#[derive(Debug, Clone)]
pub struct InclineReport {
    pub runs: Vec<InclineRun>,
    /// |g|, m/s².
    pub gravity: f64,
    /// Sphere radius, m.
    pub radius: f64,
    pub dt: f64,
    pub t_stop: f64,
    /// Start of the fitted window, s.
    pub settle: f64,
    /// Slip speed above which a run counts as sliding, m/s.
    pub slip_threshold: f64,
    pub checks: Vec<Check>,
    pub wall_seconds: f64,
}

/// Closed form of the incline: (rolls, a, dω/dt).
pub fn incline_closed_form(angle_deg: f64, mu: f64, g: f64, radius: f64) -> (bool, f64, f64) {
    let a = angle_deg.to_radians();
    if a.tan() <= 3.5 * mu {
        (true, 5.0 / 7.0 * g * a.sin(), 5.0 / 7.0 * g * a.sin() / radius)
    } else {
        (false, g * (a.sin() - mu * a.cos()), 2.5 * mu * g * a.cos() / radius)
    }
}

/// Least-squares slope accumulator.
#[derive(Debug, Clone, Copy, Default)]
struct Slope {
    n: f64,
    t: f64,
    y: f64,
    tt: f64,
    ty: f64,
}

impl Slope {
    fn add(&mut self, t: f64, y: f64) {
        self.n += 1.0;
        self.t += t;
        self.y += y;
        self.tt += t * t;
        self.ty += t * y;
    }

    fn slope(&self) -> f64 {
        (self.n * self.ty - self.t * self.y) / (self.n * self.tt - self.t * self.t)
    }
}

fn incline_sim(base: &Case, sphere: &Sphere, angle_deg: f64, mu: f64) -> Result<InclineRun, VerifyError> {
    let g = base.config.gravity.length();
    let a = angle_deg.to_radians();
    let mut c = base.clone();
    c.config.gravity = g * Vec3::new(a.sin(), -a.cos(), 0.0);
    for p in &mut c.config.wall_params {
        p.mu = mu;
    }
    let r = sphere.template.radius;
    let g_normal = g * a.cos();
    let init = [sphere.resting(0.0, 0.0, g_normal)];
    let settle = sphere.settle_time(g_normal);
    let y0 = init[0].position.y;
    let (mut fit_v, mut fit_w) = (Slope::default(), Slope::default());
    let mut oscillation = 0.0f64;
    let mut sim = Simulation::new(c.config.clone(), Particles::from_init(&init))?;
    let steps = sim.total_steps();
    sim.run_with(steps, |s| {
        let t = s.time();
        let p = s.particles();
        if t >= settle {
            fit_v.add(t, p.velocity[0].x);
            fit_w.add(t, -p.omega[0].z);
        }
        oscillation = oscillation.max((p.position[0].y - y0).abs());
    });
    let (rolls, accel, alpha) = incline_closed_form(angle_deg, mu, g, r);
    Ok(InclineRun {
        angle_deg,
        mu,
        rolls,
        accel_sim: fit_v.slope(),
        accel,
        alpha_sim: fit_w.slope(),
        alpha,
        slip_end: slip(sim.particles(), 0),
        normal_oscillation: oscillation / sphere.static_overlap(g_normal),
    })
}

/// Runs the incline sweep (in parallel) and evaluates its checks; writes nothing.
pub fn evaluate_incline() -> Result<InclineReport, VerifyError> {
    let start = Instant::now();
    let base = incline_case()?;
    let sphere = Sphere::of(&base)?;
    let specs: Vec<(f64, f64)> =
        INCLINE_MU.iter().flat_map(|&mu| INCLINE_ANGLES_DEG.iter().map(move |&a| (a, mu))).collect();
    let runs: Vec<InclineRun> =
        specs.par_iter().map(|&(a, mu)| incline_sim(&base, &sphere, a, mu)).collect::<Result<_, _>>()?;
    let g = base.config.gravity.length();
    let t_stop = base.config.t_stop;
    let dt = match base.config.time_step {
        grainflow::TimeStepRule::Fixed(dt) => dt,
        grainflow::TimeStepRule::Mfix { .. } => f64::NAN,
    };
    // The smallest slip a sliding run of the sweep can have at the end:
    // g(sin α − 3.5μ cos α)·t_stop; a run counts as sliding above a tenth of it.
    let smallest_sliding_slip = runs
        .iter()
        .filter(|r| !r.rolls)
        .map(|r| {
            let a = r.angle_deg.to_radians();
            g * (a.sin() - 3.5 * r.mu * a.cos()) * t_stop
        })
        .fold(f64::INFINITY, f64::min);
    let slip_threshold = 0.1 * smallest_sliding_slip;
    let settle = sphere.settle_time(g * INCLINE_ANGLES_DEG[INCLINE_ANGLES_DEG.len() - 1].to_radians().cos());
    let mut checks = Vec::new();
    let wrong: Vec<&InclineRun> =
        runs.iter().filter(|r| r.rolls != (r.slip_end.abs() <= slip_threshold)).collect();
    checks.push(Check::assert(
        "rolls without slipping iff tan α ≤ 3.5μ",
        wrong.len() as f64,
        0.0,
        format!(
            "number of the {} runs whose final slip contradicts the criterion{} (sliding if |slip| > {:.2e} m/s, a tenth of the smallest sliding slip of the sweep, g(sin α − 3.5μ cos α)t at α = 35°, μ = 0.2, 0.03 % above its threshold; stuck runs end with |slip| ≤ {:.1e} m/s)",
            runs.len(),
            wrong.first().map_or(String::new(), |r| format!(", first α = {}°, μ = {}", r.angle_deg, r.mu)),
            slip_threshold,
            runs.iter().filter(|r| r.rolls).map(|r| r.slip_end.abs()).fold(0.0, f64::max)
        ),
    ));
    let worst = |f: &dyn Fn(&InclineRun) -> f64, rolling: bool| {
        runs.iter().filter(|r| r.rolls == rolling).map(|r| (f(r), r)).fold(
            None,
            |best: Option<(f64, &InclineRun)>, (e, r)| match best {
                Some((b, _)) if b.is_nan() || e <= b => best,
                _ => Some((e, r)),
            },
        )
    };
    let cases = [
        (true, "rolling: a = (5/7)g·sin α", "rolling: dω/dt = (5/7)g·sin α/R"),
        (false, "sliding: a = g(sin α − μ·cos α)", "sliding: dω/dt = 2.5μg·cos α/R"),
    ];
    for (rolling, a_name, w_name) in cases {
        // Rounding over the ≤ 1.3e5 steps of a run is ~1e-11; the start-up transient of the
        // stuck spring has decayed by e⁻³⁰ ≈ 1e-13 when the fit starts. 1e-9 relative.
        let why = if rolling {
            format!(
                "least squares from 30 decay times of the tangential oscillation (≤ {settle:.2e} s: the spring takes up the static friction with an overshoot, damped by e_t) to {t_stop} s; then no slip: rounding and the e⁻³⁰ tail only"
            )
        } else {
            format!(
                "least squares from ≤ {settle:.2e} s to {t_stop} s; the contact sits at the Coulomb limit with constant forces: Verlet is exact, rounding only"
            )
        };
        for (name, f) in [
            (
                a_name,
                (&|r: &InclineRun| ((r.accel_sim - r.accel) / r.accel).abs()) as &dyn Fn(&InclineRun) -> f64,
            ),
            (w_name, &|r: &InclineRun| ((r.alpha_sim - r.alpha) / r.alpha).abs()),
        ] {
            match worst(f, rolling) {
                Some((e, r)) => checks.push(Check::assert(
                    name,
                    e,
                    1e-9,
                    format!("relative, worst at α = {}°, μ = {}; {why}; tolerance 1e-9", r.angle_deg, r.mu),
                )),
                None => checks.push(Check::assert(name, f64::NAN, 1e-9, "no run in this regime")),
            }
        }
    }
    if let Some((e, r)) = worst(&|r| r.normal_oscillation, true)
        .into_iter()
        .chain(worst(&|r| r.normal_oscillation, false))
        .max_by(|a, b| a.0.total_cmp(&b.0))
    {
        checks.push(Check::report(
            "normal oscillation left: max |y − y₀|/δ_s",
            e,
            format!("worst at α = {}°, μ = {}; the sphere starts at its static overlap, so only rounding of δ_s remains", r.angle_deg, r.mu),
        ));
    }
    Ok(InclineReport {
        runs,
        gravity: g,
        radius: sphere.template.radius,
        dt,
        t_stop,
        settle,
        slip_threshold,
        checks,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

fn incline_figure(report: &InclineReport) -> Figure {
    let (g, radius) = (report.gravity, report.radius);
    let angles: Vec<f64> = (0..=650).map(|k| k as f64 * 0.1).collect();
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle, MarkerShape::Square];
    let rolling = || {
        Series::line(
            "rolling: (5/7)sin α",
            angles.iter().map(|&a| (a, 5.0 / 7.0 * a.to_radians().sin())).collect(),
            LineStyle::Dashed,
            Color::BLACK,
        )
    };
    let (mut pa, mut pw) = (vec![rolling()], vec![rolling()]);
    for (k, &mu) in INCLINE_MU.iter().enumerate() {
        let color = Color::palette(k);
        let closed: Vec<(f64, (bool, f64, f64))> =
            angles.iter().map(|&a| (a, incline_closed_form(a, mu, g, radius))).collect();
        pa.push(Series::line(
            format!("closed form, μ = {mu}"),
            closed.iter().map(|(a, c)| (*a, c.1 / g)).collect(),
            LineStyle::Thin,
            color,
        ));
        pw.push(Series::line(
            format!("closed form, μ = {mu}"),
            closed.iter().map(|(a, c)| (*a, c.2 * radius / g)).collect(),
            LineStyle::Thin,
            color,
        ));
        let runs = || report.runs.iter().filter(move |r| r.mu == mu);
        pa.push(Series::markers(
            format!("grainflow, μ = {mu}"),
            runs().map(|r| (r.angle_deg, r.accel_sim / g)).collect(),
            shapes[k],
            color,
        ));
        pw.push(Series::markers(
            format!("grainflow, μ = {mu}"),
            runs().map(|r| (r.angle_deg, r.alpha_sim * radius / g)).collect(),
            shapes[k],
            color,
        ));
    }
    Figure {
        title: "Sphere released on an incline: rolls iff tan α ≤ 3.5μ".into(),
        note: Some("glass bead R = 5 mm on a rigid plane, Hertz–Mindlin, lever R; thresholds 19.3° (μ = 0.1), 35.0° (0.2), 46.4° (0.3)".into()),
        panels: vec![
            Panel {
                series: pa,
                x_range: Some((0.0, 65.0)),
                ..Panel::new("Acceleration down the slope", "incline angle α (deg)", "a/g")
            },
            Panel {
                series: pw,
                x_range: Some((0.0, 65.0)),
                ..Panel::new("Angular acceleration", "incline angle α (deg)", "R·(dω/dt)/g")
            },
        ],
    }
}

/// The `rolling_incline` suite entry: runs, writes `DIR/rolling_incline/` and reports.
pub fn run_incline(dir: &Path, _options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let report = evaluate_incline()?;
    let out = case_dir(dir, "rolling_incline")?;
    let mut files = Vec::new();
    let mut csv = String::from("angle_deg,mu,regime,accel_sim,accel_analytic,alpha_sim,alpha_analytic\n");
    for r in &report.runs {
        let _ = writeln!(
            csv,
            "{},{},{},{:.10},{:.10},{:.8},{:.8}",
            r.angle_deg,
            r.mu,
            if r.rolls { "rolling" } else { "sliding" },
            r.accel_sim,
            r.accel,
            r.alpha_sim,
            r.alpha
        );
    }
    write_file(out.join("rolling_incline.csv"), &csv, &mut files)?;
    let png = crate::report::write_figure(&out, "rolling_incline", &incline_figure(&report), &mut files)?;
    let title = "sphere released on an incline: rolling or sliding";
    let mut summary = summary_markdown(title, &report.checks);
    let _ = write!(
        summary,
        "\n{} runs (α = 5 … 60° × μ = {:?}); Δt = {:.1e} s to {} s; accelerations fitted from {:.2e} s on; sliding if |slip| > {:.2e} m/s at the end; {:.2} s.\n",
        report.runs.len(),
        INCLINE_MU,
        report.dt,
        report.t_stop,
        report.settle,
        report.slip_threshold,
        report.wall_seconds
    );
    write_file(out.join("summary.md"), &summary, &mut files)?;
    Ok(CaseOutcome {
        name: "rolling_incline",
        title: title.into(),
        checks: report.checks,
        files,
        figures: vec![png],
        notes: vec![
            "A glass bead released from rest on inclines of 5–60° (gravity tilted, the plane y = 0) with μ = 0.1, 0.2, 0.3: it rolls without slipping with a = (5/7)g·sin α exactly when tan α ≤ 3.5μ, and otherwise slides with a = g(sin α − μ·cos α) while spinning up at 2.5μg·cos α/R. The sweep includes α = 35° with μ = 0.2, only 0.03 % past the threshold: it slides, as it must. Hertz–Mindlin with lever R; the sphere starts at its static overlap and e_t = 0.5 damps the tangential spring as it takes up the static friction.".into(),
        ],
        wall_seconds: report.wall_seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incline_threshold_and_regimes() {
        let (g, r) = (9.80665, 0.005);
        // tan α = 3.5μ separates the regimes; at the threshold both forms agree.
        let mu: f64 = 0.2;
        let alpha_c = (3.5 * mu).atan().to_degrees();
        let (rolls, a, w) = incline_closed_form(alpha_c - 1e-9, mu, g, r);
        let (slides, a2, w2) = incline_closed_form(alpha_c + 1e-9, mu, g, r);
        assert!(rolls && !slides);
        assert!((a - a2).abs() < 1e-6 && (w - w2).abs() < 1e-3);
        // 35° with μ = 0.2 is just past the threshold (34.99°).
        assert!(!incline_closed_form(35.0, 0.2, g, r).0);
    }

    #[test]
    fn case_files_parse_and_start_at_the_static_overlap() {
        for case in [plane_case(), incline_case()] {
            let case = case.expect("parses");
            let sphere = Sphere::of(&case).expect("one sphere");
            let g_n = -case.config.gravity.y;
            let y = case.particles.position[0].y;
            let expected = sphere.template.radius - sphere.static_overlap(g_n);
            assert!((y - expected).abs() < 1e-15, "{y} vs {expected}");
            // Δt resolves the tangential oscillation with at least 50 steps.
            if let grainflow::TimeStepRule::Fixed(dt) = case.config.time_step {
                assert!(2.0 * PI / sphere.tangential_frequency(g_n) / dt > 50.0);
            }
        }
    }
}
