//! Cylinder walls as a contact source: infinite circular cylinders ([`Cylinder`]), the
//! particles inside (a drum, a pipe) or outside (a rod). The contact is exact: the distance
//! from a centre to the surface is |R − |d⊥|| along the radial direction, no facets. A
//! cylinder's surface may turn about its axis, and its velocity at the contact point enters
//! the contact's relative velocity, so that a drum needs no mesh.
//!
//! Every particle is tested against every cylinder at every evaluation (a few operations each,
//! O(N) for a cylinder): there are no candidates to keep. The loads follow the wall law of the
//! plane walls and meshes ([`wall_law`], effective radius the particle's own), each rounded to
//! the evaluation's quanta (`forces::sum`), so adding them on one thread after the other
//! sources gives the same sums as anywhere else. A contact's tangential history is kept by
//! (slot, cylinder), sorted, from one evaluation to the next; a cohesive law's contact holds
//! to its pull-off distance once formed (it has a history), as at the meshes.

use super::{ContactSource, Diagnosed, LoadRun, MeshLoad, View, wall_coeffs_of};
use crate::contact::law::{normal_spring_energy, parts};
use crate::contact::pair::{PairInput, wall_law};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw, LeverArm};
use crate::forces::{Peak, Quanta, Quantum, max_peak};
use crate::math::Vec3;
use crate::neighbor::NeighborState;
use crate::simulation::{ContactInfo, ContactPartner, Simulation};
use crate::state::Particles;
use crate::surface::{CellData, CellValues, Surface, SurfaceKind, TUBE_FACETS, Which, box_corners};
use crate::wall::{Cylinder, CylinderContact};

/// The tangential history of one particle–cylinder contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CylinderHistory {
    pub slot: u32,
    pub cylinder: u32,
    pub h: Vec3,
}

/// One contact's load on its particle: the force, and the torque about the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LoadPart {
    cylinder: u32,
    centre: Vec3,
    force: Vec3,
    torque: Vec3,
}

/// The cylinder walls, and what their contacts keep between evaluations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cylinders {
    /// The cylinder walls.
    pub walls: Vec<Cylinder>,
    /// The histories of the last evaluation's contacts, by (slot, cylinder).
    pub history: Vec<CylinderHistory>,
    /// The last evaluation's loads on the particles from the cylinders.
    loads: Vec<LoadPart>,
}

/// Slot `i`'s place relative to `cyl` and its overlap, m, if the centre is within the
/// radius plus `reach` of the surface, on the particles' side or behind it.
#[inline]
fn near(cyl: &Cylinder, p: &Particles, i: usize, reach: f64) -> Option<(CylinderContact, f64)> {
    let k = cyl.locate(p.position[i])?;
    let overlap = p.radius[i] - k.distance;
    (overlap > -reach || overlap >= 0.0).then_some((k, overlap))
}

/// The wall law's input for slot `i`'s contact `k` with `cyl`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn cylinder_input(
    p: &Particles,
    law: &ContactLaw,
    i: usize,
    k: &CylinderContact,
    overlap: f64,
    c: &ContactCoeffs,
    h: Vec3,
    cyl: &Cylinder,
) -> PairInput {
    let lever = if law.lever == LeverArm::RadicalPlane { k.distance } else { p.radius[i] };
    PairInput {
        d: -k.normal,
        ra: overlap,
        rb: lever,
        dv: p.velocity[i] - cyl.velocity(k.point),
        wa: p.omega[i],
        wb: Vec3::ZERO,
        h,
        c: *c,
        m_eff: p.mass[i],
    }
}

impl Cylinders {
    /// The cylinder walls `walls`.
    pub(crate) fn new(walls: Vec<Cylinder>) -> Cylinders {
        Cylinders { walls, ..Default::default() }
    }

    /// The stored history of (slot `i`, cylinder `c`), if it has one.
    fn own(&self, i: usize, c: usize) -> Option<Vec3> {
        self.history
            .binary_search_by_key(&(i as u32, c as u32), |h| (h.slot, h.cylinder))
            .ok()
            .map(|j| self.history[j].h)
    }

    /// Calls `visit(slot, cylinder, contact, overlap, coefficients, history)` for every
    /// cylinder contact of the state `v`, as the next evaluation would find them (a cohesive
    /// contact formed at the last evaluation holds to its pull-off distance).
    fn each_contact(
        &self,
        v: &View,
        mut visit: impl FnMut(usize, usize, &CylinderContact, f64, &ContactCoeffs, Vec3),
    ) {
        let (p, reaches) = (v.particles, v.law.normal.reaches());
        // Ghosts' contacts are their owners' ranks' to evaluate.
        for i in 0..v.owned.min(p.len()) {
            for (m, cyl) in self.walls.iter().enumerate() {
                let c = &wall_coeffs_of(v.coeffs, &v.law, p, i, cyl.material);
                let reach = if reaches { c.pull_off } else { 0.0 };
                let Some((k, overlap)) = near(cyl, p, i, reach) else { continue };
                let own = self.own(i, m);
                if overlap >= 0.0 || own.is_some() {
                    visit(i, m, &k, overlap, c, own.unwrap_or(Vec3::ZERO));
                }
            }
        }
    }

    fn contact_infos_for<N: NormalSubModel, T: TangentialSubModel>(
        &self,
        v: &View,
        out: &mut Vec<ContactInfo>,
    ) {
        let law = v.law;
        self.each_contact(v, |i, m, k, overlap, c, h| {
            let input = cylinder_input(v.particles, &law, i, k, overlap, c, h, &self.walls[m]);
            let (load, _, _) = wall_law::<N, T, { parts::ALL }>(&law, 0.0, &input);
            let f_n = load.f.dot(k.normal);
            out.push(ContactInfo {
                particle: i,
                other: ContactPartner::Cylinder(m),
                point: k.point,
                normal: -k.normal,
                overlap,
                normal_force: f_n.abs(),
                tangential_force: (load.f - k.normal * f_n).length(),
            });
        });
    }

    /// The loads on the particles from cylinder `m` at the last force evaluation, each (the
    /// particle's centre, the force, the torque about the centre).
    fn loads_of(&self, m: usize) -> Vec<(Vec3, Vec3, Vec3)> {
        self.loads.iter().filter(|l| l.cylinder == m as u32).map(|l| (l.centre, l.force, l.torque)).collect()
    }

    /// Restores the cylinder contacts' histories of a checkpoint: (particle id, cylinder) and
    /// history of each; `ids` are the particles' ids by slot.
    fn set_histories(&mut self, ids: &[u32], (owners, h): (Vec<[u32; 2]>, Vec<Vec3>)) -> Result<(), String> {
        if owners.len() != h.len() {
            return Err("the cylinder contacts' lists have different lengths".into());
        }
        let slots = crate::state::SlotsById::new(ids);
        let mut history = Vec::with_capacity(h.len());
        for (&[id, cylinder], &h) in owners.iter().zip(&h) {
            let slot = Some(slots.get(id)).filter(|&s| s != crate::state::NO_SLOT).ok_or_else(|| {
                format!("a cylinder contact names particle {id}, which the case does not have")
            })?;
            if cylinder as usize >= self.walls.len() {
                return Err(format!(
                    "a cylinder contact names cylinder {cylinder}, but the case has {}",
                    self.walls.len()
                ));
            }
            history.push(CylinderHistory { slot, cylinder, h });
        }
        // Stable: records come mostly in order (those of particles that stayed).
        history.sort_by_key(|h| (h.slot, h.cylinder));
        if history.windows(2).any(|w| (w[0].slot, w[0].cylinder) == (w[1].slot, w[1].cylinder)) {
            return Err("a cylinder contact appears twice".into());
        }
        self.history = history;
        Ok(())
    }
}

/// The loads, histories and peak of a run of slots' cylinder contacts, in slot order.
#[derive(Debug, Default)]
struct Part {
    stored: Vec<CylinderHistory>,
    loads: Vec<LoadPart>,
    slots: Vec<usize>,
    peak: Peak,
}

/// The settings of one evaluation's cylinder loads: the coefficients, the law, the quanta,
/// whether the springs advance, and their Δt (0 when they do not), s.
type Settings<'a> = (&'a CoeffTable, ContactLaw, Quanta, bool, f64);

impl Cylinders {
    /// The cylinder contacts of the slots `slots` into `out`; `old` holds the histories of the
    /// evaluation before, by (slot, cylinder).
    fn slot_loads<N: NormalSubModel, T: TangentialSubModel>(
        &self,
        p: &Particles,
        (coeffs, law, quanta, advance, dt): Settings,
        slots: std::ops::Range<usize>,
        old: &[CylinderHistory],
        out: &mut Part,
    ) {
        let mut o = old.partition_point(|h| (h.slot as usize) < slots.start);
        for i in slots {
            for (m, cyl) in self.walls.iter().enumerate() {
                let key = (i as u32, m as u32);
                while o < old.len() && (old[o].slot, old[o].cylinder) < key {
                    o += 1;
                }
                let own = (o < old.len() && (old[o].slot, old[o].cylinder) == key).then(|| old[o].h);
                let c = &wall_coeffs_of(coeffs, &law, p, i, cyl.material);
                let reach = if N::REACHES { c.pull_off } else { 0.0 };
                let Some((k, overlap)) = near(cyl, p, i, reach) else { continue };
                if !N::wall_touching(overlap, reach, own.is_some()) {
                    continue;
                }
                let h = own.unwrap_or(Vec3::ZERO);
                let input = cylinder_input(p, &law, i, &k, overlap, c, h, cyl);
                let (load, h_new, bound) = wall_law::<N, T, { parts::ALL }>(&law, dt, &input);
                let round = |q: Quantum, v: Vec3| Vec3::new(q.round(v.x), q.round(v.y), q.round(v.z));
                let (f, ta) = (round(quanta.force, load.f), round(quanta.torque, load.ta));
                out.loads.push(LoadPart { cylinder: m as u32, centre: p.position[i], force: f, torque: ta });
                out.slots.push(i);
                out.peak = max_peak(out.peak, bound);
                out.stored.push(CylinderHistory {
                    slot: i as u32,
                    cylinder: m as u32,
                    h: if advance { h_new } else { h },
                });
            }
        }
    }
}

impl ContactSource for Cylinders {
    /// Every particle's cylinder-contact loads, slot after slot, cylinder after cylinder.
    fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, run: &mut LoadRun) {
        if self.walls.is_empty() {
            return;
        }
        let clock = run.times.is_some().then(std::time::Instant::now);
        let (law, quanta, advance) = (run.law, run.quanta, run.advance);
        let dt = if advance { run.dt } else { 0.0 };
        let old = std::mem::take(&mut self.history);
        let mut part = Part {
            stored: Vec::with_capacity(old.len()),
            loads: std::mem::take(&mut self.loads),
            slots: Vec::new(),
            peak: [0.0; 2],
        };
        part.loads.clear();
        // Ghosts' contacts are their owners' ranks' to evaluate.
        let n = run.owned.min(run.particles.len());
        let settings = (run.coeffs, law, quanta, advance, dt);
        match run.pool.filter(|_| n >= crate::threads::MIN_PARALLEL_SLOTS) {
            Some(pool) => {
                // Runs of slots on the threads, joined in slot order: the loads and histories
                // one pass over the slots gives.
                let p = &*run.particles;
                let found = pool.install(|| {
                    crate::threads::in_runs(n, |slots| {
                        let mut out = Part::default();
                        self.slot_loads::<N, T>(p, settings, slots, &old, &mut out);
                        out
                    })
                });
                for f in found {
                    part.stored.extend_from_slice(&f.stored);
                    part.loads.extend_from_slice(&f.loads);
                    part.slots.extend_from_slice(&f.slots);
                    part.peak = max_peak(part.peak, f.peak);
                }
            }
            None => self.slot_loads::<N, T>(run.particles, settings, 0..n, &old, &mut part),
        }
        let Part { stored, loads, slots, peak } = part;
        let p = &mut *run.particles;
        for (l, &i) in loads.iter().zip(&slots) {
            p.force[i] += l.force;
            p.torque[i] += l.torque;
        }
        run.peak = max_peak(run.peak, peak);
        self.loads = loads;
        // In (slot, cylinder) order, as found.
        self.history = if advance { stored } else { old };
        if let (Some(c), Some(t)) = (clock, run.times.as_deref_mut()) {
            t.walls += c.elapsed().as_secs_f64();
        }
    }

    fn contact_infos(&self, v: &View, out: &mut Vec<ContactInfo>) {
        if self.walls.is_empty() {
            return;
        }
        crate::with_submodels!(v.law, |N, T| self.contact_infos_for::<N, T>(v, out))
    }

    fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed)) {
        let (p, normal) = (v.particles, v.law.normal);
        self.each_contact(v, |i, _, _, overlap, c, _| {
            visit((overlap, p.radius[i], normal_spring_energy(normal, c, overlap)));
        });
    }

    /// Histories of removed slots go; the others go with their particles.
    fn rearrange(&mut self, new_of: &[u32], _list: &mut NeighborState) {
        self.history.retain_mut(|h| {
            let k = new_of[h.slot as usize];
            h.slot = k;
            k != u32::MAX
        });
        // Stable: the kept records are in order already (`new_of` keeps the slots' order).
        self.history.sort_by_key(|h| (h.slot, h.cylinder));
    }

    /// Nothing: appended slots have no history yet, and every slot is tested at every
    /// evaluation.
    fn appended(&mut self, _n_old: usize, _n: usize) {}

    fn heap_bytes(&self) -> usize {
        self.history.capacity() * std::mem::size_of::<CylinderHistory>()
            + self.loads.capacity() * std::mem::size_of::<LoadPart>()
    }

    /// (slot, cylinder, history).
    const CARRIED: usize = 5;

    fn carry(&self, out: &mut Vec<u64>) {
        for h in &self.history {
            out.extend([h.slot as u64, h.cylinder as u64]);
            out.extend(h.h.to_array().map(f64::to_bits));
        }
    }

    fn take_carried(&mut self, ids: &[u32], records: &[u64]) -> Result<(), String> {
        let (mut owners, mut h) = (Vec::new(), Vec::new());
        for r in records.chunks_exact(Self::CARRIED) {
            owners.push([r[0] as u32, r[1] as u32]);
            h.push(Vec3::from_array([r[2], r[3], r[4]].map(f64::from_bits)));
        }
        self.set_histories(ids, (owners, h))
    }

    const SURFACES: &'static [SurfaceKind] = &[CYLINDERS];

    /// The cylinders (if any) as tubes of [`TUBE_FACETS`] quadrilaterals each, of finite
    /// length: the stretch of the axis the box spans. Cell data: `cylinder` (the cylinder's
    /// index), `material`.
    fn surfaces(&self, _sim: &Simulation, lo: Vec3, hi: Vec3, which: Which, out: &mut Vec<Surface>) {
        if !which.wants(CYLINDERS) || self.walls.is_empty() {
            return;
        }
        let mut s = Surface::new(CYLINDERS);
        let (mut index, mut material) = (Vec::new(), Vec::new());
        for (k, c) in self.walls.iter().enumerate() {
            let t = box_corners(lo, hi).map(|x| (x - c.origin).dot(c.axis));
            let (t0, t1) =
                t.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
            let u = c.axis.any_orthonormal_vector();
            let w = c.axis.cross(u);
            let base = s.points.len();
            for j in 0..TUBE_FACETS {
                let phi = std::f64::consts::TAU * j as f64 / TUBE_FACETS as f64;
                let r = (u * phi.cos() + w * phi.sin()) * c.radius;
                s.points.push(c.origin + c.axis * t0 + r);
                s.points.push(c.origin + c.axis * t1 + r);
            }
            for j in 0..TUBE_FACETS {
                let next = (j + 1) % TUBE_FACETS;
                s.push_polygon([base + 2 * j, base + 2 * next, base + 2 * next + 1, base + 2 * j + 1]);
                index.push(k as i32);
                material.push(c.material as i32);
            }
        }
        s.cell_data = vec![
            CellData { name: "cylinder", values: CellValues::Int(index) },
            CellData { name: "material", values: CellValues::Int(material) },
        ];
        out.push(s);
    }
}

/// The cylinders' surface: fixed (a turning shell keeps its shape).
const CYLINDERS: SurfaceKind = SurfaceKind { stem: "cylinders", moves: false };

impl Simulation {
    /// The cylinder walls.
    pub fn cylinders(&self) -> &[Cylinder] {
        &self.sources.cylinders.walls
    }

    /// The load the particles exerted on cylinder `m` at the last force evaluation (zero
    /// before the first): the force, and the torque about `about`. The sums do not depend on
    /// the particles' order; the force is exactly minus the sum of the particles' loads from it.
    /// Spread over ranks, the sums are over every rank's contacts: collective.
    pub fn cylinder_load(&self, m: usize, about: Vec3) -> MeshLoad {
        self.wall_load_over_ranks(&self.sources.cylinders.loads_of(m), about)
    }

    /// Restores the cylinder contacts' histories of a checkpoint: (particle id, cylinder) and
    /// history of each.
    pub(crate) fn set_cylinder_histories(&mut self, lists: (Vec<[u32; 2]>, Vec<Vec3>)) -> Result<(), String> {
        let ids = self.particles().id.clone();
        self.sources.cylinders.set_histories(&ids, lists)
    }
}

/// Refuses a cylinder with a non-finite or meaningless value, or a material not defined
/// (`materials` of them): the message names it.
pub(crate) fn check_cylinder(c: &Cylinder, materials: usize) -> Result<(), String> {
    let name = &c.name;
    if c.material >= materials {
        return Err(format!(
            "cylinder '{name}' uses wall material {} but only {materials} are defined",
            c.material
        ));
    }
    let unit = c.axis.is_finite() && (c.axis.length() - 1.0).abs() <= 1e-12;
    if !(c.origin.is_finite() && unit && c.radius.is_finite() && c.radius > 0.0 && c.omega.is_finite()) {
        return Err(format!(
            "cylinder '{name}' needs a finite origin, a unit axis, a finite radius > 0 and a finite omega"
        ));
    }
    Ok(())
}

/// A cylinder that meets the faces of a periodic axis: its index and the axis. Cylinders have
/// no periodic images, as particles have; one whose axis lies along a periodic axis is the
/// same in every image and is allowed; any other must stay more than `max_radius` inside the
/// axis's faces (so its axis must be normal to that axis), as a mesh must.
pub fn periodic_cylinder_reach(
    cylinders: &[Cylinder],
    periodic: &crate::boundary::Periodic,
    max_radius: f64,
) -> Option<(usize, usize)> {
    let (lo, hi) = (periodic.lo.to_array(), periodic.hi.to_array());
    cylinders.iter().enumerate().find_map(|(m, c)| {
        let (a, o) = (c.axis.to_array(), c.origin.to_array());
        (0..3)
            .find(|&k| {
                let along = (0..3).all(|j| j == k || a[j] == 0.0);
                let inside = a[k] == 0.0
                    && o[k] - c.radius >= lo[k] + max_radius
                    && o[k] + c.radius <= hi[k] - max_radius;
                periodic.axes[k] && !along && !inside
            })
            .map(|k| (m, k))
    })
}

/// The sentence for [`periodic_cylinder_reach`]'s finding about the cylinder `c`.
pub fn periodic_cylinder_message(c: &Cylinder, axis: usize, max_radius: f64) -> String {
    let x = ["x", "y", "z"][axis];
    format!(
        "cylinder '{}' (axis {:?}) crosses or comes within {max_radius:e} m (the largest particle radius) of the faces of the periodic axis {x}: cylinders have no periodic images, so a particle across the face would meet it on one side only; put its axis along {x}, keep the cylinder more than {max_radius:e} m within the faces, or make {x} non-periodic",
        c.name,
        c.axis.to_array()
    )
}

/// The cylinder-wall contacts ((particle id, cylinder), history).
impl crate::checkpoint::Saved for Cylinders {
    fn save<W: std::io::Write>(
        &self,
        sim: &Simulation,
        e: &mut crate::checkpoint::Enc<W>,
    ) -> std::io::Result<()> {
        let id = &sim.particles().id;
        let h = &self.history;
        e.pairs(h.len(), h.iter().map(|h| [id[h.slot as usize], h.cylinder]))?;
        e.vec3s_from(h.iter().map(|h| h.h))
    }

    fn saved_bytes(&self, _sim: &Simulation) -> usize {
        crate::checkpoint::pairs_bytes(self.history.len())
    }

    fn load<R: std::io::Read>(
        d: &mut crate::checkpoint::Dec<R>,
        state: &mut crate::checkpoint::SourceState,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        state.cylinder_contacts = (d.pairs("cylinder contacts")?, d.vec3s("cylinder contact histories")?);
        Ok(())
    }
}
