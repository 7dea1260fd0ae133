//! Hostile input, run as a user would: every reader (TOML case files, CSV, particle_input.dat,
//! LAMMPS data, MFIX decks, `--motion` files, checkpoints) is given files that are special,
//! huge, deeply nested, inconsistent or absurd. Each run must end with exit code 2 and a message
//! saying what is wrong, inside a virtual-memory cap and before a hang guard, and never panic.
//! Inputs the program should only warn about are checked for the warning and exit code 0.
//!
//! The base inputs are in tests/hostile/; large inputs are generated into a temporary folder
//! (sparse where they are only large, not full).
//!
//! Run against the readers this corpus was written for (before grainflow issue 26), most cases
//! fail: runs killed by the memory cap (LAMMPS and particle_input.dat files longer than
//! declared, a line of repeats, a 30 000-deep expression), runs still going at the hang guard
//! (FIFOs, `dt = 1e-300`), absurd inputs that ran and exited 0, and misleading messages.

use std::fs::File;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Virtual-memory cap of every run, KiB: 64 MiB, about five times what a one-particle run
/// needs. Measured on the 2-core development machine (x86-64 Linux, glibc) by running the base
/// case (one particle, 778 steps, `-j 1`) under decreasing `ulimit -v`: it completes under
/// 12 000 KiB and aborts on a failed allocation under 9 000 KiB, so it needs 10-12 MiB of
/// address space. (Its VmPeak without a cap, ~140 MB, is mostly glibc's per-thread malloc arena,
/// reserved, not used; under a cap glibc falls back to the main heap.) The readers replaced
/// here took 1.4-23 GB on these inputs. [`base_inputs_run_under_the_cap`] shows the cap leaves
/// room for a real run, so a refusal below is the program's, not the cap's (an allocation
/// refused by the cap aborts with 134, not 2).
const VM_CAP_KB: u64 = 65_536;

/// A run still going after this long is killed and fails the test: a guard against hangs (a
/// FIFO opened for reading, a loop over 10^298 steps), not a timing assertion.
const HANG_GUARD: Duration = Duration::from_secs(20);

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/hostile");

fn base(name: &str) -> String {
    std::fs::read_to_string(Path::new(DATA).join(name)).expect("base input")
}

/// A file of a hostile case.
enum Content {
    Bytes(Vec<u8>),
    /// A sparse file of this many zero bytes (large without filling the disk).
    Sparse(u64),
    Dir,
    Fifo,
    /// A symbolic link to this path.
    Link(&'static str),
    /// A copy of a checkpoint written by the base case, cut or changed by the function.
    Checkpoint(fn(Vec<u8>) -> Vec<u8>),
}

struct Hostile {
    name: String,
    files: Vec<(String, Content)>,
    args: Vec<String>,
    /// Part of the message on standard error.
    expect: String,
}

struct Outcome {
    code: Option<i32>,
    stderr: String,
    timed_out: bool,
}

fn text(s: impl Into<String>) -> Content {
    Content::Bytes(s.into().into_bytes())
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// Replaces `from` with `to` once (the text must occur: a case that edits nothing would
/// test the base input).
fn edit(base: &str, from: &str, to: &str) -> String {
    assert!(base.contains(from), "test bug: '{from}' not in the base input");
    base.replacen(from, to, 1)
}

const RUN_CASE: &[&str] = &["run", "case.toml", "--out", "out", "-j", "1"];
const RUN_DECK: &[&str] = &["run", "mfix.dat", "--out", "out-deck", "-j", "1"];
const INLINE: &str = "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]\n";

/// The base case with one edit.
fn toml(name: &str, from: &str, to: &str, expect: &str) -> Hostile {
    Hostile {
        name: name.into(),
        files: vec![("case.toml".into(), text(edit(&base("case.toml"), from, to)))],
        args: strings(RUN_CASE),
        expect: expect.into(),
    }
}

/// The base case reading its particles from `file` (given as `content`, or a path outside).
fn with_particles(name: &str, table: &str, file: &str, content: Option<Content>, expect: &str) -> Hostile {
    let case = edit(&base("case.toml"), INLINE, &format!("[particles]\nfile = \"{file}\"\n{table}"));
    let mut files = vec![("case.toml".to_string(), text(case))];
    if let Some(c) = content {
        files.push((file.to_string(), c));
    }
    Hostile { name: name.into(), files, args: strings(RUN_CASE), expect: expect.into() }
}

/// The base deck (edited) with a particle file.
fn deck(name: &str, deck: String, particles: Content, extra: &[&str], expect: &str) -> Hostile {
    let mut args = strings(RUN_DECK);
    args.extend(strings(extra));
    Hostile {
        name: name.into(),
        files: vec![("mfix.dat".into(), text(deck)), ("particle_input.dat".into(), particles)],
        args,
        expect: expect.into(),
    }
}

fn deck_edit(name: &str, from: &str, to: &str, expect: &str) -> Hostile {
    deck(name, edit(&base("mfix.dat"), from, to), text(base("particle_input.dat")), &[], expect)
}

/// The base deck with user functions replaced by a motion file.
fn motion(name: &str, file: &str, content: Option<Content>, expect: &str) -> Hostile {
    let mut h = deck(
        name,
        edit(&base("mfix.dat"), "MEW = 0.3", "MEW = 0.3  CALL_USR = .TRUE."),
        text(base("particle_input.dat")),
        &["--motion", file],
        expect,
    );
    if let Some(c) = content {
        h.files.push((file.into(), c));
    }
    h
}

fn restart(name: &str, file: &str, content: Option<Content>, expect: &str) -> Hostile {
    let mut files = vec![("case.toml".to_string(), text(base("case.toml")))];
    if let Some(c) = content {
        files.push((file.to_string(), c));
    }
    let mut args = strings(RUN_CASE);
    args.extend(strings(&["--restart", file]));
    Hostile { name: name.into(), files, args, expect: expect.into() }
}

/// `n` LAMMPS atom lines with ids from 1.
fn atom_lines(n: usize) -> String {
    let mut s = String::with_capacity(n * 40);
    for k in 1..=n {
        let x = 0.001 + 0.098 * (k % 1000) as f64 / 1000.0;
        s.push_str(&format!("{k} 1 0.004 2500 {x} 0.05 0.05\n"));
    }
    s
}

fn lammps_with(atoms: &str, velocities: &str, count: usize) -> String {
    format!(
        "LAMMPS data file\n\n{count} atoms\n1 atom types\n\n0 0.1 xlo xhi\n0 0.1 ylo yhi\n0 0.1 zlo zhi\n\nAtoms # sphere\n\n{atoms}{velocities}"
    )
}

const LAMMPS_TABLE: &str = "format = \"lammps\"\n";

fn phases(n: usize) -> String {
    (0..n).map(|k| format!("[[phases]]\nname = \"p{k}\"\ndiameter = 0.004\ndensity = 2500.0\n")).collect()
}

fn nested(n: usize) -> String {
    format!("{}1.0e4{}", "(".repeat(n), ")".repeat(n))
}

/// Every refused input. Each names what it tests; the expected text is part of the message.
fn cases() -> Vec<Hostile> {
    let gib = 1u64 << 30;
    let mut v = vec![
        // ---- the case file itself
        restart_like_case("case file: /dev/zero", "/dev/zero", None, "character device, not a regular file"),
        restart_like_case(
            "case file: /dev/urandom",
            "/dev/urandom",
            None,
            "character device, not a regular file",
        ),
        restart_like_case(
            "case file: a directory",
            "dir.toml",
            Some(Content::Dir),
            "a directory, not a regular file",
        ),
        restart_like_case("case file: a FIFO", "fifo.toml", Some(Content::Fifo), "a named pipe (FIFO)"),
        restart_like_case(
            "case file: 1 GiB",
            "big.toml",
            Some(Content::Sparse(gib)),
            "more than a case file can be (4.0 MiB)",
        ),
        restart_like_case(
            "case file: just over 4 MiB of comments",
            "long.toml",
            Some(Content::Bytes(vec![b'#'; (4 << 20) + 1])),
            "more than a case file can be",
        ),
        restart_like_case(
            "case file: not UTF-8",
            "bin.toml",
            Some(Content::Bytes(b"version = 1\n\xff\xfe".to_vec())),
            "not UTF-8 text",
        ),
        restart_like_case("case file: /proc/self/status", "/proc/self/status", None, "TOML parse error"),
        restart_like_case("case file: missing", "none.toml", None, "cannot read none.toml"),
        restart_like_case(
            "case file: arrays nested 100 000 deep",
            "deep.toml",
            Some(text(format!("x = {}{}\n", "[".repeat(100_000), "]".repeat(100_000)))),
            "TOML parse error",
        ),
        // ---- absurd step counts (issue 26: they ran 0 steps and reported success, or for ever)
        toml("kn = 1e300", "kn = 1000.0", "kn = 1e300", "more than the limit of 1e10 steps"),
        toml("t_stop = 1e300", "t_stop = 0.01", "t_stop = 1e300", "more than the limit of 1e10 steps"),
        toml("dt = 5e-324", "t_stop = 0.01", "t_stop = 0.01\ndt = 5e-324", "overflows"),
        toml(
            "dt = 1e-300",
            "t_stop = 0.01",
            "t_stop = 0.01\ndt = 1e-300",
            "more than the limit of 1e10 steps",
        ),
        toml("dt = 1e-12 for 0.1 s", "t_stop = 0.01", "t_stop = 0.1\ndt = 1e-12", "1.000e11 steps"),
        // ---- derived quantities that overflow or underflow from finite inputs
        toml("density 1e308", "density = 2500.0", "density = 1e308", "beyond what double precision can hold"),
        toml("diameter 1e-300", "diameter = 0.004", "diameter = 1e-300", "particle mass"),
        toml("diameter 1e200", "diameter = 0.004", "diameter = 1e200", "particle mass"),
        // ---- tables too many to hold
        toml(
            "5000 phases",
            "[[phases]]\nname = \"glass\"",
            &format!("{}[[phases]]\nname = \"glass\"", phases(4999)),
            "at most 100 phases",
        ),
        toml(
            "200 wall materials",
            "[contact]",
            &format!(
                "{}[contact]",
                (0..200).map(|k| format!("[[wall_materials]]\nname = \"w{k}\"\n")).collect::<String>()
            ),
            "at most 100 wall materials",
        ),
        // ---- inconsistent settings
        toml(
            "periodic x twice",
            "max = [0.1, 0.1, 0.1]",
            "max = [0.1, 0.1, 0.1]\nperiodic = [\"x\", \"x\"]",
            "listed twice",
        ),
        toml(
            "two particles at the same centre",
            INLINE,
            &format!("{INLINE}{INLINE}"),
            "have the same centre",
        ),
        toml(
            "max_initial_overlap above max_overlap",
            INLINE,
            &format!("[particles]\nmax_initial_overlap = 0.6\n{INLINE}"),
            "must not exceed max_overlap = 0.5",
        ),
        toml("max_overlap = 0", INLINE, &format!("[particles]\nmax_overlap = 0.0\n{INLINE}"), "(0, 1]"),
        toml("max_overlap = 2", INLINE, &format!("[particles]\nmax_overlap = 2.0\n{INLINE}"), "(0, 1]"),
        toml(
            "follow rules in a cycle",
            INLINE,
            &format!(
                "{INLINE}[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.02, 0.05]\n[[motion]]\nparticles = 1\nrule = \"follow\"\nleader = 2\naxes = [\"x\"]\n[[motion]]\nparticles = 2\nrule = \"follow\"\nleader = 1\naxes = [\"y\"]\n"
            ),
            "cycle (1 follows 2 follows 1)",
        ),
        toml(
            "a particle with two motion rules",
            INLINE,
            &format!(
                "{INLINE}[[motion]]\nparticles = 1\nrule = \"hold\"\n[[motion]]\nparticles = 1\nrule = \"hold\"\n"
            ),
            "two prescribed-motion rules",
        ),
        toml(
            "the MFIX name mew",
            "en = 0.9\n[contact.wall]",
            "mew = 0.4\n[contact.wall]",
            "did you mean `mu`?",
        ),
        // ---- particle_input.dat
        with_particles("mfix file: /dev/zero", "", "/dev/zero", None, "character device"),
        with_particles("mfix file: /dev/urandom", "", "/dev/urandom", None, "character device"),
        with_particles("mfix file: a directory", "", "p.dat", Some(Content::Dir), "a directory"),
        with_particles("mfix file: a FIFO", "", "p.dat", Some(Content::Fifo), "a named pipe"),
        with_particles(
            "mfix file: 1 GiB of zero bytes",
            "",
            "p.dat",
            Some(Content::Sparse(gib)),
            "longer than 65536 bytes",
        ),
        with_particles(
            "mfix file: 5 GiB",
            "",
            "p.dat",
            Some(Content::Sparse(5 * gib)),
            "more than a particle file can be (4.0 GiB)",
        ),
        with_particles("mfix file: empty", "", "p.dat", Some(text("")), "holds no particles"),
        with_particles(
            "mfix file: only comments",
            "",
            "p.dat",
            Some(text("# x y z r rho u v w\n! none\n")),
            "holds no particles",
        ),
        with_particles(
            "mfix file: 7 columns",
            "",
            "p.dat",
            Some(text("0.05 0.05 0.05 0.002 2500 0 0\n")),
            "line 1: expected 8 numbers",
        ),
        with_particles(
            "mfix file: not UTF-8",
            "",
            "p.dat",
            Some(Content::Bytes(b"0.05 0.05 \xff\n".to_vec())),
            "not UTF-8",
        ),
        with_particles(
            "mfix file: NaN",
            "",
            "p.dat",
            Some(text("0.05 0.05 NaN 0.002 2500 0 0 0\n")),
            "'NaN' is not a number",
        ),
        with_particles(
            "mfix file: /proc/self/status",
            "",
            "/proc/self/status",
            None,
            "line 1: expected 8 numbers",
        ),
        with_particles(
            "mfix file: two beads at one centre",
            "",
            "p.dat",
            Some(text("0.05 0.05 0.05 0.002 2500 0 0 0\n0.05 0.05 0.05 0.002 2500 0 0 0\n")),
            "particle 1 at (5.000000e-2, 5.000000e-2, 5.000000e-2) m and particle 2 have the same centre",
        ),
        // ---- CSV
        with_particles("csv: /dev/zero", "", "/dev/zero", None, "character device"),
        with_particles(
            "csv: 1 GiB of zero bytes",
            "",
            "p.csv",
            Some(Content::Sparse(gib)),
            "longer than 65536 bytes",
        ),
        with_particles("csv: empty", "", "p.csv", Some(text("")), "the file is empty"),
        with_particles(
            "csv: a header and no rows",
            "",
            "p.csv",
            Some(text("x,y,z,phase\n")),
            "a header row but no particles",
        ),
        with_particles(
            "csv: a column twice",
            "",
            "p.csv",
            Some(text("x,y,z,phase,x\n0.05,0.05,0.05,glass,0.01\n")),
            "the column 'x' appears twice (columns 1 and 5)",
        ),
        with_particles(
            "csv: an unknown column",
            "",
            "p.csv",
            Some(text("x,y,z,phase,colour\n")),
            "unknown column 'colour'",
        ),
        with_particles(
            "csv: id 0",
            "",
            "p.csv",
            Some(text("id,x,y,z,phase\n0,0.05,0.05,0.05,glass\n")),
            "id 0 must be a whole number >= 1",
        ),
        with_particles(
            "csv: an id twice",
            "",
            "p.csv",
            Some(text("id,x,y,z,phase\n3,0.05,0.05,0.05,glass\n3,0.05,0.02,0.05,glass\n")),
            "particle id 3 is used twice",
        ),
        with_particles(
            "csv: radius 1e-300",
            "",
            "p.csv",
            Some(text("x,y,z,phase,radius\n0.05,0.05,0.05,glass,1e-300\n")),
            "particle 1 mass",
        ),
        // ---- LAMMPS data
        with_particles("lammps: /dev/urandom", LAMMPS_TABLE, "/dev/urandom", None, "character device"),
        with_particles(
            "lammps: 1 GiB of zero bytes",
            LAMMPS_TABLE,
            "p.data",
            Some(Content::Sparse(gib)),
            "longer than 65536 bytes",
        ),
        with_particles(
            "lammps: 100 atoms declared, 10^6 given",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with(&atom_lines(1_000_000), "", 100))),
            "line 112: the header declares 100 atoms but the Atoms section has more",
        ),
        with_particles(
            "lammps: 10^18 atoms declared, 2 given",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with(&atom_lines(2), "", 1_000_000_000_000_000_000))),
            "declares 1000000000000000000 atoms but the Atoms section has 2",
        ),
        with_particles(
            "lammps: 0 atoms",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with("", "", 0))),
            "declares 0 atoms",
        ),
        with_particles(
            "lammps: Atoms before the count",
            LAMMPS_TABLE,
            "p.data",
            Some(text(format!("title\n\nAtoms # sphere\n\n{}", atom_lines(2)))),
            "before the header declares the atom count",
        ),
        with_particles(
            "lammps: a velocity line twice",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with(&atom_lines(2), "\nVelocities\n\n1 0 0 0 0 0 0\n1 1 0 0 0 0 0\n", 2))),
            "the velocity of atom 1 is given twice",
        ),
        with_particles(
            "lammps: two Velocities sections",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with(
                &atom_lines(2),
                "\nVelocities\n\n1 0 0 0 0 0 0\n2 0 0 0 0 0 0\n\nVelocities\n\n1 0 0 0 0 0 0\n",
                2,
            ))),
            "a second Velocities section",
        ),
        with_particles(
            "lammps: an atom id twice",
            LAMMPS_TABLE,
            "p.data",
            Some(text(lammps_with(
                "2 1 0.004 2500 0.05 0.05 0.05\n1 1 0.004 2500 0.05 0.02 0.05\n2 1 0.004 2500 0.05 0.08 0.05\n",
                "",
                3,
            ))),
            "line 14: atom id 2 appears twice (also on line 12)",
        ),
        // ---- MFIX decks
        deck_edit(
            "deck: a line of 1000 × 100000*0.7",
            "MEW = 0.3",
            &format!("MEW = 0.3\nDES_EN_INPUT = {}", vec!["100000*0.7"; 1000].join(" ")),
            "more than 100000 values",
        ),
        deck_edit(
            "deck: 2000 lines of 100*1",
            "MEW = 0.3",
            &format!(
                "MEW = 0.3\n{}",
                (1..=2000).map(|k| format!("DES_EN_INPUT({}) = 100*0.5\n", 100 * k)).collect::<String>()
            ),
            "more than 100000 values",
        ),
        deck_edit(
            "deck: @( ) 30 000 deep",
            "KN = 1.0e4",
            &format!("KN = @({})", nested(30_000)),
            "nests deeper than 64 levels",
        ),
        deck_edit(
            "deck: @( ) 65 deep",
            "KN = 1.0e4",
            &format!("KN = @({})", nested(64)),
            "nests deeper than 64 levels",
        ),
        deck_edit(
            "deck: @( ) with 30 000 signs",
            "KN = 1.0e4",
            &format!("KN = @({}1)", "-".repeat(30_000)),
            "nests deeper",
        ),
        deck_edit(
            "deck: a subscript beyond any array",
            "MEW = 0.3",
            "MEW = 0.3\nDES_EN_INPUT(1000000) = 0.5",
            "beyond any MFIX array",
        ),
        deck(
            "deck: density 1e308",
            edit(&base("mfix.dat"), "RO_S0 = 1000.0 2000.0", "RO_S0 = 1e308 2000.0"),
            text(edit(&base("particle_input.dat"), "0.05 1000.0", "0.05 1e308")),
            &[],
            "beyond what double precision can hold",
        ),
        deck_edit("deck: KN = 1e300", "KN = 1.0e4", "KN = 1.0e300", "more than the limit of 1e10 steps"),
        deck_edit(
            "deck: TSTOP = 1e300",
            "TSTOP = 0.01",
            "TSTOP = 1e300",
            "more than the limit of 1e10 steps",
        ),
        deck(
            "deck: PARTICLES = 2, 1.5·10^6 lines",
            base("mfix.dat"),
            text("0.5 0.5 0.5 0.05 1000.0 0 0 0\n".repeat(1_500_000)),
            &[],
            "overlap by 2.000 of the smaller radius",
        ),
        deck(
            "deck: particle file of 1 GiB of zero bytes",
            base("mfix.dat"),
            Content::Sparse(gib),
            &[],
            "longer than 65536 bytes",
        ),
        deck("deck: particle file a directory", base("mfix.dat"), Content::Dir, &[], "a directory"),
        deck("deck: particle file a FIFO", base("mfix.dat"), Content::Fifo, &[], "a named pipe"),
        // ---- --motion files
        motion(
            "motion: /dev/urandom",
            "/dev/urandom",
            None,
            "character device, not a regular file; a motion file",
        ),
        motion("motion: a FIFO", "m.toml", Some(Content::Fifo), "a named pipe"),
        motion("motion: 1 GiB", "m.toml", Some(Content::Sparse(gib)), "more than a motion file can be"),
        motion(
            "motion: a cycle",
            "m.toml",
            Some(text(
                "[[motion]]\nparticles = 1\nrule = \"follow\"\nleader = 2\naxes = [\"x\"]\n[[motion]]\nparticles = 2\nrule = \"follow\"\nleader = 1\naxes = [\"x\"]\n",
            )),
            "follow each other in a cycle",
        ),
        motion("motion: no rules", "m.toml", Some(text("# nothing\n")), "[[motion]]"),
        // ---- checkpoints (--restart)
        restart("checkpoint: /dev/zero", "/dev/zero", None, "not a regular file"),
        restart("checkpoint: /dev/urandom", "/dev/urandom", None, "not a regular file"),
        restart("checkpoint: a directory", "c.gfc", Some(Content::Dir), "cannot restart from c.gfc"),
        restart("checkpoint: empty", "c.gfc", Some(text("")), "not a grainflow checkpoint"),
        restart(
            "checkpoint: garbage",
            "c.gfc",
            Some(text("grainflow checkpoint? no.\n".repeat(100))),
            "not a grainflow checkpoint",
        ),
        restart(
            "checkpoint: truncated",
            "c.gfc",
            Some(Content::Checkpoint(|b| b[..b.len() / 2].to_vec())),
            "truncated",
        ),
        restart(
            "checkpoint: wrong signature",
            "c.gfc",
            Some(Content::Checkpoint(|mut b| {
                b[0] ^= 0xff;
                b
            })),
            "not a grainflow checkpoint",
        ),
        restart(
            "checkpoint: a flipped payload byte",
            "c.gfc",
            Some(Content::Checkpoint(|mut b| {
                let k = b.len() - 40;
                b[k] ^= 0x10;
                b
            })),
            "cannot restart from c.gfc",
        ),
    ];
    // The deck itself a special or huge file.
    for (name, path, content, expect) in [
        (
            "deck: a link to /dev/zero",
            "zero.dat",
            Some(Content::Link("/dev/zero")),
            "character device, not a regular file; an MFIX deck",
        ),
        ("deck: a directory", "d.dat", Some(Content::Dir), "a directory"),
        ("deck: a FIFO", "f.dat", Some(Content::Fifo), "a named pipe"),
        ("deck: 1 GiB", "big.dat", Some(Content::Sparse(gib)), "more than an MFIX deck can be"),
    ] {
        let mut files = Vec::new();
        if let Some(c) = content {
            files.push((path.to_string(), c));
        }
        v.push(Hostile {
            name: name.into(),
            files,
            args: strings(&["run", path, "--out", "out", "-j", "1"]),
            expect: expect.into(),
        });
    }
    // Plans that cannot work, refused before the run starts (issue 38, items 16, 17, 20).
    let pour = |every: &str, amount: &str| {
        format!(
            "{INLINE}[[insertions]]\nname = \"pour\"\n{amount}every = {every}\n[insertions.region]\nkind = \"box\"\nmin = [0.0, 0.06, 0.0]\nmax = [0.1, 0.1, 0.1]\n[[insertions.phases]]\nphase = \"glass\"\n"
        )
    };
    v.push(toml(
        "insertion: every = 1e-12, far below the step (hung)",
        INLINE,
        &pour("1e-12", "rate = 1000.0\n"),
        "[[insertions]] 'pour': `every` = 1e-12 is invalid",
    ));
    let mut h = toml(
        "insertion: 1e8 beads in all past --memory-limit 1GB",
        INLINE,
        &pour("0.01", "rate = 1e9\ncount = 100000000\n"),
        "`count` = 100000000 is invalid: the run would hold up to",
    );
    h.args.extend(strings(&["--memory-limit", "1GB"]));
    v.push(h);
    for (name, set, expect) in [
        ("--set: a misspelt key", "time.tstop=0.1", "did you mean `t_stop`?"),
        ("--set: no such entry", "phases.7.density=1", "`phases` has 1 entry (0 to 0), not an entry 7"),
        ("--set: not a value", "time.t_stop=0.1s", "`0.1s` is not a TOML value"),
    ] {
        v.push(Hostile {
            name: name.into(),
            files: vec![("case.toml".into(), text(base("case.toml")))],
            args: strings(&[RUN_CASE, &["--set", set]].concat()),
            expect: expect.into(),
        });
    }
    // `convert` reads decks through the same reader.
    v.push(Hostile {
        name: "convert: @( ) 30 000 deep".into(),
        files: vec![
            (
                "mfix.dat".into(),
                text(edit(&base("mfix.dat"), "KN = 1.0e4", &format!("KN = @({})", nested(30_000)))),
            ),
            ("particle_input.dat".into(), text(base("particle_input.dat"))),
        ],
        args: strings(&["convert", "mfix.dat"]),
        expect: "nests deeper than 64 levels".into(),
    });
    v.push(Hostile {
        name: "convert: /dev/urandom".into(),
        files: Vec::new(),
        args: strings(&["convert", "/dev/urandom"]),
        expect: "character device".into(),
    });
    v
}

/// A run of a case file given by path (the case file itself is the hostile input).
fn restart_like_case(name: &str, path: &str, content: Option<Content>, expect: &str) -> Hostile {
    let mut files = Vec::new();
    if let Some(c) = content {
        files.push((path.to_string(), c));
    }
    Hostile {
        name: name.into(),
        files,
        args: strings(&["run", path, "--out", "out", "-j", "1"]),
        expect: expect.into(),
    }
}

/// A checkpoint of the base case, written once.
fn checkpoint() -> &'static [u8] {
    static CK: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    CK.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("case.toml"), base("case.toml")).expect("write");
        let o = run(
            dir.path(),
            &strings(&["run", "case.toml", "--out", "ck", "-j", "1", "-q", "--checkpoint-every", "100"]),
        );
        assert_eq!(o.code, Some(0), "the base case must run: {}", o.stderr);
        std::fs::read(dir.path().join("ck/checkpoint.gfc")).expect("the run writes a checkpoint")
    })
}

fn write(dir: &Path, name: &str, content: &Content) {
    let path = dir.join(name);
    match content {
        Content::Bytes(b) => std::fs::write(&path, b).expect("write"),
        Content::Sparse(n) => File::create(&path).and_then(|f| f.set_len(*n)).expect("sparse file"),
        Content::Dir => std::fs::create_dir(&path).expect("dir"),
        Content::Fifo => {
            let ok = Command::new("mkfifo").arg(&path).status().is_ok_and(|s| s.success());
            assert!(ok, "mkfifo {}", path.display());
        }
        Content::Link(to) => std::os::unix::fs::symlink(to, &path).expect("symlink"),
        Content::Checkpoint(change) => std::fs::write(&path, change(checkpoint().to_vec())).expect("write"),
    }
}

/// Runs the program under the memory cap and the hang guard, in `dir`.
fn run(dir: &Path, args: &[String]) -> Outcome {
    let err_path = dir.join("stderr.txt");
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {VM_CAP_KB}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_grainflow"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(File::create(dir.join("stdout.txt")).expect("stdout file"))
        .stderr(File::create(&err_path).expect("stderr file"))
        .spawn()
        .expect("spawn");
    let start = Instant::now();
    let (code, timed_out) = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break (status.code(), false);
        }
        if start.elapsed() > HANG_GUARD {
            let _ = child.kill();
            let _ = child.wait();
            break (None, true);
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = String::from_utf8_lossy(&std::fs::read(&err_path).unwrap_or_default()).into_owned();
    Outcome { code, stderr, timed_out }
}

/// Runs one case in a fresh folder; `None` if it behaved, else what went wrong.
fn check(h: &Hostile) -> Option<String> {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, content) in &h.files {
        write(dir.path(), name, content);
    }
    let o = run(dir.path(), &h.args);
    let head: String = o.stderr.chars().take(600).collect();
    if o.timed_out {
        return Some(format!("{}: still running after {HANG_GUARD:?} (killed)", h.name));
    }
    if o.code != Some(2) || !o.stderr.contains(&h.expect) || o.stderr.contains("panicked") {
        return Some(format!(
            "{}: exit {:?}, expected 2 and a message containing {:?}; stderr:\n{head}",
            h.name, o.code, h.expect
        ));
    }
    None
}

fn run_share(part: usize, of: usize) {
    let all = cases();
    let failures: Vec<String> =
        all.iter().enumerate().filter(|(k, _)| k % of == part).filter_map(|(_, h)| check(h)).collect();
    assert!(
        failures.is_empty(),
        "{} of the hostile cases failed:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

// The corpus in two halves, so that the test harness runs them on two threads.
#[test]
fn hostile_inputs_first_half() {
    run_share(0, 2);
}

#[test]
fn hostile_inputs_second_half() {
    run_share(1, 2);
}

#[test]
fn the_corpus_covers_every_reader() {
    let all = cases();
    // The issue asks for at least 60 cases across the readers.
    assert!(all.len() >= 60, "only {} cases", all.len());
    eprintln!("{} hostile cases", all.len());
    for prefix in
        ["case file:", "mfix file:", "csv:", "lammps:", "deck:", "motion:", "checkpoint:", "convert:"]
    {
        assert!(
            all.iter().filter(|h| h.name.starts_with(prefix)).count() >= 2,
            "fewer than 2 '{prefix}' cases"
        );
    }
    let mut names: Vec<&str> = all.iter().map(|h| h.name.as_str()).collect();
    names.sort_unstable();
    let before = names.len();
    names.dedup();
    assert_eq!(before, names.len(), "two cases share a name");
}

/// The base inputs run to completion under the same cap: a refusal above is the program's.
#[test]
fn base_inputs_run_under_the_cap() {
    let dir = tempfile::tempdir().expect("temp dir");
    for f in ["case.toml", "mfix.dat", "particle_input.dat"] {
        std::fs::write(dir.path().join(f), base(f)).expect("write");
    }
    for args in [RUN_CASE, RUN_DECK] {
        let o = run(dir.path(), &strings(args));
        assert_eq!(o.code, Some(0), "{args:?}: {}", o.stderr);
    }
}

/// Inputs that are read with a warning (or silently accepted), not refused.
#[test]
fn warned_inputs_run() {
    // (what, files, arguments, the warning expected, if any)
    type Warned = (&'static str, Vec<(String, Content)>, Vec<String>, Option<&'static str>);
    let cases: Vec<Warned> = vec![
        (
            "a LAMMPS box other than the domain",
            vec![
                (
                    "case.toml".into(),
                    text(edit(&base("case.toml"), INLINE, "[particles]\nfile = \"p.data\"\n")),
                ),
                ("p.data".into(), text(base("particles.data").replace("0 0.1 zlo zhi", "0 0.2 zlo zhi"))),
            ],
            strings(RUN_CASE),
            Some("declares the box [0.0, 0.0, 0.0] to [0.1, 0.1, 0.2], which [domain] min"),
        ),
        (
            "a TOML case file with a byte-order mark",
            vec![("case.toml".into(), text(format!("\u{feff}{}", base("case.toml"))))],
            strings(RUN_CASE),
            None,
        ),
        (
            "a CSV file with a byte-order mark",
            vec![
                (
                    "case.toml".into(),
                    text(edit(&base("case.toml"), INLINE, "[particles]\nfile = \"p.csv\"\n")),
                ),
                ("p.csv".into(), text(format!("\u{feff}{}", base("particles.csv")))),
            ],
            strings(RUN_CASE),
            None,
        ),
        (
            "particle_input.dat with a byte-order mark",
            vec![
                (
                    "case.toml".into(),
                    text(edit(&base("case.toml"), INLINE, "[particles]\nfile = \"p.dat\"\n")),
                ),
                ("p.dat".into(), text(format!("\u{feff}{}", base("glass.dat")))),
            ],
            strings(RUN_CASE),
            None,
        ),
        (
            "an MFIX deck with a byte-order mark",
            vec![
                ("mfix.dat".into(), text(format!("\u{feff}{}", base("mfix.dat")))),
                ("particle_input.dat".into(), text(base("particle_input.dat"))),
            ],
            strings(RUN_DECK),
            None,
        ),
        (
            "a motion file with a byte-order mark",
            vec![
                (
                    "mfix.dat".into(),
                    text(edit(&base("mfix.dat"), "MEW = 0.3", "MEW = 0.3  CALL_USR = .TRUE.")),
                ),
                ("particle_input.dat".into(), text(base("particle_input.dat"))),
                ("m.toml".into(), text(format!("\u{feff}{}", base("motion.toml")))),
            ],
            [strings(RUN_DECK), strings(&["--motion", "m.toml"])].concat(),
            None,
        ),
    ];
    let mut failures = Vec::new();
    for (name, files, args, warning) in &cases {
        let dir = tempfile::tempdir().expect("temp dir");
        for (f, c) in files {
            write(dir.path(), f, c);
        }
        let o = run(dir.path(), args);
        let warned =
            warning.is_none_or(|w| o.stderr.lines().any(|l| l.starts_with("warning: ") && l.contains(w)));
        if o.code != Some(0) || !warned {
            failures.push(format!(
                "{name}: exit {:?}, expected 0{}; stderr:\n{}",
                o.code,
                warning.map_or(String::new(), |w| format!(" and the warning {w:?}")),
                o.stderr
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// A domain that holds the LAMMPS file's box along its walled axes (LAMMPS shrink-wraps a
/// flow's open top) is no reason for a warning.
#[test]
fn a_lammps_box_inside_the_domain_is_not_warned_about() {
    let dir = tempfile::tempdir().expect("temp dir");
    write(
        dir.path(),
        "case.toml",
        &text(edit(&base("case.toml"), INLINE, "[particles]\nfile = \"p.data\"\n")),
    );
    write(dir.path(), "p.data", &text(base("particles.data").replace("0 0.1 zlo zhi", "0 0.08 zlo zhi")));
    let o = run(dir.path(), &strings(RUN_CASE));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(!o.stderr.contains("declares the box"), "{}", o.stderr);
}
