//! A case's initial particles handed out over ranks: rank 0 reads and checks them all, as one
//! process does ([`grainflow_case::Bed::Here`]); the others read the rest of the case alone
//! ([`grainflow_case::Bed::Elsewhere`]). [`share_case`] then makes the ranks agree on whether
//! the case holds (rank 0's refusal is every rank's), gives them rank 0's time step and case
//! hash (both depend on the particles), and sends each rank the particles of the box it will
//! start with, in the file's order, a chunk at a time. No rank but 0 ever holds the whole
//! set, and rank 0 holds it only until its share is cut out.
//!
//! ```text
//! agreement, from each rank:   [failed, bytes, message words...]
//! from rank 0 to every rank:   [particles per rank..., rule, dt or factor bits, hash bytes,
//!                               hash words...]
//! a chunk, rank 0 to rank r:   13 words per particle (id << 32 | phase, radius, mass,
//!                              inertia, position, velocity, angular velocity: the bits)
//! ```

use crate::relay::{bytes_of, words_of};
use grainflow::domain::Comm;
use grainflow::{Particles, TimeStepRule, Vec3};
use grainflow_case::Case;

/// Particles sent in one exchange (13 words each: 6.8 MB).
const CHUNK: usize = 1 << 16;

/// Words per particle in a chunk.
const WORDS: usize = 13;

/// Why the ranks did not all get their share: the message of the lowest rank that failed
/// (rank 0's whenever it failed), and that rank.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused {
    /// The lowest failing rank.
    pub rank: usize,
    /// Its message.
    pub message: String,
}

/// Every rank's case, rank 0's whole and the others' without their particles (`mine`, or
/// the message why it did not load), made one: if any rank failed, every rank returns the
/// lowest failing rank's message; otherwise every rank returns its case with rank 0's time
/// step and hash and its own share of the particles (`particles_are_share`): those in the box
/// it will start with ([`grainflow::simulation::starting_ranks`]), in the file's order. A
/// collective: every rank calls it once.
pub fn share_case(comm: &dyn Comm, mine: Result<Case, String>) -> Result<Case, Refused> {
    let (rank, ranks) = (comm.rank(), comm.size());
    let said = match &mine {
        Ok(_) => vec![0, 0],
        Err(m) => {
            let mut w = vec![1, m.len() as u64];
            w.extend(words_of(m.as_bytes()));
            w
        }
    };
    let all = comm.all_gather(&said);
    if let Some((r, w)) = all.iter().enumerate().find(|(_, w)| w[0] == 1) {
        return Err(Refused {
            rank: r,
            message: String::from_utf8_lossy(&bytes_of(&w[2..], w[1])).into_owned(),
        });
    }
    let mut case = mine.expect("every rank loaded its case");
    // What depends on the particles, from rank 0: with the number of particles each rank
    // starts with, in the boxes the ranks will cut for them (so that none migrates at once).
    let mut runs: Vec<Vec<u32>> = vec![Vec::new(); ranks];
    let head = if rank == 0 {
        let starts = grainflow::simulation::starting_ranks(&case.particles, case.config.periodic, ranks);
        for (i, &r) in starts.iter().enumerate() {
            runs[r as usize].push(i as u32);
        }
        drop(starts);
        let (tag, value) = match case.config.time_step {
            TimeStepRule::Fixed(dt) => (0, dt),
            TimeStepRule::Mfix { factor } => (1, factor),
        };
        let mut w: Vec<u64> = runs.iter().map(|r| r.len() as u64).collect();
        w.extend([tag, value.to_bits(), case.hash.len() as u64]);
        w.extend(words_of(case.hash.as_bytes()));
        w
    } else {
        Vec::new()
    };
    let head = comm.all_gather(&head).swap_remove(0);
    let (counts, head) = head.split_at(ranks);
    let value = f64::from_bits(head[1]);
    case.config.time_step =
        if head[0] == 0 { TimeStepRule::Fixed(value) } else { TimeStepRule::Mfix { factor: value } };
    case.hash = String::from_utf8_lossy(&bytes_of(&head[3..], head[2])).into_owned();
    // Each rank's particles, a chunk per exchange; every rank makes the same exchanges.
    // Without force and torque, as rank 0's bed (zero until the simulation holds them).
    let mut got = Particles::with_capacity(counts[rank] as usize);
    (got.force, got.torque) = (Vec::new(), Vec::new());
    for to in 1..ranks {
        for start in (0..counts[to] as usize).step_by(CHUNK) {
            let end = (start + CHUNK).min(counts[to] as usize);
            let mut out = vec![Vec::new(); ranks];
            if rank == 0 {
                out[to] = chunk(&case.particles, &runs[to][start..end]);
            }
            let came = comm.exchange(out).swap_remove(0);
            if rank == to {
                read_chunk(&came, &mut got);
            }
        }
    }
    if rank == 0 {
        // In place: the whole set is never held twice over.
        got = std::mem::take(&mut case.particles);
        got.keep_slots(&runs[0]);
    }
    case.particles = got;
    case.particles_are_share = true;
    Ok(case)
}

fn chunk(p: &Particles, slots: &[u32]) -> Vec<u64> {
    let mut w = Vec::with_capacity(slots.len() * WORDS);
    for i in slots.iter().map(|&i| i as usize) {
        w.push((u64::from(p.id[i]) << 32) | u64::from(p.phase[i]));
        w.extend([p.radius[i], p.mass[i], p.inertia[i]].map(f64::to_bits));
        for v in [p.position[i], p.velocity[i], p.omega[i]] {
            w.extend(v.to_array().map(f64::to_bits));
        }
    }
    w
}

fn read_chunk(w: &[u64], p: &mut Particles) {
    let v = |k: usize| Vec3::new(f64::from_bits(w[k]), f64::from_bits(w[k + 1]), f64::from_bits(w[k + 2]));
    for at in (0..w.len()).step_by(WORDS) {
        p.id.push((w[at] >> 32) as u32);
        p.phase.push(w[at] as u32);
        p.radius.push(f64::from_bits(w[at + 1]));
        p.mass.push(f64::from_bits(w[at + 2]));
        p.inertia.push(f64::from_bits(w[at + 3]));
        p.position.push(v(at + 4));
        p.velocity.push(v(at + 7));
        p.omega.push(v(at + 10));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow::domain::LocalComm;
    use grainflow_case::Bed;
    use std::path::Path;
    use std::sync::Arc;

    /// The settling bed of the examples (486 beads of their own sizes) on Hertz contacts,
    /// copied into `dir` with `edit` applied to its particle file.
    fn bed_case(dir: &Path, edit: impl Fn(String) -> String) -> std::path::PathBuf {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/settling-bed");
        // Hertz contacts, whose default step is taken from the smallest particles.
        let case = r#"version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.05, 0.2, 0.05]
[physics]
gravity = [0.0, -9.80665, 0.0]
[[phases]]
name = "glass"
diameter = 0.004
density = 2500.0
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[[wall_materials]]
name = "wall"
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[contact]
model = "hertz"
[contact.particle]
en = 0.7
et = 0.5
mu = 0.4
[contact.wall]
en = 0.7
et = 0.5
mu = 0.4
[time]
t_stop = 0.01
[particles]
file = "particles.csv"
"#;
        std::fs::write(dir.join("case.toml"), case).unwrap();
        let csv = std::fs::read_to_string(src.join("particles.csv")).unwrap();
        std::fs::write(dir.join("particles.csv"), edit(csv)).unwrap();
        dir.join("case.toml")
    }

    /// Every rank of 3 loads the case as `grainflow run` does over ranks and takes its share.
    fn on_three_ranks(path: &Path) -> Vec<Result<Case, Refused>> {
        std::thread::scope(|s| {
            let ranks: Vec<_> = LocalComm::team(3)
                .into_iter()
                .map(|comm| {
                    s.spawn(move || {
                        let comm: Arc<dyn Comm> = Arc::new(comm);
                        let bed = if comm.rank() == 0 { Bed::Here } else { Bed::Elsewhere };
                        let relay = crate::relay::over_ranks(comm.clone());
                        let mine =
                            grainflow_case::load_scoped(path, &[], &relay, bed).map_err(|e| e.to_string());
                        share_case(&*comm, mine)
                    })
                })
                .collect();
            ranks.into_iter().map(|h| h.join().expect("rank")).collect()
        })
    }

    fn by_id(p: &Particles) -> Particles {
        let mut order: Vec<usize> = (0..p.len()).collect();
        order.sort_by_key(|&i| p.id[i]);
        p.gathered(&order)
    }

    #[test]
    fn every_rank_gets_its_box_with_rank_0s_time_step_and_hash() {
        let dir = tempfile::tempdir().unwrap();
        let path = bed_case(dir.path(), |t| t);
        let one = grainflow_case::load(&path).expect("the bed loads");
        // Without rank 0's step a rank would run with the phases' (the nudge this test sees).
        let alone = grainflow_case::load_scoped(&path, &[], &grainflow_case::input::direct, Bed::Elsewhere)
            .expect("the rest of the case loads");
        assert!(alone.particles.is_empty());
        assert_ne!(alone.config.time_step, one.config.time_step);
        assert_ne!(alone.hash, one.hash);
        let cases: Vec<Case> = on_three_ranks(&path).into_iter().map(|c| c.expect("shared")).collect();
        let starts = grainflow::simulation::starting_ranks(&one.particles, one.config.periodic, 3);
        let mut all = Particles::default();
        for (r, c) in cases.iter().enumerate() {
            assert!(c.particles_are_share);
            assert_eq!(c.config.time_step, one.config.time_step, "rank {r}");
            assert_eq!(c.hash, one.hash, "rank {r}");
            // Its box's particles, in the file's order, bit for bit.
            let mine: Vec<usize> = (0..starts.len()).filter(|&i| starts[i] as usize == r).collect();
            assert!(mine.len() > one.particles.len() / 4, "rank {r} starts with {} of 486", mine.len());
            assert_eq!(c.particles, one.particles.gathered(&mine), "rank {r}");
            all.append(&c.particles);
        }
        assert_eq!(by_id(&all), by_id(&one.particles));
    }

    #[test]
    fn a_bad_particle_is_every_ranks_refusal_with_rank_0s_message() {
        let dir = tempfile::tempdir().unwrap();
        let path = bed_case(dir.path(), |t| t.replacen("\n300,glass,", "\n300,glas,", 1));
        let one = grainflow_case::load(&path).expect_err("a phase no one has").to_string();
        assert!(one.contains("line 301"), "{one}");
        for (r, got) in on_three_ranks(&path).into_iter().enumerate() {
            assert_eq!(got.err(), Some(Refused { rank: 0, message: one.clone() }), "rank {r}");
        }
    }
}
