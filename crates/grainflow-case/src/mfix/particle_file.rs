//! `particle_input.dat` (legacy, CGS, 2-D and version 2.0 layouts): the particles, their
//! phases, and the overlaps they start with.

use super::keywords::Unit;
use super::*;
use crate::case::DEFAULT_MAX_INITIAL_OVERLAP;
use crate::error::CaseError;
use crate::input;
use crate::particles;
use crate::raw::*;
use grainflow::{Phase, Vec3, Wall};
use std::collections::HashMap;

impl Translator<'_> {
    /// `[particles]` from particle_input.dat, and text to add to the case hash.
    pub(super) fn particles(
        &mut self,
        phases: &[Phase],
        lo: Vec3,
        hi: Vec3,
        faces: &[&str],
        walls: &[grainflow::mesh::Mesh],
        read_file: &input::Opener<'_>,
    ) -> Result<(RawParticles, String), CaseError> {
        let count = self.deck.int("PARTICLES", &[])?;
        if let Some(g) = &count
            && g.v < 0
        {
            return Err(CaseError::invalid(
                g.loc.to_string(),
                g.key.clone(),
                g.text.clone(),
                "must be a number of particles, 0 or more (0: no particle file, the particles come from mass inflows)",
            ));
        }
        let want = count.as_ref().map_or(default_int("PARTICLES"), |g| g.v) as usize;
        // One streamed pass: the data lines are counted (MFIX reads exactly PARTICLES of
        // them, so the pass stops soon after a file that has more), and kept as numbers for
        // the overlap check (SI) or the inline list (CGS). The bytes are kept for the case
        // hash only for CGS, whose particles the case lists inline.
        let kept = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
        let reader = read_file(PARTICLE_FILE)?;
        let reader: Box<dyn std::io::BufRead> = if self.cgs {
            Box::new(std::io::BufReader::new(Tee { inner: reader, out: kept.clone() }))
        } else {
            reader
        };
        let mut stream = input::Stream::new(reader, PARTICLE_FILE);
        let mut data: Vec<(usize, [f64; 8])> = Vec::new();
        let mut first_error: Option<CaseError> = None;
        let mut n_data = 0usize;
        let mut longer = false;
        let dims = if self.flag("NO_K")? { 2 } else { 3 };
        let mut v2: Option<V2Layout> = None;
        let mut v2_header = V2Header::default();
        let mut want = want;
        let mut phases_given: Vec<Option<usize>> = Vec::new();
        while let Some((line, l)) = stream.next_line()? {
            let pf = |message: String| CaseError::ParticleFile { path: PARTICLE_FILE.into(), line, message };
            if line == 1 && l.trim_end().starts_with("Version 2.0") {
                v2_header.on = true;
                continue;
            }
            if v2_header.on && v2.is_none() {
                // MFIX's fixed header: the dimension on line 19, the count on 20, the
                // columns on 24–31, data from line 35.
                v2_header.read(line, l, dims).map_err(pf)?;
                if line == V2_DATA_LINE - 1 {
                    let layout = v2_header.layout(dims).map_err(pf)?;
                    if let Some(g) = &count
                        && g.v as usize != layout.particles
                    {
                        self.note(format!(
                            "{}: PARTICLES = {} is not used: the version 2.0 particle file gives its own count, {} (MFIX's rule)",
                            g.loc, g.v, layout.particles
                        ));
                    }
                    want = layout.particles;
                    v2 = Some(layout);
                }
                continue;
            }
            let Some(fields) = particles::mfix_fields(l) else { continue };
            if n_data == want {
                // MFIX reads the first PARTICLES lines of a longer file.
                longer = true;
                break;
            }
            n_data += 1;
            if first_error.is_some() {
                continue;
            }
            let numbers = match &v2 {
                Some(layout) => layout.numbers(&fields, phases).map(|(v, m)| {
                    phases_given.push(Some(m));
                    v
                }),
                None if dims == 2 => two_d_numbers(&fields),
                None if self.cgs => cgs_numbers(&fields),
                None => particles::mfix_numbers(&fields),
            };
            match numbers {
                Ok(v) => data.push((line, v)),
                Err(message) => first_error = Some(pf(message)),
            }
        }
        if v2_header.on && v2.is_none() {
            return Err(CaseError::ParticleFile {
                path: PARTICLE_FILE.into(),
                line: 1,
                message: format!(
                    "a version 2.0 file has a header of {} lines; this one ends before its data",
                    V2_DATA_LINE - 1
                ),
            });
        }
        // A version 2.0 file (phases given) or a 2-D one is listed in the case.
        let longer = longer || v2.is_some() || dims == 2;
        drop(stream);
        if n_data < want {
            let (loc, text) =
                count.as_ref().map_or((self.origin.to_string(), format!("{want} (MFIX's default)")), |g| {
                    (g.loc.to_string(), g.text.clone())
                });
            return Err(CaseError::invalid(
                loc,
                "PARTICLES",
                text,
                format!(
                    "{PARTICLE_FILE} lists only {n_data} particle{}, and MFIX reads PARTICLES of them: set PARTICLES = {n_data}",
                    if n_data == 1 { "" } else { "s" },
                ),
            ));
        }
        if longer {
            self.note(format!(
                "{PARTICLE_FILE} lists more than PARTICLES = {want} particles: the first {want} are read, as MFIX reads them"
            ));
        }
        if let Some(e) = first_error {
            return Err(e);
        }
        let mut raw = RawParticles {
            file: None,
            format: None,
            max_initial_overlap: None,
            // MFIX stops no run for overlap: the health check stops a deck's run only at an
            // overlap of the whole smaller radius.
            max_overlap: Some(DECK_MAX_OVERLAP),
            order: None,
            resort: None,
            list: Vec::new(),
        };
        let mut extra_source = String::new();
        let init = if self.cgs || longer {
            let mut init = Vec::new();
            for (k, (line, v)) in data.iter().enumerate() {
                let err = |message: String| CaseError::ParticleFile {
                    path: PARTICLE_FILE.into(),
                    line: *line,
                    message,
                };
                let [x, y, z, r, rho, u, vv, w] = *v;
                let (x, y, z, r, rho, vel) = if self.cgs {
                    (
                        x / 100.0,
                        y / 100.0,
                        z / 100.0,
                        r / 100.0,
                        Unit::Density.cgs_to_si(rho),
                        [u, vv, w].map(|c| Unit::Velocity.cgs_to_si(c)),
                    )
                } else {
                    (x, y, z, r, rho, [u, vv, w])
                };
                if !(r.is_finite() && r > 0.0) {
                    return Err(err(format!("radius {} cm must be positive", v[3])));
                }
                // MFIX compares in the deck's units: its SMALL_NUMBER is 1e-15 cm and g/cm³ in CGS.
                let exact = if self.cgs {
                    (particles::SMALL_NUMBER / 100.0, particles::SMALL_NUMBER * 1000.0)
                } else {
                    (particles::SMALL_NUMBER, particles::SMALL_NUMBER)
                };
                let given = phases_given.get(k).copied().flatten();
                let phase = given
                    .or_else(|| particles::match_phase_within(2.0 * r, rho, phases, exact))
                    .ok_or_else(|| {
                        let (lu, du, lf, df) =
                            if self.cgs { ("cm", "g/cm³", 100.0, 1e-3) } else { ("m", "kg/m³", 1.0, 1.0) };
                        err(format!(
                            "no phase has diameter {} {lu} and density {} {du} (the phases: {})",
                            2.0 * v[3],
                            v[4],
                            phases
                                .iter()
                                .map(|p| format!(
                                    "'{}' D_P0 = {} {lu}, RO_S0 = {} {du}",
                                    p.name,
                                    p.diameter * lf,
                                    p.density * df
                                ))
                                .collect::<Vec<_>>()
                                .join("; ")
                        ))
                    })?;
                let diameter = 2.0 * r;
                raw.list.push(RawParticle {
                    id: None,
                    phase: Some(phases[phase].name.clone()),
                    position: Some([x, y, z]),
                    velocity: Some(vel),
                    angular_velocity: None,
                    diameter: (diameter != phases[phase].diameter).then_some(diameter),
                });
                init.push((
                    Vec3::new(x, y, z),
                    if diameter != phases[phase].diameter { r } else { phases[phase].radius() },
                ));
            }
            extra_source = if self.cgs {
                let text = String::from_utf8_lossy(&kept.borrow()).into_owned();
                format!("\0file\0{PARTICLE_FILE}\0{text}")
            } else {
                let numbers: Vec<[f64; 8]> = data.iter().map(|(_, v)| *v).collect();
                format!("\0file\0{PARTICLE_FILE}\0{numbers:?}")
            };
            init
        } else {
            raw.file = Some(PARTICLE_FILE.into());
            data.iter().map(|(_, v)| (Vec3::new(v[0], v[1], v[2]), v[3])).collect()
        };
        // MFIX does not check initial overlaps; grainflow's cases refuse more than
        // DEFAULT_MAX_INITIAL_OVERLAP unless told. Say what this deck needs.
        let overlap = [largest_overlap(&init, lo, hi, faces), largest_mesh_overlap(&init, walls)]
            .into_iter()
            .flatten()
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((ratio, what)) = overlap
            && ratio > DEFAULT_MAX_INITIAL_OVERLAP
        {
            let limit = ((ratio * 100.0).ceil() + 1.0) / 100.0;
            if limit > DECK_MAX_OVERLAP {
                return Err(CaseError::Geometry(format!(
                    "{PARTICLE_FILE}: {what} overlap by {ratio:.3} of the smaller radius at the start; MFIX does not check this, but grainflow runs a deck's particles only up to an overlap of the whole radius: separate them"
                )));
            }
            raw.max_initial_overlap = Some(limit);
            self.note(format!(
                    "{PARTICLE_FILE}: {what} overlap by {ratio:.3} of the smaller radius at the start; MFIX does not check this, grainflow's own limit ({DEFAULT_MAX_INITIAL_OVERLAP}) is raised to {limit} for this deck ([particles] max_initial_overlap)"
                ));
        }
        Ok((raw, extra_source))
    }
}

/// The largest initial overlap, as a fraction of the smaller radius (pairs) or the radius
/// (the box faces that are walls, `faces`: a cyclic or open face is none), with who overlaps.
fn largest_overlap(p: &[(Vec3, f64)], lo: Vec3, hi: Vec3, faces: &[&str]) -> Option<(f64, String)> {
    let mut best: Option<(f64, String)> = None;
    let mut consider = |ratio: f64, what: &dyn Fn() -> String| {
        if ratio > best.as_ref().map_or(0.0, |b| b.0) {
            best = Some((ratio, what()));
        }
    };
    for w in Wall::domain_box(lo, hi, 0).iter().filter(|w| faces.contains(&w.name.as_str())) {
        for (i, (x, r)) in p.iter().enumerate() {
            let overlap = r - w.distance(*x);
            consider(overlap / r, &|| format!("particle {} and wall {}", i + 1, w.name));
        }
    }
    let cell = 2.0 * p.iter().map(|q| q.1).fold(0.0, f64::max);
    if cell > 0.0 {
        let key =
            |x: Vec3| ((x.x / cell).floor() as i64, (x.y / cell).floor() as i64, (x.z / cell).floor() as i64);
        let mut grid: HashMap<(i64, i64, i64), Vec<usize>> = HashMap::new();
        for (i, (x, _)) in p.iter().enumerate() {
            grid.entry(key(*x)).or_default().push(i);
        }
        for (i, (x, r)) in p.iter().enumerate() {
            let (a, b, c) = key(*x);
            for da in -1..=1 {
                for db in -1..=1 {
                    for dc in -1..=1 {
                        for &j in grid.get(&(a + da, b + db, c + dc)).map_or(&[][..], |v| v.as_slice()) {
                            if j <= i {
                                continue;
                            }
                            let (y, s) = p[j];
                            let overlap = r + s - (y - *x).length();
                            consider(overlap / r.min(s), &|| format!("particles {} and {}", i + 1, j + 1));
                        }
                    }
                }
            }
        }
    }
    best
}

/// The eight numbers of a CGS `particle_input.dat` line, as written (cm, g/cm³, cm/s).
fn cgs_numbers(fields: &[&str]) -> Result<[f64; 8], String> {
    if fields.len() != 8 {
        return Err(format!("expected 8 numbers (x y z radius density u v w, CGS), found {}", fields.len()));
    }
    let mut v = [0.0; 8];
    for (slot, f) in v.iter_mut().zip(fields) {
        *slot = lexer::fortran_number(f).ok_or_else(|| format!("'{f}' is not a number"))?;
    }
    Ok(v)
}

/// The numbers of a 2-D legacy line, `x y radius density u v`, as the 3-D eight with z = 0
/// and w = 0 (MFIX's 2-D particles lie in the plane z = 0).
fn two_d_numbers(fields: &[&str]) -> Result<[f64; 8], String> {
    if fields.len() != 6 {
        return Err(format!(
            "expected 6 numbers (x y radius density u v: NO_K = .TRUE. is 2-D), found {}",
            fields.len()
        ));
    }
    let mut v = [0.0; 6];
    for (slot, f) in v.iter_mut().zip(fields) {
        *slot = lexer::fortran_number(f).ok_or_else(|| format!("'{f}' is not a number"))?;
    }
    Ok([v[0], v[1], 0.0, v[2], v[3], v[4], v[5], 0.0])
}

/// The first data line of a version 2.0 `particle_input.dat` (MFIX's fixed header).
const V2_DATA_LINE: usize = 35;

/// A column of a version 2.0 file: read from the file (its 0-based start) or one value for
/// every particle.
#[derive(Debug, Clone)]
enum V2Col {
    Read(usize),
    Uniform(Vec<f64>),
}

/// The header of a version 2.0 file as it is read.
#[derive(Debug, Default)]
struct V2Header {
    on: bool,
    particles: Option<usize>,
    /// (label, read, defaults) of lines 24–31.
    options: Vec<(String, bool, Vec<f64>)>,
}

/// The labels of lines 24–31, in MFIX's order.
const V2_OPTIONS: [&str; 8] =
    ["Coordinates", "Phase_ID", "Diameter", "Density", "Velocity", "Temperature", "Species", "User_Scalar"];

impl V2Header {
    fn read(&mut self, line: usize, text: &str, dims: usize) -> Result<(), String> {
        let fields: Vec<&str> =
            text.split(|c: char| c.is_whitespace() || c == ',').filter(|f| !f.is_empty()).collect();
        let label = |want: &str| -> Result<(), String> {
            match fields.first() {
                Some(f) if f.trim_end_matches(':').eq_ignore_ascii_case(want) => Ok(()),
                _ => Err(format!(
                    "'{}': line {line} of a version 2.0 file is its '{want}:' line (MFIX reads the header by line number)",
                    text.trim()
                )),
            }
        };
        match line {
            19 => {
                label("Dimension")?;
                let d: usize =
                    fields.get(1).and_then(|f| f.parse().ok()).ok_or("the dimension must be 2 or 3")?;
                if d != dims {
                    return Err(format!("the file is {d}-D and the deck {dims}-D (NO_K)"));
                }
            }
            20 => {
                label("Particles")?;
                let n: usize = fields
                    .get(1)
                    .and_then(|f| f.parse().ok())
                    .filter(|&n| n <= 100_000_000)
                    .ok_or("the number of particles must be a whole number (at most 10⁸)")?;
                self.particles = Some(n);
            }
            24..=31 => {
                let want = V2_OPTIONS[line - 24];
                label(want)?;
                let read = match fields.get(1).map(|f| f.to_ascii_uppercase()) {
                    Some(f) if f == "T" => true,
                    Some(f) if f == "F" => false,
                    _ => return Err(format!("'{}': the {want} option must be T or F", text.trim())),
                };
                let defaults: Vec<f64> = fields[2..].iter().map_while(|f| lexer::fortran_number(f)).collect();
                self.options.push((want.to_string(), read, defaults));
            }
            _ => {}
        }
        Ok(())
    }

    /// The columns, from the options read. Temperature, species and user scalars follow the
    /// columns grainflow reads, so their widths do not move them.
    fn layout(&self, dims: usize) -> Result<V2Layout, String> {
        let particles = self.particles.ok_or("the header has no 'Particles:' line")?;
        if self.options.len() != V2_OPTIONS.len() {
            return Err("the header's variable lines (24–31) are incomplete".into());
        }
        let mut next = 0usize;
        let mut col = |k: usize, width: usize| -> Result<V2Col, String> {
            let (label, read, defaults) = &self.options[k];
            if *read {
                let c = V2Col::Read(next);
                next += width;
                Ok(c)
            } else if defaults.len() >= width {
                Ok(V2Col::Uniform(defaults[..width].to_vec()))
            } else {
                Err(format!("{label}: F needs its default value{}", if width > 1 { "s" } else { "" }))
            }
        };
        let xyz = match col(0, dims)? {
            V2Col::Read(c) => c,
            V2Col::Uniform(_) => return Err("Coordinates must be read (T)".into()),
        };
        let phase = col(1, 1)?;
        let diameter = col(2, 1)?;
        let density = col(3, 1)?;
        let velocity = col(4, dims)?;
        Ok(V2Layout { particles, dims, xyz, phase, diameter, density, velocity, min_columns: next })
    }
}

/// How a version 2.0 data line gives a particle.
#[derive(Debug, Clone)]
struct V2Layout {
    particles: usize,
    dims: usize,
    xyz: usize,
    phase: V2Col,
    diameter: V2Col,
    density: V2Col,
    velocity: V2Col,
    /// The columns grainflow reads; the line may have more (temperature, species, …).
    min_columns: usize,
}

impl V2Layout {
    /// The eight legacy numbers (x y z radius density u v w, in the deck's units) and the
    /// phase index.
    fn numbers(&self, fields: &[&str], phases: &[Phase]) -> Result<([f64; 8], usize), String> {
        if fields.len() < self.min_columns {
            return Err(format!(
                "expected at least {} numbers (the header's T columns), found {}",
                self.min_columns,
                fields.len()
            ));
        }
        let num = |c: usize| -> Result<f64, String> {
            lexer::fortran_number(fields[c])
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{}' is not a number", fields[c]))
        };
        let one = |c: &V2Col| -> Result<f64, String> {
            match c {
                V2Col::Read(k) => num(*k),
                V2Col::Uniform(v) => Ok(v[0]),
            }
        };
        let d = self.dims;
        let mut x = [0.0; 3];
        for (k, slot) in x.iter_mut().enumerate().take(d) {
            *slot = num(self.xyz + k)?;
        }
        let mut v = [0.0; 3];
        for (k, slot) in v.iter_mut().enumerate().take(d) {
            *slot = match &self.velocity {
                V2Col::Read(c) => num(c + k)?,
                V2Col::Uniform(u) => u[k],
            };
        }
        let m = one(&self.phase)?;
        if !(m >= 1.0 && m.fract() == 0.0 && (m as usize) <= phases.len()) {
            return Err(format!("phase {m} is not a solids phase of the deck (1 to {})", phases.len()));
        }
        let diameter = one(&self.diameter)?;
        if diameter.is_nan() || diameter <= 0.0 {
            return Err(format!("diameter {diameter} must be positive"));
        }
        let density = one(&self.density)?;
        Ok(([x[0], x[1], x[2], diameter / 2.0, density, v[0], v[1], v[2]], m as usize - 1))
    }
}

/// The largest overlap of a particle with an STL wall, as a fraction of its radius, and which.
fn largest_mesh_overlap(p: &[(Vec3, f64)], walls: &[grainflow::mesh::Mesh]) -> Option<(f64, String)> {
    let mut best: Option<(f64, String)> = None;
    for (i, &(x, r)) in p.iter().enumerate() {
        for mesh in walls {
            for t in 0..mesh.triangle_count() as u32 {
                let c = mesh.corners(t);
                let lo = c[0].min(c[1]).min(c[2]) - Vec3::splat(r);
                let hi = c[0].max(c[1]).max(c[2]) + Vec3::splat(r);
                if x.cmplt(lo).any() || x.cmpgt(hi).any() {
                    continue;
                }
                let d = (x - grainflow::mesh::closest_point_on_triangle(x, c).point).length();
                let ratio = (r - d) / r;
                if ratio > 0.0 && best.as_ref().is_none_or(|b| ratio > b.0) {
                    best = Some((ratio, format!("particle {} and the STL wall {}", i + 1, mesh.name())));
                }
            }
        }
    }
    best
}
