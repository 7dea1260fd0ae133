//! The contact test of the force stage: which of a block's listed pairs and wall pairs touch.
//!
//! The test does not branch on its outcome, which no predictor could guess: every pair is
//! written into the next place of a list ([`Found`]), which only a touching pair keeps; the
//! loads are then computed for the listed pairs in batches. On beds too large for the
//! processor's caches it asks a few rows ahead for the data of the particles about to come
//! within the pairs' reach ([`prefetch_ahead`]).

use std::ops::Range;

use super::ForceInputs;
use crate::contact::pair::{contact_reach, kept_or_zero};
use crate::contact::submodel::{NormalSubModel, formed};
use crate::math::Vec3;

/// From this many particles on, the contact test asks for the data ahead of it
/// ([`prefetch_ahead`]): their arrays no longer fit the processor's last-level cache, and the
/// data entering the stretch the pairs reach comes from memory. With fewer, the requests only
/// cost time (measurements: bench/results/2026-12-01-design-history.md).
const PREFETCH_MIN_PARTICLES: usize = 200_000;

/// Rows ahead of the contact test whose farthest partner's data [`prefetch_ahead`] asks for.
const AHEAD: usize = 8;

/// Asks the processor to bring into its caches the data of the farthest partner of row
/// a + [`AHEAD`]: the particle about to enter the stretch of slots the rows' pairs reach (the
/// slots behind it are in cache already). `acc` are the rows' accumulators (from slot
/// `rows.start`). A hint only; nothing is read.
#[inline(always)]
fn prefetch_ahead(x: &ForceInputs, a: usize, rows: Range<usize>, acc: [&[Vec3]; 2]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T1, _mm_prefetch};
        let row = (a + AHEAD).min(rows.end - 1);
        let (start, end) = (x.offsets[row], x.offsets[row + 1]);
        if end == start {
            return;
        }
        fn at<T>(s: &[T], i: usize) -> Option<*const i8> {
            s.get(i).map(|v| (v as *const T).cast())
        }
        let b = x.partners[end - 1] as usize;
        let local = b.checked_sub(rows.start).unwrap_or(usize::MAX);
        let wanted = [
            at(x.position, b),
            at(x.velocity, b),
            at(x.omega, b),
            at(acc[0], local),
            at(acc[1], local),
            at(x.radius, b),
            at(x.mass, b),
        ];
        for p in wanted.into_iter().flatten() {
            // SAFETY: a prefetch reads nothing and cannot fault; the address is of a live
            // element besides.
            #[allow(unsafe_code)]
            unsafe {
                _mm_prefetch::<_MM_HINT_T1>(p)
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, a, rows, acc);
}

/// Touching pairs listed per stretch of rows.
pub(super) const FOUND: usize = 256;

/// A pair listed by the contact test: pair `k` of row `a`; `fresh` if it did not touch at
/// the last evaluation (its stored history is then not its own). Packed in 8 bytes (the test
/// writes one for every pair it tests): the row, and the pair index with the flag in its top
/// bit (a list holds at most [`MAX_PAIRS`](crate::neighbor::MAX_PAIRS), 2^31 − 1).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Found {
    pub(super) a: u32,
    k_fresh: u32,
}

impl Found {
    const FRESH: u32 = 1 << 31;

    #[inline(always)]
    fn new(a: usize, k: usize, fresh: bool) -> Self {
        debug_assert!(k <= crate::neighbor::MAX_PAIRS);
        Found { a: a as u32, k_fresh: k as u32 | (fresh as u32) << 31 }
    }

    /// The pair's index in the list.
    #[inline(always)]
    pub(super) fn k(&self) -> usize {
        (self.k_fresh & !Self::FRESH) as usize
    }

    #[inline(always)]
    pub(super) fn fresh(&self) -> bool {
        self.k_fresh & Self::FRESH != 0
    }
}

/// Where the contact test of a block's rows has got to: pair k of row a.
pub(super) struct Cursor {
    pub(super) a: usize,
    pub(super) k: usize,
}

/// Lists the pairs from `cursor` on that touch and the crossing pairs (whose loads were
/// computed before), until the rows end or `found` is full, and returns how many it listed;
/// sets the contact flags of the pairs tested (`in_contact` holds those of the rows' pairs).
/// The test does not branch on its outcome (which no predictor could guess): every pair is
/// written into the next place, which only a touching pair keeps. `acc` are the rows'
/// accumulators, for [`prefetch_ahead`].
#[inline(always)]
pub(super) fn find_contacts<N: NormalSubModel>(
    x: &ForceInputs,
    rows: Range<usize>,
    acc: [&[Vec3]; 2],
    cursor: &mut Cursor,
    in_contact: &mut [bool],
    found: &mut [Found; FOUND],
) -> usize {
    if x.images.any() {
        find_contacts_in::<N, true>(x, rows, acc, cursor, in_contact, found)
    } else {
        find_contacts_in::<N, false>(x, rows, acc, cursor, in_contact, found)
    }
}

/// The pull-off distance of the pair of slots a, b (for a normal model `N` that reaches
/// beyond the touch).
#[inline(always)]
pub(super) fn pair_reach<N: NormalSubModel>(x: &ForceInputs, a: usize, b: usize) -> f64 {
    let c = match x.coeffs.uniform_pair() {
        Some(c) => c,
        None => x.coeffs.pair(x.phase[a] as usize, x.phase[b] as usize),
    };
    let (ra, rb) = (x.radius[a], x.radius[b]);
    contact_reach::<N>(x.coeffs, c, ra * rb / (ra + rb))
}

/// [`find_contacts`] for domains with (`PERIODIC`) or without periodic axes: the choice made
/// once, not per pair; the touch condition the normal model `N`'s. The loop reads each row's partners and contact flags as slices, and the
/// particles below the rows' end through slices of that length, so that it makes no bounds
/// check per pair.
#[inline(never)]
fn find_contacts_in<N: NormalSubModel, const PERIODIC: bool>(
    x: &ForceInputs,
    rows: Range<usize>,
    acc: [&[Vec3]; 2],
    cursor: &mut Cursor,
    in_contact: &mut [bool],
    found: &mut [Found; FOUND],
) -> usize {
    let (r0, r1) = (rows.start, rows.end);
    let k0 = x.offsets[r0];
    // Slices of exactly the slots below r1: a partner below r1 (not crossing) is then read
    // without a bounds check.
    let (position, radius) = (&x.position[..r1], &x.radius[..r1]);
    let images = x.images;
    let mut n = 0;
    let Cursor { mut a, mut k } = *cursor;
    let far = x.position.len() >= PREFETCH_MIN_PARTICLES;
    while a < r1 {
        let (xa, ra) = (position[a], radius[a]);
        let end = x.offsets[a + 1];
        if far {
            prefetch_ahead(x, a, r0..r1, acc);
        }
        // The row's pairs from k on, with their contact flags.
        let flags = &mut in_contact[k - k0..end - k0];
        for (j, (&b, flag)) in x.partners[k..end].iter().zip(flags).enumerate() {
            if n >= FOUND {
                *cursor = Cursor { a, k: k + j };
                return n;
            }
            let b = b as usize;
            let (keep, fresh) = if b < r1 {
                let d = position[b] - xa;
                let d = if PERIODIC { images.nearest_on_periodic_axes(d) } else { d };
                let reach = if N::REACHES { pair_reach::<N>(x, a, b) } else { 0.0 };
                let touching = N::touching(d.length_squared(), ra, radius[b], reach, *flag);
                let fresh = !*flag;
                *flag = touching;
                (touching, fresh)
            } else {
                (true, false)
            };
            found[n] = Found::new(a, k + j, fresh);
            n += keep as usize;
        }
        k = end;
        a += 1;
    }
    *cursor = Cursor { a, k };
    n
}

/// Lists, as indices into `wall_pairs`, the wall pairs from `at` on that touch, until the list
/// ends or `found` is full; clears the histories of the others and returns how many it listed.
/// Like [`find_contacts`], without a branch on the test's outcome; the touch condition the
/// normal model `N`'s (a wall pair has no contact flag: a formed contact of a model that
/// reaches beyond the touch is known by its history, `submodel::formed`).
#[inline(never)]
pub(super) fn find_wall_contacts<N: NormalSubModel>(
    x: &ForceInputs,
    wall_pairs: &[[u32; 2]],
    at: &mut usize,
    hist: &mut [Vec3],
    found: &mut [usize; FOUND],
) -> usize {
    let mut n = 0;
    while *at < wall_pairs.len() && n < FOUND {
        let [i, w] = wall_pairs[*at];
        let (i, wall) = (i as usize, &x.walls[w as usize]);
        let overlap = x.radius[i] - (x.position[i] - wall.point).dot(wall.normal);
        let reach = if N::REACHES {
            contact_reach::<N>(x.coeffs, x.coeffs.wall(x.phase[i] as usize, wall.material), x.radius[i])
        } else {
            0.0
        };
        let touching = N::wall_touching(overlap, reach, N::REACHES && formed(hist[*at]));
        hist[*at] = kept_or_zero(hist[*at], touching);
        found[n] = *at;
        n += touching as usize;
        *at += 1;
    }
    n
}
