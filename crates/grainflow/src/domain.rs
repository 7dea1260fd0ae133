//! The domain cut into one box per rank, by recursive coordinate bisection weighted by work:
//! the first step of spreading a run over processes.
//!
//! A region of `r` ranks is cut across its longest side (the lowest axis of equally long
//! ones) into a part for `⌊r/2⌋` ranks and one for the rest, where the work before the cut is
//! the share of the first part; each part is then cut the same way until every part has one
//! rank. The particles are taken in the order of their coordinate along the cut and their id,
//! so the cut depends only on the particles, never on the order they are held in: every rank
//! that cuts the same particles finds the same boxes, to the bit.
//!
//! A particle belongs to the box with `lo ≤ x < hi` on every axis ([`Boxes::owner`]); a cut
//! lies halfway between the last particle before it and the first after it.

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

/// A particle as the cut sees it: its position, its work (any positive measure, e.g. 1 + its
/// contacts) and its id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weighted {
    pub position: Vec3,
    pub work: f64,
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
    let mut items = particles.to_vec();
    let mut boxes = Vec::with_capacity(ranks.max(1));
    cut(lo, hi, &mut items, ranks.max(1), &mut boxes);
    Boxes { boxes, domain: [lo, hi] }
}

/// Cuts the region `lo`..`hi` holding `items` into `ranks` boxes, appended to `out` in rank
/// order.
fn cut(lo: Vec3, hi: Vec3, items: &mut [Weighted], ranks: usize, out: &mut Vec<[Vec3; 2]>) {
    if ranks == 1 {
        out.push([lo, hi]);
        return;
    }
    let extent = hi - lo;
    let axis = (0..3).fold(0, |best, k| if extent[k] > extent[best] { k } else { best });
    items.sort_unstable_by(|a, b| a.position[axis].total_cmp(&b.position[axis]).then(a.id.cmp(&b.id)));
    let first = ranks / 2;
    let total: f64 = items.iter().map(|p| p.work).sum();
    let target = total * first as f64 / ranks as f64;
    // The first particle with at least the first part's share of the work before it.
    let mut before = 0.0;
    let mut k = items.len();
    for (i, p) in items.iter().enumerate() {
        if before >= target {
            k = i;
            break;
        }
        before += p.work;
    }
    let coordinate = |i: usize| items[i].position[axis];
    let at = if items.is_empty() {
        lo[axis] + extent[axis] * first as f64 / ranks as f64
    } else if k == 0 {
        lo[axis].min(coordinate(0))
    } else if k == items.len() {
        hi[axis].max(coordinate(k - 1))
    } else {
        0.5 * (coordinate(k - 1) + coordinate(k))
    };
    let at = at.clamp(lo[axis], hi[axis]);
    // The particles before the cut plane (those at the plane's coordinate belong above it).
    let split = items.partition_point(|p| p.position[axis] < at);
    let (low, high) = items.split_at_mut(split);
    let (mut low_hi, mut high_lo) = (hi, lo);
    low_hi[axis] = at;
    high_lo[axis] = at;
    cut(lo, low_hi, low, first, out);
    cut(high_lo, hi, high, ranks - first, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn cloud(n: usize, seed: u64, work: impl Fn(Vec3) -> f64) -> Vec<Weighted> {
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
            let particles = cloud(5_000, seed, |x| 1.0 + (x.x * 3.0).floor());
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
                work[inside[0]] += p.work;
            }
            let total: f64 = particles.iter().map(|p| p.work).sum();
            let w_max = particles.iter().map(|p| p.work).fold(0.0, f64::max);
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
        let particles = cloud(2_000, 9, |x| 1.0 + x.y);
        let mut reversed = particles.clone();
        reversed.reverse();
        for ranks in [2, 3, 5, 8] {
            assert_eq!(bisect(lo, hi, &particles, ranks), bisect(lo, hi, &reversed, ranks));
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
                Weighted { position: Vec3::new(x, 0.5, 0.5), work: if x < 1.0 { 9.0 } else { 1.0 }, id: i }
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
        let particles = cloud(600, 11, |_| 1.0);
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
