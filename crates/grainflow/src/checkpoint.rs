//! Checkpoints: the complete dynamic state of a simulation as bytes, so that a restarted run
//! continues bit for bit as if it had never stopped — positions, velocities, spins, contact
//! histories, Adams–Bashforth history, neighbour list, prescribed-motion anchors, step count.
//!
//! Layout (little-endian): magic `GRAINFLW`, format version (u32), then a length-prefixed
//! payload and its FNV-1a 64 checksum, and nothing after it. The payload starts with the case
//! hash given by the caller, so a checkpoint is never applied to another case by mistake, and
//! the simulation's run id ([`Simulation::run_id`]), so that a restart can tell its own run's
//! outputs from another's. Writing the bytes to a
//! file (atomically) is the caller's business. Both ways the bytes stream: a checkpoint is
//! written from the state and read into it without a second copy of it in memory.

use crate::math::Vec3;
use crate::mesh::Pose;
use crate::neighbor::NeighborState;
use crate::simulation::{Simulation, SimulationConfig};
use crate::state::Particles;
use std::io::{self, Read, Write};
use thiserror::Error;

/// The checkpoint format this build writes (3: the run id after the case hash; contact pairs
/// and particle–wall pairs named by particle ids, so that a checkpoint does not depend on the
/// order the particles are stored in; 4: the last force evaluation's load peaks, from which the
/// next takes the quanta of its sums, and the count of evaluations with inexact sums, after
/// the flags; 5: the mesh-wall contacts' histories, at the end; 6: each mesh wall's motion
/// state — its anchor and its pose — after them; 7: the insertions' and outlets' state; 8: the
/// caller's note ([`Simulation::checkpoint_note`]), last; 9: the cylinder-wall contacts'
/// histories, before the note; 10: each contact source's section, in the sources' order,
/// after the motion anchors; 11: the mesh motions set between steps, before the note). A
/// checkpoint of format 2 or 3
/// continues with the quanta of its first evaluation taken afresh: not bit for bit as the run
/// that wrote it would have gone on.
pub const FORMAT_VERSION: u32 = 11;
/// The oldest format this build still reads (2: without the run id, pairs by slots).
pub const OLDEST_FORMAT_READ: u32 = 2;
const MAGIC: &[u8; 8] = b"GRAINFLW";
/// Bytes before the payload: signature, version, payload length.
const HEADER: usize = 20;

/// Why a checkpoint cannot be used.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CheckpointError {
    /// Not a grainflow checkpoint at all.
    #[error("not a grainflow checkpoint (the file does not start with the checkpoint signature)")]
    NotACheckpoint,
    /// Written by a format version this build does not read.
    #[error("checkpoint format version {found}; this grainflow reads versions {oldest} to {newest}")]
    Version {
        /// Version in the file.
        found: u32,
        /// Oldest version this build reads.
        oldest: u32,
        /// Version this build writes.
        newest: u32,
    },
    /// Shorter than its header says.
    #[error("the checkpoint is truncated ({0}); it was probably being written when the run stopped")]
    Truncated(&'static str),
    /// Bytes after the checksum: the file is not one checkpoint as written (appended to, or
    /// two files joined).
    #[error("the checkpoint has {0} bytes after its end; it is not a checkpoint as grainflow wrote it")]
    TrailingBytes(u64),
    /// Contents do not match their checksum.
    #[error("the checkpoint is corrupted (checksum mismatch)")]
    Corrupted,
    /// Written for another case, or the case changed since.
    #[error("the checkpoint was written for a different case file (case hash {found}, this case {expected})")]
    WrongCase {
        /// Hash in the checkpoint.
        found: String,
        /// Hash of the case given.
        expected: String,
    },
    /// Consistent bytes that do not fit the case (particle count, ids, …).
    #[error("the checkpoint does not fit the case: {0}")]
    Mismatch(String),
    /// The bytes could not be read.
    #[error("cannot read the checkpoint: {0}")]
    Read(String),
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

fn fnv1a_update(mut h: u64, bytes: &[u8]) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Writes the payload to `w`, keeping its checksum and length.
pub(crate) struct Enc<W: Write> {
    w: W,
    sum: u64,
    written: usize,
}

impl<W: Write> Enc<W> {
    fn put(&mut self, b: &[u8]) -> io::Result<()> {
        self.sum = fnv1a_update(self.sum, b);
        self.written += b.len();
        self.w.write_all(b)
    }
    pub(crate) fn u64(&mut self, v: u64) -> io::Result<()> {
        self.put(&v.to_le_bytes())
    }
    pub(crate) fn f64(&mut self, v: f64) -> io::Result<()> {
        self.put(&v.to_le_bytes())
    }
    pub(crate) fn bytes(&mut self, b: &[u8]) -> io::Result<()> {
        self.u64(b.len() as u64)?;
        self.put(b)
    }
    pub(crate) fn u32s(&mut self, v: &[u32]) -> io::Result<()> {
        self.u64(v.len() as u64)?;
        v.iter().try_for_each(|x| self.put(&x.to_le_bytes()))
    }
    pub(crate) fn f64s(&mut self, v: &[f64]) -> io::Result<()> {
        self.u64(v.len() as u64)?;
        v.iter().try_for_each(|x| self.f64(*x))
    }
    pub(crate) fn vec3s(&mut self, v: &[Vec3]) -> io::Result<()> {
        self.vec3s_from(v.iter().copied())
    }
    pub(crate) fn vec3s_from(&mut self, v: impl ExactSizeIterator<Item = Vec3>) -> io::Result<()> {
        self.u64(v.len() as u64)?;
        v.flat_map(|x| x.to_array()).try_for_each(|c| self.f64(c))
    }
    pub(crate) fn pairs(&mut self, count: usize, v: impl Iterator<Item = [u32; 2]>) -> io::Result<()> {
        self.u64(2 * count as u64)?;
        v.flatten().try_for_each(|x| self.put(&x.to_le_bytes()))
    }
}

/// Reads the payload from a stream, keeping its checksum and the bytes left of it.
pub(crate) struct Dec<R: Read> {
    r: R,
    left: u64,
    sum: u64,
    /// The bytes read last (at most [`CHUNK_ELEMENTS`] elements of a vector).
    scratch: Vec<u8>,
}

/// Elements of a vector read at a time.
const CHUNK_ELEMENTS: usize = 4096;

/// `r.read_exact(buf)`, an early end counting as a truncated checkpoint.
fn read_exact(mut r: impl Read, buf: &mut [u8], what: &'static str) -> Result<(), CheckpointError> {
    r.read_exact(buf).map_err(|e| match e.kind() {
        io::ErrorKind::UnexpectedEof => CheckpointError::Truncated(what),
        _ => CheckpointError::Read(e.to_string()),
    })
}

impl<R: Read> Dec<R> {
    /// Reads the next `n` bytes of the payload into `scratch`.
    fn fill(&mut self, n: usize, what: &'static str) -> Result<&[u8], CheckpointError> {
        if n as u64 > self.left {
            return Err(CheckpointError::Truncated(what));
        }
        self.scratch.clear();
        self.scratch.resize(n, 0);
        read_exact(&mut self.r, &mut self.scratch, what)?;
        self.sum = fnv1a_update(self.sum, &self.scratch);
        self.left -= n as u64;
        Ok(&self.scratch)
    }
    pub(crate) fn u64(&mut self, what: &'static str) -> Result<u64, CheckpointError> {
        let b = self.fill(8, what)?;
        Ok(u64::from_le_bytes(std::array::from_fn(|i| b[i])))
    }
    pub(crate) fn f64(&mut self, what: &'static str) -> Result<f64, CheckpointError> {
        Ok(f64::from_bits(self.u64(what)?))
    }
    /// A count of elements of `elem` bytes each. A count the rest of the payload cannot hold
    /// was damaged (the payload's length was checked against the checkpoint's size before):
    /// it is refused, so no count asks for more memory than the checkpoint's size.
    fn len(&mut self, elem: usize, what: &'static str) -> Result<usize, CheckpointError> {
        let n = self.u64(what)?;
        match n.checked_mul(elem as u64) {
            Some(bytes) if bytes <= self.left => Ok(n as usize),
            _ => Err(CheckpointError::Corrupted),
        }
    }
    /// `n` elements of `elem` bytes each, decoded by `decode`, read a chunk at a time.
    fn elements<T>(
        &mut self,
        n: usize,
        elem: usize,
        what: &'static str,
        decode: impl Fn(&[u8]) -> T,
    ) -> Result<Vec<T>, CheckpointError> {
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let m = CHUNK_ELEMENTS.min(n - out.len());
            out.extend(self.fill(m * elem, what)?.chunks_exact(elem).map(&decode));
        }
        Ok(out)
    }
    pub(crate) fn bytes(&mut self, what: &'static str) -> Result<Vec<u8>, CheckpointError> {
        let n = self.len(1, what)?;
        self.elements(n, 1, what, |c| c[0])
    }
    pub(crate) fn u32s(&mut self, what: &'static str) -> Result<Vec<u32>, CheckpointError> {
        let n = self.len(4, what)?;
        self.elements(n, 4, what, le_u32)
    }
    pub(crate) fn f64s(&mut self, what: &'static str) -> Result<Vec<f64>, CheckpointError> {
        let n = self.len(8, what)?;
        self.elements(n, 8, what, le_f64)
    }
    pub(crate) fn vec3s(&mut self, what: &'static str) -> Result<Vec<Vec3>, CheckpointError> {
        let n = self.len(24, what)?;
        self.elements(n, 24, what, |c| Vec3::new(le_f64(&c[..8]), le_f64(&c[8..16]), le_f64(&c[16..])))
    }
    pub(crate) fn pairs(&mut self, what: &'static str) -> Result<Vec<[u32; 2]>, CheckpointError> {
        let flat = self.len(4, what)?;
        if flat % 2 != 0 {
            return Err(CheckpointError::Mismatch(format!("{what}: odd length")));
        }
        self.elements(flat / 2, 8, what, |c| [le_u32(&c[..4]), le_u32(&c[4..])])
    }
    /// Reads what is left of the payload (its checksum still to be checked).
    fn skip_rest(&mut self) -> Result<(), CheckpointError> {
        while self.left > 0 {
            let n = self.left.min(1 << 16) as usize;
            self.fill(n, "payload")?;
        }
        Ok(())
    }
}

/// Turns the particle ids that name a format 3 checkpoint's pairs into the slots the
/// particles were restored to (a pair whose slots come out reversed is taken in the other
/// direction by the neighbour list, its history negated).
fn ids_to_slots(ids: &[u32], nl: &mut NeighborState) -> Result<(), CheckpointError> {
    let mut by_id: Vec<(u32, u32)> = ids.iter().enumerate().map(|(slot, &id)| (id, slot as u32)).collect();
    by_id.sort_unstable();
    if let Some(w) = by_id.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(CheckpointError::Mismatch(format!("particle id {} appears twice", w[0].0)));
    }
    let slot = |id: u32| -> Result<u32, CheckpointError> {
        by_id.binary_search_by_key(&id, |e| e.0).map(|k| by_id[k].1).map_err(|_| {
            CheckpointError::Mismatch(format!(
                "a contact names particle {id}, which the checkpoint does not hold"
            ))
        })
    };
    for pair in &mut nl.pairs {
        *pair = [slot(pair[0])?, slot(pair[1])?];
    }
    for pair in &mut nl.wall_pairs {
        pair[0] = slot(pair[0])?;
    }
    Ok(())
}

fn le_u32(c: &[u8]) -> u32 {
    u32::from_le_bytes(std::array::from_fn(|i| c[i]))
}

fn le_f64(c: &[u8]) -> f64 {
    f64::from_le_bytes(std::array::from_fn(|i| c[i]))
}

/// A checkpoint's payload, decoded.
struct Payload {
    case_hash: String,
    run_id: String,
    step: u64,
    timing: (f64, f64, f64),
    history_started: bool,
    forces_current: bool,
    /// The load peaks (None: not known) and the inexact-sum count.
    sums: (Option<[f64; 2]>, u64),
    particles: Particles,
    neighbors: NeighborState,
    anchors: Vec<Vec3>,
    /// What the contact sources carry (the pairs' and plane walls' histories are in
    /// `neighbors`).
    sources: SourceState,
    /// The insertions' and outlets' state (None before format 7).
    flow: Option<Vec<u64>>,
    /// The mesh motions set between steps (empty before format 11).
    scripted: Vec<f64>,
    /// The caller's note (empty before format 8).
    note: Vec<u8>,
}

/// What the contact sources carry across a restart, as a checkpoint holds it (particles by
/// id), before it is handed back to the sources.
#[derive(Debug, Default)]
pub(crate) struct SourceState {
    /// Particle pairs (ids) and their histories.
    pub pairs: Vec<[u32; 2]>,
    pub pair_history: Vec<Vec3>,
    /// Particle–plane-wall pairs (id, wall) and their histories.
    pub wall_pairs: Vec<[u32; 2]>,
    pub wall_history: Vec<Vec3>,
    /// The mesh-wall contacts: (particle id, mesh), triangle, normal, history.
    pub mesh_contacts: (Vec<[u32; 2]>, Vec<u32>, Vec<Vec3>, Vec<Vec3>),
    /// Each mesh's motion: anchor time, anchor pose, pose (None before format 6).
    pub mesh_motion: Option<Vec<(f64, Pose, Pose)>>,
    /// The cylinder-wall contacts: (particle id, cylinder), history (none before format 9).
    pub cylinder_contacts: (Vec<[u32; 2]>, Vec<Vec3>),
}

/// A contact source's section of a checkpoint (format 10 on): what it carries across a restart,
/// written and read in the sources' order (`forces::source::each_source_type!`).
pub(crate) trait Saved {
    /// Writes the section for the state of `sim`, naming particles by id.
    fn save<W: Write>(&self, sim: &Simulation, e: &mut Enc<W>) -> io::Result<()>;
    /// The bytes [`save`](Self::save) writes.
    fn saved_bytes(&self, sim: &Simulation) -> usize;
    /// Reads the section into `state`.
    fn load<R: Read>(d: &mut Dec<R>, state: &mut SourceState) -> Result<(), CheckpointError>;
}

/// The bytes of a list of `n` pairs and of `n` vectors, as [`Enc`] writes them.
pub(crate) fn pairs_bytes(n: usize) -> usize {
    (8 + 8 * n) + (8 + 24 * n)
}

/// f64s per mesh of the motion state: τ, then two poses of a quaternion and a translation.
pub(crate) const MOTION_F64S: usize = 15;

/// A pose from 7 numbers (quaternion x, y, z, w; translation).
pub(crate) fn pose_of(v: &[f64]) -> Pose {
    Pose {
        rotation: glam::DQuat::from_xyzw(v[0], v[1], v[2], v[3]),
        translation: Vec3::new(v[4], v[5], v[6]),
    }
}

/// The 7 numbers of a pose.
pub(crate) fn pose_numbers(p: &Pose) -> [f64; 7] {
    let (q, t) = (p.rotation, p.translation);
    [q.x, q.y, q.z, q.w, t.x, t.y, t.z]
}

/// Each mesh's motion state (anchor time, anchor pose, pose), as [`MOTION_F64S`] numbers a mesh.
pub(crate) fn mesh_motion(d: &mut Dec<impl Read>) -> Result<Vec<(f64, Pose, Pose)>, CheckpointError> {
    let v = d.f64s("mesh motion")?;
    if v.len() % MOTION_F64S != 0 {
        return Err(CheckpointError::Truncated("mesh motion"));
    }
    Ok(v.chunks_exact(MOTION_F64S).map(|c| (c[0], pose_of(&c[1..8]), pose_of(&c[8..15]))).collect())
}

/// The insertions' and outlets' state, in 64-bit words.
fn flow_words(d: &mut Dec<impl Read>) -> Result<Vec<u64>, CheckpointError> {
    let b = d.bytes("insertions and outlets")?;
    if b.len() % 8 != 0 {
        return Err(CheckpointError::Truncated("insertions and outlets"));
    }
    Ok(b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect())
}

impl Payload {
    fn decode(d: &mut Dec<impl Read>, version: u32) -> Result<Payload, CheckpointError> {
        let case_hash = String::from_utf8_lossy(&d.bytes("case hash")?).into_owned();
        let run_id = if version >= 3 {
            String::from_utf8_lossy(&d.bytes("run id")?).into_owned()
        } else {
            String::new()
        };
        let step = d.u64("step")?;
        let timing = (d.f64("time")?, d.f64("time step")?, d.f64("start time")?);
        let history_started = d.u64("flags")? != 0;
        let forces_current = d.u64("flags")? != 0;
        let sums = if version >= 4 {
            let peak = [d.f64("load peaks")?, d.f64("load peaks")?];
            let inexact = d.u64("inexact sums")?;
            // NaN: written before any evaluation.
            (peak.iter().all(|p| !p.is_nan()).then_some(peak), inexact)
        } else {
            (None, 0)
        };
        let mut p = Particles {
            id: d.u32s("ids")?,
            phase: d.u32s("phases")?,
            radius: d.f64s("radii")?,
            mass: d.f64s("masses")?,
            inertia: d.f64s("inertia")?,
            ..Default::default()
        };
        for v in [
            &mut p.position,
            &mut p.velocity,
            &mut p.omega,
            &mut p.force,
            &mut p.torque,
            &mut p.accel_prev,
            &mut p.alpha_prev,
        ] {
            *v = d.vec3s("particle vectors")?;
        }
        let (skin, built) = (d.f64("skin")?, d.u64("flags")? != 0);
        let mut sources = SourceState::default();
        let (reference, anchors, flow);
        if version >= 10 {
            reference = d.vec3s("reference positions")?;
            anchors = d.vec3s("motion anchors")?;
            crate::forces::source::each_source_type!(|S| S::load(d, &mut sources)?);
            flow = Some(flow_words(d)?);
        } else {
            // The sections in the order of formats 2–9.
            crate::forces::source::Pairs::load(d, &mut sources)?;
            crate::forces::source::Planes::load(d, &mut sources)?;
            reference = d.vec3s("reference positions")?;
            anchors = d.vec3s("motion anchors")?;
            if version >= 5 {
                sources.mesh_contacts = (
                    d.pairs("mesh contacts")?,
                    d.u32s("mesh contact triangles")?,
                    d.vec3s("mesh contact normals")?,
                    d.vec3s("mesh contact histories")?,
                );
            }
            if version >= 6 {
                sources.mesh_motion = Some(mesh_motion(d)?);
            }
            flow = if version >= 7 { Some(flow_words(d)?) } else { None };
            if version >= 9 {
                crate::forces::source::Cylinders::load(d, &mut sources)?;
            }
        }
        let neighbors = NeighborState {
            skin,
            built,
            pairs: std::mem::take(&mut sources.pairs),
            pair_history: std::mem::take(&mut sources.pair_history),
            wall_pairs: std::mem::take(&mut sources.wall_pairs),
            wall_history: std::mem::take(&mut sources.wall_history),
            reference,
        };
        let scripted = if version >= 11 { d.f64s("scripted mesh motions")? } else { Vec::new() };
        if scripted.len() % crate::forces::source::SCRIPTED_F64S != 0 {
            return Err(CheckpointError::Truncated("scripted mesh motions"));
        }
        let note = if version >= 8 { d.bytes("note")? } else { Vec::new() };
        let mut neighbors = neighbors;
        if version >= 3 {
            ids_to_slots(&p.id, &mut neighbors)?;
        }
        Ok(Payload {
            case_hash,
            run_id,
            step,
            timing,
            history_started,
            forces_current,
            sums,
            particles: p,
            neighbors,
            anchors,
            sources,
            flow,
            scripted,
            note,
        })
    }
}

impl Simulation {
    /// The simulation's complete dynamic state as checkpoint bytes, tagged with `case_hash`.
    pub fn checkpoint(&self, case_hash: &str) -> Vec<u8> {
        let mut out = Vec::new();
        self.checkpoint_into(case_hash, &mut out);
        out
    }

    /// As [`checkpoint`](Self::checkpoint), into `out` (cleared first; its allocation is
    /// reused, so keeping a rolling copy of the state costs one copy, not two).
    pub fn checkpoint_into(&self, case_hash: &str, out: &mut Vec<u8>) {
        out.clear();
        out.reserve_exact(self.checkpoint_size(case_hash));
        self.write_checkpoint(case_hash, &mut *out).expect("writing to memory cannot fail");
    }

    /// The size of the checkpoint in bytes.
    pub fn checkpoint_size(&self, case_hash: &str) -> usize {
        HEADER + self.payload_size(case_hash) + 8
    }

    /// Size of the payload (between the header and the checksum).
    fn payload_size(&self, case_hash: &str) -> usize {
        let p = self.particles();
        let nl = self.neighbors();
        let n = p.len();
        8 + case_hash.len()
            + 8
            + self.run_id().len()
            + 6 * 8
            + 3 * 8
            + 2 * (8 + 4 * n)
            + 3 * (8 + 8 * n)
            + 5 * (8 + 24 * n)
            + 2 * (8 + 24 * p.accel_prev.len())
            + 16
            + (8 + 24 * nl.reference().len())
            + (8 + 24 * self.motion_anchors().len())
            + self.sources.saved_bytes(self)
            + (8 + 8 * self.flow_words().len())
            + (8 + 8 * self.scripted_motion_numbers().len())
            + (8 + self.checkpoint_note().len())
    }

    /// Streams the checkpoint to `w` (no copy of the state in memory: a large state can go
    /// straight to a file). The bytes are those of [`checkpoint`](Self::checkpoint).
    pub fn write_checkpoint(&self, case_hash: &str, mut w: impl Write) -> io::Result<()> {
        let payload = self.payload_size(case_hash);
        w.write_all(MAGIC)?;
        w.write_all(&FORMAT_VERSION.to_le_bytes())?;
        w.write_all(&(payload as u64).to_le_bytes())?;
        let mut e = Enc { w, sum: FNV_OFFSET, written: 0 };
        let p = self.particles();
        let nl = self.neighbors();
        e.bytes(case_hash.as_bytes())?;
        e.bytes(self.run_id().as_bytes())?;
        let (step, history_started, forces_current) = self.counters();
        e.u64(step)?;
        let (time, dt, t_start) = self.timing();
        e.f64(time)?;
        e.f64(dt)?;
        e.f64(t_start)?;
        e.u64(history_started as u64)?;
        e.u64(forces_current as u64)?;
        let (peak, inexact) = self.sums_state();
        for v in peak.unwrap_or([f64::NAN; 2]) {
            e.f64(v)?;
        }
        e.u64(inexact)?;
        e.u32s(&p.id)?;
        e.u32s(&p.phase)?;
        for v in [&p.radius, &p.mass, &p.inertia] {
            e.f64s(v)?;
        }
        for v in [&p.position, &p.velocity, &p.omega, &p.force, &p.torque, &p.accel_prev, &p.alpha_prev] {
            e.vec3s(v)?;
        }
        e.f64(nl.skin())?;
        e.u64(nl.is_built() as u64)?;
        e.vec3s(nl.reference())?;
        e.vec3s(&self.motion_anchors())?;
        self.sources.save(self, &mut e)?;
        e.bytes(&self.flow_words().iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>())?;
        e.f64s(&self.scripted_motion_numbers())?;
        e.bytes(self.checkpoint_note())?;
        // The header announced the payload's length before it was written.
        if e.written != payload {
            return Err(io::Error::other(format!(
                "internal error: checkpoint payload of {} bytes announced as {payload}",
                e.written
            )));
        }
        let sum = e.sum;
        e.w.write_all(&sum.to_le_bytes())
    }

    /// Rebuilds a simulation of `config` from checkpoint bytes written for `case_hash`
    /// (`None`: accept a checkpoint of a changed case, e.g. after fixing a time step; the
    /// particles must still match).
    pub fn restore(
        config: SimulationConfig,
        bytes: &[u8],
        case_hash: Option<&str>,
    ) -> Result<Simulation, RestoreError> {
        Simulation::restore_from(config, bytes, bytes.len() as u64, case_hash)
    }

    /// [`restore`](Self::restore) from a stream of `size` bytes (a checkpoint file and its
    /// length), read as it is decoded: the checkpoint is never held in memory whole.
    pub fn restore_from(
        config: SimulationConfig,
        mut r: impl Read,
        size: u64,
        case_hash: Option<&str>,
    ) -> Result<Simulation, RestoreError> {
        // Shorter than a signature, or another one: not a checkpoint (a failing read is
        // reported as such).
        let mut magic = [0u8; 8];
        let read = if size < 8 {
            Err(CheckpointError::Truncated("signature"))
        } else {
            read_exact(&mut r, &mut magic, "signature")
        };
        match read {
            Err(CheckpointError::Read(e)) => return Err(CheckpointError::Read(e).into()),
            Err(_) => return Err(CheckpointError::NotACheckpoint.into()),
            Ok(()) if &magic != MAGIC => return Err(CheckpointError::NotACheckpoint.into()),
            Ok(()) => {}
        }
        let mut word = [0u8; 4];
        read_exact(&mut r, &mut word, "version")?;
        let version = u32::from_le_bytes(word);
        if !(OLDEST_FORMAT_READ..=FORMAT_VERSION).contains(&version) {
            return Err(CheckpointError::Version {
                found: version,
                oldest: OLDEST_FORMAT_READ,
                newest: FORMAT_VERSION,
            }
            .into());
        }
        let mut long = [0u8; 8];
        read_exact(&mut r, &mut long, "length")?;
        let len = u64::from_le_bytes(long);
        let total = len.checked_add((HEADER + 8) as u64);
        if total.is_none_or(|total| total > size) {
            return Err(CheckpointError::Truncated("payload").into());
        }
        if let Some(total) = total
            && total < size
        {
            return Err(CheckpointError::TrailingBytes(size - total).into());
        }
        let mut d = Dec { r, left: len, sum: FNV_OFFSET, scratch: Vec::new() };
        let payload = Payload::decode(&mut d, version);
        // The checksum covers the whole payload: read what the decoding left (all of it if a
        // damaged count stopped it), so that damage is reported as such.
        match &payload {
            Err(e @ (CheckpointError::Truncated(_) | CheckpointError::Read(_))) => {
                return Err(e.clone().into());
            }
            _ => d.skip_rest()?,
        }
        read_exact(&mut d.r, &mut long, "checksum")?;
        if u64::from_le_bytes(long) != d.sum {
            return Err(CheckpointError::Corrupted.into());
        }
        let payload = payload?;
        if let Some(expected) = case_hash
            && payload.case_hash != expected
        {
            return Err(
                CheckpointError::WrongCase { found: payload.case_hash, expected: expected.into() }.into()
            );
        }
        let Payload {
            step,
            timing,
            history_started,
            forces_current,
            particles,
            neighbors,
            anchors,
            run_id,
            sums,
            sources,
            flow,
            scripted,
            note,
            ..
        } = payload;
        let mut sim = Simulation::unbuilt(config, particles)?;
        sim.set_run_id(run_id);
        sim.set_checkpoint_note(note);
        sim.set_sums_state(sums.0, sums.1);
        sim.restore_dynamic_state(timing, step, history_started, forces_current, neighbors, &anchors)
            .map_err(CheckpointError::Mismatch)?;
        sim.set_mesh_histories(sources.mesh_contacts).map_err(CheckpointError::Mismatch)?;
        sim.set_cylinder_histories(sources.cylinder_contacts).map_err(CheckpointError::Mismatch)?;
        sim.set_scripted_motions(&scripted).map_err(CheckpointError::Mismatch)?;
        if let Some(motion) = sources.mesh_motion {
            sim.set_mesh_motion_state(&motion).map_err(CheckpointError::Mismatch)?;
        }
        if let Some(flow) = flow {
            sim.set_flow_words(&flow).map_err(CheckpointError::Mismatch)?;
        }
        sim.prepare_mesh_candidates();
        Ok(sim)
    }
}

/// Why a restart failed: the checkpoint, or the engine's set-up checks.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RestoreError {
    /// The checkpoint itself.
    #[error("{0}")]
    Checkpoint(#[from] CheckpointError),
    /// The restored state failed the engine's checks.
    #[error("{0}")]
    Engine(#[from] crate::error::EngineError),
}
