//! The domain cut into one box per rank, by recursive coordinate bisection weighted by work:
//! the first step of spreading a run over processes.
//!
//! A region of `r` ranks is cut across its longest side (the lowest axis of equally long
//! ones) into a part for `⌊r/2⌋` ranks and one for the rest, where the work before the cut is
//! the share of the first part; each part is then cut the same way until every part has one
//! rank. A cut is found by histograms of the work along its axis, each narrowing the bracket
//! the cut lies in to the bin where the share is reached: the histograms are sums of integers,
//! so the cut depends only on the particles, never on the order they are held in or on how
//! they are shared among the ranks that find it ([`bisect_over`]): every rank finds the same
//! boxes, to the bit.
//!
//! A particle belongs to the box with `lo ≤ x < hi` on every axis ([`Boxes::owner`]).

use crate::boundary::Periodic;
use crate::math::Vec3;

/// What the ranks of a run say to each other: a message is a list of 64-bit words (`f64`s by
/// their bits). Every rank calls each method at the same point of the run (they are
/// collective); the run's MPI layer implements it, and [`LocalComm`] runs ranks as threads of
/// one process (for tests).
pub trait Comm: Send + Sync + std::fmt::Debug {
    /// This rank, from 0.
    fn rank(&self) -> usize;
    /// The number of ranks.
    fn size(&self) -> usize;
    /// Sends `out[r]` to rank `r` (one list per rank, this one's included) and returns what
    /// each rank sent to this one, by rank.
    fn exchange(&self, out: Vec<Vec<u64>>) -> Vec<Vec<u64>>;
    /// Every rank's `mine`, by rank.
    fn all_gather(&self, mine: &[u64]) -> Vec<Vec<u64>> {
        self.exchange(vec![mine.to_vec(); self.size()])
    }
}

/// What decides whether the ranks' boxes are cut again, and how the cut weighs their work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Weigh {
    /// The particles and their list partners, counted: the same re-cuts on every run of a
    /// case.
    #[default]
    Work,
    /// Each rank's measured busy time (its steps less the time it spends in the
    /// communicator): a rank slowed by its processor, or by work the count misses (mesh
    /// contacts), gets a smaller box. The cuts then differ from run to run; the results do
    /// not (they never depend on the boxes).
    Time,
}

/// A communicator that keeps the time spent in its calls (the waits for the other ranks
/// included): what a rank did not spend on its own work.
#[derive(Debug)]
pub(crate) struct Timed {
    inner: std::sync::Arc<dyn Comm>,
    nanos: std::sync::atomic::AtomicU64,
}

impl Timed {
    pub(crate) fn new(inner: std::sync::Arc<dyn Comm>) -> Timed {
        Timed { inner, nanos: std::sync::atomic::AtomicU64::new(0) }
    }

    /// Nanoseconds spent in calls so far.
    pub(crate) fn nanos(&self) -> u64 {
        self.nanos.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn timed<T>(&self, f: impl FnOnce(&dyn Comm) -> T) -> T {
        let t = std::time::Instant::now();
        let got = f(&*self.inner);
        self.nanos.fetch_add(t.elapsed().as_nanos() as u64, std::sync::atomic::Ordering::Relaxed);
        got
    }
}

impl Comm for Timed {
    fn rank(&self) -> usize {
        self.inner.rank()
    }

    fn size(&self) -> usize {
        self.inner.size()
    }

    fn exchange(&self, out: Vec<Vec<u64>>) -> Vec<Vec<u64>> {
        self.timed(|c| c.exchange(out))
    }

    fn all_gather(&self, mine: &[u64]) -> Vec<Vec<u64>> {
        self.timed(|c| c.all_gather(mine))
    }
}

/// Ranks as threads of one process: [`LocalComm::team`] gives one communicator per rank, each
/// to be used on its own thread.
#[derive(Debug)]
pub struct LocalComm {
    rank: usize,
    shared: std::sync::Arc<Mailbox>,
}

/// The messages on their way: `slots[to][from]`, and the barrier the ranks meet at.
#[derive(Debug)]
struct Mailbox {
    slots: std::sync::Mutex<Vec<Vec<Vec<u64>>>>,
    barrier: std::sync::Barrier,
}

impl LocalComm {
    /// Communicators for `ranks` ranks (at least one).
    pub fn team(ranks: usize) -> Vec<LocalComm> {
        let n = ranks.max(1);
        let shared = std::sync::Arc::new(Mailbox {
            slots: std::sync::Mutex::new(vec![vec![Vec::new(); n]; n]),
            barrier: std::sync::Barrier::new(n),
        });
        (0..n).map(|rank| LocalComm { rank, shared: shared.clone() }).collect()
    }
}

impl Comm for LocalComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.shared.slots.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    fn exchange(&self, out: Vec<Vec<u64>>) -> Vec<Vec<u64>> {
        {
            let mut slots = self.shared.slots.lock().unwrap_or_else(|e| e.into_inner());
            for (to, words) in out.into_iter().enumerate() {
                slots[to][self.rank] = words;
            }
        }
        self.shared.barrier.wait();
        let got: Vec<Vec<u64>> = {
            let mut slots = self.shared.slots.lock().unwrap_or_else(|e| e.into_inner());
            slots[self.rank].iter_mut().map(std::mem::take).collect()
        };
        // Nobody writes the next round before everyone has read this one.
        self.shared.barrier.wait();
        got
    }
}

/// A particle as the cut sees it: its position, its work (any positive count, e.g. 1 + its
/// contacts) and its id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weighted {
    pub position: Vec3,
    pub work: u64,
    pub id: u64,
}

/// The boxes of the ranks, rank by rank: `lo` and `hi` corners, m; and the domain they tile.
#[derive(Debug, Clone, PartialEq)]
pub struct Boxes {
    pub boxes: Vec<[Vec3; 2]>,
    pub domain: [Vec3; 2],
}

impl Boxes {
    /// The rank whose box holds `x` (`lo ≤ x < hi` on every axis; a point on the domain's upper
    /// faces belongs to the box that ends there), or `None` outside the domain.
    pub fn owner(&self, x: Vec3) -> Option<usize> {
        self.owner_near(x, 0)
    }

    /// [`owner`](Self::owner), looking at the box of `likely` first (the same answer: the
    /// boxes do not overlap).
    pub fn owner_near(&self, x: Vec3, likely: usize) -> Option<usize> {
        let [lo, hi] = self.domain;
        let inside = |b: &[Vec3; 2]| {
            (0..3).all(|k| {
                let (v, l, h) = (x[k], b[0][k], b[1][k]);
                l <= v && (v < h || (h == hi[k] && v == h))
            })
        };
        if (0..3).any(|k| !(x[k] >= lo[k] && x[k] <= hi[k])) {
            return None;
        }
        if self.boxes.get(likely).is_some_and(inside) {
            return Some(likely);
        }
        self.boxes.iter().position(inside)
    }

    /// Appends to `out` every other rank (with the shift of the periodic image, m) whose box
    /// lies closer than `reach` to a particle at `x` owned by rank `own`: the ranks that need
    /// it as a ghost, for its contacts with their particles. A rank's own box counts through a
    /// periodic image (a rank that wraps onto itself); shifts run over −L, 0 and +L on the
    /// periodic axes of `periodic`, whose box must be the domain.
    pub fn ghost_ranks(
        &self,
        x: Vec3,
        reach: f64,
        own: usize,
        periodic: &Periodic,
        out: &mut Vec<(usize, Vec3)>,
    ) {
        // At least `reach` inside its own box, a particle is `reach` or more from every other
        // box (they do not overlap) and every periodic image is as far outside the domain.
        if let Some([lo, hi]) = self.boxes.get(own)
            && (x - *lo).min(*hi - x).min_element() >= reach
        {
            return;
        }
        let length = periodic.hi - periodic.lo;
        let steps = |k: usize| if periodic.axes[k] { -1..=1 } else { 0..=0 };
        for sx in steps(0) {
            for sy in steps(1) {
                for sz in steps(2) {
                    let shift = Vec3::new(sx as f64 * length.x, sy as f64 * length.y, sz as f64 * length.z);
                    let image = x + shift;
                    for (r, b) in self.boxes.iter().enumerate() {
                        if r == own && shift == Vec3::ZERO {
                            continue;
                        }
                        let gap = (b[0] - image).max(image - b[1]).max(Vec3::ZERO);
                        if gap.length_squared() < reach * reach {
                            out.push((r, shift));
                        }
                    }
                }
            }
        }
    }
}

/// Cuts the domain `lo`..`hi` into `ranks` boxes (at least one) of about equal work of
/// `particles` (see the module doc).
pub fn bisect(lo: Vec3, hi: Vec3, particles: &[Weighted], ranks: usize) -> Boxes {
    bisect_over(lo, hi, particles, ranks, &mut |counts| counts)
}

/// Bins of a bracket's histogram, and the rounds that narrow a cut's bracket: a cut lies
/// within 64⁻⁴ ≈ 6·10⁻⁸ of its side's length of the best place between two particles.
const BINS: usize = 64;
const ROUNDS: usize = 4;

/// [`bisect`] of particles held by several ranks, each with its share: `sum` adds a list of
/// counts element by element over the ranks (every rank calls this alike, and `sum` as often,
/// with lists of the same length). The sums are of integers, so every rank finds the same
/// boxes whatever the order the ranks answer in.
pub fn bisect_over(
    lo: Vec3,
    hi: Vec3,
    particles: &[Weighted],
    ranks: usize,
    sum: &mut dyn FnMut(Vec<u64>) -> Vec<u64>,
) -> Boxes {
    // The parts so far, in rank order: corners and ranks; and each particle's part.
    let mut parts: Vec<([Vec3; 2], usize)> = vec![([lo, hi], ranks.max(1))];
    let mut part_of = vec![0usize; particles.len()];
    loop {
        let cutting: Vec<usize> = (0..parts.len()).filter(|&k| parts[k].1 > 1).collect();
        if cutting.is_empty() {
            break;
        }
        // Per part being cut: its axis, its row among those cut (or none).
        let axis = |k: usize| {
            let e = parts[k].0[1] - parts[k].0[0];
            (0..3).fold(0, |best, a| if e[a] > e[best] { a } else { best })
        };
        let mut row = vec![usize::MAX; parts.len()];
        for (r, &k) in cutting.iter().enumerate() {
            row[k] = r;
        }
        let mut totals = vec![0u64; cutting.len()];
        for (p, &k) in particles.iter().zip(&part_of) {
            if row[k] != usize::MAX {
                totals[row[k]] += p.work;
            }
        }
        let totals = sum(totals);
        // The bracket [a, b) each cut lies in, the work below a, and the work in [a, b).
        let mut bracket: Vec<(f64, f64)> =
            cutting.iter().map(|&k| (parts[k].0[0][axis(k)], parts[k].0[1][axis(k)])).collect();
        let mut below = vec![0u64; cutting.len()];
        let mut inside = totals.clone();
        // Whether `w` of a part's work before the cut reaches its first ranks' share.
        let reaches = |w: u64, r: usize, k: usize| {
            let (n, first) = (parts[k].1 as u128, (parts[k].1 / 2) as u128);
            w as u128 * n >= totals[r] as u128 * first
        };
        for _ in 0..ROUNDS {
            let mut hist = vec![0u64; cutting.len() * BINS];
            for (p, &k) in particles.iter().zip(&part_of) {
                let r = row[k];
                if r != usize::MAX
                    && let Some(bin) = bin_of(p.position[axis(k)], bracket[r])
                {
                    hist[r * BINS + bin] += p.work;
                }
            }
            let hist = sum(hist);
            for (r, &k) in cutting.iter().enumerate() {
                let bins = &hist[r * BINS..(r + 1) * BINS];
                let mut before = below[r];
                let mut at = BINS - 1;
                for (bin, &w) in bins.iter().enumerate() {
                    if reaches(before + w, r, k) {
                        at = bin;
                        break;
                    }
                    before += w;
                }
                below[r] = before;
                inside[r] = bins[at];
                bracket[r] = (edge(bracket[r], at), edge(bracket[r], at + 1));
            }
        }
        // Each part's first part next, and where it was cut (axis, coordinate).
        let mut next = Vec::with_capacity(parts.len() + cutting.len());
        let mut renumber = vec![(0usize, None); parts.len()];
        for (k, &([l, h], n)) in parts.iter().enumerate() {
            let r = row[k];
            if r == usize::MAX {
                renumber[k] = (next.len(), None);
                next.push(([l, h], n));
                continue;
            }
            let (a, first) = (axis(k), n / 2);
            let at = if totals[r] == 0 {
                l[a] + (h[a] - l[a]) * first as f64 / n as f64
            } else {
                // The bracket's end whose work before it is nearer the share.
                let share = totals[r] as f64 * first as f64 / n as f64;
                let (w_lo, w_hi) = (below[r] as f64, (below[r] + inside[r]) as f64);
                if share - w_lo <= w_hi - share { bracket[r].0 } else { bracket[r].1 }
            };
            let at = at.clamp(l[a], h[a]);
            let (mut low_hi, mut high_lo) = (h, l);
            low_hi[a] = at;
            high_lo[a] = at;
            renumber[k] = (next.len(), Some((a, at)));
            next.push(([l, low_hi], first));
            next.push(([high_lo, h], n - first));
        }
        for (p, k) in particles.iter().zip(part_of.iter_mut()) {
            let (low, cut) = renumber[*k];
            *k = match cut {
                Some((a, at)) if p.position[a] >= at => low + 1,
                _ => low,
            };
        }
        parts = next;
    }
    Boxes { boxes: parts.into_iter().map(|(b, _)| b).collect(), domain: [lo, hi] }
}

/// The `k`th of the `BINS + 1` edges of the bins of `[a, b)`.
fn edge((a, b): (f64, f64), k: usize) -> f64 {
    if k == BINS { b } else { a + (b - a) * (k as f64 / BINS as f64) }
}

/// The bin of `[a, b)` that holds `x` (`edge(k) ≤ x < edge(k + 1)`), or none outside it.
fn bin_of(x: f64, bracket: (f64, f64)) -> Option<usize> {
    let (a, b) = bracket;
    if !(x >= a && x < b) {
        return None;
    }
    let mut k = (((x - a) / (b - a) * BINS as f64) as usize).min(BINS - 1);
    while k > 0 && x < edge(bracket, k) {
        k -= 1;
    }
    while k + 1 < BINS && x >= edge(bracket, k + 1) {
        k += 1;
    }
    Some(k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn cloud(n: usize, seed: u64, work: impl Fn(Vec3) -> u64) -> Vec<Weighted> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let position =
                    Vec3::new(rng.random::<f64>() * 4.0, rng.random::<f64>() * 2.0, rng.random::<f64>());
                Weighted { position, work: work(position), id: i as u64 }
            })
            .collect()
    }

    /// The boxes tile the domain (their volumes add up to its volume, and every particle lies
    /// in exactly one), and each holds its share of the work to within one particle's work per
    /// level of cuts: a cut misses its target by less than the work of the particle at it.
    #[test]
    fn boxes_tile_the_domain_and_share_the_work() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0));
        for (ranks, seed) in [(1, 1), (2, 2), (3, 3), (4, 4), (7, 5), (16, 6)] {
            let particles = cloud(5_000, seed, |x| 1 + (x.x * 3.0) as u64);
            let cut = bisect(lo, hi, &particles, ranks);
            assert_eq!(cut.boxes.len(), ranks);
            let volume: f64 =
                cut.boxes.iter().map(|b| (b[1] - b[0]).x * (b[1] - b[0]).y * (b[1] - b[0]).z).sum();
            // Volumes of boxes cut at rounded coordinates: to a few roundings of the domain's.
            assert!((volume - 8.0).abs() < 1e-12, "{ranks} ranks: volume {volume}");
            let mut work = vec![0.0; ranks];
            for p in &particles {
                let inside: Vec<usize> = (0..ranks)
                    .filter(|&r| {
                        (0..3).all(|k| {
                            cut.boxes[r][0][k] <= p.position[k] && p.position[k] < cut.boxes[r][1][k]
                        })
                    })
                    .collect();
                assert_eq!(inside.len(), 1, "{ranks} ranks: particle {} in boxes {inside:?}", p.id);
                assert_eq!(cut.owner(p.position), Some(inside[0]));
                work[inside[0]] += p.work as f64;
            }
            let total = particles.iter().map(|p| p.work).sum::<u64>() as f64;
            let w_max = particles.iter().map(|p| p.work).max().unwrap_or(0) as f64;
            // A cut misses its target by less than one particle's work, and a part's target
            // follows the work it was given: the errors add up over the levels of cuts. (Twice
            // that, for a particle on either side of a cut's midpoint.)
            let levels = (ranks as f64).log2().ceil();
            for (r, w) in work.iter().enumerate() {
                let share = total / ranks as f64;
                assert!(
                    (w - share).abs() <= levels * 2.0 * w_max,
                    "{ranks} ranks: rank {r} has work {w}, its share {share}"
                );
            }
        }
    }

    /// The cut depends on the particles only: held in another order, they give the same bits.
    #[test]
    fn the_cut_does_not_depend_on_the_order_of_the_particles() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0));
        let particles = cloud(2_000, 9, |x| 1 + (x.y * 4.0) as u64);
        let mut reversed = particles.clone();
        reversed.reverse();
        for ranks in [2, 3, 5, 8] {
            assert_eq!(bisect(lo, hi, &particles, ranks), bisect(lo, hi, &reversed, ranks));
        }
    }

    /// Shared among ranks (three threads, each holding every third particle), the particles
    /// are cut into the boxes one holder of them all finds, to the bit.
    #[test]
    fn ranks_holding_shares_find_the_boxes_of_one_holder() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0));
        let particles = cloud(3_000, 13, |x| 1 + (x.x * 5.0) as u64);
        for ranks in [2, 3, 5] {
            let whole = bisect(lo, hi, &particles, ranks);
            let shares: Vec<Boxes> = std::thread::scope(|s| {
                let handles: Vec<_> = LocalComm::team(3)
                    .into_iter()
                    .map(|comm| {
                        let mine: Vec<Weighted> =
                            particles.iter().skip(comm.rank()).step_by(3).copied().collect();
                        s.spawn(move || {
                            bisect_over(lo, hi, &mine, ranks, &mut |counts| {
                                let all = comm.all_gather(&counts);
                                (0..counts.len()).map(|k| all.iter().map(|c| c[k]).sum()).collect()
                            })
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().expect("a rank")).collect()
            });
            for b in &shares {
                assert_eq!(b, &whole, "{ranks} boxes");
            }
        }
    }

    /// Work, not count: a quarter of the domain with nine times the work per particle takes
    /// its rank nearly alone. Two ranks on particles spread evenly along x with work 9 for
    /// x < 1 and 1 beyond: the work before x is 9x (x ≤ 1), then 9 + (x − 1); half of the
    /// total 12 is reached at x = 6/9 ≈ 0.667, to within the spacing of the particles.
    #[test]
    fn the_cut_follows_the_work() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 1.0, 1.0));
        let particles: Vec<Weighted> = (0..4_000)
            .map(|i| {
                let x = (i as f64 + 0.5) / 1000.0;
                Weighted { position: Vec3::new(x, 0.5, 0.5), work: if x < 1.0 { 9 } else { 1 }, id: i }
            })
            .collect();
        let cut = bisect(lo, hi, &particles, 2);
        let at = cut.boxes[0][1].x;
        assert!((at - 2.0 / 3.0).abs() < 1e-3, "cut at x = {at}");
        assert_eq!(cut.owner(Vec3::new(4.0, 1.0, 1.0)), Some(1), "the upper corner belongs to the last box");
        assert_eq!(cut.owner(Vec3::new(4.1, 0.5, 0.5)), None);
    }

    /// Ghosts suffice: every pair of particles closer than the reach, owned by two ranks or
    /// one rank through a periodic image, finds each particle as a ghost on the other's rank
    /// with the shift that brings it next to the other (checked against every pair).
    #[test]
    fn every_pair_within_reach_across_ranks_has_its_ghosts() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0));
        let periodic = Periodic { lo, hi, axes: [true, false, true] };
        let particles = cloud(600, 11, |_| 1);
        let reach = 0.3;
        for ranks in [1, 2, 3, 5] {
            let cut = bisect(lo, hi, &particles, ranks);
            let owner: Vec<usize> = particles.iter().map(|p| cut.owner(p.position).unwrap()).collect();
            let ghosts: Vec<Vec<(usize, Vec3)>> = particles
                .iter()
                .zip(&owner)
                .map(|(p, &o)| {
                    let mut g = Vec::new();
                    cut.ghost_ranks(p.position, reach, o, &periodic, &mut g);
                    g
                })
                .collect();
            let mut checked = 0;
            for (i, a) in particles.iter().enumerate() {
                for (j, b) in particles.iter().enumerate() {
                    if i == j {
                        continue;
                    }
                    for sx in -1..=1 {
                        for sz in -1..=1 {
                            let shift = Vec3::new(4.0 * sx as f64, 0.0, sz as f64);
                            let near = (a.position + shift - b.position).length() < reach;
                            if near && (owner[i] != owner[j] || shift != Vec3::ZERO) {
                                checked += 1;
                                assert!(
                                    ghosts[i].contains(&(owner[j], shift)),
                                    "{ranks} ranks: particle {i} (rank {}) is not a ghost on rank {} at shift {shift}",
                                    owner[i],
                                    owner[j]
                                );
                            }
                        }
                    }
                }
            }
            assert!(checked > 100, "{ranks} ranks: only {checked} pairs across ranks or images");
        }
    }
}
