//! `[physics]`, `[neighbor]`, `[output]` and `[parallel]`: gravity, the neighbour-list skin,
//! the output intervals and the ranks' rebalancing.

use super::OutputSettings;
use super::fields::{check, choose, vec3};
use crate::error::CaseError;
use crate::raw::{RawNeighbor, RawOutput, RawParallel, RawPhysics};
use grainflow::Vec3;
use grainflow::contact::limits::Range;
use grainflow::domain::Weigh;
use grainflow::simulation::STANDARD_GRAVITY;

/// The settings of the four small tables.
pub(super) struct Settings {
    pub gravity: Vec3,
    pub skin: Option<f64>,
    pub output: OutputSettings,
    /// The ranks' work imbalance that re-cuts their boxes (none: never).
    pub rebalance: Option<f64>,
    /// What that imbalance is of.
    pub weigh: Weigh,
}

/// `[parallel] threshold` by default: a re-cut when the slowest rank has 10 % more work than
/// the mean.
pub const DEFAULT_REBALANCE: f64 = 0.1;

/// `[physics]`, `[neighbor]`, `[output]` and `[parallel]`, in that order.
pub(super) fn settings(
    physics: &RawPhysics,
    neighbor: &RawNeighbor,
    output: &RawOutput,
    parallel: &RawParallel,
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
    let threshold = match parallel.threshold {
        Some(t) if !(t.is_finite() && t >= 0.0) => {
            return Err(CaseError::invalid("[parallel]", "threshold", t, "must be a fraction >= 0"));
        }
        t => t.unwrap_or(DEFAULT_REBALANCE),
    };
    let rebalance = parallel.rebalance.unwrap_or(true).then_some(threshold);
    let words = [("time", Weigh::Time), ("work", Weigh::Work)];
    let weigh = choose("[parallel]", "weigh", parallel.weigh.as_deref(), Weigh::Time, &words)?;
    Ok(Settings { gravity, skin, output: settings, rebalance, weigh })
}
