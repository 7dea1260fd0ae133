//! Any bytes as a checkpoint: restored or refused (truncated, corrupted, wrong version, does
//! not fit the case), never a panic or a huge allocation.
#![no_main]

use grainflow::contact::{ContactLaw, ContactParams, NormalModel};
use grainflow::state::ParticleInit;
use grainflow::{Integrator, Particles, Phase, Simulation, SimulationConfig, TimeStepRule, Vec3, Wall, WallMaterial};
use libfuzzer_sys::fuzz_target;

fn config() -> SimulationConfig {
    let p = ContactParams { kn: Some(1000.0), ..Default::default() };
    SimulationConfig {
        phases: vec![Phase { name: "a".into(), diameter: 0.004, density: 2500.0, youngs_modulus: None, poisson_ratio: None }],
        wall_materials: vec![WallMaterial { name: "w".into(), youngs_modulus: None, poisson_ratio: None }],
        walls: Wall::domain_box(Vec3::ZERO, Vec3::splat(0.1), 0),
        law: ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        pair_params: vec![p],
        wall_params: vec![p],
        integrator: Integrator::AdamsBashforth,
        time_step: TimeStepRule::Fixed(1e-5),
        t_start: 0.0,
        t_stop: 1e-3,
        gravity: Vec3::new(0.0, -9.81, 0.0),
        skin: None,
        motion: Vec::new(),
        periodic: None,
        meshes: Vec::new(),
        cylinders: Vec::new(),
        resort: grainflow::ResortRule::Auto,
        insertions: Vec::new(),
        outlets: Vec::new(),
    }
}

fuzz_target!(|data: &[u8]| {
    let init = [ParticleInit { id: 1, phase: 0, radius: 0.002, density: 2500.0, position: Vec3::splat(0.05), velocity: Vec3::ZERO, omega: Vec3::ZERO }];
    // A real checkpoint prefix makes the fuzzer reach past the signature quickly.
    let mut sim = match Simulation::new(config(), Particles::from_init(&init)) {
        Ok(s) => s,
        Err(_) => return,
    };
    if data.first() == Some(&0) {
        sim.step();
        let mut bytes = sim.checkpoint("h");
        for (k, b) in data.iter().skip(1).enumerate() {
            let i = (k * 7919) % bytes.len();
            bytes[i] ^= b;
        }
        let _ = Simulation::restore(config(), &bytes, Some("h"));
    } else if let Ok(mut s) = Simulation::restore(config(), data, None) {
        for _ in 0..5 {
            s.step();
        }
    }
});
