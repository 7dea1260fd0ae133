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
    /// The particle's slot, and its leader's (kept up to date when particles move to other
    /// slots).
    pub(crate) slot: usize,
    pub(crate) leader: Option<usize>,
    /// Whether the rule follows a leader (whose slot, on ranks, may be on another rank).
    follows: bool,
    axes: [bool; 3],
    anchor: Vec3,
}

/// Refuses rule sets without a meaning: a particle with two rules (which one holds?), and
/// leaders that follow each other in a cycle (no particle of the cycle moves freely, and where
/// they end up would depend on the order the rules are applied in).
pub fn check_rules(rules: &[PrescribedMotion]) -> Result<(), EngineError> {
    use std::collections::HashMap;
    let mut leader_of: HashMap<u32, Option<u32>> = HashMap::with_capacity(rules.len());
    for r in rules {
        let leader = match r.rule {
            MotionRule::Hold => None,
            MotionRule::Follow { leader, .. } if leader == r.particle => {
                return Err(EngineError::BadReference(format!("particle {leader} cannot follow itself")));
            }
            MotionRule::Follow { leader, .. } => Some(leader),
        };
        if leader_of.insert(r.particle, leader).is_some() {
            return Err(EngineError::BadReference(format!(
                "particle {} has two prescribed-motion rules; give each particle one",
                r.particle
            )));
        }
    }
    // 1: on the chain being walked, 2: known to end at a particle that is not following.
    let mut state: HashMap<u32, u8> = HashMap::with_capacity(leader_of.len());
    let mut ids: Vec<u32> = leader_of.keys().copied().collect();
    ids.sort_unstable();
    for start in ids {
        let mut chain = Vec::new();
        let mut cur = start;
        while state.get(&cur).copied().unwrap_or(0) == 0 {
            let Some(Some(next)) = leader_of.get(&cur) else { break };
            state.insert(cur, 1);
            chain.push(cur);
            cur = *next;
        }
        if state.get(&cur) == Some(&1) {
            let from = chain.iter().position(|&c| c == cur).unwrap_or(0);
            let cycle: Vec<String> =
                chain[from..].iter().chain(std::iter::once(&cur)).map(|c| c.to_string()).collect();
            return Err(EngineError::BadReference(format!(
                "prescribed motion: particles follow each other in a cycle ({}); a chain of leaders must end at a particle that is not following",
                cycle.join(" follows ")
            )));
        }
        for c in chain {
            state.insert(c, 2);
        }
    }
    Ok(())
}

pub(crate) fn resolve(rules: &[PrescribedMotion], p: &Particles) -> Result<Vec<ResolvedMotion>, EngineError> {
    check_rules(rules)?;
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
            Ok(ResolvedMotion { slot, leader, follows: leader.is_some(), axes, anchor: p.position[slot] })
        })
        .collect()
}

/// Slots held fixed (rule `Hold`): they never move, so pairs among them can be left out.
pub(crate) fn held(rules: &[ResolvedMotion], n: usize) -> Vec<bool> {
    let mut held = vec![false; n];
    for r in rules {
        if !r.follows {
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

impl ResolvedMotion {
    /// A rule anchored at `anchor` whose slots are not known yet (a rule by ids, on ranks).
    pub(crate) fn spread(follows: bool, axes: [bool; 3], anchor: Vec3) -> Self {
        ResolvedMotion { slot: 0, leader: None, follows, axes, anchor }
    }

    /// This rule for the particle in slot `slot`, its leader in slot `leader` (none: one
    /// whose position the caller gives, as on ranks).
    pub(crate) fn at_slots(self, slot: usize, leader: Option<usize>) -> Self {
        ResolvedMotion { slot, leader, ..self }
    }

    /// Whether the rule follows a leader.
    pub(crate) fn follows(&self) -> bool {
        self.follows
    }

    /// The position the rule puts its particle at, given its leader's position now.
    pub(crate) fn target(&self, leader: Vec3) -> Vec3 {
        let (mut x, lx) = (self.anchor.to_array(), leader.to_array());
        for k in (0..3).filter(|&k| self.follows && self.axes[k]) {
            x[k] = lx[k];
        }
        Vec3::from_array(x)
    }

    /// The position the rule started from.
    pub(crate) fn anchor(&self) -> Vec3 {
        self.anchor
    }
}

/// Puts every prescribed particle where its rule says, at rest. Returns true if that changed
/// any position, velocity or angular velocity (bit for bit): a held particle already at its
/// anchor and at rest changes nothing, so the forces of the state stay valid.
pub(crate) fn apply(rules: &[ResolvedMotion], p: &mut Particles) -> bool {
    let mut changed = false;
    for r in rules {
        let x = r.target(r.leader.map_or(r.anchor, |l| p.position[l]));
        changed |= put(p, r.slot, x);
    }
    changed
}

/// Puts slot `s` at `x`, at rest; whether that changed its state, bit for bit (so that -0.0
/// and 0.0, or any NaN, count as a change).
pub(crate) fn put(p: &mut Particles, s: usize, x: Vec3) -> bool {
    let same = |a: Vec3, b: Vec3| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits);
    let changed =
        !(same(p.position[s], x) && same(p.velocity[s], Vec3::ZERO) && same(p.omega[s], Vec3::ZERO));
    p.position[s] = x;
    p.velocity[s] = Vec3::ZERO;
    p.omega[s] = Vec3::ZERO;
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::ParticleInit;

    fn two_particles() -> Particles {
        let q = |id: u32, x: f64| ParticleInit {
            id,
            phase: 0,
            radius: 0.5,
            density: 1.0,
            position: Vec3::new(x, 0.0, 0.0),
            velocity: Vec3::ZERO,
            omega: Vec3::ZERO,
        };
        Particles::from_init(&[q(1, 0.0), q(2, 2.0)])
    }

    #[test]
    fn applying_a_rule_reports_whether_the_state_changed() {
        let mut p = two_particles();
        let hold = resolve(&[PrescribedMotion { particle: 1, rule: MotionRule::Hold }], &p).unwrap();
        // At its anchor and at rest: nothing changes, so the forces of the state stay valid.
        assert!(!apply(&hold, &mut p));
        // Any drift of position, velocity or spin is undone and reported.
        p.velocity[0] = Vec3::new(0.0, 0.0, -1e-300);
        assert!(apply(&hold, &mut p));
        assert_eq!(p.velocity[0], Vec3::ZERO);
        assert!(!apply(&hold, &mut p));
        p.position[0].x = 1e-16;
        assert!(apply(&hold, &mut p));
        assert_eq!(p.position[0].x, 0.0);
        p.omega[0].y = -0.0;
        assert!(apply(&hold, &mut p), "-0.0 is not the rest state's bits");
        // A follower moves with its leader: a change whenever the leader moved.
        let follow = resolve(
            &[PrescribedMotion {
                particle: 2,
                rule: MotionRule::Follow { leader: 1, axes: [true, false, false] },
            }],
            &p,
        )
        .unwrap();
        assert!(apply(&follow, &mut p), "particle 2 jumps to its leader's x");
        assert!(!apply(&follow, &mut p));
        p.position[0].x = 0.25;
        assert!(apply(&follow, &mut p));
        assert_eq!(p.position[1].x, 0.25);
    }

    #[test]
    fn rule_sets_without_a_meaning_are_refused() {
        let follow = |particle, leader| PrescribedMotion {
            particle,
            rule: MotionRule::Follow { leader, axes: [true, false, false] },
        };
        let hold = |particle| PrescribedMotion { particle, rule: MotionRule::Hold };
        // A chain ending at a held particle is fine; so is one ending at a free particle.
        assert!(check_rules(&[follow(1, 2), follow(2, 3), hold(3)]).is_ok());
        assert!(check_rules(&[follow(1, 2), follow(3, 2)]).is_ok());
        let e = check_rules(&[hold(5), follow(1, 2), follow(2, 3), follow(3, 1)]).unwrap_err().to_string();
        assert!(e.contains("cycle (1 follows 2 follows 3 follows 1)"), "{e}");
        let e = check_rules(&[hold(4), follow(4, 1)]).unwrap_err().to_string();
        assert!(e.contains("particle 4 has two prescribed-motion rules"), "{e}");
        let e = check_rules(&[follow(7, 7)]).unwrap_err().to_string();
        assert!(e.contains("cannot follow itself"), "{e}");
        // Through resolve too (the engine's set-up).
        assert!(resolve(&[follow(1, 2), follow(2, 1)], &two_particles()).is_err());
    }
}
