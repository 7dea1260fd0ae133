//! Prescribed particle motion, applied after every step (where MFIX runs its user hooks).
//!
//! A prescribed particle is integrated like any other, then overwritten: its velocity and
//! angular velocity are set to zero and its position is restored — each axis either to the
//! position it started with, or (for `Follow`) to the current position of a leader particle.

use crate::error::EngineError;
use crate::math::Vec3;
use crate::state::Particles;

/// What a prescribed particle does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionRule {
    /// Held at its initial position, at rest.
    Hold,
    /// On each axis marked `true`, copies the leader's position; on the others, keeps its
    /// initial position. Velocity and angular velocity are zero.
    Follow {
        /// Stable id of the leader.
        leader: u32,
        /// Axes x, y, z on which it follows.
        axes: [bool; 3],
    },
}

/// A rule applied to one particle, by stable id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrescribedMotion {
    /// Stable id of the prescribed particle.
    pub particle: u32,
    /// Its rule.
    pub rule: MotionRule,
}

/// A rule resolved to particle slots.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ResolvedMotion {
    slot: usize,
    leader: Option<usize>,
    axes: [bool; 3],
    anchor: Vec3,
}

pub(crate) fn resolve(rules: &[PrescribedMotion], p: &Particles) -> Result<Vec<ResolvedMotion>, EngineError> {
    let mut slot_of = std::collections::HashMap::with_capacity(p.len());
    for (i, &id) in p.id.iter().enumerate() {
        slot_of.insert(id, i);
    }
    let find = |id: u32, role: &str| {
        slot_of.get(&id).copied().ok_or_else(|| {
            EngineError::BadReference(format!(
                "prescribed motion names {role} particle id {id}, which does not exist"
            ))
        })
    };
    rules
        .iter()
        .map(|r| {
            let slot = find(r.particle, "a")?;
            let (leader, axes) = match r.rule {
                MotionRule::Hold => (None, [false; 3]),
                MotionRule::Follow { leader, axes } => {
                    if leader == r.particle {
                        return Err(EngineError::BadReference(format!(
                            "particle {leader} cannot follow itself"
                        )));
                    }
                    (Some(find(leader, "a leader")?), axes)
                }
            };
            Ok(ResolvedMotion { slot, leader, axes, anchor: p.position[slot] })
        })
        .collect()
}

/// Slots held fixed (rule `Hold`): they never move, so pairs among them can be left out.
pub(crate) fn held(rules: &[ResolvedMotion], n: usize) -> Vec<bool> {
    let mut held = vec![false; n];
    for r in rules {
        if r.leader.is_none() {
            held[r.slot] = true;
        }
    }
    held
}

/// The anchor (initial position) of each resolved rule.
pub(crate) fn anchors(rules: &[ResolvedMotion]) -> Vec<Vec3> {
    rules.iter().map(|r| r.anchor).collect()
}

/// Sets the anchors from a checkpoint.
pub(crate) fn set_anchors(rules: &mut [ResolvedMotion], anchors: &[Vec3]) -> Result<(), String> {
    if rules.len() != anchors.len() {
        return Err(format!("{} prescribed-motion anchors for {} rules", anchors.len(), rules.len()));
    }
    for (r, a) in rules.iter_mut().zip(anchors) {
        r.anchor = *a;
    }
    Ok(())
}

/// The runs of consecutive slots not under prescribed motion, in order.
pub(crate) fn free_runs(rules: &[ResolvedMotion], n: usize) -> Vec<std::ops::Range<usize>> {
    let mut prescribed = vec![false; n];
    for r in rules {
        prescribed[r.slot] = true;
    }
    let mut runs = Vec::new();
    let mut start = None;
    for (i, &p) in prescribed.iter().chain(std::iter::once(&true)).enumerate() {
        match (p, start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                runs.push(s..i);
                start = None;
            }
            _ => {}
        }
    }
    runs
}

pub(crate) fn apply(rules: &[ResolvedMotion], p: &mut Particles) {
    for r in rules {
        let mut x = r.anchor.to_array();
        if let Some(l) = r.leader {
            let lx = p.position[l].to_array();
            for k in 0..3 {
                if r.axes[k] {
                    x[k] = lx[k];
                }
            }
        }
        p.position[r.slot] = Vec3::from_array(x);
        p.velocity[r.slot] = Vec3::ZERO;
        p.omega[r.slot] = Vec3::ZERO;
    }
}
