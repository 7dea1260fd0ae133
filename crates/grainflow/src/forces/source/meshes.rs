//! The mesh-wall stage of a force evaluation: each particle's candidate triangles (found with
//! the meshes' triangle grids whenever the neighbour list is rebuilt, within the particle's
//! radius plus the skin), its contacts with each mesh ([`crate::mesh::sphere_contacts`]: every
//! surface touched once), their loads by the case's law as against a plane wall, and their
//! tangential histories.
//!
//! A contact's history is kept under the triangle that owns it. A particle that rolls from one
//! triangle onto the next takes the history of its contact there before: a contact without a
//! history of its own takes that of the particle's unclaimed contact of the evaluation before
//! on the same mesh whose normal is closest to its own (within 60°), so that the spring does
//! not snap back at a seam.
//!
//! On threads, the slots are shared out in consecutive runs: each run's candidates are
//! searched and its contacts' loads and histories computed on its own, and the runs' results
//! are joined in slot order, so the candidates, the histories and the list of loads are those
//! one thread finds, whatever the thread count. The loads are rounded to the sums' quanta like
//! every other load (`forces::sum`), so adding them after the pair stage gives the same sums
//! as adding them anywhere else.
//!
//! A moving mesh ([`crate::mesh::motion`]) stays binned in its pose as loaded: a particle's
//! centre is taken into that pose to find its contacts, and the contacts' normals and points
//! are turned back. The wall's velocity at the contact point (its motion's v + ω × (x − o),
//! plus a surface velocity) enters the contact's relative velocity. The candidates are found
//! again when the neighbour list is rebuilt or a mesh has moved more than half the skin since
//! they were found (around the list's reference positions, which no particle has left by more
//! than half the skin): so no contact is missed.

use super::{ContactSource, Diagnosed, LoadRun, View, wall_coeffs_of};
use crate::contact::law::{normal_spring_energy, parts};
use crate::contact::pair::{PairInput, wall_law};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{ContactCoeffs, ContactLaw, LeverArm};
use crate::error::EngineError;
use crate::forces::{Peak, Quanta, Quantum, max_peak};
use crate::math::Vec3;
use crate::mesh::MeshMotion;
use crate::mesh::grid::NearScratch;
use crate::mesh::motion::Anchor;
use crate::mesh::{Mesh, MeshContact, MeshWall, Pose, SurfaceMotion, TriangleGrid, sphere_contacts};
use crate::neighbor::NeighborState;
use crate::simulation::{ContactInfo, ContactPartner, Simulation};
use crate::state::Particles;
use crate::surface::{CellData, CellValues, Surface, SurfaceKind, Which};
use crate::threads;

/// A contact's normal may turn this far (cosine) from one evaluation to the next and still
/// carry its history to another triangle: 60°.
const CARRY_COS: f64 = 0.5;

/// The tangential history of one particle–mesh contact, under the triangle that owns it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeshHistory {
    pub slot: u32,
    pub mesh: u32,
    pub triangle: u32,
    /// The contact's normal (from the surface to the centre) when the history was stored.
    pub normal: Vec3,
    pub h: Vec3,
}

/// A candidate triangle of a particle: the mesh, the triangle, and its distance from the
/// particle's centre when the candidates were found (in the mesh's pose as loaded), m.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    mesh: u32,
    triangle: u32,
    distance: f64,
}

/// Where a slot's candidates are in [`Meshes::candidates`]: `len` of them from `start`, in
/// room for `cap`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Span {
    start: u32,
    len: u32,
    cap: u32,
}

impl Span {
    fn range(self) -> std::ops::Range<usize> {
        self.start as usize..(self.start + self.len) as usize
    }
}

/// The mesh walls as a contact source: the meshes, and what their contacts keep between
/// evaluations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Meshes {
    /// The mesh walls.
    pub walls: Vec<MeshWall>,
    grids: Vec<TriangleGrid>,
    /// On ranks, this rank's box: the grids of fixed meshes bin only the triangles near it
    /// (none: every triangle).
    near: Option<[Vec3; 2]>,
    /// Whether the candidates are current (false: found afresh at the next evaluation).
    built: bool,
    /// The neighbour-list build at which fixed meshes' candidates were last checked.
    checked_build: Option<u64>,
    /// The particle count they were found for.
    built_n: usize,
    /// Where each slot's centre was, relative to each mesh (in the mesh's pose as loaded),
    /// when its candidates were found: slot i, mesh m at `centres[i * meshes + m]`, m.
    centres: Vec<Vec3>,
    /// The working memory of each run of slots (one run off threads).
    workers: Vec<Worker>,
    /// Slot i's candidates are `candidates[span[i].range()]`, by mesh. A
    /// slot whose candidates are found again keeps its room if they fit, else takes new room
    /// at the end (a quarter more than it needs); the room left behind (`garbage`, entries)
    /// is given back when it is half the list.
    span: Vec<Span>,
    candidates: Vec<Candidate>,
    garbage: usize,
    /// The histories of the last evaluation's contacts, by (slot, mesh, triangle).
    pub history: Vec<MeshHistory>,
    /// Where each mesh's motion starts from (none: every one from the run's start).
    pub anchors: Vec<Anchor>,
    /// The run's start time, from which the meshes' motions are timed, s.
    pub t0: f64,
    /// Which meshes had their motion set between steps (none: every one moves as its case
    /// says); checkpoints record those meshes' motions.
    pub scripted: Vec<bool>,
    /// The last evaluation's loads on the particles from the meshes, for the meshes' loads.
    loads: Vec<MeshLoadPart>,
    /// Whether [`ContactSource::redistributed`] has just taken the candidates into the new
    /// slots, which the `take_carried` after it then keeps.
    redistributed: bool,
}

/// What one run of slots works with: marks of the triangles met by a query (per mesh), the
/// candidates it found (with their counts and the centres, per slot) and its loads.
#[derive(Debug, Clone, Default)]
struct Worker {
    marks: Vec<NearScratch>,
    near: Vec<(u32, f64)>,
    found: Vec<Candidate>,
    lens: Vec<u32>,
    centres: Vec<Vec3>,
    out: SlotLoads,
}

impl Worker {
    fn heap_bytes(&self) -> usize {
        self.marks.iter().map(|m| m.heap_bytes()).sum::<usize>()
            + self.near.capacity() * 16
            + self.found.capacity() * std::mem::size_of::<Candidate>()
            + self.lens.capacity() * 4
            + self.centres.capacity() * 24
            + self.out.stored.capacity() * std::mem::size_of::<MeshHistory>()
            + self.out.loads.capacity() * std::mem::size_of::<MeshLoadPart>()
    }
}

/// A mesh's motion rates at an evaluation: (linear velocity, angular velocity, a point on the
/// axis, the surface's own motion then), `None` if its surface does not move.
type Rates = Option<(Vec3, Vec3, Vec3, SurfaceMotion)>;

/// One mesh contact's load on its particle: the force, and the torque about the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
struct MeshLoadPart {
    slot: u32,
    mesh: u32,
    centre: Vec3,
    force: Vec3,
    torque: Vec3,
}

/// The load the particles exert on a mesh wall.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshLoad {
    /// Force, N.
    pub force: Vec3,
    /// Torque about the point it was asked for, N·m.
    pub torque: Vec3,
}

impl Meshes {
    /// The mesh walls `walls` of a run that starts at `t0`, s.
    pub(crate) fn new(walls: Vec<MeshWall>, t0: f64) -> Meshes {
        Meshes { walls, t0, ..Default::default() }
    }

    /// Heap bytes of the candidates, histories and grids.
    fn bytes(&self) -> usize {
        self.grids.iter().map(TriangleGrid::heap_bytes).sum::<usize>()
            + self.span.capacity() * std::mem::size_of::<Span>()
            + self.centres.capacity() * 24
            + self.workers.iter().map(Worker::heap_bytes).sum::<usize>()
            + self.candidates.capacity() * std::mem::size_of::<Candidate>()
            + self.history.capacity() * std::mem::size_of::<MeshHistory>()
            + self.loads.capacity() * std::mem::size_of::<MeshLoadPart>()
    }

    /// The anchor of mesh `m`'s motion.
    fn anchor(&self, m: usize) -> Anchor {
        self.anchors.get(m).copied().unwrap_or(Anchor::START)
    }

    /// Gives mesh `m` (< the count) the motion `motion` set by a script, for the rest of the
    /// run (its window: always), if it passes the case's checks; marks it as set.
    fn script(&mut self, m: usize, motion: MeshMotion) -> Result<(), EngineError> {
        let mut wall = self.walls[m].clone();
        (wall.motion, wall.window) = (motion, crate::mesh::motion::MotionWindow::ALWAYS);
        crate::simulation::check_mesh_motion(&wall)?;
        self.walls[m] = wall;
        self.scripted.resize(self.walls.len(), false);
        self.scripted[m] = true;
        Ok(())
    }

    /// True if the candidates are those of `n` particles.
    fn ready(&self, n: usize) -> bool {
        self.built && self.built_n == n && self.span.len() == n
    }

    /// The slots with candidates, ascending.
    fn active(&self) -> impl Iterator<Item = usize> + '_ {
        self.span.iter().enumerate().filter(|(_, s)| s.len > 0).map(|(i, _)| i)
    }

    /// Gives back the room left behind by candidates that moved: the candidates packed in slot
    /// order.
    fn compact(&mut self) {
        let mut packed = Vec::with_capacity(self.candidates.len() - self.garbage);
        for s in &mut self.span {
            let r = s.range();
            *s = Span { start: packed.len() as u32, len: s.len, cap: s.len };
            packed.extend_from_slice(&self.candidates[r]);
        }
        self.candidates = packed;
        self.garbage = 0;
    }

    /// Fills `contacts` with the contacts of slot `i` (centre `centre`, radius `r`)
    /// with mesh `m` in pose `pose` among its candidates, found within `r + reach` (`reach`: a
    /// cohesive law's pull-off distance, else 0; a contact's overlap with the radius is its
    /// `overlap − reach`); normals and points placed in the pose. Only the candidates that
    /// may be within reach are tested: a triangle at distance d₀ from where the centre was
    /// (both in the mesh's pose as loaded) is at least d₀ − |moved| from it now.
    /// `triangles` is scratch.
    #[allow(clippy::too_many_arguments)]
    fn contacts_of(
        &self,
        i: usize,
        (m, mesh, pose): (usize, &Mesh, &Pose),
        centre: Vec3,
        r: f64,
        reach: f64,
        triangles: &mut Vec<u32>,
        contacts: &mut Vec<MeshContact>,
    ) {
        let cands = &self.candidates[self.span[i].range()];
        let first = cands.partition_point(|c| c.mesh < m as u32);
        let mine = &cands[first..];
        contacts.clear();
        if mine.first().is_none_or(|c| c.mesh != m as u32) {
            return;
        }
        let meshes = self.centres.len() / self.built_n.max(1);
        let was = self.centres[i * meshes + m];
        let y = if pose.is_identity() { centre } else { pose.unapply(centre) };
        let within = r + reach;
        // The rounding of the distances and of the move, far below this margin.
        let limit = within + (y - was).length() + 1e-9 * within;
        triangles.clear();
        triangles.extend(
            mine.iter()
                .take_while(|c| c.mesh == m as u32)
                .filter(|c| c.distance <= limit)
                .map(|c| c.triangle),
        );
        if triangles.is_empty() {
            return;
        }
        sphere_contacts(mesh, triangles, y, within, contacts);
        if !pose.is_identity() {
            for c in contacts.iter_mut() {
                c.normal = pose.turn(c.normal);
                c.point = pose.apply(c.point);
            }
        }
    }

    /// Slots renumbered: slot `k` is now what slot `order[k]` was (`new_of[old]`, `u32::MAX`
    /// for a removed slot). Histories of removed slots go; the others' histories and
    /// candidates go with their particles.
    fn remap(&mut self, new_of: &[u32]) {
        self.history.retain_mut(|h| {
            let k = new_of[h.slot as usize];
            h.slot = k;
            k != u32::MAX
        });
        // Stable: the kept records are mostly in order already (`new_of` keeps the slots'
        // order, unless a rank laid its particles out again).
        self.history.sort_by_key(|h| (h.slot, h.mesh, h.triangle));
        if !self.ready(new_of.len()) || !self.centres.len().is_multiple_of(new_of.len().max(1)) {
            self.built = false;
            return;
        }
        let meshes = self.centres.len() / new_of.len().max(1);
        // The new slots run up to the last one named; one named by none has no candidates
        // yet (they are found at the next evaluation, as for an appended slot).
        let n = new_of.iter().filter(|&&k| k != u32::MAX).map(|&k| k as usize + 1).max().unwrap_or(0);
        let mut span = vec![Span::default(); n];
        let mut centres = vec![Vec3::INFINITY; n * meshes];
        for (old, &k) in new_of.iter().enumerate() {
            if k == u32::MAX {
                self.garbage += self.span[old].cap as usize;
            } else {
                let k = k as usize;
                span[k] = self.span[old];
                centres[k * meshes..(k + 1) * meshes]
                    .copy_from_slice(&self.centres[old * meshes..(old + 1) * meshes]);
            }
        }
        (self.span, self.centres, self.built_n) = (span, centres, n);
        if self.garbage > self.candidates.len() / 2 {
            self.compact();
        }
    }

    /// Particles appended to the `n_old` slots, up to `n`: their candidates are found at the next evaluation
    /// (their centres are nowhere yet, so they are stale), the others' kept.
    fn append(&mut self, n_old: usize, n: usize) {
        if !self.ready(n_old) || n_old == 0 {
            self.built = false;
            return;
        }
        let meshes = self.centres.len() / self.built_n;
        self.span.resize(n, Span::default());
        self.centres.resize(n * meshes, Vec3::INFINITY);
        self.built_n = n;
        // Fixed meshes are checked once a neighbour-list build: check at the next evaluation.
        self.checked_build = None;
    }
}

/// What the mesh loads of a run of slots give: the stored histories, the loads on the
/// particles (in the order of their slots, then meshes, then triangles) and their peak.
#[derive(Debug, Clone, Default)]
struct SlotLoads {
    stored: Vec<MeshHistory>,
    loads: Vec<MeshLoadPart>,
    peak: Peak,
}

/// The settings of one evaluation's mesh loads.
struct LoadSettings<'a> {
    poses: &'a [Pose],
    rates: &'a [Rates],
    quanta: Quanta,
    advance: bool,
    /// Δt for the springs (0 when they are not advanced), s.
    dt: f64,
}

impl Meshes {
    /// The pose of mesh `m` at time `t`, s.
    pub(crate) fn pose_at(&self, m: usize, t: f64) -> Pose {
        let wall = &self.walls[m];
        if !wall.motion.moves() {
            return Pose::IDENTITY;
        }
        self.anchor(m).pose(&wall.motion, &wall.window, t - self.t0)
    }

    /// The poses of every mesh at time `t`, s.
    fn poses_at(&self, t: f64) -> Vec<Pose> {
        (0..self.walls.len()).map(|m| self.pose_at(m, t)).collect()
    }

    /// Restores the mesh-wall contacts' histories of a checkpoint: (particle id, mesh),
    /// triangle, normal and history of each; `ids` are the particles' ids by slot.
    pub(crate) fn set_histories(
        &mut self,
        ids: &[u32],
        (owners, triangles, normals, h): (Vec<[u32; 2]>, Vec<u32>, Vec<Vec3>, Vec<Vec3>),
    ) -> Result<(), String> {
        let n = owners.len();
        if triangles.len() != n || normals.len() != n || h.len() != n {
            return Err("the mesh contacts' lists have different lengths".into());
        }
        let slots = crate::state::SlotsById::new(ids);
        let mut history = Vec::with_capacity(n);
        for k in 0..n {
            let [id, mesh] = owners[k];
            let slot = Some(slots.get(id))
                .filter(|&s| s != crate::state::NO_SLOT)
                .ok_or_else(|| format!("a mesh contact names particle {id}, which the case does not have"))?;
            let fits = self
                .walls
                .get(mesh as usize)
                .is_some_and(|m| (triangles[k] as usize) < m.mesh.triangle_count());
            if !fits {
                return Err(format!(
                    "a mesh contact names triangle {} of mesh {mesh}, which the case does not have",
                    triangles[k]
                ));
            }
            history.push(MeshHistory { slot, mesh, triangle: triangles[k], normal: normals[k], h: h[k] });
        }
        // Stable: records come mostly in order (those of particles that stayed).
        history.sort_by_key(|h| (h.slot, h.mesh, h.triangle));
        if history
            .windows(2)
            .any(|w| (w[0].slot, w[0].mesh, w[0].triangle) == (w[1].slot, w[1].mesh, w[1].triangle))
        {
            return Err("a mesh contact appears twice".into());
        }
        self.history = history;
        Ok(())
    }

    /// The loads on the particles from mesh `m` at the last force evaluation, each (the
    /// particle's centre, the force, the torque about the centre).
    fn loads_of(&self, m: usize) -> Vec<(Vec3, Vec3, Vec3)> {
        self.loads.iter().filter(|l| l.mesh == m as u32).map(|l| (l.centre, l.force, l.torque)).collect()
    }

    /// (anchor time since the start, s; anchor pose; pose at `t`) of every mesh.
    fn motion_state(&self, t: f64) -> Vec<(f64, Pose, Pose)> {
        (0..self.walls.len())
            .map(|m| {
                let a = self.anchor(m);
                (a.tau, a.pose, self.pose_at(m, t))
            })
            .collect()
    }

    /// Restores what [`motion_state`](Self::motion_state) gave, at time `t`.
    fn set_motion_state(&mut self, state: &[(f64, Pose, Pose)], t: f64) -> Result<(), String> {
        if state.len() != self.walls.len() {
            return Err(format!(
                "the checkpoint has {} mesh walls, the case {}",
                state.len(),
                self.walls.len()
            ));
        }
        let tau = t - self.t0;
        self.anchors = state.iter().map(|&(tau, pose, _)| Anchor { tau, pose }).collect();
        for (m, &(_, _, was)) in state.iter().enumerate() {
            if self.pose_at(m, t) != was {
                self.anchors[m] = Anchor { tau, pose: was };
            }
        }
        if self.anchors.iter().all(|a| *a == Anchor::START) {
            self.anchors.clear();
        }
        self.built = false;
        Ok(())
    }

    /// Calls `visit(slot, mesh, contact, overlap, coefficients)` for every mesh-wall contact
    /// of the state `v`, with the candidates of the last evaluation (none before the first):
    /// as the next evaluation would find them (a cohesive contact formed at the last
    /// evaluation holds to its pull-off distance).
    fn each_contact(&self, v: &View, mut visit: impl FnMut(usize, usize, &MeshContact, f64, &ContactCoeffs)) {
        let p = v.particles;
        if self.walls.is_empty() || !self.ready(p.len()) {
            return;
        }
        let reaches = v.law.normal.reaches();
        let poses = self.poses_at(v.time);
        let (mut contacts, mut triangles) = (Vec::new(), Vec::new());
        for i in self.active() {
            for (m, MeshWall { mesh, material, .. }) in self.walls.iter().enumerate() {
                let c = &wall_coeffs_of(v.coeffs, &v.law, p, i, *material);
                let reach = if reaches { c.pull_off } else { 0.0 };
                self.contacts_of(
                    i,
                    (m, mesh, &poses[m]),
                    p.position[i],
                    p.radius[i],
                    reach,
                    &mut triangles,
                    &mut contacts,
                );
                for k in &contacts {
                    let overlap = p.radius[i] - k.distance;
                    let formed = || {
                        self.history
                            .binary_search_by_key(&(i as u32, m as u32, k.triangle), |h| {
                                (h.slot, h.mesh, h.triangle)
                            })
                            .is_ok()
                    };
                    if overlap >= 0.0 || (reaches && formed()) {
                        visit(i, m, k, overlap, c);
                    }
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
        let rates = self.rates(v.time);
        self.each_contact(v, |i, m, k, overlap, c| {
            let h = self
                .history
                .binary_search_by_key(&(i as u32, m as u32, k.triangle), |h| (h.slot, h.mesh, h.triangle))
                .map_or(Vec3::ZERO, |j| self.history[j].h);
            let input = mesh_input(v.particles, &law, i, k, overlap, c, h, rates[m]);
            let (load, _, _) = wall_law::<N, T, { parts::ALL }>(&law, 0.0, &input);
            let f_n = load.f.dot(k.normal);
            out.push(ContactInfo {
                particle: i,
                other: ContactPartner::Mesh { mesh: m, triangle: k.triangle as usize },
                point: k.point,
                normal: -k.normal,
                overlap,
                normal_force: f_n.abs(),
                tangential_force: (load.f - k.normal * f_n).length(),
            });
        });
    }

    /// Each mesh's motion rates (linear velocity, angular velocity, a point on the axis) at
    /// time `t`, once per evaluation; `None` for a mesh whose surface does not move.
    fn rates(&self, t: f64) -> Vec<Rates> {
        self.walls
            .iter()
            .map(|w| {
                w.moves().then(|| {
                    let tau = t - self.t0;
                    let (v, o, x) = w.motion.rates_within(&w.window, tau);
                    (v, o, x, w.surface_at(tau))
                })
            })
            .collect()
    }

    /// On ranks: the box of this rank's particles, which the grids of fixed meshes bin the
    /// triangles near (binned again when it changes).
    pub(crate) fn bin_near(&mut self, near: [Vec3; 2]) {
        if self.near != Some(near) {
            self.near = Some(near);
            self.grids.clear();
        }
    }

    /// The triangles the meshes' grids hold, over all meshes (a triangle once per mesh).
    pub(crate) fn binned_triangles(&self) -> usize {
        self.grids.iter().map(TriangleGrid::triangle_count).sum()
    }

    /// Finds the candidates of the state `v` if they are not current, so that the contacts
    /// and diagnostics of a state not yet evaluated (a new or a restored simulation) include
    /// its mesh contacts. The next evaluation finds the same contacts with them as with any
    /// other complete candidates: the results do not change.
    pub(crate) fn prepare(&mut self, v: &View) {
        if self.walls.is_empty() {
            return;
        }
        let poses = self.poses_at(v.time);
        self.update_candidates(v, &poses, None);
    }

    /// Finds the candidates again where they may have become incomplete. A slot's candidates
    /// are the triangles within its radius, the law's pull-off distance and a margin S (the
    /// neighbour skin) of where its centre was relative to each mesh (in the mesh's pose as
    /// loaded, so that the candidates do not depend on the pose). They hold every triangle in
    /// reach while the centre has moved relative to the mesh by at most S: a slot whose centre
    /// moved farther relative to a mesh (`poses`: the meshes now) is searched again, and all
    /// are when the slots changed. A particle turning with a drum keeps its candidates.
    fn update_candidates(&mut self, v: &View, poses: &[Pose], pool: Option<&rayon::ThreadPool>) {
        let margin = v.neighbors.skin();
        let n = v.particles.len();
        let n_meshes = self.walls.len();
        let full = !self.ready(n) || self.centres.len() != n * n_meshes;
        let mut x: &[Vec3] = &v.particles.position;
        // Within S, less the rounding of the moves (far below this).
        let mut limit = (margin * (1.0 - 1e-9)).powi(2);
        let reference = v.neighbors.reference();
        if !full && reference.len() == n && self.walls.iter().all(|w| !w.motion.moves()) {
            // Fixed meshes: no particle moves half the skin from where the neighbour list was
            // last built (its reference positions), so a centre within S/2 of those holds until
            // the next build: the candidates need checking only once a build.
            let build = v.neighbors.stats().builds;
            if self.checked_build == Some(build) {
                return;
            }
            self.checked_build = Some(build);
            x = reference;
            limit *= 0.25;
        }
        // The meshes' poses taken back, as matrices (a point x is at R·(x − t) as loaded).
        let back: Vec<Option<(glam::DMat3, Vec3)>> = poses
            .iter()
            .map(|p| {
                (!p.is_identity()).then(|| (glam::DMat3::from_quat(p.rotation.conjugate()), p.translation))
            })
            .collect();
        let relative = |i: usize, m: usize| match back[m] {
            None => x[i],
            Some((r, t)) => r * (x[i] - t),
        };
        let stale = |i: usize| {
            full || (0..n_meshes)
                .any(|m| (relative(i, m) - self.centres[i * n_meshes + m]).length_squared() > limit)
        };
        let pool = pool.filter(|_| n >= threads::MIN_PARALLEL_SLOTS);
        // Ghosts have no candidates: their contacts are their owners' ranks' to evaluate.
        let owned = v.owned.min(n);
        let stale: Vec<usize> = match pool {
            Some(pool) => pool.install(|| {
                threads::in_runs(owned, |r| r.filter(|&i| stale(i)).collect::<Vec<usize>>()).concat()
            }),
            None => (0..owned).filter(|&i| stale(i)).collect(),
        };
        if full {
            self.centres.clear();
            self.centres.resize(n * n_meshes, Vec3::ZERO);
            self.span.clear();
            self.span.resize(n, Span::default());
            self.candidates.clear();
            self.garbage = 0;
        }
        if stale.is_empty() {
            // A rank whose own particles are all gone still holds a list of its slots.
            if full {
                self.built = true;
                self.built_n = n;
            }
            return;
        }
        if self.grids.len() != self.walls.len() {
            let cell = 2.0 * v.r_max + margin;
            // An owned centre lies in the box, or has moved less than the margin out of it
            // since: the triangles within reach of it meet the box widened so.
            let reach = Vec3::splat(v.r_max + 2.0 * margin + v.coeffs.reach());
            self.grids = self
                .walls
                .iter()
                .map(|m| match self.near.filter(|_| !m.motion.moves()) {
                    Some([lo, hi]) => TriangleGrid::within(&m.mesh, cell, lo - reach, hi + reach),
                    None => TriangleGrid::new(&m.mesh, cell),
                })
                .collect();
        }
        // Each run of the stale slots is searched on its own; the runs' finds are then placed
        // in slot order, as one search of them all would place them.
        let parts = match pool {
            Some(pool) if stale.len() >= threads::MIN_PARALLEL_SLOTS => {
                threads::RUNS_PER_THREAD * pool.current_num_threads()
            }
            _ => 1,
        };
        let mut workers = std::mem::take(&mut self.workers);
        if workers.len() < parts {
            workers.resize_with(parts, Worker::default);
        }
        let search = |w: &mut Worker, slots: &[usize]| self.search(v, poses, margin, slots, w);
        match pool.filter(|_| parts > 1) {
            Some(pool) => {
                let runs = threads::runs(stale.len(), parts).map(|r| &stale[r]);
                let parts: Vec<_> = workers[..parts].iter_mut().zip(runs).collect();
                pool.install(|| threads::each_taken(parts, |(w, s)| search(w, s)));
            }
            None => search(&mut workers[0], &stale),
        }
        let pad = Candidate { mesh: u32::MAX, triangle: u32::MAX, distance: f64::INFINITY };
        for (w, r) in workers.iter().zip(threads::runs(stale.len(), parts)) {
            let mut at = 0;
            for (k, &i) in stale[r].iter().enumerate() {
                self.centres[i * n_meshes..(i + 1) * n_meshes]
                    .copy_from_slice(&w.centres[k * n_meshes..(k + 1) * n_meshes]);
                let found = &w.found[at..at + w.lens[k] as usize];
                at += found.len();
                let span = &mut self.span[i];
                let len = found.len() as u32;
                if len <= span.cap {
                    self.candidates[span.start as usize..][..found.len()].copy_from_slice(found);
                    span.len = len;
                } else {
                    self.garbage += span.cap as usize;
                    let cap = if full { len } else { len + len / 4 };
                    *span = Span { start: self.candidates.len() as u32, len, cap };
                    self.candidates.extend_from_slice(found);
                    self.candidates.resize(self.candidates.len() + (cap - len) as usize, pad);
                }
            }
        }
        self.workers = workers;
        if self.garbage > self.candidates.len() / 2 {
            self.compact();
        }
        self.built = true;
        self.built_n = n;
    }

    /// Searches the meshes for the candidates of `slots` (their centres taken into each mesh's
    /// pose as loaded, from `poses`; within radius + `margin` + pull-off distance): `w.found`
    /// holds them slot after slot, `w.lens` their count per slot and `w.centres` the centres,
    /// mesh after mesh.
    fn search(&self, v: &View, poses: &[Pose], margin: f64, slots: &[usize], w: &mut Worker) {
        let p = v.particles;
        w.marks.resize_with(self.walls.len(), NearScratch::default);
        w.found.clear();
        w.lens.clear();
        w.centres.clear();
        for &i in slots {
            let before = w.found.len();
            for (m, (wall, grid)) in self.walls.iter().zip(&self.grids).enumerate() {
                let pose = &poses[m];
                let y = if pose.is_identity() { p.position[i] } else { pose.unapply(p.position[i]) };
                w.centres.push(y);
                let reach = wall_coeffs_of(v.coeffs, &v.law, p, i, wall.material).pull_off;
                grid.near_with_distances(
                    &wall.mesh,
                    y,
                    p.radius[i] + margin + reach,
                    &mut w.marks[m],
                    &mut w.near,
                );
                w.found.extend(w.near.iter().map(|&(t, distance)| Candidate {
                    mesh: m as u32,
                    triangle: t,
                    distance,
                }));
            }
            w.lens.push((w.found.len() - before) as u32);
        }
    }

    /// The mesh loads of the slots `slots` of the state `v` into `out`: `old` holds the
    /// histories of the evaluation before, by (slot, mesh, triangle).
    fn slot_loads<N: NormalSubModel, T: TangentialSubModel>(
        &self,
        v: &View,
        s: &LoadSettings,
        slots: std::ops::Range<usize>,
        old: &[MeshHistory],
        out: &mut SlotLoads,
    ) {
        let (p, law) = (v.particles, v.law);
        let (mut contacts, mut triangles): (Vec<MeshContact>, Vec<u32>) = (Vec::new(), Vec::new());
        let mut claimed: Vec<bool> = Vec::new();
        let mut o = old.partition_point(|h| (h.slot as usize) < slots.start);
        for i in slots {
            if self.span[i].len == 0 {
                continue;
            }
            // Histories are kept only for contacts, which only slots with candidates have.
            while o < old.len() && (old[o].slot as usize) < i {
                o += 1;
            }
            let o0 = o;
            while o < old.len() && old[o].slot as usize == i {
                o += 1;
            }
            let mine = &old[o0..o];
            claimed.clear();
            claimed.resize(mine.len(), false);
            for (m, MeshWall { mesh, material, .. }) in self.walls.iter().enumerate() {
                let c = &wall_coeffs_of(v.coeffs, &law, p, i, *material);
                let reach = if N::REACHES { c.pull_off } else { 0.0 };
                let radius = p.radius[i];
                let pose = (m, mesh, &s.poses[m]);
                self.contacts_of(i, pose, p.position[i], radius, reach, &mut triangles, &mut contacts);
                for k in contacts.iter() {
                    let overlap = radius - k.distance;
                    let own = mine.iter().position(|h| h.mesh == m as u32 && h.triangle == k.triangle);
                    if !N::wall_touching(overlap, reach, own.is_some()) {
                        continue;
                    }
                    let from = own.or_else(|| carried(mine, &claimed, m as u32, k.normal));
                    let h = from.map_or(Vec3::ZERO, |j| {
                        claimed[j] = true;
                        mine[j].h
                    });
                    let input = mesh_input(p, &law, i, k, overlap, c, h, s.rates[m]);
                    let (load, h_new, bound) = wall_law::<N, T, { parts::ALL }>(&law, s.dt, &input);
                    let round = |q: Quantum, v: Vec3| Vec3::new(q.round(v.x), q.round(v.y), q.round(v.z));
                    let (f, ta) = (round(s.quanta.force, load.f), round(s.quanta.torque, load.ta));
                    out.loads.push(MeshLoadPart {
                        slot: i as u32,
                        mesh: m as u32,
                        centre: p.position[i],
                        force: f,
                        torque: ta,
                    });
                    out.peak = max_peak(out.peak, bound);
                    out.stored.push(MeshHistory {
                        slot: i as u32,
                        mesh: m as u32,
                        triangle: k.triangle,
                        normal: k.normal,
                        h: if s.advance { h_new } else { h },
                    });
                }
            }
        }
    }
}

impl ContactSource for Meshes {
    /// Every particle's mesh-contact loads, after the candidates are brought up to date.
    fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, run: &mut LoadRun) {
        if self.walls.is_empty() {
            return;
        }
        let clock = run.times.is_some().then(std::time::Instant::now);
        let poses = self.poses_at(run.time);
        self.update_candidates(&run.view(), &poses, run.pool);
        let rates = self.rates(run.time);
        let settings = LoadSettings {
            poses: &poses,
            rates: &rates,
            quanta: run.quanta,
            advance: run.advance,
            dt: if run.advance { run.dt } else { 0.0 },
        };
        let old = std::mem::take(&mut self.history);
        let n = self.span.len();
        let pool = run.pool.filter(|_| n >= threads::MIN_PARALLEL_SLOTS);
        let parts = pool.map_or(1, |pool| threads::RUNS_PER_THREAD * pool.current_num_threads());
        let mut workers = std::mem::take(&mut self.workers);
        if workers.len() < parts {
            workers.resize_with(parts, Worker::default);
        }
        {
            let view = run.view();
            let work = |w: &mut Worker, slots: std::ops::Range<usize>| {
                w.out.stored.clear();
                w.out.loads.clear();
                w.out.peak = [0.0; 2];
                self.slot_loads::<N, T>(&view, &settings, slots, &old, &mut w.out);
            };
            match pool {
                Some(pool) => {
                    let parts: Vec<_> = workers[..parts].iter_mut().zip(threads::runs(n, parts)).collect();
                    pool.install(|| threads::each_taken(parts, |(w, r)| work(w, r)));
                }
                None => work(&mut workers[0], 0..n),
            }
        }
        let workers_used = &workers[..parts.min(n.max(1))];
        let p = &mut *run.particles;
        let mut loads = std::mem::take(&mut self.loads);
        loads.clear();
        let mut stored = Vec::with_capacity(workers_used.iter().map(|w| w.out.stored.len()).sum());
        for w in workers_used {
            for l in &w.out.loads {
                p.force[l.slot as usize] += l.force;
                p.torque[l.slot as usize] += l.torque;
            }
            loads.extend_from_slice(&w.out.loads);
            stored.extend_from_slice(&w.out.stored);
            run.peak = max_peak(run.peak, w.out.peak);
        }
        // Two contacts of a particle never share an owner (`sphere_contacts` merges them), so
        // the order is that of (slot, mesh, triangle) once sorted; slots and meshes come in
        // order already.
        if !stored.is_sorted_by_key(|h| (h.slot, h.mesh, h.triangle)) {
            stored.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        }
        self.workers = workers;
        self.loads = loads;
        self.history = if run.advance { stored } else { old };
        if let (Some(c), Some(t)) = (clock, run.times.as_deref_mut()) {
            t.meshes += c.elapsed().as_secs_f64();
        }
    }

    fn contact_infos(&self, v: &View, out: &mut Vec<ContactInfo>) {
        crate::with_submodels!(v.law, |N, T| self.contact_infos_for::<N, T>(v, out))
    }

    fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed)) {
        let (p, normal) = (v.particles, v.law.normal);
        self.each_contact(v, |i, _, _, overlap, c| {
            visit((overlap, p.radius[i], normal_spring_energy(normal, c, overlap)));
        });
    }

    fn rearrange(&mut self, new_of: &[u32], _list: &mut NeighborState) {
        self.remap(new_of);
    }

    fn appended(&mut self, n_old: usize, n: usize) {
        self.append(n_old, n);
    }

    fn redistributed(&mut self, new_of: &[u32], n: usize) {
        self.remap(new_of);
        self.append(self.built_n, n);
        self.redistributed = self.built;
    }

    fn heap_bytes(&self) -> usize {
        self.bytes()
    }

    /// (slot, mesh, triangle, normal, history).
    const CARRIED: usize = 9;

    fn carry(&self, out: &mut Vec<u64>) {
        for h in &self.history {
            out.extend([h.slot as u64, h.mesh as u64, h.triangle as u64]);
            out.extend(h.normal.to_array().into_iter().chain(h.h.to_array()).map(f64::to_bits));
        }
    }

    fn take_carried(&mut self, ids: &[u32], records: &[u64]) -> Result<(), String> {
        let mut lists = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let v = |w: &[u64]| Vec3::from_array([w[0], w[1], w[2]].map(f64::from_bits));
        for r in records.chunks_exact(Self::CARRIED) {
            lists.0.push([r[0] as u32, r[1] as u32]);
            lists.1.push(r[2] as u32);
            lists.2.push(v(&r[3..6]));
            lists.3.push(v(&r[6..9]));
        }
        // The slots changed: the candidates are found again, but for particles that stayed
        // on this rank when `redistributed` took theirs into the new slots.
        if !std::mem::take(&mut self.redistributed) {
            self.built = false;
        }
        self.set_histories(ids, lists)
    }

    const SURFACES: &'static [SurfaceKind] = &[FIXED_MESHES, MOVING_MESHES];

    /// The meshes that do not move (if any), then those that do (if any), as triangles where
    /// they are. Cell data: `mesh` (the mesh's index), `triangle` (its index in its mesh, as
    /// contacts name it) and `normal` (towards the particles' side).
    fn surfaces(&self, sim: &Simulation, _lo: Vec3, _hi: Vec3, which: Which, out: &mut Vec<Surface>) {
        for kind in [FIXED_MESHES, MOVING_MESHES] {
            let shown: Vec<usize> =
                (0..self.walls.len()).filter(|&m| self.walls[m].motion.moves() == kind.moves).collect();
            if !which.wants(kind) || shown.is_empty() {
                continue;
            }
            let mut s = Surface::new(kind);
            let (mut index, mut triangle, mut normals) = (Vec::new(), Vec::new(), Vec::new());
            for m in shown {
                let (mesh, pose) = (&self.walls[m].mesh, self.pose_at(m, sim.time()));
                let base = s.points.len();
                s.points.extend(mesh.vertices().iter().map(|&y| pose.apply(y)));
                for (t, corners) in mesh.triangles().iter().enumerate() {
                    s.push_polygon(corners.iter().map(|&v| base + v as usize));
                    index.push(m as i32);
                    triangle.push(t as i32);
                }
                normals.extend(mesh.normals().iter().map(|&n| pose.turn(n)));
            }
            s.cell_data = vec![
                CellData { name: "mesh", values: CellValues::Int(index) },
                CellData { name: "triangle", values: CellValues::Int(triangle) },
                CellData { name: "normal", values: CellValues::Vector(normals) },
            ];
            out.push(s);
        }
    }
}

/// The surface of the meshes that do not move: shown once.
const FIXED_MESHES: SurfaceKind = SurfaceKind { stem: "meshes_fixed", moves: false };
/// The surface of the meshes that move: shown at every frame.
const MOVING_MESHES: SurfaceKind = SurfaceKind { stem: "meshes", moves: true };

impl Simulation {
    /// Restores the mesh-wall contacts' histories of a checkpoint: (particle id, mesh),
    /// triangle, normal and history of each.
    pub(crate) fn set_mesh_histories(
        &mut self,
        lists: (Vec<[u32; 2]>, Vec<u32>, Vec<Vec3>, Vec<Vec3>),
    ) -> Result<(), String> {
        let ids = self.particles().id.clone();
        self.sources.meshes.set_histories(&ids, lists)
    }

    /// Where mesh `m` is now (its pose as loaded moved by its motion so far).
    pub fn mesh_pose(&self, m: usize) -> Pose {
        self.sources.meshes.pose_at(m, self.time())
    }

    /// The vertices of mesh `m` where they are now, m (in the order of
    /// [`Mesh::vertices`]).
    pub fn mesh_vertices(&self, m: usize) -> Vec<Vec3> {
        let pose = self.mesh_pose(m);
        self.meshes()[m].mesh.vertices().iter().map(|&y| pose.apply(y)).collect()
    }

    /// The mesh walls.
    pub fn meshes(&self) -> &[MeshWall] {
        &self.sources.meshes.walls
    }

    /// The load the particles exerted on mesh `m` at the last force evaluation (zero before
    /// the first): the force, and the torque about `about`. The sums do not depend on the
    /// particles' order; the force is exactly minus the sum of the particles' loads from it.
    /// Spread over ranks, the sums are over every rank's contacts: collective.
    pub fn mesh_load(&self, m: usize, about: Vec3) -> MeshLoad {
        self.wall_load_over_ranks(&self.sources.meshes.loads_of(m), about)
    }

    /// Gives mesh `m` the motion `motion` from now on, for the rest of the run: it goes on from
    /// where it is, anchored at this time (between steps; a user's hook or script prescribing
    /// a mesh's motion, as MFIX's user functions do). The motion is checked as a case's is.
    /// Checkpoints record it, and a restart from them goes on with it.
    pub fn set_mesh_motion(&mut self, m: usize, motion: MeshMotion) -> Result<(), EngineError> {
        let n = self.sources.meshes.walls.len();
        if m >= n {
            return Err(EngineError::BadReference(format!("mesh {m}: the case has {n} meshes")));
        }
        let t = self.time();
        let meshes = &mut self.sources.meshes;
        let here = meshes.pose_at(m, t);
        meshes.script(m, motion)?;
        if meshes.anchors.len() < n {
            meshes.anchors.resize(n, Anchor::START);
        }
        meshes.anchors[m] = Anchor { tau: t - meshes.t0, pose: here };
        // The forces held are those of the wall's velocity before.
        self.forces_current = false;
        Ok(())
    }

    /// Whether a mesh's motion was set between steps ([`set_mesh_motion`](Self::set_mesh_motion)).
    pub fn has_scripted_motion(&self) -> bool {
        self.sources.meshes.scripted.iter().any(|&s| s)
    }

    /// The motions set between steps, as a checkpoint records them: [`SCRIPTED_F64S`] numbers
    /// a mesh so set (its index, then [`motion_numbers`]).
    pub(crate) fn scripted_motion_numbers(&self) -> Vec<f64> {
        let meshes = &self.sources.meshes;
        let set = meshes.scripted.iter().enumerate().filter(|(_, s)| **s);
        set.flat_map(|(m, _)| std::iter::once(m as f64).chain(motion_numbers(&meshes.walls[m].motion)))
            .collect()
    }

    /// Gives the meshes the motions a checkpoint recorded as set between steps (see
    /// [`scripted_motion_numbers`](Self::scripted_motion_numbers)), before their motion state is
    /// restored.
    pub(crate) fn set_scripted_motions(&mut self, numbers: &[f64]) -> Result<(), String> {
        let n = self.sources.meshes.walls.len();
        for c in numbers.chunks_exact(SCRIPTED_F64S) {
            let m = c[0] as usize;
            let motion = motion_of(&c[1..]).filter(|_| c[0] >= 0.0 && c[0].fract() == 0.0 && m < n);
            let Some(motion) = motion else {
                return Err(format!(
                    "the checkpoint sets the motion of mesh {} from a script, which this case's {n} meshes do not fit",
                    c[0]
                ));
            };
            self.sources.meshes.script(m, motion).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// Restores each mesh's motion state of a checkpoint (anchor time since the start, s;
    /// anchor pose; pose then). A mesh whose motion
    /// in this case puts it elsewhere than the checkpoint's pose (the case's motion changed)
    /// continues from the checkpoint's pose, anchored at its time.
    pub(crate) fn set_mesh_motion_state(&mut self, state: &[(f64, Pose, Pose)]) -> Result<(), String> {
        let t = self.time();
        self.sources.meshes.set_motion_state(state, t)
    }
}

/// The wall law's input for slot `i`'s contact `k` (placed) with a mesh whose motion has
/// `rates`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn mesh_input(
    p: &Particles,
    law: &ContactLaw,
    i: usize,
    k: &MeshContact,
    overlap: f64,
    c: &ContactCoeffs,
    h: Vec3,
    rates: Rates,
) -> PairInput {
    let lever = if law.lever == LeverArm::RadicalPlane { k.distance } else { p.radius[i] };
    PairInput {
        d: -k.normal,
        ra: overlap,
        rb: lever,
        dv: p.velocity[i] - mesh_velocity(rates, k.point, k.normal),
        wa: p.omega[i],
        wb: Vec3::ZERO,
        h,
        c: *c,
        m_eff: p.mass[i],
    }
}

/// The velocity of a mesh's surface (its motion's and its surface's `rates`) at the point `x`
/// (normal `normal`).
#[inline]
fn mesh_velocity(rates: Rates, x: Vec3, normal: Vec3) -> Vec3 {
    match rates {
        None => Vec3::ZERO,
        Some((v, w, o, surface)) => v + w.cross(x - o) + surface.velocity(x, normal),
    }
}

/// The particle's unclaimed contact of the evaluation before on mesh `mesh` whose normal is
/// closest to `normal`, if within [`CARRY_COS`].
fn carried(mine: &[MeshHistory], claimed: &[bool], mesh: u32, normal: Vec3) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (j, h) in mine.iter().enumerate() {
        let c = h.normal.dot(normal);
        if h.mesh == mesh && !claimed[j] && c >= CARRY_COS && best.is_none_or(|(_, b)| c > b) {
            best = Some((j, c));
        }
    }
    best.map(|(j, _)| j)
}

/// A mesh that comes, within the first `span` s of its motion ([`MeshWall::swept_bounds`]),
/// closer than `max_radius` to a face of a periodic axis (or crosses it): its index, the axis
/// and the extent it sweeps along it. Meshes have no periodic images, as particles have: a
/// particle beyond that face would meet such a mesh on one side only, so set-up refuses it.
pub fn periodic_mesh_reach(
    meshes: &[MeshWall],
    periodic: &crate::boundary::Periodic,
    max_radius: f64,
    span: f64,
) -> Option<(usize, usize, f64, f64)> {
    let (lo, hi) = (periodic.lo.to_array(), periodic.hi.to_array());
    meshes.iter().enumerate().find_map(|(m, wall)| {
        let (a, b) = wall.swept_bounds(span);
        let (a, b) = (a.to_array(), b.to_array());
        (0..3)
            .find(|&k| periodic.axes[k] && !(a[k] >= lo[k] + max_radius && b[k] <= hi[k] - max_radius))
            .map(|k| (m, k, a[k], b[k]))
    })
}

/// The sentence for [`periodic_mesh_reach`]'s finding about the mesh called `name`.
pub fn periodic_mesh_message(
    name: &str,
    (axis, from, to): (usize, f64, f64),
    periodic: &crate::boundary::Periodic,
    max_radius: f64,
) -> String {
    let x = ["x", "y", "z"][axis];
    let (lo, hi) = (periodic.lo.to_array()[axis], periodic.hi.to_array()[axis]);
    format!(
        "mesh '{name}' reaches across or within {max_radius:e} m (the largest particle radius) of the periodic faces {x} = {lo:e} and {x} = {hi:e} m (it spans {x} from {from:e} to {to:e} m over the run): meshes have no periodic images, so a particle across the face would meet it on one side only; keep the mesh more than {max_radius:e} m inside the faces of the periodic axis {x}, or make the axis non-periodic (for a flat floor along a periodic axis, use a [[walls]] plane)"
    )
}

/// Numbers a mesh of the motions a checkpoint records as set between steps: the mesh's index,
/// then the motion's [`motion_numbers`].
pub(crate) const SCRIPTED_F64S: usize = 11;

/// A mesh motion as 10 numbers: its kind (0 fixed, 1 translating, 2 rotating, 3 oscillating),
/// then its parameters in the order of [`MeshMotion`]'s fields, zeros after them.
fn motion_numbers(motion: &MeshMotion) -> [f64; 10] {
    let mut v = [0.0; 10];
    match *motion {
        MeshMotion::Fixed => {}
        MeshMotion::Translate { velocity } => {
            v[0] = 1.0;
            v[1..4].copy_from_slice(&velocity.to_array());
        }
        MeshMotion::Rotate { origin, axis, omega, ramp } => {
            v[0] = 2.0;
            v[1..4].copy_from_slice(&origin.to_array());
            v[4..7].copy_from_slice(&axis.to_array());
            (v[7], v[8]) = (omega, ramp);
        }
        MeshMotion::Oscillate { amplitude, frequency } => {
            v[0] = 3.0;
            v[1..4].copy_from_slice(&amplitude.to_array());
            v[4] = frequency;
        }
    }
    v
}

/// The motion of [`motion_numbers`] (None: not a kind).
fn motion_of(v: &[f64]) -> Option<MeshMotion> {
    let vec = |i: usize| Vec3::new(v[i], v[i + 1], v[i + 2]);
    Some(match v[0] {
        0.0 => MeshMotion::Fixed,
        1.0 => MeshMotion::Translate { velocity: vec(1) },
        2.0 => MeshMotion::Rotate { origin: vec(1), axis: vec(4), omega: v[7], ramp: v[8] },
        3.0 => MeshMotion::Oscillate { amplitude: vec(1), frequency: v[4] },
        _ => return None,
    })
}

/// The mesh-wall contacts ((particle id, mesh), owning triangle, normal, history), then each
/// mesh's motion state (anchor time, anchor pose, pose now).
impl crate::checkpoint::Saved for Meshes {
    fn save<W: std::io::Write>(
        &self,
        sim: &Simulation,
        e: &mut crate::checkpoint::Enc<W>,
    ) -> std::io::Result<()> {
        let id = &sim.particles().id;
        let h = &self.history;
        e.pairs(h.len(), h.iter().map(|h| [id[h.slot as usize], h.mesh]))?;
        e.u32s(&h.iter().map(|h| h.triangle).collect::<Vec<_>>())?;
        e.vec3s_from(h.iter().map(|h| h.normal))?;
        e.vec3s_from(h.iter().map(|h| h.h))?;
        let numbers = crate::checkpoint::pose_numbers;
        let motion: Vec<f64> = self
            .motion_state(sim.time())
            .iter()
            .flat_map(|(tau, anchor, now)| std::iter::once(*tau).chain(numbers(anchor)).chain(numbers(now)))
            .collect();
        e.f64s(&motion)
    }

    fn saved_bytes(&self, _sim: &Simulation) -> usize {
        (8 + 8 + 8 + 8 + (8 + 4 + 24 + 24) * self.history.len())
            + (8 + 8 * crate::checkpoint::MOTION_F64S * self.walls.len())
    }

    fn load<R: std::io::Read>(
        d: &mut crate::checkpoint::Dec<R>,
        state: &mut crate::checkpoint::SourceState,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        state.mesh_contacts = (
            d.pairs("mesh contacts")?,
            d.u32s("mesh contact triangles")?,
            d.vec3s("mesh contact normals")?,
            d.vec3s("mesh contact histories")?,
        );
        state.mesh_motion = Some(crate::checkpoint::mesh_motion(d)?);
        Ok(())
    }
}
