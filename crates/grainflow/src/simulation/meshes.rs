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
//! The loads are rounded to the sums' quanta like every other load (`forces::sum`), so adding
//! them after the pair stage, on one thread, gives the same sums as adding them anywhere else.
//!
//! A moving mesh ([`crate::mesh::motion`]) stays binned in its pose as loaded: a particle's
//! centre is taken into that pose to find its contacts, and the contacts' normals and points
//! are turned back. The wall's velocity at the contact point (its motion's v + ω × (x − o),
//! plus a surface velocity) enters the contact's relative velocity. The candidates are found
//! again when the neighbour list is rebuilt or a mesh has moved more than half the skin since
//! they were found (around the list's reference positions, which no particle has left by more
//! than half the skin): so no contact is missed.

use super::Simulation;
use crate::contact::law::parts;
use crate::contact::pair::{PairInput, contact_coeffs, contact_reach, wall_law};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw, LeverArm};
use crate::forces::{Peak, Quanta, Quantum, max_peak};
use crate::math::Vec3;
use crate::mesh::grid::NearScratch;
use crate::mesh::motion::Anchor;
use crate::mesh::{Mesh, MeshContact, MeshWall, Pose, SurfaceMotion, TriangleGrid, sphere_contacts};
use crate::state::Particles;

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

/// Where a slot's candidates are in [`MeshStage::candidates`]: `len` of them from `start`, in
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

/// What the mesh stage keeps between evaluations.
#[derive(Debug, Clone, Default)]
pub(crate) struct MeshStage {
    grids: Vec<TriangleGrid>,
    /// Whether the candidates are current (false: found afresh at the next evaluation).
    built: bool,
    /// The neighbour-list build at which fixed meshes' candidates were last checked.
    checked_build: Option<u64>,
    /// The particle count they were found for.
    built_n: usize,
    /// Where each slot's centre was, relative to each mesh (in the mesh's pose as loaded),
    /// when its candidates were found: slot i, mesh m at `centres[i * meshes + m]`, m.
    centres: Vec<Vec3>,
    /// Marks of the triangles met by a query, per mesh.
    marks: Vec<NearScratch>,
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
    /// The last evaluation's loads on the particles from the meshes, for the meshes' loads.
    loads: Vec<MeshLoadPart>,
}

/// A mesh's motion rates at an evaluation: (linear velocity, angular velocity, a point on the
/// axis, the surface's own motion then), `None` if its surface does not move.
type Rates = Option<(Vec3, Vec3, Vec3, SurfaceMotion)>;

/// One mesh contact's load on its particle: the force, and the torque about the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
struct MeshLoadPart {
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

impl MeshStage {
    /// The stage of a run that starts at `t0`, s.
    pub(crate) fn new(t0: f64) -> MeshStage {
        MeshStage { t0, ..Default::default() }
    }

    /// Heap bytes of the stage.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.grids.iter().map(TriangleGrid::heap_bytes).sum::<usize>()
            + self.span.capacity() * std::mem::size_of::<Span>()
            + self.centres.capacity() * 24
            + self.marks.iter().map(|m| m.heap_bytes()).sum::<usize>()
            + self.candidates.capacity() * std::mem::size_of::<Candidate>()
            + self.history.capacity() * std::mem::size_of::<MeshHistory>()
            + self.loads.capacity() * std::mem::size_of::<MeshLoadPart>()
    }

    /// The anchor of mesh `m`'s motion.
    fn anchor(&self, m: usize) -> Anchor {
        self.anchors.get(m).copied().unwrap_or(Anchor::START)
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
    pub(crate) fn remap(&mut self, new_of: &[u32]) {
        self.history.retain_mut(|h| {
            let k = new_of[h.slot as usize];
            h.slot = k;
            k != u32::MAX
        });
        self.history.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        if !self.ready(new_of.len()) || !self.centres.len().is_multiple_of(new_of.len().max(1)) {
            self.built = false;
            return;
        }
        let meshes = self.centres.len() / new_of.len().max(1);
        let n = new_of.iter().filter(|&&k| k != u32::MAX).count();
        let mut span = vec![Span::default(); n];
        let mut centres = vec![Vec3::ZERO; n * meshes];
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
    pub(crate) fn appended(&mut self, n_old: usize, n: usize) {
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

impl Simulation {
    /// The mesh-wall contacts' histories, by (slot, mesh, triangle).
    pub(crate) fn mesh_histories(&self) -> &[MeshHistory] {
        &self.mesh_stage.history
    }

    /// Restores the mesh-wall contacts' histories of a checkpoint: (particle id, mesh),
    /// triangle, normal and history of each.
    pub(crate) fn set_mesh_histories(
        &mut self,
        (owners, triangles, normals, h): (Vec<[u32; 2]>, Vec<u32>, Vec<Vec3>, Vec<Vec3>),
    ) -> Result<(), String> {
        let n = owners.len();
        if triangles.len() != n || normals.len() != n || h.len() != n {
            return Err("the mesh contacts' lists have different lengths".into());
        }
        let mut by_id: Vec<(u32, u32)> =
            self.particles.id.iter().enumerate().map(|(s, &id)| (id, s as u32)).collect();
        by_id.sort_unstable();
        let mut history = Vec::with_capacity(n);
        for k in 0..n {
            let [id, mesh] = owners[k];
            let slot = by_id
                .binary_search_by_key(&id, |e| e.0)
                .map(|j| by_id[j].1)
                .map_err(|_| format!("a mesh contact names particle {id}, which the case does not have"))?;
            let fits = self
                .meshes
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
        history.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        if history
            .windows(2)
            .any(|w| (w[0].slot, w[0].mesh, w[0].triangle) == (w[1].slot, w[1].mesh, w[1].triangle))
        {
            return Err("a mesh contact appears twice".into());
        }
        self.mesh_stage.history = history;
        Ok(())
    }

    /// The pose of mesh `m` at time `t`, s.
    pub(crate) fn mesh_pose_at(&self, m: usize, t: f64) -> Pose {
        let wall = &self.meshes[m];
        if !wall.motion.moves() {
            return Pose::IDENTITY;
        }
        self.mesh_stage.anchor(m).pose(&wall.motion, &wall.window, t - self.mesh_stage.t0)
    }

    /// Where mesh `m` is now (its pose as loaded moved by its motion so far).
    pub fn mesh_pose(&self, m: usize) -> Pose {
        self.mesh_pose_at(m, self.time())
    }

    /// The vertices of mesh `m` where they are now, m (in the order of
    /// [`Mesh::vertices`]).
    pub fn mesh_vertices(&self, m: usize) -> Vec<Vec3> {
        let pose = self.mesh_pose(m);
        self.meshes[m].mesh.vertices().iter().map(|&y| pose.apply(y)).collect()
    }

    /// The mesh walls.
    pub fn meshes(&self) -> &[MeshWall] {
        &self.meshes
    }

    /// The load the particles exerted on mesh `m` at the last force evaluation (zero before
    /// the first): the force, and the torque about `about`. The sums do not depend on the
    /// particles' order; the force is exactly minus the sum of the particles' loads from it.
    pub fn mesh_load(&self, m: usize, about: Vec3) -> MeshLoad {
        use crate::observe::order_free_sum;
        let parts: Vec<&MeshLoadPart> = self.mesh_stage.loads.iter().filter(|l| l.mesh == m as u32).collect();
        let sum = |f: &dyn Fn(&MeshLoadPart) -> Vec3| {
            let c =
                |k: usize| order_free_sum(&parts.iter().map(|l| f(l).to_array()[k]).collect::<Vec<f64>>());
            Vec3::new(c(0), c(1), c(2))
        };
        MeshLoad {
            force: -sum(&|l| l.force),
            torque: -sum(&|l| (l.centre - about).cross(l.force) + l.torque),
        }
    }

    /// (anchor time since the start, s; anchor pose; pose now) of every mesh, for checkpoints.
    pub(crate) fn mesh_motion_state(&self) -> Vec<(f64, Pose, Pose)> {
        (0..self.meshes.len())
            .map(|m| {
                let a = self.mesh_stage.anchor(m);
                (a.tau, a.pose, self.mesh_pose(m))
            })
            .collect()
    }

    /// Restores what [`mesh_motion_state`](Self::mesh_motion_state) gave. A mesh whose motion
    /// in this case puts it elsewhere than the checkpoint's pose (the case's motion changed)
    /// continues from the checkpoint's pose, anchored at its time.
    pub(crate) fn set_mesh_motion_state(&mut self, state: &[(f64, Pose, Pose)]) -> Result<(), String> {
        if state.len() != self.meshes.len() {
            return Err(format!(
                "the checkpoint has {} mesh walls, the case {}",
                state.len(),
                self.meshes.len()
            ));
        }
        let tau = self.time() - self.mesh_stage.t0;
        self.mesh_stage.anchors = state.iter().map(|&(tau, pose, _)| Anchor { tau, pose }).collect();
        for (m, &(_, _, was)) in state.iter().enumerate() {
            if self.mesh_pose(m) != was {
                self.mesh_stage.anchors[m] = Anchor { tau, pose: was };
            }
        }
        if self.mesh_stage.anchors.iter().all(|a| *a == Anchor::START) {
            self.mesh_stage.anchors.clear();
        }
        self.mesh_stage.built = false;
        Ok(())
    }

    /// Calls `visit(slot, overlap)` for every mesh-wall contact of the current state, with the
    /// candidates of the last evaluation (none before the first), for diagnostics: as the next
    /// evaluation would find them (a cohesive contact formed at the last evaluation holds to
    /// its pull-off distance).
    pub(super) fn visit_mesh_contacts(
        &self,
        mut visit: impl FnMut(usize, f64, &crate::contact::ContactCoeffs),
    ) {
        self.each_mesh_contact(|i, _, _, overlap, c| visit(i, overlap, c));
    }

    /// Calls `visit(slot, mesh, contact, overlap, coefficients)` for every mesh-wall contact
    /// of the current state, as [`visit_mesh_contacts`](Self::visit_mesh_contacts) finds them.
    fn each_mesh_contact(
        &self,
        mut visit: impl FnMut(usize, usize, &MeshContact, f64, &crate::contact::ContactCoeffs),
    ) {
        let (st, p) = (&self.mesh_stage, &self.particles);
        if self.meshes.is_empty() || !st.ready(p.len()) {
            return;
        }
        let reaches = self.law.normal.reaches();
        let poses: Vec<Pose> = (0..self.meshes.len()).map(|m| self.mesh_pose(m)).collect();
        let (mut contacts, mut triangles) = (Vec::new(), Vec::new());
        for i in st.active() {
            for (m, MeshWall { mesh, material, .. }) in self.meshes.iter().enumerate() {
                let c = &self.wall_coeffs(i, *material);
                let reach = if reaches { c.pull_off } else { 0.0 };
                st.contacts_of(
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
                        st.history
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

    /// The mesh-wall contacts of the current state with their forces, for output (see
    /// [`Simulation::contacts`]): as the next evaluation would see them, springs not advanced.
    pub(super) fn mesh_contact_infos(&self, out: &mut Vec<super::ContactInfo>) {
        crate::with_submodels!(self.law, |N, T| self.mesh_contact_infos_for::<N, T>(out))
    }

    fn mesh_contact_infos_for<N: NormalSubModel, T: TangentialSubModel>(
        &self,
        out: &mut Vec<super::ContactInfo>,
    ) {
        let (st, law) = (&self.mesh_stage, self.law);
        let rates = self.mesh_rates(self.time());
        self.each_mesh_contact(|i, m, k, overlap, c| {
            let h = st
                .history
                .binary_search_by_key(&(i as u32, m as u32, k.triangle), |h| (h.slot, h.mesh, h.triangle))
                .map_or(Vec3::ZERO, |j| st.history[j].h);
            let input = self.mesh_input(i, k, overlap, c, h, rates[m]);
            let (load, _, _) = wall_law::<N, T, { parts::ALL }>(&law, 0.0, &input);
            let f_n = load.f.dot(k.normal);
            out.push(super::ContactInfo {
                particle: i,
                other: super::ContactPartner::Mesh { mesh: m, triangle: k.triangle as usize },
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
    fn mesh_rates(&self, t: f64) -> Vec<Rates> {
        self.meshes
            .iter()
            .map(|w| {
                w.moves().then(|| {
                    let tau = t - self.mesh_stage.t0;
                    let (v, o, x) = w.motion.rates_within(&w.window, tau);
                    (v, o, x, w.surface_at(tau))
                })
            })
            .collect()
    }

    /// The coefficients of slot `i`'s contacts with wall material `material`: its phase's,
    /// formed for its own radius and mass where the table is per unit size (the pull-off
    /// distance too).
    #[inline]
    pub(super) fn wall_coeffs(&self, i: usize, material: usize) -> ContactCoeffs {
        wall_coeffs_of(&self.coeffs, &self.law, &self.particles, i, material)
    }

    /// The wall law's input for slot `i`'s contact `k` (placed) with a mesh whose motion has
    /// `rates`.
    #[inline]
    fn mesh_input(
        &self,
        i: usize,
        k: &MeshContact,
        overlap: f64,
        c: &crate::contact::ContactCoeffs,
        h: Vec3,
        rates: Rates,
    ) -> PairInput {
        let p = &self.particles;
        let lever = if self.law.lever == LeverArm::RadicalPlane { k.distance } else { p.radius[i] };
        PairInput {
            d: -k.normal,
            ra: overlap,
            rb: lever,
            dv: p.velocity[i] - self.mesh_velocity(rates, k.point, k.normal),
            wa: p.omega[i],
            wb: Vec3::ZERO,
            h,
            c: *c,
            m_eff: p.mass[i],
        }
    }

    /// The velocity of a mesh's surface (its motion's and its surface's `rates`) at the point
    /// `x` (normal `normal`).
    #[inline]
    fn mesh_velocity(&self, rates: Rates, x: Vec3, normal: Vec3) -> Vec3 {
        match rates {
            None => Vec3::ZERO,
            Some((v, w, o, surface)) => v + w.cross(x - o) + surface.velocity(x, normal),
        }
    }

    /// Finds the mesh candidates of the current state if they are not current, so that the
    /// contacts and diagnostics of a state not yet evaluated (a new or a restored simulation)
    /// include its mesh contacts. The next evaluation finds the same contacts with them as
    /// with any other complete candidates: the results do not change.
    pub(crate) fn prepare_mesh_candidates(&mut self) {
        if self.meshes.is_empty() {
            return;
        }
        let poses: Vec<Pose> = (0..self.meshes.len()).map(|m| self.mesh_pose(m)).collect();
        self.update_mesh_candidates(&poses);
    }

    /// Finds the candidates again where they may have become incomplete. A slot's candidates
    /// are the triangles within its radius, the law's pull-off distance and a margin S (the
    /// neighbour skin) of where its centre was relative to each mesh (in the mesh's pose as
    /// loaded, so that the candidates do not depend on the pose). They hold every triangle in
    /// reach while the centre has moved relative to the mesh by at most S: a slot whose centre
    /// moved farther relative to a mesh (`poses`: the meshes now) is searched again, and all
    /// are when the slots changed. A particle turning with a drum keeps its candidates.
    fn update_mesh_candidates(&mut self, poses: &[Pose]) {
        let margin = self.neighbors.skin();
        let n = self.particles.len();
        let n_meshes = self.meshes.len();
        let st = &self.mesh_stage;
        let full = !st.ready(n) || st.centres.len() != n * n_meshes;
        let mut x: &[Vec3] = &self.particles.position;
        // Within S, less the rounding of the moves (far below this).
        let mut limit = (margin * (1.0 - 1e-9)).powi(2);
        let reference = self.neighbors.reference();
        if !full && reference.len() == n && self.meshes.iter().all(|w| !w.motion.moves()) {
            // Fixed meshes: no particle moves half the skin from where the neighbour list was
            // last built (its reference positions), so a centre within S/2 of those holds until
            // the next build: the candidates need checking only once a build.
            let build = self.neighbors.stats().builds;
            if st.checked_build == Some(build) {
                return;
            }
            self.mesh_stage.checked_build = Some(build);
            x = reference;
            limit *= 0.25;
        }
        let st = &self.mesh_stage;
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
                .any(|m| (relative(i, m) - st.centres[i * n_meshes + m]).length_squared() > limit)
        };
        let stale: Vec<usize> = (0..n).filter(|&i| stale(i)).collect();
        if stale.is_empty() {
            return;
        }
        if st.grids.len() != self.meshes.len() {
            let cell = 2.0 * self.particles.max_radius().max(self.flow.max_radius()) + margin;
            self.mesh_stage.grids = self.meshes.iter().map(|m| TriangleGrid::new(&m.mesh, cell)).collect();
        }
        let st = &mut self.mesh_stage;
        if full {
            st.centres.clear();
            st.centres.resize(n * n_meshes, Vec3::ZERO);
            st.span.clear();
            st.span.resize(n, Span::default());
            st.candidates.clear();
            st.garbage = 0;
        }
        st.marks.resize_with(self.meshes.len(), NearScratch::default);
        let p = &self.particles;
        let (mut near, mut found) = (Vec::new(), Vec::new());
        for i in stale {
            found.clear();
            for (m, (wall, grid)) in self.meshes.iter().zip(&st.grids).enumerate() {
                let pose = &poses[m];
                let y = if pose.is_identity() { p.position[i] } else { pose.unapply(p.position[i]) };
                st.centres[i * n_meshes + m] = y;
                let reach = wall_coeffs_of(&self.coeffs, &self.law, p, i, wall.material).pull_off;
                grid.near_with_distances(
                    &wall.mesh,
                    y,
                    p.radius[i] + margin + reach,
                    &mut st.marks[m],
                    &mut near,
                );
                found.extend(near.iter().map(|&(t, distance)| Candidate {
                    mesh: m as u32,
                    triangle: t,
                    distance,
                }));
            }
            let span = &mut st.span[i];
            let len = found.len() as u32;
            if len <= span.cap {
                st.candidates[span.start as usize..][..found.len()].copy_from_slice(&found);
                span.len = len;
            } else {
                st.garbage += span.cap as usize;
                let cap = if full { len } else { len + len / 4 };
                *span = Span { start: st.candidates.len() as u32, len, cap };
                st.candidates.extend_from_slice(&found);
                let pad = Candidate { mesh: u32::MAX, triangle: u32::MAX, distance: f64::INFINITY };
                st.candidates.resize(st.candidates.len() + (cap - len) as usize, pad);
            }
        }
        if st.garbage > st.candidates.len() / 2 {
            st.compact();
        }
        st.built = true;
        st.built_n = n;
    }

    /// Adds every particle's mesh-contact loads, rounded to `quanta`, to the force and torque
    /// accumulators, raising `peak`; with `advance`, advances and stores their histories. `t`
    /// is the time of the particles' positions.
    pub(super) fn mesh_loads<N: NormalSubModel, T: TangentialSubModel>(
        &mut self,
        quanta: Quanta,
        advance: bool,
        peak: &mut Peak,
        t: f64,
    ) {
        if self.meshes.is_empty() {
            return;
        }
        let poses: Vec<Pose> = (0..self.meshes.len()).map(|m| self.mesh_pose_at(m, t)).collect();
        self.update_mesh_candidates(&poses);
        let dt = if advance { self.time_step.dt } else { 0.0 };
        let rates = self.mesh_rates(t);
        let law = self.law;
        let old = std::mem::take(&mut self.mesh_stage.history);
        let mut loads = std::mem::take(&mut self.mesh_stage.loads);
        loads.clear();
        let mut stored = Vec::with_capacity(old.len());
        let (mut contacts, mut triangles): (Vec<MeshContact>, Vec<u32>) = (Vec::new(), Vec::new());
        let mut claimed: Vec<bool> = Vec::new();
        let mut o = 0;
        for i in 0..self.mesh_stage.span.len() {
            if self.mesh_stage.span[i].len == 0 {
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
            for (m, MeshWall { mesh, material, .. }) in self.meshes.iter().enumerate() {
                let p = &self.particles;
                let c = &self.wall_coeffs(i, *material);
                let reach = if N::REACHES { c.pull_off } else { 0.0 };
                let radius = p.radius[i];
                self.mesh_stage.contacts_of(
                    i,
                    (m, mesh, &poses[m]),
                    p.position[i],
                    radius,
                    reach,
                    &mut triangles,
                    &mut contacts,
                );
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
                    let input = self.mesh_input(i, k, overlap, c, h, rates[m]);
                    let (load, h_new, bound) = wall_law::<N, T, { parts::ALL }>(&law, dt, &input);
                    let round = |q: Quantum, v: Vec3| Vec3::new(q.round(v.x), q.round(v.y), q.round(v.z));
                    let (f, ta) = (round(quanta.force, load.f), round(quanta.torque, load.ta));
                    self.particles.force[i] += f;
                    self.particles.torque[i] += ta;
                    loads.push(MeshLoadPart {
                        mesh: m as u32,
                        centre: self.particles.position[i],
                        force: f,
                        torque: ta,
                    });
                    *peak = max_peak(*peak, bound);
                    stored.push(MeshHistory {
                        slot: i as u32,
                        mesh: m as u32,
                        triangle: k.triangle,
                        normal: k.normal,
                        h: if advance { h_new } else { h },
                    });
                }
            }
        }
        // Two contacts of a particle never share an owner (`sphere_contacts` merges them), so
        // the order is that of (slot, mesh, triangle) once sorted; slots and meshes come in
        // order already.
        if !stored.is_sorted_by_key(|h| (h.slot, h.mesh, h.triangle)) {
            stored.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        }
        let st = &mut self.mesh_stage;
        st.loads = loads;
        st.history = if advance { stored } else { old };
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

/// [`Simulation::wall_coeffs`] from the table, law and particles.
#[inline]
fn wall_coeffs_of(
    coeffs: &CoeffTable,
    law: &ContactLaw,
    p: &Particles,
    i: usize,
    material: usize,
) -> ContactCoeffs {
    let c = coeffs.wall(p.phase[i] as usize, material);
    if !coeffs.sized() {
        return *c;
    }
    let r = p.radius[i];
    let mut sized = contact_coeffs(coeffs, law, c, r, p.mass[i]);
    sized.pull_off = crate::with_normal_submodel!(law.normal, |N| contact_reach::<N>(coeffs, c, r));
    sized
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
