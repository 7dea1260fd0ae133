//! What the set-up needs to know of the whole particle set, from the part a rank holds: a run
//! set up over ranks ([`Simulation::new_over_ranks`]) starts with each rank holding a share of
//! the particles, and takes the same time step, skin, first insertion id, checks and motion
//! rules as one process holding them all. Each fact is reduced exactly (maxima, minima, an
//! error agreed by every rank), so it is the one process's bits; in one process every
//! reduction is the value itself.

use super::Simulation;
use crate::domain::Comm;
use crate::error::EngineError;
use crate::math::Vec3;
use crate::motion::{MotionRule, PrescribedMotion, ResolvedMotion};
use crate::state::Particles;
use std::sync::Arc;

/// The ranks a set-up spans (none: one process).
#[derive(Clone, Copy)]
pub(super) struct Whole<'a>(pub(super) Option<&'a dyn Comm>);

impl Whole<'_> {
    /// The largest of every rank's `x`.
    pub(super) fn max(&self, x: f64) -> f64 {
        self.each(&[x.to_bits()]).map(|w| f64::from_bits(w[0])).fold(x, f64::max)
    }

    /// The largest of every rank's `x`.
    pub(super) fn max_u64(&self, x: u64) -> u64 {
        self.each(&[x]).map(|w| w[0]).fold(x, u64::max)
    }

    /// Whether `yes` holds on any rank.
    pub(super) fn any(&self, yes: bool) -> bool {
        self.each(&[yes as u64]).any(|w| w[0] != 0) || yes
    }

    /// Each element's smallest over the ranks.
    pub(super) fn mins(&self, xs: Vec<f64>) -> Vec<f64> {
        let mine: Vec<u64> = xs.iter().map(|x| x.to_bits()).collect();
        let mut out = xs;
        for w in self.each(&mine) {
            for (o, b) in out.iter_mut().zip(w) {
                *o = o.min(f64::from_bits(b));
            }
        }
        out
    }

    /// Each element's sum over the ranks (exact).
    pub(super) fn sums<const K: usize>(&self, xs: [i128; K]) -> [i128; K] {
        let mine: Vec<u64> = xs.iter().flat_map(|&x| [x as u128 as u64, (x as u128 >> 64) as u64]).collect();
        let Some(comm) = self.0 else { return xs };
        let mut out = [0i128; K];
        for w in comm.all_gather(&mine) {
            for (k, o) in out.iter_mut().enumerate() {
                *o += (w[2 * k] as u128 | (w[2 * k + 1] as u128) << 64) as i128;
            }
        }
        out
    }

    /// Every rank's words (none in one process).
    fn each(&self, mine: &[u64]) -> impl Iterator<Item = Vec<u64>> {
        self.0.map(|c| c.all_gather(mine)).unwrap_or_default().into_iter()
    }

    /// `mine` if no rank failed, else the failure of the lowest rank that failed, on every
    /// rank (as its message: its kind is kept on the rank that found it). With shares in the
    /// order of the particle file, that is the one process's first failure.
    pub(super) fn agree<T>(&self, mine: Result<T, EngineError>) -> Result<T, EngineError> {
        let Some(comm) = self.0 else { return mine };
        let words = match &mine {
            Ok(_) => vec![0],
            Err(e) => {
                let text = e.to_string().into_bytes();
                let mut w = vec![1, text.len() as u64];
                w.extend(text.chunks(8).map(|c| {
                    let mut b = [0u8; 8];
                    b[..c.len()].copy_from_slice(c);
                    u64::from_le_bytes(b)
                }));
                w
            }
        };
        let all = comm.all_gather(&words);
        match all.iter().position(|w| w[0] != 0) {
            None => mine,
            Some(r) if r == comm.rank() => mine,
            Some(r) => {
                let len = all[r][1] as usize;
                let bytes: Vec<u8> = all[r][2..].iter().flat_map(|w| w.to_le_bytes()).take(len).collect();
                Err(EngineError::BadReference(String::from_utf8_lossy(&bytes).into_owned()))
            }
        }
    }

    /// The smallest particle id held on more than one slot over all ranks, if any: each rank
    /// sends each id to the rank `id mod ranks`, which looks for repeats among those it gets.
    pub(super) fn repeated_id(&self, ids: &[u32]) -> Option<u32> {
        let repeat = |sorted: &mut Vec<u32>| {
            sorted.sort_unstable();
            sorted.windows(2).find(|w| w[0] == w[1]).map(|w| w[0])
        };
        let Some(comm) = self.0 else { return repeat(&mut ids.to_vec()) };
        let ranks = comm.size();
        let mut out = vec![Vec::new(); ranks];
        for &id in ids {
            out[id as usize % ranks].push(id as u64);
        }
        let mut got: Vec<u32> = comm.exchange(out).into_iter().flatten().map(|w| w as u32).collect();
        let mine = repeat(&mut got).map_or(u64::MAX, u64::from);
        let least = self.each(&[mine]).map(|w| w[0]).fold(mine, u64::min);
        (least != u64::MAX).then_some(least as u32)
    }

    /// The prescribed-motion rules resolved for the particles here, and (over ranks) every
    /// rank's rules by ids in the case's order, anchored where their particles start. A rule
    /// that names a particle no rank holds is refused as one process refuses it.
    pub(super) fn resolve_motion(
        &self,
        rules: &[PrescribedMotion],
        p: &Particles,
    ) -> Result<(Vec<ResolvedMotion>, Vec<super::ranks::RuleById>), EngineError> {
        let Some(comm) = self.0 else { return Ok((crate::motion::resolve(rules, p)?, Vec::new())) };
        crate::motion::check_rules(rules)?;
        let slots = crate::state::SlotsById::new(&p.id);
        let here = |id: u32| Some(slots.get(id)).filter(|&s| s != crate::state::NO_SLOT);
        // Per rule: whether its particle is here, where it starts, and whether its leader is.
        let mut mine = Vec::with_capacity(5 * rules.len());
        for r in rules {
            let at = here(r.particle);
            mine.push(at.is_some() as u64);
            let x = at.map_or(Vec3::ZERO, |s| p.position[s as usize]);
            mine.extend(x.to_array().map(f64::to_bits));
            let leader = match r.rule {
                MotionRule::Follow { leader, .. } => here(leader).is_some(),
                MotionRule::Hold => false,
            };
            mine.push(leader as u64);
        }
        let all = comm.all_gather(&mine);
        let missing = |id: u32, role: &str| {
            EngineError::BadReference(format!(
                "prescribed motion names {role} particle id {id}, which does not exist"
            ))
        };
        let mut by_id = Vec::with_capacity(rules.len());
        for (k, r) in rules.iter().enumerate() {
            let w = |rank: usize| &all[rank][5 * k..5 * k + 5];
            let Some(owner) = (0..all.len()).find(|&rank| w(rank)[0] != 0) else {
                return Err(missing(r.particle, "a"));
            };
            let anchor = Vec3::new(
                f64::from_bits(w(owner)[1]),
                f64::from_bits(w(owner)[2]),
                f64::from_bits(w(owner)[3]),
            );
            let (leader, axes) = match r.rule {
                MotionRule::Hold => (None, [false; 3]),
                MotionRule::Follow { leader, axes } => {
                    if !(0..all.len()).any(|rank| w(rank)[4] != 0) {
                        return Err(missing(leader, "a leader"));
                    }
                    (Some(leader), axes)
                }
            };
            let rule = ResolvedMotion::spread(leader.is_some(), axes, anchor);
            by_id.push(super::ranks::RuleById { id: r.particle, leader, rule });
        }
        let local = rules
            .iter()
            .zip(&by_id)
            .filter_map(|(r, b)| here(r.particle).map(|s| b.rule.at_slots(s as usize, None)))
            .collect();
        Ok((local, by_id))
    }
}

impl Simulation {
    /// Sets up a run spread over the ranks of `comm` from each rank's share of its particles
    /// (`share`: any split of them, each particle on one rank), as [`Simulation::new`] and
    /// [`Simulation::decompose`] would from all of them, with the same bits — without any rank
    /// holding more than its share: the facts of the whole set (the time step, the skin, the
    /// checks, the motion rules) are reduced over the ranks, and the particles move to the
    /// ranks of their boxes before any list is built. With shares in the order of a particle
    /// file, a refusal is the one process's. Collective.
    pub fn new_over_ranks(
        config: super::SimulationConfig,
        share: Particles,
        comm: Arc<dyn Comm>,
        rebalance: Option<f64>,
    ) -> Result<Self, EngineError> {
        let (mut sim, rules) = Simulation::unbuilt_over(config, share, Whole(Some(&*comm)))?;
        sim.spread_share(comm, rebalance, rules)?;
        // Two particles at the same centre (see `new`): the smallest such pair of ids anywhere.
        let same = sim.same_centre_pair();
        let whole = Whole(sim.comm().map(|c| &**c));
        let least = whole.each(&[same.map_or(u64::MAX, |s| s.0)]).map(|w| w[0]).min().unwrap_or(u64::MAX);
        if least != u64::MAX {
            let err = same.filter(|s| s.0 == least).map(|(key, x)| super::same_centre(key, x));
            whole.agree(err.map_or(Ok(()), Err))?;
        }
        let before = sim.total_particles();
        sim.flow_stage(false)?;
        // The boxes were cut before the batches due at the start were placed: cut again for
        // them (the particles move at the next rebuild), or a hopper filled at the start
        // would sit in the box that holds the insertion region.
        if sim.total_particles() != before {
            sim.cut_again();
        }
        sim.prepare_mesh_candidates();
        Ok(sim)
    }
}
