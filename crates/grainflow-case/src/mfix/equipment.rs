//! The equipment of a deck: the box's faces (walls, cyclic pairs, flow boundaries), the STL
//! walls of `CG_*` boundary conditions, DEM mass inflows (`MI`) and pressure outflows (`PO`),
//! and the particles `GENER_PART_CONFIG` generates in the IC regions.
//!
//! MFIX's rules, as grainflow follows them:
//! - a face of the box is a DEM wall unless its axis is cyclic or a flow boundary lies on it
//!   (with STL geometry too: MFIX turns the box's default walls into facets);
//! - a `CG_NSW`, `CG_FSW` or `CG_PSW` boundary whose region is an STL region gives its facets
//!   as a mesh wall; slip conditions are the gas's, the DEM wall is the same for all three;
//! - `MI` inserts particles through its face at the flux its solids volume fraction and
//!   velocity (or `BC_MASSFLOW_S`) give; `PO` removes the particles whose centres cross it;
//! - `GENER_PART_CONFIG` fills each IC region with its phases' volume fractions, at the
//!   region's solids velocity, with the region's size distribution.

use super::deck::show;
use super::geometry;
use super::{Translator, seed};
use crate::error::CaseError;
use crate::input;
use crate::raw::*;
use grainflow::{Phase, Vec3};

/// The box faces, by axis and side, as the case names them.
const FACES: [[&str; 2]; 3] = [["x_min", "x_max"], ["y_min", "y_max"], ["z_min", "z_max"]];
/// The region keywords of a boundary or initial condition, by axis: (low, high).
const BC_KEYS: [(&str, &str); 3] = [("BC_X_W", "BC_X_E"), ("BC_Y_S", "BC_Y_N"), ("BC_Z_B", "BC_Z_T")];
const BC_INDEX_KEYS: [(&str, &str); 3] = [("BC_I_W", "BC_I_E"), ("BC_J_S", "BC_J_N"), ("BC_K_B", "BC_K_T")];

/// What the boundary conditions and IC regions give the case.
#[derive(Debug, Default)]
pub(super) struct Equipment {
    /// The faces of the box that are walls.
    pub walls: Vec<&'static str>,
    /// The cyclic axes.
    pub periodic: Vec<String>,
    pub meshes: Vec<RawMesh>,
    pub insertions: Vec<RawInsertion>,
    pub outlets: Vec<RawOutlet>,
    /// True when a flow boundary opens the box: particles leaving it are removed.
    pub open: bool,
    /// The particles `GENER_PART_CONFIG` seeds.
    pub particles: Vec<RawParticle>,
}

/// A boundary region flat on one axis: the plane and the rectangle on it.
struct Flat {
    axis: usize,
    at: f64,
    lo: Vec3,
    hi: Vec3,
}

impl Translator<'_> {
    /// What a 2-D (`NO_K`) deck may not have: gravity along z, and the features that place
    /// particles or walls in 3-D (generated particles, mass inflows, STL walls).
    pub(super) fn two_d_checks(&mut self, gravity: [f64; 3]) -> Result<(), CaseError> {
        let d = self.deck;
        let loc = d.bool("NO_K", &[])?.map_or(self.origin.to_string(), |g| g.loc.to_string());
        if gravity[2] != 0.0 {
            self.block(CaseError::invalid(
                loc.clone(),
                "GRAVITY_Z",
                gravity[2],
                "a 2-D run (NO_K = .TRUE.) has no z direction: gravity must lie in x and y",
            ));
        }
        for (key, what) in
            [("GENER_PART_CONFIG", "particles generated in 2-D"), ("USE_STL", "STL walls in 2-D")]
        {
            if self.flag(key)? {
                self.block(CaseError::invalid(
                    loc.clone(),
                    "NO_K",
                    ".TRUE.",
                    format!("grainflow cannot run this: {what} ({key} with NO_K) are not supported; list the particles in particle_input.dat (x y radius density u v)"),
                ));
            }
        }
        for idx in d.indices("BC_TYPE") {
            if let Some(t) = self.word("BC_TYPE", &idx)?
                && matches!(t.v.as_str(), "MI" | "MASS_INFLOW")
            {
                self.block(Self::invalid_word(
                    &t,
                    "grainflow cannot run this: a mass inflow in a 2-D run (NO_K) is not supported",
                ));
            }
        }
        Ok(())
    }

    /// The cyclic axes (`CYCLIC_X`, `CYCLIC_X_PD`, …). With no gas, a pressure-driven cyclic
    /// axis is an ordinary one for the particles.
    pub(super) fn cyclic(&mut self) -> Result<[bool; 3], CaseError> {
        let mut on = [false; 3];
        for (a, ax) in ["X", "Y", "Z"].iter().enumerate() {
            on[a] = self.flag(&format!("CYCLIC_{ax}"))? || self.flag(&format!("CYCLIC_{ax}_PD"))?;
            if self.flag(&format!("CYCLIC_{ax}_PD"))? {
                self.note(format!(
                    "{}: CYCLIC_{ax}_PD: the pressure drop acts on the gas only; with no gas the {} axis is periodic for the particles",
                    self.origin,
                    ax.to_ascii_lowercase()
                ));
            }
        }
        Ok(on)
    }

    /// The region of boundary condition `i` by coordinates, or by cell indices on MFIX's
    /// uniform grid (`IMAX` cells across the box; cells 1 and IMAX+2 are the ghost layers
    /// outside the faces).
    fn bc_region(&self, i: i64, lo: Vec3, hi: Vec3) -> Result<Option<(Vec3, Vec3)>, CaseError> {
        let d = self.deck;
        let cells = [d.int("IMAX", &[])?, d.int("JMAX", &[])?, d.int("KMAX", &[])?].map(|g| g.map(|g| g.v));
        let mut a_lo = lo;
        let mut a_hi = hi;
        for a in 0..3 {
            let (kw, ke) = BC_KEYS[a];
            let (iw, ie) = BC_INDEX_KEYS[a];
            match (self.real(kw, &[i])?, self.real(ke, &[i])?) {
                (Some(w), Some(e)) => {
                    a_lo[a] = w.v.min(e.v);
                    a_hi[a] = w.v.max(e.v);
                    continue;
                }
                (None, None) => {}
                _ => return Ok(None),
            }
            match (d.int(iw, &[i])?, d.int(ie, &[i])?, cells[a]) {
                (Some(w), Some(e), Some(n)) if n > 0 => {
                    let dx = (hi[a] - lo[a]) / n as f64;
                    // Cell k (2..=n+1) spans [lo + (k − 2)·dx, lo + (k − 1)·dx]; a ghost cell
                    // stands for its face.
                    let west = |k: i64| lo[a] + ((k - 2).clamp(0, n) as f64) * dx;
                    let east = |k: i64| lo[a] + ((k - 1).clamp(0, n) as f64) * dx;
                    let (w, e) = (w.v.min(e.v), w.v.max(e.v));
                    if w == e && (w == 1 || w == n + 2) {
                        a_lo[a] = if w == 1 { lo[a] } else { hi[a] };
                        a_hi[a] = a_lo[a];
                    } else {
                        a_lo[a] = west(w);
                        a_hi[a] = east(e);
                    }
                }
                (None, None, _) => {}
                _ => return Ok(None),
            }
        }
        Ok(Some((a_lo, a_hi)))
    }

    /// A boundary region flat on exactly one axis.
    fn flat(lo: Vec3, hi: Vec3, size: Vec3) -> Option<Flat> {
        let flat: Vec<usize> = (0..3).filter(|&a| (hi[a] - lo[a]).abs() <= 1e-9 * size[a]).collect();
        match flat[..] {
            [axis] => Some(Flat { axis, at: lo[axis], lo, hi }),
            _ => None,
        }
    }

    /// The boundary conditions and, with `GENER_PART_CONFIG`, the generated particles.
    pub(super) fn equipment(
        &mut self,
        lo: Vec3,
        hi: Vec3,
        periodic: [bool; 3],
        phases: &[Phase],
        t_start: f64,
        exists: &dyn Fn(&str) -> bool,
        read_file: &input::Opener<'_>,
    ) -> Result<Equipment, CaseError> {
        let d = self.deck;
        let size = hi - lo;
        let stl = self.flag("CARTESIAN_GRID")? && self.flag("USE_STL")?;
        if self.flag("USE_STL")?
            && !self.flag("CARTESIAN_GRID")?
            && let Some(g) = d.bool("USE_STL", &[])?
        {
            self.note(format!(
                "{}: USE_STL = .TRUE. without CARTESIAN_GRID = .TRUE.: MFIX reads no STL file then, and neither does grainflow",
                g.loc
            ));
        }
        let mut eq = Equipment {
            periodic: (0..3).filter(|&a| periodic[a]).map(|a| ["x", "y", "z"][a].to_string()).collect(),
            ..Default::default()
        };
        // Faces opened by flow boundaries, by axis and side.
        let mut open = [[false; 2]; 3];
        let mut bcs: Vec<i64> = Vec::new();
        for key in ["BC_TYPE", "BC_X_W", "BC_X_E", "BC_Y_S", "BC_Y_N", "BC_Z_B", "BC_Z_T"] {
            bcs.extend(d.indices(key).into_iter().filter_map(|i| i.first().copied()));
        }
        bcs.sort_unstable();
        bcs.dedup();
        let mut stl_bcs = Vec::new();
        let mut walls_on_faces = Vec::new();
        for i in bcs {
            let Some(t) = self.word("BC_TYPE", &[i])? else { continue };
            let kind = t.v.as_str();
            let cg_wall = matches!(kind, "CG_NSW" | "CG_FSW" | "CG_PSW");
            let wall = cg_wall
                || matches!(
                    kind,
                    "NSW" | "FSW" | "PSW" | "NO_SLIP_WALL" | "FREE_SLIP_WALL" | "PAR_SLIP_WALL"
                );
            if wall {
                if self.moving_wall(i)? {
                    continue;
                }
                if cg_wall && stl {
                    stl_bcs.push(i);
                    continue;
                }
                // A wall region on a face of the box is a DEM wall anyway.
                let region = self.bc_region(i, lo, hi)?;
                let on_face = region.is_some_and(|(a, b)| {
                    Self::flat(a, b, size).is_some_and(|f| {
                        (f.at - lo[f.axis]).abs() <= 1e-9 * size[f.axis]
                            || (f.at - hi[f.axis]).abs() <= 1e-9 * size[f.axis]
                    })
                });
                if on_face {
                    walls_on_faces.push(format!("BC_TYPE({i}) = '{kind}' ({})", t.loc));
                } else if cg_wall {
                    self.block(Self::invalid_word(
                        &t,
                        format!(
                            "grainflow cannot run this: a cut-cell wall needs STL geometry (CARTESIAN_GRID = .TRUE. and USE_STL = .TRUE.); boundary {i}'s region is not on a face of the box"
                        ),
                    ));
                } else {
                    self.block(Self::invalid_word(
                        &t,
                        format!(
                            "grainflow cannot run this: wall region {i} does not lie on a face of the box (e.g. BC_X_W({i}) = BC_X_E({i}) = X_MIN); a wall inside the box is an obstacle: describe it as STL geometry (CARTESIAN_GRID, USE_STL) or use [[walls]] planes in a TOML case"
                        ),
                    ));
                }
                continue;
            }
            if matches!(kind, "PI" | "P_INFLOW" | "OF" | "OUTFLOW") {
                self.block(Self::invalid_word(
                    &t,
                    "grainflow cannot run this: MFIX refuses pressure inflows ('PI') and outflows ('OF') with DEM particles; use 'PO' or 'MO' for an outlet, 'MI' for an inlet",
                ));
                continue;
            }
            let flow = matches!(kind, "MI" | "MASS_INFLOW" | "PO" | "P_OUTFLOW" | "MO" | "MASS_OUTFLOW");
            if !flow {
                self.block(Self::invalid_word(
                    &t,
                    "must be a wall ('NSW', 'FSW', 'PSW', their 'CG_' forms) or a flow boundary ('MI', 'PO', 'MO')",
                ));
                continue;
            }
            let Some((a, b)) = self.bc_region(i, lo, hi)? else {
                self.block(CaseError::invalid(
                    t.loc.to_string(),
                    show("BC_TYPE", &[i]),
                    format!("'{kind}'"),
                    format!("boundary {i} needs its region: BC_X_W({i}), BC_X_E({i}), … (or the cell indices BC_I_W({i}), …)"),
                ));
                continue;
            };
            let Some(f) = Self::flat(a, b, size) else {
                self.block(Self::invalid_word(
                    &t,
                    format!("a flow boundary is a plane: boundary {i}'s region must be flat in exactly one of x, y, z"),
                ));
                continue;
            };
            let side = if (f.at - lo[f.axis]).abs() <= 1e-9 * size[f.axis] {
                0
            } else if (f.at - hi[f.axis]).abs() <= 1e-9 * size[f.axis] {
                1
            } else {
                self.block(Self::invalid_word(
                    &t,
                    format!(
                        "grainflow cannot run this: flow boundary {i} lies inside the box; grainflow's flow boundaries lie on its faces"
                    ),
                ));
                continue;
            };
            if periodic[f.axis] {
                self.block(Self::invalid_word(
                    &t,
                    format!("boundary {i} lies on a face of a cyclic axis, which has no boundary"),
                ));
                continue;
            }
            // Outward normal of the face.
            let mut normal = [0.0; 3];
            normal[f.axis] = if side == 0 { -1.0 } else { 1.0 };
            let mut point = f.lo;
            point[f.axis] = f.at;
            if matches!(kind, "MI" | "MASS_INFLOW") {
                let ins = self.mass_inflow(i, &f, normal, phases, t_start, read_file)?;
                if ins.is_empty() {
                    // No solids come in: MFIX keeps the face a wall.
                    continue;
                }
                eq.insertions.extend(ins);
            } else {
                eq.outlets.push(RawOutlet {
                    name: Some(format!("bc{i}")),
                    region: None,
                    point: Some(point.to_array()),
                    normal: Some(normal),
                });
            }
            open[f.axis][side] = true;
            eq.open = true;
        }
        if !walls_on_faces.is_empty() {
            self.note(format!(
                "{}: wall boundary conditions on faces of the box, which are DEM walls anyway (their gas-side settings are ignored): {}",
                self.origin,
                walls_on_faces.join(", ")
            ));
        }
        let no_k = self.flag("NO_K")?;
        for (a, faces) in FACES.iter().enumerate() {
            for (s, face) in faces.iter().enumerate() {
                if !(periodic[a] || open[a][s] || (a == 2 && no_k)) {
                    eq.walls.push(face);
                }
            }
        }
        // Internal surfaces: STL ones are walls too (MFIX reads is_NNNN.stl).
        let mut is_ids: Vec<i64> =
            d.indices("IS_TYPE").into_iter().filter_map(|i| i.first().copied()).collect();
        is_ids.sort_unstable();
        is_ids.dedup();
        let mut stl_is = Vec::new();
        for i in is_ids {
            let Some(t) = self.word("IS_TYPE", &[i])? else { continue };
            if t.v == "STL" && stl {
                stl_is.push(i);
            } else {
                self.block(Self::invalid_word(
                    &t,
                    "grainflow cannot run this: of the internal surfaces only STL ones (IS_TYPE = 'STL', with CARTESIAN_GRID and USE_STL) are read; give others as [[walls]] or [[meshes]] in a TOML case",
                ));
            }
        }
        if !stl_is.is_empty() {
            match geometry::is_walls(&self.lexed.gui, &stl_is, exists) {
                Ok(walls) => self.push_walls(walls, true, &mut eq)?,
                Err(message) => self.block(CaseError::Geometry(format!("{}: {message}", self.origin))),
            }
        }
        if !stl_bcs.is_empty() {
            self.stl_walls(&stl_bcs, exists, &mut eq)?;
        } else if stl {
            self.note(format!(
                "{}: CARTESIAN_GRID and USE_STL are set but no boundary condition is a cut-cell wall ('CG_NSW', 'CG_FSW', 'CG_PSW'): the run has the box's walls only",
                self.origin
            ));
        }
        if self.flag("GENER_PART_CONFIG")? {
            let walls = self.load_walls(&eq.meshes, read_file)?;
            eq.particles = self.generated(lo, hi, phases, &walls, read_file)?;
            if eq.insertions.is_empty()
                && eq.particles.is_empty()
                && let Some(g) = d.bool("GENER_PART_CONFIG", &[])?
            {
                self.block(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "no IC region has a solids volume fraction IC_EP_S(i,m) > 0 (or MFIX's lattice holds none of its particles) and no mass inflow brings particles: the run would have none",
                ));
            }
        }
        Ok(eq)
    }

    /// True (and reported as a blocker) if wall `i` is given a velocity: a deck cannot say
    /// which part of the wall moves how; a motion file can.
    fn moving_wall(&mut self, i: i64) -> Result<bool, CaseError> {
        let d = self.deck;
        for key in ["BC_UW_S", "BC_VW_S", "BC_WW_S"] {
            for idx in d.indices(key).into_iter().filter(|x| x.first() == Some(&i)) {
                if let Some(g) = d.real(key, &idx)?
                    && g.v != 0.0
                {
                    self.block(CaseError::invalid(
                        g.loc.to_string(),
                        g.key,
                        g.text,
                        "grainflow cannot run this: a wall velocity from the deck is not read; give the wall's motion in a --motion file ([[walls]] tables, docs/mfix-decks.md); only 0 is accepted here",
                    ));
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// The STL facets of the cut-cell walls, as mesh walls.
    fn stl_walls(
        &mut self,
        bcs: &[i64],
        exists: &dyn Fn(&str) -> bool,
        eq: &mut Equipment,
    ) -> Result<(), CaseError> {
        let walls = match geometry::stl_walls(&self.lexed.gui, bcs, exists) {
            Ok(w) => w,
            Err(message) => {
                self.block(CaseError::Geometry(format!("{}: {message}", self.origin)));
                return Ok(());
            }
        };
        self.push_walls(walls, false, eq)
    }

    /// STL walls as `[[meshes]]`: boundary conditions' or (`internal`) internal surfaces'.
    fn push_walls(
        &mut self,
        walls: Vec<geometry::StlWall>,
        internal: bool,
        eq: &mut Equipment,
    ) -> Result<(), CaseError> {
        // MFIX's own transform of geometry.stl (SCALE_STL, then TX/TY/TZ_STL).
        let scale = self.real("SCALE_STL", &[])?.map_or(1.0, |g| g.v);
        let shift = [
            self.real("TX_STL", &[])?.map_or(0.0, |g| g.v),
            self.real("TY_STL", &[])?.map_or(0.0, |g| g.v),
            self.real("TZ_STL", &[])?.map_or(0.0, |g| g.v),
        ];
        for w in walls {
            let (s, t) = if w.from_solver_file {
                (scale * w.scale, [0, 1, 2].map(|k| scale * w.translate[k] + shift[k]))
            } else {
                (w.scale, w.translate)
            };
            eq.meshes.push(RawMesh {
                name: Some(w.name.clone()),
                file: Some(w.file.clone()),
                material: None,
                scale: (s != 1.0).then_some(s),
                rotate: (w.rotate != [0.0; 3]).then_some(w.rotate),
                translate: (t != [0.0; 3]).then_some(t),
                flip_normals: w.flip_normals.then_some(true),
                // MFIX reads files with zero-area facets; they touch nothing.
                skip_degenerate: Some(true),
                motion: None,
                surface: None,
                torque_about: None,
            });
            self.mesh_bcs.push(if internal { -w.bc } else { w.bc });
        }
        Ok(())
    }

    /// A phase's size distribution from `{prefix}_PSD_TYPE(i,m)` and its parameters.
    fn psd(
        &mut self,
        prefix: &str,
        i: i64,
        m: i64,
        phase: &Phase,
        read_file: &input::Opener<'_>,
    ) -> Result<RawInsertPhase, CaseError> {
        let mut p = RawInsertPhase {
            phase: Some(phase.name.clone()),
            fraction: None,
            distribution: None,
            diameter: None,
            mean: None,
            sigma: None,
            min_diameter: None,
            max_diameter: None,
            diameters: None,
            weights: None,
            weights_by: None,
            cdf: None,
        };
        let idx = [i, m];
        let kind = self.word(&format!("{prefix}_PSD_TYPE"), &idx)?;
        let key = |k: &str| format!("{prefix}_PSD_{k}");
        let need = |t: &mut Self, k: &str| -> Result<Option<f64>, CaseError> {
            let name = key(k);
            match t.real(&name, &idx)? {
                Some(g) if g.v.is_finite() && g.v > 0.0 => Ok(Some(g.v)),
                Some(g) => {
                    Err(CaseError::invalid(g.loc.to_string(), g.key, g.text, "must be a positive length"))
                }
                None => Ok(None),
            }
        };
        let Some(kind) = kind else { return Ok(p) };
        match kind.v.as_str() {
            "MONO" => {}
            "NORMAL" | "LOG_NORMAL" => {
                let mean = need(self, "MEAN_DP")?;
                let sigma = need(self, "STDEV")?;
                let (min, max) = (need(self, "MIN_DP")?, need(self, "MAX_DP")?);
                let (Some(mean), Some(sigma), Some(min), Some(max)) = (mean, sigma, min, max) else {
                    return Err(CaseError::missing(
                        kind.loc.to_string(),
                        format!(
                            "{}, {}, {}, {}",
                            show(&key("MEAN_DP"), &idx),
                            show(&key("STDEV"), &idx),
                            show(&key("MIN_DP"), &idx),
                            show(&key("MAX_DP"), &idx)
                        ),
                        format!("{} = '{}' needs its mean, standard deviation and bounds", kind.key, kind.v),
                    ));
                };
                p.distribution = Some(if kind.v == "NORMAL" { "normal" } else { "lognormal" }.into());
                p.mean = Some(mean);
                p.sigma = Some(sigma);
                p.min_diameter = Some(min);
                p.max_diameter = Some(max);
            }
            "UNIFORM" => {
                let (Some(min), Some(max)) = (need(self, "MIN_DP")?, need(self, "MAX_DP")?) else {
                    return Err(CaseError::missing(
                        kind.loc.to_string(),
                        format!("{}, {}", show(&key("MIN_DP"), &idx), show(&key("MAX_DP"), &idx)),
                        format!("{} = 'UNIFORM' needs its bounds", kind.key),
                    ));
                };
                p.distribution = Some("uniform".into());
                p.min_diameter = Some(min);
                p.max_diameter = Some(max);
            }
            "CUSTOM" => {
                let (diameters, cdf) = self.custom_psd(&kind, prefix, i, m, read_file)?;
                p.distribution = Some("cdf".into());
                p.diameters = Some(diameters);
                p.cdf = Some(cdf);
            }
            _ => {
                return Err(Self::invalid_word(
                    &kind,
                    "must be 'MONO', 'NORMAL', 'LOG_NORMAL', 'UNIFORM' or 'CUSTOM'",
                ));
            }
        }
        Ok(p)
    }

    /// The particles `GENER_PART_CONFIG` seeds in the IC regions, as MFIX seeds them
    /// ([`super::seed`]), behind none of the STL walls `walls`.
    fn generated(
        &mut self,
        lo: Vec3,
        hi: Vec3,
        phases: &[Phase],
        walls: &[grainflow::mesh::Mesh],
        read_file: &input::Opener<'_>,
    ) -> Result<Vec<RawParticle>, CaseError> {
        let d = self.deck;
        let mut ics: Vec<i64> = d.indices("IC_EP_S").into_iter().filter_map(|i| i.first().copied()).collect();
        ics.sort_unstable();
        ics.dedup();
        let mut rng = seed::stream();
        let mut out = Vec::new();
        let mut parts_of = Vec::new();
        for &ic in &ics {
            let mut parts = Vec::new();
            for (m, phase) in phases.iter().enumerate() {
                let m = m as i64 + 1;
                let Some(ep) = self.real("IC_EP_S", &[ic, m])? else { continue };
                if !(0.0..1.0).contains(&ep.v) {
                    return Err(CaseError::invalid(
                        ep.loc.to_string(),
                        ep.key,
                        ep.text,
                        "must be a solids volume fraction in [0, 1)",
                    ));
                }
                if ep.v == 0.0 {
                    continue;
                }
                let velocity = [
                    self.real("IC_U_S", &[ic, m])?.map_or(0.0, |g| g.v),
                    self.real("IC_V_S", &[ic, m])?.map_or(0.0, |g| g.v),
                    self.real("IC_W_S", &[ic, m])?.map_or(0.0, |g| g.v),
                ];
                // A granular temperature, m²/s² (cm²/s² in a CGS deck).
                let theta = self.real("IC_THETA_M", &[ic, m])?.map_or(0.0, |g| g.v.max(0.0))
                    / if self.cgs { 1e4 } else { 1.0 };
                let part = self.psd("IC", ic, m, phase, read_file)?;
                let sizes = crate::flow::sizes(&part, &show("IC_PSD_TYPE", &[ic, m]), phase)?;
                parts.push(seed::SeedPhase { ic, m, phase, ep: ep.v, sizes, velocity, theta });
            }
            if !parts.is_empty() {
                parts_of.push((ic, parts));
            }
        }
        // MFIX's MAX_RADIUS: the largest radius of the particles it seeds.
        let max_radius = parts_of
            .iter()
            .flat_map(|(_, parts)| parts.iter().map(|p| 0.5 * p.sizes.max_diameter()))
            .fold(0.0, f64::max);
        for (ic, parts) in &parts_of {
            let region = self.ic_box(*ic, lo, hi)?;
            out.extend(self.seed(region, parts, walls, max_radius, &mut rng)?);
        }
        Ok(out)
    }

    /// A DEM mass inflow through face `f`: each phase with a solids volume fraction
    /// `BC_EP_S(i,m)` and a velocity into the box (or a `BC_MASSFLOW_S(i,m)`) is inserted at
    /// the mass rate ε_s·A·|v|·ρ_s, in layers two largest diameters deep just inside the face,
    /// one layer each time the stream has carried the last one clear.
    fn mass_inflow(
        &mut self,
        i: i64,
        f: &Flat,
        outward: [f64; 3],
        phases: &[Phase],
        t_start: f64,
        read_file: &input::Opener<'_>,
    ) -> Result<Vec<RawInsertion>, CaseError> {
        let area: f64 = (0..3).filter(|&a| a != f.axis).map(|a| f.hi[a] - f.lo[a]).product();
        let mut out = Vec::new();
        for (m, phase) in phases.iter().enumerate() {
            let m = m as i64 + 1;
            let idx = [i, m];
            let ep = self.real("BC_EP_S", &idx)?;
            let massflow = self.real("BC_MASSFLOW_S", &idx)?;
            let v = Vec3::new(
                self.real("BC_U_S", &idx)?.map_or(0.0, |g| g.v),
                self.real("BC_V_S", &idx)?.map_or(0.0, |g| g.v),
                self.real("BC_W_S", &idx)?.map_or(0.0, |g| g.v),
            );
            let inward = -v.dot(Vec3::from_array(outward));
            let rho = phase.density;
            let (mass_rate, speed, what) = match (&ep, &massflow) {
                (_, Some(q)) if q.v > 0.0 => {
                    let e = ep.as_ref().map_or(0.0, |g| g.v);
                    // Without a velocity MFIX derives it from the flux: |v| = Q/(ρ ε A).
                    let speed = if inward > 0.0 {
                        inward
                    } else if e > 0.0 {
                        q.v / (rho * e * area)
                    } else {
                        0.0
                    };
                    (q.v, speed, q.key.clone())
                }
                (Some(e), _) if e.v > 0.0 => (e.v * area * inward.max(0.0) * rho, inward, e.key.clone()),
                _ => continue,
            };
            if !(mass_rate > 0.0 && speed > 0.0) {
                let g = ep.as_ref().or(massflow.as_ref()).expect("one of them is given");
                self.block(CaseError::invalid(
                    g.loc.to_string(),
                    g.key.clone(),
                    g.text.clone(),
                    format!(
                        "mass inflow {i} needs a solids velocity into the box (BC_U_S, BC_V_S, BC_W_S({i},{m})) with {what}"
                    ),
                ));
                continue;
            }
            let part = self.psd("BC", i, m, phase, read_file)?;
            let dmax = part
                .max_diameter
                .or(part.diameters.as_ref().and_then(|d| d.last().copied()))
                .unwrap_or(phase.diameter);
            // What the inflow brings by TSTOP, at least (in its largest particles), must fit
            // the memory limit: refused here, at its keyword, before the run is planned.
            let span = self.real("TSTOP", &[])?.map_or(0.0, |g| g.v) - t_start;
            let at_least = mass_rate * span.max(0.0) / (rho * std::f64::consts::FRAC_PI_6 * dmax.powi(3));
            let needed = crate::plan::estimate(at_least, 0.0, 0.0, 0.0, grainflow::Integrator::Euler).bytes;
            if let Err(why) = crate::plan::check_memory(
                needed,
                &format!(
                    "mass inflow {i} ({mass_rate:e} kg/s until TSTOP, {at_least:.4e} particles at least)"
                ),
            ) {
                let g =
                    massflow.as_ref().filter(|q| q.v > 0.0).or(ep.as_ref()).expect("one of them is given");
                self.block(CaseError::invalid(g.loc.to_string(), g.key.clone(), g.text.clone(), why));
                continue;
            }
            // The layer just inside the face, two largest diameters deep (whole spheres fit
            // in it at any height of one diameter's range); a batch each time the stream has
            // carried the last one through it, so the layer's solids fraction is ε_s.
            let depth = 2.0 * dmax;
            let mut lo = f.lo;
            let mut hi = f.hi;
            let inward_sign = -outward[f.axis];
            if inward_sign > 0.0 {
                lo[f.axis] = f.at;
                hi[f.axis] = f.at + depth;
            } else {
                lo[f.axis] = f.at - depth;
                hi[f.axis] = f.at;
            }
            let velocity = if v.length_squared() > 0.0 { v } else { Vec3::from_array(outward) * -speed };
            out.push(RawInsertion {
                name: Some(format!("bc{i}_{}", phase.name)),
                region: Some(RawRegion {
                    kind: Some("box".into()),
                    min: Some(lo.to_array()),
                    max: Some(hi.to_array()),
                    base: None,
                    axis: None,
                    length: None,
                    radius: None,
                    mesh: None,
                }),
                file: None,
                count: None,
                volume_fraction: None,
                mass: None,
                at: None,
                rate: None,
                mass_rate: Some(mass_rate),
                start: Some(t_start),
                every: Some(depth / speed),
                velocity: Some(velocity.to_array()),
                seed: None,
                fractions_by: None,
                phases: vec![part],
            });
        }
        if out.is_empty() {
            self.note(format!(
                "{}: mass inflow {i} brings no solids (no BC_EP_S({i},m) > 0 or BC_MASSFLOW_S({i},m) > 0): its face stays a wall, as in MFIX",
                self.origin
            ));
        }
        Ok(out)
    }
}

impl Translator<'_> {
    /// The custom size distribution of `{prefix}_PSD_TYPE(i,m) = 'CUSTOM'`: MFIX's file of
    /// `n, 1`, `CDF`, one header line, then n rows `diameter value` (list-directed: commas or
    /// spaces), diameters in the deck's length unit.
    fn custom_psd(
        &mut self,
        kind: &super::deck::Got<String>,
        prefix: &str,
        i: i64,
        m: i64,
        read_file: &input::Opener<'_>,
    ) -> Result<(Vec<f64>, Vec<f64>), CaseError> {
        let exists = |n: &str| read_file(n).is_ok();
        let name = self.custom_psd_file(prefix, i, m, &exists)?;
        let reader = read_file(&name).map_err(|e| {
            CaseError::invalid(
                kind.loc.to_string(),
                kind.key.clone(),
                format!("'{}'", kind.v),
                format!("the custom size distribution file {name} cannot be read beside the deck: {e}"),
            )
        })?;
        let mut stream = input::Stream::new(reader, &name);
        let err =
            |line: usize, message: String| CaseError::ParticleFile { path: name.clone(), line, message };
        let mut rows: Option<usize> = None;
        let mut form: Option<String> = None;
        let mut header = false;
        let mut diameters = Vec::new();
        let mut values = Vec::new();
        while let Some((line, text)) = stream.next_line()? {
            let t = text.trim();
            if t.is_empty() {
                continue;
            }
            let fields: Vec<&str> =
                t.split(|c: char| c == ',' || c.is_whitespace()).filter(|f| !f.is_empty()).collect();
            let Some(n) = rows else {
                let n = fields
                    .first()
                    .and_then(|f| f.parse::<usize>().ok())
                    .filter(|&n| (2..=100_000).contains(&n));
                rows = Some(n.ok_or_else(|| err(line, format!("'{t}': the first line must be the number of rows (2 to 100 000) and of columns, e.g. '51, 1'")))?);
                continue;
            };
            if form.is_none() {
                let f = t.to_ascii_uppercase();
                if f != "CDF" && f != "PDF" {
                    return Err(err(line, format!("'{t}': the second line must be CDF or PDF")));
                }
                form = Some(f);
                continue;
            }
            if !header {
                header = true;
                continue;
            }
            if diameters.len() == n {
                return Err(err(line, format!("more rows than the {n} the first line gives")));
            }
            let num = |f: Option<&&str>| {
                f.and_then(|f| f.replace(['d', 'D'], "e").parse::<f64>().ok()).filter(|v| v.is_finite())
            };
            let (Some(d), Some(v)) = (num(fields.first()), num(fields.get(1))) else {
                return Err(err(line, format!("'{t}': a row is a diameter and a value")));
            };
            diameters.push(if self.cgs { d / 100.0 } else { d });
            values.push(v);
        }
        let n = rows.unwrap_or(0);
        if diameters.len() != n || n == 0 {
            return Err(err(0, format!("{} rows, but the first line gives {n}", diameters.len())));
        }
        let cdf = if form.as_deref() == Some("PDF") {
            // A density at each diameter, linear between them: the cdf is its running
            // trapezoidal integral, normalised.
            let mut c = vec![0.0; n];
            for k in 1..n {
                c[k] = c[k - 1] + 0.5 * (values[k] + values[k - 1]) * (diameters[k] - diameters[k - 1]);
            }
            let total = c[n - 1];
            if total.is_nan() || total <= 0.0 {
                return Err(err(0, "the density integrates to zero".into()));
            }
            c.iter().map(|x| x / total).collect()
        } else {
            values
        };
        let check = grainflow::insertion::psd::SizeDistribution::Cdf {
            diameters: diameters.clone(),
            cdf: cdf.clone(),
        }
        .check();
        check.map_err(|e| err(0, e.to_string()))?;
        Ok((diameters, cdf))
    }
}

impl Translator<'_> {
    /// The file of a custom size distribution: MFIX's solver reads `IC_PSD_iiii_mmmm.txt`
    /// (`BC_…` for a boundary), which its GUI writes from the file its `psd` and
    /// `ic_distributions` (`bc_distributions`) comments name; without the solver's file the
    /// GUI's is read.
    fn custom_psd_file(
        &self,
        prefix: &str,
        i: i64,
        m: i64,
        exists: &dyn Fn(&str) -> bool,
    ) -> Result<String, CaseError> {
        let solver = format!("{prefix}_PSD_{i:04}_{m:04}.txt");
        if exists(&solver) {
            return Ok(solver);
        }
        let gui = &self.lexed.gui;
        let lower = prefix.to_ascii_lowercase();
        let from_gui = || -> Option<String> {
            let table = geometry::gui_json(gui, &format!("{lower}_distributions"))?.ok()?;
            let name = table.as_array()?.iter().find_map(|row| {
                let row = row.as_array()?;
                (row.first()?.as_i64()? == i).then_some(())?;
                row.get(1)?.as_array()?.iter().find_map(|pm| {
                    let pm = pm.as_array()?;
                    (pm.first()?.as_i64()? == m).then(|| pm.get(1)?.as_str().map(str::to_string))?
                })
            })?;
            let psd = geometry::gui_json(gui, "psd")?.ok()?;
            psd.get(&name)?.get("filename")?.as_str().map(|f| f.replace("${proj_dir}/", ""))
        };
        match from_gui() {
            Some(f) if exists(&f) => Ok(f),
            Some(f) => Err(CaseError::Geometry(format!(
                "{}: the custom size distribution of {} = 'CUSTOM' is in {solver}, or in {f} as the GUI's comments say; neither can be read beside the deck",
                self.origin,
                show(&format!("{prefix}_PSD_TYPE"), &[i, m])
            ))),
            None => Err(CaseError::Geometry(format!(
                "{}: the custom size distribution of {} = 'CUSTOM' is read from {solver} beside the deck, which cannot be read",
                self.origin,
                show(&format!("{prefix}_PSD_TYPE"), &[i, m])
            ))),
        }
    }
}

impl Translator<'_> {
    /// The STL walls as meshes, loaded as the case will load them, for seeding.
    pub(super) fn load_walls(
        &mut self,
        meshes: &[RawMesh],
        read_file: &input::Opener<'_>,
    ) -> Result<Vec<grainflow::mesh::Mesh>, CaseError> {
        use std::io::Read;
        let mut out = Vec::new();
        for m in meshes {
            let file = m.file.clone().unwrap_or_default();
            let mut bytes = Vec::new();
            read_file(&file)?
                .take(input::MAX_PARTICLE_FILE_BYTES)
                .read_to_end(&mut bytes)
                .map_err(|source| CaseError::Read { path: file.clone().into(), source })?;
            let transform = grainflow::mesh::MeshTransform {
                scale: m.scale.unwrap_or(1.0),
                rotation_deg: m.rotate.unwrap_or([0.0; 3]),
                translation: Vec3::from_array(m.translate.unwrap_or([0.0; 3])),
                flip_normals: m.flip_normals.unwrap_or(false),
                skip_degenerate: m.skip_degenerate.unwrap_or(false),
            };
            let mesh = grainflow::mesh::Mesh::from_stl(&file, &bytes, &transform).map_err(|e| {
                CaseError::Geometry(format!(
                    "{}: the STL wall {}: {e}",
                    self.origin,
                    m.name.clone().unwrap_or_default()
                ))
            })?;
            out.push(mesh);
        }
        Ok(out)
    }
}
