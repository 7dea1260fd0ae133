//! Shared set-up helpers for the physics tests (not a test target itself).
//!
//! Every test file includes this module with `mod common;`; not every file uses every helper.
#![allow(dead_code)]

use grainflow::contact::{
    ContactParams, ContactSizes, CoulombCap, HistoryFrame, LeverArm, NormalDamping, NormalModel,
    TangentialModel,
};
use grainflow::state::ParticleInit;
use grainflow::{
    ContactLaw, Integrator, Particles, Phase, Simulation, SimulationConfig, TimeStepRule, Vec3, Wall,
    WallMaterial,
};
use std::f64::consts::PI;

/// Mass of a solid sphere, written out independently of the engine's helper.
pub fn sphere_mass(r: f64, rho: f64) -> f64 {
    4.0 / 3.0 * PI * r.powi(3) * rho
}

/// A phase without elastic constants (LSD).
pub fn phase(name: &str, diameter: f64, density: f64) -> Phase {
    Phase { name: name.into(), diameter, density, youngs_modulus: None, poisson_ratio: None }
}

/// A phase with elastic constants (Hertz).
pub fn elastic_phase(name: &str, diameter: f64, density: f64, e: f64, nu: f64) -> Phase {
    Phase { name: name.into(), diameter, density, youngs_modulus: Some(e), poisson_ratio: Some(nu) }
}

/// A wall material, with or without elastic constants.
pub fn wall_material(name: &str, e: Option<f64>, nu: Option<f64>) -> WallMaterial {
    WallMaterial { name: name.into(), youngs_modulus: e, poisson_ratio: nu }
}

/// LSD contact inputs: k_n, e_n, μ; MFIX defaults otherwise.
pub fn lsd_params(kn: f64, en: f64, mu: f64) -> ContactParams {
    ContactParams { kn: Some(kn), en, mu, ..Default::default() }
}

/// Hertz contact inputs: e_n, e_t, μ.
pub fn hertz_params(en: f64, et: f64, mu: f64) -> ContactParams {
    ContactParams { en, et: Some(et), mu, ..Default::default() }
}

/// A configuration with zero gravity, an explicit time step and a very long run (tests call
/// `step()` themselves).
pub fn config(
    law: ContactLaw,
    phases: Vec<Phase>,
    wall_materials: Vec<WallMaterial>,
    walls: Vec<Wall>,
    pair_params: Vec<ContactParams>,
    wall_params: Vec<ContactParams>,
    integrator: Integrator,
    dt: f64,
) -> SimulationConfig {
    SimulationConfig {
        phases,
        wall_materials,
        walls,
        meshes: Vec::new(),
        cylinders: Vec::new(),
        law,
        pair_params,
        wall_params,
        integrator,
        time_step: TimeStepRule::Fixed(dt),
        t_start: 0.0,
        t_stop: 1.0e6 * dt,
        gravity: Vec3::ZERO,
        skin: None,
        motion: Vec::new(),
        periodic: None,
        resort: grainflow::ResortRule::Never,
        insertions: Vec::new(),
        outlets: Vec::new(),
    }
}

/// One particle's initial data.
pub fn particle(id: u32, phase: u32, radius: f64, density: f64, x: Vec3, v: Vec3) -> ParticleInit {
    ParticleInit { id, phase, radius, density, position: x, velocity: v, omega: Vec3::ZERO }
}

/// Builds a simulation, panicking with the engine's message on a set-up error.
pub fn simulation(config: SimulationConfig, init: &[ParticleInit]) -> Simulation {
    Simulation::new(config, Particles::from_init(init)).expect("valid test set-up")
}

/// SplitMix64: a small deterministic generator, so the tests need no extra dependency.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }

    /// A point uniformly distributed in the box [lo, hi].
    pub fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }

    /// A uniformly distributed unit vector.
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.normal(), self.normal(), self.normal());
            let l = v.length();
            if l > 1e-3 {
                return v / l;
            }
        }
    }

    /// An index in 0..n.
    pub fn index(&mut self, n: usize) -> usize {
        (self.uniform() * n as f64) as usize % n
    }
}

/// Relative error |a − b|/|b|.
pub fn rel_err(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// Random dense bed: `n` spheres in random slots (ids in random order, positions on a jittered
/// lattice so that they start touching), random velocities.
pub fn bed(n: usize, lo: Vec3, hi: Vec3, radius: f64, seed: u64) -> Vec<ParticleInit> {
    let mut rng = Rng::new(seed);
    let pitch = 2.0 * radius;
    let cells = ((hi - lo) / pitch).floor();
    let (nx, ny) = (cells.x as usize, cells.y as usize);
    let mut init: Vec<ParticleInit> = (0..n)
        .map(|k| {
            let (ix, iy, iz) = (k % nx, (k / nx) % ny, k / (nx * ny));
            let x = lo + pitch * (Vec3::new(ix as f64, iy as f64, iz as f64) + Vec3::splat(0.5));
            let r = radius * rng.range(0.97, 1.0);
            let jitter =
                0.1 * radius * Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            particle(k as u32 + 1, 0, r, 2500.0, x + jitter, 0.3 * rng.unit())
        })
        .collect();
    // Random slot order: a Fisher–Yates shuffle.
    for k in (1..init.len()).rev() {
        init.swap(k, rng.index(k + 1));
    }
    init
}

/// The box of [`chute_config`]: 30 × 30 mm, periodic in x and y, 60 mm high.
pub const CHUTE_BOX: (Vec3, Vec3) = (Vec3::ZERO, Vec3::new(0.03, 0.03, 0.06));

/// A chute: [`CHUTE_BOX`] with a lid at z = 31 mm that keeps an agitated bed dense (walls may
/// face the non-periodic axis), gravity 9.81 m/s² tilted 26° along x, one phase and the lid's
/// material, the same contact parameters for pairs and the lid, Δt = 20 µs.
pub fn chute_config(
    law: ContactLaw,
    phase: Phase,
    lid: WallMaterial,
    params: ContactParams,
    integrator: Integrator,
) -> SimulationConfig {
    let (lo, hi) = CHUTE_BOX;
    let wall = Wall::plane("lid", Vec3::new(0.0, 0.0, 0.031), Vec3::new(0.0, 0.0, -1.0), 0);
    let mut cfg =
        config(law, vec![phase], vec![lid], vec![wall], vec![params], vec![params], integrator, 2.0e-5);
    cfg.periodic = Some(grainflow::Periodic { lo, hi, axes: [true, true, false] });
    cfg.gravity = 9.81 * Vec3::new(26f64.to_radians().sin(), 0.0, -26f64.to_radians().cos());
    cfg
}

/// LAMMPS's `gran/hooke/history` law as the yardstick chute sets it (damping γ·m_eff, history
/// projected on the tangent plane, radius lever arms, LAMMPS's Coulomb cap), with the test
/// chute's coefficients.
pub fn lammps_hooke() -> (ContactLaw, ContactParams) {
    let law = ContactLaw {
        damping: NormalDamping::MassVelocity,
        history: HistoryFrame::Project,
        lever: LeverArm::Radius,
        coulomb: CoulombCap::Lammps,
        ..ContactLaw::mfix(NormalModel::LinearSpringDashpot)
    };
    let params = ContactParams {
        kn: Some(2000.0),
        gamma_n: Some(1314.0),
        gamma_t: Some(657.0),
        mu: 0.5,
        ..Default::default()
    };
    (law, params)
}

/// LAMMPS's `granular hertz/material … tangential mindlin … damping tsuji` as the Hertz–Mindlin
/// yardstick bed sets it, with e_n = e_t = 0.9 and μ = 0.5.
pub fn lammps_mindlin() -> (ContactLaw, ContactParams) {
    let law = ContactLaw {
        normal: NormalModel::Hertz,
        tangential: TangentialModel::IncrementalMindlin,
        history: HistoryFrame::Rotate,
        lever: LeverArm::LammpsGranular,
        damping: NormalDamping::Tsuji,
        clip_attraction: false,
        coulomb: CoulombCap::Lammps,
        sizes: ContactSizes::Own,
    };
    (law, ContactParams { etat_fac: 1.0, ..hertz_params(0.9, 0.9, 0.5) })
}

/// 10⁻¹⁰ more x-velocity, relative, for the topmost particle (never part of a held base).
pub fn nudge(init: &mut [ParticleInit]) {
    let top = (0..init.len()).max_by(|&a, &b| init[a].position.z.total_cmp(&init[b].position.z)).unwrap();
    let v = &mut init[top].velocity;
    v.x += 1e-10 * v.length().max(1e-3);
}

/// Glass beads of 2 mm (E = 5 MPa, ν = 0.3) in the walled box `lo`..`hi`, LAMMPS's
/// Hertz–Mindlin law with restitution `en` for pairs and walls alike, velocity Verlet at
/// 2·10⁻⁵ s, no gravity.
pub fn walled_mindlin(lo: Vec3, hi: Vec3, en: f64) -> SimulationConfig {
    let (law, elastic) = lammps_mindlin();
    let elastic = ContactParams { en, ..elastic };
    config(
        law,
        vec![elastic_phase("glass", 0.002, 2500.0, 5.0e6, 0.3)],
        vec![wall_material("wall", Some(5.0e6), Some(0.3))],
        Wall::domain_box(lo, hi, 0),
        vec![elastic],
        vec![elastic],
        Integrator::VelocityVerlet,
        2.0e-5,
    )
}

/// 3 000 beads in a walled 30 × 30 × 60 mm box, LAMMPS's Hertz–Mindlin law, velocity Verlet
/// (with `nudged`, the topmost one nudged).
pub fn walled_bed(nudged: bool) -> Simulation {
    let (cfg, init) = walled_bed_case(nudged);
    simulation(cfg, &init)
}

/// LIGGGHTS's `pair_style gran model hertz tangential history` as its scripts set it: β-based
/// damping, the spring alone tested against Coulomb, R − δ/2 lever arms, and histories kept
/// while a pair is apart.
pub fn liggghts_hertz() -> ContactLaw {
    ContactLaw {
        damping: NormalDamping::Liggghts,
        coulomb: CoulombCap::Liggghts,
        lever: LeverArm::Liggghts,
        history: HistoryFrame::Liggghts,
        ..lammps_mindlin().0
    }
}

/// The configuration and particles of [`walled_bed`].
pub fn walled_bed_case(nudged: bool) -> (SimulationConfig, Vec<ParticleInit>) {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(0.03, 0.03, 0.06));
    let mut cfg = walled_mindlin(lo, hi, lammps_mindlin().1.en);
    cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
    let mut init = bed(3000, lo, hi, 0.001, 11);
    if nudged {
        nudge(&mut init);
    }
    (cfg, init)
}

/// A tube of `n` flat facets about the z axis, corners on the circle of radius `r`, for
/// |z| ≤ `h`, normals inwards.
pub fn tube(n: usize, r: f64, h: f64) -> grainflow::mesh::Mesh {
    let mut v = Vec::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        v.push(Vec3::new(r * a.cos(), r * a.sin(), -h));
        v.push(Vec3::new(r * a.cos(), r * a.sin(), h));
    }
    let (lo, hi) = (|k: usize| (2 * (k % n)) as u32, |k: usize| (2 * (k % n) + 1) as u32);
    let mut t = Vec::new();
    for k in 0..n {
        t.push([lo(k), hi(k + 1), lo(k + 1)]);
        t.push([lo(k), hi(k), hi(k + 1)]);
    }
    grainflow::mesh::Mesh::from_indexed("drum", &v, &t, &grainflow::mesh::MeshTransform::default())
        .expect("a valid tube")
}
