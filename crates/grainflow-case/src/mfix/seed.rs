//! `GENER_PART_CONFIG`: the particles MFIX 21.3 seeds in its IC regions
//! (`des/generate_particles_mod.f`, `GENERATE_PARTICLE_CONFIG_DEM`), placed as MFIX places
//! them, so that a deck starts with MFIX's count in MFIX's lattice:
//!
//! - the count is ⌊ε_s·V/v̄⌋, v̄ the mean particle volume of the phase's size distribution and
//!   V the fluid volume of the grid cells the IC covers (its faces moved to the nearest faces
//!   of MFIX's uniform grid, `CALC_CELL`, ties to the lower face): with STL walls only the part
//!   of each cut cell on the particles' side, and no cell behind the walls (MFIX's
//!   `GET_IC_VOLUME`; [`super::cells`]);
//! - the sites are MFIX's lattice in the IC region as given, `IC_DES_LATTICE` 'HEXA' (its default) or 'CUBIC', spaced by
//!   the largest diameter times 1 + `IC_DES_SPACING` (0.05), filled from the bottom (−y)
//!   upwards, x fastest; seeding stops after the first whole xz-plane that reaches the count,
//!   and the last sites seeded beyond the count are dropped; `IC_DES_RAND` jitters the sites
//!   by up to ±½ of `IC_DES_RAND`·spacing·d (a quarter for 'HEXA'), as MFIX does;
//! - with STL walls, a site is skipped when its cell has no fluid in it, or (with
//!   `IC_DES_CHECK_STL_OVERLAP`, the default) when it lies behind the plane of a facet near
//!   its cell or within 1.05 largest radii of that plane (MFIX's
//!   `CHECK_IF_PARTICLE_OVERLAPS_STL` on its DES grid, [`super::cells::DesGrid`]); a deck
//!   without MFIX's grid (`IMAX`, `JMAX`, `KMAX`) falls back to the nearest triangle;
//! - several phases of one IC are seeded one above the other, each from the last one's top;
//! - diameters are drawn from the phase's distribution and velocities are the IC's, with
//!   normal fluctuations of variance `IC_THETA_M` in each component, from a seeded stream
//!   (MFIX's random numbers are not reproduced).

use super::Translator;
use super::deck::show;
use crate::error::CaseError;
use crate::raw::RawParticle;
use grainflow::insertion::InsertRng;
use grainflow::mesh::Mesh;
use grainflow::{Phase, Vec3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

/// The most sites a deck may seed (a mistyped volume fraction must not ask for gigabytes).
const MAX_SITES: usize = 20_000_000;

/// One phase of an IC region to seed.
pub(super) struct SeedPhase<'a> {
    pub ic: i64,
    pub m: i64,
    pub phase: &'a Phase,
    pub ep: f64,
    pub sizes: grainflow::insertion::psd::SizeDistribution,
    pub velocity: [f64; 3],
    pub theta: f64,
}

impl Translator<'_> {
    /// The region of IC `ic` as given (clipped to the box), where MFIX seeds its lattice, the
    /// volume of the grid cells it covers, which sets MFIX's count without STL walls, and
    /// those cells' index ranges on MFIX's grid (when the deck gives the grid).
    pub(super) fn ic_box(&self, ic: i64, lo: Vec3, hi: Vec3) -> Result<IcRegion, CaseError> {
        const KEYS: [(&str, &str, &str); 3] =
            [("IC_X_W", "IC_X_E", "IMAX"), ("IC_Y_S", "IC_Y_N", "JMAX"), ("IC_Z_B", "IC_Z_T", "KMAX")];
        let mut a = lo;
        let mut b = hi;
        let mut volume = 1.0;
        let mut range = Some([[0usize; 2]; 3]);
        for (k, (kw, ke, kn)) in KEYS.iter().enumerate() {
            let (Some(w), Some(e)) = (self.real(kw, &[ic])?, self.real(ke, &[ic])?) else {
                return Err(CaseError::missing(
                    self.origin,
                    format!("{}, {}", show(kw, &[ic]), show(ke, &[ic])),
                    format!(
                        "the region of initial condition {ic}, whose particles GENER_PART_CONFIG generates"
                    ),
                ));
            };
            let cells = self.deck.int(kn, &[])?.map(|g| g.v).filter(|&n| n > 0);
            let snap = |x: f64| match cells {
                Some(n) if k < 2 || !self.flag("NO_K").unwrap_or(false) => {
                    let dx = (hi[k] - lo[k]) / n as f64;
                    let f = ((x - lo[k]) / dx).clamp(0.0, n as f64);
                    // The nearest face, a tie going to the lower one (MFIX's CALC_CELL).
                    let below = f.floor();
                    let face = if f - below <= 0.5 { below } else { below + 1.0 };
                    lo[k] + face * dx
                }
                _ => x.clamp(lo[k], hi[k]),
            };
            if w.v > e.v {
                // MFIX stops on such a region (its check of the IC's bounds): it is empty.
                return Err(CaseError::invalid(
                    e.loc.to_string(),
                    show(ke, &[ic]),
                    e.text,
                    format!(
                        "initial condition {ic}'s region ends before it starts: {} = {} is above it (MFIX refuses this region)",
                        show(kw, &[ic]),
                        w.text
                    ),
                ));
            }
            a[k] = w.v.max(lo[k]);
            b[k] = e.v.min(hi[k]);
            match (cells, range.as_mut()) {
                (Some(n), Some(r)) => {
                    let dx = (hi[k] - lo[k]) / n as f64;
                    let index = |x: f64| ((snap(x) - lo[k]) / dx).round().clamp(0.0, n as f64) as usize;
                    r[k] = [index(a[k]), index(b[k])];
                }
                _ => range = None,
            }
            let cells = snap(b[k]) - snap(a[k]);
            volume *= if k == 2 && self.flag("NO_K")? { 1.0 } else { cells };
            if b[k] <= a[k] || cells <= 0.0 {
                return Err(CaseError::invalid(
                    w.loc.to_string(),
                    show(kw, &[ic]),
                    w.text,
                    format!("initial condition {ic}'s region is empty inside the box (on MFIX's grid)"),
                ));
            }
        }
        Ok(IcRegion { start: a, end: b, volume, cells: range })
    }

    /// MFIX's lattice sites for the phases of one IC region, skipped where MFIX skips them
    /// near or behind the STL walls, as particles.
    pub(super) fn seed(
        &mut self,
        region: IcRegion,
        parts: &[SeedPhase<'_>],
        walls: &[Mesh],
        stl: Option<&StlGrids>,
        max_radius: f64,
        rng: &mut InsertRng,
    ) -> Result<Vec<RawParticle>, CaseError> {
        let no_k = self.flag("NO_K")?;
        let (start, end) = (region.start, region.end);
        // MFIX counts the fluid volume of the IC's cells: with STL walls, only the part of
        // each cut cell on the particles' side, and no cell behind the walls.
        let volume = match (stl, region.cells) {
            (Some(g), Some(r)) => {
                let v = g.fluid.fluid_volume(r, g.tol_small);
                if v < region.volume {
                    self.note(format!(
                        "{}: initial condition {}: the fluid volume of its cells inside the STL walls is {v:.6e} m³ of their {:.6e} m³ (MFIX's count is taken from it)",
                        self.origin,
                        parts.first().map_or(0, |p| p.ic),
                        region.volume
                    ));
                }
                v
            }
            _ => region.volume,
        };
        let mut y_init = start.y;
        let mut out = Vec::new();
        for part in parts {
            let (ic, m) = (part.ic, part.m);
            let idx = [ic, m];
            let v_mean = std::f64::consts::FRAC_PI_6 * part.sizes.mean_cube();
            let want = (part.ep * volume / v_mean).floor();
            if want.is_nan() || want >= MAX_SITES as f64 {
                return Err(CaseError::invalid(
                    self.origin,
                    show("IC_EP_S", &idx),
                    part.ep,
                    format!(
                        "asks for {want:e} particles in initial condition {ic}; at most {MAX_SITES} are seeded"
                    ),
                ));
            }
            if let Err(why) = crate::plan::check_memory(
                crate::plan::seeded_bytes(want),
                &format!("seeding {want:e} particles in initial condition {ic}"),
            ) {
                return Err(CaseError::invalid(self.origin, show("IC_EP_S", &idx), part.ep, why));
            }
            let want = want as usize;
            if want == 0 {
                continue;
            }
            let lattice = self.word("IC_DES_LATTICE", &idx)?.map_or("HEXA".to_string(), |g| g.v);
            let spacing = self.real("IC_DES_SPACING", &idx)?.map_or(0.05, |g| g.v);
            let factor = |k: &str| -> Result<f64, CaseError> {
                Ok(self.real(&format!("IC_DES_SPACE_FACTOR_{k}"), &idx)?.map_or(1.0, |g| g.v))
            };
            let (fx, fy, fz) = (factor("X")?, factor("Y")?, factor("Z")?);
            let dmax = part.sizes.max_diameter();
            let r = [
                0.5 * dmax * (1.0 + spacing * fx),
                0.5 * dmax * (1.0 + spacing * fy),
                0.5 * dmax * (1.0 + spacing * fz),
            ];
            let len = end - start;
            let ly = end.y - y_init;
            let trunc = |l: f64, r: f64| ((l - r) / r).trunc();
            let s3 = 3f64.sqrt();
            let s6 = 6f64.sqrt();
            let mut z_init = start.z;
            let mut narrow = false;
            let (nx, ny, nz, cell) = match lattice.as_str() {
                "CUBIC" => {
                    let n = |l: f64, d: f64| ((l - d) / d).floor().max(1.0) as usize;
                    let (nx, ny, nz) = (n(len.x, 2.0 * r[0]), n(ly, 2.0 * r[1]), n(len.z, 2.0 * r[2]));
                    (
                        nx,
                        ny,
                        if no_k { 1 } else { nz },
                        [len.x / nx as f64, ly / ny as f64, if no_k { 0.0 } else { len.z / nz as f64 }],
                    )
                }
                "HEXA" if !no_k => {
                    let nx = (0.5 * trunc(len.x, r[0]) - 1.5).floor();
                    let ny = (1.5 * (trunc(ly, r[1]) - 1.0) / s6).floor();
                    let mut nz = ((trunc(len.z, r[2]) - 1.0) / s3 - 1.0 / 3.0).floor();
                    if nz < 1.0 {
                        nz = 1.0;
                        narrow = true;
                        z_init = 0.5 * (start.z + end.z);
                    }
                    (nx.max(1.0) as usize, ny.max(1.0) as usize, nz as usize, [0.0; 3])
                }
                "HEXA" => {
                    let nx = (0.5 * trunc(len.x, r[0]) - 0.5).floor();
                    let ny = (1.5 * (trunc(ly, r[0]) - 1.0) / s3).floor();
                    (nx.max(1.0) as usize, ny.max(1.0) as usize, 1, [0.0; 3])
                }
                other => {
                    let g = self.word("IC_DES_LATTICE", &idx)?.expect("given");
                    return Err(Self::invalid_word(&g, format!("'{other}': must be 'HEXA' or 'CUBIC'")));
                }
            };
            if nx.saturating_mul(ny).saturating_mul(nz) > MAX_SITES {
                return Err(CaseError::invalid(
                    self.origin,
                    show("IC_EP_S", &idx),
                    part.ep,
                    format!("initial condition {ic}'s lattice has more than {MAX_SITES} sites"),
                ));
            }
            let two_d = no_k || narrow;
            let site = |ii: usize, jj: usize, kk: usize| -> Vec3 {
                let (ii, jj, kk) = (ii as f64, jj as f64, kk as f64);
                match lattice.as_str() {
                    "CUBIC" => Vec3::new(
                        start.x + (ii - 1.0) * cell[0] + 0.5 * cell[0],
                        y_init + (jj - 1.0) * cell[1] + 0.5 * cell[1],
                        z_init + (kk - 1.0) * cell[2] + 0.5 * cell[2],
                    ),
                    _ if !two_d => Vec3::new(
                        start.x + (2.0 * ii + ((jj + kk) % 2.0)) * r[0],
                        y_init + (2.0 * jj / 3.0) * s6 * r[1],
                        z_init + (kk + (jj % 2.0) / 3.0) * s3 * r[2],
                    ),
                    _ => Vec3::new(start.x + (2.0 * ii + (jj % 2.0)) * r[0], y_init + jj * s3 * r[1], z_init),
                }
            };
            // IC_DES_RAND: a uniform jitter of the sites, rfac·(U − ½) per axis.
            let rand = self.real("IC_DES_RAND", &idx)?.map_or(0.0, |g| g.v);
            let base = if lattice == "CUBIC" { 1.0 } else { 0.5 };
            let jitter = base * rand * spacing * dmax;
            let jitter_factor = [
                self.real("IC_DES_RAND_FACTOR_X", &idx)?.map_or(1.0, |g| g.v) * fx,
                self.real("IC_DES_RAND_FACTOR_Y", &idx)?.map_or(1.0, |g| g.v) * fy,
                self.real("IC_DES_RAND_FACTOR_Z", &idx)?.map_or(1.0, |g| g.v) * fz,
            ];
            let check_stl = self.deck.bool("IC_DES_CHECK_STL_OVERLAP", &idx)?.is_none_or(|g| g.v);
            let mut seeded: Vec<RawParticle> = Vec::new();
            let mut top = y_init;
            'planes: for jj in 1..=ny {
                for kk in 1..=nz {
                    for ii in 1..=nx {
                        let mut p = site(ii, jj, kk);
                        if jitter > 0.0 {
                            for (c, f) in jitter_factor.iter().enumerate() {
                                if c < 2 || !no_k {
                                    p[c] += (rng.random::<f64>() - 0.5) * jitter * f;
                                }
                            }
                        }
                        if no_k {
                            p.z = 0.0;
                        }
                        top = top.max(p.y);
                        match stl {
                            Some(g) => {
                                // MFIX seeds only in cells with fluid in them, and (with
                                // IC_DES_CHECK_STL_OVERLAP) clear of the planes of the
                                // facets around the site's cell.
                                if !g.fluid.wet(p) {
                                    continue;
                                }
                                if check_stl
                                    && let Some((west, east)) = g.fluid.faces_of(p)
                                    && !g.des.clear(p, west, east, &g.facets)
                                {
                                    continue;
                                }
                            }
                            None => {
                                if check_stl && !walls.is_empty() && !clear_of(p, walls, 1.05 * max_radius) {
                                    continue;
                                }
                            }
                        }
                        let diameter = part.sizes.sample(rng);
                        let mut v = part.velocity;
                        if part.theta > 0.0 {
                            let s = part.theta.sqrt();
                            for (c, vc) in v.iter_mut().enumerate() {
                                if c < 2 || !no_k {
                                    let z: f64 = StandardNormal.sample(rng);
                                    *vc += s * z;
                                }
                            }
                        }
                        seeded.push(RawParticle {
                            id: None,
                            phase: Some(part.phase.name.clone()),
                            position: Some(p.to_array()),
                            velocity: (v != [0.0; 3]).then_some(v),
                            angular_velocity: None,
                            diameter: (diameter != part.phase.diameter).then_some(diameter),
                        });
                    }
                }
                if seeded.len() >= want {
                    break 'planes;
                }
            }
            if seeded.len() < want {
                self.note(format!(
                    "{}: initial condition {ic}, phase {m}: MFIX's lattice holds {} of the {want} particles IC_EP_S({ic},{m}) = {} asks for; {} are seeded, as MFIX seeds them",
                    self.origin,
                    seeded.len(),
                    part.ep,
                    seeded.len()
                ));
            }
            seeded.truncate(want);
            // The next phase starts above this one (MFIX's yINIT).
            y_init = top + r[1];
            out.append(&mut seeded);
        }
        Ok(out)
    }
}

/// An IC region: its box as given (clipped to the domain), the volume of MFIX's grid cells it
/// covers and their index ranges [from, to) on each axis (without a grid in the deck, none).
pub(super) struct IcRegion {
    pub start: Vec3,
    pub end: Vec3,
    pub volume: f64,
    pub cells: Option<[[usize; 2]; 3]>,
}

/// MFIX's fluid and DES grids cut by the deck's STL walls ([`super::cells`]).
pub(super) struct StlGrids {
    pub facets: Vec<super::cells::Facet>,
    pub fluid: super::cells::FluidGrid,
    pub des: super::cells::DesGrid,
    /// `TOL_SMALL_CELL`: cut cells with less fluid are not counted in an IC's volume.
    pub tol_small: f64,
}

/// True if `p` is in front of its nearest triangle (without MFIX's grid in the deck) (on the side its normal points to, the
/// particles' side) and farther than `gap` from every triangle.
fn clear_of(p: Vec3, walls: &[Mesh], gap: f64) -> bool {
    let mut best = f64::INFINITY;
    let mut squareness = 0.0;
    let mut front = true;
    for mesh in walls {
        let normals = mesh.normals();
        for t in 0..mesh.triangle_count() as u32 {
            let c = mesh.corners(t);
            // A cheap lower bound first: the distance to the triangle's bounding box.
            let lo = c[0].min(c[1]).min(c[2]);
            let hi = c[0].max(c[1]).max(c[2]);
            let outside = (lo - p).max(p - hi).max(Vec3::ZERO);
            if outside.length() > best * (1.0 + 1e-9) {
                continue;
            }
            let q = grainflow::mesh::contact::closest_point_on_triangle(p, c).point;
            let dist = (p - q).length();
            let side = (p - q).dot(normals[t as usize]);
            // Of triangles equally near (at an edge or a corner), the one facing p most
            // squarely tells the side.
            let square = if dist > 0.0 { side.abs() / dist } else { 1.0 };
            if dist < best * (1.0 - 1e-9) || (dist <= best * (1.0 + 1e-9) && square > squareness) {
                best = dist;
                squareness = square;
                front = side >= 0.0;
            }
        }
    }
    front && best > gap
}

/// The stream that draws the seeded particles' sizes and velocities: one per deck, fixed.
pub(super) fn stream() -> InsertRng {
    InsertRng::seed_from_u64(0x4d46_4958_5345_4544)
}
