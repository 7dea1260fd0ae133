//! `[[motion]]`: particles held in place or following a leader.

use super::fields::require;
use crate::error::CaseError;
use crate::raw::{IdSelection, RawMotion};
use grainflow::{MotionRule, Particles, PrescribedMotion};

/// The prescribed motions of `[[motion]]`, each id checked against the particles (when they
/// are here: see [`super::Bed::Elsewhere`]).
pub(super) fn motion(
    raw: &[RawMotion],
    particles: Option<&Particles>,
) -> Result<Vec<PrescribedMotion>, CaseError> {
    let ids: Option<std::collections::HashSet<u32>> =
        particles.map(|p| if raw.is_empty() { Default::default() } else { p.id.iter().copied().collect() });
    let has = |id: u32| ids.as_ref().is_none_or(|ids| ids.contains(&id));
    let mut motion = Vec::new();
    for (k, m) in raw.iter().enumerate() {
        let table = format!("[[motion]] #{}", k + 1);
        let (first, last) = match require(m.particles.clone(), &table, "particles", "an id or [first, last]")?
        {
            IdSelection::One(i) => (i, i),
            IdSelection::Range([a, b]) if a <= b => (a, b),
            IdSelection::Range([a, b]) => {
                return Err(CaseError::invalid(
                    &table,
                    "particles",
                    format!("[{a}, {b}]"),
                    "the first id must not exceed the last",
                ));
            }
        };
        let rule_word = require(m.rule.clone(), &table, "rule", "\"hold\" or \"follow\"")?;
        for id in first..=last {
            let rule = match rule_word.as_str() {
                "hold" => {
                    if m.leader.is_some() || m.leader_offset.is_some() || m.axes.is_some() {
                        return Err(CaseError::invalid(
                            &table,
                            "rule",
                            "\"hold\"",
                            "a held particle takes no leader, leader_offset or axes",
                        ));
                    }
                    MotionRule::Hold
                }
                "follow" => {
                    let leader = match (m.leader, m.leader_offset) {
                        (Some(l), None) => l,
                        (None, Some(off)) => {
                            let l = id as i64 + off;
                            u32::try_from(l).map_err(|_| {
                                CaseError::invalid(
                                    &table,
                                    "leader_offset",
                                    off,
                                    format!("particle {id} would follow id {l}, which cannot exist"),
                                )
                            })?
                        }
                        _ => {
                            return Err(CaseError::invalid(
                                &table,
                                "leader",
                                "(see leader_offset)",
                                "\"follow\" needs exactly one of `leader` (an id) or `leader_offset`",
                            ));
                        }
                    };
                    let words = require(
                        m.axes.clone(),
                        &table,
                        "axes",
                        "the axes that follow the leader, e.g. [\"x\", \"z\"]",
                    )?;
                    let mut axes = [false; 3];
                    for w in &words {
                        let k = ["x", "y", "z"].iter().position(|a| a == w).ok_or_else(|| {
                            CaseError::invalid(
                                &table,
                                "axes",
                                format!("\"{w}\""),
                                "each axis must be \"x\", \"y\" or \"z\"",
                            )
                        })?;
                        axes[k] = true;
                    }
                    MotionRule::Follow { leader, axes }
                }
                other => {
                    return Err(CaseError::invalid(
                        &table,
                        "rule",
                        format!("\"{other}\""),
                        "must be \"hold\" or \"follow\"",
                    ));
                }
            };
            if !has(id) {
                return Err(CaseError::invalid(&table, "particles", id, "no particle has this id"));
            }
            if let MotionRule::Follow { leader, .. } = rule
                && !has(leader)
            {
                return Err(CaseError::invalid(
                    &table,
                    "leader",
                    leader,
                    format!("particle {id} would follow id {leader}, which no particle has"),
                ));
            }
            motion.push(PrescribedMotion { particle: id, rule });
        }
    }
    Ok(motion)
}
