//! JKR cohesion (`grainflow verify jkr`): the engine's `jkr` normal model against the JKR
//! closed forms and against LAMMPS's `pair granular … jkr`.
//!
//! **Closed forms.** On the law's own force–overlap curve (no velocity, so no damping): the
//! largest tension is the pull-off force F_c = 3πγR* (γ LAMMPS's surface energy; (3/2)πwR*
//! with the work of adhesion w = 2γ), found at the overlap −δ_c, δ_c = a_c²/(3R*),
//! a_c = (9πγR*²/(4E*))^{1/3}; at touch (δ = 0) the tension is (8/9)F_c; and the stored
//! energy is the integral of the force. The minimum is found by golden-section search, which
//! knows nothing of the closed forms.
//!
//! **The dynamic case** (`cases/jkr/pair.toml`): two equal spheres meet obliquely, stick (sliding
//! at the Coulomb limit of JKR's critical force),
//! stretch beyond the touch and pull off. The contact must end where the overlap passes
//! −δ_c. LAMMPS 2021 ran the same state, law and step (`bench/lammps/in.jkr_pair.lmp`); its
//! output, every 10 steps, is `cases/jkr/lammps_pair.txt`. `tests/jkr.rs` runs LAMMPS
//! afresh when it is installed and checks that output is still what it writes.

use crate::check::Check;
use crate::error::VerifyError;
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions};
use grainflow::contact::geometry::ContactGeometry;
use grainflow::contact::law::{contact_force_dyn, normal_spring_energy};
use grainflow::{ContactLaw, Simulation, Vec3};
use grainflow_case::Case;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The shipped case file.
pub const CASE: &str = include_str!("../cases/jkr/pair.toml");
/// LAMMPS 2021's output for the same case (`bench/lammps/in.jkr_pair.lmp`).
pub const LAMMPS: &str = include_str!("../cases/jkr/lammps_pair.txt");
/// LAMMPS prints every this many steps.
pub const EVERY: u64 = 10;

/// Agreement with LAMMPS, relative to each quantity's scale (see [`compare`]): the runs share
/// state, law and step, and a two-body contact does not amplify differences; what remains is
/// rounding — LAMMPS's closed form of the contact radius is another sequence of operations
/// than ours (≈1e-15 relative per evaluation), accumulated over ~3 600 steps of contact and
/// printed to 15 digits. 1e-8 leaves three orders of magnitude for that, and a contact that
/// ended one step earlier or later in one code (a jump of F_c, 30 % of the force scale)
/// fails by far.
pub const LAMMPS_TOLERANCE: f64 = 1e-8;

/// One printed state: particle 1's velocity and force, the centres' separation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Step.
    pub step: u64,
    /// x₂ − x₁, m.
    pub sep: f64,
    /// Particle 1's velocity (x, y), m/s.
    pub v1: [f64; 2],
    /// Particle 1's force (x, y), N.
    pub f1: [f64; 2],
}

/// The shipped case, parsed.
pub fn case() -> Result<Case, VerifyError> {
    crate::report::shipped_case("jkr/pair.toml", CASE, &[])
}

/// The rows of a LAMMPS `fix print` file as `in.jkr_pair.lmp` writes it.
pub fn parse_lammps(text: &str) -> Vec<Row> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| {
            let f: Vec<f64> = l.split_whitespace().filter_map(|v| v.parse().ok()).collect();
            (f.len() == 6).then(|| Row { step: f[0] as u64, sep: f[1], v1: [f[2], f[3]], f1: [f[4], f[5]] })
        })
        .collect()
}

/// What the engine's run of the case gives.
#[derive(Debug, Clone)]
pub struct Run {
    /// Every [`EVERY`] steps, from step 0, as LAMMPS prints.
    pub rows: Vec<Row>,
    /// R₁ + R₂, m.
    pub radius_sum: f64,
    /// The pull-off distance δ_c of the pair's coefficients, m.
    pub pull_off: f64,
    /// The stretch |x₂ − x₁| − (R₁ + R₂) at the last step in contact and at the first step
    /// after, m.
    pub stretch_at_pull_off: (f64, f64),
    /// Steps with a contact force.
    pub contact_steps: u64,
    /// The largest |F_t|/(μ·|F_ne + 2F_c|) over the contact (1 while sliding).
    pub sliding_ratio: f64,
}

/// Runs the case, recording particle 1 every [`EVERY`] steps.
pub fn run() -> Result<Run, VerifyError> {
    let case = case()?;
    let mut sim = Simulation::new(case.config, case.particles)?;
    let (i, j) = (sim.particles().index_of(1).unwrap_or(0), sim.particles().index_of(2).unwrap_or(1));
    let c = *sim.coefficients().pair(0, 0);
    let radius_sum = sim.particles().radius[i] + sim.particles().radius[j];
    let row = |sim: &Simulation| {
        let p = sim.particles();
        Row {
            step: sim.step_index(),
            sep: p.position[j].x - p.position[i].x,
            v1: [p.velocity[i].x, p.velocity[i].y],
            f1: [p.force[i].x, p.force[i].y],
        }
    };
    let mut rows = vec![row(&sim)];
    let law = *sim.law();
    let f_c = 3.0 * PI * c.surface_energy * c.r_star;
    let (mut was, mut contact_steps, mut sliding_ratio) = (false, 0, 0.0f64);
    let (mut last_in, mut first_out) = (f64::NAN, f64::NAN);
    while !sim.finished() {
        sim.step();
        let r = row(&sim);
        // The centres drift apart across x as they slide: the stretch along the line of
        // centres.
        let p = sim.particles();
        let d = p.position[j] - p.position[i];
        let stretch = d.length() - radius_sum;
        let touching = r.f1 != [0.0, 0.0];
        if touching {
            contact_steps += 1;
            last_in = stretch;
            // The tangential force against the critical force of the elastic force at this
            // overlap.
            let n = d.normalize();
            let f = p.force[i];
            let f_t = (f - f.dot(n) * n).length();
            let f_el = elastic_force(&law, &c, -stretch);
            sliding_ratio = sliding_ratio.max(f_t / (c.mu * (f_el + 2.0 * f_c).abs()));
        } else if was && first_out.is_nan() {
            first_out = stretch;
        }
        was = touching;
        if r.step % EVERY == 0 {
            rows.push(r);
        }
    }
    let pull_off = (last_in, first_out);
    Ok(Run {
        rows,
        radius_sum,
        pull_off: c.pull_off,
        stretch_at_pull_off: pull_off,
        contact_steps,
        sliding_ratio,
    })
}

/// The elastic normal force of the law at overlap `delta` (no velocity), N.
fn elastic_force(law: &ContactLaw, c: &grainflow::contact::ContactCoeffs, delta: f64) -> f64 {
    let g = ContactGeometry { normal: Vec3::X, overlap: delta, lever_i: 1e-3, lever_j: 1e-3 };
    let mut h = Vec3::ZERO;
    contact_force_dyn(law, c, &g, Vec3::ZERO, &mut h, 0.0).elastic_normal
}

/// The largest differences between two runs' rows of the same steps: of the separation
/// relative to the largest |overlap| of `a`, of the velocity relative to `a`'s initial speed,
/// of the force relative to `a`'s largest force; and the step of each. Rows of steps only one
/// has are counted in `unmatched`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Comparison {
    pub sep: (f64, u64),
    pub velocity: (f64, u64),
    pub force: (f64, u64),
    pub matched: usize,
    pub unmatched: usize,
}

/// Compares `b` with `a` (see [`Comparison`]); `radius_sum` = R₁ + R₂.
pub fn compare(a: &[Row], b: &[Row], radius_sum: f64) -> Comparison {
    let norm = |v: [f64; 2]| v[0].hypot(v[1]);
    let overlap = a.iter().map(|r| (r.sep - radius_sum).abs()).filter(|d| *d < 1e-5).fold(0.0, f64::max);
    let speed = a.first().map_or(1.0, |r| norm(r.v1));
    let force = a.iter().map(|r| norm(r.f1)).fold(0.0, f64::max);
    let mut out = Comparison::default();
    let worse = |slot: &mut (f64, u64), e: f64, step: u64| {
        if e > slot.0 || e.is_nan() {
            *slot = (e, step);
        }
    };
    for r in a {
        match b.iter().find(|s| s.step == r.step) {
            Some(s) => {
                out.matched += 1;
                worse(&mut out.sep, (s.sep - r.sep).abs() / overlap, r.step);
                let dv = [s.v1[0] - r.v1[0], s.v1[1] - r.v1[1]];
                worse(&mut out.velocity, norm(dv) / speed, r.step);
                let df = [s.f1[0] - r.f1[0], s.f1[1] - r.f1[1]];
                worse(&mut out.force, norm(df) / force, r.step);
            }
            None => out.unmatched += 1,
        }
    }
    out.unmatched += b.len().saturating_sub(out.matched);
    out
}

/// The closed-form checks on the law's force curve of the case's coefficients.
fn closed_form_checks(law: &ContactLaw, c: &grainflow::contact::ContactCoeffs) -> Vec<Check> {
    let e_star = 0.75 * c.kn;
    let (r, gamma) = (c.r_star, c.surface_energy);
    let f_c = 3.0 * PI * gamma * r;
    let a_c = (9.0 * PI * gamma * r * r / (4.0 * e_star)).cbrt();
    let delta_c = a_c * a_c / (3.0 * r);
    let f = |d: f64| elastic_force(law, c, d);
    // Golden-section search for the largest tension on [−1.5 δ_c, 0] (the branch ends at
    // −2.08 δ_c).
    let (mut lo, mut hi) = (-1.5 * delta_c, 0.0);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if f(x1) < f(x2) {
            hi = x2;
        } else {
            lo = x1;
        }
        if hi - lo < 1e-14 * delta_c {
            break;
        }
    }
    let at = 0.5 * (lo + hi);
    let mut checks = vec![
        Check::assert(
            "largest tension on the force curve = pull-off force 3πγR*",
            (f(at) + f_c).abs() / f_c,
            1e-10,
            format!(
                "relative; F_c = {f_c:.6e} N (γ = {gamma} J/m², R* = {r:e} m); the minimum is flat, so the search's error in δ enters squared (≈1e-16), the rest is the force's rounding"
            ),
        ),
        Check::assert(
            "where it is largest = pull-off distance δ_c = a_c²/(3R*)",
            (-at - delta_c).abs() / delta_c,
            1e-6,
            format!(
                "relative; δ_c = {delta_c:.6e} m; a search on a flat minimum locates it to about √ε of the force's relative rounding (≈1e-8·δ_c); the engine's own δ_c (the contact test's) differs by {:.1e}",
                (c.pull_off - delta_c).abs() / delta_c
            ),
        ),
        Check::assert(
            "tension at touch (δ = 0) = (8/9)F_c",
            (f(0.0) + 8.0 / 9.0 * f_c).abs() / f_c,
            1e-12,
            "relative; a(0)³ = 4πγR*²/E*; a dozen correctly rounded operations",
        ),
    ];
    let mut worst = 0.0f64;
    for k in 0..=40 {
        let d = -delta_c + k as f64 * (6.0 * delta_c) / 40.0;
        let h = 1e-4 * delta_c;
        let du = (normal_spring_energy(law.normal, c, d + h) - normal_spring_energy(law.normal, c, d - h))
            / (2.0 * h);
        worst = worst.max((du - f(d)).abs() / f_c);
    }
    checks.push(Check::assert(
        "stored energy: dU/dδ = F_n from −δ_c to 5δ_c",
        worst,
        1e-6,
        "relative to F_c; central differences with a step of 1e-4·δ_c (truncation ≈1e-8·F_c, cancellation ≈1e-16·U/h)",
    ));
    checks
}

/// The checks of the run: its pull-off and its agreement with LAMMPS.
fn run_checks(run: &Run, lammps: &[Row]) -> (Vec<Check>, Comparison) {
    let (last, next) = run.stretch_at_pull_off;
    let travel = next - last;
    let mut checks = vec![Check::assert(
        "the contact ends where the stretch passes δ_c",
        (last - run.pull_off).max(0.0) / travel + (run.pull_off - next).max(0.0) / travel,
        0.0,
        format!(
            "in steps' travel: last stretch in contact {last:.6e} m ≤ δ_c = {:.6e} m < first after {next:.6e} m ({} steps in contact)",
            run.pull_off, run.contact_steps
        ),
    )];
    let cmp = compare(lammps, &run.rows, run.radius_sum);
    checks.push(Check::assert(
        "LAMMPS pair granular jkr: rows of the same steps",
        cmp.unmatched as f64,
        0.0,
        format!("{} rows matched (every {EVERY} steps)", cmp.matched),
    ));
    for (name, (e, step), scale) in [
        ("separation", cmp.sep, "the largest |overlap|"),
        ("velocity of particle 1", cmp.velocity, "the initial speed"),
        ("force on particle 1", cmp.force, "the largest force"),
    ] {
        checks.push(Check::assert(
            format!("LAMMPS pair granular jkr: {name}"),
            e,
            LAMMPS_TOLERANCE,
            format!("largest difference relative to {scale}, at step {step}"),
        ));
    }
    checks.push(Check::report(
        "sliding: largest |F_t| / (μ·|F_ne + 2F_c|)",
        run.sliding_ratio,
        "1 while the contact slides at the Coulomb limit of JKR's critical force",
    ));
    (checks, cmp)
}

fn csv(run: &Run, lammps: &[Row]) -> String {
    let mut s = String::from("step,separation_m,v1x_m_s,v1y_m_s,f1x_N,f1y_N,lammps_f1x_N,lammps_f1y_N\n");
    for r in &run.rows {
        let l = lammps.iter().find(|l| l.step == r.step);
        let (lx, ly) = l.map_or((f64::NAN, f64::NAN), |l| (l.f1[0], l.f1[1]));
        let _ = writeln!(
            s,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            r.step, r.sep, r.v1[0], r.v1[1], r.f1[0], r.f1[1], lx, ly
        );
    }
    s
}

fn figure(run: &Run, lammps: &[Row], law: &ContactLaw, c: &grainflow::contact::ContactCoeffs) -> Figure {
    let contact = |rows: &[Row]| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.f1 != [0.0, 0.0])
            .map(|r| ((run.radius_sum - r.sep) / run.pull_off, -r.f1[0] * 1e3))
            .collect()
    };
    let mut curve =
        Panel::new("Normal force against overlap", "δ/δ_c", "force on 2 along +x, mN (tension < 0)");
    let quasi: Vec<(f64, f64)> = (0..=120)
        .map(|k| -1.0 + k as f64 * 0.1)
        .map(|x| (x, elastic_force(law, c, x * run.pull_off) * 1e3))
        .collect();
    curve.series.push(Series::line("grainflow", contact(&run.rows), LineStyle::Solid, Color::BLUE));
    curve.series.push(Series::markers("LAMMPS", contact(lammps), MarkerShape::Circle, Color::ORANGE));
    curve.series.push(Series::line("elastic part (no damping)", quasi, LineStyle::Thin, Color::BLACK));
    let mut history = Panel::new("Velocity of particle 1", "step", "v₁, m/s");
    let v = |rows: &[Row], k: usize| rows.iter().map(|r| (r.step as f64, r.v1[k])).collect::<Vec<_>>();
    history.series.push(Series::line("grainflow v_x", v(&run.rows, 0), LineStyle::Solid, Color::BLUE));
    history.series.push(Series::line("grainflow v_y", v(&run.rows, 1), LineStyle::Dashed, Color::BLUE));
    let sparse = |rows: Vec<(f64, f64)>| rows.into_iter().step_by(20).collect::<Vec<_>>();
    history.series.push(Series::markers("LAMMPS", sparse(v(lammps, 0)), MarkerShape::Circle, Color::ORANGE));
    history.series.push(Series::markers("", sparse(v(lammps, 1)), MarkerShape::Circle, Color::ORANGE));
    Figure {
        title: "JKR pair: approach, adhesion, pull-off".into(),
        panels: vec![curve, history],
        note: Some("LAMMPS 2021 pair granular jkr … damping tsuji, tangential mindlin (bench/lammps/in.jkr_pair.lmp)".into()),
    }
}

/// Runs the case into `DIR/jkr/`.
pub fn run_case(dir: &Path, _options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let start = Instant::now();
    let case = case()?;
    let sim = Simulation::new(case.config, case.particles)?;
    let (law, c) = (*sim.law(), *sim.coefficients().pair(0, 0));
    let mut checks = closed_form_checks(&law, &c);
    let run = run()?;
    let lammps = parse_lammps(LAMMPS);
    let (more, cmp) = run_checks(&run, &lammps);
    checks.extend(more);
    let title = "JKR cohesion: closed forms and a pair pulled off, against LAMMPS";
    let (files, png) = crate::report::write_case_files(
        dir,
        "jkr",
        title,
        &csv(&run, &lammps),
        &figure(&run, &lammps, &law, &c),
        &checks,
    )?;
    Ok(CaseOutcome {
        name: "jkr",
        title: title.into(),
        checks,
        files,
        figures: vec![png],
        notes: vec![
            "The jkr normal model is LAMMPS's pair granular jkr with damping tsuji: the contact radius a(δ) solves δ = a²/R* − 2√(πγa/E*), the force is (4/3)E*a³/R* − 4√(πγE*)a^{3/2} plus Tsuji's dashpot on √a, a contact forms at touch and holds to −δ_c, and the Coulomb limit is μ·|F_ne + 2F_c|. γ is LAMMPS's surface energy; the work of adhesion is 2γ.".into(),
            format!(
                "From the same state LAMMPS and grainflow agree to {:.1e} in the separation, {:.1e} in the velocity and {:.1e} in the force (relative to each one's scale), over {} printed steps: the same contact, stretched past the touch and pulled off at the same step.",
                cmp.sep.0, cmp.velocity.0, cmp.force.0, cmp.matched
            ),
        ],
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}
