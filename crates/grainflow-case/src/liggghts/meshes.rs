//! Mesh walls of a script: `fix mesh/surface` (a mesh read and placed), `fix wall/gran … mesh`
//! (the meshes particles touch) and `fix move/mesh` (how a mesh moves, from the step the fix
//! is defined until it is `unfix`ed), translated to `[[meshes]]` with `[meshes.motion]`.

use super::{Command, Translator, at, number};
use crate::error::CaseError;
use crate::raw::{RawMesh, RawMeshMotion};

/// A `fix mesh/surface`: the file and its placement, as grainflow's transform takes it.
#[derive(Debug, Clone)]
pub(super) struct MeshFix {
    pub id: String,
    pub file: String,
    pub wall_type: usize,
    pub scale: f64,
    /// Degrees about x, y, z (in that order), as `[[meshes]] rotate`.
    pub rotate: [f64; 3],
    pub translate: [f64; 3],
    /// Named by a `fix wall/gran … mesh`: particles touch it.
    pub wall: bool,
    /// `fix move/mesh`: the motion, the step it starts at and the step it stops at.
    pub motion: Option<(RawMeshMotion, u64, Option<u64>, String)>,
}

/// LIGGGHTS's `rotateMesh` turns degrees into radians with π written as 3.14159265: the
/// rotation grainflow is given in degrees is scaled so that it turns by the same angle.
// The value LIGGGHTS writes, deliberately not π.
#[allow(clippy::approx_constant)]
pub(super) const LIGGGHTS_PI: f64 = 3.14159265;

impl Translator {
    /// `fix ID all mesh/surface[/stress] file F type T [scale s] [move x y z]
    /// [rotate axis ax ay az angle a] …`, the placements in the order given (as LIGGGHTS
    /// applies them). grainflow scales, then rotates about x, y, z, then translates: an order
    /// that is not that one is refused.
    pub(super) fn mesh_surface(&mut self, c: &Command) -> Result<(), CaseError> {
        let w = &c.words;
        if w.get(4).map(String::as_str) != Some("file") || w.get(6).map(String::as_str) != Some("type") {
            return Err(at(c, "write `fix ID all mesh/surface file FILE type T …`".into()));
        }
        let mut m = MeshFix {
            id: w[1].clone(),
            file: w[5].clone(),
            wall_type: number(c, 7)? as usize,
            scale: 1.0,
            rotate: [0.0; 3],
            translate: [0.0; 3],
            wall: false,
            motion: None,
        };
        if self.meshes.iter().any(|x| x.id == m.id) {
            return Err(at(c, format!("a mesh `{}` is defined already", m.id)));
        }
        // Kept even if its placement is refused, so that the commands naming it are not
        // refused as well.
        let placed = self.place(c, &mut m);
        self.meshes.push(m);
        placed
    }

    /// The placement keywords of a `mesh/surface` from word 8 on, into `m`.
    fn place(&mut self, c: &Command, m: &mut MeshFix) -> Result<(), CaseError> {
        let w = &c.words;
        // How far along grainflow's order the placements have come: 0 scale, 1–3 the
        // rotations about x, y, z, 4 the translation.
        let mut stage = 0;
        let mut k = 8;
        while k < w.len() {
            let at_stage = |now: usize, stage: &mut usize, what: &str| -> Result<(), CaseError> {
                if now < *stage {
                    return Err(at(
                        c,
                        format!(
                            "`{what}` after a placement grainflow applies later (it scales, then rotates about x, y, z, then moves): write them in that order"
                        ),
                    ));
                }
                *stage = now;
                Ok(())
            };
            match w[k].as_str() {
                "scale" => {
                    at_stage(0, &mut stage, "scale")?;
                    m.scale *= number(c, k + 1)?;
                    k += 2;
                }
                "move" => {
                    at_stage(4, &mut stage, "move")?;
                    for (j, t) in m.translate.iter_mut().enumerate() {
                        *t += number(c, k + 1 + j)?;
                    }
                    k += 4;
                }
                "rotate"
                    if w.get(k + 1).map(String::as_str) == Some("axis")
                        && w.get(k + 5).map(String::as_str) == Some("angle") =>
                {
                    let axis = [number(c, k + 2)?, number(c, k + 3)?, number(c, k + 4)?];
                    let angle = number(c, k + 6)? * LIGGGHTS_PI / std::f64::consts::PI;
                    let along: Vec<usize> = (0..3).filter(|&j| axis[j] != 0.0).collect();
                    if along.len() != 1 {
                        return Err(at(
                            c,
                            "`rotate axis …`: grainflow translates rotations about the x, y or z axis".into(),
                        ));
                    }
                    let j = along[0];
                    at_stage(1 + j, &mut stage, "rotate")?;
                    m.rotate[j] += angle * axis[j].signum();
                    k += 7;
                }
                "heal" | "precision" | "verbose" | "curvature" | "curvature_tolerant" => {
                    self.note(c, "tunes LIGGGHTS's mesh reading (ignored; grainflow refuses a mesh it cannot read as it is)");
                    k += 2;
                }
                other => {
                    return Err(at(
                        c,
                        format!(
                            "`mesh/surface … {other}` is not translated (file, type, scale, move and rotate are)"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The `mesh n_meshes N meshes ID …` part of a `fix wall/gran`: those meshes become walls.
    pub(super) fn mesh_walls(&mut self, c: &Command, from: usize) -> Result<(), CaseError> {
        let w = &c.words;
        if w.get(from + 1).map(String::as_str) != Some("n_meshes")
            || w.get(from + 3).map(String::as_str) != Some("meshes")
        {
            return Err(at(c, "write `fix ID all wall/gran MODEL … mesh n_meshes N meshes ID …`".into()));
        }
        let n = number(c, from + 2)? as usize;
        let ids = &w[(from + 4).min(w.len())..];
        if ids.len() != n {
            return Err(at(c, format!("`n_meshes {n}` names {} meshes", ids.len())));
        }
        for id in ids {
            match self.meshes.iter_mut().find(|m| &m.id == id) {
                Some(m) => m.wall = true,
                None => {
                    return Err(at(c, format!("`meshes {id}`: no `fix {id} all mesh/surface` before it")));
                }
            }
        }
        Ok(())
    }

    /// `fix ID all move/mesh mesh M linear vx vy vz`, `… rotate origin x y z axis ax ay az
    /// period T` or `… wiggle amplitude ax ay az period T`: from this point of the script (the
    /// steps run so far) on.
    pub(super) fn move_mesh(&mut self, c: &Command) -> Result<(), CaseError> {
        let w = &c.words;
        if w.get(4).map(String::as_str) != Some("mesh") || w.len() < 7 {
            return Err(at(c, "write `fix ID all move/mesh mesh MESH linear|rotate …`".into()));
        }
        let num = |k| number(c, k);
        let motion = match (w[6].as_str(), w.len()) {
            ("linear", 10) => RawMeshMotion {
                kind: Some("translate".into()),
                velocity: Some([num(7)?, num(8)?, num(9)?]),
                ..Default::default()
            },
            ("rotate", 17) if w[7] == "origin" && w[11] == "axis" && w[15] == "period" => {
                let period = num(16)?;
                if period == 0.0 {
                    return Err(at(c, "`period 0`: a rotation needs a period".into()));
                }
                RawMeshMotion {
                    kind: Some("rotate".into()),
                    origin: Some([num(8)?, num(9)?, num(10)?]),
                    axis: Some([num(12)?, num(13)?, num(14)?]),
                    omega: Some(2.0 * std::f64::consts::PI / period),
                    ..Default::default()
                }
            }
            // LIGGGHTS moves the mesh by A·ω·cos(ωt)·dt a step, which sums to A·sin(ωt) to
            // first order in the step: grainflow takes the closed form.
            ("wiggle", 13) if w[7] == "amplitude" && w[11] == "period" => {
                let period = num(12)?;
                if period <= 0.0 {
                    return Err(at(c, "`period`: an oscillation needs a positive period".into()));
                }
                RawMeshMotion {
                    kind: Some("oscillate".into()),
                    amplitude: Some([num(8)?, num(9)?, num(10)?]),
                    frequency: Some(1.0 / period),
                    ..Default::default()
                }
            }
            (kind, _) => {
                self.block(c, format!("`move/mesh … {kind}` (or these arguments of it) is not yet translated: `linear VX VY VZ`, `rotate origin … axis … period T` and `wiggle amplitude AX AY AZ period T` are"));
                return Ok(());
            }
        };
        let steps = self.steps;
        let Some(m) = self.meshes.iter_mut().find(|m| m.id == w[5]) else {
            return Err(at(c, format!("`mesh {}`: no `fix {} all mesh/surface` before it", w[5], w[5])));
        };
        if m.motion.is_some() {
            self.block(
                c,
                format!("mesh `{}` gets a second `move/mesh`: one motion a mesh is translated", w[5]),
            );
            return Ok(());
        }
        m.motion = Some((motion, steps, None, w[1].clone()));
        Ok(())
    }

    /// `unfix ID` of a `move/mesh`: the mesh stops where it got to. True if ID was one.
    pub(super) fn unfix_motion(&mut self, id: &str) -> bool {
        let steps = self.steps;
        for m in &mut self.meshes {
            if let Some((_, _, stop @ None, fix)) = &mut m.motion
                && fix == id
            {
                *stop = Some(steps);
                return true;
            }
        }
        false
    }

    /// The `[[meshes]]` of the walls, with their motions timed at `dt`.
    pub(super) fn raw_meshes(&self, dt: f64) -> Vec<RawMesh> {
        self.meshes
            .iter()
            .filter(|m| m.wall)
            .map(|m| RawMesh {
                name: Some(m.id.clone()),
                file: Some(m.file.clone()),
                material: Some(format!("type{}", m.wall_type)),
                scale: Some(m.scale),
                rotate: Some(m.rotate),
                translate: Some(m.translate),
                flip_normals: None,
                skip_degenerate: None,
                motion: m.motion.as_ref().map(|(motion, start, stop, _)| RawMeshMotion {
                    start: (*start > 0).then_some(*start as f64 * dt),
                    stop: stop.map(|s| s as f64 * dt),
                    ..motion.clone()
                }),
                surface: None,
                torque_about: None,
            })
            .collect()
    }
}
