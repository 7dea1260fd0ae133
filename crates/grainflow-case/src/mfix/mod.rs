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
pub mod deck;
mod equipment;
pub mod geometry;
pub mod keywords;
pub mod lexer;
mod seed;

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

/// The file given with `--motion`: what a deck's user-defined functions did, in grainflow's
/// terms: `[[motion]]` rules for particles, `[[walls]]` for the deck's STL walls.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct MotionFile {
    #[serde(default)]
    motion: Vec<RawMotion>,
    #[serde(default)]
    walls: Vec<WallRule>,
}

/// `[[walls]]` of a motion file: how the STL wall of boundary condition `bc` moves.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct WallRule {
    /// The deck's boundary condition (a `CG_NSW`, `CG_FSW` or `CG_PSW` wall), or
    bc: Option<i64>,
    /// its internal surface (`IS_TYPE = 'STL'`).
    is: Option<i64>,
    /// The mesh moving as a rigid body (`[meshes.motion]`).
    motion: Option<RawMeshMotion>,
    /// A velocity of its surface, the mesh staying in place (`[meshes.surface]`).
    surface: Option<RawMeshSurface>,
}

fn parse_motion(text: &str, origin: &str) -> Result<MotionFile, CaseError> {
    let m: MotionFile = toml::from_str(text).map_err(|e| {
        CaseError::Syntax(format!(
            "{origin}: {e}\n(a motion file holds [[motion]] tables for particles, as in a case file, and [[walls]] tables for the deck's STL walls, docs/mfix-decks.md)"
        ))
    })?;
    if m.motion.is_empty() && m.walls.is_empty() {
        return Err(CaseError::missing(
            origin,
            "[[motion]] or [[walls]]",
            "at least one rule: a prescribed particle motion or a wall's motion",
        ));
    }
    for (k, w) in m.walls.iter().enumerate() {
        // A wall moves one way: a second table for the same one would silently replace it.
        if let Some(j) = m.walls[..k]
            .iter()
            .position(|o| (o.bc.is_some() && o.bc == w.bc) || (o.is.is_some() && o.is == w.is))
        {
            let (key, id) = match (w.bc, w.is) {
                (Some(b), _) => ("bc", b),
                (None, Some(i)) => ("is", i),
                (None, None) => unreachable!("a match needs an id"),
            };
            return Err(CaseError::invalid(
                format!("{origin}: [[walls]] #{}", k + 1),
                key,
                id,
                format!(
                    "[[walls]] #{} already gives this wall's motion; give each wall one [[walls]] table",
                    j + 1
                ),
            ));
        }
        if w.bc.is_some() == w.is.is_some() {
            return Err(CaseError::missing(
                format!("{origin}: [[walls]] #{}", k + 1),
                "bc or is",
                "the wall: its boundary condition `bc = N` or its internal surface `is = N`, one of them",
            ));
        }
        if w.motion.is_none() && w.surface.is_none() {
            return Err(CaseError::missing(
                format!("{origin}: [[walls]] #{}", k + 1),
                "motion or surface",
                "how the wall of this boundary condition moves",
            ));
        }
    }
    Ok(m)
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
            contact: Some(contact.0),
            time: Some(time),
            neighbor,
            output,
            particles: Some(particles),
            motion,
            insertions: equipment.insertions,
            outlets: equipment.outlets,
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
                    self.block(CaseError::invalid(
                        e.loc.to_string(),
                        show(key, idx),
                        written,
                        format!("grainflow cannot run this: {why}{only}"),
                    ));
                }
            }
        }
        if let Some(loc) = &self.lexed.reactions {
            self.block(CaseError::invalid(
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
                self.block(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: MFIX restart files cannot be read; use RUN_TYPE = 'NEW' (grainflow restarts from its own checkpoints: grainflow run --restart)",
                ));
            }
            Some(g) => {
                self.block(Self::invalid_word(
                    &g,
                    "must be 'NEW' (or MFIX's 'RESTART_1', 'RESTART_2', which grainflow cannot read)",
                ));
            }
            None => {}
        }
        match self.word("COORDINATES", &[])? {
            Some(g) if g.v == "CARTESIAN" => {}
            Some(g) if g.v == "CYLINDRICAL" => {
                self.block(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: only COORDINATES = 'CARTESIAN' is supported",
                ));
            }
            Some(g) => {
                self.block(Self::invalid_word(
                    &g,
                    "must be 'CARTESIAN' (or 'CYLINDRICAL', which grainflow cannot run)",
                ));
            }
            None => {}
        }
        match self.real("RO_G0", &[])? {
            Some(g) if g.v == 0.0 => {}
            Some(g) => {
                // The drag on a particle grows with the gas viscosity, not its density: a deck
                // with a vanishing gas density (MFIX's poly_dem_inlet_outlet, 1.3d-30) still
                // drags its particles through the gas.
                let drag = d.string("DRAG_TYPE", &[], true)?;
                let (drag_name, drag_at) =
                    drag.as_ref().map_or(("SYAM_OBRIEN".to_string(), "MFIX's default".to_string()), |t| {
                        (t.v.clone(), t.loc.to_string())
                    });
                let mu = d
                    .real("MU_G0", &[])?
                    .map_or("MU_G0 not given: MFIX's Sutherland air viscosity".to_string(), |m| {
                        format!("MU_G0 = {} ({})", m.text, m.loc)
                    });
                let what = if g.v.abs() < 1e-6 {
                    format!(
                        "grainflow cannot run this: the gas density is vanishingly small, but the gas still drags the particles: DRAG_TYPE = '{drag_name}' ({drag_at}) with {mu}, and the deck's gas velocities; grainflow has no gas phase and no drag. A pure granular run has RO_G0 = 0.0 (then MFIX computes no drag either)"
                    )
                } else {
                    format!(
                        "grainflow cannot run this: a gas density couples gas and particles (drag: DRAG_TYPE = '{drag_name}' ({drag_at}) with {mu}; buoyancy) and grainflow has no gas phase; a pure granular run has RO_G0 = 0.0"
                    )
                };
                self.block(CaseError::invalid(g.loc.to_string(), g.key, g.text, what));
            }
            None => {
                self.block(CaseError::missing(
                    self.origin,
                    "RO_G0",
                    "a pure granular (DEM-only) run needs RO_G0 = 0.0; without it MFIX computes a gas density from the ideal-gas law and couples gas and particles, which grainflow cannot",
                ));
            }
        }
        if let Some(g) = d.bool("CALL_USR", &[])? {
            if g.v && !have_motion {
                self.block(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "grainflow cannot run user-defined Fortran functions (usr0.f, usr1_des.f, …), which can change any result. If they only write output, run without them: grainflow run DECK CALL_USR=.F. (the deck stays as it is). If they prescribe motion — particles held or moved (MFIX's DEM05), a drum or a belt turned by a key-frame table (data_kf_NNNN.txt) — say the same in a motion file of [[motion]] and [[walls]] tables and run grainflow run DECK --motion FILE (docs/mfix-decks.md, \"User-defined functions\")",
                ));
            }
            if g.v {
                self.note(format!(
                    "{}: CALL_USR = .TRUE.: the deck's user-defined functions are replaced by the rules of the --motion file",
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
        let no_k = self.flag("NO_K")?;
        for (a, ax) in ["X", "Y", "Z"].iter().enumerate() {
            if a == 2 && no_k {
                // 2-D: the particles lie in z = 0; the box's depth is set from their size.
                continue;
            }
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
