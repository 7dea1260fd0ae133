//! The linked-cell Verlet list against an O(N²) brute force.
//!
//! `NeighborList::build` keeps a pair when |x_j − x_i|² < (R_i + R_j + skin)² and a
//! particle–wall pair when the signed distance d < R + skin (both strict, see neighbor.rs); the
//! brute force below uses exactly the same comparisons on the same floating-point values, so
//! the two sets must be *equal* — not one a superset of the other — with no tolerance.

mod common;

use common::*;
use grainflow::neighbor::NeighborList;
use grainflow::state::ParticleInit;
use grainflow::{ContactLaw, Integrator, NormalModel, Particles, Simulation, Vec3, Wall};
use std::collections::{HashMap, HashSet};

fn particles_from(positions: &[Vec3], radii: &[f64]) -> Particles {
    let init: Vec<ParticleInit> = positions
        .iter()
        .zip(radii)
        .enumerate()
        .map(|(k, (&x, &r))| particle(1000 + 7 * k as u32, 0, r, 2500.0, x, Vec3::ZERO))
        .collect();
    Particles::from_init(&init)
}

/// Brute-force pairs, as id pairs (lower id first).
fn brute_pairs(p: &Particles, skin: f64) -> HashSet<(u32, u32)> {
    let mut out = HashSet::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let cut = p.radius[i] + p.radius[j] + skin;
            if (p.position[j] - p.position[i]).length_squared() < cut * cut {
                out.insert((p.id[i].min(p.id[j]), p.id[i].max(p.id[j])));
            }
        }
    }
    out
}

/// Brute-force particle–wall pairs, as (id, wall index).
fn brute_walls(p: &Particles, walls: &[Wall], skin: f64) -> HashSet<(u32, u32)> {
    let mut out = HashSet::new();
    for i in 0..p.len() {
        for (w, wall) in walls.iter().enumerate() {
            if wall.distance(p.position[i]) < p.radius[i] + skin {
                out.insert((p.id[i], w as u32));
            }
        }
    }
    out
}

/// The list's pairs as id pairs (lower id first); checks the documented ordering on the way:
/// slot a < slot b, ordered by slots, no duplicates, one history slot per pair.
fn listed_pairs(nl: &NeighborList, p: &Particles) -> Vec<(u32, u32)> {
    let slots: Vec<[u32; 2]> = nl.pairs().collect();
    for &[a, b] in &slots {
        assert!(a < b, "pair ({a}, {b}) not ordered by slot");
    }
    assert!(slots.windows(2).all(|w| w[0] < w[1]), "pairs not ordered by slots or duplicated");
    assert_eq!(nl.pair_history().len(), slots.len());
    assert_eq!(nl.pair_count(), slots.len());
    slots
        .iter()
        .map(|&[a, b]| {
            let (x, y) = (p.id[a as usize], p.id[b as usize]);
            (x.min(y), x.max(y))
        })
        .collect()
}

fn listed_walls(nl: &NeighborList, p: &Particles) -> Vec<(u32, u32)> {
    let ids: Vec<(u32, u32)> = nl.wall_pairs().iter().map(|&[i, w]| (p.id[i as usize], w)).collect();
    assert!(nl.wall_pairs().windows(2).all(|w| w[0] < w[1]), "wall pairs not ordered by slots or duplicated");
    assert_eq!(nl.wall_history().len(), ids.len());
    ids
}

fn assert_same(what: &str, listed: &[(u32, u32)], brute: &HashSet<(u32, u32)>) {
    let listed_set: HashSet<(u32, u32)> = listed.iter().copied().collect();
    let missing: Vec<_> = brute.difference(&listed_set).take(5).collect();
    let extra: Vec<_> = listed_set.difference(brute).take(5).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "{what}: {} listed vs {} brute force; missing e.g. {missing:?}, extra e.g. {extra:?}",
        listed_set.len(),
        brute.len()
    );
}

/// Builds a list and compares it with the brute force; returns it.
fn check_build(what: &str, p: &Particles, walls: &[Wall], skin: f64) -> NeighborList {
    let mut nl = NeighborList::new(skin);
    nl.build(p, walls);
    let brute = brute_pairs(p, skin);
    assert_same(&format!("{what}: pairs"), &listed_pairs(&nl, p), &brute);
    assert_same(&format!("{what}: wall pairs"), &listed_walls(&nl, p), &brute_walls(p, walls, skin));
    assert!(!brute.is_empty(), "{what}: a test without any pair tests nothing");
    nl
}

/// Radii uniform in [r0, 3.5·r0] (a factor 3.5 between the smallest and the largest).
fn poly_radii(rng: &mut Rng, n: usize, r0: f64) -> Vec<f64> {
    (0..n).map(|_| rng.range(r0, 3.5 * r0)).collect()
}

fn unit_box_walls() -> Vec<Wall> {
    let mut w = Wall::domain_box(Vec3::ZERO, Vec3::ONE, 0);
    // And an oblique plane through the middle of the box.
    w.push(Wall::plane("oblique", Vec3::splat(0.5), Vec3::new(1.0, -2.0, 0.5), 0));
    w
}

#[test]
fn uniform_polydisperse_matches_brute_force() {
    let mut rng = Rng::new(1);
    for &(n, r0, skin) in &[(500, 0.01, 0.002), (3000, 0.005, 0.001), (2000, 0.004, 0.0)] {
        let x: Vec<Vec3> = (0..n).map(|_| rng.in_box(Vec3::ZERO, Vec3::ONE)).collect();
        let r = poly_radii(&mut rng, n, r0);
        check_build(&format!("uniform N={n}"), &particles_from(&x, &r), &unit_box_walls(), skin);
    }
}

/// Pairs among marked particles (held ones, whose mutual forces act on nothing that moves)
/// are left out, all others kept: the list equals the brute force less the marked–marked
/// pairs, which must be there to leave out.
#[test]
fn pairs_among_marked_particles_are_left_out() {
    let mut rng = Rng::new(7);
    let (n, r0, skin) = (2000, 0.01, 0.002);
    let x: Vec<Vec3> = (0..n).map(|_| rng.in_box(Vec3::ZERO, Vec3::ONE)).collect();
    let r = poly_radii(&mut rng, n, r0);
    let p = particles_from(&x, &r);
    // The lower third of the box marked, as a rough base would be.
    let marked: Vec<bool> = p.position.iter().map(|x| x.y < 1.0 / 3.0).collect();
    let is_marked: HashMap<u32, bool> = p.id.iter().copied().zip(marked.iter().copied()).collect();
    let mut nl = NeighborList::new(skin);
    nl.exclude_pairs_among(marked);
    nl.build(&p, &[]);
    let all = brute_pairs(&p, skin);
    let kept: HashSet<(u32, u32)> =
        all.iter().copied().filter(|(i, j)| !(is_marked[i] && is_marked[j])).collect();
    let left_out = all.len() - kept.len();
    assert!(left_out > 100 && kept.len() > 100, "{left_out} pairs to leave out, {} to keep", kept.len());
    assert_same("marked", &listed_pairs(&nl, &p), &kept);
}

/// Dense Gaussian clusters of very different sizes, some particles far outside (which forces
/// the cell grid to coarsen: more cells than the engine allows), and a wide radius range.
/// A list's state restores to the same list whether its pairs come in list order (as a
/// checkpoint writes them, taken as they are) or in any other (sorted, a pair given the other
/// way round taking its history negated); a pair listed twice is refused, leaving the list as
/// it was.
#[test]
fn a_restored_list_is_the_same_in_any_pair_order() {
    let mut rng = Rng::new(11);
    let n = 2000;
    let x: Vec<Vec3> = (0..n).map(|_| rng.in_box(Vec3::ZERO, Vec3::ONE)).collect();
    let r = poly_radii(&mut rng, n, 0.01);
    let p = particles_from(&x, &r);
    let walls = unit_box_walls();
    let mut nl = check_build("restore", &p, &walls, 0.002);
    // Every other pair carries a history (distinct values, so a misplaced one shows).
    for k in (0..nl.pair_count()).step_by(2) {
        nl.set_pair_history(k, Vec3::new(k as f64 + 1.0, -(k as f64), 0.5));
    }
    let state = nl.state();
    assert!(state.pairs.len() > 100, "too few pairs ({}) to test", state.pairs.len());
    let restored = |s: grainflow::neighbor::NeighborState| {
        let mut other = NeighborList::new(0.0);
        other.set_state(s, p.len(), walls.len()).map(|_| other.state())
    };
    assert_eq!(restored(state.clone()), Ok(state.clone()), "in list order");
    let mut shuffled = state.clone();
    shuffled.pairs.reverse();
    shuffled.pair_history.reverse();
    for k in (0..shuffled.pairs.len()).step_by(3) {
        let [a, b] = shuffled.pairs[k];
        shuffled.pairs[k] = [b, a];
        shuffled.pair_history[k] = -shuffled.pair_history[k];
    }
    assert_eq!(restored(shuffled), Ok(state.clone()), "reversed, every third pair turned");
    let mut doubled = state.clone();
    doubled.pairs[1] = doubled.pairs[0];
    let mut other = check_build("restore", &p, &walls, 0.002);
    let before = other.state();
    assert!(other.set_state(doubled, p.len(), walls.len()).is_err(), "a pair listed twice");
    assert_eq!(other.state(), before, "a refused state leaves the list as it was");
}

#[test]
fn clustered_polydisperse_matches_brute_force() {
    let mut rng = Rng::new(2);
    let n = 2500;
    let centres: Vec<(Vec3, f64)> =
        (0..8).map(|k| (rng.in_box(Vec3::ZERO, Vec3::ONE), 0.005 * (1.0 + k as f64))).collect();
    let mut x: Vec<Vec3> = (0..n)
        .map(|_| {
            let (c, s) = centres[rng.index(centres.len())];
            c + s * Vec3::new(rng.normal(), rng.normal(), rng.normal())
        })
        .collect();
    let r = poly_radii(&mut rng, n, 0.002);
    check_build("clusters", &particles_from(&x, &r), &unit_box_walls(), 0.0005);
    // Outliers far away: the bounding box grows by 1e4, the grid must coarsen.
    x[0] = Vec3::new(5000.0, -3000.0, 7000.0);
    x[1] = Vec3::new(-4000.0, 2000.0, 1.0);
    x[2] = x[0] + Vec3::new(0.004, 0.0, 0.0);
    check_build("clusters + outliers", &particles_from(&x, &r), &unit_box_walls(), 0.0005);
}

/// Degenerate extents: everything in one plane, or on one line.
#[test]
fn flat_and_linear_packings_match_brute_force() {
    let mut rng = Rng::new(3);
    let n = 1500;
    let r = poly_radii(&mut rng, n, 0.003);
    let plane: Vec<Vec3> = (0..n).map(|_| Vec3::new(rng.uniform(), 0.25, rng.uniform())).collect();
    check_build("plane", &particles_from(&plane, &r), &unit_box_walls(), 0.001);
    let line: Vec<Vec3> = (0..n).map(|_| Vec3::new(0.5, 0.5, 5.0 * rng.uniform())).collect();
    check_build("line", &particles_from(&line, &r), &unit_box_walls(), 0.001);
}

/// Pairs at *exactly* the cut-off distance are excluded, just inside included (strict <), for
/// both the pair and the wall test: binary fractions make every distance exact.
#[test]
fn cutoff_is_strict_and_exact() {
    // R = 0.5, skin = 0.25: cut = 1.25. A row at spacing 1.25 (exactly at the cut-off) and a
    // row at spacing 1.25 − 2⁻²⁰ (just inside).
    let (r, skin) = (0.5, 0.25);
    let mut x = Vec::new();
    for k in 0..6 {
        x.push(Vec3::new(1.25 * k as f64, 0.0, 0.0));
    }
    let inside = 1.25 - 2f64.powi(-20);
    for k in 0..6 {
        x.push(Vec3::new(inside * k as f64, 10.0, 0.0));
    }
    // Walls at exactly R + skin from the first row, just inside for the second.
    let walls = vec![
        Wall::plane("at", Vec3::new(0.0, -0.75, 0.0), Vec3::Y, 0),
        Wall::plane("inside", Vec3::new(0.0, 10.0 + 0.75 - 2f64.powi(-20), 0.0), -Vec3::Y, 0),
    ];
    let p = particles_from(&x, &vec![r; x.len()]);
    let nl = check_build("exact cut-off", &p, &walls, skin);
    assert_eq!(nl.pair_count(), 5, "only the 5 neighbours of the inner row are listed");
    assert_eq!(nl.wall_pairs().len(), 6, "only the inner row is near its wall");
}

/// On a rebuild, pairs that persist keep their history (matched by their slots, which never
/// change during a run), new pairs start from zero.
#[test]
fn rebuild_keeps_history_of_persisting_pairs() {
    let mut rng = Rng::new(4);
    let n = 1500;
    let skin = 0.002;
    let x: Vec<Vec3> = (0..n).map(|_| rng.in_box(Vec3::ZERO, Vec3::ONE)).collect();
    let r = poly_radii(&mut rng, n, 0.008);
    let p = particles_from(&x, &r);
    let walls = unit_box_walls();
    let mut nl = check_build("before", &p, &walls, skin);
    // Distinct markers, a function of the ids.
    let pair_marker = |a: u32, b: u32| Vec3::new(a as f64, b as f64, 0.5);
    let wall_marker = |i: u32, w: u32| Vec3::new(i as f64, w as f64, -0.25);
    // Only some pairs are in contact (carry a history): every third one.
    let in_contact = |a: u32, b: u32| (a + b).is_multiple_of(3);
    let before_pairs = listed_pairs(&nl, &p);
    for (k, &(a, b)) in before_pairs.iter().enumerate() {
        if in_contact(a, b) {
            nl.set_pair_history(k, pair_marker(a, b));
        }
    }
    assert_eq!(nl.pair_contact_count(), before_pairs.iter().filter(|&&(a, b)| in_contact(a, b)).count());
    let before_walls = listed_walls(&nl, &p);
    for (k, &(i, w)) in before_walls.iter().enumerate() {
        nl.wall_history_mut()[k] = wall_marker(i, w);
    }
    let before_pairs: HashSet<_> = before_pairs.into_iter().collect();
    let before_walls: HashSet<_> = before_walls.into_iter().collect();

    // Move every particle by up to 4 skins per axis, keeping its slot.
    let init: Vec<ParticleInit> = (0..n)
        .map(|k| {
            let d = 4.0 * skin * Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            particle(p.id[k], 0, r[k], 2500.0, x[k] + d, Vec3::ZERO)
        })
        .collect();
    let moved = Particles::from_init(&init);
    nl.build(&moved, &walls);
    let brute = brute_pairs(&moved, skin);
    let after_pairs = listed_pairs(&nl, &moved);
    assert_same("after: pairs", &after_pairs, &brute);
    let after_walls = listed_walls(&nl, &moved);
    assert_same("after: walls", &after_walls, &brute_walls(&moved, &walls, skin));

    let (mut kept, mut fresh) = (0, 0);
    let after_history = nl.pair_history();
    for (k, &(a, b)) in after_pairs.iter().enumerate() {
        if before_pairs.contains(&(a, b)) {
            let expected = if in_contact(a, b) { pair_marker(a, b) } else { Vec3::ZERO };
            assert_eq!(after_history[k], expected, "pair ({a}, {b})");
            kept += 1;
        } else {
            assert_eq!(after_history[k], Vec3::ZERO, "new pair ({a}, {b})");
            fresh += 1;
        }
    }
    for (k, &(i, w)) in after_walls.iter().enumerate() {
        if before_walls.contains(&(i, w)) {
            assert_eq!(nl.wall_history()[k], wall_marker(i, w), "wall pair ({i}, {w})");
        } else {
            assert_eq!(nl.wall_history()[k], Vec3::ZERO, "new wall pair ({i}, {w})");
        }
    }
    eprintln!("{kept} persisting pairs, {fresh} new pairs");
    assert!(kept > 50 && fresh > 50, "both kinds must occur ({kept} kept, {fresh} new)");
}

/// Under a law that keeps histories apart (LIGGGHTS's), a rebuild carries a pair's history
/// when the pair carries one and its spheres overlap at the new positions, and drops it
/// otherwise, as LIGGGHTS's own rebuild does; the default list carries every history it held,
/// overlapping or not. On threads (`update` over two blocks) the list is the same, and a
/// checkpoint's state restores it.
#[test]
fn rebuild_keeps_apart_histories_only_of_overlapping_pairs() {
    let mut rng = Rng::new(9);
    let (r, skin, side) = (0.01, 0.004, 10);
    // A cubic lattice at the contact distance, jittered: about half the neighbours overlap.
    let mut x = Vec::new();
    for i in 0..side * side * side {
        let l = Vec3::new((i % side) as f64, (i / side % side) as f64, (i / side / side) as f64);
        x.push(
            2.0 * r * l
                + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * 0.1 * r,
        );
    }
    let n = x.len();
    let radii = vec![r; n];
    let p = particles_from(&x, &radii);
    let marker = |a: u32, b: u32| Vec3::new(a as f64, b as f64, 0.5);
    let marked = |keep: bool| {
        let mut nl = NeighborList::new(skin);
        nl.keep_histories_apart(keep);
        nl.build(&p, &[]);
        let pairs = listed_pairs(&nl, &p);
        for (k, &(a, b)) in pairs.iter().enumerate() {
            nl.set_pair_history(k, marker(a, b));
        }
        (nl, pairs.into_iter().collect::<HashSet<_>>())
    };
    // Every particle moved by up to a skin per axis (more than half a skin: a rebuild is due).
    let init: Vec<ParticleInit> = (0..n)
        .map(|k| {
            let d = skin * Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            particle(p.id[k], 0, r, 2500.0, x[k] + d, Vec3::ZERO)
        })
        .collect();
    let moved = Particles::from_init(&init);
    let slot_of: HashMap<u32, usize> = (0..n).map(|k| (moved.id[k], k)).collect();
    let overlaps = |a: u32, b: u32| {
        let d = moved.position[slot_of[&b]] - moved.position[slot_of[&a]];
        d.length_squared() < (2.0 * r) * (2.0 * r)
    };
    let (mut carried, mut dropped) = (0, 0);
    for keep in [false, true] {
        let (mut serial, before) = marked(keep);
        serial.build(&moved, &[]);
        let (mut threaded, _) = marked(keep);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        pool.install(|| threaded.update(&moved, &[], &[0..n / 2, n / 2..n]));
        assert_eq!(threaded.stats().builds, 2, "the threaded list was rebuilt");
        let after = listed_pairs(&serial, &moved);
        assert_eq!(after, listed_pairs(&threaded, &moved), "keep {keep}: the same pairs on threads");
        assert_eq!(
            serial.pair_history(),
            threaded.pair_history(),
            "keep {keep}: the same histories on threads"
        );
        let history = serial.pair_history();
        for (k, &(a, b)) in after.iter().enumerate() {
            let goes_on = before.contains(&(a, b)) && (!keep || overlaps(a, b));
            let expected = if goes_on { marker(a, b) } else { Vec3::ZERO };
            assert_eq!(history[k], expected, "keep {keep}: pair ({a}, {b})");
            if keep && before.contains(&(a, b)) {
                if goes_on { carried += 1 } else { dropped += 1 }
            }
        }
        let mut restored = NeighborList::new(skin);
        restored.keep_histories_apart(keep);
        restored.set_state(serial.state(), n, 0).unwrap();
        assert_eq!(restored.pair_history(), history, "keep {keep}: a checkpoint keeps the histories");
    }
    eprintln!("{carried} histories carried, {dropped} dropped");
    assert!(carried > 100 && dropped > 100, "both kinds must occur ({carried} carried, {dropped} dropped)");
}

/// The build is O(N): at the same number density and size distribution, the distance tests
/// per particle hardly change between N = 1 000 and N = 16 000 (a quadratic search would
/// grow 16×; the only N-dependence left is the surface fraction of the box, where particles
/// have fewer neighbours).
#[test]
fn build_cost_is_linear() {
    let mut rng = Rng::new(5);
    let (r0, skin): (f64, f64) = (0.01, 0.002);
    // About 0.5 particles per cell of side 2·3.5·r0 + skin.
    let density = 0.5 / (7.0 * r0 + skin).powi(3);
    let per_particle: Vec<f64> = [1_000usize, 16_000]
        .iter()
        .map(|&n| {
            let side = (n as f64 / density).cbrt();
            let x: Vec<Vec3> = (0..n).map(|_| rng.in_box(Vec3::ZERO, Vec3::splat(side))).collect();
            let r = poly_radii(&mut rng, n, r0);
            let mut nl = NeighborList::new(skin);
            nl.build(&particles_from(&x, &r), &[]);
            let c = nl.stats().distance_checks as f64 / n as f64;
            eprintln!("N = {n}: {c:.2} distance checks per particle, {} pairs", nl.pair_count());
            c
        })
        .collect();
    let ratio = per_particle[1] / per_particle[0];
    assert!(
        (1.0 / 1.5..=1.5).contains(&ratio),
        "distance checks per particle changed by {ratio} from N = 1000 to 16000"
    );
}

/// Far apart, non-interacting particles at constant velocity: the simulation rebuilds exactly
/// when some particle has moved more than skin/2 since the last build, never otherwise.
#[test]
fn simulation_rebuilds_exactly_after_half_a_skin() {
    let skin = 1e-3;
    let dt = 1e-4;
    // The fast particle moves skin/2 in 3.5 steps: a rebuild at every 4th force evaluation.
    let v_fast = 0.5 * skin / (3.5 * dt);
    for integrator in [Integrator::Euler, Integrator::AdamsBashforth] {
        for slow_only in [false, true] {
            let p = lsd_params(1e4, 1.0, 0.0);
            let mut cfg = config(
                ContactLaw::mfix(NormalModel::LinearSpringDashpot),
                vec![phase("p", 0.002, 2500.0)],
                vec![wall_material("w", None, None)],
                Vec::new(),
                vec![p],
                vec![p],
                integrator,
                dt,
            );
            cfg.skin = Some(skin);
            let steps = 201u64;
            // A slow particle that in the whole run moves less than skin/2.
            let v_slow = 0.4 * skin / (steps as f64 * dt);
            let mut init =
                vec![particle(1, 0, 0.001, 2500.0, Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, v_slow, 0.0))];
            if !slow_only {
                init.push(particle(
                    2,
                    0,
                    0.001,
                    2500.0,
                    Vec3::new(1.0, 0.0, 0.0),
                    Vec3::new(-v_fast, 0.0, v_fast).normalize() * v_fast,
                ));
            }
            let mut sim = simulation(cfg, &init);
            assert_eq!(sim.neighbors().stats().builds, 1, "built once at set-up");
            for k in 0..steps {
                // Force evaluation k sees positions after k steps; the last build was at
                // evaluation 4·floor(k/4) (or at set-up).
                sim.step();
                let expected = if slow_only { 1 } else { 1 + k / 4 };
                assert_eq!(
                    sim.neighbors().stats().builds,
                    expected,
                    "{integrator:?}, slow_only = {slow_only}: builds after {} steps",
                    k + 1
                );
            }
        }
    }
}

/// The displacement test asks for a rebuild exactly when one particle, in whichever slot, moved
/// more than skin/2 along any axis — by the nearest image on periodic axes, so that a particle
/// wrapped across the box has not moved far — or has a position that is not a number.
#[test]
fn displacement_test_finds_the_one_particle_that_moved_too_far() {
    use grainflow::Periodic;
    let skin = 0.01;
    let per = Periodic { lo: Vec3::ZERO, hi: Vec3::new(1.0, 1.0, 1.0), axes: [true, false, true] };
    // 11 particles: two groups of four and three after them.
    let positions: Vec<Vec3> = (0..11)
        .map(|k| Vec3::new(0.05 + 0.08 * k as f64, 0.5 + 0.01 * k as f64, 0.3 + 0.05 * k as f64))
        .collect();
    let p = particles_from(&positions, &[0.01; 11]);
    let mut nl = NeighborList::with_periodic(skin, per);
    nl.build(&p, &[]);
    assert!(!nl.needs_rebuild(&p.position, &[]), "nothing moved");
    let half = 0.5 * skin;
    for slot in 0..11 {
        for axis in 0..3 {
            for (step, far) in
                [(half * (1.0 + 1e-9), true), (half * (1.0 - 1e-9), false), (-half * (1.0 + 1e-9), true)]
            {
                let mut xs = p.position.clone();
                let mut x = xs[slot].to_array();
                x[axis] += step;
                xs[slot] = Vec3::from_array(x);
                assert_eq!(nl.needs_rebuild(&xs, &[]), far, "slot {slot}, axis {axis}, moved {step}");
            }
        }
        // Along a periodic axis, one box length away is the same place.
        let mut xs = p.position.clone();
        xs[slot].x += 1.0;
        assert!(!nl.needs_rebuild(&xs, &[]), "slot {slot} wrapped along x");
        xs[slot].y = f64::NAN;
        assert!(nl.needs_rebuild(&xs, &[]), "slot {slot} not a number");
    }
}

/// During a real run (a dense, frictional, polydisperse gas falling in a box) every contact
/// at the positions where forces were evaluated is in the list the force loop used.
#[test]
fn simulation_never_misses_a_contact() {
    let mut rng = Rng::new(6);
    let n = 400;
    let side = 0.03;
    let mut init: Vec<ParticleInit> = Vec::new();
    while init.len() < n {
        let r = rng.range(0.0004, 0.0014);
        let x = rng.in_box(Vec3::splat(0.0015), Vec3::splat(side - 0.0015));
        if init.iter().all(|q| (q.position - x).length() > q.radius + r) {
            let v = 0.5 * rng.unit();
            init.push(particle(init.len() as u32, 0, r, 2500.0, x, v));
        }
    }
    let p = lsd_params(200.0, 0.8, 0.3);
    let mut cfg = config(
        ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        vec![phase("p", 0.002, 2500.0)],
        vec![wall_material("w", None, None)],
        Wall::domain_box(Vec3::ZERO, Vec3::splat(side), 0),
        vec![p],
        vec![p],
        Integrator::Euler,
        2e-5,
    );
    cfg.gravity = Vec3::new(0.0, -9.81, 0.0);
    let mut sim: Simulation = simulation(cfg, &init);
    let skin = sim.neighbors().skin();
    let mut contacts_seen = 0usize;
    for _ in 0..1500 {
        // Forces of this step are computed at the current positions, with the list as it is
        // after the (possible) rebuild inside the step.
        let before = sim.particles().clone();
        sim.step();
        let nl = sim.neighbors();
        let listed: HashSet<(u32, u32)> = listed_pairs(nl, &before).into_iter().collect();
        let listed_w: HashSet<(u32, u32)> = listed_walls(nl, &before).into_iter().collect();
        for (key, _) in touching_pairs(&before) {
            contacts_seen += 1;
            assert!(listed.contains(&key), "contact {key:?} missing from the list");
        }
        for i in 0..before.len() {
            for (w, wall) in sim.walls().iter().enumerate() {
                if wall.distance(before.position[i]) <= before.radius[i] {
                    contacts_seen += 1;
                    assert!(listed_w.contains(&(before.id[i], w as u32)));
                }
            }
        }
    }
    eprintln!(
        "{contacts_seen} contact-steps checked, {} builds, skin {skin:e}",
        sim.neighbors().stats().builds
    );
    assert!(contacts_seen > 1000);
    assert!(sim.neighbors().stats().builds > 5);
}

/// Pairs in contact (d ≤ R_i + R_j), by ids, with their overlap.
fn touching_pairs(p: &Particles) -> HashMap<(u32, u32), f64> {
    let mut out = HashMap::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = (p.position[j] - p.position[i]).length();
            if d <= p.radius[i] + p.radius[j] {
                out.insert((p.id[i].min(p.id[j]), p.id[i].max(p.id[j])), p.radius[i] + p.radius[j] - d);
            }
        }
    }
    out
}

/// A pair closer than the cut-off by 5e-14 m whose centres the cell grid puts two cells apart,
/// so the linked-cell search never compares them. Cause (neighbor.rs, `build_pairs`): the cell
/// side equals the largest cut-off exactly (`cell = 2.0 * p.max_radius() + skin`) and cell
/// coordinates are computed as `((x - l) * inv) as usize` with `inv = 1.0 / cell` rounded, so
/// (x_b − lo)/cell = 504.99999999999994 lands in cell 505 while its partner at
/// (x_a − lo)/cell = 503.99999999999994 stays in cell 503. (Found by a random search over
/// radii, skins and offsets, placing pairs within a few ulps of a cell boundary and of the
/// cut-off; such pairs are missed often.) Physically harmless with a positive skin (the
/// missed pair is a skin away from touching), but with `skin = 0` it is a contact with overlap
/// ~1e-14 m that the force loop cannot see (next test), and it breaks the documented guarantee
/// "every pair closer than R_i + R_j + skin". A cell side a relative 1e-9 larger than the
/// cut-off would remove it.
#[test]
fn pair_at_cutoff_across_cell_boundary_is_found() {
    let (r, skin) = (0.402_448_648_090_735_33, 0.264_425_576_728_630_04);
    let lo = -69.584_033_995_365_3;
    let (xa, xb) = (469.354_693_951_325_43, 470.424_016_824_235_5);
    let x = [
        Vec3::new(lo, 0.0, 0.0),
        Vec3::new(xa, 0.0, 0.0),
        Vec3::new(xb, 0.0, 0.0),
        // Beyond, so that x_b's cell is not clamped to the last one.
        Vec3::new(xb + 10.0, 0.0, 0.0),
    ];
    let p = particles_from(&x, &[r; 4]);
    // The brute force sees the pair (1, 2) …
    let cut = r + r + skin;
    assert!((x[2] - x[1]).length_squared() < cut * cut);
    // … and so must the list.
    check_build("cell boundary", &p, &[], skin);
}

/// The same rounding with `skin = 0`: two particles that *touch* (overlap 6.06e-14 m,
/// `pair_contact` says so) are not in the list, so the force loop never sees the contact.
#[test]
fn touching_pair_across_cell_boundary_is_found_with_zero_skin() {
    use grainflow::contact::geometry::pair_contact;
    let r = 0.704_270_327_832_633_3;
    let lo = -87.193_712_354_600_54;
    let (xa, xb) = (1_007.242_377_097_311_5, 1_008.650_917_752_976_7);
    let x = [
        Vec3::new(lo, 0.0, 0.0),
        Vec3::new(xa, 0.0, 0.0),
        Vec3::new(xb, 0.0, 0.0),
        Vec3::new(xb + 10.0, 0.0, 0.0),
    ];
    let g = pair_contact(x[1], x[2], r, r).expect("the two particles touch");
    assert!(g.overlap > 0.0);
    check_build("touching pair, zero skin", &particles_from(&x, &[r; 4]), &[], 0.0);
}

/// The rebuild criterion is strict and exact: a displacement of exactly skin/2 does not
/// rebuild, the next step does. Dyadic numbers make every position exact: Δt = 2⁻¹⁴ s,
/// v = 2⁻¹⁰ m/s, so a step is 2⁻²⁴ m, and skin = 2⁻¹⁶ m, so skin/2 = 128 steps is reached
/// exactly: rebuilds at force evaluations 129, 258, … (a threshold off by more than 1/128
/// relative would shift them).
#[test]
fn simulation_rebuild_at_exactly_half_a_skin_is_strict() {
    let (skin, dt, v) = (2f64.powi(-16), 2f64.powi(-14), 2f64.powi(-10));
    let steps = 400u64;
    for integrator in [Integrator::Euler, Integrator::AdamsBashforth] {
        let p = lsd_params(1e4, 1.0, 0.0);
        let mut cfg = config(
            ContactLaw::mfix(NormalModel::LinearSpringDashpot),
            vec![phase("p", 0.002, 2500.0)],
            vec![wall_material("w", None, None)],
            Vec::new(),
            vec![p],
            vec![p],
            integrator,
            dt,
        );
        cfg.skin = Some(skin);
        let init = [
            particle(1, 0, 0.001, 2500.0, Vec3::ZERO, Vec3::new(0.0, 0.0, -v)),
            particle(2, 0, 0.001, 2500.0, Vec3::ONE, Vec3::ZERO),
        ];
        let mut sim = simulation(cfg, &init);
        for k in 0..steps {
            sim.step();
            assert_eq!(
                sim.neighbors().stats().builds,
                1 + k / 129,
                "{integrator:?}: builds after {} steps",
                k + 1
            );
        }
        // The position really is exact.
        assert_eq!(sim.particles().position[0], Vec3::new(0.0, 0.0, -(steps as f64) * v * dt));
    }
}
