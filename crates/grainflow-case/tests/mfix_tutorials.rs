//! MFIX 21.3.2's hopper tutorials (`tutorials/dem/hopper_custom_psd`,
//! `tutorials/dem/hopper_massinflow_psd`, vendored unchanged in tests/mfix_decks/hopper/ with
//! their STL and size distribution) against what MFIX 21.3.2 itself did with them, run side by
//! side (bench/results/2026-12-02-mfix-tutorials.md, issue 38): the particles
//! `GENER_PART_CONFIG` seeds, where it leaves sites empty, and the rate of the mass inflow.
//! MFIX's figures are the independent reference.

use grainflow_case::mfix;
use std::path::{Path, PathBuf};

fn hopper(deck: &str) -> mfix::DeckCase {
    let p: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mfix_decks/hopper").join(deck);
    mfix::load(&p, &[], None).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The count is ⌊ε_s·V/v̄⌋ with V the fluid volume of the IC's cells inside the hopper
/// (MFIX's cut cells), not the IC box: MFIX seeded 32 485 (grainflow's box volume gave
/// 49 699). The fluid volume is sampled 8×8×8 per cut cell: 1 % covers it (the samples' error
/// is well below that over the 1 500 cut cells) and the count's ±0.2 % of MFIX's Monte-Carlo
/// mean volume of the custom distribution.
///
/// MFIX skips a site whose cell has no fluid, or that lies behind, or within 1.05 largest
/// radii of, the plane of any facet near its cell: the sites at the top of the outlet pipe,
/// behind the cone's planes, stay empty. MFIX had 18 particles below y = 0 (the pipe) where
/// grainflow's nearest-triangle rule put 118; the lattice is MFIX's site for site, and a
/// site at a cell face may fall either way of the face in the two codes' roundings: 3 of slack.
#[test]
fn the_custom_psd_hopper_seeds_mfix_count_and_leaves_the_pipe_top_empty() {
    let d = hopper("hopper_dem_custom_psd.mfx");
    let p = &d.case.particles;
    let mfix_count = 32_485.0;
    let n = p.len() as f64;
    assert!((n / mfix_count - 1.0).abs() < 0.01, "{n} seeded, MFIX seeded {mfix_count}");
    let below = (0..p.len()).filter(|&i| p.position[i].y < 0.0).count();
    assert!(below.abs_diff(18) <= 3, "{below} particles below y = 0, MFIX had 18");
}

/// As above for the mass-inflow hopper: MFIX seeded 3 963 (grainflow's box volume gave
/// 6 265).
#[test]
fn the_mass_inflow_hopper_seeds_mfix_count() {
    let d = hopper("hopper_mass_inflow.mfx");
    let n = d.case.particles.len() as f64;
    assert!((n / 3963.0 - 1.0).abs() < 0.01, "{n} seeded, MFIX seeded 3963");
}

/// MFIX feeds the top inlet (ε_s = 0.1, 0.1 m/s down, the 0.125 m square top of a round
/// hopper) through the fluid area of its cut cells only: 2 887 particles a second by its
/// log, against the whole face's 3 681. The rate here is the translated mass rate over
/// ρ_s·v̄, v̄ the mean volume of the truncated log-normal (mean 4.1 mm, σ 1 mm, 2 to 8 mm)
/// integrated by the midpoint rule (10⁵ points: exact to 1e-8); MFIX's own v̄ is a
/// Monte-Carlo mean of 10⁵ draws (±0.3 %), so 2 % holds both. Every inflow window lies
/// inside the hopper's top, the circle of radius 62.5 mm (a polygon of it) about its axis:
/// no particle enters outside it, where 263 of 2 397 did.
#[test]
fn the_mass_inflow_feeds_only_the_hopper_top_at_mfix_rate() {
    let d = hopper("hopper_mass_inflow.mfx");
    let (m, s) = (4.1e-3f64, 1.0e-3f64);
    let sg2 = (1.0 + s * s / (m * m)).ln();
    let mu = m.ln() - 0.5 * sg2;
    let (lo, hi, n) = (2.0e-3, 8.0e-3, 100_000);
    let h = (hi - lo) / n as f64;
    let (mut z, mut m3) = (0.0, 0.0);
    for i in 0..n {
        let x: f64 = lo + (i as f64 + 0.5) * h;
        let pdf = (-(x.ln() - mu).powi(2) / (2.0 * sg2)).exp() / x;
        z += pdf;
        m3 += pdf * x.powi(3);
    }
    let v_mean = std::f64::consts::FRAC_PI_6 * m3 / z;
    let rate: f64 = d.raw.insertions.iter().map(|i| i.mass_rate.expect("a mass rate")).sum();
    let per_second = rate / (1000.0 * v_mean);
    assert!((per_second / 2887.0 - 1.0).abs() < 0.02, "{per_second} particles/s, MFIX fed 2887");
    // The smallest sphere (2 mm) reaches farthest: its centre stays 1 mm inside the box.
    let r_min = 1.0e-3;
    for ins in &d.raw.insertions {
        let r = ins.region.as_ref().expect("a region");
        let (a, b) = (r.min.expect("box"), r.max.expect("box"));
        // The centres' range: the box less the radius on each side.
        for x in [a[0] + r_min, b[0] - r_min] {
            for z in [a[2] + r_min, b[2] - r_min] {
                let off = ((x - 0.0625).powi(2) + (z - 0.0625).powi(2)).sqrt();
                assert!(off < 0.0625, "{:?}: ({x}, {z}) is {off} m off the axis", ins.name);
            }
        }
    }
}
