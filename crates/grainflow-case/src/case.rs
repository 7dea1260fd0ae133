//! From a raw case file to a validated [`Case`]: SI values, engine objects, cross-field checks.

use crate::error::CaseError;
use crate::input;
use crate::particles;
use crate::raw::*;
use crate::set::SetOverride;
use grainflow::contact::coefficients::{MAX_PHASES, MAX_WALL_MATERIALS};
use grainflow::contact::limits::{self, Range};
use grainflow::contact::{
    ContactLaw, ContactParams, ContactSizes, CoulombCap, HistoryFrame, LeverArm, NormalDamping, NormalModel,
    TangentialModel,
};
use grainflow::mesh::{
    KeyFrames, Mesh, MeshError, MeshMotion, MeshTransform, MeshWall, MotionWindow, SurfaceMotion,
    TriangleGrid, closest_point_on_triangle,
};
use grainflow::simulation::STANDARD_GRAVITY;
use grainflow::state::ParticleInit;
use grainflow::{
    Integrator, MotionRule, Particles, Phase, PrescribedMotion, SimulationConfig, TimeStepRule, Vec3, Wall,
    WallMaterial,
};
use std::path::Path;

/// The case-file format version this program reads.
pub const CASE_VERSION: i64 = 1;

/// A validated case, ready to become a [`grainflow::Simulation`].
#[derive(Debug, Clone)]
pub struct Case {
    /// The case's title.
    pub title: String,
    /// Engine configuration.
    pub config: SimulationConfig,
    /// Initial particles.
    pub particles: Particles,
    /// Output settings.
    pub output: OutputSettings,
    /// The domain box (lower and upper corner), m.
    pub domain: (Vec3, Vec3),
    /// SHA-256 of the case text and every file it read, hex: ties outputs and checkpoints to
    /// their inputs.
    pub hash: String,
    /// Things the user should know (e.g. parameters the chosen model does not use).
    pub warnings: Vec<String>,
    /// `[particles] max_overlap`: the largest overlap allowed during the run, as a fraction of
    /// the smaller radius (the run's health check stops a run that exceeds it).
    pub max_overlap: f64,
    /// The mesh walls' names, in the order of `config.meshes`.
    pub mesh_names: Vec<String>,
    /// The point each mesh's torque is reported about in the time series (`torque_about`,
    /// else its rotation axis's origin, else the origin of coordinates), m.
    pub mesh_torque_about: Vec<Vec3>,
}

/// `[output]`, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputSettings {
    /// Interval between outputs, s; `None` = 100 outputs over the run.
    pub interval: Option<f64>,
    /// Write particle snapshots.
    pub snapshots: bool,
    /// Interval between VTK frames, s; `None` = no VTK output.
    pub vtk_interval: Option<f64>,
}

/// Reads and validates a case file; particle files are read relative to its folder.
/// Both are read through [`crate::input`]: regular files only, within its size limits, the
/// particle file streamed.
pub fn load(path: &Path) -> Result<Case, CaseError> {
    let text = input::read_text(path, input::Kind::CaseFile)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let raw = parse_raw(&text, &path.display().to_string())?;
    from_raw_opened(raw, &text, &input::open_beside(&dir))
}

/// [`load`] with `--set` overrides applied to the file's keys before it is validated (see
/// [`SetOverride`]): a key set is validated exactly as if the file said it. The case hash
/// covers the overrides.
pub fn load_with(path: &Path, sets: &[SetOverride]) -> Result<Case, CaseError> {
    if sets.is_empty() {
        return load(path);
    }
    let text = input::read_text(path, input::Kind::CaseFile)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (raw, source) = parse_raw_with(&text, &path.display().to_string(), sets)?;
    from_raw_opened(raw, &source, &input::open_beside(&dir))
}

/// [`parse`] with `--set` overrides (see [`load_with`]).
pub fn parse_with(
    text: &str,
    origin: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
    sets: &[SetOverride],
) -> Result<Case, CaseError> {
    let (raw, source) = parse_raw_with(text, origin, sets)?;
    from_raw(raw, &source, read_file)
}

/// The raw case with the overrides applied, and the text its hash covers: the file's, then
/// each override. The file is read as it is first, so that its own mistakes are reported at
/// their lines; a mistake only the overrides make names them.
fn parse_raw_with(text: &str, origin: &str, sets: &[SetOverride]) -> Result<(RawCase, String), CaseError> {
    use serde::Deserialize;
    parse_raw(text, origin)?;
    let mut table: toml::Table = toml::from_str(input::strip_bom(text))
        .map_err(|e| CaseError::Syntax(did_you_mean(format!("{origin}: {e}"))))?;
    let mut source = text.to_string();
    for set in sets {
        set.apply(&mut table).map_err(CaseError::Syntax)?;
        source.push_str(&format!("\0--set\0{}={}", set.path, set.text));
    }
    let shown: Vec<String> = sets.iter().map(|s| format!("{}={}", s.path, s.text)).collect();
    let raw = RawCase::deserialize(toml::Value::Table(table)).map_err(|e| {
        CaseError::Syntax(did_you_mean(format!(
            "{origin} with --set {}: {}",
            shown.join(" --set "),
            e.to_string().trim_end()
        )))
    })?;
    Ok((raw, source))
}

fn parse_raw(text: &str, origin: &str) -> Result<RawCase, CaseError> {
    toml::from_str(input::strip_bom(text))
        .map_err(|e| CaseError::Syntax(did_you_mean(format!("{origin}: {e}"))))
}

/// Validates case-file text. `origin` names it in messages; `read_file` reads a particle file
/// named in the case.
pub fn parse(
    text: &str,
    origin: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
) -> Result<Case, CaseError> {
    let raw = parse_raw(text, origin)?;
    from_raw(raw, text, read_file)
}

/// Validates a case built in memory rather than read from TOML (an MFIX deck translated by
/// [`crate::mfix`]) exactly as [`parse`] validates a case file. `source` is the text the case
/// was made from: the case hash covers it and every file read through `read_file`.
pub fn from_raw(
    raw: RawCase,
    source: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
) -> Result<Case, CaseError> {
    from_raw_opened(raw, source, &input::open_text(read_file))
}

/// [`from_raw`] with particle files opened as streams.
pub(crate) fn from_raw_opened(
    raw: RawCase,
    source: &str,
    open: &input::Opener<'_>,
) -> Result<Case, CaseError> {
    use sha2::{Digest, Sha256};
    // The hash covers the case text and every file it reads, in the order read: the bytes
    // are hashed as the reader takes them, and a reader that succeeds reads to the end.
    let hasher = std::cell::RefCell::new(Sha256::new());
    hasher.borrow_mut().update(source.as_bytes());
    let hashing_open = |name: &str| {
        let reader = open(name)?;
        let mut h = hasher.borrow_mut();
        h.update(b"\0file\0");
        h.update(name.as_bytes());
        h.update(b"\0");
        drop(h);
        Ok(input::Stream::new(std::io::BufReader::new(Hashing { inner: reader, hasher: &hasher }), name))
    };
    // Mesh files are read whole, as bytes (a binary STL is not text), and hashed the same way.
    let hashing_read = |name: &str| -> Result<Vec<u8>, CaseError> {
        use std::io::Read;
        let mut bytes = Vec::new();
        open(name)?
            .read_to_end(&mut bytes)
            .map_err(|source| CaseError::Read { path: name.into(), source })?;
        let mut h = hasher.borrow_mut();
        h.update(b"\0file\0");
        h.update(name.as_bytes());
        h.update(b"\0");
        h.update(&bytes);
        Ok(bytes)
    };
    let mut case = validate(raw, &hashing_open, &hashing_read)?;
    case.hash = hasher.into_inner().finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok(case)
}

/// A reader that adds every byte it passes to the case hash.
struct Hashing<'h> {
    inner: Box<dyn std::io::BufRead>,
    hasher: &'h std::cell::RefCell<sha2::Sha256>,
}

impl std::io::Read for Hashing<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use sha2::Digest;
        let n = self.inner.read(buf)?;
        self.hasher.borrow_mut().update(&buf[..n]);
        Ok(n)
    }
}

/// Adds "did you mean `x`?" to serde's "unknown field `y`, expected one of `a`, `b`, …" when
/// one of the expected keys is close to the unknown one, or the unknown one is the MFIX (or
/// another code's) name of an expected key (`mew` → `mu`).
fn did_you_mean(message: String) -> String {
    let Some(start) = message.find("unknown field `") else { return message };
    let rest = &message[start + 15..];
    let Some(end) = rest.find('`') else { return message };
    let unknown = &rest[..end];
    let Some(list) = rest.find("expected one of ").map(|k| &rest[k + 16..]) else { return message };
    let expected: Vec<&str> = list
        .split(',')
        .map(|w| w.trim().trim_matches(|c: char| c == '`' || c.is_whitespace() || c == '.'))
        .filter(|w| !w.is_empty())
        .collect();
    let alias = ALIASES
        .iter()
        .find(|(a, k)| a.eq_ignore_ascii_case(unknown) && expected.contains(k))
        .map(|(a, k)| (*k, format!(" (`{a}` is its name in MFIX or other codes)")));
    let best = alias
        .or_else(|| crate::error::closest(unknown, expected.iter().copied()).map(|w| (w, String::new())));
    match best {
        Some((w, why)) => format!("{}\ndid you mean `{w}`?{why}", message.trim_end()),
        None => message,
    }
}

/// Names users bring from MFIX decks and other DEM codes, and the case-file key they mean.
const ALIASES: &[(&str, &str)] = &[
    ("mew", "mu"),
    ("mew_w", "mu"),
    ("friction", "mu"),
    ("mew_r", "mu_roll"),
    ("mew_rw", "mu_roll"),
    ("rolling_friction", "mu_roll"),
    ("des_en_input", "en"),
    ("des_en_wall_input", "en"),
    ("restitution", "en"),
    ("e_n", "en"),
    ("des_et_input", "et"),
    ("e_t", "et"),
    ("kn_w", "kn"),
    ("k_n", "kn"),
    ("kt_w_fac", "kt_fac"),
    ("des_etat_fac", "etat_fac"),
    ("des_etat_w_fac", "etat_fac"),
    ("d_p0", "diameter"),
    ("ro_s0", "density"),
    ("rho", "density"),
    ("e_young", "youngs_modulus"),
    ("ew_young", "youngs_modulus"),
    ("young", "youngs_modulus"),
    ("youngs", "youngs_modulus"),
    ("v_poisson", "poisson_ratio"),
    ("vw_poisson", "poisson_ratio"),
    ("poisson", "poisson_ratio"),
    ("nu", "poisson_ratio"),
    ("tstop", "t_stop"),
    ("time", "t_start"),
    ("des_intg_method", "integrator"),
    ("factor_rlm", "skin"),
];

fn require<T>(v: Option<T>, table: &str, key: &str, hint: &str) -> Result<T, CaseError> {
    v.ok_or_else(|| CaseError::missing(table, key, hint))
}

pub(crate) fn check(r: Range, table: &str, key: &str, v: f64) -> Result<f64, CaseError> {
    if r.contains(v) { Ok(v) } else { Err(CaseError::invalid(table, key, v, r.valid)) }
}

fn choose<T: Copy>(
    table: &str,
    key: &str,
    value: Option<&str>,
    default: T,
    words: &[(&str, T)],
) -> Result<T, CaseError> {
    let Some(v) = value else { return Ok(default) };
    words.iter().find(|(w, _)| *w == v).map(|(_, t)| *t).ok_or_else(|| {
        let list: Vec<String> = words.iter().map(|(w, _)| format!("\"{w}\"")).collect();
        CaseError::invalid(table, key, format!("\"{v}\""), format!("must be one of {}", list.join(", ")))
    })
}

pub(crate) fn vec3(a: [f64; 3], table: &str, key: &str) -> Result<Vec3, CaseError> {
    let v = Vec3::from_array(a);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CaseError::invalid(table, key, format!("{a:?}"), "all three components must be finite numbers"))
    }
}

fn validate<'h>(
    raw: RawCase,
    open: &dyn Fn(&str) -> Result<input::Stream<'h>, CaseError>,
    read_bytes: &dyn Fn(&str) -> Result<Vec<u8>, CaseError>,
) -> Result<Case, CaseError> {
    let mut warnings = Vec::new();
    match raw.version {
        None => {
            return Err(CaseError::missing(
                "top level",
                "version",
                format!("the case-file format version; this program reads version {CASE_VERSION}"),
            ));
        }
        Some(CASE_VERSION) => {}
        Some(v) => {
            return Err(CaseError::invalid(
                "top level",
                "version",
                v,
                format!("this program reads case-file version {CASE_VERSION}"),
            ));
        }
    }

    // Domain.
    let domain = require(raw.domain, "top level", "[domain]", "the domain box: min and max corners in m")?;
    let min = vec3(require(domain.min, "[domain]", "min", "lower corner of the box, m")?, "[domain]", "min")?;
    let max = vec3(require(domain.max, "[domain]", "max", "upper corner of the box, m")?, "[domain]", "max")?;
    if !(max.cmpgt(min).all()) {
        return Err(CaseError::invalid(
            "[domain]",
            "max",
            format!("{:?}", max.to_array()),
            format!("every component must exceed min = {:?}", min.to_array()),
        ));
    }

    // Phases.
    if raw.phases.is_empty() {
        return Err(CaseError::missing(
            "top level",
            "[[phases]]",
            "at least one solids phase with name, diameter (m) and density (kg/m³)",
        ));
    }
    // Checked before any table is built: the pair tables grow as the square of the count.
    if raw.phases.len() > MAX_PHASES {
        return Err(CaseError::invalid(
            "top level",
            "[[phases]]",
            format!("({} tables)", raw.phases.len()),
            format!("at most {MAX_PHASES} phases are allowed (MFIX allows 10)"),
        ));
    }
    if raw.wall_materials.len() > MAX_WALL_MATERIALS {
        return Err(CaseError::invalid(
            "top level",
            "[[wall_materials]]",
            format!("({} tables)", raw.wall_materials.len()),
            format!("at most {MAX_WALL_MATERIALS} wall materials are allowed"),
        ));
    }
    let mut phases = Vec::new();
    for (k, p) in raw.phases.iter().enumerate() {
        let table = format!("[[phases]] #{}", k + 1);
        let name = require(p.name.clone(), &table, "name", "a unique phase name")?;
        let table = format!("[[phases]] '{name}'");
        if phases.iter().any(|q: &Phase| q.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "phase names must be unique",
            ));
        }
        let diameter = check(
            limits::DIAMETER,
            &table,
            "diameter",
            require(p.diameter, &table, "diameter", "reference diameter in m")?,
        )?;
        let density = check(
            limits::DENSITY,
            &table,
            "density",
            require(p.density, &table, "density", "density in kg/m³")?,
        )?;
        let youngs_modulus =
            p.youngs_modulus.map(|v| check(limits::YOUNGS, &table, "youngs_modulus", v)).transpose()?;
        let poisson_ratio =
            p.poisson_ratio.map(|v| check(limits::POISSON, &table, "poisson_ratio", v)).transpose()?;
        let phase = Phase { name, diameter, density, youngs_modulus, poisson_ratio };
        let m = phase.mass();
        if !(m.is_finite() && m >= f64::MIN_POSITIVE) {
            return Err(CaseError::invalid(
                &table,
                if (1e-9..=1.0).contains(&diameter) { "density" } else { "diameter" },
                format!("(diameter {diameter:e} m, density {density:e} kg/m³)"),
                format!(
                    "the particle mass ρ·π·d³/6 = {m:e} kg is beyond what double precision can hold; are the diameter and density in SI units (m, kg/m³)?"
                ),
            ));
        }
        phases.push(phase);
    }
    let phase_index = |name: &str, table: &str, key: &str| -> Result<usize, CaseError> {
        phases.iter().position(|p| p.name == name).ok_or_else(|| {
            let names: Vec<String> = phases.iter().map(|p| format!("\"{}\"", p.name)).collect();
            CaseError::invalid(
                table,
                key,
                format!("\"{name}\""),
                format!("not a phase; the phases are {}", names.join(", ")),
            )
        })
    };

    // Wall materials and walls.
    let mut wall_materials = Vec::new();
    for (k, w) in raw.wall_materials.iter().enumerate() {
        let table = format!("[[wall_materials]] #{}", k + 1);
        let name = require(w.name.clone(), &table, "name", "a unique wall material name")?;
        let table = format!("[[wall_materials]] '{name}'");
        if wall_materials.iter().any(|q: &WallMaterial| q.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "wall material names must be unique",
            ));
        }
        let youngs_modulus =
            w.youngs_modulus.map(|v| check(limits::YOUNGS, &table, "youngs_modulus", v)).transpose()?;
        let poisson_ratio =
            w.poisson_ratio.map(|v| check(limits::POISSON, &table, "poisson_ratio", v)).transpose()?;
        wall_materials.push(WallMaterial { name, youngs_modulus, poisson_ratio });
    }
    if wall_materials.is_empty() {
        wall_materials.push(WallMaterial { name: "wall".into(), youngs_modulus: None, poisson_ratio: None });
    }
    let material_index = |name: &Option<String>, table: &str, key: &str| -> Result<usize, CaseError> {
        let Some(name) = name else { return Ok(0) };
        wall_materials.iter().position(|m| &m.name == name).ok_or_else(|| {
            let names: Vec<String> = wall_materials.iter().map(|p| format!("\"{}\"", p.name)).collect();
            CaseError::invalid(
                table,
                key,
                format!("\"{name}\""),
                format!("not a wall material; the wall materials are {}", names.join(", ")),
            )
        })
    };
    let mut axes = [false; 3];
    for a in domain.periodic.iter().flatten() {
        let k = ["x", "y", "z"].iter().position(|n| n == a).ok_or_else(|| {
            CaseError::invalid(
                "[domain]",
                "periodic",
                format!("\"{a}\""),
                "each periodic axis must be \"x\", \"y\" or \"z\"",
            )
        })?;
        if axes[k] {
            return Err(CaseError::invalid(
                "[domain]",
                "periodic",
                format!("{:?}", domain.periodic.as_deref().unwrap_or_default()),
                format!("the axis \"{a}\" is listed twice; list each periodic axis once"),
            ));
        }
        axes[k] = true;
    }
    let periodic = axes.iter().any(|&a| a).then_some(grainflow::Periodic { lo: min, hi: max, axes });
    let faces = ["x_min", "x_max", "y_min", "y_max", "z_min", "z_max"];
    let wanted: Vec<bool> = match &domain.walls {
        WallSelection::All(all) => (0..6).map(|k| *all && !axes[k / 2]).collect(),
        WallSelection::Faces(list) => {
            let mut w = vec![false; 6];
            for f in list {
                let k = faces.iter().position(|n| n == f).ok_or_else(|| {
                    CaseError::invalid(
                        "[domain]",
                        "walls",
                        format!("\"{f}\""),
                        "faces are \"x_min\", \"x_max\", \"y_min\", \"y_max\", \"z_min\", \"z_max\"",
                    )
                })?;
                if axes[k / 2] {
                    return Err(CaseError::invalid(
                        "[domain]",
                        "walls",
                        format!("\"{f}\""),
                        "a periodic axis has no walls",
                    ));
                }
                w[k] = true;
            }
            w
        }
    };
    let mut walls = Vec::new();
    if wanted.iter().any(|&w| w) {
        let m = material_index(&domain.wall_material, "[domain]", "wall_material")?;
        walls.extend(
            Wall::domain_box(min, max, m).into_iter().zip(&wanted).filter(|(_, w)| **w).map(|(wall, _)| wall),
        );
    }
    for (k, w) in raw.walls.iter().enumerate() {
        let name = w.name.clone().unwrap_or_else(|| format!("wall {}", k + 1));
        let table = format!("[[walls]] '{name}'");
        let point = vec3(require(w.point, &table, "point", "a point on the plane, m")?, &table, "point")?;
        let normal = vec3(
            require(w.normal, &table, "normal", "normal pointing into the particle space")?,
            &table,
            "normal",
        )?;
        if normal.length() == 0.0 {
            return Err(CaseError::invalid(
                &table,
                "normal",
                format!("{:?}", normal.to_array()),
                "the normal must not be zero",
            ));
        }
        walls.push(Wall::plane(name, point, normal, material_index(&w.material, &table, "material")?));
    }
    let mut meshes: Vec<MeshWall> = Vec::new();
    let mut mesh_names: Vec<String> = Vec::new();
    let mut mesh_torque_about: Vec<Vec3> = Vec::new();
    // The meshes' motions are timed from the run's start ([time] is checked below).
    let t_start_given = raw.time.as_ref().and_then(|t| t.t_start).filter(|t| t.is_finite()).unwrap_or(0.0);
    for (k, m) in raw.meshes.iter().enumerate() {
        let table = format!("[[meshes]] #{}", k + 1);
        let name = require(m.name.clone(), &table, "name", "a unique mesh name, for messages")?;
        let table = format!("[[meshes]] '{name}'");
        if mesh_names.contains(&name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "mesh names must be unique",
            ));
        }
        let file = require(
            m.file.clone(),
            &table,
            "file",
            "the mesh file (.stl or .obj), relative to the case file",
        )?;
        let material = material_index(&m.material, &table, "material")?;
        let scale = m.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(CaseError::invalid(
                &table,
                "scale",
                scale,
                "must be a positive, finite number of metres per file unit (1e-3 for millimetres)",
            ));
        }
        let rotation = vec3(m.rotate.unwrap_or([0.0; 3]), &table, "rotate")?;
        let translation = vec3(m.translate.unwrap_or([0.0; 3]), &table, "translate")?;
        let transform = MeshTransform {
            scale,
            rotation_deg: rotation.to_array(),
            translation,
            flip_normals: m.flip_normals.unwrap_or(false),
            skip_degenerate: m.skip_degenerate.unwrap_or(false),
        };
        let mesh = load_mesh(&file, &transform, read_bytes).map_err(|e| e.into_case_error(&table))?;
        if mesh.skipped_degenerate() > 0 {
            warnings.push(format!(
                "{table}: {} of {file}'s triangles have no area and are left out (skip_degenerate = true)",
                mesh.skipped_degenerate()
            ));
        }
        if mesh.outside_box(min, max) {
            let (lo, hi) = mesh.bounds();
            return Err(CaseError::Geometry(format!(
                "{table}: mesh '{name}' lies outside the domain [{:?}, {:?}] (its bounding box after the transform is [{:?}, {:?}] m); check `scale`, `rotate` and `translate`, or enlarge [domain]",
                min.to_array(),
                max.to_array(),
                lo.to_array(),
                hi.to_array()
            )));
        }
        let motion = mesh_motion(m.motion.as_ref(), &table)?;
        let window = mesh_motion_window(m.motion.as_ref(), &table, t_start_given)?;
        let surface = mesh_surface(m.surface.as_ref(), &table)?;
        let surface_factor = mesh_surface_factor(m.surface.as_ref(), &table, t_start_given, read_bytes)?;
        let wall = MeshWall { mesh, material, motion, window, surface, surface_factor };
        let about = match m.torque_about {
            Some(p) => vec3(p, &table, "torque_about")?,
            None => crate::output::rotation_axis(&wall).map_or(Vec3::ZERO, |(origin, _)| origin),
        };
        meshes.push(wall);
        mesh_names.push(name);
        mesh_torque_about.push(about);
    }

    // Contact law and tables.
    let contact = require(raw.contact, "top level", "[contact]", "the contact model and its parameters")?;
    let normal = choose(
        "[contact]",
        "model",
        contact.model.as_deref(),
        NormalModel::LinearSpringDashpot,
        NormalModel::CHOICES,
    )?;
    let tangential = choose(
        "[contact]",
        "tangential",
        contact.tangential.as_deref(),
        TangentialModel::MfixTotal,
        TangentialModel::CHOICES,
    )?;
    let history = choose(
        "[contact]",
        "history",
        contact.history.as_deref(),
        HistoryFrame::Mfix,
        &[("mfix", HistoryFrame::Mfix), ("project", HistoryFrame::Project), ("rotate", HistoryFrame::Rotate)],
    )?;
    let lever = choose(
        "[contact]",
        "lever_arm",
        contact.lever_arm.as_deref(),
        LeverArm::RadicalPlane,
        &[
            ("mfix", LeverArm::RadicalPlane),
            ("radius", LeverArm::Radius),
            ("lammps_granular", LeverArm::LammpsGranular),
        ],
    )?;
    let damping = choose(
        "[contact]",
        "damping",
        contact.damping.as_deref(),
        NormalDamping::Mfix,
        &[
            ("mfix", NormalDamping::Mfix),
            ("exact_restitution", NormalDamping::ExactRestitution),
            ("mass_velocity", NormalDamping::MassVelocity),
            ("tsuji", NormalDamping::Tsuji),
        ],
    )?;
    let clip_attraction = contact.clip_attraction.unwrap_or(false);
    let coulomb = choose(
        "[contact]",
        "coulomb",
        contact.coulomb.as_deref(),
        CoulombCap::Mfix,
        &[("mfix", CoulombCap::Mfix), ("lammps", CoulombCap::Lammps)],
    )?;
    let sizes = choose(
        "[contact]",
        "sizes",
        contact.sizes.as_deref(),
        ContactSizes::Own,
        &[("own", ContactSizes::Own), ("phase", ContactSizes::Phase)],
    )?;
    let law = ContactLaw { normal, tangential, history, lever, damping, clip_attraction, coulomb, sizes };
    if normal == NormalModel::Jkr {
        // The damping JKR takes (LAMMPS's examples pair `jkr` with `damping tsuji`), and no
        // clipping, which would remove its adhesion.
        if damping != NormalDamping::Tsuji {
            return Err(CaseError::invalid(
                "[contact]",
                "damping",
                format!("{:?}", contact.damping.as_deref().unwrap_or("mfix")),
                "the jkr model takes damping = \"tsuji\" (LAMMPS's pair granular pairs jkr with it)",
            ));
        }
        if clip_attraction {
            return Err(CaseError::invalid(
                "[contact]",
                "clip_attraction",
                "true",
                "the jkr model is attractive by design: clipping the normal force at zero would remove its adhesion",
            ));
        }
    }
    if normal.elastic() {
        let model = law.normal_name();
        for p in &phases {
            let table = format!("[[phases]] '{}'", p.name);
            require(
                p.youngs_modulus,
                &table,
                "youngs_modulus",
                &format!("Young's modulus in Pa, required by the {model} model"),
            )?;
            require(
                p.poisson_ratio,
                &table,
                "poisson_ratio",
                &format!("Poisson's ratio, required by the {model} model"),
            )?;
        }
        if !walls.is_empty() || !meshes.is_empty() {
            for m in &wall_materials {
                let table = format!("[[wall_materials]] '{}'", m.name);
                require(
                    m.youngs_modulus,
                    &table,
                    "youngs_modulus",
                    &format!("Young's modulus in Pa, required by the {model} model for walls"),
                )?;
                require(
                    m.poisson_ratio,
                    &table,
                    "poisson_ratio",
                    &format!("Poisson's ratio, required by the {model} model for walls"),
                )?;
            }
        }
    }
    for (table, t, is_pair) in
        [("[contact.particle]", &contact.particle, None), ("[contact.wall]", &contact.wall, None)]
            .into_iter()
            .chain(contact.pairs.iter().map(|t| ("[[contact.pairs]]", t, Some(true))))
            .chain(contact.walls.iter().map(|t| ("[[contact.walls]]", t, Some(false))))
    {
        let misplaced = match is_pair {
            None => [
                ("phases", t.phases.is_some()),
                ("phase", t.phase.is_some()),
                ("material", t.material.is_some()),
            ]
            .into_iter()
            .find(|x| x.1),
            Some(true) => {
                [("phase", t.phase.is_some()), ("material", t.material.is_some())].into_iter().find(|x| x.1)
            }
            Some(false) => [("phases", t.phases.is_some())].into_iter().find(|x| x.1),
        };
        if let Some((key, _)) = misplaced {
            return Err(CaseError::invalid(
                table,
                key,
                "(given)",
                "this key selects a pair: `phases` belongs in [[contact.pairs]], `phase` and `material` in [[contact.walls]]",
            ));
        }
        check_params(table, t, law, &mut warnings)?;
    }
    let n = phases.len();
    let mut pair_tables: Vec<Option<&RawContactParams>> = vec![None; n * (n + 1) / 2];
    for t in &contact.pairs {
        let table = "[[contact.pairs]]";
        let [a, b] = require(t.phases.clone(), table, "phases", "the two phase names of the pair")?;
        let (ia, ib) = (phase_index(&a, table, "phases")?, phase_index(&b, table, "phases")?);
        let slot = &mut pair_tables[grainflow::contact::coefficients::upper_triangle_index(ia, ib, n)];
        if slot.is_some() {
            return Err(CaseError::invalid(
                table,
                "phases",
                format!("[\"{a}\", \"{b}\"]"),
                "each phase pair may appear only once",
            ));
        }
        *slot = Some(t);
    }
    let nw = if walls.is_empty() && meshes.is_empty() { 0 } else { wall_materials.len() };
    let mut wall_tables: Vec<Option<&RawContactParams>> = vec![None; n * nw];
    for t in &contact.walls {
        let table = "[[contact.walls]]";
        let ph = require(t.phase.clone(), table, "phase", "the phase name")?;
        let ip = phase_index(&ph, table, "phase")?;
        let iw = material_index(&t.material, table, "material")?;
        if nw == 0 {
            continue;
        }
        let slot = &mut wall_tables[ip * nw + iw];
        if slot.is_some() {
            return Err(CaseError::invalid(
                table,
                "phase",
                format!("\"{ph}\""),
                "each phase and wall material may appear only once",
            ));
        }
        *slot = Some(t);
    }
    let mut pair_params = Vec::with_capacity(pair_tables.len());
    for m in 0..n {
        for l in m..n {
            let over = pair_tables[grainflow::contact::coefficients::upper_triangle_index(m, l, n)];
            let what = format!("phase pair '{}'-'{}'", phases[m].name, phases[l].name);
            pair_params.push(layer(over, &contact.particle, law, "[contact.particle]", &what)?);
        }
    }
    let mut wall_params = Vec::with_capacity(wall_tables.len());
    for m in 0..n {
        for w in 0..nw {
            let what =
                format!("phase '{}' against wall material '{}'", phases[m].name, wall_materials[w].name);
            wall_params.push(layer(wall_tables[m * nw + w], &contact.wall, law, "[contact.wall]", &what)?);
        }
    }
    if nw == 0 {
        wall_materials.clear();
    }

    // Time.
    let time = require(raw.time, "top level", "[time]", "t_stop (s) and optionally dt, integrator")?;
    let t_start = time.t_start.unwrap_or(0.0);
    if !t_start.is_finite() {
        return Err(CaseError::invalid("[time]", "t_start", t_start, "must be a finite time in s"));
    }
    let t_stop = require(time.t_stop, "[time]", "t_stop", "end time of the run, s")?;
    if !(t_stop.is_finite() && t_stop > t_start) {
        return Err(CaseError::invalid(
            "[time]",
            "t_stop",
            t_stop,
            format!("must be a finite time in s after t_start = {t_start}"),
        ));
    }
    // The Hertz default is taken again from the smallest particles once they are known.
    let hertz_default = time.dt.is_none()
        && time.dtsolid_factor.is_none()
        && normal.elastic()
        && grainflow::timestep::hertz_default_dt(&phases).is_some();
    let mut time_step = match (time.dt, time.dtsolid_factor) {
        (Some(_), Some(_)) => {
            return Err(CaseError::invalid(
                "[time]",
                "dtsolid_factor",
                "(given with dt)",
                "give either an explicit dt or MFIX's dtsolid_factor, not both",
            ));
        }
        (Some(dt), None) if dt.is_finite() && dt > 0.0 => TimeStepRule::Fixed(dt),
        (Some(dt), None) => {
            return Err(CaseError::invalid("[time]", "dt", dt, "must be a positive time in s"));
        }
        // A Hertz case without dt: a fraction of the Rayleigh time (MFIX's rule takes the
        // Hertz K_n as linear and gives a step some 20 times below the stable one). MFIX decks
        // give dtsolid_factor, and keep MFIX's rule.
        (None, None) if normal.elastic() && grainflow::timestep::hertz_default_dt(&phases).is_some() => {
            TimeStepRule::Fixed(grainflow::timestep::hertz_default_dt(&phases).unwrap_or(f64::NAN))
        }
        (None, f) => {
            let factor = f.unwrap_or(50.0);
            if !(factor.is_finite() && factor >= 10.0) {
                return Err(CaseError::invalid(
                    "[time]",
                    "dtsolid_factor",
                    factor,
                    "must be at least 10 (MFIX rejects smaller values)",
                ));
            }
            TimeStepRule::Mfix { factor }
        }
    };
    let integrator = choose(
        "[time]",
        "integrator",
        time.integrator.as_deref(),
        Integrator::Euler,
        &[
            ("euler", Integrator::Euler),
            ("adams_bashforth", Integrator::AdamsBashforth),
            ("velocity_verlet", Integrator::VelocityVerlet),
        ],
    )?;

    let gravity = match raw.physics.gravity {
        Some(g) => vec3(g, "[physics]", "gravity")?,
        None => Vec3::new(0.0, -STANDARD_GRAVITY, 0.0),
    };
    let skin = raw
        .neighbor
        .skin
        .map(|s| {
            check(
                Range {
                    lo: 0.0,
                    lo_open: false,
                    hi: f64::MAX,
                    hi_open: false,
                    valid: "must be a length >= 0 in m",
                },
                "[neighbor]",
                "skin",
                s,
            )
        })
        .transpose()?;
    let interval = raw
        .output
        .interval
        .map(|v| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(CaseError::invalid("[output]", "interval", v, "must be a positive time in s"))
            }
        })
        .transpose()?;
    let vtk_interval = raw
        .output
        .vtk_interval
        .map(|v| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(CaseError::invalid("[output]", "vtk_interval", v, "must be a positive time in s"))
            }
        })
        .transpose()?;
    let output = OutputSettings { interval, snapshots: raw.output.snapshots.unwrap_or(true), vtk_interval };

    // Insertions and outlets.
    let mesh_set = crate::flow::Meshes { walls: &meshes, names: &mesh_names };
    let read_particles = |file: &str| particles::read_csv_from(&mut open(file)?, &phases);
    let flow_domain = crate::flow::Domain { lo: min, hi: max, periodic: axes };
    let mut insertions =
        crate::flow::insertions(&raw.insertions, &phases, &mesh_set, t_start, &flow_domain, &read_particles)?;
    let outlets = crate::flow::outlets(&raw.outlets, &mesh_set, domain.leaving.as_deref(), &flow_domain)?;

    // Particles (none needed when an insertion brings them).
    let praw = match raw.particles {
        Some(p) => p,
        None if !insertions.is_empty() => RawParticles::default(),
        None => require(
            None,
            "top level",
            "[particles]",
            "a particle file and/or [[particles.list]] (or [[insertions]])",
        )?,
    };
    let mut init: Vec<ParticleInit> = Vec::new();
    if let Some(file) = &praw.file {
        let lower = file.to_ascii_lowercase();
        let format = praw.format.clone().unwrap_or_else(|| {
            if lower.ends_with(".csv") {
                "csv".into()
            } else if lower.ends_with(".data") {
                "lammps".into()
            } else {
                "mfix".into()
            }
        });
        if !["mfix", "csv", "lammps"].contains(&format.as_str()) {
            return Err(CaseError::invalid(
                "[particles]",
                "format",
                format!("\"{format}\""),
                "must be \"mfix\", \"csv\" or \"lammps\"",
            ));
        }
        let mut stream = open(file)?;
        init = match format.as_str() {
            "mfix" => particles::read_mfix_from(&mut stream, &phases)?,
            "csv" => particles::read_csv_from(&mut stream, &phases)?,
            "lammps" => {
                let data = crate::lammps::read_data_from(&mut stream, &phases)?;
                if let Some((blo, bhi)) = data.bounds {
                    // A larger domain along a walled axis only holds the file's box (LAMMPS
                    // shrink-wraps a flow's open top); a periodic axis of another length, or a
                    // domain that cuts into the file's box, is another system.
                    let tol = 1e-9 * (max - min).abs().max_element();
                    let differs = (0..3).any(|k| {
                        let (dl, dh, fl, fh) = (min[k], max[k], blo[k], bhi[k]);
                        if axes[k] {
                            (dl - fl).abs() > tol || (dh - fh).abs() > tol
                        } else {
                            dl > fl + tol || dh < fh - tol
                        }
                    });
                    if differs {
                        warnings.push(format!(
                            "[particles]: the LAMMPS data file {file} declares the box {:?} to {:?}, which [domain] min = {:?}, max = {:?} does not match (along a periodic axis) or does not hold; grainflow uses [domain] (its walls and periodic axes), not the file's box",
                            blo.to_array(),
                            bhi.to_array(),
                            min.to_array(),
                            max.to_array()
                        ));
                    }
                }
                data.atoms
            }
            other => {
                return Err(CaseError::invalid(
                    "[particles]",
                    "format",
                    format!("\"{other}\""),
                    "must be \"mfix\", \"csv\" or \"lammps\"",
                ));
            }
        };
    } else if let Some(f) = &praw.format {
        return Err(CaseError::invalid(
            "[particles]",
            "format",
            format!("\"{f}\""),
            "only meaningful together with `file`",
        ));
    }
    for (k, p) in praw.list.iter().enumerate() {
        let table = format!("[[particles.list]] #{}", k + 1);
        let phase = phase_index(
            &require(p.phase.clone(), &table, "phase", "the particle's phase name")?,
            &table,
            "phase",
        )?;
        let radius = match p.diameter {
            Some(d) => 0.5 * check(limits::DIAMETER, &table, "diameter", d)?,
            None => phases[phase].radius(),
        };
        init.push(ParticleInit {
            id: p.id.unwrap_or((init.len() + 1) as u32),
            phase: phase as u32,
            radius,
            density: phases[phase].density,
            position: vec3(require(p.position, &table, "position", "centre in m")?, &table, "position")?,
            velocity: vec3(p.velocity.unwrap_or([0.0; 3]), &table, "velocity")?,
            omega: vec3(p.angular_velocity.unwrap_or([0.0; 3]), &table, "angular_velocity")?,
        });
    }
    if init.is_empty() && insertions.is_empty() {
        return Err(CaseError::missing(
            "[particles]",
            "file or list",
            "at least one particle (or [[insertions]])",
        ));
    }
    match praw.order.as_deref() {
        None | Some("input") => {}
        Some("spatial") => {
            let r_max = init.iter().map(|p| p.radius).fold(0.0, f64::max);
            let cut = 2.0 * r_max + skin.unwrap_or_else(|| grainflow::simulation::default_skin(r_max));
            sort_into_bins(&mut init, min, 0.5 * cut);
        }
        Some(other) => {
            return Err(CaseError::invalid(
                "[particles]",
                "order",
                format!("\"{other}\""),
                "must be \"input\" or \"spatial\"",
            ));
        }
    }
    let resort = match &praw.resort {
        None => grainflow::ResortRule::Auto,
        Some(crate::raw::RawResort::Word(w)) if w == "auto" => grainflow::ResortRule::Auto,
        Some(crate::raw::RawResort::Word(w)) if w == "never" => grainflow::ResortRule::Never,
        Some(crate::raw::RawResort::Steps(k)) if *k >= 1 => grainflow::ResortRule::Every(*k as u64),
        Some(other) => {
            return Err(CaseError::invalid(
                "[particles]",
                "resort",
                match other {
                    crate::raw::RawResort::Word(w) => format!("\"{w}\""),
                    crate::raw::RawResort::Steps(k) => k.to_string(),
                },
                "must be \"auto\", \"never\" or a number of steps >= 1",
            ));
        }
    };
    let particles = Particles::from_init(&init);
    // A large bed's inputs are as large as its state: let them go before the checks below.
    drop(init);

    // Prescribed motion (the ids are gathered only if there is any).
    let ids: std::collections::HashSet<u32> =
        if raw.motion.is_empty() { Default::default() } else { particles.id.iter().copied().collect() };
    let mut motion = Vec::new();
    for (k, m) in raw.motion.iter().enumerate() {
        let table = format!("[[motion]] #{}", k + 1);
        let (first, last) = match require(m.particles.clone(), &table, "particles", "an id or [first, last]")?
        {
            IdSelection::One(i) => (i, i),
            IdSelection::Range([a, b]) if a <= b => (a, b),
            IdSelection::Range([a, b]) => {
                return Err(CaseError::invalid(
                    &table,
                    "particles",
                    format!("[{a}, {b}]"),
                    "the first id must not exceed the last",
                ));
            }
        };
        let rule_word = require(m.rule.clone(), &table, "rule", "\"hold\" or \"follow\"")?;
        for id in first..=last {
            let rule = match rule_word.as_str() {
                "hold" => {
                    if m.leader.is_some() || m.leader_offset.is_some() || m.axes.is_some() {
                        return Err(CaseError::invalid(
                            &table,
                            "rule",
                            "\"hold\"",
                            "a held particle takes no leader, leader_offset or axes",
                        ));
                    }
                    MotionRule::Hold
                }
                "follow" => {
                    let leader = match (m.leader, m.leader_offset) {
                        (Some(l), None) => l,
                        (None, Some(off)) => {
                            let l = id as i64 + off;
                            u32::try_from(l).map_err(|_| {
                                CaseError::invalid(
                                    &table,
                                    "leader_offset",
                                    off,
                                    format!("particle {id} would follow id {l}, which cannot exist"),
                                )
                            })?
                        }
                        _ => {
                            return Err(CaseError::invalid(
                                &table,
                                "leader",
                                "(see leader_offset)",
                                "\"follow\" needs exactly one of `leader` (an id) or `leader_offset`",
                            ));
                        }
                    };
                    let words = require(
                        m.axes.clone(),
                        &table,
                        "axes",
                        "the axes that follow the leader, e.g. [\"x\", \"z\"]",
                    )?;
                    let mut axes = [false; 3];
                    for w in &words {
                        let k = ["x", "y", "z"].iter().position(|a| a == w).ok_or_else(|| {
                            CaseError::invalid(
                                &table,
                                "axes",
                                format!("\"{w}\""),
                                "each axis must be \"x\", \"y\" or \"z\"",
                            )
                        })?;
                        axes[k] = true;
                    }
                    MotionRule::Follow { leader, axes }
                }
                other => {
                    return Err(CaseError::invalid(
                        &table,
                        "rule",
                        format!("\"{other}\""),
                        "must be \"hold\" or \"follow\"",
                    ));
                }
            };
            if !ids.contains(&id) {
                return Err(CaseError::invalid(&table, "particles", id, "no particle has this id"));
            }
            if let MotionRule::Follow { leader, .. } = rule
                && !ids.contains(&leader)
            {
                return Err(CaseError::invalid(
                    &table,
                    "leader",
                    leader,
                    format!("particle {id} would follow id {leader}, which no particle has"),
                ));
            }
            motion.push(PrescribedMotion { particle: id, rule });
        }
    }

    let run_overlap = praw.max_overlap.unwrap_or(DEFAULT_MAX_OVERLAP);
    if !(run_overlap.is_finite() && run_overlap > 0.0 && run_overlap <= 1.0) {
        return Err(CaseError::invalid(
            "[particles]",
            "max_overlap",
            run_overlap,
            "must be a fraction in (0, 1] of the smaller radius",
        ));
    }
    let max_overlap = praw.max_initial_overlap.unwrap_or(DEFAULT_MAX_INITIAL_OVERLAP.min(run_overlap));
    if !(max_overlap.is_finite() && max_overlap >= 0.0) {
        return Err(CaseError::invalid(
            "[particles]",
            "max_initial_overlap",
            max_overlap,
            "must be a fraction >= 0 of the radius",
        ));
    }
    if max_overlap > run_overlap {
        return Err(CaseError::invalid(
            "[particles]",
            "max_initial_overlap",
            max_overlap,
            format!(
                "must not exceed max_overlap = {run_overlap} (the run stops at an overlap above max_overlap, so a start above it could not run); raise max_overlap too, or separate the particles"
            ),
        ));
    }
    grainflow::motion::check_rules(&motion).map_err(|e| CaseError::Geometry(format!("[[motion]]: {e}")))?;
    check_geometry(&particles, &walls, &meshes, &mesh_names, (min, max), max_overlap)?;
    crate::flow::check_given(
        &raw.insertions,
        &mut insertions,
        &particles,
        max_overlap,
        t_start,
        &mut warnings,
    )?;
    if let Some(per) = &periodic {
        let skin = skin.unwrap_or_else(|| grainflow::simulation::default_skin(particles.max_radius()));
        per.check(particles.max_radius(), skin, &walls)?;
        // The largest radius any particle has or is inserted with.
        let r_max = insertions
            .iter()
            .flat_map(|ins| &ins.mixture.parts)
            .map(|part| 0.5 * part.sizes.max_diameter())
            .fold(particles.max_radius(), f64::max);
        if let Some((m, axis, from, to)) =
            grainflow::simulation::periodic_mesh_reach(&meshes, per, r_max, t_stop - t_start)
        {
            let text =
                grainflow::simulation::periodic_mesh_message(&mesh_names[m], (axis, from, to), per, r_max);
            return Err(CaseError::Geometry(format!("[[meshes]] '{}': {text}", mesh_names[m])));
        }
    }
    let force_dt = time.force_dt.unwrap_or(false);
    // Contacts of their own sizes: the time step from the smallest particles (as the engine
    // takes it).
    // Each particle's own size is checked before the smallest one sets a step.
    grainflow::simulation::check_particles(&particles, phases.len())?;
    let sizes = grainflow::simulation::RunSizes::of(&phases, &particles, &insertions);
    let smallest_radius = sizes.smallest.iter().map(Phase::radius).fold(f64::INFINITY, f64::min);
    let step_phases =
        if law.sizes == ContactSizes::Own && sizes.vary { sizes.smallest } else { phases.clone() };
    if let Some(dt) = grainflow::timestep::hertz_default_dt(&step_phases).filter(|_| hertz_default) {
        time_step = TimeStepRule::Fixed(dt);
    }
    let dt = check_stability(
        time_step,
        t_stop - t_start,
        &law,
        &step_phases,
        &wall_materials,
        &pair_params,
        &wall_params,
        force_dt,
        &mut warnings,
    )?;
    if let Some((k, text)) =
        grainflow::timestep::mesh_travel_problem(&meshes, &mesh_names, smallest_radius, dt)
    {
        let table = format!("[[meshes]] '{}'", mesh_names[k]);
        if force_dt {
            warnings.push(format!("{table}: motion: {text} (running anyway: [time] force_dt = true)"));
        } else {
            return Err(CaseError::Geometry(format!(
                "{table}: motion: {text}; or lower the mesh's speed, or set [time] force_dt = true to run anyway"
            )));
        }
    }

    let config = SimulationConfig {
        phases,
        wall_materials,
        walls,
        meshes,
        law,
        pair_params,
        wall_params,
        integrator,
        time_step,
        t_start,
        t_stop,
        gravity,
        skin,
        motion,
        periodic,
        resort,
        insertions,
        outlets,
    };
    Ok(Case {
        title: raw.title,
        config,
        particles,
        output,
        domain: (min, max),
        hash: String::new(),
        warnings,
        max_overlap: run_overlap,
        mesh_names,
        mesh_torque_about,
    })
}

/// Sorts particles into cubic bins of edge `bin` over the domain from `lo`, bin by bin with x
/// fastest, then y, then z (ties by id). Particles close in space end up close in memory, and
/// the force loop meets a particle's neighbours in a few steady streams (the rows of bins
/// around it), which the processor's prefetcher follows; a Morton curve, tried first, keeps
/// neighbours as close but scatters the accesses and ran slower. LAMMPS sorts its atoms the
/// same way, into bins of half the neighbour cut-off.
fn sort_into_bins(init: &mut [ParticleInit], lo: Vec3, bin: f64) {
    let key = |x: Vec3| {
        // Saturating casts: positions are checked later, and any order is correct.
        let b = ((x - lo) / bin).floor();
        (b.z as i64, b.y as i64, b.x as i64)
    };
    init.sort_by_cached_key(|p| (key(p.position), p.id));
}

/// Why a mesh could not be loaded: the file could not be read, or it is not a usable mesh.
enum MeshLoadError {
    Mesh(MeshError),
    Case(CaseError),
}

impl MeshLoadError {
    fn into_case_error(self, table: &str) -> CaseError {
        match self {
            MeshLoadError::Mesh(e) => CaseError::Mesh { table: table.into(), source: Box::new(e) },
            MeshLoadError::Case(e) => e,
        }
    }
}

/// A unit axis from `[meshes.*] axis`.
fn axis_of(a: Option<[f64; 3]>, table: &str) -> Result<Vec3, CaseError> {
    let a = require(a, table, "axis", "the direction of the axis, e.g. [0, 1, 0]")?;
    let v = vec3(a, table, "axis")?;
    if v.length() > 0.0 && v.length().is_finite() {
        Ok(v.normalize())
    } else {
        Err(CaseError::invalid(table, "axis", format!("{a:?}"), "must be a non-zero vector"))
    }
}

/// The angular velocity, rad/s, from exactly one of `omega` and `rpm`.
fn omega_of(omega: Option<f64>, rpm: Option<f64>, table: &str) -> Result<f64, CaseError> {
    let w = match (omega, rpm) {
        (Some(w), None) => w,
        (None, Some(n)) => n * std::f64::consts::TAU / 60.0,
        (Some(_), Some(_)) => {
            return Err(CaseError::invalid(
                table,
                "rpm",
                "given with omega",
                "give `omega` (rad/s) or `rpm`, not both",
            ));
        }
        (None, None) => {
            return Err(CaseError::missing(
                table,
                "omega",
                "the angular velocity: `omega` in rad/s or `rpm`",
            ));
        }
    };
    if w.is_finite() {
        Ok(w)
    } else {
        Err(CaseError::invalid(
            table,
            if omega.is_some() { "omega" } else { "rpm" },
            w,
            "must be a finite number",
        ))
    }
}

/// `[meshes.motion]` as the engine's motion; keys another kind uses are refused.
fn mesh_motion(m: Option<&RawMeshMotion>, table: &str) -> Result<MeshMotion, CaseError> {
    let Some(m) = m else { return Ok(MeshMotion::Fixed) };
    let table = format!("{table} [motion]");
    let kind = require(m.kind.as_deref(), &table, "kind", "\"translate\", \"rotate\" or \"oscillate\"")?;
    let given = [
        ("velocity", m.velocity.is_some()),
        ("axis", m.axis.is_some()),
        ("origin", m.origin.is_some()),
        ("omega", m.omega.is_some()),
        ("rpm", m.rpm.is_some()),
        ("ramp", m.ramp.is_some()),
        ("amplitude", m.amplitude.is_some()),
        ("frequency", m.frequency.is_some()),
    ];
    let uses: &[&str] = match kind {
        "translate" => &["velocity"],
        "rotate" => &["axis", "origin", "omega", "rpm", "ramp"],
        "oscillate" => &["amplitude", "frequency"],
        other => {
            return Err(CaseError::invalid(
                &table,
                "kind",
                format!("\"{other}\""),
                "must be one of \"translate\", \"rotate\", \"oscillate\"",
            ));
        }
    };
    if let Some((key, _)) = given.iter().find(|(k, g)| *g && !uses.contains(k)) {
        return Err(CaseError::invalid(
            &table,
            *key,
            "given",
            format!("is not a key of kind \"{kind}\" (its keys: {})", uses.join(", ")),
        ));
    }
    Ok(match kind {
        "translate" => MeshMotion::Translate {
            velocity: vec3(
                require(m.velocity, &table, "velocity", "the velocity, m/s")?,
                &table,
                "velocity",
            )?,
        },
        "rotate" => {
            let ramp = m.ramp.unwrap_or(0.0);
            if !(ramp.is_finite() && ramp >= 0.0) {
                return Err(CaseError::invalid(&table, "ramp", ramp, "must be a time >= 0, in s"));
            }
            MeshMotion::Rotate {
                origin: vec3(m.origin.unwrap_or([0.0; 3]), &table, "origin")?,
                axis: axis_of(m.axis, &table)?,
                omega: omega_of(m.omega, m.rpm, &table)?,
                ramp,
            }
        }
        _ => {
            let frequency = require(m.frequency, &table, "frequency", "the frequency, Hz")?;
            if !(frequency.is_finite() && frequency > 0.0) {
                return Err(CaseError::invalid(
                    &table,
                    "frequency",
                    frequency,
                    "must be a positive frequency, in Hz",
                ));
            }
            MeshMotion::Oscillate {
                amplitude: vec3(
                    require(m.amplitude, &table, "amplitude", "the amplitude, m")?,
                    &table,
                    "amplitude",
                )?,
                frequency,
            }
        }
    })
}

/// `[meshes.motion]`'s `start` and `stop` (times, s) as the engine's window, timed from the
/// run's start `t_start` as the motion is.
fn mesh_motion_window(
    m: Option<&RawMeshMotion>,
    table: &str,
    t_start: f64,
) -> Result<MotionWindow, CaseError> {
    let Some(m) = m else { return Ok(MotionWindow::ALWAYS) };
    let table = format!("{table} [motion]");
    let start = m.start.unwrap_or(t_start);
    if !(start.is_finite() && start >= t_start) {
        return Err(CaseError::invalid(
            &table,
            "start",
            start,
            format!("must be a finite time in s, at or after [time] t_start = {t_start}"),
        ));
    }
    let stop = m.stop.unwrap_or(f64::INFINITY);
    if m.stop.is_some() && !(stop.is_finite() && stop > start) {
        return Err(CaseError::invalid(
            &table,
            "stop",
            stop,
            format!("must be a finite time in s after the motion's start {start}"),
        ));
    }
    Ok(MotionWindow { start: start - t_start, stop: stop - t_start })
}

/// `[meshes.surface]` as the engine's surface motion.
fn mesh_surface(s: Option<&RawMeshSurface>, table: &str) -> Result<SurfaceMotion, CaseError> {
    let Some(s) = s else { return Ok(SurfaceMotion::None) };
    let table = format!("{table} [surface]");
    let turning = s.axis.is_some() || s.omega.is_some() || s.rpm.is_some() || s.origin.is_some();
    match (s.velocity, turning) {
        (Some(v), false) => Ok(SurfaceMotion::Translate { velocity: vec3(v, &table, "velocity")? }),
        (None, true) => Ok(SurfaceMotion::Rotate {
            origin: vec3(s.origin.unwrap_or([0.0; 3]), &table, "origin")?,
            axis: axis_of(s.axis, &table)?,
            omega: omega_of(s.omega, s.rpm, &table)?,
        }),
        (Some(_), true) => Err(CaseError::invalid(
            &table,
            "velocity",
            "given with a turning",
            "give either `velocity` (a belt) or `axis` with `omega` or `rpm` (a turning surface), not both",
        )),
        (None, false) => Err(CaseError::missing(
            &table,
            "velocity",
            "`velocity` (a belt) or `axis` with `omega` or `rpm` (a turning surface)",
        )),
    }
}

/// `[meshes.surface]`'s `keyframes` and `keyframe_column`: the factor of the surface's
/// velocity in time, column `keyframe_column` of the MFIX key-frame file `keyframes` (read
/// through `read_bytes`, so its text is in the case hash), timed from the run's start
/// `t_start` (the file's times are the case's, as MFIX's are its run's).
fn mesh_surface_factor(
    s: Option<&RawMeshSurface>,
    table: &str,
    t_start: f64,
    read_bytes: &dyn Fn(&str) -> Result<Vec<u8>, CaseError>,
) -> Result<Option<KeyFrames>, CaseError> {
    let Some(s) = s else { return Ok(None) };
    let table = format!("{table} [surface]");
    let Some(file) = &s.keyframes else {
        return match s.keyframe_column {
            None => Ok(None),
            Some(c) => Err(CaseError::invalid(
                &table,
                "keyframe_column",
                c,
                "is given without `keyframes`, the key-frame file it picks a column of",
            )),
        };
    };
    let column = s.keyframe_column.unwrap_or(1);
    if column < 1 {
        return Err(CaseError::invalid(
            &table,
            "keyframe_column",
            column,
            "must be a variable of the key-frame file, counted from 1 (the column after the time)",
        ));
    }
    let shown = format!("\"{file}\"");
    let bytes = read_bytes(file).map_err(|e| match e {
        CaseError::Read { source, .. } => CaseError::invalid(
            &table,
            "keyframes",
            &shown,
            format!("the key-frame file cannot be read: {source}"),
        ),
        other => other,
    })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        CaseError::invalid(
            &table,
            "keyframes",
            &shown,
            format!("the key-frame file is not text (UTF-8): {e}"),
        )
    })?;
    let frames = KeyFrames::from_mfix(text, usize::try_from(column).unwrap_or(usize::MAX))
        .and_then(|k| k.shifted(t_start))
        .map_err(|e| {
            CaseError::invalid(&table, "keyframes", &shown, format!("not a usable MFIX key-frame file: {e}"))
        })?;
    Ok(Some(frames))
}

/// The mesh in `file` (named as in the case file, read through `read_bytes`), an STL or OBJ
/// file by its extension as [`Mesh::load`] decides; a file that cannot be read is a
/// [`MeshError::Read`] naming it.
fn load_mesh(
    file: &str,
    transform: &MeshTransform,
    read_bytes: &dyn Fn(&str) -> Result<Vec<u8>, CaseError>,
) -> Result<Mesh, MeshLoadError> {
    let ext = Path::new(file).extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let parse: fn(&str, &[u8], &MeshTransform) -> Result<Mesh, MeshError> = match ext.as_deref() {
        Some("stl") => Mesh::from_stl,
        Some("obj") => Mesh::from_obj,
        _ => return Err(MeshLoadError::Mesh(MeshError::Format { file: file.into() })),
    };
    let bytes = read_bytes(file).map_err(|e| match e {
        CaseError::Read { source, .. } => {
            MeshLoadError::Mesh(MeshError::Read { file: file.into(), reason: source.to_string() })
        }
        other => MeshLoadError::Case(other),
    })?;
    parse(file, &bytes, transform).map_err(MeshLoadError::Mesh)
}

/// Default of `[particles] max_initial_overlap`.
pub const DEFAULT_MAX_INITIAL_OVERLAP: f64 = 0.05;

/// Default of `[particles] max_overlap`: half the smaller radius.
pub const DEFAULT_MAX_OVERLAP: f64 = 0.5;

/// Particles must start inside the domain box, in front of every wall, and overlap no wall
/// or other particle by more than `max_overlap` of the (smaller) radius: a larger overlap
/// releases a burst of elastic energy at the first step.
///
/// A mesh has no "behind" (a sheet may be touched from either side): only the overlap is
/// checked, as the distance from the centre to the nearest triangle.
fn check_geometry(
    p: &Particles,
    walls: &[Wall],
    meshes: &[MeshWall],
    mesh_names: &[String],
    (lo, hi): (Vec3, Vec3),
    max_overlap: f64,
) -> Result<(), CaseError> {
    let at = |i: usize| {
        let x = p.position[i];
        format!("particle {} at ({:.6e}, {:.6e}, {:.6e}) m", p.id[i], x.x, x.y, x.z)
    };
    for i in 0..p.len() {
        let x = p.position[i];
        if x.cmplt(lo).any() || x.cmpgt(hi).any() {
            return Err(CaseError::Geometry(format!(
                "{} is outside the domain box [{:?}, {:?}]; move it inside or enlarge [domain]",
                at(i),
                lo.to_array(),
                hi.to_array()
            )));
        }
        for w in walls {
            let d = w.distance(x);
            if d < 0.0 {
                return Err(CaseError::Geometry(format!(
                    "{} is behind wall '{}' (its centre is {:.3e} m on the wall's far side)",
                    at(i),
                    w.name,
                    -d
                )));
            }
            let overlap = p.radius[i] - d;
            if overlap > max_overlap * p.radius[i] {
                return Err(CaseError::Geometry(format!(
                    "{} overlaps wall '{}' by {:.3e} m = {:.3} of its radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                    at(i),
                    w.name,
                    overlap,
                    overlap / p.radius[i]
                )));
            }
        }
    }
    let mut near = Vec::new();
    for (MeshWall { mesh, .. }, name) in meshes.iter().zip(mesh_names) {
        let grid = TriangleGrid::new(mesh, 2.0 * p.max_radius());
        for i in 0..p.len() {
            let (x, r) = (p.position[i], p.radius[i]);
            // The triangles closer than r·(1 − max_overlap): those overlapped by more than the
            // limit (none when the limit is the whole radius or more).
            grid.near(mesh, x, r * (1.0 - max_overlap), &mut near);
            let closest = near
                .iter()
                .map(|&t| (t, (x - closest_point_on_triangle(x, mesh.corners(t)).point).length()))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((t, d)) = closest {
                let overlap = r - d;
                return Err(CaseError::Geometry(format!(
                    "{} overlaps mesh '{name}' (triangle {t}) by {:.3e} m = {:.3} of its radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                    at(i),
                    overlap,
                    overlap / r
                )));
            }
        }
    }
    let mut nl = grainflow::neighbor::NeighborList::new(0.0);
    nl.build(p, &[]);
    for [i, j] in nl.pairs() {
        let (i, j) = (i as usize, j as usize);
        if p.position[i] == p.position[j] {
            return Err(CaseError::Geometry(format!(
                "{} and particle {} have the same centre: their contact has no normal direction; move one of them",
                at(i),
                p.id[j]
            )));
        }
        let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
        let r = p.radius[i].min(p.radius[j]);
        if overlap > max_overlap * r {
            return Err(CaseError::Geometry(format!(
                "{} and particle {} overlap by {:.3e} m = {:.3} of the smaller radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                at(i),
                p.id[j],
                overlap,
                overlap / r
            )));
        }
    }
    Ok(())
}

/// An explicit time step above the contact law's stability limit is refused unless forced;
/// MFIX's rule above it (possible only through stiff walls, which MFIX leaves out) warns.
/// The step in use.
fn check_stability(
    rule: TimeStepRule,
    span: f64,
    law: &ContactLaw,
    phases: &[Phase],
    wall_materials: &[WallMaterial],
    pair_params: &[ContactParams],
    wall_params: &[ContactParams],
    force: bool,
    warnings: &mut Vec<String>,
) -> Result<f64, CaseError> {
    let table = grainflow::contact::CoeffTable::build(law, phases, wall_materials, pair_params, wall_params)?;
    let limit = grainflow::timestep::stability_limit(law, phases, wall_materials, &table);
    // The step and the step count, refused here as the engine would refuse them.
    // (Only the step matters here, not the Hertz collision time the explanation states.)
    let chosen = grainflow::timestep::choose(rule, law, phases, &table, span, &(1.0, String::new()))?;
    match rule {
        TimeStepRule::Fixed(dt) if dt > limit.dt_max => {
            let text = format!(
                "dt = {dt:e} s is above the stability limit {:.4e} s of the {} model ({}); a safe choice is dt = {:.4e} s, or leave dt out for MFIX's rule",
                limit.dt_max,
                law.normal_name(),
                limit.reason,
                limit.dt_safe
            );
            if force {
                warnings.push(format!("[time]: {text} (running anyway: force_dt = true)"));
                Ok(dt)
            } else {
                Err(CaseError::invalid(
                    "[time]",
                    "dt",
                    dt,
                    format!("{text}; set force_dt = true to run anyway"),
                ))
            }
        }
        TimeStepRule::Mfix { factor } => {
            let dt = chosen.dt;
            if dt > limit.dt_max {
                warnings.push(format!(
                    "[time]: MFIX's rule (TCOLL/{factor}) gives dt = {dt:.4e} s, above the stability limit {:.4e} s ({}); consider dt = {:.4e} s",
                    limit.dt_max, limit.reason, limit.dt_safe
                ));
            }
            Ok(dt)
        }
        TimeStepRule::Fixed(dt) => Ok(dt),
    }
}

/// Range checks of one contact table, and warnings for keys the model does not use.
fn check_params(
    table: &str,
    t: &RawContactParams,
    law: ContactLaw,
    warnings: &mut Vec<String>,
) -> Result<(), CaseError> {
    let checks: [(&str, Option<f64>, Range); 10] = [
        ("kn", t.kn, limits::KN),
        ("kt_fac", t.kt_fac, limits::KT_FAC),
        ("etat_fac", t.etat_fac, limits::ETAT_FAC),
        ("en", t.en, limits::EN),
        ("et", t.et, limits::ET),
        ("mu", t.mu, limits::MU),
        ("mu_roll", t.mu_roll, limits::MU_ROLL),
        ("gamma_n", t.gamma_n, limits::GAMMA),
        ("gamma_t", t.gamma_t, limits::GAMMA),
        ("surface_energy", t.surface_energy, limits::SURFACE_ENERGY),
    ];
    for (key, v, r) in checks {
        if let Some(v) = v {
            check(r, table, key, v)?;
        }
    }
    let unused: &[(&str, bool)] = match law.normal {
        NormalModel::LinearSpringDashpot => {
            &[("et", t.et.is_some()), ("surface_energy", t.surface_energy.is_some())]
        }
        NormalModel::Hertz => &[
            ("kn", t.kn.is_some()),
            ("kt_fac", t.kt_fac.is_some()),
            ("surface_energy", t.surface_energy.is_some()),
        ],
        NormalModel::Jkr => &[
            ("kn", t.kn.is_some()),
            ("kt_fac", t.kt_fac.is_some()),
            ("et", t.et.is_some()),
            ("hertz_kn", t.hertz_kn.is_some()),
            ("hertz_kt", t.hertz_kt.is_some()),
        ],
    };
    for (key, given) in unused {
        if *given {
            warnings
                .push(format!("{table}: `{key}` is not used by the {} model (ignored)", law.normal_name()));
        }
    }
    Ok(())
}

/// Layers an override table over the defaults table over MFIX's built-in defaults, and checks
/// that the model's required values are present.
fn layer(
    over: Option<&RawContactParams>,
    base: &RawContactParams,
    law: ContactLaw,
    base_table: &str,
    what: &str,
) -> Result<ContactParams, CaseError> {
    let d = ContactParams::default();
    let pick = |f: fn(&RawContactParams) -> Option<f64>| over.and_then(f).or_else(|| f(base));
    let p = ContactParams {
        kn: pick(|t| t.kn),
        kt_fac: pick(|t| t.kt_fac).unwrap_or(d.kt_fac),
        etat_fac: pick(|t| t.etat_fac).unwrap_or(d.etat_fac),
        en: pick(|t| t.en).unwrap_or(d.en),
        et: pick(|t| t.et),
        mu: pick(|t| t.mu).unwrap_or(d.mu),
        mu_roll: pick(|t| t.mu_roll).unwrap_or(d.mu_roll),
        gamma_n: pick(|t| t.gamma_n),
        gamma_t: pick(|t| t.gamma_t),
        hertz_kn: pick(|t| t.hertz_kn),
        hertz_kt: pick(|t| t.hertz_kt),
        surface_energy: pick(|t| t.surface_energy),
    };
    match law.normal {
        NormalModel::LinearSpringDashpot if p.kn.is_none() => Err(CaseError::missing(
            base_table,
            "kn",
            format!("normal stiffness in N/m for the {what}; set it there or in an override table"),
        )),
        NormalModel::Hertz
            if p.et.is_none()
                && matches!(law.damping, NormalDamping::Mfix | NormalDamping::ExactRestitution) =>
        {
            Err(CaseError::missing(
                base_table,
                "et",
                format!("tangential restitution for the {what}, required by the hertz model"),
            ))
        }
        NormalModel::Jkr if p.surface_energy.is_none() => Err(CaseError::missing(
            base_table,
            "surface_energy",
            format!(
                "surface energy γ in J/m² for the {what}, required by the jkr model (LAMMPS's: the pull-off force is 3πγR*)"
            ),
        )),
        NormalModel::LinearSpringDashpot | NormalModel::Hertz | NormalModel::Jkr => Ok(p),
    }
}
