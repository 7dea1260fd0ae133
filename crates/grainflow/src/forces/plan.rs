//! How the force stage shares its work out over threads: the slots cut into blocks of
//! consecutive rows with about equal estimated work ([`ForcePlan::prepare`]), the pairs that
//! cross from one block into a later one, and where each crossing pair's load arrives. Made
//! again with each neighbour-list build; it decides who computes what, never the order of a
//! sum, so the results do not depend on it.

use std::ops::Range;

use super::CrossingLoad;
use crate::math::Vec3;

/// Below this many particles the force stage runs on one thread (the threads' start-up would
/// cost more than they save). The results do not depend on it.
pub const MIN_PARALLEL_PARTICLES: usize = 2048;

/// Blocks per thread. More blocks would let the threads balance uneven work, at the price of
/// more crossing pairs; on the yardstick cases more gained nothing (measurements:
/// bench/results/2026-12-01-design-history.md), so each thread takes one block.
pub const BLOCKS_PER_THREAD: usize = 1;

/// How the slots are cut into blocks for threads, with the crossing pairs; rebuilt with the
/// neighbour list.
#[derive(Debug, Clone, Default)]
pub(crate) struct ForcePlan {
    /// The neighbour-list build this plan was made for, and the block count asked for.
    made_for: Option<(u64, usize)>,
    /// Rows of each block.
    pub(super) blocks: Vec<Range<usize>>,
    /// End of each block's wall pairs in the wall list.
    pub(super) wall_ends: Vec<usize>,
    /// Crossing pairs (row a, pair index k), grouped by block in list order.
    pub(super) crossing: Vec<(u32, usize)>,
    /// Start of each block's crossing pairs in `crossing` (blocks + 1 entries).
    pub(super) crossing_start: Vec<usize>,
    /// Crossing pairs arriving at each slot, as indices into `crossing`, in list order:
    /// `incoming[incoming_start[b]..incoming_start[b + 1]]` (32 bits: fewer than 2^32 crossing
    /// pairs, which would take hundreds of GB of memory).
    pub(super) incoming_start: Vec<u32>,
    pub(super) incoming: Vec<u32>,
    /// The crossing pairs' loads (None: not in contact).
    pub(super) loads: Vec<CrossingLoad>,
    /// Made before any contact was known: to be made again.
    provisional: bool,
    /// Each block's working memory, kept from one evaluation to the next.
    pub(super) scratch: Vec<super::Scratch>,
}

/// The work of a touching pair (gathering its inputs, the law, adding its load) in units of a
/// pair that is only tested for contact, and the work of a row (a particle: its accumulators,
/// its walk through the list, its arriving crossing pairs). Fitted to the time each block of
/// the force stage took on one core, so that blocks of more particles and fewer contacts per
/// particle (the chute's upper block) take as long as the others (measurements:
/// bench/results/2026-12-01-design-history.md).
const CONTACT_COST: usize = 4;
/// The work of a row, in the same units (see [`CONTACT_COST`]).
const ROW_COST: usize = 5;

impl ForcePlan {
    /// The blocks of slots, if the plan is for `n` slots (empty otherwise): the per-particle
    /// stages share the slots out over the threads the same way.
    pub fn blocks_for(&self, n: usize) -> &[Range<usize>] {
        if self.blocks.last().is_some_and(|b| b.end == n) { &self.blocks } else { &[] }
    }

    /// Heap bytes held by the plan.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.blocks.capacity() * size_of::<Range<usize>>()
            + self.crossing.capacity() * size_of::<(u32, usize)>()
            + (self.wall_ends.capacity() + self.crossing_start.capacity()) * size_of::<usize>()
            + (self.incoming_start.capacity() + self.incoming.capacity()) * 4
            + self.loads.capacity() * size_of::<CrossingLoad>()
            + self.scratch.capacity() * size_of::<super::Scratch>()
    }

    /// Cuts `n` slots into `n_blocks` blocks of about equal work, unless it was done for this
    /// neighbour-list build already. The work of a row is estimated from its pairs and wall
    /// pairs and how many of them touched at the last evaluation (`in_contact`, and a wall
    /// history that is not zero): the blocks must take equally long, and a touching pair costs
    /// several times a pair that is only tested. A plan made before any contact was known (the
    /// first build of a run) is made again at the next evaluation.
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        build: u64,
        n_blocks: usize,
        offsets: &[usize],
        partners: &[u32],
        in_contact: &[bool],
        wall_pairs: &[[u32; 2]],
        wall_history: &[Vec3],
    ) {
        let same_build = self.made_for == Some((build, n_blocks));
        if same_build && !self.provisional {
            return;
        }
        self.made_for = Some((build, n_blocks));
        let n = offsets.len().saturating_sub(1);
        // The total work, from whole-list counts (they compile to vector instructions).
        let contacts = in_contact.iter().filter(|&&c| c).count();
        let wall_contacts = wall_history.iter().filter(|&&h| h != Vec3::ZERO).count();
        let total = ROW_COST * n
            + partners.len()
            + CONTACT_COST * contacts
            + wall_pairs.len()
            + CONTACT_COST * wall_contacts;
        self.provisional = !same_build && contacts + wall_contacts == 0;
        // Block t ends at the first row with at least t/n_blocks of the work before it. The rows
        // are walked only up to the last cut (the work after it is not needed).
        self.blocks.clear();
        let (mut start, mut before, mut w) = (0, 0, 0);
        let mut targets = (1..n_blocks).map(|t| total * t / n_blocks).peekable();
        for a in 0..n {
            while targets.next_if(|&target| before >= target).is_some() {
                self.blocks.push(start..a);
                start = a;
            }
            if targets.peek().is_none() {
                break;
            }
            let row = offsets[a]..offsets[a + 1];
            let touching = in_contact[row.clone()].iter().filter(|&&c| c).count();
            before += ROW_COST + row.len() + CONTACT_COST * touching;
            while w < wall_pairs.len() && wall_pairs[w][0] as usize == a {
                before += 1 + CONTACT_COST * (wall_history[w] != Vec3::ZERO) as usize;
                w += 1;
            }
        }
        while self.blocks.len() + 1 < n_blocks {
            self.blocks.push(start..n);
            start = n;
        }
        self.blocks.push(start..n);
        self.wall_ends.clear();
        self.wall_ends
            .extend(self.blocks.iter().map(|r| wall_pairs.partition_point(|&[i, _]| (i as usize) < r.end)));
        self.crossing.clear();
        self.crossing_start.clear();
        self.incoming_start.clear();
        self.incoming_start.resize(n + 1, 0);
        for rows in &self.blocks {
            self.crossing_start.push(self.crossing.len());
            // (The last block's pairs all lie inside it.)
            if rows.end == n {
                continue;
            }
            for a in rows.clone() {
                for k in offsets[a]..offsets[a + 1] {
                    let b = partners[k] as usize;
                    if b >= rows.end {
                        self.crossing.push((a as u32, k));
                        self.incoming_start[b + 1] += 1;
                    }
                }
            }
        }
        self.crossing_start.push(self.crossing.len());
        for b in 0..n {
            self.incoming_start[b + 1] += self.incoming_start[b];
        }
        self.incoming.clear();
        self.incoming.resize(self.crossing.len(), 0);
        // Each slot's start serves as its next free place, then the starts are shifted back
        // into place (each has become the next slot's start).
        for (c, &(_, k)) in self.crossing.iter().enumerate() {
            let at = &mut self.incoming_start[partners[k] as usize];
            self.incoming[*at as usize] = c as u32;
            *at += 1;
        }
        self.incoming_start.copy_within(0..n, 1);
        if let Some(first) = self.incoming_start.first_mut() {
            *first = 0;
        }
        self.loads.clear();
        self.loads.resize(self.crossing.len(), None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks share the estimated work, not the pairs: with every pair of the first half of the
    /// rows touching, the first block ends where the work (a row: ROW_COST; a pair tested: 1;
    /// touching: 1 + CONTACT_COST) is halved. A plan made with no contact known is made again
    /// once the flags are set, and then kept.
    #[test]
    fn blocks_share_the_work_of_touching_pairs() {
        let n = 100;
        // Two pairs per row (the last two rows have fewer partners).
        let mut offsets = vec![0];
        let mut partners = Vec::new();
        for a in 0..n {
            partners.extend(((a + 1)..n.min(a + 3)).map(|b| b as u32));
            offsets.push(partners.len());
        }
        let mut touching = vec![false; partners.len()];
        let mut plan = ForcePlan::default();
        plan.prepare(1, 2, &offsets, &partners, &touching, &[], &[]);
        // 100 rows and 197 pairs: work 5 + 2 = 7 per row but for the last two, 697 in all; the
        // first block ends at the first row with 348 before it.
        assert_eq!(plan.blocks, [0..50, 50..n], "by rows and pairs while no contact is known");
        touching[..offsets[n / 2]].fill(true);
        plan.prepare(1, 2, &offsets, &partners, &touching, &[], &[]);
        // Work of the first 50 rows: 50 × (5 + 2 × 5) = 750; of the last 50: 50 × 5 + 97 pairs
        // = 347. Half of 1097: 548, reached after 37 rows of 15.
        assert_eq!(plan.blocks, [0..37, 37..n]);
        touching.fill(false);
        plan.prepare(1, 2, &offsets, &partners, &touching, &[], &[]);
        assert_eq!(plan.blocks, [0..37, 37..n], "kept until the next build");
    }
}
