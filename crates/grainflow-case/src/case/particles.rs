//! `[particles]`: the particle file and `[[particles.list]]`, their order in memory, resorting
//! and the overlaps allowed at the start and during the run.

use super::fields::{check, require, vec3};
use super::materials::phase_index;
use super::{DEFAULT_MAX_INITIAL_OVERLAP, DEFAULT_MAX_OVERLAP};
use crate::error::CaseError;
use crate::particles;
use crate::raw::RawParticles;
use grainflow::contact::limits;
use grainflow::state::ParticleInit;
use grainflow::{Particles, Phase, Vec3};

/// The initial particles and the settings of `[particles]` the later checks use.
pub(super) struct Bed {
    pub particles: Particles,
    pub resort: grainflow::ResortRule,
    pub max_overlap: Option<f64>,
    pub max_initial_overlap: Option<f64>,
}

/// `[particles]`, its file read through `open` (none is needed when an insertion brings the
/// particles).
pub(super) fn particles<'h>(
    raw: Option<RawParticles>,
    inserting: bool,
    phases: &[Phase],
    (open, bed): (&super::OpenStream<'_, 'h>, super::Bed),
    (min, max): (Vec3, Vec3),
    axes: [bool; 3],
    skin: Option<f64>,
    warnings: &mut Vec<String>,
) -> Result<Bed, CaseError> {
    let praw = match raw {
        Some(p) => p,
        None if inserting => RawParticles::default(),
        None => require(
            None,
            "top level",
            "[particles]",
            "a particle file and/or [[particles.list]] (or [[insertions]])",
        )?,
    };
    let mut init: Vec<ParticleInit> = Vec::new();
    let elsewhere = bed == super::Bed::Elsewhere;
    if elsewhere {
        // Another process reads the file and the list, and checks them.
    } else if let Some(file) = &praw.file {
        let lower = file.to_ascii_lowercase();
        let format = praw.format.clone().unwrap_or_else(|| {
            if lower.ends_with(".csv") {
                "csv".into()
            } else if lower.ends_with(".data") {
                "lammps".into()
            } else {
                "mfix".into()
            }
        });
        if !["mfix", "csv", "lammps"].contains(&format.as_str()) {
            return Err(CaseError::invalid(
                "[particles]",
                "format",
                format!("\"{format}\""),
                "must be \"mfix\", \"csv\" or \"lammps\"",
            ));
        }
        let mut stream = open(file)?;
        init = match format.as_str() {
            "mfix" => particles::read_mfix_from(&mut stream, phases)?,
            "csv" => particles::read_csv_from(&mut stream, phases)?,
            "lammps" => {
                let data = crate::lammps::read_data_from(&mut stream, phases)?;
                if let Some((blo, bhi)) = data.bounds {
                    // A larger domain along a walled axis only holds the file's box (LAMMPS
                    // shrink-wraps a flow's open top); a periodic axis of another length, or a
                    // domain that cuts into the file's box, is another system.
                    let tol = 1e-9 * (max - min).abs().max_element();
                    let differs = (0..3).any(|k| {
                        let (dl, dh, fl, fh) = (min[k], max[k], blo[k], bhi[k]);
                        if axes[k] {
                            (dl - fl).abs() > tol || (dh - fh).abs() > tol
                        } else {
                            dl > fl + tol || dh < fh - tol
                        }
                    });
                    if differs {
                        warnings.push(format!(
                            "[particles]: the LAMMPS data file {file} declares the box {:?} to {:?}, which [domain] min = {:?}, max = {:?} does not match (along a periodic axis) or does not hold; grainflow uses [domain] (its walls and periodic axes), not the file's box",
                            blo.to_array(),
                            bhi.to_array(),
                            min.to_array(),
                            max.to_array()
                        ));
                    }
                }
                data.atoms
            }
            other => {
                return Err(CaseError::invalid(
                    "[particles]",
                    "format",
                    format!("\"{other}\""),
                    "must be \"mfix\", \"csv\" or \"lammps\"",
                ));
            }
        };
    } else if let Some(f) = &praw.format {
        return Err(CaseError::invalid(
            "[particles]",
            "format",
            format!("\"{f}\""),
            "only meaningful together with `file`",
        ));
    }
    for (k, p) in praw.list.iter().enumerate().filter(|_| !elsewhere) {
        let table = format!("[[particles.list]] #{}", k + 1);
        let phase = phase_index(
            phases,
            &require(p.phase.clone(), &table, "phase", "the particle's phase name")?,
            &table,
            "phase",
        )?;
        let radius = match p.diameter {
            Some(d) => 0.5 * check(limits::DIAMETER, &table, "diameter", d)?,
            None => phases[phase].radius(),
        };
        init.push(ParticleInit {
            id: p.id.unwrap_or((init.len() + 1) as u32),
            phase: phase as u32,
            radius,
            density: phases[phase].density,
            position: vec3(require(p.position, &table, "position", "centre in m")?, &table, "position")?,
            velocity: vec3(p.velocity.unwrap_or([0.0; 3]), &table, "velocity")?,
            omega: vec3(p.angular_velocity.unwrap_or([0.0; 3]), &table, "angular_velocity")?,
        });
    }
    if init.is_empty() && !inserting && !elsewhere {
        return Err(CaseError::missing(
            "[particles]",
            "file or list",
            "at least one particle (or [[insertions]])",
        ));
    }
    match praw.order.as_deref() {
        None | Some("input") => {}
        _ if elsewhere => {}
        Some("spatial") => {
            let r_max = init.iter().map(|p| p.radius).fold(0.0, f64::max);
            let cut = 2.0 * r_max + skin.unwrap_or_else(|| grainflow::simulation::default_skin(r_max));
            sort_into_bins(&mut init, min, 0.5 * cut);
        }
        Some(other) => {
            return Err(CaseError::invalid(
                "[particles]",
                "order",
                format!("\"{other}\""),
                "must be \"input\" or \"spatial\"",
            ));
        }
    }
    let resort = match &praw.resort {
        None => grainflow::ResortRule::Auto,
        Some(crate::raw::RawResort::Word(w)) if w == "auto" => grainflow::ResortRule::Auto,
        Some(crate::raw::RawResort::Word(w)) if w == "never" => grainflow::ResortRule::Never,
        Some(crate::raw::RawResort::Steps(k)) if *k >= 1 => grainflow::ResortRule::Every(*k as u64),
        Some(other) => {
            return Err(CaseError::invalid(
                "[particles]",
                "resort",
                match other {
                    crate::raw::RawResort::Word(w) => format!("\"{w}\""),
                    crate::raw::RawResort::Steps(k) => k.to_string(),
                },
                "must be \"auto\", \"never\" or a number of steps >= 1",
            ));
        }
    };
    // A large bed's inputs are as large as its state: they go as it is built.
    let particles = Particles::from_init_vec(init);
    Ok(Bed {
        particles,
        resort,
        max_overlap: praw.max_overlap,
        max_initial_overlap: praw.max_initial_overlap,
    })
}

/// `[particles] max_overlap` and `max_initial_overlap`, checked against each other: (the
/// run's limit, the start's limit).
pub(super) fn overlaps(
    max_overlap: Option<f64>,
    max_initial_overlap: Option<f64>,
) -> Result<(f64, f64), CaseError> {
    let run_overlap = max_overlap.unwrap_or(DEFAULT_MAX_OVERLAP);
    if !(run_overlap.is_finite() && run_overlap > 0.0 && run_overlap <= 1.0) {
        return Err(CaseError::invalid(
            "[particles]",
            "max_overlap",
            run_overlap,
            "must be a fraction in (0, 1] of the smaller radius",
        ));
    }
    let start_overlap = max_initial_overlap.unwrap_or(DEFAULT_MAX_INITIAL_OVERLAP.min(run_overlap));
    if !(start_overlap.is_finite() && start_overlap >= 0.0) {
        return Err(CaseError::invalid(
            "[particles]",
            "max_initial_overlap",
            start_overlap,
            "must be a fraction >= 0 of the radius",
        ));
    }
    if start_overlap > run_overlap {
        return Err(CaseError::invalid(
            "[particles]",
            "max_initial_overlap",
            start_overlap,
            format!(
                "must not exceed max_overlap = {run_overlap} (the run stops at an overlap above max_overlap, so a start above it could not run); raise max_overlap too, or separate the particles"
            ),
        ));
    }
    Ok((run_overlap, start_overlap))
}

/// Sorts particles into cubic bins of edge `bin` over the domain from `lo`, bin by bin with x
/// fastest, then y, then z (ties by id). Particles close in space end up close in memory, and
/// the force loop meets a particle's neighbours in a few steady streams (the rows of bins
/// around it), which the processor's prefetcher follows; a Morton curve, tried first, keeps
/// neighbours as close but scatters the accesses and ran slower. LAMMPS sorts its atoms the
/// same way, into bins of half the neighbour cut-off.
fn sort_into_bins(init: &mut [ParticleInit], lo: Vec3, bin: f64) {
    let key = |x: Vec3| {
        // Saturating casts: positions are checked later, and any order is correct.
        let b = ((x - lo) / bin).floor();
        (b.z as i64, b.y as i64, b.x as i64)
    };
    init.sort_by_cached_key(|p| (key(p.position), p.id));
}
