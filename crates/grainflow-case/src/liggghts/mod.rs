//! LIGGGHTS input scripts, translated into grainflow's case.
//!
//! A script ([`script`]: its lines, variables and includes) is a list of commands. Each
//! command grainflow knows is translated into the same [`RawCase`] a TOML case file gives and
//! validated by the same code, as MFIX decks are ([`crate::mfix`]); `grainflow convert` writes
//! that case as TOML. Commands that cannot change a granular result (`newton`, `communicate`,
//! `processors`, `atom_modify`, computes and thermo formatting) are noted and skipped. Every
//! other command, and every option of a known command that grainflow cannot honour, is a
//! blocker: the run is refused with the whole list, each with its line.
//!
//! The translation, command by command, is in docs/liggghts-scripts.md. In short:
//! - `read_data` gives the particles (its file), the box (its bounds; a shrink-wrapped upper
//!   bound, `boundary … s`/`m`, is raised by the box's height) and one phase per atom type;
//! - `pair_style gran model hertz tangential history` is grainflow's `hertz` with LIGGGHTS's
//!   damping, Coulomb cap and lever arm; `model hooke/stiffness` is `lsd` with γ_n·m_eff
//!   damping; `fix property/global` gives their constants per atom type (pair);
//! - `fix wall/gran … primitive type t xplane|yplane|zplane c` is a plane wall facing the
//!   particles, of type t's material;
//! - `fix gravity`, `timestep`, `neighbor` (the skin), `fix freeze` and the integrated group
//!   of `fix nve/sphere` (the other particles are held), `thermo N` (the time series'
//!   interval) and the steps of every `run`.
//!
//! Files the script names (`include`, `read_data`) are read beside the script, as LIGGGHTS
//! reads them when run from the script's folder.

pub mod script;

use crate::case::Case;
use crate::error::CaseError;
use crate::input;
use crate::raw::*;
use script::{Command, Variables};

mod insertions;
mod meshes;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// A script translated and validated.
#[derive(Debug, Clone)]
pub struct ScriptCase {
    /// The validated case.
    pub case: Case,
    /// The translated case before validation: `grainflow convert` writes it as TOML.
    pub raw: RawCase,
    /// What the translation reports: commands skipped and LIGGGHTS rules applied.
    pub notes: Vec<String>,
}

/// True for the files `grainflow run` reads as LIGGGHTS scripts: `in.*` and `*.liggghts`.
pub fn is_script(path: &Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    name.starts_with("in.") || name.ends_with(".liggghts")
}

/// Reads, translates and validates a script; `vars` are `-var NAME VALUE` pairs. Included and
/// data files are read beside the script.
pub fn load(path: &Path, vars: &[(String, String)]) -> Result<ScriptCase, CaseError> {
    load_relayed(path, vars, &input::direct)
}

/// [`load`] with the included and data files passed through `relay` (see [`input::Relay`]).
pub fn load_relayed(
    path: &Path,
    vars: &[(String, String)],
    relay: &input::Relay<'_>,
) -> Result<ScriptCase, CaseError> {
    let text = input::read_text(path, input::Kind::Deck)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let beside = input::open_beside(&dir);
    let open = input::relayed(&beside, relay);
    let read = |name: &str| -> Result<String, CaseError> {
        let mut s = String::new();
        open(name)?
            .read_to_string(&mut s)
            .map_err(|e| CaseError::Syntax(format!("{name}: cannot read it as text: {e}")))?;
        Ok(s)
    };
    translate(&text, &path.display().to_string(), vars, &read, &open)
}

/// Translates and validates script text; `read` gives included and data files as text,
/// `open` the particle file to the case.
pub fn translate(
    text: &str,
    origin: &str,
    vars: &[(String, String)],
    read: &dyn Fn(&str) -> Result<String, CaseError>,
    open: &input::Opener<'_>,
) -> Result<ScriptCase, CaseError> {
    let mut variables = Variables::given(vars);
    let commands = script::commands(input::strip_bom(text), origin, &mut variables, read, 0)?;
    let mut t = Translator::default();
    for c in &commands {
        t.command(c, read);
    }
    let raw = t.finish(origin)?;
    let mut source = text.to_string();
    for (k, v) in vars {
        source.push_str(&format!("\n# -var {k} {v}"));
    }
    // The case layer's messages name a table and key of the translation: the script is named
    // before them.
    let mut case = crate::case::from_raw_opened(raw.clone(), &source, open).map_err(|e| {
        if e.to_string().contains(origin) {
            e
        } else {
            CaseError::Syntax(format!("{origin}, as translated: {e}"))
        }
    })?;
    let mut warnings = t.notes.clone();
    warnings.append(&mut case.warnings);
    case.warnings = warnings;
    Ok(ScriptCase { case, raw, notes: t.notes })
}

/// What `read_data` gave.
#[derive(Debug, Clone, Default)]
struct Data {
    file: String,
    lo: [f64; 3],
    hi: [f64; 3],
    /// (id, type) of every atom.
    atoms: Vec<(u32, usize)>,
    /// Diameter and density of the first atom of each type (index type − 1).
    first_of_type: Vec<Option<(f64, f64)>>,
}

/// The contact law of `pair_style gran`.
#[derive(Debug, Clone, PartialEq)]
struct Pair {
    model: String,
    tangential: String,
    tangential_damping: bool,
    limit_force: bool,
}

/// `fix … wall/gran … primitive`.
#[derive(Debug, Clone)]
struct PlaneWall {
    axis: usize,
    at: f64,
    wall_type: usize,
}

/// A group: the atom types it holds (`None`: all).
type Group = Option<Vec<usize>>;

#[derive(Default)]
struct Translator {
    notes: Vec<String>,
    blockers: Vec<CaseError>,
    boundary: Option<[String; 3]>,
    data: Option<Data>,
    skin: Option<f64>,
    dt: Option<f64>,
    gravity: Option<[f64; 3]>,
    /// `fix property/global` values by property name: one (`scalar`), one a type
    /// (`peratomtype`) or one a pair of types, row by row (`peratomtypepair`), with the command.
    props: BTreeMap<String, (Vec<f64>, Command)>,
    pair: Option<Pair>,
    walls: Vec<PlaneWall>,
    groups: BTreeMap<String, Group>,
    frozen: Vec<String>,
    integrated: Option<String>,
    steps: u64,
    thermo: Option<u64>,
    lost_ignored: bool,
    exclusions: Vec<(String, String, Command)>,
    meshes: Vec<meshes::MeshFix>,
    regions: BTreeMap<String, insertions::Region>,
    templates: BTreeMap<String, insertions::Template>,
    mixtures: BTreeMap<String, insertions::Mixture>,
    packs: Vec<insertions::Pack>,
}

/// A message about command `c`.
fn at(c: &Command, message: String) -> CaseError {
    CaseError::ParticleFile { path: c.file.clone(), line: c.line, message }
}

/// Where a value of the property `name` must lie, if `v` lies outside (None for properties
/// grainflow does not read, and for values in range).
fn out_of_range(name: &str, v: f64) -> Option<&'static str> {
    let (ok, range) = match name {
        "youngsModulus" | "kn" | "kt" => (v > 0.0, "positive"),
        "poissonsRatio" => (v > -1.0 && v <= 0.5, "in (−1, 0.5]"),
        "coefficientRestitution" => (v > 0.0 && v <= 1.0, "in (0, 1]"),
        "coefficientFriction" | "gamman" | "gammat" => (v >= 0.0, "≥ 0"),
        _ => (true, ""),
    };
    (!ok).then_some(range)
}

fn number(c: &Command, k: usize) -> Result<f64, CaseError> {
    let w = c.words.get(k).ok_or_else(|| at(c, format!("`{}` needs more arguments", c.words.join(" "))))?;
    w.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| at(c, format!("`{w}` (argument {k} of `{}`) is not a number", c.words[0])))
}

impl Translator {
    fn note(&mut self, c: &Command, what: &str) {
        self.notes.push(format!("{}: `{}` {what}", c.at(), c.words.join(" ")));
    }

    fn block(&mut self, c: &Command, why: impl Into<String>) {
        self.blockers.push(at(c, why.into()));
    }

    fn command(&mut self, c: &Command, read: &dyn Fn(&str) -> Result<String, CaseError>) {
        if let Err(e) = self.try_command(c, read) {
            self.blockers.push(e);
        }
    }

    fn try_command(
        &mut self,
        c: &Command,
        read: &dyn Fn(&str) -> Result<String, CaseError>,
    ) -> Result<(), CaseError> {
        let w: Vec<&str> = c.words.iter().map(String::as_str).collect();
        match w[0] {
            "units" if w.get(1) == Some(&"si") => {}
            "units" => self.block(c, format!("`units {}`: grainflow reads scripts in `units si` only", w[1..].join(" "))),
            "atom_style" if matches!(w.get(1), Some(&"granular") | Some(&"sphere")) => {}
            "atom_style" => self.block(c, "grainflow's particles are spheres: `atom_style granular` or `sphere`"),
            "boundary" if w.len() == 4 => {
                self.boundary = Some([w[1].to_string(), w[2].to_string(), w[3].to_string()]);
            }
            "newton" | "communicate" | "comm_modify" | "processors" | "atom_modify" => {
                self.note(c, "is about LIGGGHTS's processes and memory: grainflow's results do not depend on it (ignored)")
            }
            "soft_particles" | "hard_particles" => {
                self.note(c, "only lifts LIGGGHTS's bound on Young's modulus (ignored; grainflow checks its own bounds)")
            }
            "compute" | "thermo_style" => {
                self.note(c, "is thermo output: grainflow writes its own time series (timeseries.csv; ignored)")
            }
            "thermo_modify" => {
                self.lost_ignored |= w.windows(2).any(|p| p == ["lost", "ignore"]);
                self.note(c, "formats thermo output (ignored; `lost ignore` removes particles that leave the box)");
            }
            "thermo" => self.thermo = Some(number(c, 1)? as u64),
            "timestep" => self.dt = Some(number(c, 1)?),
            "neighbor" => {
                self.skin = Some(number(c, 1)?);
                if w.get(2).is_some_and(|s| *s != "bin") {
                    self.note(c, "asks for another neighbour method: grainflow bins (the skin is kept)");
                }
            }
            "neigh_modify" => self.neigh_modify(c),
            "read_data" => self.read_data(c, read)?,
            "group" => self.group(c),
            "pair_style" => self.pair_style(c),
            "pair_coeff" if w.get(1) == Some(&"*") && w.get(2) == Some(&"*") && w.len() == 3 => {}
            "pair_coeff" => self.block(c, "granular pair coefficients come from `fix property/global`: write `pair_coeff * *`"),
            "fix" => self.fix(c)?,
            "unfix" if w.len() == 2 && (self.unfix_motion(w[1]) || self.unfix_pack(w[1])) => {}
            "region" => self.region(c)?,
            "create_box" => self.create_box(c)?,
            "unfix" => self.block(c, "only a `move/mesh` can be unfixed so far (a fix that ends between runs is not yet translated)"),
            "print" | "echo" | "log" => self.note(c, "is screen or log output (ignored)"),
            "run" => {
                let n = number(c, 1)?;
                if n < 0.0 || n.fract() != 0.0 {
                    return Err(at(c, format!("`run {}`: the step count must be a whole number ≥ 0", w[1])));
                }
                if w.get(2) == Some(&"upto") {
                    self.steps = self.steps.max(n as u64);
                } else if w.len() > 2 {
                    self.block(c, format!("`run` options `{}` are not read", w[2..].join(" ")));
                } else {
                    self.steps += n as u64;
                }
            }
            other => self.block(c, format!("`{other}` is not translated (docs/liggghts-scripts.md lists the commands that are)")),
        }
        Ok(())
    }

    fn neigh_modify(&mut self, c: &Command) {
        let w = &c.words;
        let (mut k, mut tuned) = (1, false);
        while k < w.len() {
            match w[k].as_str() {
                "delay" | "every" | "check" | "one" | "page" => {
                    tuned = true;
                    k += 2;
                }
                "exclude" if w.get(k + 1).map(String::as_str) == Some("group") && k + 3 < w.len() => {
                    // Checked at the end: only between held particles, whose forces move nothing.
                    self.exclusions.push((w[k + 2].clone(), w[k + 3].clone(), c.clone()));
                    k += 4;
                }
                _ => {
                    self.block(c, format!("`neigh_modify {}` is not read", w[k]));
                    return;
                }
            }
        }
        if tuned {
            self.note(c, "tunes LIGGGHTS's neighbour lists (grainflow rebuilds its own when a particle has moved half the skin)");
        } else {
            self.note(c, "leaves out pairs of held particles, as grainflow always does (they move nothing)");
        }
    }

    fn read_data(
        &mut self,
        c: &Command,
        read: &dyn Fn(&str) -> Result<String, CaseError>,
    ) -> Result<(), CaseError> {
        let file = c.words.get(1).ok_or_else(|| at(c, "`read_data` needs a file".into()))?.clone();
        if c.words.len() > 2 {
            self.block(c, format!("`read_data` options `{}` are not read", c.words[2..].join(" ")));
        }
        let text = read(&file).map_err(|e| at(c, format!("`read_data {file}`: {e}")))?;
        let (lo, hi) = crate::lammps::box_bounds(&text)
            .ok_or_else(|| at(c, format!("{file}: the header does not give xlo xhi, ylo yhi and zlo zhi")))?;
        let mut data =
            Data { file: file.clone(), lo: lo.to_array(), hi: hi.to_array(), ..Default::default() };
        let mut in_atoms = false;
        for (k, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if line.starts_with(|ch: char| ch.is_ascii_alphabetic()) {
                in_atoms = line.starts_with("Atoms");
                continue;
            }
            if !in_atoms {
                continue;
            }
            let f: Vec<&str> = line.split_whitespace().collect();
            let bad = || CaseError::ParticleFile {
                path: file.clone(),
                line: k + 1,
                message: "an atom line of `atom_style granular` is `id type diameter density x y z`".into(),
            };
            if f.len() < 7 {
                return Err(bad());
            }
            let (id, ty): (u32, usize) = (f[0].parse().map_err(|_| bad())?, f[1].parse().map_err(|_| bad())?);
            let (d, rho): (f64, f64) = (f[2].parse().map_err(|_| bad())?, f[3].parse().map_err(|_| bad())?);
            if ty == 0 || ty > 64 {
                return Err(at(
                    c,
                    format!("{file}, line {}: atom type {ty}: grainflow reads types 1 to 64", k + 1),
                ));
            }
            if data.first_of_type.len() < ty {
                data.first_of_type.resize(ty, None);
            }
            data.first_of_type[ty - 1].get_or_insert((d, rho));
            data.atoms.push((id, ty));
        }
        if data.atoms.is_empty() {
            return Err(at(c, format!("{file}: no Atoms section with atoms")));
        }
        self.data = Some(data);
        Ok(())
    }

    fn group(&mut self, c: &Command) {
        let w: Vec<&str> = c.words.iter().map(String::as_str).collect();
        let types = match (w.get(2).copied(), w.len()) {
            (Some("type"), n) if n > 3 => {
                w[3..].iter().map(|t| t.parse::<usize>().ok()).collect::<Option<Vec<_>>>()
            }
            (Some("subtract"), 5) => match (self.types_of(w[3]), self.types_of(w[4])) {
                (Some(a), Some(b)) => Some(a.into_iter().filter(|t| !b.contains(t)).collect()),
                _ => None,
            },
            _ => None,
        };
        match types {
            Some(t) => {
                self.groups.insert(w[1].to_string(), Some(t));
            }
            None => self.block(c, "grainflow reads groups by atom type (`group NAME type 1 2`) and `subtract` of them, after `read_data`"),
        }
    }

    /// The atom types of group `g` (every type for `all`).
    fn types_of(&self, g: &str) -> Option<Vec<usize>> {
        let n = self.data.as_ref().map_or(0, |d| d.first_of_type.len());
        if g == "all" { Some((1..=n).collect()) } else { self.groups.get(g).cloned().flatten() }
    }

    /// `pair_style gran model M tangential T [option on|off]…`, or the same words of a wall.
    fn contact_words(&mut self, c: &Command, words: &[String]) -> Option<Pair> {
        let mut pair = Pair {
            model: String::new(),
            tangential: String::new(),
            tangential_damping: true,
            limit_force: false,
        };
        let mut k = 0;
        while k + 1 < words.len() {
            let (key, v) = (words[k].as_str(), words[k + 1].as_str());
            match key {
                "model" => pair.model = v.to_string(),
                "tangential" => pair.tangential = v.to_string(),
                "tangential_damping" | "limitForce" if v == "on" || v == "off" => {
                    if key == "limitForce" {
                        pair.limit_force = v == "on"
                    } else {
                        pair.tangential_damping = v == "on"
                    }
                }
                _ => {
                    self.block(c, format!("`{key} {v}`: grainflow translates `model`, `tangential`, `tangential_damping` and `limitForce` (rolling friction and cohesion are not yet translated)"));
                    return None;
                }
            }
            k += 2;
        }
        if k != words.len() {
            self.block(c, format!("`{}` has no value", words[k]));
            return None;
        }
        if !matches!(pair.model.as_str(), "hertz" | "hooke/stiffness") {
            self.block(
                c,
                format!(
                    "`model {}`: grainflow translates `model hertz` and `model hooke/stiffness`",
                    pair.model
                ),
            );
            return None;
        }
        if pair.tangential != "history" {
            self.block(
                c,
                format!("`tangential {}`: grainflow translates `tangential history`", pair.tangential),
            );
            return None;
        }
        Some(pair)
    }

    fn pair_style(&mut self, c: &Command) {
        if c.words.get(1).map(String::as_str) != Some("gran") {
            self.block(c, "grainflow translates `pair_style gran`");
            return;
        }
        let words = c.words[2..].to_vec();
        if let Some(p) = self.contact_words(c, &words) {
            self.pair = Some(p);
        }
    }

    fn fix(&mut self, c: &Command) -> Result<(), CaseError> {
        let w: Vec<&str> = c.words.iter().map(String::as_str).collect();
        if w.len() < 4 {
            return Err(at(c, "`fix` needs an id, a group and a style".into()));
        }
        let (group, style) = (w[2], w[3]);
        match style {
            "property/global" => {
                if w.len() < 7 {
                    return Err(at(c, "write `fix ID all property/global NAME STYLE VALUE …`".into()));
                }
                let kind = w.get(5).copied().unwrap_or("");
                let values: Vec<f64> = (6..w.len()).map(|k| number(c, k)).collect::<Result<_, _>>()?;
                let values = match kind {
                    "scalar" if values.len() == 1 => values,
                    "scalar" => return Err(at(c, format!("`property/global {} scalar` takes one value, not {}", w[4], values.len()))),
                    "peratomtype" => values,
                    "peratomtypepair" if !values.is_empty() => {
                        let n = values[0] as usize;
                        if values.len() != 1 + n * n {
                            return Err(at(c, format!("`peratomtypepair {n}` needs {} values, not {}", n * n, values.len() - 1)));
                        }
                        values[1..].to_vec()
                    }
                    _ => return Err(at(c, format!("`property/global {} {kind}`: grainflow reads scalar, peratomtype and peratomtypepair values", w[4]))),
                };
                if let Some((v, range)) = values.iter().find_map(|&v| out_of_range(w[4], v).map(|r| (v, r))) {
                    return Err(at(c, format!("`property/global {}`: the value {v} must be {range}", w[4])));
                }
                self.props.insert(w[4].to_string(), (values, c.clone()));
            }
            "gravity" if w.len() == 9 && w[5] == "vector" => {
                let g = number(c, 4)?;
                let v = [number(c, 6)?, number(c, 7)?, number(c, 8)?];
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if len == 0.0 {
                    return Err(at(c, "the gravity vector is zero".into()));
                }
                self.gravity = Some(v.map(|x| g * x / len));
            }
            "mesh/surface" | "mesh/surface/stress" => {
                if style == "mesh/surface/stress" {
                    self.note(c, "writes mesh stresses, which are not yet translated (the mesh is)");
                }
                self.mesh_surface(c)?;
            }
            "move/mesh" => self.move_mesh(c)?,
            "particletemplate/sphere" => self.template(c)?,
            s if s.starts_with("particledistribution/discrete") => self.mixture(c, s)?,
            "insert/pack" => self.insert_pack(c, group)?,
            "nve/sphere" if w.len() == 4 => self.integrated = Some(group.to_string()),
            "freeze" if w.len() == 4 => self.frozen.push(group.to_string()),
            "wall/gran" => self.wall(c, group)?,
            _ => self.block(c, format!("`fix {style}` (or these options of it) is not translated (docs/liggghts-scripts.md lists what is)")),
        }
        Ok(())
    }

    fn wall(&mut self, c: &Command, group: &str) -> Result<(), CaseError> {
        let w = &c.words;
        // Looked for after the style, so that a fix named `primitive` or `mesh` is not taken.
        let after_style = |word: &str| w.iter().skip(4).position(|x| x == word).map(|k| k + 4);
        let p = after_style("primitive");
        if group != "all" {
            self.block(c, "a wall acting on a group only is not translated: walls act on every particle");
        }
        let Some(p) = p else {
            let Some(m) = after_style("mesh") else {
                self.block(
                    c,
                    "write `… primitive type T xplane|yplane|zplane C` or `… mesh n_meshes N meshes ID …`",
                );
                return Ok(());
            };
            let law = w[4..m].to_vec();
            let Some(law) = self.contact_words(c, &law) else { return Ok(()) };
            if self.pair.as_ref().is_some_and(|pair| *pair != law) {
                self.block(c, "the wall's contact model differs from `pair_style`'s: grainflow has one law for pairs and walls");
            }
            return self.mesh_walls(c, m);
        };
        let law = w[4..p].to_vec();
        let Some(law) = self.contact_words(c, &law) else { return Ok(()) };
        if self.pair.as_ref().is_some_and(|pair| *pair != law) {
            self.block(c, "the wall's contact model differs from `pair_style`'s: grainflow has one law for pairs and walls");
        }
        let (ty, kind) = (w.get(p + 1).map(String::as_str), w.get(p + 3).map(String::as_str));
        let axis = match kind {
            Some("xplane") => 0,
            Some("yplane") => 1,
            Some("zplane") => 2,
            _ => {
                self.block(
                    c,
                    format!(
                        "`primitive … {}`: grainflow translates xplane, yplane and zplane",
                        kind.unwrap_or("")
                    ),
                );
                return Ok(());
            }
        };
        if ty != Some("type") || w.len() != p + 5 {
            return Err(at(c, "write `primitive type T xplane|yplane|zplane POSITION`".into()));
        }
        let wall_type = number(c, p + 2)? as usize;
        self.walls.push(PlaneWall { axis, at: number(c, p + 4)?, wall_type });
        Ok(())
    }

    /// One value of property `name` for the type pair (a, b) (1-based), given per type or
    /// per type pair.
    fn prop(&self, name: &str, a: usize, b: usize) -> Option<f64> {
        let (v, c) = self.props.get(name)?;
        let n = self.data.as_ref().map_or(1, |d| d.first_of_type.len()).max(a).max(b);
        match (c.words.get(5).map(String::as_str), v.len()) {
            (Some("scalar"), 1) => Some(v[0]),
            (Some("peratomtype"), l) if l == n => Some(v[a - 1]),
            (Some("peratomtypepair"), l) if l == n * n => Some(v[(a - 1) * n + (b - 1)]),
            _ => None,
        }
    }

    /// Property `name` for every pair of `types`, if it is one value for all of them.
    fn uniform(&mut self, name: &str, types: &[usize], others: &[usize]) -> Result<Option<f64>, CaseError> {
        let mut seen: Option<f64> = None;
        for &a in types {
            for &b in others {
                let Some(v) = self.prop(name, a, b) else {
                    return match self.props.get(name) {
                        Some((v, c)) => Err(at(
                            c,
                            format!(
                                "`property/global {name}`: {} values do not fit the {} atom types of the data file (peratomtype: one a type; peratomtypepair N: N×N)",
                                v.len(),
                                types.len()
                            ),
                        )),
                        None => Ok(None),
                    };
                };
                if seen.is_some_and(|s| s != v) {
                    let c = &self.props[name].1;
                    return Err(at(
                        c,
                        format!(
                            "`property/global {name}`: values that differ between atom types are not yet translated"
                        ),
                    ));
                }
                seen = Some(v);
            }
        }
        Ok(seen)
    }

    fn finish(&mut self, origin: &str) -> Result<RawCase, CaseError> {
        // Errors that name a line name the script already.
        let whole = |e: CaseError| match e {
            CaseError::ParticleFile { .. } => e,
            e => CaseError::Syntax(format!("{origin}: {e}")),
        };
        self.template_phases();
        let Some(data) = self.data.clone() else {
            self.blockers.push(CaseError::Syntax(format!(
                "{origin}: no `read_data` or `create_box`: there is no box"
            )));
            return Err(CaseError::Blockers(std::mem::take(&mut self.blockers)));
        };
        let types: Vec<usize> = (1..=data.first_of_type.len()).collect();
        let n = types.len();
        for (name, (v, c)) in &self.props {
            let (kind, want) = match c.words.get(5).map(String::as_str) {
                Some("peratomtype") => ("peratomtype", n),
                Some("peratomtypepair") => ("peratomtypepair", n * n),
                _ => ("scalar", 1),
            };
            if v.len() != want {
                let e = format!(
                    "`property/global {name} {kind}`: {} values for the {n} atom types of the data file, which need {want}",
                    v.len()
                );
                self.blockers.push(at(c, e));
            }
        }
        let contact = self.contact(&types).map_err(whole);
        let contact = match contact {
            Ok(c) => Some(c),
            Err(e) => {
                self.blockers.push(e);
                None
            }
        };
        let held = self.held(&types);
        if let Some(p) = self.packs.iter().find(|p| {
            let m = &self.mixtures[&p.mixture];
            m.parts.iter().any(|(t, _)| held.contains(&self.templates[t].atom_type))
        }) {
            let e = at(&p.command, "particles inserted of a type that is frozen or not integrated are not translated (held particles are named by id)".into());
            self.blockers.push(e);
        }
        for (a, b, c) in std::mem::take(&mut self.exclusions) {
            let holds = |g: &str| self.types_of(g).is_some_and(|t| t.iter().all(|x| held.contains(x)));
            if !(holds(&a) && holds(&b)) {
                self.blockers.push(at(
                    &c,
                    format!(
                        "`exclude group {a} {b}`: grainflow excludes contacts only between held particles"
                    ),
                ));
            }
        }
        if !self.blockers.is_empty() {
            return Err(CaseError::Blockers(std::mem::take(&mut self.blockers)));
        }
        let contact = contact.expect("no blockers");
        let boundary = self.boundary.clone().unwrap_or_else(|| ["p".into(), "p".into(), "p".into()]);
        let (mut lo, mut hi) = (data.lo, data.hi);
        let mut periodic = Vec::new();
        for (k, b) in boundary.iter().enumerate() {
            let axis = ["x", "y", "z"][k];
            if b == "p" {
                periodic.push(axis.to_string());
                continue;
            }
            // A shrink-wrapped bound follows the particles in LIGGGHTS: room for them to go.
            let span = hi[k] - lo[k];
            let (low, high) = (
                b.chars().next().unwrap_or('f'),
                b.chars().nth(1).unwrap_or(b.chars().next().unwrap_or('f')),
            );
            if matches!(low, 's' | 'm') {
                lo[k] -= span;
            }
            if matches!(high, 's' | 'm') {
                hi[k] += span;
            }
        }
        let centre: Vec<f64> = (0..3).map(|k| 0.5 * (data.lo[k] + data.hi[k])).collect();
        // LIGGGHTS's defaults in SI units (its `units si`): 1e-8 s and a skin of 1 mm.
        let dt = self.dt.unwrap_or(1e-8);
        if self.dt.is_none() {
            self.notes.push(format!("{origin}: no `timestep`: LIGGGHTS's default in SI units, 1e-8 s"));
        }
        if self.steps == 0 {
            self.blockers
                .push(CaseError::Syntax(format!("{origin}: no `run` with steps: there is nothing to run")));
        }
        let mut phases = Vec::new();
        for &t in &types {
            let (d, rho) = data.first_of_type[t - 1].unwrap_or((f64::NAN, f64::NAN));
            let own = |name: &str| self.prop(name, t, t);
            phases.push(RawPhase {
                name: Some(format!("type{t}")),
                diameter: d.is_finite().then_some(d),
                density: rho.is_finite().then_some(rho),
                youngs_modulus: own("youngsModulus"),
                poisson_ratio: own("poissonsRatio"),
            });
        }
        let meshes = self.raw_meshes(dt);
        for m in self.meshes.iter().filter(|m| !m.wall) {
            self.notes.push(format!(
                "{origin}: mesh `{}` is not a wall (no `wall/gran … meshes {}`): left out",
                m.id, m.id
            ));
        }
        let wall_types: Vec<usize> = {
            let mut v: Vec<usize> = self.walls.iter().map(|w| w.wall_type).collect();
            v.extend(self.meshes.iter().filter(|m| m.wall).map(|m| m.wall_type));
            v.sort_unstable();
            v.dedup();
            v
        };
        let wall_materials = wall_types
            .iter()
            .map(|&t| RawWallMaterial {
                name: Some(format!("type{t}")),
                youngs_modulus: self.prop("youngsModulus", t, t),
                poisson_ratio: self.prop("poissonsRatio", t, t),
            })
            .collect();
        let walls = self
            .walls
            .iter()
            .enumerate()
            .map(|(k, w)| {
                let mut point = [0.0; 3];
                point[w.axis] = w.at;
                let mut normal = [0.0; 3];
                normal[w.axis] = if centre[w.axis] >= w.at { 1.0 } else { -1.0 };
                RawWall {
                    name: Some(format!("wall{}", k + 1)),
                    point: Some(point),
                    normal: Some(normal),
                    material: Some(format!("type{}", w.wall_type)),
                }
            })
            .collect();
        let motion = self.hold_rules(&data, &held);
        let interval = self.thermo.filter(|&n| n > 0).unwrap_or(self.steps.max(1)) as f64 * dt;
        Ok(RawCase {
            version: Some(crate::case::CASE_VERSION),
            title: format!("LIGGGHTS script {origin}"),
            domain: Some(RawDomain {
                min: Some(lo),
                max: Some(hi),
                walls: WallSelection::All(false),
                periodic: (!periodic.is_empty()).then_some(periodic),
                wall_material: None,
                leaving: Some(if self.lost_ignored { "remove" } else { "stop" }.into()),
            }),
            physics: RawPhysics { gravity: Some(self.gravity.unwrap_or([0.0; 3])) },
            phases,
            wall_materials,
            walls,
            meshes,
            cylinders: Vec::new(),
            contact: Some(contact),
            time: Some(RawTime {
                t_stop: Some(self.steps as f64 * dt),
                t_start: None,
                dt: Some(dt),
                dtsolid_factor: None,
                integrator: Some("velocity_verlet".into()),
                force_dt: None,
            }),
            neighbor: RawNeighbor { skin: Some(self.skin.unwrap_or(0.001)) },
            output: RawOutput { interval: Some(interval), snapshots: Some(false), ..Default::default() },
            parallel: Default::default(),
            particles: (!data.file.is_empty()).then(|| RawParticles {
                file: Some(data.file.clone()),
                // States written mid-flow by another code can hold overlaps of a few per cent.
                max_initial_overlap: Some(0.5),
                ..Default::default()
            }),
            motion,
            insertions: self.raw_insertions(dt),
            outlets: Vec::new(),
        })
    }

    /// The types held still: frozen, or outside the integrated group.
    fn held(&mut self, types: &[usize]) -> Vec<usize> {
        let mut held: Vec<usize> = Vec::new();
        for g in self.frozen.clone() {
            match self.types_of(&g) {
                Some(t) => held.extend(t),
                None => self
                    .blockers
                    .push(CaseError::Syntax(format!("`fix freeze` of group `{g}`, which is not defined"))),
            }
        }
        match self.integrated.clone() {
            None => self.blockers.push(CaseError::Syntax("no `fix nve/sphere`: nothing would move".into())),
            Some(g) => match self.types_of(&g) {
                Some(moving) => held.extend(types.iter().filter(|t| !moving.contains(t))),
                None => self.blockers.push(CaseError::Syntax(format!(
                    "`fix nve/sphere` of group `{g}`, which is not defined"
                ))),
            },
        }
        held.sort_unstable();
        held.dedup();
        held
    }

    /// `[[motion]] rule = "hold"` for the ids of the held types, as ranges.
    fn hold_rules(&self, data: &Data, held: &[usize]) -> Vec<RawMotion> {
        let mut ids: Vec<u32> =
            data.atoms.iter().filter(|(_, t)| held.contains(t)).map(|(id, _)| *id).collect();
        ids.sort_unstable();
        let mut ranges: Vec<IdSelection> = Vec::new();
        let mut k = 0;
        while k < ids.len() {
            let start = ids[k];
            while k + 1 < ids.len() && ids[k + 1] == ids[k] + 1 {
                k += 1;
            }
            ranges.push(if ids[k] == start {
                IdSelection::One(start)
            } else {
                IdSelection::Range([start, ids[k]])
            });
            k += 1;
        }
        ranges
            .into_iter()
            .map(|r| RawMotion {
                particles: Some(r),
                rule: Some("hold".into()),
                leader: None,
                leader_offset: None,
                axes: None,
            })
            .collect()
    }

    /// `[contact]` from `pair_style gran` and the properties.
    fn contact(&mut self, types: &[usize]) -> Result<RawContact, CaseError> {
        let pair = self.pair.clone().ok_or_else(|| CaseError::Syntax("no `pair_style gran`".into()))?;
        let walls: Vec<usize> = self
            .walls
            .iter()
            .map(|w| w.wall_type)
            .chain(self.meshes.iter().filter(|m| m.wall).map(|m| m.wall_type))
            .collect();
        let need = |this: &mut Self, name: &str, with: &[usize]| -> Result<f64, CaseError> {
            this.uniform(name, types, with)?.ok_or_else(|| {
                CaseError::Syntax(format!(
                    "`fix property/global {name}` is required by `model {}`",
                    pair.model
                ))
            })
        };
        let mut particle =
            RawContactParams { mu: Some(need(self, "coefficientFriction", types)?), ..Default::default() };
        let mut wall = RawContactParams::default();
        if !walls.is_empty() {
            wall.mu = Some(need(self, "coefficientFriction", &walls)?);
        }
        let hertz = pair.model == "hertz";
        for (t, with) in [(&mut particle, types.to_vec()), (&mut wall, walls.clone())] {
            if with.is_empty() {
                continue;
            }
            if hertz {
                t.en = Some(need(self, "coefficientRestitution", &with)?);
                t.etat_fac = Some(if pair.tangential_damping { 1.0 } else { 0.0 });
            } else {
                let kn = need(self, "kn", &with)?;
                t.kn = Some(kn);
                t.kt_fac = Some(need(self, "kt", &with)? / kn);
                t.gamma_n = Some(need(self, "gamman", &with)?);
                t.gamma_t = Some(if pair.tangential_damping { need(self, "gammat", &with)? } else { 0.0 });
            }
        }
        Ok(RawContact {
            model: Some(if hertz { "hertz" } else { "lsd" }.into()),
            tangential: Some("mfix".into()),
            history: Some("liggghts".into()),
            lever_arm: Some("liggghts".into()),
            damping: Some(if hertz { "liggghts" } else { "mass_velocity" }.into()),
            clip_attraction: Some(pair.limit_force),
            coulomb: Some("liggghts".into()),
            sizes: Some("own".into()),
            particle,
            wall,
            pairs: Vec::new(),
            walls: Vec::new(),
        })
    }
}

/// The TOML of a translated script, with its notes as comments.
pub fn to_toml(raw: &RawCase, origin: &str, notes: &[String]) -> Result<String, CaseError> {
    let what = format!("the LIGGGHTS script {origin}");
    crate::mfix::translated_toml(raw, &what, "docs/liggghts-scripts.md", "script", notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A data file of two spheres of type 1 and one of type 2 (`atom_style granular`).
    const DATA: &str = "LIGGGHTS data\n\n3 atoms\n2 atom types\n\n0 0.04 xlo xhi\n0 0.04 ylo yhi\n0 0.02 zlo zhi\n\nAtoms\n\n1 1 0.002 2500 0.01 0.01 0.001\n2 1 0.002 2500 0.02 0.01 0.001\n3 2 0.002 2500 0.03 0.01 0.001\n";

    fn translated(script: &str, vars: &[(&str, &str)]) -> Result<ScriptCase, CaseError> {
        let vars: Vec<(String, String)> = vars.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        let read = |name: &str| -> Result<String, CaseError> {
            match name {
                "bed.data" => Ok(DATA.into()),
                "plate.stl" => Ok(PLATE.into()),
                _ => Err(CaseError::Syntax(format!("no file {name}"))),
            }
        };
        translate(script, "in.test", &vars, &read, &input::open_text(&read))
    }

    const HERTZ: &str = "variable nrun index 2000\natom_style granular\nboundary f f fm\nnewton off\nunits si\nread_data bed.data\nneighbor 0.0002 bin\nneigh_modify delay 0\nsoft_particles yes\nfix m1 all property/global youngsModulus peratomtype 5.0e6 5.0e6\nfix m2 all property/global poissonsRatio peratomtype 0.3 0.3\nfix m3 all property/global coefficientRestitution peratomtypepair 2 0.9 0.9 0.9 0.9\nfix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5\npair_style gran model hertz tangential history\npair_coeff * *\nfix wz all wall/gran model hertz tangential history primitive type 1 zplane 0.0\nfix wx all wall/gran model hertz tangential history primitive type 1 xplane 0.04\ntimestep 2.0e-5\nfix grav all gravity 9.81 vector 0.0 0.0 -2.0\ngroup base type 2\ngroup moving subtract all base\nfix integ moving nve/sphere\nthermo 100\nrun ${nrun}\nrun 500\n";

    #[test]
    fn a_hertz_box_script_becomes_the_case_it_means() {
        let s = translated(HERTZ, &[("nrun", "1000")]).expect("translates");
        let r = &s.raw;
        let c = r.contact.as_ref().unwrap();
        assert_eq!(c.model.as_deref(), Some("hertz"));
        assert_eq!(c.damping.as_deref(), Some("liggghts"));
        assert_eq!(c.coulomb.as_deref(), Some("liggghts"));
        assert_eq!(c.history.as_deref(), Some("liggghts"));
        assert_eq!(c.lever_arm.as_deref(), Some("liggghts"));
        assert_eq!((c.particle.en, c.particle.mu, c.wall.en), (Some(0.9), Some(0.5), Some(0.9)));
        // Gravity: g times the normalised vector, as `fix gravity` reads it.
        assert_eq!(r.physics.gravity, Some([0.0, 0.0, -9.81]));
        // The walls face the particles: z = 0 upwards, x = 0.04 towards −x.
        assert_eq!(r.walls[0].normal, Some([0.0, 0.0, 1.0]));
        assert_eq!((r.walls[1].point, r.walls[1].normal), (Some([0.04, 0.0, 0.0]), Some([-1.0, 0.0, 0.0])));
        // `-var nrun 1000` wins over the index variable; the two runs add up.
        let time = r.time.as_ref().unwrap();
        assert_eq!((time.dt, time.t_stop), (Some(2e-5), Some(1500.0 * 2e-5)));
        assert_eq!(r.output.interval, Some(100.0 * 2e-5));
        // The upper z bound is shrink-wrapped: raised by the box's height.
        let d = r.domain.as_ref().unwrap();
        assert_eq!((d.min, d.max), (Some([0.0, 0.0, 0.0]), Some([0.04, 0.04, 0.04])));
        // Type 2 is outside the integrated group: held.
        assert_eq!(r.motion.len(), 1);
        assert!(matches!(r.motion[0].particles, Some(IdSelection::One(3))));
        assert_eq!(s.case.particles.len(), 3);
        assert!(s.notes.iter().any(|n| n.contains("line 4") && n.contains("newton off")));
    }

    /// A 40 mm square in the file's xy plane, in millimetres.
    const PLATE: &str = "solid plate\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 40 0 0\nvertex 40 40 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 40 40 0\nvertex 0 40 0\nendloop\nendfacet\nendsolid plate\n";

    /// A mesh placed as LIGGGHTS places it (in the order written: scale, rotate, move), made
    /// a wall, set turning after the first run and stopped by `unfix` after the second.
    #[test]
    fn a_mesh_wall_its_placement_and_its_timed_motion() {
        let script = HERTZ.replace(
            "thermo 100\nrun ${nrun}\nrun 500\n",
            "fix plate all mesh/surface file plate.stl type 1 scale 0.001 rotate axis 0 0 1 angle 90 move 0.04 0 0.01\n\
             fix pw all wall/gran model hertz tangential history mesh n_meshes 1 meshes plate\n\
             run 1000\nfix spin all move/mesh mesh plate rotate origin 0.02 0.02 0.01 axis 0 0 1 period 2\n\
             run 500\nunfix spin\nrun 100\n",
        );
        let s = translated(&script, &[]).expect("translates");
        let m = &s.raw.meshes[0];
        assert_eq!(
            (m.file.as_deref(), m.material.as_deref(), m.scale),
            (Some("plate.stl"), Some("type1"), Some(0.001))
        );
        // LIGGGHTS turns degrees into radians with π = 3.14159265.
        assert_eq!(m.rotate, Some([0.0, 0.0, 90.0 * meshes::LIGGGHTS_PI / std::f64::consts::PI]));
        assert_eq!(m.translate, Some([0.04, 0.0, 0.01]));
        let motion = m.motion.as_ref().expect("a motion");
        assert_eq!((motion.kind.as_deref(), motion.omega), (Some("rotate"), Some(std::f64::consts::PI)));
        assert_eq!((motion.origin, motion.axis), (Some([0.02, 0.02, 0.01]), Some([0.0, 0.0, 1.0])));
        assert_eq!((motion.start, motion.stop), (Some(1000.0 * 2e-5), Some(1500.0 * 2e-5)));
        assert_eq!(s.case.config.meshes.len(), 1);
        // A placement out of grainflow's order, and a mesh no wall names, are told.
        let bad = script.replace(
            "scale 0.001 rotate axis 0 0 1 angle 90 move 0.04 0 0.01",
            "move 0.04 0 0.01 scale 0.001",
        );
        let e = translated(&bad, &[]).unwrap_err().to_string();
        assert!(e.contains("`scale` after") && e.contains("line 23"), "{e}");
        assert!(!e.contains("no `fix plate"), "{e}");
        // `wiggle`: LIGGGHTS's oscillation, A·sin(2πt/T) from where the fix is defined.
        let wiggle = script.replace(
            "rotate origin 0.02 0.02 0.01 axis 0 0 1 period 2",
            "wiggle amplitude 0 0 0.002 period 0.5",
        );
        let s = translated(&wiggle, &[]).expect("translates");
        let motion = s.raw.meshes[0].motion.as_ref().expect("a motion");
        assert_eq!(
            (motion.kind.as_deref(), motion.amplitude, motion.frequency),
            (Some("oscillate"), Some([0.0, 0.0, 0.002]), Some(2.0))
        );
        assert_eq!(motion.start, Some(1000.0 * 2e-5));
        let apart = script.replace(
            "meshes plate\n",
            "meshes plate\nfix face all mesh/surface file plate.stl type 1 scale 0.001\n",
        );
        let s = translated(&apart, &[]).expect("translates");
        assert!(s.notes.iter().any(|n| n.contains("mesh `face` is not a wall")), "{:?}", s.notes);
    }

    /// Particles made by the script: a box from a region, a mixture of three templates of two
    /// types by mass, and `insert/pack … insert_every once` into a cylinder, unfixed after its
    /// run of one step.
    #[test]
    fn a_packed_insertion_from_templates_and_a_mixture() {
        let script = "atom_style granular\nboundary f f f\nunits si\n\
            region box block -0.052 0.052 -0.022 0.022 -0.052 0.052 units box\ncreate_box 2 box\n\
            fix m1 all property/global youngsModulus peratomtype 5.0e6 5.0e6\n\
            fix m2 all property/global poissonsRatio peratomtype 0.3 0.3\n\
            fix m3 all property/global coefficientRestitution peratomtypepair 2 0.9 0.9 0.9 0.9\n\
            fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5\n\
            pair_style gran model hertz tangential history\npair_coeff * *\ntimestep 2e-5\n\
            fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 2500 radius constant 0.001\n\
            fix pts2 all particletemplate/sphere 15485867 atom_type 1 density constant 2500 radius constant 0.0015\n\
            fix pts3 all particletemplate/sphere 15485869 atom_type 2 density constant 4000 radius constant 0.001\n\
            fix pdd all particledistribution/discrete 15485871 3 pts1 0.3 pts2 0.5 pts3 0.2\n\
            region insreg cylinder y 0.0 0.0 0.046 -0.018 0.018 units box\n\
            fix ins all insert/pack seed 32452843 distributiontemplate pdd insert_every once &\n\
              overlapcheck yes all_in yes maxattempt 500 verbose no vel constant 0.0 0.0 -0.5 &\n\
              particles_in_region 500 region insreg\n\
            fix integ all nve/sphere\nrun 1\nunfix ins\nrun 999\n";
        let s = translated(script, &[]).expect("translates");
        let r = &s.raw;
        let d = r.domain.as_ref().unwrap();
        assert_eq!((d.min, d.max), (Some([-0.052, -0.022, -0.052]), Some([0.052, 0.022, 0.052])));
        assert!(r.particles.is_none(), "no particles before the insertion");
        assert_eq!((r.phases[0].diameter, r.phases[0].density), (Some(0.002), Some(2500.0)));
        assert_eq!((r.phases[1].diameter, r.phases[1].density), (Some(0.002), Some(4000.0)));
        let ins = &r.insertions[0];
        assert_eq!(
            (ins.count, ins.at, ins.velocity, ins.seed),
            (Some(500), None, Some([0.0, 0.0, -0.5]), Some(32452843))
        );
        assert_eq!(ins.fractions_by.as_deref(), Some("mass"));
        let reg = ins.region.as_ref().unwrap();
        assert_eq!(
            (reg.kind.as_deref(), reg.base, reg.axis),
            (Some("cylinder"), Some([0.0, -0.018, 0.0]), Some([0.0, 1.0, 0.0]))
        );
        assert_eq!((reg.length, reg.radius), (Some(0.036), Some(0.046)));
        // Type 1: 0.3 + 0.5 of the mass, in two sizes by mass; type 2: 0.2, one size.
        let (a, b) = (&ins.phases[0], &ins.phases[1]);
        let (total, one) = (0.3 + 0.5 + 0.2, 0.3 + 0.5);
        assert_eq!(
            (a.phase.as_deref(), a.fraction, a.distribution.as_deref()),
            (Some("type1"), Some(one / total), Some("table"))
        );
        assert_eq!(
            (a.diameters.clone(), a.weights.clone()),
            (Some(vec![0.002, 0.003]), Some(vec![0.3 / one, 0.5 / one]))
        );
        assert_eq!(a.weights_by.as_deref(), Some("mass"));
        assert_eq!(
            (b.phase.as_deref(), b.fraction, b.diameter),
            (Some("type2"), Some(0.2 / total), Some(0.002))
        );
        assert_eq!(r.time.as_ref().unwrap().t_stop, Some(1000.0 * 2e-5));
        assert_eq!(s.case.config.insertions.len(), 1);
        // Repeated filling is not translated yet, and is told.
        let again = script.replace("insert_every once", "insert_every 1000");
        let e = translated(&again, &[]).unwrap_err().to_string();
        assert!(e.contains("insert_every") && e.contains("line 18"), "{e}");
    }

    #[test]
    fn every_blocker_is_listed_with_its_line() {
        let bad = HERTZ.replace("units si", "units lj").replace(
            "thermo 100",
            "fix m all mesh/surface file a.stl type 1 wear finnie\ncreate_atoms 1 single 0 0 0",
        ) + "fix ins all insert/pack seed 1\n";
        let e = translated(&bad, &[]).unwrap_err().to_string();
        for want in ["line 5", "units si", "mesh/surface", "create_atoms", "insert/pack"] {
            assert!(e.contains(want), "`{want}` missing from:\n{e}");
        }
        // A wall law other than the pair's, and per-type values that differ.
        let bad = HERTZ
            .replace("zplane 0.0", "zplane 0.0\nfix w2 all wall/gran model hooke/stiffness tangential history primitive type 1 yplane 0.0")
            .replace("coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5", "coefficientFriction peratomtypepair 2 0.5 0.4 0.4 0.5");
        let e = translated(&bad, &[]).unwrap_err().to_string();
        assert!(e.contains("differs from `pair_style`"), "{e}");
        assert!(e.contains("coefficientFriction") && e.contains("differ"), "{e}");
    }
}
