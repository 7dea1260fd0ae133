//! Restart: a run interrupted at any step and continued from its checkpoint is bit-identical
//! to the uninterrupted run — positions, velocities, spins, contact histories, Adams–Bashforth
//! history, neighbour list — for every integrator and contact law. Broken checkpoints are
//! refused with a clear error.

mod common;

use common::*;
use grainflow::checkpoint::{CheckpointError, RestoreError};
use grainflow::contact::{ContactLaw, ContactParams, NormalModel, TangentialModel};
use grainflow::{
    Integrator, MotionRule, NormalDamping, PrescribedMotion, Simulation, SimulationConfig, Vec3, Wall,
};

/// 120 frictional, inelastic particles falling into a box under gravity (many contacts
/// forming and breaking, neighbour rebuilds), one of them held fixed by prescribed motion.
fn setup(
    normal: NormalModel,
    integrator: Integrator,
) -> (SimulationConfig, Vec<grainflow::state::ParticleInit>) {
    let mut law = ContactLaw { tangential: TangentialModel::IncrementalMindlin, ..ContactLaw::mfix(normal) };
    if normal == NormalModel::Jkr {
        // JKR takes LAMMPS's damping (as in `granular jkr … damping tsuji`).
        law.damping = NormalDamping::Tsuji;
    }
    let (phases, params) = match normal {
        NormalModel::LinearSpringDashpot => {
            (vec![phase("glass", 0.004, 2500.0)], lsd_params(500.0, 0.7, 0.4))
        }
        NormalModel::Hertz => {
            (vec![elastic_phase("glass", 0.004, 2500.0, 5e6, 0.3)], hertz_params(0.7, 0.7, 0.4))
        }
        // Cohesive: contacts hold past the touch (to −δ_c) and pull off, so the restart must
        // carry the formed contacts' histories as well.
        NormalModel::Jkr => (
            vec![elastic_phase("glass", 0.004, 2500.0, 5e6, 0.3)],
            ContactParams { surface_energy: Some(5e-3), ..hertz_params(0.7, 0.7, 0.4) },
        ),
    };
    let lo = Vec3::ZERO;
    let hi = Vec3::new(0.03, 0.06, 0.03);
    let mut cfg = config(
        law,
        phases,
        vec![wall_material("steel", Some(5e6), Some(0.3))],
        Wall::domain_box(lo, hi, 0),
        vec![params],
        vec![params],
        integrator,
        2e-5,
    );
    cfg.gravity = Vec3::new(0.0, -9.81, 0.0);
    cfg.motion = vec![PrescribedMotion { particle: 1, rule: MotionRule::Hold }];
    let mut rng = Rng::new(7);
    let mut init = Vec::new();
    'outer: while init.len() < 120 {
        let x = rng.in_box(Vec3::splat(0.003), hi - Vec3::splat(0.003));
        for q in &init {
            let q: &grainflow::state::ParticleInit = q;
            if (q.position - x).length() < 0.0045 {
                continue 'outer;
            }
        }
        init.push(particle(
            init.len() as u32 + 1,
            0,
            rng.range(0.0017, 0.0021),
            2500.0,
            x,
            rng.unit() * 0.05,
        ));
    }
    (cfg, init)
}

fn assert_identical(a: &Simulation, b: &Simulation, what: &str) {
    assert_eq!(a.step_index(), b.step_index(), "{what}: steps");
    assert_eq!(a.particles(), b.particles(), "{what}: particle state differs");
    let (na, nb) = (a.neighbors().state(), b.neighbors().state());
    assert_eq!(na, nb, "{what}: neighbour list or contact histories differ");
}

#[test]
fn restarted_runs_are_bit_identical_for_every_integrator_and_law() {
    for normal in [NormalModel::LinearSpringDashpot, NormalModel::Hertz, NormalModel::Jkr] {
        for integrator in [Integrator::Euler, Integrator::AdamsBashforth, Integrator::VelocityVerlet] {
            let what = format!("{normal:?} {integrator:?}");
            let (cfg, init) = setup(normal, integrator);
            let mut straight = simulation(cfg.clone(), &init);
            let mut first = simulation(cfg.clone(), &init);
            // Stop at an odd step, in the middle of the settling (contacts forming).
            let (stop, end) = (4237, 8000);
            for _ in 0..stop {
                first.step();
            }
            first.set_run_id("run-7");
            let bytes = first.checkpoint("case-hash");
            drop(first);
            let mut resumed = Simulation::restore(cfg, &bytes, Some("case-hash")).expect("restores");
            assert_eq!(resumed.run_id(), "run-7", "{what}: the run id goes with the state");
            for _ in 0..end {
                straight.step();
            }
            for _ in stop..end {
                resumed.step();
            }
            let contacts = straight.diagnostics().contacts;
            assert!(
                contacts > 50,
                "{what}: only {contacts} contacts — the test would not exercise histories"
            );
            assert_identical(&straight, &resumed, &what);
        }
    }
}

/// The checkpoint's own error of a restore that must fail.
fn checkpoint_error(restored: Result<Simulation, RestoreError>) -> CheckpointError {
    match restored {
        Err(RestoreError::Checkpoint(e)) => e,
        other => panic!("expected a checkpoint error, got {other:?}"),
    }
}

#[test]
fn broken_checkpoints_are_refused_with_a_clear_error() {
    let (cfg, init) = setup(NormalModel::LinearSpringDashpot, Integrator::AdamsBashforth);
    let mut sim = simulation(cfg.clone(), &init);
    for _ in 0..100 {
        sim.step();
    }
    let good = sim.checkpoint("h1");
    let err =
        |bytes: &[u8], hash: &str| checkpoint_error(Simulation::restore(cfg.clone(), bytes, Some(hash)));
    assert!(matches!(err(&good[..good.len() / 2], "h1"), CheckpointError::Truncated(_)));
    assert!(matches!(err(&good[..10], "h1"), CheckpointError::Truncated(_)));
    let mut flipped = good.clone();
    let k = flipped.len() / 3;
    flipped[k] ^= 0x10;
    assert_eq!(err(&flipped, "h1"), CheckpointError::Corrupted);
    let mut version = good.clone();
    version[8] = 99;
    assert_eq!(
        err(&version, "h1"),
        CheckpointError::Version {
            found: 99,
            oldest: grainflow::checkpoint::OLDEST_FORMAT_READ,
            newest: grainflow::checkpoint::FORMAT_VERSION
        }
    );
    // Bytes after the checksum: two checkpoints joined, or one appended to.
    let mut longer = good.clone();
    longer.extend_from_slice(b"\n");
    assert_eq!(err(&longer, "h1"), CheckpointError::TrailingBytes(1));
    let twice = [good.as_slice(), good.as_slice()].concat();
    assert_eq!(err(&twice, "h1"), CheckpointError::TrailingBytes(good.len() as u64));
    assert_eq!(err(b"PK\x03\x04 not a checkpoint", "h1"), CheckpointError::NotACheckpoint);
    assert!(matches!(err(&good, "h2"), CheckpointError::WrongCase { .. }));
    // Messages a user reads:
    assert!(CheckpointError::Corrupted.to_string().contains("corrupted"));
    assert!(CheckpointError::Truncated("payload").to_string().contains("truncated"));
    // The good one still restores after all that, and a changed case is accepted on request.
    Simulation::restore(cfg.clone(), &good, Some("h1")).expect("restores");
    Simulation::restore(cfg, &good, None).expect("restores for a changed case when asked");
}

/// Hands out at most `piece` bytes per read, as a pipe or a slow file system may, and fails
/// with an I/O error after `fail_after` bytes.
struct Trickle<'a> {
    bytes: &'a [u8],
    piece: usize,
    fail_after: usize,
    given: usize,
}

impl std::io::Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.given >= self.fail_after {
            return Err(std::io::Error::other("device went away"));
        }
        let n = buf.len().min(self.piece).min(self.bytes.len()).min(self.fail_after - self.given);
        buf[..n].copy_from_slice(&self.bytes[..n]);
        self.bytes = &self.bytes[n..];
        self.given += n;
        Ok(n)
    }
}

#[test]
fn a_checkpoint_read_as_a_stream_restores_the_same_state() {
    let (cfg, init) = setup(NormalModel::Hertz, Integrator::VelocityVerlet);
    let mut sim = simulation(cfg.clone(), &init);
    for _ in 0..6000 {
        sim.step();
    }
    let bytes = sim.checkpoint("h");
    let contacts = sim.diagnostics().contacts;
    assert!(contacts > 50, "only {contacts} contacts: the state should hold contact histories");
    let trickle = |piece, fail_after| Trickle { bytes: &bytes, piece, fail_after, given: 0 };
    // In pieces of 7 bytes (never a whole number, never aligned to a value): the same state as
    // from memory, and as the simulation itself.
    let streamed =
        Simulation::restore_from(cfg.clone(), trickle(7, usize::MAX), bytes.len() as u64, Some("h"))
            .expect("restores from a stream");
    let from_memory = Simulation::restore(cfg.clone(), &bytes, Some("h")).expect("restores");
    assert_identical(&streamed, &from_memory, "stream vs memory");
    assert_identical(&streamed, &sim, "stream vs the simulation");
    // A read that fails half-way is reported as such (not as damage), one that ends early as
    // truncation, and a stream shorter than its stated size too.
    let restore = |r: Trickle, size: usize| {
        checkpoint_error(Simulation::restore_from(cfg.clone(), r, size as u64, Some("h")))
    };
    let half = bytes.len() / 2;
    for fail_after in [half, 3] {
        match restore(trickle(4096, fail_after), bytes.len()) {
            CheckpointError::Read(m) => assert!(m.contains("device went away"), "{m}"),
            other => panic!("expected a read error after {fail_after} bytes, got {other:?}"),
        }
    }
    let short = Trickle { bytes: &bytes[..half], piece: 4096, fail_after: usize::MAX, given: 0 };
    assert!(matches!(restore(short, bytes.len()), CheckpointError::Truncated(_)));
    assert!(matches!(restore(trickle(4096, usize::MAX), half), CheckpointError::Truncated(_)));
}

#[test]
fn a_damaged_count_is_refused_as_corruption_without_allocating_it() {
    let (cfg, init) = setup(NormalModel::LinearSpringDashpot, Integrator::Euler);
    let mut sim = simulation(cfg.clone(), &init);
    for _ in 0..200 {
        sim.step();
    }
    let good = sim.checkpoint("h");
    // The payload starts (after the 20-byte header) with the case hash's length, then the
    // hash, the run id's length (the run id is empty), step, time, time step, start time, two
    // flags, two load peaks and the inexact-sum count (8 bytes each), then the count of ids.
    // Claiming 2^61 ids (16 EiB) must be refused from the payload's length, before any memory
    // is asked for.
    let ids_count = 20 + 8 + "h".len() + 8 + 9 * 8;
    assert_eq!(
        u64::from_le_bytes(good[ids_count..ids_count + 8].try_into().unwrap()),
        init.len() as u64,
        "layout assumed by this test"
    );
    let mut damaged = good.clone();
    damaged[ids_count..ids_count + 8].copy_from_slice(&(1u64 << 61).to_le_bytes());
    assert_eq!(checkpoint_error(Simulation::restore(cfg, &damaged, Some("h"))), CheckpointError::Corrupted);
}

/// Checkpoint format 3 names the pairs by particle ids: with ids in no order (none equal to
/// its slot or its slot + 1), a restart is still bit-identical to the uninterrupted run.
#[test]
fn pairs_named_by_scrambled_ids_restore_bit_identically() {
    let (mut cfg, mut init) = setup(NormalModel::LinearSpringDashpot, Integrator::AdamsBashforth);
    // 37 and 120 are coprime: k ↦ 37k mod 120 is a permutation of the slots.
    for (k, p) in init.iter_mut().enumerate() {
        p.id = 1000 + 3 * ((37 * k as u32) % 120);
    }
    cfg.motion = vec![PrescribedMotion { particle: init[0].id, rule: MotionRule::Hold }];
    let mut straight = simulation(cfg.clone(), &init);
    let mut first = simulation(cfg.clone(), &init);
    // As in the test above: stopped mid-settling, compared when the bed is dense.
    for _ in 0..4237 {
        first.step();
        straight.step();
    }
    let bytes = first.checkpoint("h");
    let mut resumed = Simulation::restore(cfg, &bytes, Some("h")).expect("restores");
    for _ in 4237..8000 {
        resumed.step();
        straight.step();
    }
    let contacts = straight.diagnostics().contacts;
    assert!(contacts > 50, "only {contacts} contacts: the histories would not be exercised");
    assert_identical(&straight, &resumed, "scrambled ids");
}
