//! Particle pairs as a contact source. The neighbour list finds the candidate pairs and keeps
//! their histories; the blocked kernel of [`crate::forces`] computes their loads (with the
//! plane walls', which each block takes first), on one thread or on the blocks of a
//! [`ForcePlan`] that this source keeps with the kernel's working memory.

use super::{ContactSource, Diagnosed, LoadRun, View};
use crate::contact::ContactCoeffs;
use crate::contact::geometry::{pair_contact_separation, relative_velocity};
use crate::contact::law::{contact_force_dyn, normal_spring_energy};
use crate::contact::pair::{
    contact_coeffs, contact_reach, pair_geometry_in_contact, pair_mass, scaled_damping,
};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel, formed};
use crate::forces::{self, ForcePlan, Scratch};
use crate::math::Vec3;
use crate::neighbor::NeighborState;
use crate::simulation::{ContactInfo, ContactPartner};

/// The particle pairs' kernel: its split over threads and its working memory on one thread.
#[derive(Debug, Clone)]
pub(crate) struct Pairs {
    /// Blocks of the parallel force stage (the per-particle stages share the slots out by
    /// them too).
    pub plan: ForcePlan,
    /// The force stage's working memory on one thread.
    pub scratch: Box<Scratch>,
}

impl Default for Pairs {
    fn default() -> Self {
        Pairs { plan: ForcePlan::default(), scratch: Scratch::new() }
    }
}

impl ContactSource for Pairs {
    /// The pair kernel: the plane walls' and the pairs' loads, after clearing the accumulators.
    fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, run: &mut LoadRun) {
        let clock = run.times.is_some().then(std::time::Instant::now);
        let p = &mut *run.particles;
        let build = run.neighbors.stats().builds;
        let (offsets, partners, pair_history, in_contact, wall_pairs, wall_history) =
            run.neighbors.split_mut();
        let x = forces::ForceInputs {
            position: &p.position,
            velocity: &p.velocity,
            omega: &p.omega,
            radius: &p.radius,
            mass: &p.mass,
            phase: &p.phase,
            held: run.held,
            common_mass: run.common_mass,
            walls: run.walls,
            coeffs: run.coeffs,
            law: run.law,
            images: run.periodic.images(),
            dt: if run.advance { run.dt } else { 0.0 },
            advance: run.advance,
            offsets,
            partners,
            wall_pairs,
            quanta: run.quanta,
        };
        let blocks = run.pool.map(|pool| {
            let plan = &mut self.plan;
            plan.prepare(
                build,
                forces::BLOCKS_PER_THREAD * pool.current_num_threads(),
                offsets,
                partners,
                in_contact,
                wall_pairs,
                wall_history,
            );
            (pool, plan)
        });
        let mut peak = [0.0; 2];
        let out = forces::ForceOutputs {
            force: &mut p.force,
            torque: &mut p.torque,
            peak: &mut peak,
            pair_history,
            in_contact,
            wall_history,
        };
        let timed = clock.is_some();
        let work = match blocks {
            Some((pool, plan)) => pool.install(|| forces::parallel::<N, T>(&x, plan, out, timed)),
            None => {
                let walls = forces::serial::<N, T>(&x, out, timed, &mut self.scratch);
                forces::ThreadWork { walls, ..Default::default() }
            }
        };
        run.peak = forces::max_peak(run.peak, peak);
        if let (Some(c), Some(t)) = (clock, run.times.as_deref_mut()) {
            let total = c.elapsed().as_secs_f64();
            t.walls += work.walls.min(total);
            t.pairs += (total - work.walls).max(0.0);
            t.threads_mean += work.mean;
            t.threads_slowest += work.slowest;
        }
    }

    fn contact_infos(&self, v: &View, out: &mut Vec<ContactInfo>) {
        let (p, law) = (v.particles, &v.law);
        let nl = v.neighbors;
        for ([i, j], h) in nl.pairs().zip(nl.pair_histories()) {
            // Seen from the particle with the lower id, whichever slot is lower: the contact
            // then reads the same however the particles are stored.
            let (i, j, h) = if p.id[i as usize] < p.id[j as usize] {
                (i as usize, j as usize, h)
            } else {
                (j as usize, i as usize, -h)
            };
            if i >= v.owned {
                continue;
            }
            let c = &pair_coeffs(v, i, j);
            let (x, r) = (&p.position, &p.radius);
            if let Some(g) = pair_geometry_in_contact(
                law.normal,
                x,
                r,
                i,
                j,
                law.lever,
                &v.periodic,
                c.pull_off,
                formed(h),
            ) {
                let c = scaled_damping(c, law.damping, pair_mass(&p.mass, v.held, i, j));
                let v_r = relative_velocity(&g, p.velocity[i], p.velocity[j], p.omega[i], p.omega[j]);
                let mut h = h;
                let f = contact_force_dyn(law, &c, &g, v_r, &mut h, 0.0);
                out.push(ContactInfo {
                    particle: i,
                    other: ContactPartner::Particle(j),
                    point: p.position[i] + g.lever_i * g.normal,
                    normal: g.normal,
                    overlap: g.overlap,
                    normal_force: f.normal.length(),
                    tangential_force: f.tangential.length(),
                });
            }
        }
    }

    fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed)) {
        let (p, law) = (v.particles, &v.law);
        let (normal, reaches, lever) = (law.normal, law.normal.reaches(), law.lever);
        let nl = v.neighbors;
        for ([i, j], h) in nl.pairs().zip(nl.pair_histories()) {
            let (i, j) = (i as usize, j as usize);
            let lower = if p.id[i] < p.id[j] { i } else { j };
            if lower >= v.owned {
                continue;
            }
            let c = &pair_coeffs(v, i, j);
            // A cohesive contact holds beyond the touch.
            let g = if reaches {
                let (x, r, per) = (&p.position, &p.radius, &v.periodic);
                pair_geometry_in_contact(normal, x, r, i, j, lever, per, c.pull_off, formed(h))
            } else {
                pair_contact_separation(
                    v.periodic.min_image(p.position[j] - p.position[i]),
                    p.radius[i],
                    p.radius[j],
                )
            };
            if let Some(g) = g {
                visit((g.overlap, p.radius[i].min(p.radius[j]), normal_spring_energy(normal, c, g.overlap)));
            }
        }
    }

    /// The pairs of a removed particle go with it; the others follow their particles (the
    /// list's `set_state` turns the pairs now stored the other way round, negating their
    /// histories, and puts the list in its order).
    fn rearrange(&mut self, new_of: &[u32], list: &mut NeighborState) {
        let gone = |a: u32| new_of[a as usize] == u32::MAX;
        let (pairs, pair_history): (Vec<[u32; 2]>, Vec<Vec3>) = list
            .pairs
            .iter()
            .zip(&list.pair_history)
            .filter(|([a, b], _)| !gone(*a) && !gone(*b))
            .map(|(&[a, b], &h)| ([new_of[a as usize], new_of[b as usize]], h))
            .unzip();
        (list.pairs, list.pair_history) = (pairs, pair_history);
    }
}

/// The coefficients of the contact of slots `i` and `j`: their phases', formed for the pair's
/// own R* and effective mass where the table is per unit size (the pull-off distance too).
fn pair_coeffs(v: &View, i: usize, j: usize) -> ContactCoeffs {
    let p = v.particles;
    let c = v.coeffs.pair(p.phase[i] as usize, p.phase[j] as usize);
    if !v.coeffs.sized() {
        return *c;
    }
    let (ra, rb) = (p.radius[i], p.radius[j]);
    let r_star = ra * rb / (ra + rb);
    let mut sized = contact_coeffs(v.coeffs, &v.law, c, r_star, pair_mass(&p.mass, v.held, i, j));
    sized.pull_off = crate::with_normal_submodel!(v.law.normal, |N| contact_reach::<N>(v.coeffs, c, r_star));
    sized
}

/// The particle pairs (ids) and their histories, from the neighbour list.
impl crate::checkpoint::Saved for Pairs {
    fn save<W: std::io::Write>(
        &self,
        sim: &crate::Simulation,
        e: &mut crate::checkpoint::Enc<W>,
    ) -> std::io::Result<()> {
        let (id, nl) = (&sim.particles().id, sim.neighbors());
        e.pairs(nl.pair_count(), nl.pairs().map(|[a, b]| [id[a as usize], id[b as usize]]))?;
        e.vec3s_from(nl.pair_histories())
    }

    fn saved_bytes(&self, sim: &crate::Simulation) -> usize {
        crate::checkpoint::pairs_bytes(sim.neighbors().pair_count())
    }

    fn load<R: std::io::Read>(
        d: &mut crate::checkpoint::Dec<R>,
        state: &mut crate::checkpoint::SourceState,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        state.pairs = d.pairs("pairs")?;
        state.pair_history = d.vec3s("pair history")?;
        Ok(())
    }
}
