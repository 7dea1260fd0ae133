//! The tangential contact models, one file each: [`mfix`] (MFIX 21.3's total-displacement
//! spring) and [`incremental_mindlin`]. Each is a zero-sized type implementing
//! [`TangentialSubModel`]: its case-file name and description, its history size and its
//! spring, dashpot and Coulomb cap.
//!
//! [`tangential_models!`](crate::tangential_models) is the registry, as
//! [`normal_models!`](crate::normal_models) is for the normal models: the enum
//! [`TangentialModel`] and its tables, and the dispatch `with_tangential_submodel!`, are
//! generated from it. A new tangential model needs its file here, its line in the registry,
//! its name in `docs/case-file.md` (checked by a test) and its description in `docs/models.md`.

pub mod incremental_mindlin;
pub mod mfix;

pub use incremental_mindlin::IncrementalMindlin;
pub use mfix::MfixTotal;

use super::HistoryFrame;
use crate::math::Vec3;

/// A tangential contact model: the spring and dashpot, its history and the Coulomb cap.
pub trait TangentialSubModel: Copy + Default + Send + Sync + 'static {
    /// The setting this type implements.
    const MODEL: TangentialModel;
    /// Its name in a case file (`[contact] tangential`), e.g. "mfix".
    const NAME: &'static str;
    /// One line on what it is, for listings.
    const DESCRIPTION: &'static str;
    /// History values it stores: the tangential displacement or force, 3.
    const HISTORY: usize;

    /// The tangential force and the history to store, from the stored history `h` already in
    /// the tangent plane as `frame` asks, the normal `n`, the tangential velocity `v_t`, the
    /// stiffness `k` and damping `damp_t` in use, the Coulomb limit `limit`, `lammps` for
    /// LAMMPS's cap, `liggghts` for LIGGGHTS's (else MFIX's) and the step `dt`. Branch-free.
    #[allow(clippy::too_many_arguments)]
    fn force(
        h: Vec3,
        n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        liggghts: bool,
        frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3);
}

/// The registry of tangential models: each once, as its [`TangentialModel`] variant (with
/// the variant's doc) and its type in this module's files (see
/// [`normal_models!`](crate::normal_models)).
#[macro_export]
#[doc(hidden)]
macro_rules! tangential_models {
    ($then:ident! $args:tt) => {
        $crate::$then! { $args
            /// MFIX 21.3: the stored **total** tangential displacement s times the current stiffness
            /// (k_t for LSD, K_t·√δ for Hertz). Not conservative for Hertz at small impact angles.
            MfixTotal = mfix::MfixTotal,
            /// Incremental Mindlin: the stored quantity is the elastic tangential force, incremented by
            /// −k(δ)·v_t·Δt each step and capped by Coulomb. Identical to `MfixTotal` for LSD.
            IncrementalMindlin = incremental_mindlin::IncrementalMindlin,
        }
    };
}

crate::tangential_models!(submodel_registry! {
    /// How the tangential spring force is formed: one variant per model of the registry
    /// ([`tangential_models!`](crate::tangential_models)).
    TangentialModel: TangentialSubModel in tangential
});

/// Calls `$body` with the type `$t: TangentialSubModel` of a [`TangentialModel`] value, once
/// per model of the registry.
#[macro_export]
#[doc(hidden)]
macro_rules! with_tangential_submodel {
    ($tangential:expr, |$t:ident| $body:expr) => {
        $crate::tangential_models!(
            submodel_dispatch! { TangentialModel in tangential, $tangential, $t, $body }
        )
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each variant dispatches to the type that implements it; the names are distinct.
    #[test]
    fn the_registry_maps_each_model_to_its_own_type() {
        for (k, &m) in TangentialModel::ALL.iter().enumerate() {
            assert_eq!(crate::with_tangential_submodel!(m, |T| T::MODEL), m);
            assert_eq!(TangentialModel::CHOICES[k], (m.name(), m));
            assert_eq!(TangentialModel::NAMES[k], m.name());
            assert!(!m.description().is_empty());
            assert!(TangentialModel::NAMES[..k].iter().all(|n| *n != m.name()), "{} twice", m.name());
        }
    }
}
