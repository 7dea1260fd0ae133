//! Particle files: MFIX's legacy `particle_input.dat` and CSV.

use crate::error::CaseError;
use crate::input::Stream;
use grainflow::Vec3;
use grainflow::material::Phase;
use grainflow::state::ParticleInit;

/// Reads MFIX's legacy `particle_input.dat` (3-D): one particle per line,
/// `x y z radius density u v w` (SI), no header. Blank lines and lines starting with `#` or `!`
/// are skipped. The phase is found as MFIX does: the phase whose diameter and density match
/// the particle's (exactly, else to a relative 1e-4: [`match_phase`]). Ids are the 1-based particle numbers.
pub fn read_mfix(text: &str, path: &str, phases: &[Phase]) -> Result<Vec<ParticleInit>, CaseError> {
    read_mfix_from(&mut Stream::from_text(text, path), phases)
}

/// [`read_mfix`] from a stream, line by line.
pub fn read_mfix_from(s: &mut Stream<'_>, phases: &[Phase]) -> Result<Vec<ParticleInit>, CaseError> {
    let mut out = Vec::new();
    let path = s.name.clone();
    while let Some((line, text)) = s.next_line()? {
        let Some(fields) = mfix_fields(text) else { continue };
        let err = |message: String| CaseError::ParticleFile { path: path.clone(), line, message };
        let [x, y, z, r, rho, u, vv, w] = mfix_numbers(&fields).map_err(err)?;
        let phase = match_phase(2.0 * r, rho, phases).ok_or_else(|| {
            err(format!(
                "no phase has diameter {} m and density {rho} kg/m³ (phases: {})",
                2.0 * r,
                describe_phases(phases)
            ))
        })?;
        let id =
            u32::try_from(out.len() + 1).map_err(|_| err(format!("more than {} particles", u32::MAX)))?;
        crate::plan::check_reading(out.len(), &path, line)?;
        out.push(ParticleInit {
            id,
            phase: phase as u32,
            radius: r,
            density: rho,
            position: Vec3::new(x, y, z),
            velocity: Vec3::new(u, vv, w),
            omega: Vec3::ZERO,
        });
    }
    if out.is_empty() {
        return Err(CaseError::ParticleFile {
            path,
            line: s.lines_read(),
            message: "the file holds no particles (one line per particle: x y z radius density u v w)".into(),
        });
    }
    Ok(out)
}

/// The fields of a data line of `particle_input.dat`, or `None` for a blank or comment line.
pub(crate) fn mfix_fields(line: &str) -> Option<Vec<&str>> {
    let t = line.trim();
    if t.is_empty() || t.starts_with('#') || t.starts_with('!') {
        return None;
    }
    Some(t.split_whitespace().collect())
}

/// The eight numbers of a `particle_input.dat` line (SI), the radius checked.
pub(crate) fn mfix_numbers(fields: &[&str]) -> Result<[f64; 8], String> {
    if fields.len() != 8 {
        return Err(format!("expected 8 numbers (x y z radius density u v w), found {}", fields.len()));
    }
    let mut v = [0.0; 8];
    for (slot, f) in v.iter_mut().zip(fields) {
        *slot = parse_number(f).ok_or_else(|| format!("'{f}' is not a number"))?;
    }
    if !(v[3].is_finite() && v[3] > 0.0) {
        return Err(format!("radius {} must be positive (m)", v[3]));
    }
    Ok(v)
}

/// Reads a CSV particle file with a header row. Columns (any order):
/// `x,y,z` (m, required), `phase` (name or 1-based index, required), `id` (default: row
/// number), `diameter` or `radius` (m, default: the phase's), `u,v,w` (m/s, default 0),
/// `wx,wy,wz` (rad/s, default 0). Unknown columns are an error.
pub fn read_csv(text: &str, path: &str, phases: &[Phase]) -> Result<Vec<ParticleInit>, CaseError> {
    read_csv_from(&mut Stream::from_text(text, path), phases)
}

/// [`read_csv`] from a stream, record by record.
pub fn read_csv_from(s: &mut Stream<'_>, phases: &[Phase]) -> Result<Vec<ParticleInit>, CaseError> {
    let path = s.name.clone();
    let path = path.as_str();
    const KNOWN: [&str; 13] =
        ["id", "phase", "x", "y", "z", "diameter", "radius", "u", "v", "w", "wx", "wy", "wz"];
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).comment(Some(b'#')).from_reader(s);
    let header_err = |message: String| CaseError::ParticleFile { path: path.to_string(), line: 1, message };
    let headers = rdr.headers().map_err(|e| header_err(format!("cannot read the header row: {e}")))?.clone();
    let mut col = [None; 13];
    if headers.iter().all(|h| h.is_empty()) {
        return Err(header_err(format!(
            "the file is empty; a CSV particle file starts with a header row naming its columns ({})",
            KNOWN.join(", ")
        )));
    }
    for (c, h) in headers.iter().enumerate() {
        let h = h.to_ascii_lowercase();
        match KNOWN.iter().position(|k| *k == h) {
            Some(k) if col[k].is_some() => {
                return Err(header_err(format!(
                    "the column '{h}' appears twice (columns {} and {}); each column may appear once",
                    col[k].map_or(0, |c: usize| c + 1),
                    c + 1
                )));
            }
            Some(k) => col[k] = Some(c),
            None => {
                return Err(header_err(format!(
                    "unknown column '{h}'; the columns are {}",
                    KNOWN.join(", ")
                )));
            }
        }
    }
    for (k, name) in [(1, "phase"), (2, "x"), (3, "y"), (4, "z")] {
        if col[k].is_none() {
            return Err(header_err(format!("the required column '{name}' is missing")));
        }
    }
    if col[5].is_some() && col[6].is_some() {
        return Err(header_err("give either 'diameter' or 'radius', not both".into()));
    }
    let mut out = Vec::new();
    for (row, rec) in rdr.records().enumerate() {
        let line = rec.as_ref().ok().and_then(|r| r.position()).map_or(row + 2, |p| p.line() as usize);
        let err = |message: String| CaseError::ParticleFile { path: path.to_string(), line, message };
        let rec = rec.map_err(|e| err(format!("{e}")))?;
        let get = |k: usize| -> Result<Option<f64>, CaseError> {
            match col[k] {
                None => Ok(None),
                Some(c) => {
                    let s = rec.get(c).unwrap_or("");
                    parse_number(s)
                        .map(Some)
                        .ok_or_else(|| err(format!("{} = '{s}' is not a number", KNOWN[k])))
                }
            }
        };
        let phase_text = col[1].and_then(|c| rec.get(c)).unwrap_or("");
        let phase = phases
            .iter()
            .position(|p| p.name == phase_text)
            .or_else(|| {
                phase_text.parse::<usize>().ok().filter(|&k| k >= 1 && k <= phases.len()).map(|k| k - 1)
            })
            .ok_or_else(|| {
                err(format!(
                    "phase '{phase_text}' is neither a phase name nor an index 1..{} (phases: {})",
                    phases.len(),
                    describe_phases(phases)
                ))
            })?;
        let radius = match (get(5)?, get(6)?) {
            (Some(d), _) => 0.5 * d,
            (_, Some(r)) => r,
            _ => phases[phase].radius(),
        };
        if !(radius.is_finite() && radius > 0.0) {
            return Err(err(format!("the radius {radius} m must be positive")));
        }
        let id = match get(0)? {
            None => u32::try_from(row + 1).map_err(|_| err(format!("more than {} particles", u32::MAX)))?,
            Some(v) if v >= 1.0 && v <= u32::MAX as f64 && v.fract() == 0.0 => v as u32,
            Some(v) => return Err(err(format!("id {v} must be a whole number >= 1"))),
        };
        let v3 = |a: usize| -> Result<Vec3, CaseError> {
            Ok(Vec3::new(get(a)?.unwrap_or(0.0), get(a + 1)?.unwrap_or(0.0), get(a + 2)?.unwrap_or(0.0)))
        };
        crate::plan::check_reading(out.len(), path, line)?;
        out.push(ParticleInit {
            id,
            phase: phase as u32,
            radius,
            density: phases[phase].density,
            position: v3(2)?,
            velocity: v3(7)?,
            omega: v3(10)?,
        });
    }
    if out.is_empty() {
        return Err(CaseError::ParticleFile {
            path: path.to_string(),
            line: 1,
            message: "the file has a header row but no particles (one row per particle below the header)"
                .into(),
        });
    }
    Ok(out)
}

fn parse_number(s: &str) -> Option<f64> {
    // Fortran-style exponents (1.0D-3) appear in MFIX files.
    let v: f64 = s.replace(['D', 'd'], "e").parse().ok()?;
    v.is_finite().then_some(v)
}

/// The phase of a particle, by MFIX's rule (`des/set_phase_index.f`): the first phase whose
/// diameter and density equal the particle's to MFIX's `SMALL_NUMBER` (1e-15, absolute, in SI
/// here); failing that, the first within a relative 1e-4 of both.
pub fn match_phase(diameter: f64, density: f64, phases: &[Phase]) -> Option<usize> {
    match_phase_within(diameter, density, phases, (SMALL_NUMBER, SMALL_NUMBER))
}

/// [`match_phase`] with the absolute tolerances of the first pass given, for diameter (m) and
/// density (kg/m³): MFIX's `SMALL_NUMBER` in the deck's units, converted to SI.
pub fn match_phase_within(diameter: f64, density: f64, phases: &[Phase], exact: (f64, f64)) -> Option<usize> {
    let first = phases
        .iter()
        .position(|p| (diameter - p.diameter).abs() < exact.0 && (density - p.density).abs() < exact.1);
    first.or_else(|| {
        let close = |a: f64, b: f64| (a - b).abs() / b < MATCH_TOLERANCE;
        phases.iter().position(|p| close(diameter, p.diameter) && close(density, p.density))
    })
}

/// MFIX's `SMALL_NUMBER`: the absolute tolerance of its first matching pass.
pub const SMALL_NUMBER: f64 = 1e-15;

/// MFIX's relative tolerance for matching a particle to a phase when no phase matches exactly.
pub const MATCH_TOLERANCE: f64 = 1e-4;

fn describe_phases(phases: &[Phase]) -> String {
    phases
        .iter()
        .map(|p| format!("'{}' d = {} m, rho = {} kg/m³", p.name, short(p.diameter), short(p.density)))
        .collect::<Vec<_>>()
        .join("; ")
}

/// A number as written for people: plain in the usual range, else with an exponent (so a
/// density of 1e308 is not 309 digits).
pub(crate) fn short(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e7).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}
