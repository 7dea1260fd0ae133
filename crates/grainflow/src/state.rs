//! Particle state as a structure of arrays.
//!
//! Every per-particle field is its own `Vec`; index `i` is the particle's current slot, `id[i]`
//! its identity. A slot is only storage: the simulation moves particles to other slots when it
//! re-sorts them, inserts or removes some, and remaps everything kept by slot (contact
//! histories, prescribed motion) as it does; checkpoints and outputs name particles by ids.

use crate::math::{Vec3, sphere_inertia, sphere_mass};

/// All particles of a simulation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// Stable ids (unique).
    pub id: Vec<u32>,
    /// Phase index into the simulation's phase list.
    pub phase: Vec<u32>,
    /// Radius, m.
    pub radius: Vec<f64>,
    /// Mass, kg.
    pub mass: Vec<f64>,
    /// Moment of inertia (2/5)·m·R², kg·m².
    pub inertia: Vec<f64>,
    /// Centre position, m.
    pub position: Vec<Vec3>,
    /// Velocity, m/s.
    pub velocity: Vec<Vec3>,
    /// Angular velocity, rad/s.
    pub omega: Vec<Vec3>,
    /// Force accumulator, N; empty (zero) in a bed not yet in a simulation, which fills it.
    pub force: Vec<Vec3>,
    /// Torque accumulator, N·m; empty (zero) like `force`.
    pub torque: Vec<Vec3>,
    /// Previous step's linear acceleration (Adams–Bashforth history), m/s²; empty unless the
    /// Adams–Bashforth integrator runs.
    pub accel_prev: Vec<Vec3>,
    /// Previous step's angular acceleration (Adams–Bashforth history), rad/s²; empty unless
    /// the Adams–Bashforth integrator runs.
    pub alpha_prev: Vec<Vec3>,
}

/// One particle's initial data, for building [`Particles`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleInit {
    /// Stable id.
    pub id: u32,
    /// Phase index.
    pub phase: u32,
    /// Radius, m.
    pub radius: f64,
    /// Density, kg/m³.
    pub density: f64,
    /// Position, m.
    pub position: Vec3,
    /// Velocity, m/s.
    pub velocity: Vec3,
    /// Angular velocity, rad/s.
    pub omega: Vec3,
}

impl Particles {
    /// An empty set with room for `n` particles.
    pub fn with_capacity(n: usize) -> Self {
        let v3 = || Vec::with_capacity(n);
        Particles {
            id: Vec::with_capacity(n),
            phase: Vec::with_capacity(n),
            radius: Vec::with_capacity(n),
            mass: Vec::with_capacity(n),
            inertia: Vec::with_capacity(n),
            position: v3(),
            velocity: v3(),
            omega: v3(),
            force: v3(),
            torque: v3(),
            accel_prev: Vec::new(),
            alpha_prev: Vec::new(),
        }
    }

    /// Builds the set from initial data; mass and inertia follow from radius and density.
    pub fn from_init(init: &[ParticleInit]) -> Self {
        let mut p = Particles::with_capacity(init.len());
        for q in init {
            p.push(q);
        }
        p
    }

    /// [`from_init`](Particles::from_init) of a set given away, without its force and torque
    /// (empty: zero until a simulation holds the set): its memory goes as the particles are
    /// built (from the back, a block at a time), so that a large bed is never held twice.
    pub fn from_init_vec(mut init: Vec<ParticleInit>) -> Self {
        const BLOCK: usize = 1 << 16;
        let n = init.len();
        let mut p = Particles {
            id: Vec::with_capacity(n),
            phase: Vec::with_capacity(n),
            radius: Vec::with_capacity(n),
            mass: Vec::with_capacity(n),
            inertia: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            velocity: Vec::with_capacity(n),
            omega: Vec::with_capacity(n),
            ..Particles::default()
        };
        // Last first, so that the first particles are at the end, where they can be let go.
        init.reverse();
        while !init.is_empty() {
            let from = init.len().saturating_sub(BLOCK);
            for q in init[from..].iter().rev() {
                p.push_state(q);
            }
            init.truncate(from);
            if init.capacity() > 2 * init.len() + BLOCK {
                init.shrink_to_fit();
            }
        }
        p
    }

    /// Keeps only the particles of `slots` (ascending), in place, and gives back the memory of
    /// the others.
    pub fn keep_slots(&mut self, slots: &[u32]) {
        fn keep<T: Copy>(v: &mut Vec<T>, slots: &[u32]) {
            if v.is_empty() {
                return;
            }
            for (k, &s) in slots.iter().enumerate() {
                v[k] = v[s as usize];
            }
            v.truncate(slots.len());
            // Room is kept for what arrives next (particles from other ranks, ghosts), unless
            // most of the set went.
            if v.capacity() > 2 * slots.len() + 1024 {
                v.shrink_to_fit();
            }
        }
        debug_assert!(slots.windows(2).all(|w| w[0] < w[1]));
        keep(&mut self.id, slots);
        keep(&mut self.phase, slots);
        keep(&mut self.radius, slots);
        keep(&mut self.mass, slots);
        keep(&mut self.inertia, slots);
        keep(&mut self.position, slots);
        keep(&mut self.velocity, slots);
        keep(&mut self.omega, slots);
        keep(&mut self.force, slots);
        keep(&mut self.torque, slots);
        keep(&mut self.accel_prev, slots);
        keep(&mut self.alpha_prev, slots);
    }

    /// Appends one particle.
    pub fn push(&mut self, q: &ParticleInit) {
        self.push_state(q);
        self.force.push(Vec3::ZERO);
        self.torque.push(Vec3::ZERO);
    }

    /// [`push`](Particles::push) without the force and torque.
    fn push_state(&mut self, q: &ParticleInit) {
        let m = sphere_mass(q.radius, q.density);
        self.id.push(q.id);
        self.phase.push(q.phase);
        self.radius.push(q.radius);
        self.mass.push(m);
        let inertia = sphere_inertia(m, q.radius);
        self.inertia.push(inertia);
        self.position.push(q.position);
        self.velocity.push(q.velocity);
        self.omega.push(q.omega);
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.id.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    /// Slot of the particle with stable id `id`, if present (linear search; for set-up only).
    pub fn index_of(&self, id: u32) -> Option<usize> {
        self.id.iter().position(|&x| x == id)
    }

    /// Largest radius, m (0 when empty).
    pub fn max_radius(&self) -> f64 {
        self.radius.iter().copied().fold(0.0, f64::max)
    }

    /// Heap bytes held by the arrays.
    pub fn heap_bytes(&self) -> usize {
        let v3 = [
            &self.position,
            &self.velocity,
            &self.omega,
            &self.force,
            &self.torque,
            &self.accel_prev,
            &self.alpha_prev,
        ];
        let f = [&self.radius, &self.mass, &self.inertia];
        v3.iter().map(|v| v.capacity() * std::mem::size_of::<Vec3>()).sum::<usize>()
            + f.iter().map(|v| v.capacity() * 8).sum::<usize>()
            + (self.id.capacity() + self.phase.capacity()) * 4
    }

    /// The particles of slots `order`, in that order (a permutation of the slots, or some of
    /// them): slot `k` of the result is slot `order[k]` of `self`.
    pub fn gathered(&self, order: &[usize]) -> Particles {
        fn pick<T: Copy>(v: &[T], order: &[usize]) -> Vec<T> {
            if v.is_empty() { Vec::new() } else { order.iter().map(|&i| v[i]).collect() }
        }
        Particles {
            id: pick(&self.id, order),
            phase: pick(&self.phase, order),
            radius: pick(&self.radius, order),
            mass: pick(&self.mass, order),
            inertia: pick(&self.inertia, order),
            position: pick(&self.position, order),
            velocity: pick(&self.velocity, order),
            omega: pick(&self.omega, order),
            force: pick(&self.force, order),
            torque: pick(&self.torque, order),
            accel_prev: pick(&self.accel_prev, order),
            alpha_prev: pick(&self.alpha_prev, order),
        }
    }

    /// Appends the particles of `other` (same fields; its Adams–Bashforth history only if this
    /// set keeps one).
    pub fn append(&mut self, other: &Particles) {
        self.id.extend_from_slice(&other.id);
        self.phase.extend_from_slice(&other.phase);
        self.radius.extend_from_slice(&other.radius);
        self.mass.extend_from_slice(&other.mass);
        self.inertia.extend_from_slice(&other.inertia);
        self.position.extend_from_slice(&other.position);
        self.velocity.extend_from_slice(&other.velocity);
        self.omega.extend_from_slice(&other.omega);
        self.force.extend_from_slice(&other.force);
        self.torque.extend_from_slice(&other.torque);
        self.accel_prev.extend_from_slice(&other.accel_prev);
        self.alpha_prev.extend_from_slice(&other.alpha_prev);
    }

    /// The slots in the order of the particles' ids (for outputs that must not depend on how
    /// the particles are stored).
    pub fn id_order(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_unstable_by_key(|&i| self.id[i]);
        order
    }

    /// Zeroes the force and torque accumulators.
    pub fn clear_forces(&mut self) {
        self.force.fill(Vec3::ZERO);
        self.torque.fill(Vec3::ZERO);
    }
}

/// No slot: a particle not held here.
pub(crate) const NO_SLOT: u32 = u32::MAX;

/// The slot of each id among particles (each id at most once): a table by id where the ids
/// are dense enough (at most about twice as many ids as slots), else the (id, slot) pairs
/// sorted.
pub(crate) struct SlotsById {
    by_id: Vec<u32>,
    sorted: Vec<(u32, u32)>,
}

impl SlotsById {
    pub(crate) fn new(ids: &[u32]) -> Self {
        let span = ids.iter().max().map_or(0, |&m| m as usize + 1);
        if span <= 2 * ids.len() + 1024 {
            let mut by_id = vec![NO_SLOT; span];
            for (s, &id) in ids.iter().enumerate() {
                by_id[id as usize] = s as u32;
            }
            Self { by_id, sorted: Vec::new() }
        } else {
            let mut sorted: Vec<(u32, u32)> = ids.iter().enumerate().map(|(s, &id)| (id, s as u32)).collect();
            sorted.sort_unstable();
            Self { by_id: Vec::new(), sorted }
        }
    }

    /// The slot of `id`, or [`NO_SLOT`].
    pub(crate) fn get(&self, id: u32) -> u32 {
        if self.sorted.is_empty() {
            self.by_id.get(id as usize).copied().unwrap_or(NO_SLOT)
        } else {
            self.sorted.binary_search_by_key(&id, |e| e.0).map_or(NO_SLOT, |k| self.sorted[k].1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_given_away_or_kept_in_part_builds_the_same_particles() {
        // Across the blocks the set is taken in (65 536), and with none.
        for n in [0, 1, 7, (1 << 16) + 3, 2 << 16] {
            let init: Vec<ParticleInit> = (0..n)
                .map(|k| {
                    let x = k as f64;
                    ParticleInit {
                        id: k as u32 + 1,
                        phase: (k % 3) as u32,
                        radius: 1e-3 * (1.0 + (k % 5) as f64),
                        density: 2500.0 + x,
                        position: Vec3::new(x, -x, 0.5 * x),
                        velocity: Vec3::new(0.1 * x, 0.0, -x),
                        omega: Vec3::new(0.0, x, 1.0),
                    }
                })
                .collect();
            let p = Particles::from_init(&init);
            let mut given = Particles::from_init_vec(init.clone());
            assert!(given.force.is_empty() && given.torque.is_empty());
            (given.force, given.torque) = (p.force.clone(), p.torque.clone());
            assert_eq!(given, p, "{n} particles");
            // Every third particle kept in place is the same as gathered.
            let slots: Vec<u32> = (0..n as u32).filter(|s| s % 3 == 1).collect();
            let mut kept = p.clone();
            kept.keep_slots(&slots);
            assert_eq!(
                kept,
                p.gathered(&slots.iter().map(|&s| s as usize).collect::<Vec<_>>()),
                "{n} particles"
            );
        }
    }
}
