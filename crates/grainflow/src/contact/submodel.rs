//! What the two categories of sub-model share. A contact law is one normal model
//! ([`normal`](super::normal): [`NormalSubModel`]) and one tangential model
//! ([`tangential`](super::tangential): [`TangentialSubModel`]), in the spirit of LAMMPS's `pair
//! granular`; each model is a zero-sized type in a file of its own that declares everything
//! the rest of the engine needs of it.
//!
//! The force stage is generic over one normal and one tangential type: it is monomorphised
//! once per pair of them, the law chosen once at set-up (`Simulation`'s dispatch,
//! `with_submodels!`), never a dynamic call per contact; every sub-model's functions are
//! `#[inline(always)]` and branch-free, so the batch loop over contacts (and its AVX2 and
//! AVX-512 copies) still compiles to vector code for each law. The two registries
//! ([`normal_models!`](crate::normal_models), [`tangential_models!`](crate::tangential_models))
//! list the models; `submodel_registry!` makes each category's enum and tables from its list,
//! `submodel_dispatch!` the dispatch from a value to its type.
//!
//! **Damping and rolling stay selectors** ([`NormalDamping`](super::NormalDamping),
//! [`LeverArm`](super::LeverArm), `law::parts`) rather than types. Their variants differ in a
//! scale (×m_eff, ×√m_eff, ×1) or a lever arm, formed for every variant and picked without a
//! branch, and the `parts` bits already compile out the costly ones (a square root for Tsuji,
//! the rolling torque) where a law cannot pick them. As type parameters they would multiply
//! the compiled copies of the force stage (×4 damping × 3 lever arms on top of 3 normal × 2
//! tangential models, each with its pair, wall and instruction-set copies) for no speed: the
//! picks cost nothing measurable (bench/results). How a damping depends on the overlap belongs
//! to the normal model (Hertz's δ^¼, JKR's √a), which is where it is.
//!
//! **History.** A contact stores one `Vec3` (in the neighbour list, for pairs and walls alike):
//! the tangential model's `HISTORY` = 3 values. A normal model may use what is left
//! ([`NormalSubModel::HISTORY`]; none needs any today). A cohesive model's contact outlives
//! the touch, so whether it has formed must be known at a negative overlap: for a pair that is
//! the list's contact flag, and for a wall pair (which has none) and after a checkpoint
//! restore (which derives the flag from the history) it is the history being non-zero. A
//! cohesive model therefore stores a zero history as −0.0 ([`mark_formed`]): the sign of a
//! zero changes no sum, product or comparison the law makes, and a history of +0.0 in every
//! component keeps meaning "no contact" everywhere.

pub use super::normal::NormalSubModel;
pub use super::tangential::TangentialSubModel;
use crate::math::Vec3;

/// A cohesive contact's stored history with its zero marked as −0.0 (see the module doc), so
/// that a formed contact is told from none by its history alone. Branch-free; other values
/// unchanged.
#[inline(always)]
pub fn mark_formed(h: Vec3) -> Vec3 {
    let zero = (h.x.to_bits() | h.y.to_bits() | h.z.to_bits()) == 0;
    Vec3::new(f64::from_bits(h.x.to_bits() | ((zero as u64) << 63)), h.y, h.z)
}

/// Whether a stored history says the contact had formed: any component other than +0.0.
#[inline(always)]
pub fn formed(h: Vec3) -> bool {
    (h.x.to_bits() | h.y.to_bits() | h.z.to_bits()) != 0
}

/// Calls `$body` with the types `$n: NormalSubModel` and `$t: TangentialSubModel` of the
/// law's settings (`$law`): the one place a runtime law becomes types. `$body` is expanded
/// once per combination of the registries' models, so each is monomorphised.
#[macro_export]
#[doc(hidden)]
macro_rules! with_submodels {
    ($law:expr, |$n:ident, $t:ident| $body:expr) => {
        $crate::with_normal_submodel!($law.normal, |$n| {
            $crate::with_tangential_submodel!($law.tangential, |$t| $body)
        })
    };
}

/// A category's enum and its tables, from its registry's list: `{ docs Enum: Trait in module }`
/// then `docs Variant = file::Type, …`. The variants, in the list's order; `ALL`, `NAMES`,
/// `CHOICES`; `name` and `description`, each the type's own (`Trait::NAME`,
/// `Trait::DESCRIPTION`).
#[macro_export]
#[doc(hidden)]
macro_rules! submodel_registry {
    ({ $(#[$em:meta])* $enum:ident : $tr:ident in $module:ident }
     $( $(#[$vm:meta])* $variant:ident = $file:ident :: $ty:ident ),* $(,)?) => {
        $(#[$em])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $enum {
            $( $(#[$vm])* $variant, )*
        }

        impl $enum {
            /// Every model, in the registry's order.
            pub const ALL: &'static [$enum] = &[$($enum::$variant),*];
            /// Every model's case-file name, in the registry's order.
            pub const NAMES: &'static [&'static str] =
                &[$(<$crate::contact::$module::$file::$ty as $crate::contact::$module::$tr>::NAME),*];
            /// (name, model) of every model: the table the case layer reads the key by.
            pub const CHOICES: &'static [(&'static str, $enum)] = &[$((
                <$crate::contact::$module::$file::$ty as $crate::contact::$module::$tr>::NAME,
                $enum::$variant,
            )),*];

            /// Its case-file name, e.g. "hertz".
            pub fn name(&self) -> &'static str {
                match self {
                    $( $enum::$variant =>
                        <$crate::contact::$module::$file::$ty as $crate::contact::$module::$tr>::NAME, )*
                }
            }

            /// One line on what it is.
            pub fn description(&self) -> &'static str {
                match self {
                    $( $enum::$variant =>
                        <$crate::contact::$module::$file::$ty as $crate::contact::$module::$tr>::DESCRIPTION, )*
                }
            }
        }
    };
}

/// The dispatch of a category's value to its type, from its registry's list: a `match` with
/// one arm per model, each binding `$n` to the model's type and expanding `$body`.
#[macro_export]
#[doc(hidden)]
macro_rules! submodel_dispatch {
    ({ $enum:ident in $module:ident, $value:expr, $n:ident, $body:expr }
     $( $(#[$vm:meta])* $variant:ident = $file:ident :: $ty:ident ),* $(,)?) => {
        match $value {
            $( $crate::contact::$enum::$variant => {
                type $n = $crate::contact::$module::$file::$ty;
                $body
            } )*
        }
    };
}
