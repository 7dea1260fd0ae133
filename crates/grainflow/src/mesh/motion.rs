//! How a mesh wall moves: its pose as a closed-form function of the time since the run's
//! start, the velocity of its surface at a point, and a surface velocity of a mesh that does
//! not itself move (a conveyor belt, a drum's shell turning in place).
//!
//! A mesh is stored in its reference pose (as loaded); at time τ its points are at
//! x = R(τ)·y + t(τ) ([`Pose`]). Contacts are found in the reference pose, with the particle's
//! centre taken there (y = R⁻¹(x − t)), so a moving mesh's triangle grid never needs binning
//! again.
//!
//! The pose is a closed form of τ (no integration, so no drift): a rotation by θ(τ) about a
//! fixed axis, a translation v·τ, or an oscillation A·sin(2πfτ). A motion may act only over a
//! window of time ([`MotionWindow`]: a gate that opens at a given time). A restart that changed
//! the motion continues from where the mesh was ([`Anchor`]). Rotations take the platform's `sin`
//! and `cos` (the same bits on one machine, so restarts are bit-identical).

use crate::math::Vec3;
use glam::DQuat;

/// Where a mesh is: x = `rotation`·y + `translation` for a point y of the mesh as loaded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub rotation: DQuat,
    pub translation: Vec3,
}

impl Pose {
    /// The pose of the mesh as loaded.
    pub const IDENTITY: Pose = Pose { rotation: DQuat::IDENTITY, translation: Vec3::ZERO };

    /// A point of the mesh as loaded, placed.
    #[inline]
    pub fn apply(&self, y: Vec3) -> Vec3 {
        self.rotation * y + self.translation
    }

    /// A direction of the mesh as loaded, placed.
    #[inline]
    pub fn turn(&self, d: Vec3) -> Vec3 {
        self.rotation * d
    }

    /// A point of space taken back to the mesh as loaded: the inverse of [`apply`](Self::apply).
    #[inline]
    pub fn unapply(&self, x: Vec3) -> Vec3 {
        self.rotation.conjugate() * (x - self.translation)
    }

    /// `self` after `first`: x = self(first(y)).
    fn after(&self, first: &Pose) -> Pose {
        Pose {
            rotation: (self.rotation * first.rotation).normalize(),
            translation: self.rotation * first.translation + self.translation,
        }
    }

    /// The identity, to the bit.
    pub fn is_identity(&self) -> bool {
        *self == Pose::IDENTITY
    }
}

/// How a mesh moves, from the run's start time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum MeshMotion {
    /// It does not move.
    #[default]
    Fixed,
    /// At a constant velocity, m/s.
    Translate { velocity: Vec3 },
    /// About the axis through `origin` along the unit vector `axis` (right-hand rule) at
    /// `omega` rad/s, reached linearly from rest over `ramp` s (0: from the start).
    Rotate { origin: Vec3, axis: Vec3, omega: f64, ramp: f64 },
    /// Sinusoidally: displacement `amplitude`·sin(2π·`frequency`·τ), m and Hz.
    Oscillate { amplitude: Vec3, frequency: f64 },
}

impl MeshMotion {
    /// The pose at τ s after the start, from the pose as loaded.
    pub fn pose(&self, tau: f64) -> Pose {
        match *self {
            MeshMotion::Fixed => Pose::IDENTITY,
            MeshMotion::Translate { velocity } => {
                Pose { rotation: DQuat::IDENTITY, translation: velocity * tau }
            }
            MeshMotion::Rotate { origin, axis, .. } => {
                let rotation = DQuat::from_axis_angle(axis, self.angle(tau));
                Pose { rotation, translation: origin - rotation * origin }
            }
            MeshMotion::Oscillate { amplitude, frequency } => Pose {
                rotation: DQuat::IDENTITY,
                translation: amplitude * (std::f64::consts::TAU * frequency * tau).sin(),
            },
        }
    }

    /// The angle turned by τ, rad (rotations only; 0 for the others).
    pub fn angle(&self, tau: f64) -> f64 {
        match *self {
            MeshMotion::Rotate { omega, ramp, .. } => {
                if ramp > 0.0 && tau < ramp {
                    0.5 * omega * tau * tau / ramp
                } else {
                    omega * (tau - 0.5 * ramp)
                }
            }
            _ => 0.0,
        }
    }

    /// (linear velocity, angular velocity, a point on the axis) at τ: a point x of the
    /// surface moves at v + ω × (x − o).
    pub fn rates(&self, tau: f64) -> (Vec3, Vec3, Vec3) {
        match *self {
            MeshMotion::Fixed => (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO),
            MeshMotion::Translate { velocity } => (velocity, Vec3::ZERO, Vec3::ZERO),
            MeshMotion::Rotate { origin, axis, omega, ramp } => {
                let w = if ramp > 0.0 && tau < ramp { omega * (tau / ramp) } else { omega };
                (Vec3::ZERO, axis * w, origin)
            }
            MeshMotion::Oscillate { amplitude, frequency } => {
                let k = std::f64::consts::TAU * frequency;
                (amplitude * (k * (k * tau).cos()), Vec3::ZERO, Vec3::ZERO)
            }
        }
    }

    /// True unless fixed.
    pub fn moves(&self) -> bool {
        *self != MeshMotion::Fixed
    }
}

/// When a mesh's motion acts, in s since the run's start (τ): the mesh stays in its pose as
/// loaded until `start`, then moves by its motion timed from `start` (the motion's own clock
/// reads τ − `start`), and from `stop` on stays where the motion took it. A gate that opens at
/// `start` by sliding away until `stop`; [`ALWAYS`](Self::ALWAYS) is the whole run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionWindow {
    pub start: f64,
    pub stop: f64,
}

impl MotionWindow {
    /// From the run's start, without end: the motion's clock is τ itself.
    pub const ALWAYS: MotionWindow = MotionWindow { start: 0.0, stop: f64::INFINITY };

    /// The motion's own clock at τ: 0 before `start`, τ − `start` within the window,
    /// `stop` − `start` after it (for [`ALWAYS`](Self::ALWAYS), τ to the bit).
    #[inline]
    pub fn clock(&self, tau: f64) -> f64 {
        (tau.min(self.stop) - self.start).max(0.0)
    }

    /// True while the motion acts: `start` ≤ τ < `stop`.
    #[inline]
    pub fn acts(&self, tau: f64) -> bool {
        self.start <= tau && tau < self.stop
    }

    /// A start no earlier than the run's and a stop after it (`stop` may be infinite).
    pub fn is_valid(&self) -> bool {
        self.start.is_finite() && self.start >= 0.0 && !self.stop.is_nan() && self.stop > self.start
    }
}

impl MeshMotion {
    /// The pose at τ of this motion acting over `window`.
    pub fn pose_within(&self, window: &MotionWindow, tau: f64) -> Pose {
        self.pose(window.clock(tau))
    }

    /// The rates at τ of this motion acting over `window`: its own inside, at rest outside.
    pub fn rates_within(&self, window: &MotionWindow, tau: f64) -> (Vec3, Vec3, Vec3) {
        if window.acts(tau) { self.rates(window.clock(tau)) } else { (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO) }
    }
}

/// A velocity of a mesh's surface in its own plane while the mesh stays where it is: at a
/// contact its component along the contact's normal is removed, so the surface slides without
/// pushing. (A drum's shell turning in place, as MFIX's drum tutorial moves its wall; a belt.)
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum SurfaceMotion {
    #[default]
    None,
    /// Every point at `velocity`, m/s (a conveyor belt).
    Translate { velocity: Vec3 },
    /// Turning about the axis through `origin` along the unit vector `axis` at `omega` rad/s.
    Rotate { origin: Vec3, axis: Vec3, omega: f64 },
}

impl SurfaceMotion {
    /// The same motion with its velocity (or angular velocity) multiplied by `k`.
    pub fn scaled(&self, k: f64) -> SurfaceMotion {
        match *self {
            SurfaceMotion::None => SurfaceMotion::None,
            SurfaceMotion::Translate { velocity } => SurfaceMotion::Translate { velocity: velocity * k },
            SurfaceMotion::Rotate { origin, axis, omega } => {
                SurfaceMotion::Rotate { origin, axis, omega: omega * k }
            }
        }
    }

    /// The surface's sliding velocity at the point `x` where the normal is `normal`.
    #[inline]
    pub fn velocity(&self, x: Vec3, normal: Vec3) -> Vec3 {
        let v = match *self {
            SurfaceMotion::None => return Vec3::ZERO,
            SurfaceMotion::Translate { velocity } => velocity,
            SurfaceMotion::Rotate { origin, axis, omega } => (axis * omega).cross(x - origin),
        };
        v - normal * v.dot(normal)
    }
}

/// The start of a mesh's motion: its pose is that of the motion (over its window) from τ to
/// `tau`, after `pose`. A run starts from (0, the pose as loaded), so its poses are the motion's closed
/// form; a restart whose case changed the motion anchors it at the checkpoint's pose and time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    pub tau: f64,
    pub pose: Pose,
}

impl Anchor {
    /// The anchor of a run's start.
    pub const START: Anchor = Anchor { tau: 0.0, pose: Pose::IDENTITY };

    /// The pose of a mesh with `motion` acting over `window` at τ.
    pub fn pose(&self, motion: &MeshMotion, window: &MotionWindow, tau: f64) -> Pose {
        if *self == Anchor::START {
            return motion.pose_within(window, tau);
        }
        // The motion's own clock now and at the anchor.
        let (now, then) = (window.clock(tau), window.clock(self.tau));
        let relative = match *motion {
            MeshMotion::Fixed => Pose::IDENTITY,
            MeshMotion::Translate { velocity } => {
                Pose { rotation: DQuat::IDENTITY, translation: velocity * (now - then) }
            }
            MeshMotion::Rotate { origin, axis, .. } => {
                let turned = motion.angle(now) - motion.angle(then);
                let rotation = DQuat::from_axis_angle(axis, turned);
                Pose { rotation, translation: origin - rotation * origin }
            }
            MeshMotion::Oscillate { .. } => Pose {
                rotation: DQuat::IDENTITY,
                translation: motion.pose(now).translation - motion.pose(then).translation,
            },
        };
        relative.after(&self.pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter turn about z through (1, 0, 0) takes (2, 0, 0) to (1, 1, 0); the pose's
    /// inverse takes it back (to rounding: 1e-15 of the coordinates).
    #[test]
    fn a_rotation_turns_about_its_axis_through_its_origin() {
        let m = MeshMotion::Rotate {
            origin: Vec3::X,
            axis: Vec3::Z,
            omega: std::f64::consts::FRAC_PI_2,
            ramp: 0.0,
        };
        let p = m.pose(1.0);
        assert!((p.apply(Vec3::new(2.0, 0.0, 0.0)) - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
        assert!((p.unapply(Vec3::new(1.0, 1.0, 0.0)) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-15);
        // The surface velocity ω × (x − o) at (2, 0, 0): (0, π/2, 0).
        let (v, w, o) = m.rates(1.0);
        let at = v + w.cross(Vec3::new(2.0, 0.0, 0.0) - o);
        assert!((at - Vec3::new(0.0, std::f64::consts::FRAC_PI_2, 0.0)).length() < 1e-15);
    }

    /// A ramp reaches ω at `ramp` with the angle ½ω·ramp, and the angle's derivative is the
    /// rate everywhere (central differences, to 1e-9 of ω).
    #[test]
    fn a_ramped_rotation_is_continuous_and_its_rate_is_the_angles_derivative() {
        let m = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Y, omega: 6.0, ramp: 0.5 };
        assert_eq!(m.angle(0.5), 0.5 * 6.0 * 0.5);
        for tau in [0.1, 0.3, 0.5, 0.7, 2.0] {
            let h = 1e-6;
            let rate = (m.angle(tau + h) - m.angle(tau - h)) / (2.0 * h);
            let w = m.rates(tau).1.y;
            assert!((rate - w).abs() < 1e-9 * 6.0 + if tau == 0.5 { 6.0 * h / 0.5 } else { 0.0 }, "τ {tau}");
        }
    }

    /// An oscillation's velocity is its displacement's derivative (central differences).
    #[test]
    fn an_oscillations_velocity_is_its_displacements_derivative() {
        let m = MeshMotion::Oscillate { amplitude: Vec3::new(0.0, 0.0, 2e-3), frequency: 10.0 };
        for tau in [0.0, 0.013, 0.05, 0.21] {
            let h = 1e-7;
            let d = (m.pose(tau + h).translation - m.pose(tau - h).translation) / (2.0 * h);
            assert!((d - m.rates(tau).0).length() < 1e-8, "τ {tau}");
        }
    }

    /// An anchored motion continues from the anchor's pose: at the anchor's time the pose is
    /// the anchor's, and from there it turns by the motion's angle since then.
    #[test]
    fn an_anchor_continues_from_its_pose() {
        let m = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega: 1.0, ramp: 0.0 };
        let start = Pose { rotation: DQuat::from_axis_angle(Vec3::Z, 0.3), translation: Vec3::ZERO };
        let a = Anchor { tau: 2.0, pose: start };
        let all = MotionWindow::ALWAYS;
        let p = a.pose(&m, &all, 2.0);
        assert!((p.apply(Vec3::X) - start.apply(Vec3::X)).length() < 1e-15);
        let later = a.pose(&m, &all, 2.5).apply(Vec3::X);
        assert!((later - Vec3::new(0.8f64.cos(), 0.8f64.sin(), 0.0)).length() < 1e-15);
        assert_eq!(Anchor::START.pose(&m, &all, 0.7), m.pose(0.7));
    }

    /// A gate sliding at v = (0.5, 0, 0) m/s over the window [0.2, 0.3) s: as loaded (and at
    /// rest) before 0.2 s, at v·(τ − 0.2) inside, and stopped at v·0.1 = 50 mm from 0.3 s on.
    /// The whole run's window is the motion itself, to the bit.
    #[test]
    fn a_windowed_motion_waits_for_its_start_and_stays_after_its_stop() {
        let v = Vec3::new(0.5, 0.0, 0.0);
        let m = MeshMotion::Translate { velocity: v };
        let w = MotionWindow { start: 0.2, stop: 0.3 };
        let at = |tau: f64| m.pose_within(&w, tau).translation;
        for tau in [0.0, 0.1, 0.2] {
            assert_eq!(at(tau), Vec3::ZERO, "τ {tau}");
        }
        assert_eq!(m.rates_within(&w, 0.1999).0, Vec3::ZERO);
        for tau in [0.21, 0.25, 0.2999] {
            assert!((at(tau) - v * (tau - 0.2)).length() < 1e-15, "τ {tau}");
            assert_eq!(m.rates_within(&w, tau).0, v, "τ {tau}");
        }
        for tau in [0.3, 0.5, 10.0] {
            assert!((at(tau) - Vec3::new(0.05, 0.0, 0.0)).length() < 1e-15, "τ {tau}");
            assert_eq!(m.rates_within(&w, tau).0, Vec3::ZERO, "τ {tau}");
        }
        // A rotation's ramp runs from the window's start: ½ω τ'²/ramp at τ' = τ − start.
        let r = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega: 2.0, ramp: 0.5 };
        let late = MotionWindow { start: 1.0, stop: f64::INFINITY };
        assert_eq!(r.pose_within(&late, 0.9), Pose::IDENTITY);
        let p = r.pose_within(&late, 1.25).apply(Vec3::X);
        let angle: f64 = 0.5 * 2.0 * 0.25 * 0.25 / 0.5;
        assert!((p - Vec3::new(angle.cos(), angle.sin(), 0.0)).length() < 1e-15);
        assert!((r.rates_within(&late, 1.25).1 - Vec3::new(0.0, 0.0, 1.0)).length() < 1e-15);
        // An anchor inside the window continues by the motion since then; one before the
        // window's start waits for it.
        let a = Anchor { tau: 0.25, pose: Pose { rotation: DQuat::IDENTITY, translation: Vec3::Y } };
        assert!((a.pose(&m, &w, 0.5).translation - (Vec3::Y + v * 0.05)).length() < 1e-15);
        let early = Anchor { tau: 0.1, pose: Pose::IDENTITY };
        assert_eq!(early.pose(&m, &w, 0.15), Pose::IDENTITY);
        for tau in [0.0, 0.3, 1.7, 123.456] {
            assert_eq!(MotionWindow::ALWAYS.clock(tau), tau);
            assert_eq!(m.pose_within(&MotionWindow::ALWAYS, tau), m.pose(tau));
            assert_eq!(m.rates_within(&MotionWindow::ALWAYS, tau), m.rates(tau));
        }
        assert!(w.is_valid() && MotionWindow::ALWAYS.is_valid());
        assert!(!MotionWindow { start: 0.3, stop: 0.3 }.is_valid());
        assert!(!MotionWindow { start: -0.1, stop: 1.0 }.is_valid());
    }

    /// A surface velocity slides in the tangent plane: its normal component is removed.
    #[test]
    fn a_surface_velocity_has_no_normal_component() {
        let s = SurfaceMotion::Translate { velocity: Vec3::new(1.0, 0.0, 1.0) };
        assert_eq!(s.velocity(Vec3::ZERO, Vec3::Z), Vec3::X);
        let d = SurfaceMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Y, omega: 2.0 };
        // On a drum of radius 0.5 about y, the point (0, 0, −0.5) with the normal +z (inwards)
        // moves at ω × r = (2ŷ) × (−0.5ẑ) = (−1, 0, 0).
        assert_eq!(d.velocity(Vec3::new(0.0, 0.0, -0.5), Vec3::Z), Vec3::new(-1.0, 0.0, 0.0));
    }
}
