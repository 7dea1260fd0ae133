//! `[[meshes]]`: triangle-mesh walls, their files, transforms, motions and surfaces.

use super::fields::{require, vec3};
use super::materials::material_index;
use crate::error::CaseError;
use crate::raw::{RawMesh, RawMeshMotion, RawMeshSurface, RawTime};
use grainflow::mesh::{
    KeyFrames, Mesh, MeshError, MeshMotion, MeshTransform, MeshWall, MotionWindow, SurfaceMotion,
};
use grainflow::{Vec3, WallMaterial};
use std::path::Path;

/// The mesh walls, their names and the points their torques are reported about, in the order
/// of the case file.
pub(super) struct MeshSet {
    pub walls: Vec<MeshWall>,
    pub names: Vec<String>,
    pub torque_about: Vec<Vec3>,
}

/// The `[[meshes]]` tables, each mesh read (through `read_bytes`) and checked against the
/// domain; its motion is timed from `[time] t_start`.
pub(super) fn meshes(
    raw_meshes: &[RawMesh],
    time: Option<&RawTime>,
    (min, max): (Vec3, Vec3),
    wall_materials: &[WallMaterial],
    read_bytes: &dyn Fn(&str) -> Result<Vec<u8>, CaseError>,
    warnings: &mut Vec<String>,
) -> Result<MeshSet, CaseError> {
    let mut meshes: Vec<MeshWall> = Vec::new();
    let mut mesh_names: Vec<String> = Vec::new();
    let mut mesh_torque_about: Vec<Vec3> = Vec::new();
    // The meshes' motions are timed from the run's start ([time] is checked below).
    let t_start_given = time.and_then(|t| t.t_start).filter(|t| t.is_finite()).unwrap_or(0.0);
    for (k, m) in raw_meshes.iter().enumerate() {
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
        let material = material_index(wall_materials, &m.material, &table, "material")?;
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
            None => rotation_axis(&wall).map_or(Vec3::ZERO, |(origin, _)| origin),
        };
        meshes.push(wall);
        mesh_names.push(name);
        mesh_torque_about.push(about);
    }
    Ok(MeshSet { walls: meshes, names: mesh_names, torque_about: mesh_torque_about })
}

/// The rotation axis of a mesh that turns, or whose surface turns: (a point on it, its
/// direction); `None` for any other mesh.
pub fn rotation_axis(wall: &MeshWall) -> Option<(Vec3, Vec3)> {
    match (wall.motion, wall.surface) {
        (MeshMotion::Rotate { origin, axis, .. }, _) | (_, SurfaceMotion::Rotate { origin, axis, .. }) => {
            Some((origin, axis))
        }
        _ => None,
    }
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
