//! MFIX input decks: `mfix.dat` and the GUI's `.mfx`, translated into grainflow's case.
//!
//! # The format
//! MFIX describes a run in a keyword file in Fortran namelist style (see [`lexer`]):
//! `KEY = value` lines, `KEY(i) = value` array elements (`KEY(i,j)` for two subscripts,
//! `KEY(i:j)` ranges), several values per keyword (`DES_EN_INPUT = 0.9 0.8 0.9`, filling
//! elements from the first subscript on), `n*value` repeats, `.T.`/`.F.` logicals, quoted
//! strings, Fortran exponents (`1.0d-3`), `@( … )` arithmetic and `!`/`#` comments. The GUI's
//! `#!MFIX-GUI key = value` comments carry its project data; grainflow reads the solids phase
//! names from them (`solids_phase_name(m)`). `@(RXNS) … @(END)` blocks hold chemistry;
//! a `THERMO DATA` section ends the keywords. Particles come from `particle_input.dat`
//! (MFIX's legacy format, one particle per line: `x y z radius density u v w`) beside the deck.
//! `KEY=VALUE` arguments override the deck, as on MFIX's command line.
//!
//! # The translation
//! A deck becomes the same [`RawCase`] a TOML case file gives, and is validated by the same
//! code ([`crate::case::from_raw`]): one `Case`, whatever the input. `grainflow convert` writes
//! that `RawCase` as TOML. The mapping, keyword by keyword, is in docs/mfix-decks.md and in
//! [`keywords::KEYWORDS`], which also holds MFIX's defaults:
//! - run control: `TSTOP` → `[time] t_stop`, `TIME` → `t_start`, `RUN_NAME`/`DESCRIPTION` →
//!   `title`; `DT` is checked but does not set the step (a pure granular MFIX run replaces it
//!   by DTSOLID); `DTSOLID_FACTOR` → `dtsolid_factor`; `DES_INTG_METHOD` → `integrator`;
//! - geometry: `X_MIN`/`X_MAX`/`XLENGTH` (and y, z) → `[domain]`, whose six faces are the walls
//!   (MFIX's default DEM walls);
//! - `GRAVITY`, `GRAVITY_X/Y/Z` → `[physics] gravity`, with MFIX's rule (all components zero
//!   means `GRAVITY` along −y);
//! - solids phases 1..`MMAX` (`SOLIDS_MODEL(m) = 'DEM'`, `D_P0`, `RO_S0`, `E_YOUNG`,
//!   `V_POISSON`) → `[[phases]]`; particles are matched to phases by diameter and density;
//! - collisions: `KN`, `KT_FAC`, `DES_ETAT_FAC`, `MEW`, `MEW_R` → `[contact.particle]`; the wall
//!   keywords → `[contact.wall]` (and `EW_YOUNG`, `VW_POISSON` → a wall material); the
//!   restitution arrays (`DES_EN_INPUT` in MFIX's upper-triangle order 1-1, 1-2, …, 2-2, …;
//!   `DES_EN_WALL_INPUT` per phase) → the defaults tables when all equal, else
//!   `[[contact.pairs]]`/`[[contact.walls]]`;
//! - `FACTOR_RLM` → the Verlet skin (FACTOR_RLM − 1) × the largest `D_P0`;
//! - particle VTK output (`WRITE_VTK_FILES`, `VTK_DT(i)` with `VTK_DATA(i) = 'P'`) → `[output]`.
//!
//! `UNITS = 'CGS'` decks are converted to SI keyword by keyword (cm → m, g/cm³ → kg/m³,
//! dyne/cm → N/m, barye → Pa, cm/s² → m/s², cm/s → m/s) and so is their particle file; their
//! particles are then listed inline in the case.
//!
//! # What is not translated
//! Every keyword has a role ([`keywords::Role`]): used; ignored because it cannot change a
//! pure-DEM result (the gas phase once `RO_G0 = 0`, the fluid solver and grid, energy and
//! species, output) — reported once per group; or refused with the reason, because it would
//! change the result and grainflow cannot do it (gas coupling, periodic or 2-D domains,
//! particle generation, cohesion, user Fortran code without a `--motion` replacement, …).
//! Unknown keywords are reported with their line and ignored.
//!
//! User-defined functions (`CALL_USR = .TRUE.`) are Fortran code. When they only prescribe
//! particle motion (MFIX's DEM05 holds its anvil spheres that way) the same rules can be given
//! as `[[motion]]` tables in a small TOML file passed beside the deck (`--motion FILE`).

pub mod deck;
pub mod keywords;
pub mod lexer;

use crate::case::{Case, DEFAULT_MAX_INITIAL_OVERLAP};
use crate::error::CaseError;
use crate::input;
use crate::particles;
use crate::raw::*;
use deck::{Deck, Got, show};
use grainflow::contact::limits::{self, Range};
use grainflow::{Phase, Vec3, Wall};
use keywords::{Allow, Dflt, Role, Unit, Why};
use lexer::Loc;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// The particle file MFIX reads, beside the deck.
pub const PARTICLE_FILE: &str = "particle_input.dat";

/// Standard gravity in SI, MFIX's default for `UNITS = 'SI'` (980.665 cm/s² in CGS).
const MFIX_GRAVITY: f64 = 9.80665;

/// A deck translated and validated.
#[derive(Debug, Clone)]
pub struct DeckCase {
    /// The validated case, as from a TOML case file. Its warnings start with the deck's notes.
    pub case: Case,
    /// The translated case before validation: `grainflow convert` writes it as TOML.
    pub raw: RawCase,
    /// What the translation reports: ignored and unknown keywords, MFIX rules applied.
    pub notes: Vec<String>,
}

/// True for the files `grainflow run` reads as MFIX decks: `*.dat`, `*.mfx`, `mfix.dat`.
pub fn is_deck(path: &Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    name.ends_with(".dat") || name.ends_with(".mfx")
}

/// Reads, translates and validates a deck; `particle_input.dat` is read beside it. `overrides`
/// are `KEY=VALUE` strings applied after the deck; `motion` is a TOML file of `[[motion]]`
/// tables replacing user-defined functions that prescribe particle motion.
///
/// Every file is read through [`crate::input`]: regular files only, within its size limits,
/// the particle file streamed.
pub fn load(path: &Path, overrides: &[String], motion: Option<&Path>) -> Result<DeckCase, CaseError> {
    let text = input::read_text(path, input::Kind::Deck)?;
    let motion_text = motion
        .map(|m| input::read_text(m, input::Kind::Motion).map(|t| (t, m.display().to_string())))
        .transpose()?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_opened(
        &text,
        &path.display().to_string(),
        overrides,
        motion_text.as_ref().map(|(t, o)| (t.as_str(), o.as_str())),
        &input::open_beside(&dir),
    )
}

/// Translates and validates deck text. `origin` names the deck in messages; `motion` is the
/// text and name of a `[[motion]]` TOML file; `read_file` reads `particle_input.dat`.
pub fn parse(
    text: &str,
    origin: &str,
    overrides: &[String],
    motion: Option<(&str, &str)>,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
) -> Result<DeckCase, CaseError> {
    parse_opened(text, origin, overrides, motion, &input::open_text(read_file))
}

/// [`parse`] with the particle file opened as a stream.
fn parse_opened(
    text: &str,
    origin: &str,
    overrides: &[String],
    motion: Option<(&str, &str)>,
    read_file: &input::Opener<'_>,
) -> Result<DeckCase, CaseError> {
    let mut lexed = lexer::lex_deck(text, origin)?;
    let mut deck = Deck::default();
    for a in std::mem::take(&mut lexed.assignments) {
        deck.assign(a)?;
    }
    for o in overrides {
        deck.assign(lexer::lex_override(o)?)?;
    }
    deck.check_types()?;
    let rules = motion.map(|(t, o)| parse_motion(input::strip_bom(t), o)).transpose()?;
    let mut tr = Translator { deck: &deck, lexed: &lexed, origin, cgs: false, notes: Vec::new() };
    let (raw, extra_source) = tr.translate(rules, read_file)?;
    let notes = tr.notes;
    // The case hash covers the deck, the overrides, the motion file and every file read.
    let mut source = text.to_string();
    for o in overrides {
        source.push_str("\0override\0");
        source.push_str(o);
    }
    if let Some((t, _)) = motion {
        source.push_str("\0motion\0");
        source.push_str(t);
    }
    source.push_str(&extra_source);
    let mut case =
        crate::case::from_raw_opened(raw.clone(), &source, read_file).map_err(|e| explain(e, origin))?;
    let mut warnings = notes.clone();
    warnings.append(&mut case.warnings);
    case.warnings = warnings;
    Ok(DeckCase { case, raw, notes })
}

/// The `[[motion]]` file given with `--motion`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MotionFile {
    #[serde(default)]
    motion: Vec<RawMotion>,
}

fn parse_motion(text: &str, origin: &str) -> Result<Vec<RawMotion>, CaseError> {
    let m: MotionFile = toml::from_str(text).map_err(|e| {
        CaseError::Syntax(format!(
            "{origin}: {e}\n(a motion file holds only [[motion]] tables, as in a case file)"
        ))
    })?;
    if m.motion.is_empty() {
        return Err(CaseError::missing(origin, "[[motion]]", "at least one prescribed-motion rule"));
    }
    Ok(m.motion)
}

/// Validation errors name grainflow's tables and keys; say that they come from the translated
/// deck (the pre-checks of the translation catch the errors that have a deck line).
fn explain(e: CaseError, origin: &str) -> CaseError {
    match e {
        CaseError::Missing { .. }
        | CaseError::Invalid { .. }
        | CaseError::Engine(_)
        | CaseError::Syntax(_) => CaseError::Syntax(format!(
            "{origin}: in the case translated from this deck (see `grainflow convert {origin}`): {e}"
        )),
        CaseError::Geometry(m) => CaseError::Geometry(format!("{origin}: {m}")),
        other => other,
    }
}

/// Serialises a translated case as a TOML case file, with a header naming the deck and the
/// translation's notes as comments.
pub fn to_toml(raw: &RawCase, origin: &str, notes: &[String]) -> Result<String, CaseError> {
    let body =
        toml::to_string(raw).map_err(|e| CaseError::Syntax(format!("{origin}: cannot write TOML: {e}")))?;
    let mut s = format!(
        "# grainflow case translated from the MFIX deck {origin} by grainflow {}.\n# Keys, units and defaults: docs/case-file.md; the translation: docs/mfix-decks.md.\n",
        env!("CARGO_PKG_VERSION")
    );
    if raw.particles.as_ref().is_some_and(|p| p.file.is_some()) {
        s.push_str("# The particle file is named relative to this file: keep it beside the deck.\n");
    }
    for n in notes {
        for (k, line) in n.lines().enumerate() {
            s.push_str(if k == 0 { "# note: " } else { "#   " });
            s.push_str(line);
            s.push('\n');
        }
    }
    s.push('\n');
    s.push_str(&body);
    Ok(s)
}

/// True when a table serialises to nothing (used by the `raw` structures to keep converted
/// case files free of empty tables).
pub fn is_empty_table<T: Serialize>(t: &T) -> bool {
    matches!(toml::Value::try_from(t), Ok(toml::Value::Table(m)) if m.is_empty())
}

/// One deck being translated.
struct Translator<'a> {
    deck: &'a Deck,
    lexed: &'a lexer::Lexed,
    origin: &'a str,
    cgs: bool,
    notes: Vec<String>,
}

/// A validated number in SI with its source.
struct Num {
    v: f64,
}

impl Translator<'_> {
    fn note(&mut self, s: impl Into<String>) {
        self.notes.push(s.into());
    }

    fn unit_name(&self, unit: Unit) -> &'static str {
        if self.cgs { unit.cgs() } else { unit.si() }
    }

    /// A real keyword element converted to SI.
    fn real(&self, key: &str, idx: &[i64]) -> Result<Option<Got<f64>>, CaseError> {
        let unit = keywords::lookup(key).map_or(Unit::None, |k| k.unit);
        Ok(self.deck.real(key, idx)?.map(|mut g| {
            if self.cgs {
                g.v = unit.cgs_to_si(g.v);
            }
            g
        }))
    }

    /// A real keyword element in SI, checked against `range` (stated in SI).
    fn ranged(&self, key: &str, idx: &[i64], range: Range, what: &str) -> Result<Option<Num>, CaseError> {
        let Some(g) = self.real(key, idx)? else { return Ok(None) };
        if range.contains(g.v) {
            Ok(Some(Num { v: g.v }))
        } else {
            let unit = keywords::lookup(key).map_or(Unit::None, |k| k.unit);
            let shown = if self.cgs && unit != Unit::None {
                format!("{} {} (= {:e} {} in SI)", g.text, unit.cgs(), g.v, unit.si())
            } else {
                g.text.clone()
            };
            Err(CaseError::invalid(g.loc.to_string(), g.key, shown, format!("{what} {}", range.valid)))
        }
    }

    fn required(
        &self,
        key: &str,
        idx: &[i64],
        range: Range,
        what: &str,
        hint: String,
    ) -> Result<f64, CaseError> {
        self.ranged(key, idx, range, what)?
            .map(|n| n.v)
            .ok_or_else(|| CaseError::missing(self.origin, show(key, idx), hint))
    }

    fn with_default(&self, key: &str, idx: &[i64], range: Range, what: &str) -> Result<f64, CaseError> {
        match self.ranged(key, idx, range, what)? {
            Some(n) => Ok(n.v),
            None => match keywords::lookup(key).map(|k| k.default) {
                Some(Dflt::Real(v)) => Ok(v),
                _ => Ok(0.0),
            },
        }
    }

    fn word(&self, key: &str, idx: &[i64]) -> Result<Option<Got<String>>, CaseError> {
        self.deck.string(key, idx, true)
    }

    fn flag(&self, key: &str) -> Result<bool, CaseError> {
        let default = matches!(keywords::lookup(key).map(|k| k.default), Some(Dflt::Bool(true)));
        Ok(self.deck.bool(key, &[])?.map_or(default, |g| g.v))
    }

    fn invalid_word(g: &Got<String>, valid: impl Into<String>) -> CaseError {
        CaseError::invalid(g.loc.to_string(), g.key.clone(), format!("'{}'", g.v), valid)
    }

    fn translate(
        &mut self,
        motion: Option<Vec<RawMotion>>,
        read_file: &input::Opener<'_>,
    ) -> Result<(RawCase, String), CaseError> {
        let d = self.deck;
        // Units first: every dimensional value depends on them.
        let units = self.word("UNITS", &[])?.ok_or_else(|| {
            CaseError::missing(
                self.origin,
                "UNITS",
                "the units of the deck: UNITS = 'SI' or UNITS = 'CGS' (MFIX requires it)",
            )
        })?;
        self.cgs = match units.v.as_str() {
            "SI" => false,
            "CGS" => true,
            _ => return Err(Self::invalid_word(&units, "must be 'SI' or 'CGS'")),
        };

        self.refusals(motion.is_some())?;
        let mmax = self.phases_count()?;
        let (lo, hi) = self.domain()?;
        self.boundary_conditions(lo, hi)?;
        let gravity = self.gravity()?;
        let mut phases = self.phases(mmax)?;
        let contact = self.contact(&mut phases)?;
        let time = self.time()?;
        let dmax = phases.iter().map(|p| p.diameter).fold(0.0, f64::max);
        let rlm = self.with_default(
            "FACTOR_RLM",
            &[],
            Range { lo: 1.0, lo_open: false, hi: f64::MAX, hi_open: false, valid: "must be at least 1" },
            "the neighbour-list factor (multiple of the sum of the radii)",
        )?;
        let neighbor = RawNeighbor { skin: Some((rlm - 1.0) * dmax) };
        let output = self.output()?;
        let (particles, extra_source) = self.particles(&phases, lo, hi, read_file)?;
        let motion = motion.unwrap_or_default();

        let title = match (d.string("RUN_NAME", &[], false)?, d.string("DESCRIPTION", &[], false)?) {
            (Some(n), Some(t)) => format!("{}: {}", n.v, t.v),
            (Some(n), None) => n.v,
            (None, Some(t)) => t.v,
            (None, None) => String::new(),
        };
        self.report_keywords();

        let wall_materials = if contact.1 {
            let ew = self.required(
                "EW_YOUNG",
                &[],
                limits::YOUNGS,
                "Young's modulus of the walls",
                format!(
                    "Young's modulus of the walls ({}), required by DES_COLL_MODEL = 'HERTZIAN'",
                    self.unit_name(Unit::Modulus)
                ),
            )?;
            let vw = self.required(
                "VW_POISSON",
                &[],
                limits::POISSON,
                "Poisson's ratio of the walls",
                "Poisson's ratio of the walls, required by DES_COLL_MODEL = 'HERTZIAN'".into(),
            )?;
            vec![RawWallMaterial {
                name: Some("wall".into()),
                youngs_modulus: Some(ew),
                poisson_ratio: Some(vw),
            }]
        } else {
            Vec::new()
        };
        let raw = RawCase {
            version: Some(crate::case::CASE_VERSION),
            title,
            domain: Some(RawDomain {
                min: Some(lo.to_array()),
                max: Some(hi.to_array()),
                walls: WallSelection::All(true),
                periodic: None,
                wall_material: None,
                leaving: None,
            }),
            physics: RawPhysics { gravity: Some(gravity) },
            phases: phases
                .iter()
                .map(|p| RawPhase {
                    name: Some(p.name.clone()),
                    diameter: Some(p.diameter),
                    density: Some(p.density),
                    youngs_modulus: p.youngs_modulus,
                    poisson_ratio: p.poisson_ratio,
                })
                .collect(),
            wall_materials,
            walls: Vec::new(),
            meshes: Vec::new(),
            contact: Some(contact.0),
            time: Some(time),
            neighbor,
            output,
            particles: Some(particles),
            motion,
            insertions: Vec::new(),
            outlets: Vec::new(),
        };
        Ok((raw, extra_source))
    }

    /// Keywords that would change the result in a way grainflow cannot reproduce.
    fn refusals(&mut self, have_motion: bool) -> Result<(), CaseError> {
        let d = self.deck;
        for key in &d.order {
            let g = &d.given[key];
            let Some(spec) = g.spec else { continue };
            let Role::Refused(allow, why) = spec.role else { continue };
            for (idx, e) in &g.entries {
                let ok = match allow {
                    Allow::False => d.bool(key, idx)?.is_none_or(|b| !b.v),
                    Allow::Zero => d.real(key, idx)?.is_none_or(|r| r.v == 0.0),
                    Allow::Never => false,
                };
                if !ok {
                    let written = e.value.as_ref().map_or(String::new(), |v| v.written());
                    let only = match allow {
                        Allow::False => " (only .FALSE., MFIX's default, can be run)",
                        Allow::Zero => " (only 0, MFIX's default, can be run)",
                        Allow::Never => "",
                    };
                    return Err(CaseError::invalid(
                        e.loc.to_string(),
                        show(key, idx),
                        written,
                        format!("grainflow cannot run this: {why}{only}"),
                    ));
                }
            }
        }
        if let Some(loc) = &self.lexed.reactions {
            return Err(CaseError::invalid(
                loc.to_string(),
                "@(RXNS)",
                "(a chemical reaction block)",
                "grainflow cannot run this: chemical reactions change particle mass and size and grainflow has no chemistry; remove the block",
            ));
        }
        if let Some(loc) = &self.lexed.thermo_data {
            self.note(format!("{loc}: the THERMO DATA section (thermochemical data) is ignored: it does not act on the particle motion"));
        }
        match self.word("RUN_TYPE", &[])? {
            Some(g) if g.v == "NEW" => {}
            Some(g) if g.v == "RESTART_1" || g.v == "RESTART_2" => {
                return Err(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: MFIX restart files cannot be read; use RUN_TYPE = 'NEW' (grainflow restarts from its own checkpoints: grainflow run --restart)",
                ));
            }
            Some(g) => {
                return Err(Self::invalid_word(
                    &g,
                    "must be 'NEW' (or MFIX's 'RESTART_1', 'RESTART_2', which grainflow cannot read)",
                ));
            }
            None => {}
        }
        match self.word("COORDINATES", &[])? {
            Some(g) if g.v == "CARTESIAN" => {}
            Some(g) if g.v == "CYLINDRICAL" => {
                return Err(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: only COORDINATES = 'CARTESIAN' is supported",
                ));
            }
            Some(g) => {
                return Err(Self::invalid_word(
                    &g,
                    "must be 'CARTESIAN' (or 'CYLINDRICAL', which grainflow cannot run)",
                ));
            }
            None => {}
        }
        match self.real("RO_G0", &[])? {
            Some(g) if g.v == 0.0 => {}
            Some(g) => {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "grainflow cannot run this: a gas density couples gas and particles (drag, buoyancy) and grainflow has no gas phase; a pure granular run has RO_G0 = 0.0",
                ));
            }
            None => {
                return Err(CaseError::missing(
                    self.origin,
                    "RO_G0",
                    "a pure granular (DEM-only) run needs RO_G0 = 0.0; without it MFIX computes a gas density from the ideal-gas law and couples gas and particles, which grainflow cannot",
                ));
            }
        }
        if let Some(g) = d.bool("CALL_USR", &[])? {
            if g.v && !have_motion {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "grainflow cannot run user-defined Fortran functions (usr0.f, usr1_des.f, …), which can change any result; if they only hold or move particles (as MFIX's DEM05 does), give the same rules as [[motion]] tables in a TOML file: grainflow run DECK --motion FILE (docs/mfix-decks.md); if they only write output, set CALL_USR = .FALSE.",
                ));
            }
            if g.v {
                self.note(format!(
                    "{}: CALL_USR = .TRUE.: the deck's user-defined functions are replaced by the [[motion]] rules of the --motion file",
                    g.loc
                ));
            }
        }
        Ok(())
    }

    fn phases_count(&self) -> Result<usize, CaseError> {
        let d = self.deck;
        let mmax = match d.int("MMAX", &[])? {
            Some(g) if (1..=10).contains(&g.v) => g.v as usize,
            Some(g) => {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "must be a number of solids phases from 1 to 10 (MFIX's DIM_M); a DEM run needs at least one phase",
                ));
            }
            None => default_int("MMAX") as usize,
        };
        for m in 1..=mmax as i64 {
            match self.word("SOLIDS_MODEL", &[m])? {
                Some(g) if g.v == "DEM" => {}
                Some(g) => {
                    return Err(Self::invalid_word(
                        &g,
                        format!(
                            "grainflow cannot run this: it runs discrete particles only; every solids phase must be SOLIDS_MODEL({m}) = 'DEM' ('TFM' continuum, 'PIC' parcels and 'CGP' coarse grains are not supported)"
                        ),
                    ));
                }
                None => {
                    return Err(CaseError::missing(
                        self.origin,
                        show("SOLIDS_MODEL", &[m]),
                        format!(
                            "MFIX's default is 'TFM' (continuum solids), which grainflow cannot run: set SOLIDS_MODEL({m}) = 'DEM'"
                        ),
                    ));
                }
            }
        }
        Ok(mmax)
    }

    /// The box from X_MIN/X_MAX/XLENGTH (and y, z), by MFIX's rules.
    fn domain(&self) -> Result<(Vec3, Vec3), CaseError> {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for (a, ax) in ["X", "Y", "Z"].iter().enumerate() {
            let (kmin, kmax, klen) = (format!("{ax}_MIN"), format!("{ax}_MAX"), format!("{ax}LENGTH"));
            let (vmin, vmax, vlen) = (self.real(&kmin, &[])?, self.real(&kmax, &[])?, self.real(&klen, &[])?);
            for g in [&vmin, &vmax, &vlen].into_iter().flatten() {
                if !g.v.is_finite() {
                    return Err(CaseError::invalid(
                        g.loc.to_string(),
                        g.key.clone(),
                        g.text.clone(),
                        "must be a finite length",
                    ));
                }
            }
            if let Some(l) = &vlen
                && l.v <= 0.0
            {
                return Err(CaseError::invalid(
                    l.loc.to_string(),
                    l.key.clone(),
                    l.text.clone(),
                    "the domain length must be positive",
                ));
            }
            let (x0, x1) = match (&vmin, &vmax, &vlen) {
                (Some(a), Some(b), Some(l)) => {
                    if ((b.v - a.v) - l.v).abs() > 1e-9 * l.v.abs() {
                        return Err(CaseError::invalid(
                            l.loc.to_string(),
                            l.key.clone(),
                            l.text.clone(),
                            format!(
                                "{klen} must equal {kmax} − {kmin} = {} − {} (or give only two of the three)",
                                b.text, a.text
                            ),
                        ));
                    }
                    (a.v, b.v)
                }
                (Some(a), Some(b), None) => (a.v, b.v),
                (Some(a), None, Some(l)) => (a.v, a.v + l.v),
                (None, Some(b), Some(l)) => (b.v - l.v, b.v),
                (None, None, Some(l)) => (0.0, l.v),
                (None, Some(b), None) => (0.0, b.v),
                (_, None, None) => {
                    return Err(CaseError::missing(
                        self.origin,
                        klen.clone(),
                        format!(
                            "the domain length in {ax} ({}): give {klen}, or {kmin} and {kmax}",
                            self.unit_name(Unit::Length)
                        ),
                    ));
                }
            };
            if x1 <= x0 {
                let g = vmax.as_ref().or(vmin.as_ref()).or(vlen.as_ref());
                let (loc, key, text) = g
                    .map_or((self.origin.to_string(), kmax.clone(), x1.to_string()), |g| {
                        (g.loc.to_string(), g.key.clone(), g.text.clone())
                    });
                return Err(CaseError::invalid(
                    loc,
                    key,
                    text,
                    format!("{kmax} must exceed {kmin} (the box is empty)"),
                ));
            }
            lo[a] = x0;
            hi[a] = x1;
        }
        Ok((Vec3::from_array(lo), Vec3::from_array(hi)))
    }

    /// Wall boundary conditions on the faces of the box are what MFIX's DEM does anyway; flow
    /// boundaries, walls inside the box and moving walls are refused.
    fn boundary_conditions(&mut self, lo: Vec3, hi: Vec3) -> Result<(), CaseError> {
        let d = self.deck;
        let mut bcs: Vec<i64> = Vec::new();
        for key in ["BC_TYPE", "BC_X_W", "BC_X_E", "BC_Y_S", "BC_Y_N", "BC_Z_B", "BC_Z_T"] {
            bcs.extend(d.indices(key).into_iter().filter_map(|i| i.first().copied()));
        }
        bcs.sort_unstable();
        bcs.dedup();
        let imax = [d.int("IMAX", &[])?, d.int("JMAX", &[])?, d.int("KMAX", &[])?].map(|g| g.map(|g| g.v));
        let mut accepted = Vec::new();
        for i in bcs {
            let Some(t) = self.word("BC_TYPE", &[i])? else { continue };
            let wall = matches!(
                t.v.as_str(),
                "NSW"
                    | "FSW"
                    | "PSW"
                    | "NO_SLIP_WALL"
                    | "FREE_SLIP_WALL"
                    | "PAR_SLIP_WALL"
                    | "CG_NSW"
                    | "CG_FSW"
                    | "CG_PSW"
            );
            if !wall {
                return Err(Self::invalid_word(
                    &t,
                    "grainflow cannot run this: only wall boundary conditions ('NSW', 'FSW', 'PSW') are accepted; flow boundaries (inflow, outflow, pressure) open the box, and grainflow's box is closed",
                ));
            }
            for key in ["BC_UW_S", "BC_VW_S", "BC_WW_S"] {
                for idx in d.indices(key).into_iter().filter(|x| x.first() == Some(&i)) {
                    if let Some(g) = d.real(key, &idx)?
                        && g.v != 0.0
                    {
                        return Err(CaseError::invalid(
                            g.loc.to_string(),
                            g.key,
                            g.text,
                            "grainflow cannot run this: moving walls are not supported; only 0 is accepted",
                        ));
                    }
                }
            }
            // On a face: for some axis both ends lie on the same face of the box.
            let axes = [
                ("BC_X_W", "BC_X_E", "BC_I_W", "BC_I_E"),
                ("BC_Y_S", "BC_Y_N", "BC_J_S", "BC_J_N"),
                ("BC_Z_B", "BC_Z_T", "BC_K_B", "BC_K_T"),
            ];
            let mut on_face = false;
            for (a, (kw, ke, iw, ie)) in axes.iter().enumerate() {
                let size = hi[a] - lo[a];
                let near = |x: f64, face: f64| (x - face).abs() <= 1e-9 * size;
                if let (Some(w), Some(e)) = (self.real(kw, &[i])?, self.real(ke, &[i])?) {
                    on_face |=
                        (near(w.v, lo[a]) && near(e.v, lo[a])) || (near(w.v, hi[a]) && near(e.v, hi[a]));
                }
                if let (Some(w), Some(e)) = (d.int(iw, &[i])?, d.int(ie, &[i])?) {
                    let ghost_hi = imax[a].map(|n| n + 2);
                    on_face |= (w.v == 1 && e.v == 1) || (Some(w.v) == ghost_hi && Some(e.v) == ghost_hi);
                }
            }
            if !on_face {
                return Err(Self::invalid_word(
                    &t,
                    format!(
                        "grainflow cannot run this: wall region {i} does not lie on a face of the box (e.g. BC_X_W({i}) = BC_X_E({i}) = X_MIN); a wall inside the box is an obstacle, which decks cannot express: use [[walls]] planes in a TOML case"
                    ),
                ));
            }
            accepted.push(format!("{}({i}) = '{}' ({})", "BC_TYPE", t.v, t.loc));
        }
        if !accepted.is_empty() {
            self.note(format!(
                "{}: wall boundary conditions on faces of the box, which are DEM walls anyway (their gas-side settings are ignored): {}",
                self.origin,
                accepted.join(", ")
            ));
        }
        Ok(())
    }

    /// MFIX's rule: components default to 0; all three 0 means GRAVITY along −y.
    fn gravity(&mut self) -> Result<[f64; 3], CaseError> {
        let finite = Range {
            lo: f64::MIN,
            lo_open: false,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a finite number",
        };
        let g = self
            .ranged("GRAVITY", &[], finite, "the gravitational acceleration")?
            .map_or(MFIX_GRAVITY, |n| n.v);
        let mut c = [0.0; 3];
        for (k, key) in ["GRAVITY_X", "GRAVITY_Y", "GRAVITY_Z"].iter().enumerate() {
            c[k] = self.ranged(key, &[], finite, "a gravity component")?.map_or(0.0, |n| n.v);
        }
        let any_component = ["GRAVITY_X", "GRAVITY_Y", "GRAVITY_Z"].iter().any(|k| self.deck.has(k));
        if c == [0.0; 3] {
            if any_component && !self.deck.has("GRAVITY") {
                self.note(format!(
                    "{}: GRAVITY_X, GRAVITY_Y and GRAVITY_Z are all zero: MFIX then applies its default gravity, {MFIX_GRAVITY} m/s² along −y, and so does grainflow (write GRAVITY = 0.0 for a run without gravity)",
                    self.origin
                ));
            }
            Ok(if g == 0.0 { [0.0; 3] } else { [0.0, -g, 0.0] })
        } else {
            if let Some(gg) = self.deck.real("GRAVITY", &[])? {
                self.note(format!("{}: GRAVITY is not used: the components GRAVITY_X/Y/Z give the gravity vector (MFIX's rule)", gg.loc));
            }
            Ok(c)
        }
    }

    fn phases(&mut self, mmax: usize) -> Result<Vec<Phase>, CaseError> {
        let mut names: BTreeMap<i64, String> = BTreeMap::new();
        for (key, value, _) in &self.lexed.gui {
            if let Some(m) = key.strip_prefix("solids_phase_name(").and_then(|r| r.strip_suffix(')'))
                && let Ok(m) = m.trim().parse::<i64>()
            {
                names.insert(m, value.trim_matches(|c| c == '\'' || c == '"').trim().to_string());
            }
        }
        let mut phases: Vec<Phase> = Vec::new();
        for m in 1..=mmax as i64 {
            let unit = self.unit_name(Unit::Length);
            let diameter = self.required(
                "D_P0",
                &[m],
                limits::DIAMETER,
                "the particle diameter",
                format!("the diameter of solids phase {m} ({unit})"),
            )?;
            let density = self.required(
                "RO_S0",
                &[m],
                limits::DENSITY,
                "the solids density",
                format!(
                    "the density of solids phase {m} ({}); variable densities (RO_XS0) are not supported",
                    self.unit_name(Unit::Density)
                ),
            )?;
            let name = names
                .get(&m)
                .filter(|n| !n.is_empty() && !phases.iter().any(|p| &p.name == *n))
                .cloned()
                .unwrap_or_else(|| format!("solids_{m}"));
            phases.push(Phase { name, diameter, density, youngs_modulus: None, poisson_ratio: None });
        }
        for key in [
            "D_P0",
            "RO_S0",
            "SOLIDS_MODEL",
            "E_YOUNG",
            "V_POISSON",
            "DES_EN_WALL_INPUT",
            "DES_ET_WALL_INPUT",
        ] {
            if let Some(extra) =
                self.deck.indices(key).into_iter().find(|i| i.first().is_some_and(|&m| m > mmax as i64))
            {
                let loc = self.deck.entry(key, &extra).map(|e| e.loc.to_string()).unwrap_or_default();
                self.note(format!("{loc}: {} is ignored: MMAX = {mmax}", show(key, &extra)));
            }
        }
        Ok(phases)
    }

    /// `[contact]` and whether the model is Hertzian.
    fn contact(&mut self, phases: &mut [Phase]) -> Result<(RawContact, bool), CaseError> {
        let model = match self.word("DES_COLL_MODEL", &[])? {
            None => default_str("DES_COLL_MODEL").to_string(),
            Some(g) if g.v == "LSD" || g.v == "HERTZIAN" => g.v,
            Some(g) => {
                return Err(Self::invalid_word(&g, "must be 'LSD' (linear spring-dashpot) or 'HERTZIAN'"));
            }
        };
        let hertz = model == "HERTZIAN";
        let n = phases.len();
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|m| (m..n).map(move |l| (m, l))).collect();
        let restitution = |t: &Self,
                           key: &str,
                           lc: usize,
                           what: &str,
                           range: Range|
         -> Result<f64, CaseError> {
            if let Some(g) = t.real(key, &[lc as i64])?
                && g.v == 0.0
                && range == limits::EN
            {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "must lie in (0, 1]: MFIX accepts 0 (critical damping) but grainflow's damping needs e > 0; use a small positive value",
                ));
            }
            t.required(key, &[lc as i64], range, what, format!("{what}; {}", order_hint(key, n)))
        };
        let mut en = Vec::new();
        let mut et = Vec::new();
        for (lc, (m, l)) in pairs.iter().enumerate() {
            let what = format!("the normal restitution coefficient of phase pair {}-{}", m + 1, l + 1);
            en.push(restitution(self, "DES_EN_INPUT", lc + 1, &what, limits::EN)?);
            if hertz {
                let what =
                    format!("the tangential restitution coefficient of phase pair {}-{}", m + 1, l + 1);
                et.push(restitution(self, "DES_ET_INPUT", lc + 1, &what, limits::ET)?);
            }
        }
        let mut enw = Vec::new();
        let mut etw = Vec::new();
        for m in 0..n {
            let what = format!("the normal restitution coefficient of phase {} against the walls", m + 1);
            enw.push(restitution(self, "DES_EN_WALL_INPUT", m + 1, &what, limits::EN)?);
            if hertz {
                let what =
                    format!("the tangential restitution coefficient of phase {} against the walls", m + 1);
                etw.push(restitution(self, "DES_ET_WALL_INPUT", m + 1, &what, limits::ET)?);
            }
        }
        for (key, count) in [
            ("DES_EN_INPUT", pairs.len()),
            ("DES_ET_INPUT", pairs.len()),
            ("DES_EN_WALL_INPUT", n),
            ("DES_ET_WALL_INPUT", n),
        ] {
            if let Some(extra) =
                self.deck.indices(key).into_iter().find(|i| i.first().is_some_and(|&k| k > count as i64))
            {
                let loc = self.deck.entry(key, &extra).map(|e| e.loc.to_string()).unwrap_or_default();
                self.note(format!(
                    "{loc}: {} is ignored: MMAX = {n} needs {count} values",
                    show(key, &extra)
                ));
            }
        }
        let mu = self.required(
            "MEW",
            &[],
            limits::MU,
            "the particle-particle friction coefficient",
            "the particle-particle Coulomb friction coefficient (MFIX requires it)".into(),
        )?;
        let mu_w = self.required(
            "MEW_W",
            &[],
            limits::MU,
            "the particle-wall friction coefficient",
            "the particle-wall Coulomb friction coefficient (MFIX requires it)".into(),
        )?;
        let mu_r = self.with_default("MEW_R", &[], limits::MU_ROLL, "the rolling friction (a length)")?;
        let mu_rw =
            self.with_default("MEW_RW", &[], limits::MU_ROLL, "the wall rolling friction (a length)")?;

        let mut particle = RawContactParams { mu: Some(mu), mu_roll: Some(mu_r), ..Default::default() };
        let mut wall = RawContactParams { mu: Some(mu_w), mu_roll: Some(mu_rw), ..Default::default() };
        let unused: &[&str];
        if hertz {
            for m in 0..n {
                let e = self.required(
                    "E_YOUNG",
                    &[m as i64 + 1],
                    limits::YOUNGS,
                    "Young's modulus",
                    format!(
                        "Young's modulus of phase {} ({}), required by DES_COLL_MODEL = 'HERTZIAN'",
                        m + 1,
                        self.unit_name(Unit::Modulus)
                    ),
                )?;
                let nu = self.required(
                    "V_POISSON",
                    &[m as i64 + 1],
                    limits::POISSON,
                    "Poisson's ratio",
                    format!("Poisson's ratio of phase {}, required by DES_COLL_MODEL = 'HERTZIAN'", m + 1),
                )?;
                phases[m].youngs_modulus = Some(e);
                phases[m].poisson_ratio = Some(nu);
            }
            unused = &["KN", "KN_W", "KT_FAC", "KT_W_FAC", "DES_ETAT_FAC", "DES_ETAT_W_FAC"];
        } else {
            let unit = self.unit_name(Unit::Stiffness);
            particle.kn = Some(self.required("KN", &[], limits::KN, "the normal spring constant", format!("the particle-particle normal spring constant ({unit}), required by DES_COLL_MODEL = 'LSD'"))?);
            wall.kn = Some(self.required(
                "KN_W",
                &[],
                limits::KN,
                "the normal spring constant",
                format!(
                    "the particle-wall normal spring constant ({unit}), required by DES_COLL_MODEL = 'LSD'"
                ),
            )?);
            particle.kt_fac = Some(self.with_default(
                "KT_FAC",
                &[],
                limits::KT_FAC,
                "the tangential to normal stiffness ratio",
            )?);
            wall.kt_fac = Some(self.with_default(
                "KT_W_FAC",
                &[],
                limits::KT_FAC,
                "the tangential to normal stiffness ratio",
            )?);
            particle.etat_fac = Some(self.with_default(
                "DES_ETAT_FAC",
                &[],
                limits::ETAT_FAC,
                "the tangential to normal damping ratio",
            )?);
            wall.etat_fac = Some(self.with_default(
                "DES_ETAT_W_FAC",
                &[],
                limits::ETAT_FAC,
                "the tangential to normal damping ratio",
            )?);
            unused = &["DES_ET_INPUT", "DES_ET_WALL_INPUT", "E_YOUNG", "V_POISSON", "EW_YOUNG", "VW_POISSON"];
        }
        let given: Vec<&str> = unused.iter().copied().filter(|k| self.deck.has(k)).collect();
        if !given.is_empty() {
            self.note(format!(
                "{}: not used by DES_COLL_MODEL = '{model}' (MFIX ignores them too): {}",
                self.origin,
                given.join(", ")
            ));
        }
        // Restitution: in the defaults table when uniform, else per pair / per phase.
        let uniform = |v: &[f64]| v.windows(2).all(|w| w[0] == w[1]);
        let mut pair_tables = Vec::new();
        let (en_uniform, et_uniform) = (uniform(&en), uniform(&et));
        if en_uniform {
            particle.en = en.first().copied();
        }
        if et_uniform {
            particle.et = et.first().copied();
        }
        if !en_uniform || !et_uniform {
            for (lc, (m, l)) in pairs.iter().enumerate() {
                pair_tables.push(RawContactParams {
                    phases: Some([phases[*m].name.clone(), phases[*l].name.clone()]),
                    en: (!en_uniform).then(|| en[lc]),
                    et: (!et_uniform).then(|| et.get(lc).copied()).flatten(),
                    ..Default::default()
                });
            }
        }
        let mut wall_tables = Vec::new();
        let (enw_uniform, etw_uniform) = (uniform(&enw), uniform(&etw));
        if enw_uniform {
            wall.en = enw.first().copied();
        }
        if etw_uniform {
            wall.et = etw.first().copied();
        }
        if !enw_uniform || !etw_uniform {
            for (m, p) in phases.iter().enumerate() {
                wall_tables.push(RawContactParams {
                    phase: Some(p.name.clone()),
                    en: (!enw_uniform).then(|| enw[m]),
                    et: (!etw_uniform).then(|| etw.get(m).copied()).flatten(),
                    ..Default::default()
                });
            }
        }
        let contact = RawContact {
            model: Some(if hertz { "hertz" } else { "lsd" }.into()),
            tangential: None,
            history: None,
            lever_arm: None,
            damping: None,
            clip_attraction: None,
            coulomb: None,
            sizes: Some("phase".into()),
            particle,
            wall,
            pairs: pair_tables,
            walls: wall_tables,
        };
        Ok((contact, hertz))
    }

    fn time(&mut self) -> Result<RawTime, CaseError> {
        let finite = Range {
            lo: 0.0,
            lo_open: false,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a time >= 0 in s",
        };
        let t0 = self.ranged("TIME", &[], finite, "the start time")?.map(|n| n.v);
        let t_stop =
            self.required("TSTOP", &[], finite, "the stop time", "the end time of the run, s".into())?;
        if t_stop <= t0.unwrap_or(0.0) {
            let g = self.real("TSTOP", &[])?;
            let (loc, text) =
                g.map_or((self.origin.to_string(), t_stop.to_string()), |g| (g.loc.to_string(), g.text));
            return Err(CaseError::invalid(
                loc,
                "TSTOP",
                text,
                format!("must be after TIME = {} s", t0.unwrap_or(0.0)),
            ));
        }
        match self.real("DT", &[])? {
            Some(g) if g.v < 0.0 => {
                return Err(CaseError::invalid(g.loc.to_string(), g.key, g.text, "must be a positive time step in s (it does not set the DEM step: MFIX's DTSOLID does)"));
            }
            Some(g) if g.v > 0.0 => {}
            _ => self.note(format!(
                "{}: DT is not given (or 0): MFIX would take the run as steady-state; in a pure granular run DT does not set the step (MFIX replaces it by DTSOLID), so grainflow runs the DEM as usual",
                self.origin
            )),
        }
        let factor = self.with_default(
            "DTSOLID_FACTOR",
            &[],
            Range {
                lo: 10.0,
                lo_open: false,
                hi: f64::MAX,
                hi_open: false,
                valid: "must be at least 10 (MFIX rejects smaller values)",
            },
            "the collision time to DEM time step ratio",
        )?;
        let method = self.word("DES_INTG_METHOD", &[])?;
        let integrator = match method.as_ref().map_or(default_str("DES_INTG_METHOD"), |g| g.v.as_str()) {
            "EULER" => "euler",
            "ADAMS_BASHFORTH" => "adams_bashforth",
            _ => {
                let valid = "must be 'EULER' (MFIX's default) or 'ADAMS_BASHFORTH'";
                return Err(method.as_ref().map_or_else(
                    || CaseError::missing(self.origin, "DES_INTG_METHOD", valid),
                    |g| Self::invalid_word(g, valid),
                ));
            }
        };
        Ok(RawTime {
            t_stop: Some(t_stop),
            t_start: t0,
            dt: None,
            dtsolid_factor: Some(factor),
            integrator: Some(integrator.into()),
            force_dt: None,
        })
    }

    /// Particle VTK output: the interval of the VTK regions holding particle data.
    fn output(&mut self) -> Result<RawOutput, CaseError> {
        let positive = Range {
            lo: 0.0,
            lo_open: true,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a positive time in s",
        };
        let mut interval: Option<f64> = None;
        for idx in self.deck.indices("VTK_DT") {
            let data = self.word("VTK_DATA", &idx)?.map_or(default_str("VTK_DATA").to_string(), |g| g.v);
            if data != "P" {
                continue;
            }
            if let Some(n) = self.ranged("VTK_DT", &idx, positive, "the VTK output interval")? {
                interval = Some(interval.map_or(n.v, |i: f64| i.min(n.v)));
            }
        }
        let on = self.flag("WRITE_VTK_FILES")?;
        match interval {
            Some(dt) if on => Ok(RawOutput { interval: Some(dt), snapshots: None, vtk_interval: Some(dt) }),
            Some(_) => {
                self.note(format!("{}: VTK_DT for particle data is given but WRITE_VTK_FILES is .FALSE.: no VTK output, outputs at grainflow's default interval", self.origin));
                Ok(RawOutput::default())
            }
            None => Ok(RawOutput::default()),
        }
    }

    /// `[particles]` from particle_input.dat, and text to add to the case hash.
    fn particles(
        &mut self,
        phases: &[Phase],
        lo: Vec3,
        hi: Vec3,
        read_file: &input::Opener<'_>,
    ) -> Result<(RawParticles, String), CaseError> {
        let count = self.deck.int("PARTICLES", &[])?;
        if let Some(g) = &count
            && g.v < 1
        {
            return Err(CaseError::invalid(
                g.loc.to_string(),
                g.key.clone(),
                g.text.clone(),
                "must be at least 1: a run without initial particles needs a mass inflow, which grainflow does not have",
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
        // Lines counted past PARTICLES for the message, at most this many.
        const COUNT_PAST: usize = 1_000_000;
        let mut complete = true;
        while let Some((line, l)) = stream.next_line()? {
            if line == 1 && l.trim().starts_with("Version") {
                return Err(CaseError::ParticleFile {
                    path: PARTICLE_FILE.into(),
                    line: 1,
                    message: format!(
                        "'{}': the header format of MFIX 20.1+ (version 2.0) is not read yet; write the legacy format, one particle per line: x y z radius density u v w",
                        l.trim()
                    ),
                });
            }
            let Some(fields) = particles::mfix_fields(l) else { continue };
            n_data += 1;
            if n_data > want {
                if n_data > want + COUNT_PAST {
                    complete = false;
                    break;
                }
                continue;
            }
            if first_error.is_some() {
                continue;
            }
            let numbers = if self.cgs { cgs_numbers(&fields) } else { particles::mfix_numbers(&fields) };
            match numbers {
                Ok(v) => data.push((line, v)),
                Err(message) => {
                    first_error = Some(CaseError::ParticleFile { path: PARTICLE_FILE.into(), line, message })
                }
            }
        }
        drop(stream);
        if n_data != want {
            let (loc, text) =
                count.as_ref().map_or((self.origin.to_string(), format!("{want} (MFIX's default)")), |g| {
                    (g.loc.to_string(), g.text.clone())
                });
            let listed = if complete { n_data.to_string() } else { format!("more than {n_data}") };
            return Err(CaseError::invalid(
                loc,
                "PARTICLES",
                text,
                if complete {
                    format!(
                        "{PARTICLE_FILE} lists {listed} particle{} and MFIX reads exactly PARTICLES of them: set PARTICLES = {n_data}",
                        if n_data == 1 { "" } else { "s" },
                    )
                } else {
                    format!(
                        "{PARTICLE_FILE} lists {listed} particles and MFIX reads exactly PARTICLES of them"
                    )
                },
            ));
        }
        if let Some(e) = first_error {
            return Err(e);
        }
        let mut raw = RawParticles {
            file: None,
            format: None,
            max_initial_overlap: None,
            max_overlap: None,
            order: None,
            resort: None,
            list: Vec::new(),
        };
        let mut extra_source = String::new();
        let init = if self.cgs {
            let mut init = Vec::new();
            for (line, v) in &data {
                let err = |message: String| CaseError::ParticleFile {
                    path: PARTICLE_FILE.into(),
                    line: *line,
                    message,
                };
                let [x, y, z, r, rho, u, vv, w] = *v;
                let (x, y, z, r) = (x / 100.0, y / 100.0, z / 100.0, r / 100.0);
                let rho = Unit::Density.cgs_to_si(rho);
                let vel = [u, vv, w].map(|c| Unit::Velocity.cgs_to_si(c));
                if !(r.is_finite() && r > 0.0) {
                    return Err(err(format!("radius {} cm must be positive", v[3])));
                }
                let phase = particles::match_phase(2.0 * r, rho, phases).ok_or_else(|| {
                    err(format!(
                        "no phase has diameter {} cm and density {} g/cm³ (the phases: {})",
                        2.0 * v[3],
                        v[4],
                        phases
                            .iter()
                            .map(|p| format!(
                                "'{}' D_P0 = {} cm, RO_S0 = {} g/cm³",
                                p.name,
                                p.diameter * 100.0,
                                p.density / 1000.0
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
            let text = String::from_utf8_lossy(&kept.borrow()).into_owned();
            extra_source = format!("\0file\0{PARTICLE_FILE}\0{text}");
            init
        } else {
            raw.file = Some(PARTICLE_FILE.into());
            data.iter().map(|(_, v)| (Vec3::new(v[0], v[1], v[2]), v[3])).collect()
        };
        // MFIX does not check initial overlaps; grainflow's cases refuse more than
        // DEFAULT_MAX_INITIAL_OVERLAP unless told. Say what this deck needs.
        if let Some((ratio, what)) = largest_overlap(&init, lo, hi)
            && ratio > DEFAULT_MAX_INITIAL_OVERLAP
        {
            let limit = ((ratio * 100.0).ceil() + 1.0) / 100.0;
            raw.max_initial_overlap = Some(limit);
            self.note(format!(
                    "{PARTICLE_FILE}: {what} overlap by {ratio:.3} of the smaller radius at the start; MFIX does not check this, grainflow's own limit ({DEFAULT_MAX_INITIAL_OVERLAP}) is raised to {limit} for this deck ([particles] max_initial_overlap)"
                ));
        }
        Ok((raw, extra_source))
    }

    /// One report per group of ignored keywords, one per unknown keyword, and the keywords
    /// MFIX requires that are missing.
    fn report_keywords(&mut self) {
        let d = self.deck;
        let mut groups: BTreeMap<Why, Vec<String>> = BTreeMap::new();
        let mut unknown = Vec::new();
        for key in &d.order {
            let g = &d.given[key];
            let at = match &g.first {
                Loc::Line { line, .. } => format!("line {line}"),
                Loc::Arg { .. } => "command line".into(),
            };
            match g.spec.map(|s| s.role) {
                Some(Role::Ignored(why)) => groups.entry(why).or_default().push(format!("{key} ({at})")),
                None => {
                    let hint =
                        keywords::closest(key).map_or(String::new(), |k| format!("; did you mean `{k}`?"));
                    unknown.push(format!(
                        "{}: unknown keyword `{key}`, ignored: it is not one of the MFIX keywords grainflow knows (docs/mfix-decks.md); if it changes the DEM in MFIX, the results will differ{hint}",
                        g.first
                    ));
                }
                _ => {}
            }
        }
        for (why, keys) in groups {
            self.note(format!("{}: ignored, {}: {}", self.origin, why.sentence(), keys.join(", ")));
        }
        self.notes.extend(unknown);
        for (key, a, b) in &d.repeated {
            self.notes.push(format!("{b}: {key} was already given at {a}; the later value is used"));
        }
        let missing: Vec<&str> = keywords::KEYWORDS
            .iter()
            .filter(|k| k.default == Dflt::MfixRequired && !d.has(k.name))
            .map(|k| k.name)
            .collect();
        if !missing.is_empty() {
            self.notes.push(format!(
                "{}: MFIX itself requires {}, which the deck does not give; grainflow does not need them",
                self.origin,
                missing.join(", ")
            ));
        }
    }
}

/// MFIX's default of a whole-number keyword, from the keyword table.
fn default_int(key: &str) -> i64 {
    match keywords::lookup(key).map(|k| k.default) {
        Some(Dflt::Int(v)) => v,
        _ => 0,
    }
}

/// MFIX's default of a word keyword, from the keyword table.
fn default_str(key: &str) -> &'static str {
    match keywords::lookup(key).map(|k| k.default) {
        Some(Dflt::Str(v)) => v,
        _ => "",
    }
}

/// Where the restitution arrays' elements go, for messages.
fn order_hint(key: &str, n: usize) -> String {
    if key.contains("WALL") {
        format!("{key} holds one value per solids phase ({n} here)")
    } else {
        format!(
            "{key} holds MMAX·(MMAX+1)/2 = {} values, one per phase pair in the order 1-1, 1-2, …, 1-M, 2-2, …",
            n * (n + 1) / 2
        )
    }
}

/// The largest initial overlap, as a fraction of the smaller radius (pairs) or the radius
/// (box faces), with who overlaps.
fn largest_overlap(p: &[(Vec3, f64)], lo: Vec3, hi: Vec3) -> Option<(f64, String)> {
    let mut best: Option<(f64, String)> = None;
    let mut consider = |ratio: f64, what: &dyn Fn() -> String| {
        if ratio > best.as_ref().map_or(0.0, |b| b.0) {
            best = Some((ratio, what()));
        }
    };
    for w in &Wall::domain_box(lo, hi, 0) {
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

/// A reader that keeps a copy of the bytes it passes.
struct Tee {
    inner: Box<dyn std::io::BufRead>,
    out: std::rc::Rc<std::cell::RefCell<Vec<u8>>>,
}

impl std::io::Read for Tee {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.out.borrow_mut().extend_from_slice(&buf[..n]);
        Ok(n)
    }
}
