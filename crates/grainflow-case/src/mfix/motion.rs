//! The file given with `--motion`: `[[motion]]` rules for particles and `[[walls]]` for
//! the deck's STL walls, standing in for user-defined functions.

use crate::error::CaseError;
use crate::raw::*;
use serde::Deserialize;

/// The file given with `--motion`: what a deck's user-defined functions did, in grainflow's
/// terms: `[[motion]]` rules for particles, `[[walls]]` for the deck's STL walls.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MotionFile {
    #[serde(default)]
    pub(super) motion: Vec<RawMotion>,
    #[serde(default)]
    pub(super) walls: Vec<WallRule>,
}

/// `[[walls]]` of a motion file: how the STL wall of boundary condition `bc` moves.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct WallRule {
    /// The deck's boundary condition (a `CG_NSW`, `CG_FSW` or `CG_PSW` wall), or
    pub(super) bc: Option<i64>,
    /// its internal surface (`IS_TYPE = 'STL'`).
    pub(super) is: Option<i64>,
    /// The mesh moving as a rigid body (`[meshes.motion]`).
    pub(super) motion: Option<RawMeshMotion>,
    /// A velocity of its surface, the mesh staying in place (`[meshes.surface]`).
    pub(super) surface: Option<RawMeshSurface>,
}

pub(super) fn parse_motion(text: &str, origin: &str) -> Result<MotionFile, CaseError> {
    let m: MotionFile = toml::from_str(text).map_err(|e| {
        CaseError::Syntax(format!(
            "{origin}: {e}\n(a motion file holds [[motion]] tables for particles, as in a case file, and [[walls]] tables for the deck's STL walls, docs/mfix-decks.md)"
        ))
    })?;
    if m.motion.is_empty() && m.walls.is_empty() {
        return Err(CaseError::missing(
            origin,
            "[[motion]] or [[walls]]",
            "at least one rule: a prescribed particle motion or a wall's motion",
        ));
    }
    for (k, w) in m.walls.iter().enumerate() {
        // A wall moves one way: a second table for the same one would silently replace it.
        if let Some(j) = m.walls[..k]
            .iter()
            .position(|o| (o.bc.is_some() && o.bc == w.bc) || (o.is.is_some() && o.is == w.is))
        {
            let (key, id) = match (w.bc, w.is) {
                (Some(b), _) => ("bc", b),
                (None, Some(i)) => ("is", i),
                (None, None) => unreachable!("a match needs an id"),
            };
            return Err(CaseError::invalid(
                format!("{origin}: [[walls]] #{}", k + 1),
                key,
                id,
                format!(
                    "[[walls]] #{} already gives this wall's motion; give each wall one [[walls]] table",
                    j + 1
                ),
            ));
        }
        if w.bc.is_some() == w.is.is_some() {
            return Err(CaseError::missing(
                format!("{origin}: [[walls]] #{}", k + 1),
                "bc or is",
                "the wall: its boundary condition `bc = N` or its internal surface `is = N`, one of them",
            ));
        }
        if w.motion.is_none() && w.surface.is_none() {
            return Err(CaseError::missing(
                format!("{origin}: [[walls]] #{}", k + 1),
                "motion or surface",
                "how the wall of this boundary condition moves",
            ));
        }
    }
    Ok(m)
}
