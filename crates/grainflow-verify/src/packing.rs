//! Poured packing (`packing`): the bulk volume fraction of monodisperse spheres poured onto a
//! flat floor, against random close packing for frictionless spheres and its fall with
//! friction.
//!
//! **Set-up** (`cases/packing/packing.toml`). A box 10 × 10 bead diameters across, periodic in
//! x and y, with a flat floor at z = 0 and an open top; 2 400 beads of d = 4 mm poured at a
//! rate (16 000 per second, a batch every 20 ms placed at random in a layer near the top, at
//! 1.5 m/s downwards), then left to settle for [`SETTLE_TIME`]. Strong damping (e = 0.3). One
//! run per friction coefficient μ (between beads and against the floor alike), in parallel.
//!
//! **Measurement.** The volume fraction of a horizontal slab, the volume of the beads inside
//! it (each sphere's exact intersection with the slab) over the slab's volume. The slab runs
//! from [`FLOOR_GAP`] bead diameters above the floor (a flat floor orders the first layers:
//! the profile φ(z), written out, oscillates there and is flat beyond) to [`SURFACE_GAP`]
//! below the bed's height H = V_solid/(φ_rcp L²), which is below the true surface for any
//! φ ≤ φ_rcp (the last layers to arrive are looser). About 12 d thick: some 1 400 beads.
//!
//! **Reference.** Silbert, Ertaş, Grest, Halsey & Levine, Phys. Rev. E 65, 031304 (2002):
//! frictionless packings at φ ≈ 0.64 (random close packing), frictional ones looser, falling
//! with μ to about 0.59–0.60 at μ ≥ 0.5; Agnolin & Roux, Phys. Rev. E 76, 061302 (2007):
//! frictionless assemblies at φ_RCP ≈ 0.639, with μ = 0.3 at φ ≈ 0.593. See
//! docs/verification.md (Poured packing).

use crate::check::Check;
use crate::error::VerifyError;
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};
use crate::report::{CaseOutcome, SuiteOptions, case_dir, shipped_case, summary_markdown, write_file};
use grainflow::{Particles, Simulation};
use grainflow_case::Case;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The case file.
pub const CASE: &str = include_str!("../cases/packing/packing.toml");
/// Settling time after the last batch, s.
pub const SETTLE_TIME: f64 = 0.4;
/// The slab starts this many bead diameters above the floor.
pub const FLOOR_GAP: f64 = 5.0;
/// The slab ends this many bead diameters below the bed's height H = V/(φ_rcp L²).
pub const SURFACE_GAP: f64 = 3.0;
/// Random close packing of equal spheres (Silbert et al. 2002; Agnolin & Roux 2007: 0.639).
pub const PHI_RCP: f64 = 0.64;
/// Tolerance on the frictionless φ: see [`evaluate`].
pub const RCP_TOLERANCE: f64 = 0.015;
/// Friction coefficients of the reduced run.
pub const REDUCED_MU: [f64; 3] = [0.0, 0.1, 0.5];
/// Friction coefficients of the full run (`--converged`).
pub const FULL_MU: [f64; 7] = [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 1.0];
/// Bin width of the profile φ(z), in bead diameters.
pub const PROFILE_BIN: f64 = 0.25;

/// What one friction coefficient gave.
#[derive(Debug, Clone)]
pub struct MuResult {
    pub mu: f64,
    /// Volume fraction of the slab.
    pub phi: f64,
    /// The slab, m.
    pub slab: (f64, f64),
    /// φ over the lower and the upper half of the slab.
    pub halves: (f64, f64),
    /// The profile (z in d, φ).
    pub profile: Vec<(f64, f64)>,
    pub beads: usize,
    /// Largest and root-mean-square speed at the end, m/s.
    pub speeds: (f64, f64),
    /// Beads the insertion could not place.
    pub missed: u64,
    pub steps: u64,
    pub wall_seconds: f64,
}

/// Everything `packing` produced.
#[derive(Debug, Clone)]
pub struct Report {
    pub results: Vec<MuResult>,
    pub d: f64,
    pub dt: f64,
    pub full: bool,
    pub checks: Vec<Check>,
    pub wall_seconds: f64,
}

/// The shipped case.
pub fn case() -> Result<Case, VerifyError> {
    shipped_case("packing/packing.toml", CASE, &[])
}

/// Volume of the sphere of radius `r` centred at height `c` between the planes z1 < z2.
pub fn slab_volume(c: f64, r: f64, z1: f64, z2: f64) -> f64 {
    let (a, b) = ((z1 - c).max(-r), (z2 - c).min(r));
    if b <= a {
        return 0.0;
    }
    let f = |u: f64| PI * (r * r * u - u * u * u / 3.0);
    f(b) - f(a)
}

/// Volume fraction of the slab z1 < z < z2 of a box of cross-section `area`.
pub fn slab_fraction(p: &Particles, area: f64, z1: f64, z2: f64) -> f64 {
    let v: f64 = (0..p.len()).map(|i| slab_volume(p.position[i].z, p.radius[i], z1, z2)).sum();
    v / (area * (z2 - z1))
}

fn run_mu(base: &Case, mu: f64) -> Result<MuResult, VerifyError> {
    let start = Instant::now();
    let mut c = base.config.clone();
    for p in c.pair_params.iter_mut().chain(c.wall_params.iter_mut()) {
        p.mu = mu;
    }
    let ins = c.insertions.first().ok_or_else(|| VerifyError::Case {
        case: "packing/packing.toml".into(),
        source: grainflow_case::CaseError::Syntax("the packing case needs its [[insertions]] table".into()),
    })?;
    // The pour's length: count / rate, rounded up to whole batches.
    let pour = match (ins.amount, ins.schedule) {
        (
            Some(grainflow::insertion::Amount::Count(n)),
            grainflow::insertion::Schedule::Rate {
                rate: grainflow::insertion::Rate::Particles(r),
                every,
                ..
            },
        ) => ((n as f64 / r) / every).ceil() * every,
        _ => 1.0,
    };
    c.t_start = 0.0;
    c.t_stop = pour + SETTLE_TIME;
    let (lo, hi) = base.domain;
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    let mut sim = Simulation::new(c, Particles::default())?;
    sim.run_to_end();
    let books = sim.flow_books();
    let p = sim.particles();
    let d = 2.0 * p.radius.iter().copied().fold(0.0, f64::max);
    let solid: f64 = p.radius.iter().map(|r| 4.0 / 3.0 * PI * r.powi(3)).sum();
    let h = solid / (PHI_RCP * area);
    let slab = (lo.z + FLOOR_GAP * d, lo.z + h - SURFACE_GAP * d);
    let phi = slab_fraction(p, area, slab.0, slab.1);
    let mid = 0.5 * (slab.0 + slab.1);
    let halves = (slab_fraction(p, area, slab.0, mid), slab_fraction(p, area, mid, slab.1));
    let top = p.position.iter().map(|x| x.z).fold(0.0, f64::max) + d;
    let bin = PROFILE_BIN * d;
    let profile = (0..((top - lo.z) / bin).ceil() as usize)
        .map(|k| {
            let z1 = lo.z + k as f64 * bin;
            ((z1 + 0.5 * bin - lo.z) / d, slab_fraction(p, area, z1, z1 + bin))
        })
        .collect();
    let max = p.velocity.iter().map(|v| v.length()).fold(0.0, f64::max);
    let rms = (p.velocity.iter().map(|v| v.length_squared()).sum::<f64>() / p.len().max(1) as f64).sqrt();
    Ok(MuResult {
        mu,
        phi,
        slab,
        halves,
        profile,
        beads: p.len(),
        speeds: (max, rms),
        missed: books.missed.iter().sum(),
        steps: sim.step_index(),
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Runs the reduced set of friction coefficients, or with `full` the full one (in parallel),
/// and evaluates the checks; writes nothing.
pub fn evaluate(full: bool) -> Result<Report, VerifyError> {
    let start = Instant::now();
    let base = case()?;
    let mus: Vec<f64> = if full { FULL_MU.to_vec() } else { REDUCED_MU.to_vec() };
    let results: Vec<MuResult> = mus.par_iter().map(|&mu| run_mu(&base, mu)).collect::<Result<_, _>>()?;
    let d = base.config.phases[0].diameter;
    let dt = match base.config.time_step {
        grainflow::TimeStepRule::Fixed(dt) => dt,
        _ => Simulation::new(base.config.clone(), base.particles.clone()).map(|s| s.dt()).unwrap_or(f64::NAN),
    };
    let mut checks = Vec::new();
    for r in &results {
        let name = format!("μ = {}", r.mu);
        checks.push(Check::assert(
            format!("{name}: every bead poured, and the bed at rest"),
            r.speeds.1 + r.missed as f64,
            0.01,
            format!(
                "root-mean-square speed at the end, m/s (largest {:.3} m/s), plus the beads the insertion could not place ({}): below 1 cm/s, a fall of 5 µm",
                r.speeds.0, r.missed
            ),
        ));
        checks.push(Check::assert(
            format!("{name}: the slab is uniform (φ of its lower and upper halves)"),
            (r.halves.0 - r.halves.1).abs(),
            0.02,
            format!(
                "|φ_lower − φ_upper| = |{:.4} − {:.4}|; each half holds some 700 beads, whose count scatters by a few per cent of √700/700 ≈ 0.004 in φ, and the floor's layering (decaying within a few d) would show as a difference of a few 0.01",
                r.halves.0, r.halves.1
            ),
        ));
    }
    if let Some(r0) = results.iter().find(|r| r.mu == 0.0) {
        checks.push(Check::assert(
            "μ = 0: random close packing, φ ≈ 0.64 (Silbert et al. 2002; Agnolin & Roux 2007: 0.639)",
            (r0.phi - PHI_RCP).abs(),
            RCP_TOLERANCE,
            format!(
                "|φ − 0.64|, φ = {:.4} in z = {:.1}–{:.1} d; the tolerance: the published values of φ_rcp spread over 0.634–0.645, the slab's ~1 400 beads scatter by ≈ 0.004, and the elastic overlaps under the bed's weight add ≲ 0.003",
                r0.phi,
                r0.slab.0 / d,
                r0.slab.1 / d
            ),
        ));
    }
    let rise = results.windows(2).map(|w| w[1].phi - w[0].phi).fold(f64::NEG_INFINITY, f64::max);
    checks.push(Check::assert(
        "φ decreases monotonically with μ (Silbert et al. 2002)",
        rise,
        0.0,
        format!(
            "largest rise of φ from one μ to the next (must be ≤ 0): {}",
            results.iter().map(|r| format!("μ = {}: φ = {:.4}", r.mu, r.phi)).collect::<Vec<_>>().join(", ")
        ),
    ));
    if let Some(r5) = results.iter().find(|r| r.mu == 0.5) {
        checks.push(Check::report(
            "μ = 0.5: φ against ≈ 0.59–0.60 (Silbert et al. 2002; reported)",
            r5.phi - 0.595,
            format!(
                "φ − 0.595, φ = {:.4}; a poured frictional packing's φ depends on the pouring (rate, height, damping) as well as on μ, so this is reported, not asserted",
                r5.phi
            ),
        ));
    }
    Ok(Report { results, d, dt, full, checks, wall_seconds: start.elapsed().as_secs_f64() })
}

fn figure(report: &Report) -> Figure {
    let mu_max = report.results.iter().map(|r| r.mu).fold(0.0, f64::max).max(0.5) * 1.05;
    let phis = vec![
        Series::markers(
            "grainflow (slab away from the floor and the surface)",
            report.results.iter().map(|r| (r.mu, r.phi)).collect(),
            MarkerShape::Square,
            Color::RED,
        ),
        Series::line(
            "random close packing, 0.64",
            vec![(0.0, PHI_RCP), (mu_max, PHI_RCP)],
            LineStyle::Dashed,
            Color::BLACK,
        ),
        Series::line(
            "≈ 0.59–0.60 at μ ≥ 0.5 (Silbert et al. 2002)",
            vec![(0.5, 0.595), (mu_max, 0.595)],
            LineStyle::Solid,
            Color::GREY,
        ),
        Series::markers(
            "μ = 0.3: 0.593 (Agnolin & Roux 2007)",
            vec![(0.3, 0.593)],
            MarkerShape::Cross,
            Color::BLUE,
        ),
    ];
    let mut prof = Vec::new();
    for (i, r) in report.results.iter().enumerate() {
        prof.push(Series::line(
            format!("μ = {}", r.mu),
            r.profile.iter().map(|&(z, p)| (p, z)).collect(),
            LineStyle::Solid,
            Color::palette(i),
        ));
    }
    if let Some(r) = report.results.first() {
        for z in [r.slab.0, r.slab.1] {
            prof.push(Series::line(
                "",
                vec![(0.0, z / report.d), (1.0, z / report.d)],
                LineStyle::Thin,
                Color::GREY,
            ));
        }
    }
    Figure {
        title: "Poured packing of monodisperse spheres: volume fraction against friction".into(),
        note: Some(format!(
            "2 400 beads d = {:.0} mm poured into a 10 d × 10 d box periodic in x and y onto a flat floor; Hertz–Mindlin E = 5 MPa, e = 0.3; {}",
            1e3 * report.d,
            if report.full {
                "full run"
            } else {
                "reduced run: μ = 0, 0.1, 0.5 (--converged for seven values)"
            }
        )),
        panels: vec![
            Panel {
                series: phis,
                x_range: Some((0.0, mu_max)),
                y_range: Some((0.55, 0.67)),
                ..Panel::new(
                    "Bulk volume fraction against the friction coefficient",
                    "μ",
                    "volume fraction φ",
                )
            },
            Panel {
                series: prof,
                x_range: Some((0.0, 1.0)),
                ..Panel::new(
                    "Profiles φ(z) (bins of d/4); thin: the slab",
                    "volume fraction φ",
                    "height z / d",
                )
            },
        ],
    }
}

/// The suite entry: runs, writes `DIR/packing/` and reports.
pub fn run_case(dir: &Path, options: &SuiteOptions) -> Result<CaseOutcome, VerifyError> {
    let report = evaluate(options.converged)?;
    let out = case_dir(dir, "packing")?;
    let mut files = Vec::new();
    let mut csv = String::from(
        "mu,phi,slab_bottom_m,slab_top_m,phi_lower_half,phi_upper_half,beads,rms_speed_m_s,steps,wall_seconds\n",
    );
    for r in &report.results {
        let _ = writeln!(
            csv,
            "{},{:.5},{:.5},{:.5},{:.5},{:.5},{},{:.2e},{},{:.1}",
            r.mu,
            r.phi,
            r.slab.0,
            r.slab.1,
            r.halves.0,
            r.halves.1,
            r.beads,
            r.speeds.1,
            r.steps,
            r.wall_seconds
        );
    }
    write_file(out.join("packing.csv"), &csv, &mut files)?;
    let mut prof = String::from("mu,z_over_d,phi\n");
    for r in &report.results {
        for (z, p) in &r.profile {
            let _ = writeln!(prof, "{},{:.3},{:.5}", r.mu, z, p);
        }
    }
    write_file(out.join("packing_profiles.csv"), &prof, &mut files)?;
    let png = crate::report::write_figure(&out, "packing", &figure(&report), &mut files)?;
    let title = "poured packing: volume fraction against friction (Silbert et al. 2002)";
    let mut summary = summary_markdown(title, &report.checks);
    let _ = write!(summary, "\nΔt = {:.2e} s; {:.1} s.\n", report.dt, report.wall_seconds);
    write_file(out.join("summary.md"), &summary, &mut files)?;
    let mut notes = vec![
        "Monodisperse beads poured at a rate into a box periodic in x and y onto a flat floor and left to settle, one run per friction coefficient; φ is the exact volume of the beads in a slab from 5 d above the floor to 3 d below the bed's height, over the slab's volume. Reference: random close packing φ ≈ 0.64 for μ = 0, falling with μ to about 0.59–0.60 (Silbert et al. 2002; Agnolin & Roux 2007).".to_string(),
    ];
    if !report.full {
        notes.push(
            "Reduced run: μ = 0, 0.1, 0.5. Run with --converged for μ = 0, 0.05, 0.1, 0.2, 0.3, 0.5, 1."
                .into(),
        );
    }
    Ok(CaseOutcome {
        name: "packing",
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

    /// The slab volumes of a sphere add up to its volume, and half of it lies below its centre.
    #[test]
    fn slab_volume_of_a_sphere() {
        let (c, r) = (0.3f64, 0.1f64);
        let whole = 4.0 / 3.0 * PI * r.powi(3);
        assert!((slab_volume(c, r, -1.0, 1.0) - whole).abs() < 1e-15);
        assert!((slab_volume(c, r, 0.0, c) - 0.5 * whole).abs() < 1e-15);
        let parts: f64 =
            (0..10).map(|k| slab_volume(c, r, 0.2 + 0.02 * k as f64, 0.22 + 0.02 * k as f64)).sum();
        assert!((parts - whole).abs() < 1e-15);
        assert_eq!(slab_volume(c, r, 0.5, 0.6), 0.0);
    }
}
