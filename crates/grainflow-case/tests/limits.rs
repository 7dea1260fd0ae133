//! The case layer's limits and honest answers: overlap limits, phase counts, repeated keys,
//! particle files that are inconsistent, the step count, and the default time step of Hertz
//! cases. (The command-line side, under a memory cap, is crates/grainflow-cli/tests/hostile.rs.)

use grainflow::TimeStepRule;
use grainflow_case::{CaseError, parse};

mod common;
use common::BASE;

const INLINE: &str = "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]\n";

fn files(name: &str) -> Result<String, CaseError> {
    let data = "LAMMPS data\n\n2 atoms\n1 atom types\n\n0 0.1 xlo xhi\n0 0.1 ylo yhi\n0 0.1 zlo zhi\n\nAtoms # sphere\n\n1 1 0.004 2500 0.05 0.05 0.05\n2 1 0.004 2500 0.05 0.02 0.05\n";
    match name {
        "dup.csv" => Ok("x,y,z,phase,Y\n0.05,0.05,0.05,glass,0.02\n".into()),
        "empty.csv" => Ok("x,y,z,phase\n# only a comment\n".into()),
        "bom.csv" => Ok("\u{feff}x,y,z,phase\n0.05,0.05,0.05,glass\n".into()),
        "box.data" => Ok(data.into()),
        "tall.data" => Ok(data.replace("0 0.1 zlo zhi", "-0.1 0.1 zlo zhi")),
        "vel.data" => Ok(format!("{data}\nVelocities\n\n1 0 0 0 0 0 0\n2 0 0 0 0 0 0\n2 1 0 0 0 0 0\n")),
        "same.dat" => Ok("0.05 0.05 0.05 0.002 2500 0 0 0\n0.05 0.05 0.05 0.002 2500 0 0 0\n".into()),
        other => {
            Err(CaseError::Read { path: other.into(), source: std::io::Error::other("not in this test") })
        }
    }
}

fn parse_text(text: &str) -> Result<grainflow_case::Case, CaseError> {
    parse(text, "case.toml", &files)
}

fn edit(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "test bug: '{from}' not in the base case");
    BASE.replacen(from, to, 1)
}

fn refused(text: &str, want: &[&str]) {
    let e = parse_text(text).expect_err("must be refused").to_string();
    for w in want {
        assert!(e.contains(w), "message lacks '{w}': {e}");
    }
}

fn with_particles(table: &str) -> String {
    edit(INLINE, &format!("[particles]\n{table}\n"))
}

#[test]
fn max_overlap_is_exposed_validated_and_bounds_the_initial_limit() {
    assert_eq!(parse_text(BASE).expect("valid").max_overlap, 0.5, "the default: half the smaller radius");
    let c = parse_text(&edit(INLINE, &format!("[particles]\nmax_overlap = 0.2\n{INLINE}"))).expect("valid");
    assert_eq!(c.max_overlap, 0.2);
    for bad in ["0.0", "-0.1", "1.5", "nan"] {
        refused(
            &edit(INLINE, &format!("[particles]\nmax_overlap = {bad}\n{INLINE}")),
            &["max_overlap", "(0, 1]"],
        );
    }
    refused(
        &edit(INLINE, &format!("[particles]\nmax_initial_overlap = 0.3\nmax_overlap = 0.2\n{INLINE}")),
        &["max_initial_overlap", "0.3", "must not exceed max_overlap = 0.2"],
    );
    // The initial limit defaults to the smaller of 0.05 and max_overlap: a 3 % wall overlap
    // (centre 0.00194 m from the floor, radius 0.002 m) passes under 0.05, not under 0.01.
    let near_floor = |table: &str| {
        edit(
            INLINE,
            &format!("[particles]\n{table}\n{}", INLINE.replace("0.05, 0.05, 0.05", "0.05, 0.00194, 0.05")),
        )
    };
    parse_text(&near_floor("")).expect("3 % is under the 5 % default");
    refused(&near_floor("max_overlap = 0.01"), &["max_initial_overlap = 0.01"]);
}

#[test]
fn repeated_and_contradictory_keys_are_refused() {
    refused(
        &edit(
            "max = [0.1, 0.1, 0.1]",
            "max = [0.1, 0.1, 0.1]\nperiodic = [\"x\", \"z\", \"x\"]\nwalls = false",
        ),
        &["[domain]", "periodic", "\"x\" is listed twice"],
    );
    refused(
        &with_particles("file = \"dup.csv\""),
        &["dup.csv, line 1", "the column 'y' appears twice (columns 2 and 5)"],
    );
    refused(&with_particles("file = \"empty.csv\""), &["empty.csv", "a header row but no particles"]);
    refused(
        &with_particles("file = \"vel.data\""),
        &["vel.data, line 19", "velocity of atom 2 is given twice"],
    );
    refused(
        &with_particles("file = \"same.dat\""),
        &["particle 1 at", "and particle 2 have the same centre"],
    );
}

#[test]
fn a_lammps_box_other_than_the_domain_is_a_warning() {
    let c = parse_text(&with_particles("file = \"box.data\"")).expect("valid");
    assert!(c.warnings.is_empty(), "the box is the domain: {:?}", c.warnings);
    let c = parse_text(&with_particles("file = \"tall.data\"")).expect("valid");
    assert_eq!(c.warnings.len(), 1, "{:?}", c.warnings);
    assert!(c.warnings[0].contains("[0.0, 0.0, -0.1]") && c.warnings[0].contains("grainflow uses [domain]"));
    parse_text(&with_particles("file = \"bom.csv\"")).expect("a byte-order mark is skipped");
}

#[test]
fn phase_and_wall_material_counts_are_limited_before_any_table() {
    let phases = |n: usize| -> String {
        (0..n).map(|k| format!("[[phases]]\nname = \"p{k}\"\ndiameter = 0.004\ndensity = 2500.0\n")).collect()
    };
    // 100 phases (the limit) are read; 101 are refused naming the limit.
    let at = |n: usize| {
        edit("[[phases]]\nname = \"glass\"", &format!("{}[[phases]]\nname = \"glass\"", phases(n - 1)))
    };
    assert_eq!(parse_text(&at(100)).expect("100 phases").config.phases.len(), 100);
    refused(&at(101), &["[[phases]]", "(101 tables)", "at most 100 phases"]);
    let walls: String = (0..101).map(|k| format!("[[wall_materials]]\nname = \"w{k}\"\n")).collect();
    refused(&edit("[contact]\n", &format!("{walls}[contact]\n")), &["at most 100 wall materials"]);
}

#[test]
fn absurd_step_counts_and_derived_overflows_are_refused() {
    // 0.01 s at the MFIX rule's 1.29e-5 s is 778 steps; each edit below makes it absurd.
    for (from, to) in [
        ("t_stop = 0.01", "t_stop = 1e300"),
        ("t_stop = 0.01", "t_stop = 0.01\ndt = 1e-300"),
        ("kn = 1000.0\nen = 0.9\nmu = 0.3\n[contact.wall]", "kn = 1e300\nen = 0.9\nmu = 0.3\n[contact.wall]"),
    ] {
        refused(&edit(from, to), &["more than the limit of 1e10 steps"]);
    }
    refused(&edit("t_stop = 0.01", "t_stop = 0.01\ndt = 5e-324"), &["overflows"]);
    // 2^33 = 8.6e9 steps (dt = 2^-33 s for 1 s) are below the limit; 1.01e10 are not.
    parse_text(&edit("t_stop = 0.01", "t_stop = 1.0\ndt = 1.1641532182693481e-10"))
        .expect("8.6e9 steps are allowed");
    refused(&edit("t_stop = 0.01", "t_stop = 1.0\ndt = 9.9e-11"), &["1.010e10 steps"]);
    refused(&edit("density = 2500.0", "density = 1e308"), &["double precision"]);
    refused(&edit("diameter = 0.004", "diameter = 1e-300"), &["`diameter`", "particle mass"]);
}

#[test]
fn the_mfix_name_of_a_key_is_suggested() {
    refused(&edit("mu = 0.3\n[contact.wall]", "mew = 0.3\n[contact.wall]"), &["did you mean `mu`?"]);
    refused(&edit("density = 2500.0", "ro_s0 = 2500.0"), &["did you mean `density`?"]);
    refused(
        &edit("kn = 1000.0\nen = 0.9\nmu", "kn = 1000.0\nen = 0.9\nmu_rol = 0.0\nmu"),
        &["did you mean `mu_roll`?"],
    );
}

#[test]
fn hertz_cases_without_dt_default_to_a_fifth_of_the_rayleigh_time() {
    let hertz = BASE.replace("model = \"lsd\"", "model = \"hertz\"").replace("kn = 1000.0\n", "et = 0.9\n");
    let c = parse_text(&hertz).expect("valid");
    // T_R = πR√(ρ/G)/(0.1631ν + 0.8766), R = 0.002 m, ρ = 2500 kg/m³, G = E/(2(1+ν)) = 2.4e10 Pa,
    // ν = 0.25: 2.2143e-6 s; the default is 0.2·T_R.
    let tr = std::f64::consts::PI * 0.002 * (2500.0f64 / 2.4e10).sqrt() / (0.1631 * 0.25 + 0.8766);
    let TimeStepRule::Fixed(dt) = c.config.time_step else { panic!("{:?}", c.config.time_step) };
    assert!((dt / (0.2 * tr) - 1.0).abs() < 1e-12, "dt = {dt}, T_R = {tr}");
    let sim = grainflow::Simulation::new(c.config.clone(), c.particles.clone()).expect("runs");
    let why = &sim.time_step().explanation;
    assert!(why.contains("Rayleigh time") && why.contains("the default for Hertz contacts"), "{why}");
    // MFIX's rule (K_n taken as linear) stays available by name, and gives a far smaller step:
    // here TCOLL/50 = 1.2e-8 s, about 37 times below the default.
    let mfix =
        parse_text(&hertz.replace("t_stop = 0.01", "t_stop = 0.01\ndtsolid_factor = 50")).expect("valid");
    assert_eq!(mfix.config.time_step, TimeStepRule::Mfix { factor: 50.0 });
    let mfix_dt = grainflow::Simulation::new(mfix.config, mfix.particles).expect("runs").dt();
    assert!(dt / mfix_dt > 20.0, "default {dt} vs MFIX's {mfix_dt}");
    // A linear case without dt keeps MFIX's rule.
    assert_eq!(parse_text(BASE).expect("valid").config.time_step, TimeStepRule::Mfix { factor: 50.0 });
}

#[test]
fn the_engine_refuses_coincident_centres_and_motion_cycles_itself() {
    let c = parse_text(&edit(
        INLINE,
        &format!("{INLINE}{}", INLINE.replace("0.05, 0.05, 0.05", "0.05, 0.02, 0.05")),
    ))
    .expect("valid");
    let mut p = c.particles.clone();
    p.position[1] = p.position[0];
    let Err(e) = grainflow::Simulation::new(c.config.clone(), p) else { panic!("accepted") };
    let e = e.to_string();
    assert!(e.contains("particles 1 and 2 have the same centre"), "{e}");
    let mut cfg = c.config.clone();
    let follow = |leader| grainflow::MotionRule::Follow { leader, axes: [true, false, false] };
    cfg.motion = vec![
        grainflow::PrescribedMotion { particle: 1, rule: follow(2) },
        grainflow::PrescribedMotion { particle: 2, rule: follow(1) },
    ];
    let Err(e) = grainflow::Simulation::new(cfg, c.particles) else { panic!("accepted") };
    let e = e.to_string();
    assert!(e.contains("cycle (1 follows 2 follows 1)"), "{e}");
}

/// The base case with an insertion (`keys` before its region) pouring glass into the upper
/// part of the box.
fn with_insertion(keys: &str) -> String {
    let id = INLINE.replace("[[particles.list]]\n", "[[particles.list]]\nid = 1\n");
    edit(
        INLINE,
        &format!(
            "{id}[[insertions]]\nname = \"pour\"\n{keys}\n[insertions.region]\nkind = \"box\"\nmin = [0.0, 0.06, 0.0]\nmax = [0.1, 0.1, 0.1]\n[[insertions.phases]]\nphase = \"glass\"\n"
        ),
    )
}

fn plan_of(text: &str, limit: f64) -> Result<grainflow_case::plan::Plan, CaseError> {
    grainflow_case::plan::plan(
        &parse_text(text).expect("a valid case"),
        grainflow_case::plan::MemoryLimit::given(limit),
    )
}

/// The plan's figures are the run's: the step count and the time-series rows as the run
/// loop counts them, and a rate insertion's batches and particles exactly (a count rate
/// brings batch k's total to rate·(k + 1)·every, and the empty region places every bead).
#[test]
fn the_plan_counts_what_the_run_does() {
    let text = with_insertion("rate = 1000.0\nevery = 0.002");
    let plan = plan_of(&text, f64::INFINITY).expect("planned");
    let case = parse_text(&text).expect("valid");
    let mut sim = grainflow::Simulation::new(case.config, case.particles).expect("set-up");
    assert_eq!(plan.dt, sim.dt());
    assert_eq!(plan.steps, sim.total_steps());
    let every = grainflow_case::plan::output_every(None, sim.dt(), sim.total_steps());
    assert_eq!(plan.output_every, every);
    // Rows at steps 0, every, 2·every, … and at the last step.
    let rows = (0..=sim.total_steps()).filter(|s| s % every == 0 || *s == sim.total_steps()).count();
    assert_eq!(plan.rows as usize, rows);
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    let books = sim.flow_books();
    assert_eq!(books.missed, vec![0]);
    let inserted = books.inserted_total().count;
    let p = &plan.insertions[0];
    // Batches at 0, 0.002, …, 0.008 s (the last step starts before 0.01 s): 5 of 2 beads.
    assert_eq!((p.batches, p.particles, p.largest_batch), (5, 10.0, 2.0));
    assert_eq!(inserted, 10, "{books:?}");
    // All at once: the count.
    let p = plan_of(&with_insertion("count = 300"), f64::INFINITY).expect("planned");
    assert_eq!((p.insertions[0].batches, p.insertions[0].particles), (1, 300.0));
    assert_eq!(p.memory.arriving, 300.0);
}

/// Item 16: batches more often than the steps are refused, naming `every`; one a step is
/// accepted.
#[test]
fn batches_more_often_than_the_steps_are_refused() {
    let dt = plan_of(BASE, f64::INFINITY).expect("planned").dt;
    let e = plan_of(&with_insertion("rate = 1000.0\nevery = 1e-12"), f64::INFINITY)
        .expect_err("refused")
        .to_string();
    for w in ["[[insertions]] 'pour'", "`every` = 1e-12 is invalid", "give every >= dt"] {
        assert!(e.contains(w), "message lacks '{w}': {e}");
    }
    plan_of(&with_insertion(&format!("rate = 1000.0\nevery = {dt:e}")), f64::INFINITY)
        .expect("one batch a step");
    let e = plan_of(&with_insertion(&format!("rate = 1000.0\nevery = {:e}", 0.5 * dt)), f64::INFINITY)
        .expect_err("two a step")
        .to_string();
    assert!(e.contains("would come 2.000e0 times in a step"), "{e}");
}

/// Item 17: past the limit, the refusal names the key that brings the particles and gives
/// the figures: 10⁶ beads by count; by volume fraction 0.5 of the 0.1 × 0.04 × 0.1 m region,
/// 2·10⁻⁴ m³ of 4 mm beads (3.3510·10⁻⁸ m³ each): 5968.3; by mass 1 kg of 8.3776·10⁻⁵ kg
/// beads: 11 936.6; at 10⁶ beads/s in batches every 1 ms, the ten batches whose steps start
/// before 0.01 s: 10⁴. Each at 544 bytes (Euler: 152 of state, 88 of neighbour list, 7 pairs
/// of 43.5).
#[test]
fn past_the_memory_limit_the_refusal_names_the_key() {
    let mib = 1024.0 * 1024.0;
    for (keys, key, value, particles) in [
        ("count = 1000000", "count", "1000000", "1.0000e6 inserted"),
        ("volume_fraction = 0.5", "volume_fraction", "0.5", "5.9683e3 inserted"),
        ("mass = 1.0", "mass", "1", "1.1937e4 inserted"),
        ("rate = 1e6\nevery = 0.001", "rate", "1e6", "1.0000e4 inserted"),
    ] {
        let e = plan_of(&with_insertion(keys), 64.0 * mib).expect_err("over the limit").to_string();
        for w in [
            format!("[[insertions]] 'pour': `{key}` = {value} is invalid"),
            particles.into(),
            "544 bytes each".into(),
            "64.0 MiB (--memory-limit)".into(),
        ] {
            assert!(e.contains(&w), "{keys}: message lacks '{w}': {e}");
        }
    }
    // The base case (one bead) fits in 64 MiB plus a little: the base is 64 MiB.
    plan_of(BASE, 65.0 * mib).expect("one bead fits");
}

/// `--set` is the file saying it: the same validated case (the hash aside, which covers the
/// overrides), and the same messages.
#[test]
fn set_overrides_are_validated_as_the_file_is() {
    use grainflow_case::{SetOverride, parse_with};
    let sets = |s: &[&str]| s.iter().map(|a| SetOverride::parse(a).expect("parses")).collect::<Vec<_>>();
    let with =
        parse_with(BASE, "case.toml", &files, &sets(&["time.t_stop=0.002", "contact.particle.mu=0.5"]))
            .expect("valid");
    let edited = parse_text(&edit("t_stop = 0.01", "t_stop = 0.002").replacen("mu = 0.3", "mu = 0.5", 1))
        .expect("valid");
    assert_eq!(with.config.t_stop, edited.config.t_stop);
    assert_eq!(format!("{:?}", with.config), format!("{:?}", edited.config));
    assert_ne!(with.hash, edited.hash, "the hash covers the overrides");
    let e = parse_with(BASE, "case.toml", &files, &sets(&["contact.particle.mu=-1"]))
        .expect_err("refused")
        .to_string();
    let from_file = parse_text(&edit("mu = 0.3", "mu = -1")).expect_err("refused").to_string();
    assert_eq!(e, from_file);
}

/// Item 16's other interval: an output interval below the step is rounded up to one step, and
/// said so (an interval that rounds to one step or more is not).
#[test]
fn output_intervals_below_the_step_are_rounded_up_with_a_warning() {
    let tiny = edit("t_stop = 0.01", "t_stop = 0.01\n[output]\ninterval = 1e-12\nvtk_interval = 1e-12");
    let plan = plan_of(&tiny, f64::INFINITY).expect("planned");
    assert_eq!(plan.output_every, 1);
    assert_eq!(plan.rows, plan.steps + 1, "a row at every step and at the start");
    assert_eq!(plan.warnings.len(), 2, "{:?}", plan.warnings);
    for (w, key) in plan.warnings.iter().zip(["`interval`", "`vtk_interval`"]) {
        assert!(w.starts_with(&format!("[output]: {key} = 1e-12 s is below the time step")), "{w}");
        assert!(w.contains("rounded up to one step"), "{w}");
    }
    let dt = plan.dt;
    let one = edit("t_stop = 0.01", &format!("t_stop = 0.01\n[output]\ninterval = {:e}", 0.6 * dt));
    let plan = plan_of(&one, f64::INFINITY).expect("planned");
    assert!(plan.warnings.is_empty() && plan.output_every == 1, "{:?}", plan.warnings);
}
