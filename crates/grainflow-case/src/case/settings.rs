//! `[physics]`, `[neighbor]` and `[output]`: gravity, the neighbour-list skin and the output
//! intervals.

use super::OutputSettings;
use super::fields::{check, vec3};
use crate::error::CaseError;
use crate::raw::{RawNeighbor, RawOutput, RawPhysics};
use grainflow::Vec3;
use grainflow::contact::limits::Range;
use grainflow::simulation::STANDARD_GRAVITY;

/// The settings of the three small tables.
pub(super) struct Settings {
    pub gravity: Vec3,
    pub skin: Option<f64>,
    pub output: OutputSettings,
}

/// `[physics]`, `[neighbor]` and `[output]`, in that order.
pub(super) fn settings(
    physics: &RawPhysics,
    neighbor: &RawNeighbor,
    output: &RawOutput,
) -> Result<Settings, CaseError> {
    let gravity = match physics.gravity {
        Some(g) => vec3(g, "[physics]", "gravity")?,
        None => Vec3::new(0.0, -STANDARD_GRAVITY, 0.0),
    };
    let skin = neighbor
        .skin
        .map(|s| {
            check(
                Range {
                    lo: 0.0,
                    lo_open: false,
                    hi: f64::MAX,
                    hi_open: false,
                    valid: "must be a length >= 0 in m",
                },
                "[neighbor]",
                "skin",
                s,
            )
        })
        .transpose()?;
    let interval = output
        .interval
        .map(|v| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(CaseError::invalid("[output]", "interval", v, "must be a positive time in s"))
            }
        })
        .transpose()?;
    let vtk_interval = output
        .vtk_interval
        .map(|v| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(CaseError::invalid("[output]", "vtk_interval", v, "must be a positive time in s"))
            }
        })
        .transpose()?;
    let settings = OutputSettings { interval, snapshots: output.snapshots.unwrap_or(true), vtk_interval };
    Ok(Settings { gravity, skin, output: settings })
}
