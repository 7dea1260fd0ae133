//! `[[phases]]` and `[[wall_materials]]`, and the lookups of their names.

use super::fields::{check, require};
use crate::error::CaseError;
use crate::raw::{RawPhase, RawWallMaterial};
use grainflow::contact::coefficients::{MAX_PHASES, MAX_WALL_MATERIALS};
use grainflow::contact::limits;
use grainflow::{Phase, WallMaterial};

/// The phases; the counts of both tables are checked first (the pair tables grow as the
/// square of the count).
pub(super) fn phases(
    raw_phases: &[RawPhase],
    raw_walls: &[RawWallMaterial],
) -> Result<Vec<Phase>, CaseError> {
    if raw_phases.is_empty() {
        return Err(CaseError::missing(
            "top level",
            "[[phases]]",
            "at least one solids phase with name, diameter (m) and density (kg/m³)",
        ));
    }
    // Checked before any table is built: the pair tables grow as the square of the count.
    if raw_phases.len() > MAX_PHASES {
        return Err(CaseError::invalid(
            "top level",
            "[[phases]]",
            format!("({} tables)", raw_phases.len()),
            format!("at most {MAX_PHASES} phases are allowed (MFIX allows 10)"),
        ));
    }
    if raw_walls.len() > MAX_WALL_MATERIALS {
        return Err(CaseError::invalid(
            "top level",
            "[[wall_materials]]",
            format!("({} tables)", raw_walls.len()),
            format!("at most {MAX_WALL_MATERIALS} wall materials are allowed"),
        ));
    }
    let mut phases = Vec::new();
    for (k, p) in raw_phases.iter().enumerate() {
        let table = format!("[[phases]] #{}", k + 1);
        let name = require(p.name.clone(), &table, "name", "a unique phase name")?;
        let table = format!("[[phases]] '{name}'");
        if phases.iter().any(|q: &Phase| q.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "phase names must be unique",
            ));
        }
        let diameter = check(
            limits::DIAMETER,
            &table,
            "diameter",
            require(p.diameter, &table, "diameter", "reference diameter in m")?,
        )?;
        let density = check(
            limits::DENSITY,
            &table,
            "density",
            require(p.density, &table, "density", "density in kg/m³")?,
        )?;
        let youngs_modulus =
            p.youngs_modulus.map(|v| check(limits::YOUNGS, &table, "youngs_modulus", v)).transpose()?;
        let poisson_ratio =
            p.poisson_ratio.map(|v| check(limits::POISSON, &table, "poisson_ratio", v)).transpose()?;
        let phase = Phase { name, diameter, density, youngs_modulus, poisson_ratio };
        let m = phase.mass();
        if !(m.is_finite() && m >= f64::MIN_POSITIVE) {
            return Err(CaseError::invalid(
                &table,
                if (1e-9..=1.0).contains(&diameter) { "density" } else { "diameter" },
                format!("(diameter {diameter:e} m, density {density:e} kg/m³)"),
                format!(
                    "the particle mass ρ·π·d³/6 = {m:e} kg is beyond what double precision can hold; are the diameter and density in SI units (m, kg/m³)?"
                ),
            ));
        }
        phases.push(phase);
    }
    Ok(phases)
}

/// The index of the phase `name`, or a message listing the phases.
pub(super) fn phase_index(phases: &[Phase], name: &str, table: &str, key: &str) -> Result<usize, CaseError> {
    phases.iter().position(|p| p.name == name).ok_or_else(|| {
        let names: Vec<String> = phases.iter().map(|p| format!("\"{}\"", p.name)).collect();
        CaseError::invalid(
            table,
            key,
            format!("\"{name}\""),
            format!("not a phase; the phases are {}", names.join(", ")),
        )
    })
}

/// The wall materials; without any, one named "wall" with no elastic constants.
pub(super) fn wall_materials(raw: &[RawWallMaterial]) -> Result<Vec<WallMaterial>, CaseError> {
    let mut wall_materials = Vec::new();
    for (k, w) in raw.iter().enumerate() {
        let table = format!("[[wall_materials]] #{}", k + 1);
        let name = require(w.name.clone(), &table, "name", "a unique wall material name")?;
        let table = format!("[[wall_materials]] '{name}'");
        if wall_materials.iter().any(|q: &WallMaterial| q.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "wall material names must be unique",
            ));
        }
        let youngs_modulus =
            w.youngs_modulus.map(|v| check(limits::YOUNGS, &table, "youngs_modulus", v)).transpose()?;
        let poisson_ratio =
            w.poisson_ratio.map(|v| check(limits::POISSON, &table, "poisson_ratio", v)).transpose()?;
        wall_materials.push(WallMaterial { name, youngs_modulus, poisson_ratio });
    }
    if wall_materials.is_empty() {
        wall_materials.push(WallMaterial { name: "wall".into(), youngs_modulus: None, poisson_ratio: None });
    }
    Ok(wall_materials)
}

/// The index of the wall material `name` (the first one if none is named), or a message
/// listing them.
pub(super) fn material_index(
    wall_materials: &[WallMaterial],
    name: &Option<String>,
    table: &str,
    key: &str,
) -> Result<usize, CaseError> {
    let Some(name) = name else { return Ok(0) };
    wall_materials.iter().position(|m| &m.name == name).ok_or_else(|| {
        let names: Vec<String> = wall_materials.iter().map(|p| format!("\"{}\"", p.name)).collect();
        CaseError::invalid(
            table,
            key,
            format!("\"{name}\""),
            format!("not a wall material; the wall materials are {}", names.join(", ")),
        )
    })
}
