//! LAMMPS data files (`write_data` output, `atom_style sphere`), so grainflow can start from
//! exactly the state a LAMMPS or LIGGGHTS run used.
//!
//! Read: the header counts and box bounds, the `Atoms` section (`id type diameter density x y
//! z`, optionally followed by three image flags), and the optional `Velocities` section (`id
//! vx vy vz wx wy wz`). Atom type k is phase k of the case (1-based, in the order of
//! `[[phases]]`); each particle keeps its own diameter and density. Other sections are skipped.

use crate::error::CaseError;
use crate::input::Stream;
use grainflow::Vec3;
use grainflow::material::Phase;
use grainflow::state::ParticleInit;

/// The box bounds a data file declares (lower, upper corner), if it has them.
pub fn box_bounds(text: &str) -> Option<(Vec3, Vec3)> {
    let mut lo = [f64::NAN; 3];
    let mut hi = [f64::NAN; 3];
    for line in text.lines().take(50) {
        let f: Vec<&str> = line.split_whitespace().collect();
        for (k, tag) in ["xlo", "ylo", "zlo"].iter().enumerate() {
            if f.len() >= 4 && f[2] == *tag {
                lo[k] = f[0].parse().ok()?;
                hi[k] = f[1].parse().ok()?;
            }
        }
    }
    let (lo, hi) = (Vec3::from_array(lo), Vec3::from_array(hi));
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// Reads the particles of a LAMMPS data file.
pub fn read_data(text: &str, path: &str, phases: &[Phase]) -> Result<Vec<ParticleInit>, CaseError> {
    read_data_from(&mut Stream::from_text(text, path), phases).map(|d| d.atoms)
}

/// What a data file gives: the atoms (sorted by id) and the box bounds, if declared.
#[derive(Debug, Clone)]
pub struct DataFile {
    /// The atoms, sorted by id.
    pub atoms: Vec<ParticleInit>,
    /// The box (lower, upper corner), if the header declares all three axes.
    pub bounds: Option<(Vec3, Vec3)>,
}

/// [`read_data`] from a stream, line by line. The header must declare the atom count
/// (`N atoms`) before the Atoms section, as LAMMPS requires; the reader stops at the first
/// atom beyond it and at the first velocity given twice.
pub fn read_data_from(s: &mut Stream<'_>, phases: &[Phase]) -> Result<DataFile, CaseError> {
    let path = s.name.clone();
    let err = |line: usize, message: String| CaseError::ParticleFile { path: path.clone(), line, message };
    // Large beds come in large files: the lines are read one at a time, and the atoms are
    // kept sorted by id (for the Velocities section) instead of in an id index.
    let mut expected_atoms: Option<usize> = None;
    let mut section = "";
    let mut in_header = true;
    let mut atoms: Vec<ParticleInit> = Vec::new();
    // The line of each atom, for the message naming an id given twice.
    let mut lines: Vec<u32> = Vec::new();
    let mut sorted = true;
    let mut has_velocity: Vec<bool> = Vec::new();
    let mut velocity_section = false;
    let mut velocities = 0usize;
    let (mut lo, mut hi) = ([f64::NAN; 3], [f64::NAN; 3]);
    let mut last_line = 0;
    while let Some((line_no, raw)) = s.next_line()? {
        last_line = line_no;
        if line_no == 1 {
            continue; // the title line
        }
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let head = raw.trim();
        if head.starts_with("Atoms") {
            if !head.contains("sphere") && head.contains('#') {
                return Err(err(
                    line_no,
                    format!("'{head}': only atom_style sphere is read (id type diameter density x y z)"),
                ));
            }
            if expected_atoms.is_none() {
                return Err(err(
                    line_no,
                    "the Atoms section comes before the header declares the atom count (`N atoms`), which LAMMPS requires".into(),
                ));
            }
            if !atoms.is_empty() || velocity_section {
                return Err(err(
                    line_no,
                    "a second Atoms section, or one after the Velocities section: a data file has one Atoms section, then at most one Velocities section".into(),
                ));
            }
            in_header = false;
            section = "Atoms";
            continue;
        }
        if head.starts_with("Velocities") {
            if velocity_section {
                return Err(err(line_no, "a second Velocities section: a data file has at most one".into()));
            }
            velocity_section = true;
            in_header = false;
            section = "Velocities";
            sort_by_id(&mut atoms, &lines, &mut sorted, &path)?;
            has_velocity = vec![false; atoms.len()];
            continue;
        }
        if head.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) {
            in_header = false;
            section = "other";
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |s: &str, what: &str| -> Result<f64, CaseError> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(line_no, format!("{what} = '{s}' is not a number")))
        };
        match section {
            "" if in_header && f.len() == 2 && f[1] == "atoms" => {
                let n = f[0]
                    .parse::<usize>()
                    .map_err(|_| err(line_no, format!("'{}' is not an atom count", f[0])))?;
                if n == 0 {
                    return Err(err(line_no, "the header declares 0 atoms: there is nothing to run".into()));
                }
                expected_atoms = Some(n);
                // Room for the first of them; the rest as they come (a header that overstates
                // the count must not reserve memory the file does not fill).
                atoms.reserve_exact(n.min(1 << 16));
            }
            "" if in_header && f.len() >= 4 && ["xlo", "ylo", "zlo"].contains(&f[2]) => {
                let k = ["xlo", "ylo", "zlo"].iter().position(|t| *t == f[2]).unwrap_or(0);
                lo[k] = num(f[0], f[2])?;
                hi[k] = num(f[1], ["xhi", "yhi", "zhi"][k])?;
            }
            "Atoms" => {
                let n = expected_atoms.unwrap_or(0);
                if atoms.len() >= n {
                    return Err(err(
                        line_no,
                        format!(
                            "the header declares {n} atoms but the Atoms section has more (this line is atom {})",
                            atoms.len() + 1
                        ),
                    ));
                }
                if f.len() != 7 && f.len() != 10 {
                    return Err(err(
                        line_no,
                        format!(
                            "expected 7 values (id type diameter density x y z), optionally 3 image flags; found {}",
                            f.len()
                        ),
                    ));
                }
                let id: u32 = f[0]
                    .parse()
                    .ok()
                    .filter(|&i| i >= 1)
                    .ok_or_else(|| err(line_no, format!("id '{}' must be a whole number >= 1", f[0])))?;
                let ty: usize = f[1].parse().ok().filter(|&t| t >= 1 && t <= phases.len()).ok_or_else(|| {
                    err(line_no, format!("atom type '{}' has no phase: the case defines {} phase(s), type k is the k-th", f[1], phases.len()))
                })?;
                let d = num(f[2], "diameter")?;
                let rho = num(f[3], "density")?;
                if !(d > 0.0 && rho > 0.0) {
                    return Err(err(line_no, format!("diameter {d} and density {rho} must be positive")));
                }
                sorted &= atoms.last().is_none_or(|a| a.id < id);
                crate::plan::check_reading(atoms.len(), &path, line_no)?;
                atoms.push(ParticleInit {
                    id,
                    phase: (ty - 1) as u32,
                    radius: 0.5 * d,
                    density: rho,
                    position: Vec3::new(num(f[4], "x")?, num(f[5], "y")?, num(f[6], "z")?),
                    velocity: Vec3::ZERO,
                    omega: Vec3::ZERO,
                });
                lines.push(u32::try_from(line_no).unwrap_or(u32::MAX));
            }
            "Velocities" => {
                if f.len() != 7 {
                    return Err(err(
                        line_no,
                        format!("expected 7 values (id vx vy vz wx wy wz); found {}", f.len()),
                    ));
                }
                let id: u32 =
                    f[0].parse().map_err(|_| err(line_no, format!("id '{}' is not a whole number", f[0])))?;
                let slot = atoms.binary_search_by_key(&id, |a| a.id).map_err(|_| {
                    err(line_no, format!("velocity for atom {id}, which the Atoms section does not have"))
                })?;
                if std::mem::replace(&mut has_velocity[slot], true) {
                    return Err(err(
                        line_no,
                        format!(
                            "the velocity of atom {id} is given twice; each atom has one Velocities line"
                        ),
                    ));
                }
                atoms[slot].velocity = Vec3::new(num(f[1], "vx")?, num(f[2], "vy")?, num(f[3], "vz")?);
                atoms[slot].omega = Vec3::new(num(f[4], "wx")?, num(f[5], "wy")?, num(f[6], "wz")?);
                velocities += 1;
            }
            _ => {}
        }
    }
    if let Some(n) = expected_atoms
        && n != atoms.len()
    {
        return Err(err(
            last_line,
            format!("the header declares {n} atoms but the Atoms section has {}", atoms.len()),
        ));
    }
    if atoms.is_empty() {
        return Err(err(last_line, "no Atoms section with particles".into()));
    }
    if velocities != 0 && velocities != atoms.len() {
        return Err(err(
            last_line,
            format!("the Velocities section covers {velocities} of {} atoms", atoms.len()),
        ));
    }
    // LAMMPS writes atoms in no particular order; keep them sorted by id.
    sort_by_id(&mut atoms, &lines, &mut sorted, &path)?;
    let (lo, hi) = (Vec3::from_array(lo), Vec3::from_array(hi));
    let bounds = (lo.is_finite() && hi.is_finite()).then_some((lo, hi));
    Ok(DataFile { atoms, bounds })
}

/// Sorts the atoms by id unless they are known to be sorted; an id that appears twice is an
/// error naming the lines of both appearances (`lines[k]` is where atom k was read).
fn sort_by_id(
    atoms: &mut [ParticleInit],
    lines: &[u32],
    sorted: &mut bool,
    path: &str,
) -> Result<(), CaseError> {
    if *sorted {
        return Ok(()); // strictly increasing ids: none twice
    }
    // The duplicate check on (id, line) pairs, 8 bytes an atom, before the atoms are moved.
    let mut keys: Vec<(u32, u32)> = atoms.iter().zip(lines).map(|(a, &l)| (a.id, l)).collect();
    keys.sort_unstable();
    if let Some(w) = keys.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(CaseError::ParticleFile {
            path: path.to_string(),
            line: w[1].1 as usize,
            message: format!("atom id {} appears twice (also on line {})", w[0].0, w[0].1),
        });
    }
    drop(keys);
    // Ids are unique, so an unstable sort orders them as a stable one, without its buffer
    // of half the atoms.
    atoms.sort_unstable_by_key(|a| a.id);
    *sorted = true;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const DATA: &str = "LAMMPS data file via write_data\n\n3 atoms\n2 atom types\n\n0 0.04 xlo xhi\n0 0.04 ylo yhi\n0 0.12 zlo zhi\n\nAtoms # sphere\n\n2 1 0.002 2500 0.01 0.02 0.03 0 0 0\n1 2 0.003 2600 0.011 0.021 0.031 0 0 0\n3 1 0.002 2500 0.012 0.022 0.032\n\nVelocities\n\n1 1 2 3 4 5 6\n2 -1 -2 -3 -4 -5 -6\n3 0 0 0 0 0 0\n";

    fn phases() -> Vec<Phase> {
        vec![
            Phase {
                name: "a".into(),
                diameter: 0.002,
                density: 2500.0,
                youngs_modulus: None,
                poisson_ratio: None,
            },
            Phase {
                name: "b".into(),
                diameter: 0.003,
                density: 2600.0,
                youngs_modulus: None,
                poisson_ratio: None,
            },
        ]
    }

    #[test]
    fn reads_atoms_velocities_and_box() {
        let p = read_data(DATA, "x.data", &phases()).expect("valid");
        assert_eq!(p.iter().map(|a| a.id).collect::<Vec<_>>(), vec![1, 2, 3]);
        assert_eq!(p[0].phase, 1);
        assert_eq!(p[0].radius, 0.0015);
        assert_eq!(p[0].density, 2600.0);
        assert_eq!(p[0].position, Vec3::new(0.011, 0.021, 0.031));
        assert_eq!(p[0].velocity, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(p[0].omega, Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(p[1].velocity, Vec3::new(-1.0, -2.0, -3.0));
        assert_eq!(box_bounds(DATA), Some((Vec3::ZERO, Vec3::new(0.04, 0.04, 0.12))));
    }

    #[test]
    fn bad_files_name_the_line() {
        let bad = |text: &str, want: &str| {
            let e = read_data(text, "x.data", &phases()).expect_err("must fail").to_string();
            assert!(e.contains(want), "{e}");
        };
        bad(
            &DATA.replace("2 1 0.002 2500 0.01", "2 3 0.002 2500 0.01"),
            "line 12: atom type '3' has no phase",
        );
        bad(&DATA.replace("3 atoms", "4 atoms"), "declares 4 atoms");
        bad(&DATA.replace("0.012 0.022 0.032", "0.012 0.022"), "line 14: expected 7 values");
        bad(&DATA.replace("1 1 2 3 4 5 6", "9 1 2 3 4 5 6"), "atom 9");
        bad(
            &DATA.replace("3 1 0.002 2500 0.012", "2 1 0.002 2500 0.012"),
            "line 14: atom id 2 appears twice",
        );
        bad(&DATA.replace("0.011 0.021", "0.011 abc"), "y = 'abc'");
    }
}
