//! The verification suite: a registry of cases, each run into `DIR/<case>/`, and one HTML
//! report for the whole suite (written by [`crate::report`]).

use crate::error::VerifyError;
use rayon::prelude::*;
use std::path::Path;

pub use crate::report::{CaseOutcome, SuiteOptions, console_summary, write_report};

/// A case of the suite.
#[derive(Clone, Copy)]
pub struct CaseEntry {
    /// Name used on the command line and as the output folder.
    pub name: &'static str,
    /// One line for `grainflow verify --list`.
    pub summary: &'static str,
    /// Runs the case, writing into `DIR/<name>/`.
    pub run: fn(&Path, &SuiteOptions) -> Result<CaseOutcome, VerifyError>,
}

/// Every case, in report order.
pub fn cases() -> Vec<CaseEntry> {
    vec![
        CaseEntry {
            name: "dem01",
            summary: "MFIX DEM01: falling particle with one wall collision (LSD), EULER and ADAMS_BASHFORTH, against the three-stage closed form",
            run: crate::dem01::run_case,
        },
        CaseEntry {
            name: "dem02",
            summary: "MFIX DEM02: bouncing particle heights (LSD) against the hard sphere, with the gravity-during-contact bound and the exact soft-sphere contact",
            run: crate::dem02::run_case,
        },
        CaseEntry {
            name: "dem03",
            summary: "MFIX DEM03: two stacked, compressed particles between walls against an RK4 reference, with a step-halving study",
            run: crate::dem03::run_case,
        },
        CaseEntry {
            name: "dem04",
            summary: "MFIX DEM04: ball slipping on a rough floor until it rolls (2/7, 5/7, 5/7)",
            run: crate::dem04::run_case,
        },
        CaseEntry {
            name: "dem05",
            summary: "MFIX DEM05: oblique particle collision, LSD and Hertz, against MFIX's output, theory and Kharaz et al. (2001)",
            run: crate::dem05::run_case,
        },
        CaseEntry {
            name: "chung_ooi",
            summary: "Chung & Ooi (2011) tests 1–8: Hertz–Mindlin impacts against closed forms (Hertz, restitution, gross sliding, spin)",
            run: crate::chung_ooi::run_case,
        },
        CaseEntry {
            name: "rolling_plane",
            summary: "sphere sliding into rolling on a plane: t* = 2u₀/(7μg), v* = (5v₀ + 2Rω₀)/7, then constant speed",
            run: crate::rolling::run_plane,
        },
        CaseEntry {
            name: "rolling_incline",
            summary: "sphere released on an incline: rolls iff tan α ≤ 3.5μ (a = (5/7)g sin α), else slides",
            run: crate::rolling::run_incline,
        },
        CaseEntry {
            name: "jkr",
            summary: "JKR cohesion: pull-off force 3πγR* and distance δ_c on the law's curve; a pair approaching, sticking and pulling off against LAMMPS pair granular jkr",
            run: crate::jkr::run_case,
        },
        CaseEntry {
            name: "drum",
            summary: "rotating drum (quasi-2D, turning mesh walls): dynamic angle of repose in the rolling regime against rotating-drum measurements (Kleinhans et al. 2011) and its rise with Fr (Brucks et al. 2007)",
            run: crate::drum::run_case,
        },
        CaseEntry {
            name: "silo",
            summary: "silo discharge (flat-bottomed cylinder and floor as triangle meshes, insertion, outlet): the rate against Beverloo's correlation, C and k fitted over the orifice size",
            run: crate::silo::run_case,
        },
        CaseEntry {
            name: "packing",
            summary: "poured packing of monodisperse spheres (rate insertion, periodic box): volume fraction ≈ 0.64 without friction, falling with μ (Silbert et al. 2002)",
            run: crate::packing::run_case,
        },
    ]
}

/// Looks up cases by name; unknown names are an error listing the known ones.
pub fn select(names: &[String]) -> Result<Vec<CaseEntry>, String> {
    let all = cases();
    if names.is_empty() {
        return Ok(all);
    }
    names
        .iter()
        .map(|n| {
            all.iter().find(|c| c.name == n).copied().ok_or_else(|| {
                let known: Vec<&str> = all.iter().map(|c| c.name).collect();
                format!("unknown verification case '{n}'; the cases are {}", known.join(", "))
            })
        })
        .collect()
}

/// Runs the cases (in parallel; each writes its own folder) and returns their outcomes in
/// the order given.
pub fn run(
    entries: &[CaseEntry],
    dir: &Path,
    options: &SuiteOptions,
) -> Result<Vec<CaseOutcome>, VerifyError> {
    entries.par_iter().map(|e| (e.run)(dir, options)).collect()
}
