//! Periodic boundaries: axes along which the domain box repeats.
//!
//! On a periodic axis a particle leaving through one face re-enters through the opposite one
//! (positions are wrapped after every step), and every pair interacts through its nearest
//! image. The box must be at least three neighbour cut-offs long on each periodic axis, so that
//! a particle never meets two images of the same neighbour.

use crate::math::Vec3;

/// The periodic axes of the domain box [lo, hi].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Periodic {
    /// Lower corner of the box, m.
    pub lo: Vec3,
    /// Upper corner of the box, m.
    pub hi: Vec3,
    /// Which of x, y, z are periodic.
    pub axes: [bool; 3],
}

impl Default for Periodic {
    fn default() -> Self {
        Periodic::NONE
    }
}

impl Periodic {
    /// No periodic axis.
    pub const NONE: Periodic = Periodic { lo: Vec3::ZERO, hi: Vec3::ZERO, axes: [false; 3] };

    /// True if at least one axis is periodic.
    pub fn any(&self) -> bool {
        self.axes.iter().any(|&a| a)
    }

    /// Checks that each periodic axis is at least three neighbour cut-offs
    /// (2·`max_radius` + `skin`) long, and that no wall faces a periodic axis.
    pub fn check(
        &self,
        max_radius: f64,
        skin: f64,
        walls: &[crate::wall::Wall],
    ) -> Result<(), crate::EngineError> {
        if !self.any() {
            return Ok(());
        }
        let cut = 2.0 * max_radius + skin;
        let l = self.lengths().to_array();
        for k in 0..3 {
            if self.axes[k] && (l[k] < 3.0 * cut || l[k].is_nan()) {
                return Err(crate::EngineError::InvalidValue {
                    what: format!("periodic length along {}", ["x", "y", "z"][k]),
                    value: format!("{}", l[k]),
                    valid: format!(
                        "a periodic box must be at least 3 neighbour cut-offs (3 × {cut:e} m) long"
                    ),
                });
            }
        }
        for w in walls {
            let nrm = w.normal.to_array();
            if (0..3).any(|k| self.axes[k] && nrm[k].abs() > 1e-12) {
                return Err(crate::EngineError::BadReference(format!(
                    "wall '{}' faces a periodic axis; periodic axes have no walls",
                    w.name
                )));
            }
        }
        Ok(())
    }

    /// Box lengths, m.
    pub fn lengths(&self) -> Vec3 {
        self.hi - self.lo
    }

    /// The nearest image of a separation vector on the periodic axes. Positions are kept
    /// inside the box, so separations lie within (−L, L) and one shift by L suffices.
    #[inline(always)]
    pub fn min_image(&self, d: Vec3) -> Vec3 {
        let mut d = d.to_array();
        let l = self.lengths().to_array();
        for k in 0..3 {
            if self.axes[k] {
                if d[k] > 0.5 * l[k] {
                    d[k] -= l[k];
                } else if d[k] < -0.5 * l[k] {
                    d[k] += l[k];
                }
            }
        }
        Vec3::from_array(d)
    }

    /// [`min_image`](Self::min_image) if any axis is periodic, else `d` itself.
    #[inline(always)]
    pub fn nearest(&self, d: Vec3) -> Vec3 {
        if self.any() { self.min_image(d) } else { d }
    }

    /// The nearest-image rule in the form the contact loops use ([`Images`]).
    pub(crate) fn images(&self) -> Images {
        let l = self.lengths().to_array();
        let pick = |k: usize, v: f64| if self.axes[k] { v } else { 0.0 };
        Images {
            any: self.any(),
            length: Vec3::new(pick(0, l[0]), pick(1, l[1]), pick(2, l[2])),
            inverse: Vec3::new(pick(0, 1.0 / l[0]), pick(1, 1.0 / l[1]), pick(2, 1.0 / l[2])),
        }
    }

    /// A position brought back into [lo, hi) on the periodic axes. A coordinate already inside
    /// is left exactly as it is (the common case, checked first: a step moves few particles
    /// across a face).
    #[inline(always)]
    pub fn wrap(&self, x: Vec3) -> Vec3 {
        let mut x = x.to_array();
        let (lo, hi) = (self.lo.to_array(), self.hi.to_array());
        for k in 0..3 {
            if self.axes[k] && !(x[k] >= lo[k] && x[k] < hi[k]) {
                x[k] = wrap_coordinate(x[k], lo[k], hi[k]);
            }
        }
        Vec3::from_array(x)
    }

    /// Brings every position of `xs` into the box: [`wrap`](Self::wrap) of each, to the bit.
    /// The coordinates are taken as one flat array, four particles at a time: most lie in the
    /// box, and a test of 12 coordinates at once finds them.
    pub fn wrap_all(&self, xs: &mut [Vec3]) {
        let flat = FlatWrap::of(self);
        let mut fours = bytemuck::cast_slice_mut::<Vec3, f64>(xs).chunks_exact_mut(12);
        for four in &mut fours {
            flat.wrap_four(four);
        }
        flat.wrap_each(fours.into_remainder());
    }
}

/// [`Periodic::wrap`] for four particles' coordinates at a time, as one flat array of 12. Most
/// positions lie in the box already: the 12 coordinates are tested against the box's bounds
/// (−∞ and ∞ on the axes that are not periodic) in a few vector instructions, and only when one
/// is out of bounds are the four particles wrapped one by one.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FlatWrap {
    periodic: Periodic,
    lo: [f64; 12],
    hi: [f64; 12],
}

impl FlatWrap {
    pub(crate) fn of(periodic: &Periodic) -> Self {
        let bound = |b: Vec3, open: f64| -> [f64; 12] {
            let b = b.to_array();
            std::array::from_fn(|j| if periodic.axes[j % 3] { b[j % 3] } else { open })
        };
        FlatWrap {
            periodic: *periodic,
            lo: bound(periodic.lo, f64::NEG_INFINITY),
            hi: bound(periodic.hi, f64::INFINITY),
        }
    }

    /// Wraps the four particles of `four` (12 coordinates).
    #[inline(always)]
    pub(crate) fn wrap_four(&self, four: &mut [f64]) {
        let four: &mut [f64; 12] = four.try_into().expect("four particles' coordinates");
        let outside = (0..12).fold(false, |out, j| out | !((four[j] >= self.lo[j]) & (four[j] < self.hi[j])));
        if outside {
            self.wrap_each(four);
        }
    }

    /// Wraps each particle of `coords` (whole triples) on its own.
    #[cold]
    pub(crate) fn wrap_each(&self, coords: &mut [f64]) {
        for x in coords.chunks_exact_mut(3) {
            let w = self.periodic.wrap(Vec3::new(x[0], x[1], x[2]));
            x.copy_from_slice(&w.to_array());
        }
    }
}

/// [`Periodic::nearest`] without a branch on the separation, for the contact loops, where
/// the branches of [`Periodic::min_image`] cost more than the arithmetic: the shift along each
/// axis is n·L with n = round(d/L), and n and L are zero on the axes that are not periodic.
///
/// For every separation shorter than half the box, and so for every pair that can touch or
/// come within a neighbour cut-off (the box is at least three cut-offs long), the result is
/// [`Periodic::min_image`]'s to the bit: d − 1·L, d − 0·L and d − (−1)·L round exactly as
/// d − L, d and d + L.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Images {
    any: bool,
    /// L on the periodic axes, 0 on the others.
    length: Vec3,
    /// 1/L on the periodic axes, 0 on the others.
    inverse: Vec3,
}

impl Images {
    /// Adding and subtracting 1.5·2^52 rounds a number of magnitude below 2^51 to an integer
    /// (to nearest, ties to even), with the instructions every x86-64 processor has.
    const ROUND: f64 = 6_755_399_441_055_744.0;

    /// `d` itself if no axis is periodic, else its nearest image.
    #[inline(always)]
    pub fn nearest(&self, d: Vec3) -> Vec3 {
        if !self.any {
            return d;
        }
        self.nearest_on_periodic_axes(d)
    }

    /// True if some axis is periodic.
    #[inline(always)]
    pub fn any(&self) -> bool {
        self.any
    }

    /// The nearest image without looking whether any axis is periodic: `d` itself, to the
    /// bit, if none is (the shifts are 0·0), at the cost of the arithmetic. For loops that
    /// make the choice once ([`any`](Self::any)).
    #[inline(always)]
    pub fn nearest_on_periodic_axes(&self, d: Vec3) -> Vec3 {
        let n = (d * self.inverse + Vec3::splat(Self::ROUND)) - Vec3::splat(Self::ROUND);
        d - n * self.length
    }
}

/// `x` brought into [lo, hi).
#[cold]
fn wrap_coordinate(x: f64, lo: f64, hi: f64) -> f64 {
    let w = lo + (x - lo).rem_euclid(hi - lo);
    // rem_euclid can round up to exactly the length for tiny negative offsets.
    if w >= hi { lo } else { w }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The branch-free nearest image is `min_image` to the bit wherever the two rules can
        /// matter (|d| below half the box on each periodic axis, so for any pair within a
        /// neighbour cut-off), and otherwise still lands within half a box (+ rounding).
        #[test]
        fn images_are_min_image_to_the_bit(
            lengths in prop::array::uniform3(0.05f64..50.0),
            axes in prop::array::uniform3(any::<bool>()),
            // Separations between two points of the box: (−L, L) on each axis.
            fractions in prop::array::uniform3(-0.999f64..0.999),
        ) {
            let lo = Vec3::new(-0.3, 1.7, 0.0);
            let per = Periodic { lo, hi: lo + Vec3::from_array(lengths), axes };
            let l = per.lengths().to_array();
            let d = Vec3::new(fractions[0] * l[0], fractions[1] * l[1], fractions[2] * l[2]);
            let (fast, reference) = (per.images().nearest(d).to_array(), per.nearest(d).to_array());
            for k in 0..3 {
                if (d.to_array()[k].abs() - 0.5 * l[k]).abs() > 1e-9 * l[k] {
                    prop_assert_eq!(fast[k].to_bits(), reference[k].to_bits(), "axis {}", k);
                }
                if axes[k] {
                    prop_assert!(fast[k].abs() <= 0.5 * l[k] * (1.0 + 1e-12));
                } else {
                    prop_assert_eq!(fast[k].to_bits(), d.to_array()[k].to_bits());
                }
            }
        }
    }

    proptest! {
        /// Wrapping many positions at once, four at a time as flat coordinates, is wrapping
        /// each on its own, to the bit: coordinates inside, outside on either side, far out,
        /// not finite, on periodic axes and on the others, in lists whose length is no
        /// multiple of four.
        #[test]
        fn wrapping_all_at_once_is_wrapping_each(
            axes in prop::array::uniform3(any::<bool>()),
            coords in prop::collection::vec(
                prop_oneof![
                    8 => -0.2f64..1.2,
                    1 => -50.0f64..50.0,
                    1 => prop::sample::select(vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 1.0]),
                ],
                0..40,
            ),
        ) {
            let per = Periodic { lo: Vec3::new(0.0, -0.1, 0.2), hi: Vec3::new(1.0, 0.9, 0.7), axes };
            let xs: Vec<Vec3> = coords.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
            let mut all = xs.clone();
            per.wrap_all(&mut all);
            // A NaN is compared as a NaN: Rust leaves the bits of a NaN made by an operation
            // (here ∞ wrapped) to the instruction that makes it.
            let bits = |v: Vec3| v.to_array().map(|c| if c.is_nan() { f64::NAN.to_bits() } else { c.to_bits() });
            for (x, got) in xs.iter().zip(&all) {
                prop_assert_eq!(bits(*got), bits(per.wrap(*x)), "{:?}", x);
            }
        }
    }

    #[test]
    fn wrapping_keeps_inside_coordinates_and_brings_the_others_into_the_box() {
        let per = Periodic {
            lo: Vec3::new(-0.3, 0.1, 0.0),
            hi: Vec3::new(0.7, 2.1, 1.0),
            axes: [true, true, false],
        };
        // Inside: untouched to the bit, even where lo + ((x − lo) mod L) would round.
        let inside = Vec3::new(0.1 + 1e-17, 0.3, 5.0);
        assert_eq!(per.wrap(inside), inside);
        // One length out on either side, several lengths out, and a hair below lo (whose
        // remainder rounds up to L): all land in [lo, hi); z is not periodic.
        for x in [Vec3::new(0.75, -0.4, -3.0), Vec3::new(-7.25, 9.9, 2.0), Vec3::new(-0.3 - 6e-17, 2.1, 0.5)]
        {
            let w = per.wrap(x).to_array();
            let l = per.lengths().to_array();
            let (lo, hi) = (per.lo.to_array(), per.hi.to_array());
            for k in 0..2 {
                assert!(w[k] >= lo[k] && w[k] < hi[k], "{x:?} wrapped to {w:?}");
                // The same point of the lattice: an integer number of lengths away (to
                // rounding of a few ulps of the coordinates involved).
                let n = (x.to_array()[k] - w[k]) / l[k];
                assert!((n - n.round()).abs() < 1e-12, "{x:?} → {w:?}: shift {n} lengths");
            }
            assert_eq!(w[2], x.z);
        }
    }
}
