//! Insertions and outlets in a run: the mass books close exactly, a restart mid-insertion is
//! bit-identical, the thread count changes nothing, placed particles never overlap.

mod common;

use common::*;
use grainflow::contact::NormalModel;
use grainflow::insertion::psd::{Basis, Mixture, MixturePart, SizeDistribution};
use grainflow::insertion::region::Region;
use grainflow::insertion::{Amount, Insertion, Outlet, OutletShape, Rate, Schedule};
use grainflow::{Integrator, Particles, Simulation, SimulationConfig, Vec3, Wall};

const RHO: f64 = 2500.0;
const D: f64 = 2e-3;
const DT: f64 = 2e-5;

/// Two phases of glass beads, 1.6–2.4 mm, by mass 30/70.
fn beads() -> Mixture {
    Mixture {
        parts: vec![
            MixturePart {
                phase: 0,
                density: RHO,
                fraction: 0.3,
                sizes: SizeDistribution::Uniform { min: 1.6e-3, max: 2.4e-3 },
            },
            MixturePart {
                phase: 1,
                density: 2.0 * RHO,
                fraction: 0.7,
                sizes: SizeDistribution::Normal { mean: D, sigma: 2e-4, min: 1.6e-3, max: 2.4e-3 },
            },
        ],
        basis: Basis::Mass,
    }
}

/// A 20 × 20 mm box, 60 mm tall, open at the bottom (z = 0): beads poured at the top at a
/// rate fall out of it through an outlet below the floor's opening.
fn pour_config(rate: f64, outlet: bool) -> SimulationConfig {
    let law = grainflow::ContactLaw::mfix(NormalModel::Hertz);
    let (lo, hi) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.02, 0.02, 0.06));
    let walls: Vec<Wall> = Wall::domain_box(lo, hi, 0).into_iter().filter(|w| w.normal.z <= 0.0).collect();
    let mut c = config(
        law,
        vec![elastic_phase("a", D, RHO, 1e7, 0.3), elastic_phase("b", D, 2.0 * RHO, 1e7, 0.3)],
        vec![wall_material("steel", Some(2e8), Some(0.3))],
        walls,
        vec![hertz_params(0.8, 0.8, 0.3); 3],
        vec![hertz_params(0.8, 0.8, 0.3); 2],
        Integrator::VelocityVerlet,
        DT,
    );
    c.gravity = Vec3::new(0.0, 0.0, -9.81);
    c.insertions = vec![Insertion {
        name: "pour".into(),
        region: Region::Box { lo: Vec3::new(0.0, 0.0, 0.045), hi: Vec3::new(0.02, 0.02, 0.06) },
        mixture: beads(),
        amount: None,
        schedule: Schedule::Rate { rate: Rate::Particles(rate), start: 0.0, every: 0.01 },
        velocity: Vec3::new(0.0, 0.0, -0.5),
        seed: 7,
        given: Vec::new(),
        max_initial_overlap: grainflow::insertion::DEFAULT_MAX_INITIAL_OVERLAP,
        plane_z: None,
    }];
    if outlet {
        c.outlets = vec![
            Outlet {
                name: "below".into(),
                shape: OutletShape::Plane {
                    point: Vec3::new(0.0, 0.0, -0.005),
                    normal: Vec3::new(0.0, 0.0, -1.0),
                },
            },
            Outlet {
                name: "domain".into(),
                shape: OutletShape::OutsideBox { lo, hi, axes: [true, true, false] },
            },
        ];
    }
    c
}

fn start(c: SimulationConfig) -> Simulation {
    Simulation::new(c, Particles::default()).expect("valid set-up")
}

/// The state in id order, as bits: positions, velocities, spins, radii, phases.
fn bits(sim: &Simulation) -> Vec<u64> {
    let (p, _) = sim.in_id_order();
    let mut out: Vec<u64> = p.id.iter().map(|&i| i as u64).collect();
    out.extend(p.phase.iter().map(|&i| i as u64));
    out.extend(p.radius.iter().map(|r| r.to_bits()));
    for v in [&p.position, &p.velocity, &p.omega] {
        out.extend(v.iter().flat_map(|x| x.to_array()).map(f64::to_bits));
    }
    out
}

/// Every two particles apart (placement's promise), brute force.
fn no_overlaps(p: &Particles) -> Result<(), String> {
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = (p.position[i] - p.position[j]).length();
            if d < p.radius[i] + p.radius[j] {
                return Err(format!(
                    "particles {} and {} overlap by {:e} m",
                    p.id[i],
                    p.id[j],
                    p.radius[i] + p.radius[j] - d
                ));
            }
        }
    }
    Ok(())
}

/// The books close exactly while beads are poured in and drain out: initial + inserted =
/// present + removed, in count and in mass quanta, at every check; and the inserted count
/// follows the rate (batch k brings the total to round(rate·(k+1)·every), less the ones
/// that found no room, which the books count too).
#[test]
fn the_books_close_exactly_while_pouring_and_draining() {
    let mut sim = start(pour_config(20_000.0, true));
    let mut removed_seen = false;
    for _ in 0..15 {
        sim.advance(1000);
        let books = sim.flow_books();
        assert!(books.close(), "the books do not close: {books:?}");
        assert_eq!(books.present.count as usize, sim.particles().len());
        // Batches every 0.01 s from t = 0, each at the first step starting at or after its
        // time: floor((t - dt)/0.01) + 1 of them by the end of the step ending at t.
        let batches = ((sim.time() - DT) / 0.01 + 1e-9).floor() as u64 + 1;
        let drawn = books.inserted_total().count + books.missed.iter().sum::<u64>();
        assert_eq!(drawn, (20_000.0 * 0.01 * batches as f64).round() as u64, "t = {}", sim.time());
        removed_seen |= books.removed_total().count > 0;
        let m = books.mass(books.present);
        let direct: f64 = sim.particles().mass.iter().sum();
        // The books' mass is each particle's mass rounded to 2^-60 of the largest: the plain
        // sum of a few thousand agrees to its own rounding, 1e-12 relative.
        assert!((m - direct).abs() <= 1e-12 * direct.max(1e-300), "{m} vs {direct}");
    }
    assert!(removed_seen, "no bead reached the outlet in 0.3 s");
    let books = sim.flow_books();
    // The open bottom's outlet took them: every removed bead crossed z = -5 mm (the domain's
    // side faces are walls, so none left sideways).
    assert!(books.removed[0].count > 0);
    assert_eq!(books.removed[1].count, 0, "beads left through the box's walls");
    // Outlets remove every 10 steps: a bead goes at most 10·dt·v (v < 2 m/s after a 0.1 m
    // fall from 0.5 m/s) = 0.4 mm beyond the outlet's plane at z = -5 mm.
    let lowest = sim.particles().position.iter().map(|x| x.z).fold(f64::INFINITY, f64::min);
    assert!(lowest > -0.0054, "a bead at z = {lowest} m, beyond the outlet");
}

/// A restart from a checkpoint written mid-insertion continues as the run without it, to
/// the bit, with the same books.
#[test]
fn a_restart_mid_insertion_is_bit_identical() {
    let mut straight = start(pour_config(20_000.0, true));
    straight.advance(3000);
    let mut first = start(pour_config(20_000.0, true));
    first.advance(1234);
    let bytes = first.checkpoint("case");
    let mut restarted =
        Simulation::restore(pour_config(20_000.0, true), &bytes, Some("case")).expect("restores");
    restarted.advance(3000 - 1234);
    assert!(straight.particles().len() > 1000);
    assert!(bits(&straight) == bits(&restarted), "the restarted run differs");
    assert_eq!(straight.flow_books(), restarted.flow_books());
}

/// Particles added and removed between steps (a user's hook or script) are counted apart
/// from the insertion's and the outlet's: the books close through both, the next inserted
/// particles take ids after the added ones, and a checkpoint carries the counts.
#[test]
fn particles_added_and_removed_by_hand_are_in_the_books() {
    let mut sim = start(pour_config(20_000.0, true));
    sim.advance(600);
    let top = sim.next_free_id();
    let added: Vec<grainflow::state::ParticleInit> = (0..3)
        .map(|k| grainflow::state::ParticleInit {
            id: top as u32 + 10 + k,
            phase: 0,
            radius: 1e-3,
            density: RHO,
            position: Vec3::new(0.005 + 0.005 * k as f64, 0.01, 0.03),
            velocity: Vec3::ZERO,
            omega: Vec3::ZERO,
        })
        .collect();
    sim.insert(&added).expect("added");
    assert_eq!(sim.next_free_id(), top + 13, "the next insertion's ids would meet the added ones");
    let taken: Vec<u32> = sim.particles().id[..2].to_vec();
    let mass_taken: f64 = sim.particles().mass[..2].iter().sum();
    assert_eq!(sim.remove_ids(&taken).expect("removed"), 2);
    sim.advance(900);
    let books = sim.flow_books();
    assert!(books.close(), "the books do not close: {books:?}");
    assert_eq!((books.added.count, books.taken.count), (3, 2));
    let one = RHO * std::f64::consts::FRAC_PI_6 * 8e-9;
    // Masses in quanta of 2^-60 of the largest bead's: within 1e-15 of the sums.
    assert!((books.mass(books.added) - 3.0 * one).abs() <= 1e-15 * one, "{:?}", books.added);
    assert!((books.mass(books.taken) - mass_taken).abs() <= 1e-15 * mass_taken);
    assert!(books.inserted_total().count > 0, "the insertion added nothing after the hand");
    let bytes = sim.checkpoint("case");
    let back = Simulation::restore(pour_config(20_000.0, true), &bytes, Some("case")).expect("restores");
    assert_eq!(back.flow_books(), books);
    assert_eq!(back.next_free_id(), sim.next_free_id());
}

/// The insertion and the removals do not depend on the thread count.
#[test]
fn one_and_several_threads_give_the_same_run() {
    let run = |threads: usize| {
        let mut sim = start(pour_config(20_000.0, true));
        sim.set_threads(threads).expect("threads");
        sim.advance(2500);
        (bits(&sim), sim.flow_books())
    };
    let one = run(1);
    for threads in [2, 3] {
        let other = run(threads);
        assert!(one.0 == other.0, "{threads} threads: the state differs");
        assert_eq!(one.1, other.1, "{threads} threads: the books differ");
    }
}

/// An insertion all at once at the start is in the initial state, placed without overlaps
/// with each other or the walls, inside its region, with the phases' densities.
#[test]
fn an_insertion_at_the_start_is_placed_without_overlaps() {
    let mut c = pour_config(1.0, false);
    c.insertions[0].schedule = Schedule::Once { at: 0.0 };
    c.insertions[0].amount = Some(Amount::VolumeFraction(0.3));
    c.insertions[0].region = Region::Box { lo: Vec3::new(0.0, 0.0, 0.0), hi: Vec3::new(0.02, 0.02, 0.03) };
    let sim = start(c);
    let p = sim.particles();
    // 30 % of 12 cm³ in beads of about 4.2 mm³: some 850.
    assert!(p.len() > 500, "{} placed", p.len());
    no_overlaps(p).unwrap();
    for i in 0..p.len() {
        let (x, r) = (p.position[i], p.radius[i]);
        assert!(x.min_element() >= r - 1e-15 && x.x <= 0.02 - r && x.y <= 0.02 - r && x.z <= 0.03 - r);
        let rho = if p.phase[i] == 0 { RHO } else { 2.0 * RHO };
        let m = sphere_mass(r, rho);
        assert!((p.mass[i] - m).abs() <= 1e-14 * m);
    }
    let books = sim.flow_books();
    assert!(books.close());
    // The volume drawn reaches 30 % of the region's, overshooting by at most one bead.
    let v: f64 = p.radius.iter().map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3)).sum();
    let target = 0.3 * 0.02 * 0.02 * 0.03;
    assert_eq!(books.missed[0], 0);
    assert!(
        v >= target && v < target + 4.0 / 3.0 * std::f64::consts::PI * 1.2e-3f64.powi(3),
        "{v} vs {target}"
    );
}

/// Two parts of one phase with their own densities (solid and porous beads): each particle has
/// the density of the part it was drawn from, and both parts come in (50/50 by number among
/// some 700 particles: each count is binomial, about 350 ± 13, so more than 100 of each).
#[test]
fn two_parts_of_one_phase_keep_their_own_densities() {
    let mut c = pour_config(1.0, false);
    let ins = &mut c.insertions[0];
    ins.schedule = Schedule::Once { at: 0.0 };
    ins.amount = Some(Amount::VolumeFraction(0.3));
    ins.region = Region::Box { lo: Vec3::new(0.0, 0.0, 0.0), hi: Vec3::new(0.02, 0.02, 0.03) };
    ins.mixture.parts[1].phase = 0;
    ins.mixture.basis = Basis::Number;
    ins.mixture.parts[0].fraction = 0.5;
    ins.mixture.parts[1].fraction = 0.5;
    let sim = start(c);
    let p = sim.particles();
    let mut counts = [0usize; 2];
    for i in 0..p.len() {
        assert_eq!(p.phase[i], 0);
        let m = |rho: f64| sphere_mass(p.radius[i], rho);
        // The mass from the density, as the engine forms it, to rounding (1e-14).
        let k = [RHO, 2.0 * RHO].iter().position(|&rho| (p.mass[i] - m(rho)).abs() <= 1e-14 * m(rho));
        counts[k.expect("a part's density")] += 1;
    }
    assert!(counts.iter().all(|&n| n > 100), "{counts:?}");
    assert!(sim.flow_books().close());
}

/// Issue 38, item 24: a thin outlet (a slab 50 µm deep under the open floor, which a bead at
/// about 1 m/s crosses in some 2 steps of 20 µs) catches every bead that crosses it, at
/// whatever step between the drains it is in the slab; a bead caught and not yet removed
/// is in the checkpoint, so a restart between two drains counts what the uninterrupted run
/// counts, to the bit.
#[test]
fn a_thin_outlet_catches_every_crossing_and_restarts_between_drains() {
    let slab = || {
        let mut c = pour_config(20_000.0, false);
        c.outlets = vec![Outlet {
            name: "slab".into(),
            shape: OutletShape::Region(Region::Box {
                lo: Vec3::new(-0.01, -0.01, -5e-5),
                hi: Vec3::new(0.03, 0.03, 0.0),
            }),
        }];
        c
    };
    let steps = 4500;
    let mut straight = start(slab());
    straight.advance(steps);
    let books = straight.flow_books();
    assert!(books.removed[0].count > 50, "{books:?}");
    // Every bead below the slab has been caught: none is left below it, beyond the ten
    // steps (about 2.2e-4 m) a caught bead falls before its drain.
    let p = straight.particles();
    assert!(p.position.iter().all(|x| x.z > -5e-5 - 3e-4), "a bead passed the slab uncaught");
    for at in [4001, 4004, 4007] {
        let mut first = start(slab());
        first.advance(at);
        let bytes = first.checkpoint("case");
        let mut restarted = Simulation::restore(slab(), &bytes, Some("case")).expect("restores");
        restarted.advance(steps - at);
        assert_eq!(straight.flow_books(), restarted.flow_books(), "restart at step {at}");
        assert!(bits(&straight) == bits(&restarted), "restart at step {at}: the state differs");
    }
}
