//! `[time]`: start, stop, the time-step rule and the integrator; the step checked against the
//! contact law's stability limit once the particles are known.

use super::fields::{choose, require};
use crate::error::CaseError;
use crate::raw::RawTime;
use grainflow::contact::{ContactLaw, ContactParams, ContactSizes};
use grainflow::mesh::MeshWall;
use grainflow::{Integrator, Particles, Phase, TimeStepRule, WallMaterial};

/// `[time]`, validated.
pub(super) struct Time {
    pub t_start: f64,
    pub t_stop: f64,
    pub time_step: TimeStepRule,
    /// The step is the Hertz default, to be taken again from the smallest particles.
    pub hertz_default: bool,
    pub integrator: Integrator,
    pub force_dt: bool,
}

/// `[time]` for the law's normal model and the phases.
pub(super) fn time(raw: Option<RawTime>, law: &ContactLaw, phases: &[Phase]) -> Result<Time, CaseError> {
    let normal = law.normal;
    let time = require(raw, "top level", "[time]", "t_stop (s) and optionally dt, integrator")?;
    let t_start = time.t_start.unwrap_or(0.0);
    if !t_start.is_finite() {
        return Err(CaseError::invalid("[time]", "t_start", t_start, "must be a finite time in s"));
    }
    let t_stop = require(time.t_stop, "[time]", "t_stop", "end time of the run, s")?;
    if !(t_stop.is_finite() && t_stop > t_start) {
        return Err(CaseError::invalid(
            "[time]",
            "t_stop",
            t_stop,
            format!("must be a finite time in s after t_start = {t_start}"),
        ));
    }
    // The Hertz default is taken again from the smallest particles once they are known.
    let hertz_default = time.dt.is_none()
        && time.dtsolid_factor.is_none()
        && normal.elastic()
        && grainflow::timestep::hertz_default_dt(phases).is_some();
    let time_step = match (time.dt, time.dtsolid_factor) {
        (Some(_), Some(_)) => {
            return Err(CaseError::invalid(
                "[time]",
                "dtsolid_factor",
                "(given with dt)",
                "give either an explicit dt or MFIX's dtsolid_factor, not both",
            ));
        }
        (Some(dt), None) if dt.is_finite() && dt > 0.0 => TimeStepRule::Fixed(dt),
        (Some(dt), None) => {
            return Err(CaseError::invalid("[time]", "dt", dt, "must be a positive time in s"));
        }
        // A Hertz case without dt: a fraction of the Rayleigh time (MFIX's rule takes the
        // Hertz K_n as linear and gives a step some 20 times below the stable one). MFIX decks
        // give dtsolid_factor, and keep MFIX's rule.
        (None, None) if normal.elastic() && grainflow::timestep::hertz_default_dt(phases).is_some() => {
            TimeStepRule::Fixed(grainflow::timestep::hertz_default_dt(phases).unwrap_or(f64::NAN))
        }
        (None, f) => {
            let factor = f.unwrap_or(50.0);
            if !(factor.is_finite() && factor >= 10.0) {
                return Err(CaseError::invalid(
                    "[time]",
                    "dtsolid_factor",
                    factor,
                    "must be at least 10 (MFIX rejects smaller values)",
                ));
            }
            TimeStepRule::Mfix { factor }
        }
    };
    let integrator = choose(
        "[time]",
        "integrator",
        time.integrator.as_deref(),
        Integrator::Euler,
        &[
            ("euler", Integrator::Euler),
            ("adams_bashforth", Integrator::AdamsBashforth),
            ("velocity_verlet", Integrator::VelocityVerlet),
        ],
    )?;
    let force_dt = time.force_dt.unwrap_or(false);
    Ok(Time { t_start, t_stop, time_step, hertz_default, integrator, force_dt })
}

/// The time-step rule in use: the Hertz default taken from the smallest particles (contacts
/// of their own sizes), the step checked against the stability limit, and the meshes' travel
/// per step.
pub(super) fn step(
    time: &Time,
    law: &ContactLaw,
    phases: &[Phase],
    wall_materials: &[WallMaterial],
    pair_params: &[ContactParams],
    wall_params: &[ContactParams],
    particles: &Particles,
    insertions: &[grainflow::insertion::Insertion],
    meshes: &[MeshWall],
    mesh_names: &[String],
    warnings: &mut Vec<String>,
) -> Result<TimeStepRule, CaseError> {
    let (t_start, t_stop, hertz_default, force_dt) =
        (time.t_start, time.t_stop, time.hertz_default, time.force_dt);
    let mut time_step = time.time_step;
    // Contacts of their own sizes: the time step from the smallest particles (as the engine
    // takes it).
    // Each particle's own size is checked before the smallest one sets a step.
    grainflow::simulation::check_particles(particles, phases.len())?;
    let sizes = grainflow::simulation::RunSizes::of(phases, particles, insertions);
    let smallest_radius = sizes.smallest.iter().map(Phase::radius).fold(f64::INFINITY, f64::min);
    let step_phases =
        if law.sizes == ContactSizes::Own && sizes.vary { sizes.smallest } else { phases.to_vec() };
    if let Some(dt) = grainflow::timestep::hertz_default_dt(&step_phases).filter(|_| hertz_default) {
        time_step = TimeStepRule::Fixed(dt);
    }
    let dt = check_stability(
        time_step,
        t_stop - t_start,
        law,
        &step_phases,
        wall_materials,
        pair_params,
        wall_params,
        force_dt,
        warnings,
    )?;
    if let Some((k, text)) = grainflow::timestep::mesh_travel_problem(meshes, mesh_names, smallest_radius, dt)
    {
        let table = format!("[[meshes]] '{}'", mesh_names[k]);
        if force_dt {
            warnings.push(format!("{table}: motion: {text} (running anyway: [time] force_dt = true)"));
        } else {
            return Err(CaseError::Geometry(format!(
                "{table}: motion: {text}; or lower the mesh's speed, or set [time] force_dt = true to run anyway"
            )));
        }
    }
    Ok(time_step)
}

/// An explicit time step above the contact law's stability limit is refused unless forced;
/// MFIX's rule above it (possible only through stiff walls, which MFIX leaves out) warns.
/// The step in use.
fn check_stability(
    rule: TimeStepRule,
    span: f64,
    law: &ContactLaw,
    phases: &[Phase],
    wall_materials: &[WallMaterial],
    pair_params: &[ContactParams],
    wall_params: &[ContactParams],
    force: bool,
    warnings: &mut Vec<String>,
) -> Result<f64, CaseError> {
    let table = grainflow::contact::CoeffTable::build(law, phases, wall_materials, pair_params, wall_params)?;
    let limit = grainflow::timestep::stability_limit(law, phases, wall_materials, &table);
    // The step and the step count, refused here as the engine would refuse them.
    // (Only the step matters here, not the Hertz collision time the explanation states.)
    let chosen = grainflow::timestep::choose(rule, law, phases, &table, span, &(1.0, String::new()))?;
    match rule {
        TimeStepRule::Fixed(dt) if dt > limit.dt_max => {
            let text = format!(
                "dt = {dt:e} s is above the stability limit {:.4e} s of the {} model ({}); a safe choice is dt = {:.4e} s, or leave dt out for MFIX's rule",
                limit.dt_max,
                law.normal_name(),
                limit.reason,
                limit.dt_safe
            );
            if force {
                warnings.push(format!("[time]: {text} (running anyway: force_dt = true)"));
                Ok(dt)
            } else {
                Err(CaseError::invalid(
                    "[time]",
                    "dt",
                    dt,
                    format!("{text}; set force_dt = true to run anyway"),
                ))
            }
        }
        TimeStepRule::Mfix { factor } => {
            let dt = chosen.dt;
            if dt > limit.dt_max {
                warnings.push(format!(
                    "[time]: MFIX's rule (TCOLL/{factor}) gives dt = {dt:.4e} s, above the stability limit {:.4e} s ({}); consider dt = {:.4e} s",
                    limit.dt_max, limit.reason, limit.dt_safe
                ));
            }
            Ok(dt)
        }
        TimeStepRule::Fixed(dt) => Ok(dt),
    }
}
