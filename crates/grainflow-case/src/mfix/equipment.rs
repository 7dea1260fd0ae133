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

/// The most cells of MFIX's grid that are cut by the STL walls here (about 100 MB).
const MAX_CUT_GRID: usize = 4_000_000;

/// A mass inflow's insertion and its face, for [`Translator::inflows_inside_the_walls`].
struct Inflow {
    /// Its index in the equipment's insertions.
    insertion: usize,
    bc: i64,
    axis: usize,
    at: f64,
    lo: Vec3,
    hi: Vec3,
    /// +1 if the box lies on the face's upper side, −1 if on its lower.
    inward: f64,
    /// The rate is ε_s·A·|v|·ρ_s, of the face's area (not a given BC_MASSFLOW_S).
    from_area: bool,
}

/// MFIX's windows on a mass inflow's face (`LAYOUT_MI_DEM`): W × H squares of the largest
/// `D_P0` across or a little more, centred on the face; a window is open when it has fluid at
/// its corners and no facet overlaps its box (1.1 windows across, 1.1 diameters deep either
/// side of the face), and MFIX closes the rows and columns at and beyond the outermost ones a
/// facet overlaps. The open windows are returned as runs along the rows of bands of rows,
/// each band tall enough for spheres up to `d_max` across centred in it (its box grown by
/// `r_min`), each run a box on the face.
fn open_windows(
    f: &Inflow,
    max_dia: f64,
    (r_min, d_max): (f64, f64),
    fluid: &super::cells::FluidGrid,
    facets: &[super::cells::Facet],
) -> Vec<(Vec3, Vec3)> {
    let (p, q) = match f.axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let (plen, qlen) = (f.hi[p] - f.lo[p], f.hi[q] - f.lo[q]);
    let wmax = (plen / max_dia).floor() as usize;
    let hmax = (qlen / max_dia).floor() as usize;
    if wmax == 0 || hmax == 0 || wmax * hmax > 4_000_000 {
        return Vec::new();
    }
    let window = (plen / wmax as f64).min(qlen / hmax as f64);
    let p0 = f.lo[p] + 0.5 * (plen - wmax as f64 * window);
    let q0 = f.lo[q] + 0.5 * (qlen - hmax as f64 * window);
    let corner = |w: usize, h: usize| {
        let mut c = Vec3::ZERO;
        c[f.axis] = f.at;
        c[p] = p0 + w as f64 * window;
        c[q] = q0 + h as f64 * window;
        c
    };
    let mut open = vec![false; wmax * hmax];
    let (mut first, mut last) = ([usize::MAX; 2], [0usize; 2]);
    let mut any = false;
    let mut half = Vec3::splat(0.55 * window);
    half[f.axis] = 1.1 * max_dia;
    let tiny = 1e-9 * window;
    for h in 0..hmax {
        for w in 0..wmax {
            let a = corner(w, h);
            let centre = a + 0.5 * (corner(w + 1, h + 1) - a);
            // Fluid at the window's corners, just inside the face.
            let wet = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].iter().all(|&(u, v)| {
                let mut x = a;
                x[p] += u * window + if u == 0.0 { tiny } else { -tiny };
                x[q] += v * window + if v == 0.0 { tiny } else { -tiny };
                x[f.axis] += f.inward * tiny;
                fluid.wet(x)
            });
            let near = facets
                .iter()
                .any(|t| t.spans(f.axis, f.at) && super::cells::tri_box_overlap(centre, half, t.corners()));
            if near {
                any = true;
                first = [first[0].min(w), first[1].min(h)];
                last = [last[0].max(w), last[1].max(h)];
            }
            open[w + wmax * h] = wet && !near;
        }
    }
    if !any && open.iter().all(|&o| o) {
        // Nothing comes near the face: all of it is open, one region.
        let (mut a, mut b) = (f.lo, f.hi);
        a[f.axis] = f.at;
        b[f.axis] = f.at;
        return vec![(a, b)];
    }
    for h in 0..hmax {
        for w in 0..wmax {
            if any && !(w > first[0] && w < last[0] && h > first[1] && h < last[1]) {
                open[w + wmax * h] = false;
            }
        }
    }
    // Bands of `band` rows, each the windows open in all of its rows: tall enough that the
    // largest sphere fits with its centre in the band (the region is the band grown by the
    // smallest radius only, so that no centre leaves the open windows).
    let band = (((d_max - 2.0 * r_min) / window).ceil().max(1.0) as usize).min(hmax);
    let mut runs = Vec::new();
    let mut h0 = 0;
    while h0 + band <= hmax {
        let rows = h0..h0 + band;
        let is_open = |w: usize| rows.clone().all(|h| open[w + wmax * h]);
        let mut w = 0;
        while w < wmax {
            if !is_open(w) {
                w += 1;
                continue;
            }
            let start = w;
            while w < wmax && is_open(w) {
                w += 1;
            }
            runs.push((corner(start, h0), corner(w, h0 + band)));
        }
        h0 += band;
    }
    runs
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
    /// particles or walls in 3-D (generated particles, STL walls). Mass inflows insert in the
    /// plane ([`Self::mass_inflow`]).
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
        let mut inflows: Vec<Inflow> = Vec::new();
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
                for (raw, from_area) in ins {
                    inflows.push(Inflow {
                        insertion: eq.insertions.len(),
                        bc: i,
                        axis: f.axis,
                        at: f.at,
                        lo: f.lo,
                        hi: f.hi,
                        inward: -normal[f.axis],
                        from_area,
                    });
                    eq.insertions.push(raw);
                }
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
        let mut grids = None;
        let gener = self.flag("GENER_PART_CONFIG")?;
        if gener {
            let walls = self.load_walls(&eq.meshes, read_file)?;
            let (particles, g) = self.generated(lo, hi, phases, &walls, read_file)?;
            eq.particles = particles;
            grids = g;
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
        self.inflows_inside_the_walls(&mut eq, &inflows, lo, hi, phases, grids.as_ref(), read_file)?;
        Ok(eq)
    }

    /// MFIX feeds a mass inflow only through the part of its face inside the STL walls: its
    /// rate is ε_s·|v|·ρ_s times the fluid area of the face's cut cells (`BC_AREA`), and its
    /// particles enter through the windows of its face (`LAYOUT_MI_DEM`: squares of the
    /// largest `D_P0` across, centred on the face) that no facet comes near. Each inflow's
    /// region becomes the runs of open windows, one insertion per run, sharing the rate by
    /// their areas.
    fn inflows_inside_the_walls(
        &mut self,
        eq: &mut Equipment,
        inflows: &[Inflow],
        lo: Vec3,
        hi: Vec3,
        phases: &[Phase],
        grids: Option<&seed::StlGrids>,
        read_file: &input::Opener<'_>,
    ) -> Result<(), CaseError> {
        if inflows.is_empty() || eq.meshes.is_empty() || self.flag("NO_K")? {
            return Ok(());
        }
        let d = self.deck;
        let mut n = [0usize; 3];
        for (k, key) in ["IMAX", "JMAX", "KMAX"].iter().enumerate() {
            match d.int(key, &[])? {
                Some(g) if g.v > 0 && g.v <= 10_000 => n[k] = g.v as usize,
                _ => {
                    self.note(format!(
                        "{}: the mass inflows feed through their whole faces: without MFIX's grid (IMAX, JMAX, KMAX) the part of a face inside the STL walls is not known",
                        self.origin
                    ));
                    return Ok(());
                }
            }
        }
        if n.iter().product::<usize>() > MAX_CUT_GRID {
            self.note(format!(
                "{}: the mass inflows feed through their whole faces: MFIX's grid has more than {MAX_CUT_GRID} cells, too many to cut by the STL walls here",
                self.origin
            ));
            return Ok(());
        }
        let own;
        let (facets, fluid) = match grids {
            Some(g) => (&g.facets, &g.fluid),
            None => {
                let walls = self.load_walls(&eq.meshes, read_file)?;
                let facets = super::cells::facets(&walls);
                let fluid = super::cells::FluidGrid::new(lo, hi, n, &facets);
                own = (facets, fluid);
                (&own.0, &own.1)
            }
        };
        let mut replaced: Vec<(usize, Vec<RawInsertion>)> = Vec::new();
        for f in inflows {
            let raw = &eq.insertions[f.insertion];
            let area_full: f64 = (0..3).filter(|&a| a != f.axis).map(|a| f.hi[a] - f.lo[a]).product();
            let area = fluid.face_area(f.axis, f.at, f.inward, f.lo, f.hi, facets);
            // MFIX's windows: squares of the largest D_P0 of the inflow's phases.
            let bc_phases: Vec<usize> = inflows
                .iter()
                .filter(|g| g.bc == f.bc)
                .filter_map(|g| {
                    let name = eq.insertions[g.insertion].phases.first()?.phase.clone()?;
                    phases.iter().position(|p| p.name == name)
                })
                .collect();
            let max_dia = bc_phases.iter().map(|&m| phases[m].diameter).fold(0.0, f64::max);
            let first = raw.phases.first();
            let d_max = first
                .and_then(|p| p.max_diameter.or(p.diameters.as_ref().and_then(|d| d.last().copied())))
                .unwrap_or(max_dia)
                .max(max_dia);
            let r_min = 0.5
                * first
                    .and_then(|p| p.min_diameter.or(p.diameters.as_ref().and_then(|d| d.first().copied())))
                    .unwrap_or(d_max)
                    .min(d_max);
            let runs = open_windows(f, max_dia, (r_min, d_max), fluid, facets);
            let open: f64 = runs
                .iter()
                .map(|(a, b)| (0..3).filter(|&k| k != f.axis).map(|k| b[k] - a[k]).product::<f64>())
                .sum();
            if runs.is_empty() || area.is_nan() || area <= 0.0 {
                self.block(CaseError::Geometry(format!(
                    "{}: mass inflow {} lies outside the STL walls: no part of its face is open (MFIX stops on this: \"no un-cut fluid cells adjacent to DEM_MI staging area\")",
                    self.origin, f.bc
                )));
                continue;
            }
            let rate = raw.mass_rate.unwrap_or(0.0) * if f.from_area { area / area_full } else { 1.0 };
            let region = raw.region.clone().expect("an inflow has a box");
            let (rmin, rmax) = (region.min.expect("box"), region.max.expect("box"));
            // The smallest sphere's centre may reach the runs' edges, none beyond.
            let pad = r_min;
            let whole = runs.len() == 1
                && (0..3).all(|x| x == f.axis || (runs[0].0[x] == f.lo[x] && runs[0].1[x] == f.hi[x]));
            let mut parts = Vec::new();
            for (k, (a, b)) in runs.iter().enumerate() {
                if whole {
                    // All of the face is open: its region as it was, at the fluid area's rate.
                    let mut ins = raw.clone();
                    ins.mass_rate = Some(rate);
                    parts.push(ins);
                    break;
                }
                let share = (0..3).filter(|&x| x != f.axis).map(|x| b[x] - a[x]).product::<f64>() / open;
                let mut r = region.clone();
                let mut lo_r = rmin;
                let mut hi_r = rmax;
                for x in (0..3).filter(|&x| x != f.axis) {
                    // Centres anywhere in the run: the box is grown by the smallest radius
                    // (within the domain).
                    lo_r[x] = (a[x] - pad).max(lo[x]);
                    hi_r[x] = (b[x] + pad).min(hi[x]);
                }
                r.min = Some(lo_r);
                r.max = Some(hi_r);
                let mut ins = raw.clone();
                ins.region = Some(r);
                ins.mass_rate = Some(rate * share);
                if runs.len() > 1 {
                    ins.name = ins.name.map(|n| format!("{n}_{}", k + 1));
                }
                parts.push(ins);
            }
            self.note(format!(
                "{}: mass inflow {}: MFIX feeds it through the part of its face inside the STL walls, {area:.6e} of its {area_full:.6e} m² ({:.1} %), {}",
                self.origin,
                f.bc,
                100.0 * area / area_full,
                if whole {
                    "all of the face open to the particles".to_string()
                } else {
                    format!("entering through {} runs of MFIX's open windows", runs.len())
                }
            ));
            replaced.push((f.insertion, parts));
        }
        // Replace from the last, so that the indices before stay valid.
        replaced.sort_by_key(|r| std::cmp::Reverse(r.0));
        for (at, parts) in replaced {
            eq.insertions.splice(at..=at, parts);
        }
        Ok(())
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
        // The STL's coordinates are in the deck's units, as every length MFIX reads (a CGS
        // deck's geometry is in cm): the file's points and the GUI's translations are scaled
        // to metres with them; TX_STL … are already converted by `real`.
        let unit = if self.cgs { super::keywords::Unit::Length.cgs_to_si(1.0) } else { 1.0 };
        for w in walls {
            let (s, t) = if w.from_solver_file {
                (unit * scale * w.scale, [0, 1, 2].map(|k| unit * scale * w.translate[k] + shift[k]))
            } else {
                (unit * w.scale, w.translate.map(|x| unit * x))
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
    ) -> Result<(Vec<RawParticle>, Option<seed::StlGrids>), CaseError> {
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
                // A granular temperature, m²/s² (cm²/s² in a CGS deck): a variance, never
                // negative (MFIX refuses a negative one).
                let theta = match self.real("IC_THETA_M", &[ic, m])? {
                    Some(g) if g.v.is_nan() || g.v < 0.0 => {
                        return Err(CaseError::invalid(
                            g.loc.to_string(),
                            g.key,
                            g.text,
                            "must be a granular temperature >= 0 (the variance of the velocity fluctuations)",
                        ));
                    }
                    Some(g) => g.v,
                    None => 0.0,
                } / if self.cgs { 1e4 } else { 1.0 };
                let part = self.psd("IC", ic, m, phase, read_file)?;
                let sizes = crate::case::flow::sizes(&part, &show("IC_PSD_TYPE", &[ic, m]), phase)?;
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
        // MFIX's MAX_RADIUS covers every phase and every size distribution's largest size,
        // the inflows' too: it sets the clearance of the seeded sites from the walls.
        let mut max_radius = max_radius;
        for (m, phase) in phases.iter().enumerate() {
            max_radius = max_radius.max(0.5 * phase.diameter);
            for idx in d.indices("BC_PSD_MAX_DP").into_iter().filter(|i| i.get(1) == Some(&(m as i64 + 1))) {
                if let Some(g) = self.real("BC_PSD_MAX_DP", &idx)?
                    && g.v.is_finite()
                {
                    max_radius = max_radius.max(0.5 * g.v);
                }
            }
        }
        let stl = self.stl_grids(lo, hi, walls, max_radius)?;
        for (ic, parts) in &parts_of {
            let region = self.ic_box(*ic, lo, hi)?;
            out.extend(self.seed(region, parts, walls, stl.as_ref(), max_radius, &mut rng)?);
        }
        Ok((out, stl))
    }

    /// MFIX's fluid grid (`IMAX`, `JMAX`, `KMAX`) and DES grid cut by the STL walls, when the
    /// deck has both walls and a grid.
    fn stl_grids(
        &mut self,
        lo: Vec3,
        hi: Vec3,
        walls: &[grainflow::mesh::Mesh],
        max_radius: f64,
    ) -> Result<Option<seed::StlGrids>, CaseError> {
        let d = self.deck;
        if walls.is_empty() || self.flag("NO_K")? {
            return Ok(None);
        }
        let mut n = [0usize; 3];
        for (k, key) in ["IMAX", "JMAX", "KMAX"].iter().enumerate() {
            match d.int(key, &[])? {
                Some(g) if g.v > 0 && g.v <= 10_000 => n[k] = g.v as usize,
                _ => return Ok(None),
            }
        }
        if n.iter().product::<usize>() > MAX_CUT_GRID {
            self.note(format!(
                "{}: MFIX's grid has more than {MAX_CUT_GRID} cells: GENER_PART_CONFIG counts the IC boxes' volume and skips sites by their nearest triangle, not by MFIX's cut cells",
                self.origin
            ));
            return Ok(None);
        }
        let size = hi - lo;
        let mut dg = [0usize; 3];
        for (k, key) in ["DESGRIDSEARCH_IMAX", "DESGRIDSEARCH_JMAX", "DESGRIDSEARCH_KMAX"].iter().enumerate()
        {
            // MFIX's default: cells of three largest diameters, or the fluid cell if smaller.
            let width = (6.0 * max_radius).min(size[k] / n[k] as f64);
            dg[k] = match d.int(key, &[])? {
                Some(g) if g.v > 0 && g.v <= 10_000 => g.v as usize,
                _ => ((size[k] / width).floor() as usize).clamp(1, 10_000),
            };
        }
        if dg.iter().product::<usize>() > 20_000_000 {
            return Ok(None);
        }
        let facets = super::cells::facets(walls);
        let fluid = super::cells::FluidGrid::new(lo, hi, n, &facets);
        let des = super::cells::DesGrid::new(lo, hi, dg, &facets, max_radius);
        let tol_small = d.real("TOL_SMALL_CELL", &[])?.map_or(0.01, |g| g.v);
        Ok(Some(seed::StlGrids { facets, fluid, des, tol_small }))
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
    ) -> Result<Vec<(RawInsertion, bool)>, CaseError> {
        // In 2-D (NO_K) the face is a segment of the plane z = 0, and MFIX's areas take the
        // deck's ZLENGTH as the depth of its one layer of cells.
        let no_k = self.flag("NO_K")?;
        let depth_2d = if no_k {
            match self.real("ZLENGTH", &[])? {
                Some(z) if z.v.is_finite() && z.v > 0.0 => Some(z.v),
                Some(z) => {
                    return Err(CaseError::invalid(
                        z.loc.to_string(),
                        z.key,
                        z.text,
                        "must be a positive length: a 2-D mass inflow's area is its width times ZLENGTH, as in MFIX",
                    ));
                }
                None => {
                    return Err(CaseError::missing(
                        self.origin,
                        "ZLENGTH",
                        format!(
                            "the depth of MFIX's 2-D cells ({}): mass inflow {i}'s area is its width times ZLENGTH, as in MFIX",
                            self.unit_name(super::keywords::Unit::Length)
                        ),
                    ));
                }
            }
        } else {
            None
        };
        let area: f64 =
            (0..3).filter(|&a| a != f.axis && !(a == 2 && no_k)).map(|a| f.hi[a] - f.lo[a]).product::<f64>()
                * depth_2d.unwrap_or(1.0);
        let mut out = Vec::new();
        for (m, phase) in phases.iter().enumerate() {
            let m = m as i64 + 1;
            let idx = [i, m];
            let ep = self.real("BC_EP_S", &idx)?;
            if let Some(g) = &ep
                && !(0.0..1.0).contains(&g.v)
            {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key.clone(),
                    g.text.clone(),
                    "must be a solids volume fraction in [0, 1): a stream of touching spheres holds at most about 0.64, and 1 leaves no room between them",
                ));
            }
            let massflow = self.real("BC_MASSFLOW_S", &idx)?;
            let v = Vec3::new(
                self.real("BC_U_S", &idx)?.map_or(0.0, |g| g.v),
                self.real("BC_V_S", &idx)?.map_or(0.0, |g| g.v),
                self.real("BC_W_S", &idx)?.map_or(0.0, |g| g.v),
            );
            let inward = -v.dot(Vec3::from_array(outward));
            let rho = phase.density;
            let from_area = !massflow.as_ref().is_some_and(|q| q.v > 0.0);
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
            if no_k && part.distribution.is_some() {
                let g = self.word("BC_PSD_TYPE", &idx)?.expect("a distribution is given");
                self.block(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: a size distribution in a 2-D mass inflow (NO_K) is not supported (spheres of several sizes cannot all be placed with their centres in z = 0); give each size its own phase, as MFIX's poly_dem_inlet_outlet does",
                ));
                continue;
            }
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
            if no_k {
                // Centres in z = 0: a box one diameter deep in z holds the spheres only there.
                // The placement keeps a relative rounding margin from the region's faces
                // (`place::MARGIN` of the region's largest coordinate), so the box is that much
                // deeper: the centres lie within twice the margin of z = 0 (below 1e-12 m for a
                // metre-sized box).
                let scale = lo.abs().max(hi.abs()).max_element().max(phase.diameter);
                let slack = 2.0 * grainflow::insertion::place::MARGIN * scale;
                lo.z = -0.5 * phase.diameter - slack;
                hi.z = 0.5 * phase.diameter + slack;
            }
            let mut v = v;
            if no_k {
                v.z = 0.0;
            }
            let velocity = if v.length_squared() > 0.0 { v } else { Vec3::from_array(outward) * -speed };
            out.push((
                RawInsertion {
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
                    plane_z: no_k.then_some(0.0),
                    fractions_by: None,
                    phases: vec![part],
                },
                from_area,
            ));
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
