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

mod cells;
mod contact;
pub mod deck;
mod domain;
mod equipment;
pub mod geometry;
pub mod keywords;
pub mod lexer;
mod motion;
mod particle_file;
mod phases;
mod refusals;
mod run_control;
mod seed;

use crate::case::Case;
use crate::error::CaseError;
use crate::input;
use crate::raw::*;
use deck::{Deck, Got, show};
use grainflow::contact::limits::{self, Range};
use keywords::{Dflt, Role, Unit, Why};
use lexer::Loc;
use motion::{MotionFile, parse_motion};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The particle file MFIX reads, beside the deck.
pub const PARTICLE_FILE: &str = "particle_input.dat";

/// The largest overlap a deck's run may reach, as a fraction of the smaller radius.
pub const DECK_MAX_OVERLAP: f64 = 1.0;

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
    load_relayed(path, overrides, motion, &input::direct)
}

/// [`load`] with the files the deck names (particles, STL, PSD, key frames) passed through
/// `relay` (see [`input::Relay`]); the deck and the motion file are read here.
pub fn load_relayed(
    path: &Path,
    overrides: &[String],
    motion: Option<&Path>,
    relay: &input::Relay<'_>,
) -> Result<DeckCase, CaseError> {
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
        &input::relayed(&input::open_beside(&dir), relay),
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
    let mut tr = Translator {
        deck: &deck,
        lexed: &lexed,
        origin,
        cgs: false,
        notes: Vec::new(),
        blockers: Vec::new(),
        mesh_bcs: Vec::new(),
    };
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
    translated_toml(raw, &format!("the MFIX deck {origin}"), "docs/mfix-decks.md", "deck", notes)
}

/// The TOML of a case translated from `what` (e.g. "the MFIX deck mfix.dat"), whose
/// translation `doc` describes, with its notes as comments; `kind` names the input ("deck").
pub(crate) fn translated_toml(
    raw: &RawCase,
    what: &str,
    doc: &str,
    kind: &str,
    notes: &[String],
) -> Result<String, CaseError> {
    let body =
        toml::to_string(raw).map_err(|e| CaseError::Syntax(format!("{what}: cannot write TOML: {e}")))?;
    let mut s = format!(
        "# grainflow case translated from {what} by grainflow {}.\n# Keys, units and defaults: docs/case-file.md; the translation: {doc}.\n",
        env!("CARGO_PKG_VERSION")
    );
    if raw.particles.as_ref().is_some_and(|p| p.file.is_some()) {
        s.push_str(&format!(
            "# The particle file is named relative to this file: keep it beside the {kind}.\n"
        ));
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
    /// What stops the deck from running, collected so that a user sees the whole list.
    blockers: Vec<CaseError>,
    /// The boundary condition of each mesh wall, in the order of the case's meshes; an
    /// internal surface's id negated.
    mesh_bcs: Vec<i64>,
}

/// A validated number in SI with its source.
struct Num {
    v: f64,
}

impl Translator<'_> {
    /// Records something that stops the deck from running; the translation goes on, so that
    /// every such thing is reported at once.
    fn block(&mut self, e: CaseError) {
        self.blockers.push(e);
    }

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

    /// The translation, with every blocker reported at once: the stages go on past what they
    /// cannot run (recorded by [`Self::block`]), and a stage's own error ends the list.
    fn translate(
        &mut self,
        motion: Option<MotionFile>,
        read_file: &input::Opener<'_>,
    ) -> Result<(RawCase, String), CaseError> {
        let result = self.stages(motion, read_file);
        let mut blockers = std::mem::take(&mut self.blockers);
        match result {
            Ok(r) if blockers.is_empty() => return Ok(r),
            Ok(_) => {}
            Err(e) => blockers.push(e),
        }
        if blockers.len() == 1 { Err(blockers.remove(0)) } else { Err(CaseError::Blockers(blockers)) }
    }

    fn stages(
        &mut self,
        motion: Option<MotionFile>,
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
        let (mut lo, mut hi) = self.domain()?;
        let mut periodic = self.cyclic()?;
        let gravity = self.gravity()?;
        let mut phases = self.phases(mmax)?;
        let contact = self.contact(&mut phases)?;
        let time = self.time()?;
        let t_start = time.t_start.unwrap_or(0.0);
        let no_k = self.flag("NO_K")?;
        if no_k {
            // MFIX's 2-D DEM: spheres in the plane z = 0, moving in x and y. A 3-D run whose
            // particles all start at z = 0 with no z velocity stays in that plane exactly
            // (every contact normal and force lies in it), so the box is given a depth of two
            // largest diameters and no walls in z.
            let dmax = phases.iter().map(|p| p.diameter).fold(0.0, f64::max);
            lo.z = -dmax;
            hi.z = dmax;
            periodic[2] = false;
            self.two_d_checks(gravity)?;
        }
        let exists = |name: &str| read_file(name).is_ok();
        let mut equipment = self.equipment(lo, hi, periodic, &phases, t_start, &exists, read_file)?;
        let dmax = phases.iter().map(|p| p.diameter).fold(0.0, f64::max);
        let rlm = self.with_default(
            "FACTOR_RLM",
            &[],
            Range { lo: 1.0, lo_open: false, hi: f64::MAX, hi_open: false, valid: "must be at least 1" },
            "the neighbour-list factor (multiple of the sum of the radii)",
        )?;
        let neighbor = RawNeighbor { skin: Some((rlm - 1.0) * dmax) };
        let output = self.output()?;
        let no_file = d.int("PARTICLES", &[])?.is_some_and(|g| g.v == 0);
        if no_file && equipment.insertions.is_empty() && !self.flag("GENER_PART_CONFIG")? {
            let g = d.int("PARTICLES", &[])?.expect("given");
            self.block(CaseError::invalid(
                g.loc.to_string(),
                g.key,
                g.text,
                "PARTICLES = 0 reads no particle file, and no mass inflow (BC_TYPE = 'MI') or GENER_PART_CONFIG brings particles: the run would have none",
            ));
        }
        let (particles, extra_source) = if no_file && !self.flag("GENER_PART_CONFIG")? {
            (RawParticles { max_overlap: Some(DECK_MAX_OVERLAP), ..RawParticles::default() }, String::new())
        } else if self.flag("GENER_PART_CONFIG")? {
            if let Some(g) = d.int("PARTICLES", &[])? {
                self.note(format!(
                    "{}: PARTICLES is not used: GENER_PART_CONFIG generates the particles (MFIX's rule)",
                    g.loc
                ));
            }
            let list = std::mem::take(&mut equipment.particles);
            self.note(format!(
                "{}: GENER_PART_CONFIG seeds {} particles in the IC regions, on MFIX's lattice",
                self.origin,
                list.len()
            ));
            (
                RawParticles { max_overlap: Some(DECK_MAX_OVERLAP), list, ..RawParticles::default() },
                String::new(),
            )
        } else {
            let walls = self.load_walls(&equipment.meshes, read_file)?;
            self.particles(&phases, lo, hi, &equipment.walls, &walls, read_file)?
        };
        let MotionFile { motion, walls: wall_rules } = motion.unwrap_or_default();
        let mut meshes = equipment.meshes;
        for (k, rule) in wall_rules.iter().enumerate() {
            let (key, id, owner) = match (rule.bc, rule.is) {
                (Some(b), _) => ("bc", b, b),
                (None, Some(i)) => ("is", i, -i),
                (None, None) => unreachable!("checked when the motion file is read"),
            };
            let mine: Vec<usize> =
                (0..meshes.len()).filter(|&j| self.mesh_bcs.get(j) == Some(&owner)).collect();
            if mine.is_empty() {
                let mut bcs: Vec<String> = self
                    .mesh_bcs
                    .iter()
                    .map(|&b| if b > 0 { format!("bc = {b}") } else { format!("is = {}", -b) })
                    .collect();
                bcs.dedup();
                self.block(CaseError::invalid(
                    format!("the --motion file's [[walls]] #{}", k + 1),
                    key,
                    id,
                    if bcs.is_empty() {
                        "the deck has no STL walls (cut-cell walls CG_NSW, CG_FSW, CG_PSW or internal surfaces IS_TYPE = 'STL', with USE_STL)"
                            .to_string()
                    } else {
                        format!("not an STL wall of the deck; its STL walls are {}", bcs.join(", "))
                    },
                ));
            }
            for j in mine {
                meshes[j].motion = rule.motion.clone();
                meshes[j].surface = rule.surface.clone();
            }
        }

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
                walls: if equipment.walls.len() + 2 * equipment.periodic.len() == 6 {
                    WallSelection::All(true)
                } else {
                    WallSelection::Faces(equipment.walls.iter().map(|f| f.to_string()).collect())
                },
                periodic: (!equipment.periodic.is_empty()).then(|| equipment.periodic.clone()),
                wall_material: None,
                leaving: equipment.open.then(|| "remove".to_string()),
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
            meshes,
            cylinders: Vec::new(),
            contact: Some(contact.0),
            time: Some(time),
            neighbor,
            output,
            parallel: Default::default(),
            particles: Some(particles),
            motion,
            insertions: equipment.insertions,
            outlets: equipment.outlets,
        };
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
