//! Rotating drum (`drum`): the dynamic angle of repose of glass beads in a quasi-2D tumbler in
//! the rolling regime, driven by a rotating triangle-mesh wall.
//!
//! **Set-up.** The tumbler of Brucks et al. (a quasi-2D drum of radius R = 45 mm, half full,
//! glass beads): a closed cylinder about z of radius R and width W = 10 mm, 96 flat facets with
//! flat end caps, normals inwards, built here as two meshes (the shell, rough, μ_w = 1; the end
//! caps, glass, μ = 0.3). 3 mm glass beads (d/R = 0.067; the experiment's 0.5 mm beads would be
//! 200 times as many) start on a hexagonal lattice in the lower half, settle for
//! [`SETTLE_TIME`] with the drum at rest, and the drum then turns at ω = √(Fr·g/R) about +z,
//! reached linearly over [`RAMP`]. The shell lifts the bed on its +x side; the free surface
//! rises towards +x.
//!
//! **Measurement.** Every [`SAMPLE_STEPS`] steps, two estimates of the surface angle θ:
//! - *centroid*: the centre of mass of the bed of a half-full (or any) drum with a flat surface
//!   lies on the chord's perpendicular bisector, so the angle of the line from the axis to the
//!   centroid from the downward vertical is the surface angle: θ_c = atan2(x_c, −y_c). Exact for
//!   a flat surface and a uniform bed; the S shape of a real surface and the finite grain size
//!   bias it by a degree or so (measured by the second estimate).
//! - *surface fit*: in the frame of θ_c, the chord's central 60 % (the ends curve, the "S")
//!   is cut into bins one grain wide; the highest grain centre of each bin is a surface point and
//!   a least-squares line through them gives θ_f = θ_c + atan(slope). The bins' top grains
//!   scatter by ±d/2, about 1.5° per sample over 16 bins; the mean over the steady window
//!   (hundreds of samples) is good to a few tenths of a degree.
//!
//! The steady window starts once the drum has turned [`STEADY_FROM_RAD`] (40°): the surface has
//! to be lifted from flat to its avalanche angle before it flows. Its mean and scatter are the
//! results.
//!
//! **Reference.** Sources and what they give are in docs/verification.md (Rotating drum): the
//! dependence of the angle on Fr alone, rising with Fr (Brucks, Arndt, Ottino & Lueptow, Phys.
//! Rev. E 75, 032301, 2007; their set-up as given in the APS DFD 2005 abstract), and the angle
//! measured in rotating drums for rounded grains, about 25° (Kleinhans, Markies, de Vet, in 't
//! Veld & Postema, J. Geophys. Res. 116, E11004, 2011, abstract).

use crate::check::Check;
use crate::error::VerifyError;
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions, case_dir, shipped_case, summary_markdown, write_file};
use grainflow::mesh::MeshMotion;
use grainflow::state::ParticleInit;
use grainflow::{Particles, Simulation, Vec3};
use grainflow_case::Case;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The case file: materials, contact law, time step.
pub const CASE: &str = include_str!("../cases/drum/drum.toml");
/// Drum radius, m (Brucks et al.'s tumbler).
pub const RADIUS: f64 = 0.045;
/// Drum width (between the end caps), m: 3.3 grain diameters.
pub const WIDTH: f64 = 0.010;
/// Facets around the shell (sagitta R(1 − cos(π/96)) = 24 µm, 0.8 % of d).
pub const FACETS: usize = 96;
/// Lattice spacing, in grain diameters.
pub const SPACING: f64 = 1.02;
/// The lattice fills the drum below this height, m (the axis, y = 0: half full before settling).
pub const FILL_TOP: f64 = 0.0;
/// Settling time with the drum at rest, s.
pub const SETTLE_TIME: f64 = 0.3;
/// Time over which the drum's speed rises linearly from rest, s.
pub const RAMP: f64 = 0.1;
/// The steady window starts when the drum has turned this far, rad (≈ 92°): the bed is lifted
/// to its largest angle, about 30°, at about 40° of rotation, then falls in one large avalanche
/// well below the dynamic angle and takes another 40° or so of rotation to settle into steady
/// rolling (drum.csv shows it).
pub const STEADY_FROM_RAD: f64 = 1.6;
/// Steps between two samples.
pub const SAMPLE_STEPS: u64 = 250;
/// The reduced run (CI): one Froude number, the drum turned to 3.2 rad (1.6 rad of steady window,
/// a quarter of a revolution).
pub const REDUCED: Run = Run { froude: 1e-2, turn_to_rad: 3.2 };
/// The full runs (`--converged`): the rolling range, each over half a revolution of steady window.
pub const FULL: [Run; 3] = [
    Run { froude: 1e-4, turn_to_rad: STEADY_FROM_RAD + PI },
    Run { froude: 1e-3, turn_to_rad: STEADY_FROM_RAD + PI },
    Run { froude: 1e-2, turn_to_rad: STEADY_FROM_RAD + PI },
];
/// Kleinhans et al. (2011): time-averaged angle of rounded grains in rotating drums, degrees
/// ("about 25°", abstract).
pub const KLEINHANS_ROUNDED_DEG: f64 = 25.0;
/// Tolerance of the comparison with it, degrees: the DEM angle follows the contact friction
/// (Zhou et al. 2001), which is not measured for the experiment's beads, and "about" is the
/// source's own precision.
pub const REFERENCE_TOLERANCE_DEG: f64 = 5.0;
/// Largest difference of the centroid angle's means over the two halves of the steady window,
/// degrees: a third of the ±3–4° saw tooth of the small avalanches the coarse grains still show.
pub const STEADY_DRIFT_DEG: f64 = 1.5;
/// Largest difference of the two estimates' means, degrees (the S shape and the grain size).
pub const METHODS_AGREE_DEG: f64 = 2.0;

/// One rotation speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Run {
    /// Fr = ω²R/g.
    pub froude: f64,
    /// The run ends when the drum has turned this far, rad.
    pub turn_to_rad: f64,
}

/// One sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time since the drum started, s.
    pub t: f64,
    /// Angle the drum has turned, rad.
    pub turned: f64,
    /// Centroid angle, degrees.
    pub centroid_deg: f64,
    /// Surface-fit angle, degrees.
    pub fit_deg: f64,
}

/// What one rotation speed gave.
#[derive(Debug, Clone)]
pub struct FroudeResult {
    pub run: Run,
    /// ω, rad/s.
    pub omega: f64,
    pub samples: Vec<Sample>,
    /// Mean and standard deviation over the steady window, degrees: centroid, surface fit.
    pub centroid: (f64, f64),
    pub fit: (f64, f64),
    /// Mean centroid angle over the first and the second half of the steady window, degrees.
    pub halves: (f64, f64),
    /// Samples in the steady window.
    pub steady_samples: usize,
    /// Largest penetration of a grain into the shell or a cap over the run, m.
    pub max_penetration: f64,
    /// Particles at the end (x, y), m, and the fitted surface line at the end.
    pub final_xy: Vec<(f64, f64)>,
    pub final_line: Vec<(f64, f64)>,
    /// Steps of the rotating part.
    pub steps: u64,
    pub wall_seconds: f64,
}

/// Everything `drum` produced.
#[derive(Debug, Clone)]
pub struct Report {
    pub results: Vec<FroudeResult>,
    pub particles: usize,
    pub dt: f64,
    pub full: bool,
    pub checks: Vec<Check>,
    pub wall_seconds: f64,
}

/// The shipped case, with the drum's two meshes as OBJ files generated by [`shell_obj`] and
/// [`caps_obj`].
pub fn case() -> Result<Case, VerifyError> {
    shipped_case("drum/drum.toml", CASE, &[("shell.obj", &shell_obj()), ("caps.obj", &caps_obj())])
}

/// Vertices and triangles as a Wavefront OBJ text (coordinates to the bit: Rust prints the
/// shortest text that reads back as the same double).
fn obj(what: &str, v: &[Vec3], t: &[[u32; 3]]) -> String {
    let mut s = format!("# {what}, generated by grainflow-verify (drum.rs)\n");
    for p in v {
        let _ = writeln!(s, "v {:?} {:?} {:?}", p.x, p.y, p.z);
    }
    for f in t {
        let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    s
}

/// The shell: `FACETS` facets about z, corners on the circle of radius R, |z| ≤ W/2, normals
/// towards the axis.
pub fn shell_obj() -> String {
    let h = 0.5 * WIDTH;
    let mut v = Vec::with_capacity(2 * FACETS);
    for k in 0..FACETS {
        let a = TAU * k as f64 / FACETS as f64;
        v.push(Vec3::new(RADIUS * a.cos(), RADIUS * a.sin(), -h));
        v.push(Vec3::new(RADIUS * a.cos(), RADIUS * a.sin(), h));
    }
    let (lo, hi) = (|k: usize| (2 * (k % FACETS)) as u32, |k: usize| (2 * (k % FACETS) + 1) as u32);
    let mut t = Vec::with_capacity(2 * FACETS);
    for k in 0..FACETS {
        t.push([lo(k), hi(k + 1), lo(k + 1)]);
        t.push([lo(k), hi(k), hi(k + 1)]);
    }
    obj("drum shell", &v, &t)
}

/// The two end caps at z = ∓W/2, fans about their centres, normals into the drum (±z).
pub fn caps_obj() -> String {
    let h = 0.5 * WIDTH;
    let mut v = vec![Vec3::new(0.0, 0.0, -h), Vec3::new(0.0, 0.0, h)];
    for k in 0..FACETS {
        let a = TAU * k as f64 / FACETS as f64;
        v.push(Vec3::new(RADIUS * a.cos(), RADIUS * a.sin(), -h));
        v.push(Vec3::new(RADIUS * a.cos(), RADIUS * a.sin(), h));
    }
    let (lo, hi) = (|k: usize| (2 + 2 * (k % FACETS)) as u32, |k: usize| (3 + 2 * (k % FACETS)) as u32);
    let mut t = Vec::with_capacity(2 * FACETS);
    for k in 0..FACETS {
        t.push([0, lo(k), lo(k + 1)]);
        t.push([1, hi(k + 1), hi(k)]);
    }
    obj("drum end caps", &v, &t)
}

/// The grains on a hexagonal lattice (rows along x, layers along z) inside the drum, below
/// [`FILL_TOP`], at least a grain radius plus 2 % from the shell and the caps; ids from 1 in
/// lattice order.
pub fn lattice(template: &ParticleInit) -> Vec<ParticleInit> {
    let r = template.radius;
    let s = SPACING * 2.0 * r;
    let row = s * 3f64.sqrt() / 2.0;
    let inner = RADIUS - 1.02 * r;
    let zs: Vec<f64> = {
        let mut z = -0.5 * WIDTH + 1.02 * r;
        let mut zs = Vec::new();
        while z <= 0.5 * WIDTH - 1.02 * r + 1e-12 {
            zs.push(z);
            z += s;
        }
        zs
    };
    let mut out = Vec::new();
    for (layer, &z) in zs.iter().enumerate() {
        let mut j = 0;
        loop {
            let y = -inner + j as f64 * row;
            if y > FILL_TOP - r {
                break;
            }
            let shift = if (j + layer) % 2 == 1 { 0.5 * s } else { 0.0 };
            let half = (inner * inner - y * y).max(0.0).sqrt();
            let mut x = -half + shift;
            while x <= half {
                if x * x + y * y <= inner * inner {
                    out.push(ParticleInit {
                        id: out.len() as u32 + 1,
                        position: Vec3::new(x, y, z),
                        velocity: Vec3::ZERO,
                        omega: Vec3::ZERO,
                        ..*template
                    });
                }
                x += s;
            }
            j += 1;
        }
    }
    out
}

/// θ_c and θ_f of the grains at `p` (degrees), and the fitted line's two ends, m.
fn angles(p: &[Vec3], d: f64) -> (f64, f64, [(f64, f64); 2]) {
    let n = p.len() as f64;
    let (xc, yc) = p.iter().fold((0.0, 0.0), |(a, b), q| (a + q.x, b + q.y));
    let (xc, yc) = (xc / n, yc / n);
    let theta = xc.atan2(-yc);
    let (u, nn) = ((theta.cos(), theta.sin()), (-theta.sin(), theta.cos()));
    let su: Vec<(f64, f64)> = p.iter().map(|q| (q.x * u.0 + q.y * u.1, q.x * nn.0 + q.y * nn.1)).collect();
    let (smin, smax) =
        su.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| (a.min(q.0), b.max(q.0)));
    let (mid, half) = (0.5 * (smin + smax), 0.3 * (smax - smin));
    let bins = ((2.0 * half) / d).floor().max(1.0) as usize;
    let mut top = vec![f64::NEG_INFINITY; bins];
    for &(s, h) in &su {
        let k = ((s - (mid - half)) / d).floor();
        if k >= 0.0 && (k as usize) < bins {
            top[k as usize] = top[k as usize].max(h);
        }
    }
    let pts: Vec<(f64, f64)> = top
        .iter()
        .enumerate()
        .filter(|(_, h)| h.is_finite())
        .map(|(k, &h)| (mid - half + (k as f64 + 0.5) * d, h))
        .collect();
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), q| (a + q.0, b + q.1));
    let (mx, my) = (sx / m, sy / m);
    let (sxx, sxy) =
        pts.iter().fold((0.0, 0.0), |(a, b), q| (a + (q.0 - mx).powi(2), b + (q.0 - mx) * (q.1 - my)));
    let slope = sxy / sxx;
    let fit = theta + slope.atan();
    let at = |s: f64| {
        let h = my + slope * (s - mx);
        (s * u.0 + h * nn.0, s * u.1 + h * nn.1)
    };
    (theta.to_degrees(), fit.to_degrees(), [at(smin), at(smax)])
}

fn mean_std(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = v.clone().count() as f64;
    let m = v.clone().sum::<f64>() / n;
    (m, (v.map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt())
}

/// Deepest penetration of a grain into the shell or a cap, m (0 if none), with the drum turned
/// by `turned` rad: the distance past the plane of the facet the grain faces.
fn penetration(p: &Particles, turned: f64) -> f64 {
    let sector = TAU / FACETS as f64;
    (0..p.len())
        .map(|i| {
            let (x, r) = (p.position[i], p.radius[i]);
            let phi = (x.y.atan2(x.x) - turned).rem_euclid(TAU);
            let mid = ((phi / sector).floor() + 0.5) * sector + turned;
            let radial = x.x * mid.cos() + x.y * mid.sin() + r - RADIUS * (0.5 * sector).cos();
            let axial = x.z.abs() + r - 0.5 * WIDTH;
            radial.max(axial).max(0.0)
        })
        .fold(0.0, f64::max)
}

/// The settled bed: the lattice dropped into the drum at rest.
fn settled(base: &Case) -> Result<Particles, VerifyError> {
    let p = &base.particles;
    let template = ParticleInit {
        id: 1,
        phase: p.phase[0],
        radius: p.radius[0],
        density: p.mass[0] / (4.0 / 3.0 * PI * p.radius[0].powi(3)),
        position: Vec3::ZERO,
        velocity: Vec3::ZERO,
        omega: Vec3::ZERO,
    };
    let mut c = base.config.clone();
    c.t_stop = SETTLE_TIME;
    let mut sim = Simulation::new(c, Particles::from_init(&lattice(&template)))?;
    sim.run_to_end();
    let p = sim.particles();
    Ok(p.gathered(&p.id_order()))
}

fn run_froude(base: &Case, bed: &Particles, run: Run) -> Result<FroudeResult, VerifyError> {
    let start = Instant::now();
    let g = base.config.gravity.length();
    let omega = (run.froude * g / RADIUS).sqrt();
    let motion = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega, ramp: RAMP };
    let mut c = base.config.clone();
    for m in &mut c.meshes {
        m.motion = motion;
    }
    // Time to turn `turn_to_rad` with the ramp: ω(t − RAMP/2).
    c.t_stop = run.turn_to_rad / omega + 0.5 * RAMP;
    let d = 2.0 * bed.radius[0];
    let mut sim = Simulation::new(c, bed.clone())?;
    let steps = sim.total_steps();
    let mut samples = Vec::new();
    let mut max_pen = 0.0f64;
    sim.run_with(steps, |s| {
        if s.step_index() % SAMPLE_STEPS == 0 {
            let t = s.time();
            let (tc, tf, _) = angles(&s.particles().position, d);
            samples.push(Sample { t, turned: motion.angle(t), centroid_deg: tc, fit_deg: tf });
            max_pen = max_pen.max(penetration(s.particles(), motion.angle(t)));
        }
    });
    let steady = || samples.iter().filter(|s| s.turned >= STEADY_FROM_RAD);
    let centroid = mean_std(steady().map(|s| s.centroid_deg));
    let fit = mean_std(steady().map(|s| s.fit_deg));
    let n = steady().count();
    let halves = (
        mean_std(steady().take(n / 2).map(|s| s.centroid_deg)).0,
        mean_std(steady().skip(n / 2).map(|s| s.centroid_deg)).0,
    );
    let p = sim.particles();
    let (_, _, line) = angles(&p.position, d);
    Ok(FroudeResult {
        run,
        omega,
        steady_samples: steady().count(),
        centroid,
        fit,
        halves,
        max_penetration: max_pen.max(penetration(p, motion.angle(sim.time()))),
        final_xy: p.position.iter().map(|x| (x.x, x.y)).collect(),
        final_line: line.to_vec(),
        samples,
        steps,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Runs the reduced case, or with `full` the three Froude numbers of the rolling range (in
/// parallel), and evaluates the checks; writes nothing.
pub fn evaluate(full: bool) -> Result<Report, VerifyError> {
    let start = Instant::now();
    let base = case()?;
    let bed = settled(&base)?;
    let runs: Vec<Run> = if full { FULL.to_vec() } else { vec![REDUCED] };
    let results: Vec<FroudeResult> =
        runs.par_iter().map(|&r| run_froude(&base, &bed, r)).collect::<Result<_, _>>()?;
    let dt = match base.config.time_step {
        grainflow::TimeStepRule::Fixed(dt) => dt,
        grainflow::TimeStepRule::Mfix { .. } => f64::NAN,
    };
    let d = 2.0 * bed.radius[0];
    let mut checks = Vec::new();
    for r in &results {
        let fr = format!("Fr = {:.0e}", r.run.froude);
        checks.push(Check::assert(
            format!("{fr}: the grains stay inside the turning drum"),
            r.max_penetration / d,
            0.05,
            "deepest penetration of a grain past the plane of the facet it faces or past a cap, over the run, in grain diameters (sampled every 250 steps); elastic overlaps at k_n = 500 N/m are ≈ 0.5 % of d under the bed's weight and a few % in the first avalanche; a grain that crossed a facet, a seam or the crease would be at ≥ 1",
        ));
        checks.push(Check::assert(
            format!("{fr}: steady state, the angle's mean over the two halves of the window"),
            (r.halves.0 - r.halves.1).abs(),
            STEADY_DRIFT_DEG,
            format!(
                "|mean θ_c, first half − second half|, degrees: {:.2}° vs {:.2}° over {} samples once the drum has turned {:.0}°; the bed has forgotten its start when the two agree within a third of the avalanche amplitude",
                r.halves.0,
                r.halves.1,
                r.steady_samples,
                STEADY_FROM_RAD.to_degrees()
            ),
        ));
        checks.push(Check::report(
            format!("{fr}: scatter of the centroid angle over the steady window (degrees)"),
            r.centroid.1,
            format!(
                "standard deviation, mean {:.2}°; continuous rolling would be well under a degree: with 3 mm grains in a 45 mm drum (d/R = 1/15, Brucks et al. had 1/90) the surface still moves in small avalanches, a saw tooth of ±3–4°",
                r.centroid.0
            ),
        ));
        checks.push(Check::assert(
            format!("{fr}: surface fit agrees with the centroid angle"),
            (r.fit.0 - r.centroid.0).abs(),
            METHODS_AGREE_DEG,
            format!(
                "|mean θ_fit − mean θ_centroid|, degrees: {:.2}° vs {:.2}° (θ_fit scatter {:.2}°); they differ by the S shape of the surface and the grain size",
                r.fit.0, r.centroid.0, r.fit.1
            ),
        ));
        checks.push(Check::assert(
            format!("{fr}: dynamic angle vs rotating-drum measurements of rounded grains (≈ 25°, Kleinhans et al. 2011)"),
            (r.fit.0 - KLEINHANS_ROUNDED_DEG).abs(),
            REFERENCE_TOLERANCE_DEG,
            format!(
                "|θ_fit − 25°|, degrees: θ_fit = {:.2}° ± {:.2}° (scatter). The source gives \"about 25°\" for rounded grains at 0.1–1 g; the DEM angle follows the contact friction (μ = 0.3 here), not measured for the beads",
                r.fit.0, r.fit.1
            ),
        ));
    }
    if full {
        let worst = results.windows(2).map(|w| w[0].fit.0 - w[1].fit.0).fold(f64::NEG_INFINITY, f64::max);
        // Reported, not asserted: at d/R = 1/15 the surface flows in small avalanches at every
        // Fr of the sweep, and their saw tooth (±3–5°, one tooth per ~25° of rotation) leaves a
        // standard error of 1–2° on each mean, as large as the rise to be resolved
        // (docs/verification.md, Rotating drum: the full sweep does not show it).
        checks.push(Check::report(
            "the angle rises with Fr (Brucks et al. 2007): largest fall of the mean θ_f from one Fr to the next (degrees; reported)",
            worst,
            format!(
                "positive = the angle fell where it should rise; {}; not resolved at this grain size (the avalanches' scatter is as large as the rise)",
                results
                    .iter()
                    .map(|r| format!("Fr = {:.0e}: θ_f {:.2}°, θ_c {:.2}° (scatter {:.1}°)", r.run.froude, r.fit.0, r.centroid.0, r.centroid.1))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    } else {
        checks.push(Check::skipped(
            "the angle rises with Fr (Brucks et al. 2007; reported)",
            "run with --converged: Fr = 1e-4, 1e-3, 1e-2, half a revolution each",
        ));
    }
    Ok(Report {
        results,
        particles: bed.len(),
        dt,
        full,
        checks,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

fn figure(report: &Report) -> Figure {
    let mut time = Vec::new();
    for (k, r) in report.results.iter().enumerate() {
        let c = Color::palette(k);
        let fr = format!("Fr = {:.0e}", r.run.froude);
        time.push(Series::line(
            format!("{fr}, surface fit"),
            r.samples.iter().map(|s| (s.turned.to_degrees(), s.fit_deg)).collect(),
            LineStyle::Solid,
            c,
        ));
        time.push(Series::line(
            format!("{fr}, centroid"),
            r.samples.iter().map(|s| (s.turned.to_degrees(), s.centroid_deg)).collect(),
            LineStyle::Dashed,
            c,
        ));
    }
    let turned_max = report.results.iter().map(|r| r.run.turn_to_rad.to_degrees()).fold(0.0, f64::max);
    time.push(Series::line(
        "≈ 25°, rounded grains (Kleinhans et al. 2011)",
        vec![(0.0, KLEINHANS_ROUNDED_DEG), (turned_max, KLEINHANS_ROUNDED_DEG)],
        LineStyle::Thin,
        Color::BLACK,
    ));
    time.push(Series::line(
        "steady window starts",
        vec![(STEADY_FROM_RAD.to_degrees(), 0.0), (STEADY_FROM_RAD.to_degrees(), 40.0)],
        LineStyle::Thin,
        Color::GREY,
    ));
    let last = report.results.last();
    let mm = |v: &[(f64, f64)]| v.iter().map(|&(x, y)| (1e3 * x, 1e3 * y)).collect::<Vec<_>>();
    let circle: Vec<(f64, f64)> = (0..=200)
        .map(|k| TAU * k as f64 / 200.0)
        .map(|a| (1e3 * RADIUS * a.cos(), 1e3 * RADIUS * a.sin()))
        .collect();
    let mut snap = vec![Series::line("drum", circle, LineStyle::Thin, Color::GREY)];
    if let Some(r) = last {
        snap.push(Series::markers(
            "grain centres (all layers)",
            mm(&r.final_xy),
            MarkerShape::Circle,
            Color::BLUE,
        ));
        snap.push(Series::line(
            format!("surface fit at the end, {:.1}°", angles_of_line(&r.final_line)),
            mm(&r.final_line),
            LineStyle::Solid,
            Color::RED,
        ));
    }
    let mut panels = vec![
        Panel {
            series: time,
            y_range: Some((0.0, 40.0)),
            ..Panel::new("Surface angle while the drum turns", "drum turned (deg)", "surface angle θ (deg)")
        },
        Panel {
            series: snap,
            x_range: Some((-50.0, 50.0)),
            y_range: Some((-50.0, 50.0)),
            ..Panel::new(
                format!(
                    "The bed at the end{}",
                    last.map_or(String::new(), |r| format!(", Fr = {:.0e}", r.run.froude))
                ),
                "x (mm)",
                "y (mm)",
            )
        },
    ];
    let pts: Vec<(f64, f64)> = report.results.iter().map(|r| (r.run.froude.log10(), r.fit.0)).collect();
    let band = |dy: f64| vec![(-4.2, KLEINHANS_ROUNDED_DEG + dy), (-1.8, KLEINHANS_ROUNDED_DEG + dy)];
    panels.push(Panel {
        series: vec![
            Series::markers(
                "grainflow, surface fit (mean over the steady window)",
                pts.clone(),
                MarkerShape::Square,
                Color::RED,
            ),
            Series::markers(
                "grainflow, centroid",
                report.results.iter().map(|r| (r.run.froude.log10(), r.centroid.0)).collect(),
                MarkerShape::Cross,
                Color::BLUE,
            ),
            Series::line(
                "≈ 25°, rounded grains (Kleinhans et al. 2011)",
                band(0.0),
                LineStyle::Solid,
                Color::BLACK,
            ),
            Series::line("± 5° (tolerance)", band(REFERENCE_TOLERANCE_DEG), LineStyle::Dashed, Color::GREY),
            Series::line("", band(-REFERENCE_TOLERANCE_DEG), LineStyle::Dashed, Color::GREY),
        ],
        x_range: Some((-4.2, -1.8)),
        y_range: Some((10.0, 40.0)),
        ..Panel::new("Dynamic angle vs Froude number", "log₁₀ Fr = log₁₀(ω²R/g)", "dynamic angle θ (deg)")
    });
    Figure {
        title: "Rotating drum, rolling regime: dynamic angle of repose".into(),
        note: Some(format!(
            "{} glass beads d = 3 mm in a drum R = 45 mm, W = 10 mm (mesh walls turning about z); LSD, μ = 0.3 (caps 0.3, shell 1.0), e_n = 0.9; {}",
            report.particles,
            if report.full {
                "Fr = 1e-4, 1e-3, 1e-2"
            } else {
                "reduced run: Fr = 1e-2 only (--converged for the sweep)"
            }
        )),
        panels,
    }
}

fn angles_of_line(l: &[(f64, f64)]) -> f64 {
    match l {
        [a, b] => (b.1 - a.1).atan2(b.0 - a.0).to_degrees(),
        _ => f64::NAN,
    }
}

/// The suite entry: runs, writes `DIR/drum/` and reports.
pub fn run_case(dir: &Path, options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let report = evaluate(options.converged)?;
    let out = case_dir(dir, "drum")?;
    let mut files = Vec::new();
    let mut csv = String::from("froude,t_s,drum_turned_deg,theta_centroid_deg,theta_fit_deg\n");
    for r in &report.results {
        for s in &r.samples {
            let _ = writeln!(
                csv,
                "{:e},{:.5},{:.4},{:.4},{:.4}",
                r.run.froude,
                s.t,
                s.turned.to_degrees(),
                s.centroid_deg,
                s.fit_deg
            );
        }
    }
    write_file(out.join("drum.csv"), &csv, &mut files)?;
    let mut by_fr = String::from(
        "froude,omega_rad_s,rpm,steady_samples,theta_centroid_mean_deg,theta_centroid_std_deg,theta_fit_mean_deg,theta_fit_std_deg,steps,wall_seconds\n",
    );
    for r in &report.results {
        let _ = writeln!(
            by_fr,
            "{:e},{:.6},{:.4},{},{:.4},{:.4},{:.4},{:.4},{},{:.2}",
            r.run.froude,
            r.omega,
            r.omega * 60.0 / TAU,
            r.steady_samples,
            r.centroid.0,
            r.centroid.1,
            r.fit.0,
            r.fit.1,
            r.steps,
            r.wall_seconds
        );
    }
    write_file(out.join("drum_angles.csv"), &by_fr, &mut files)?;
    let png = crate::report::write_figure(&out, "drum", &figure(&report), &mut files)?;
    let title = "rotating drum: dynamic angle of repose in the rolling regime";
    let mut summary = summary_markdown(title, &report.checks);
    let _ = write!(
        summary,
        "\n{} grains, Δt = {:.1e} s, settled {} s, ramp {} s; steady window from {:.0}° of drum rotation; {:.2} s.\n",
        report.particles,
        report.dt,
        SETTLE_TIME,
        RAMP,
        STEADY_FROM_RAD.to_degrees(),
        report.wall_seconds
    );
    write_file(out.join("summary.md"), &summary, &mut files)?;
    let mut notes = vec![format!(
        "A quasi-2D tumbler (R = 45 mm as Brucks et al.'s, W = 10 mm) of two triangle meshes turning about its axis, half filled with {} 3 mm glass beads settled from a lattice. The surface angle is measured from the bed's centroid and by a line fitted to the top grains of the chord's central 60 %. The reference is the angle of rounded grains in rotating drums, about 25° (Kleinhans et al. 2011), and the dependence on Fr alone, rising with it (Brucks et al. 2007); no published table of angle against Fr for this set-up was available, see docs/verification.md.",
        report.particles
    )];
    if !report.full {
        notes.push("Reduced run (Fr = 1e-2, an eighth of a revolution of steady flow). Run with --converged for Fr = 1e-4, 1e-3 and 1e-2 over half a revolution each and the check that the angle rises with Fr.".into());
    }
    Ok(CaseOutcome {
        name: "drum",
        title: title.into(),
        checks: report.checks,
        files,
        figures: vec![png],
        notes,
        wall_seconds: report.wall_seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat bed at angle θ: both estimates give θ.
    #[test]
    fn angles_of_a_flat_tilted_half_disc() {
        let d = 0.003;
        for deg in [0.0f64, 15.0, 27.0] {
            let t = deg.to_radians();
            let (u, n) = ((t.cos(), t.sin()), (-t.sin(), t.cos()));
            let mut p = Vec::new();
            let step = 0.001;
            let m = (RADIUS / step) as i32;
            for i in -m..=m {
                for j in -m..=0 {
                    let (s, h) = (i as f64 * step, j as f64 * step);
                    if s * s + h * h < RADIUS * RADIUS {
                        p.push(Vec3::new(s * u.0 + h * n.0, s * u.1 + h * n.1, 0.0));
                    }
                }
            }
            let (c, f, _) = angles(&p, d);
            assert!((c - deg).abs() < 0.2, "centroid {c} vs {deg}");
            assert!((f - deg).abs() < 0.2, "fit {f} vs {deg}");
        }
    }

    #[test]
    fn meshes_build_and_the_lattice_fits() {
        let base = case().expect("the case and its meshes load");
        assert_eq!(base.config.meshes.len(), 2);
        let p = &base.particles;
        let template = ParticleInit {
            id: 1,
            phase: 0,
            radius: p.radius[0],
            density: 2500.0,
            position: Vec3::ZERO,
            velocity: Vec3::ZERO,
            omega: Vec3::ZERO,
        };
        let l = lattice(&template);
        assert!(l.len() > 500, "{}", l.len());
        assert_eq!(penetration(&Particles::from_init(&l), 0.0), 0.0);
    }
}
