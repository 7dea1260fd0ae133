//! Triangle-mesh walls: their geometry, from a CAD file to the contacts of a sphere with them.
//!
//! - [`load`]: STL (ASCII and binary) and Wavefront OBJ input, with a load-time transform
//!   ([`MeshTransform`]) from file units and axes to the case's.
//! - [`Mesh`] (this module, built in [`build`]): the welded, validated, indexed mesh and its
//!   topology — per triangle its unit normal, edges and neighbours; per edge its vertices,
//!   triangles and [`EdgeKind`]; per vertex its triangles — derived once at load, in flat
//!   vectors with `u32` indices.
//! - [`contact`]: the closest point of a point on a triangle and the contacts of one sphere
//!   with the mesh, each particle–surface contact counted once.
//!
//! A triangle's normal follows its winding (right hand: corners a, b, c give
//! (b − a) × (c − a)); it points to the side the particles are expected on. Open meshes
//! (sheets, a hopper without a lid) are allowed, and a sphere may touch a sheet from either
//! side.
//!
//! ## Conventions
//! Side k of a triangle (k = 0, 1, 2) joins its corners k and (k + 1) mod 3. Edges are numbered
//! in the order they are first met walking the triangles in order, and sides 0, 1, 2 of each;
//! vertices in the order they are first met walking the triangles' corners. So the numbering
//! is a function of the file alone.

pub mod build;
pub mod contact;
pub mod grid;
pub mod keyframes;
pub mod load;
pub mod motion;
pub mod polygon;

pub use contact::{ClosestPoint, MeshContact, Primitive, Region, closest_point_on_triangle, sphere_contacts};
pub use grid::TriangleGrid;
pub use keyframes::{Interpolation, KeyFrameError, KeyFrames};
pub use motion::{MeshMotion, MotionWindow, Pose, SurfaceMotion};

use crate::math::Vec3;
use std::fmt;
use thiserror::Error;

/// Marks "no triangle" in the flat neighbour and edge arrays.
const NONE: u32 = u32::MAX;

/// How the surface bends at an edge, seen from the side its normals point to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EdgeKind {
    /// A ridge: the surface falls away on both sides (an outer edge of a box).
    Convex,
    /// A valley: the surface rises on both sides (the crease between a floor and a wall).
    Concave,
    /// The two triangles are coplanar within [`FLAT_COS`].
    Flat,
    /// Only one triangle has this edge: the rim of an open mesh.
    Boundary,
}

/// Two triangles meeting at an edge are coplanar when their normals' dot product exceeds this
/// (an angle below about 1.4e-5 rad): far above the rounding of a triangle's normal (about
/// ε·|x|/h for a triangle h high among coordinates of magnitude |x|, so 1.4e-5 only for
/// slivers 1e-11·|x| high), far below any bend a CAD model means.
pub const FLAT_COS: f64 = 1.0 - 1e-10;

/// One edge of the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Its two vertices, in the order its first (lowest-index) triangle runs along it; the
    /// second triangle, if any, runs the other way.
    pub vertices: [u32; 2],
    triangles: [u32; 2],
    /// How the surface bends here.
    pub kind: EdgeKind,
}

impl Edge {
    /// The triangles on this edge, ascending: two, or one on a boundary.
    pub fn triangles(&self) -> &[u32] {
        if self.triangles[1] == NONE { &self.triangles[..1] } else { &self.triangles }
    }
}

/// A welded, validated triangle mesh with its topology. Built by [`Mesh::load`],
/// [`Mesh::from_stl`], [`Mesh::from_obj`] or [`Mesh::from_indexed`]; immutable afterwards.
/// Coordinates are in metres, after the load-time transform.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    name: String,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Each triangle's corners, beside the indexed form: the contact tests read a triangle
    /// in one place.
    corner_table: Vec<[Vec3; 3]>,
    normals: Vec<Vec3>,
    triangle_edges: Vec<[u32; 3]>,
    neighbours: Vec<[u32; 3]>,
    edges: Vec<Edge>,
    /// The triangles of vertex v are `vertex_triangles[vertex_offsets[v]..vertex_offsets[v + 1]]`.
    vertex_offsets: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// Whether all of a vertex's edges are [`EdgeKind::Flat`]: a vertex inside a flat patch.
    flat_vertices: Vec<bool>,
    lo: Vec3,
    hi: Vec3,
    /// The largest coordinate magnitude, m: the scale of the coordinates' rounding, which the
    /// contact tests' tolerances follow.
    extent: f64,
    /// Degenerate triangles left out ([`MeshTransform::skip_degenerate`]).
    skipped: u32,
}

impl Mesh {
    /// How many degenerate triangles of the file were left out
    /// ([`MeshTransform::skip_degenerate`]).
    pub fn skipped_degenerate(&self) -> usize {
        self.skipped as usize
    }

    /// The name given at load (the file's path), for messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The welded vertices, m.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Each triangle's three vertex indices, in winding order.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Triangle `t`'s corners, m.
    pub fn corners(&self, t: u32) -> [Vec3; 3] {
        self.corner_table[t as usize]
    }

    /// Each triangle's unit normal (right-hand winding).
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// Each triangle's edge ids, side k joining corners k and (k + 1) mod 3.
    pub fn triangle_edges(&self) -> &[[u32; 3]] {
        &self.triangle_edges
    }

    /// The triangle across side `side` of triangle `t`, if any.
    pub fn neighbour(&self, t: u32, side: usize) -> Option<u32> {
        let n = self.neighbours[t as usize][side];
        (n != NONE).then_some(n)
    }

    /// All edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The triangles that have vertex `v` as a corner, ascending.
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        let (a, b) = (self.vertex_offsets[v as usize], self.vertex_offsets[v as usize + 1]);
        &self.vertex_triangles[a as usize..b as usize]
    }

    /// The axis-aligned bounding box (min, max) of the vertices, m.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// True if the mesh's bounding box does not meet the closed box [`lo`, `hi`], so that no
    /// part of the mesh is inside it (e.g. a mesh placed wholly outside the domain). False does
    /// not prove that a triangle is inside: a box can overlap the bounding box only.
    pub fn outside_box(&self, lo: Vec3, hi: Vec3) -> bool {
        self.hi.cmplt(lo).any() || self.lo.cmpgt(hi).any()
    }
}

/// A triangle named in a message: its index in the mesh and, for a text file, the line it came
/// from (the `facet` line of an ASCII STL, the `f` line of an OBJ).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Index of the triangle in the mesh (OBJ polygons count as their fan's triangles).
    pub triangle: u32,
    /// Line in the file, from 1.
    pub line: Option<u32>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "triangle {} (line {line})", self.triangle),
            None => write!(f, "triangle {}", self.triangle),
        }
    }
}

/// A mesh that cannot be read or used. Every message starts with the file's name.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The file could not be read.
    #[error("{file}: cannot read it: {reason}")]
    Read {
        /// The file.
        file: String,
        /// The operating system's reason.
        reason: String,
    },
    /// The file name ends neither in `.stl` nor in `.obj`.
    #[error("{file}: unknown mesh format (the name must end in .stl or .obj)")]
    Format {
        /// The file.
        file: String,
    },
    /// A line of an ASCII STL or OBJ file that cannot be parsed.
    #[error("{file}:{line}: {reason}")]
    Syntax {
        /// The file.
        file: String,
        /// Line, from 1.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A binary STL whose size does not match its triangle count, or a file too short to be
    /// one that does not start as an ASCII STL.
    #[error("{file}: not an STL file: {reason}")]
    BinarySize {
        /// The file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// The load-time transform cannot be applied.
    #[error("{file}: transform: {reason}")]
    Transform {
        /// The file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// More triangles than a mesh may have ([`build::MAX_TRIANGLES`]).
    #[error("{file}: {triangles} triangles, more than the {limit} a mesh may have")]
    TooLarge {
        /// The file.
        file: String,
        /// How many it has.
        triangles: usize,
        /// How many it may have.
        limit: usize,
    },
    /// The file holds no triangles.
    #[error("{file}: the mesh has no triangles")]
    Empty {
        /// The file.
        file: String,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("{file}: {at}: vertex index {index} is out of range ({count} vertices)")]
    BadIndex {
        /// The file.
        file: String,
        /// The triangle.
        at: Location,
        /// The index as written.
        index: i64,
        /// How many vertices there are.
        count: usize,
    },
    /// A corner that is not finite after the transform.
    #[error("{file}: {at}: corner {corner} is not finite after the transform ({position})")]
    NonFinite {
        /// The file.
        file: String,
        /// The triangle.
        at: Location,
        /// Which corner, 0..3.
        corner: usize,
        /// The transformed position, m.
        position: Vec3,
    },
    /// A triangle of (nearly) zero area: area < [`build::DEGENERATE_AREA`]·L², L its longest
    /// edge.
    #[error(
        "{file}: {at} is degenerate: its area {area:e} m² is below {:e} times its longest edge \
         squared ({longest:e} m, squared)",
        build::DEGENERATE_AREA
    )]
    Degenerate {
        /// The file.
        file: String,
        /// The triangle.
        at: Location,
        /// Its area, m².
        area: f64,
        /// Its longest edge, m.
        longest: f64,
    },
    /// Two triangles with the same three vertices (in any order).
    #[error("{file}: {at} repeats {first} (the same three vertices)")]
    Duplicate {
        /// The file.
        file: String,
        /// The later triangle.
        at: Location,
        /// The earlier one.
        first: Location,
    },
    /// Two triangles run along their shared edge in the same direction: one of them faces the
    /// other way.
    #[error(
        "{file}: {at} and {other} run along their shared edge from {from} to {to} in the same \
         direction, so their normals disagree (reverse the corner order of one of them)"
    )]
    Orientation {
        /// The file.
        file: String,
        /// The later triangle.
        at: Location,
        /// The earlier triangle on the edge.
        other: Location,
        /// The edge's first vertex, m.
        from: Vec3,
        /// The edge's second vertex, m.
        to: Vec3,
    },
    /// A third triangle on an edge (see [`build`] for why this is refused).
    #[error(
        "{file}: {at} is a third triangle on the edge from {from} to {to} (after {first} and \
         {second}); a mesh edge may join at most two triangles (load pieces that meet along an \
         edge as separate meshes)"
    )]
    NonManifold {
        /// The file.
        file: String,
        /// The third triangle.
        at: Location,
        /// The first triangle on the edge.
        first: Location,
        /// The second.
        second: Location,
        /// The edge's first vertex, m.
        from: Vec3,
        /// The edge's second vertex, m.
        to: Vec3,
    },
}

/// How a mesh file's coordinates become the case's: p′ = R·(s·p) + t, with the scale s first,
/// then the rotation R = R_z·R_y·R_x (about the fixed x axis first, then y, then z, each by the
/// right-hand rule), then the translation t. Optionally every triangle's winding is reversed,
/// turning its normal round.
///
/// Quarter turns (multiples of 90°) use exact sines and cosines, so that a quarter-turned
/// axis-aligned floor stays exactly flat.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshTransform {
    /// Metres per file unit (1e-3 for a file in millimetres); finite and positive.
    pub scale: f64,
    /// Rotations about the x, y and z axes, degrees, applied in that order.
    pub rotation_deg: [f64; 3],
    /// Translation, m, applied last.
    pub translation: Vec3,
    /// Reverse every triangle's winding (a file whose normals point away from the particles).
    pub flip_normals: bool,
    /// Leave out triangles of (nearly) zero area instead of refusing the file: such a
    /// triangle has no face a sphere can touch (CAD exporters leave slivers at T-junctions).
    /// Its neighbours' edges along it are then open edges.
    pub skip_degenerate: bool,
}

impl Default for MeshTransform {
    /// The identity: coordinates in metres, as they are.
    fn default() -> Self {
        MeshTransform {
            scale: 1.0,
            rotation_deg: [0.0; 3],
            translation: Vec3::ZERO,
            flip_normals: false,
            skip_degenerate: false,
        }
    }
}

/// A triangle-mesh wall of a simulation: its surface (as loaded, in its reference pose), its
/// material (an index into the simulation's wall materials), how it moves and when, and how its
/// surface slides.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshWall {
    pub mesh: Mesh,
    pub material: usize,
    pub motion: MeshMotion,
    /// When `motion` acts (the whole run unless told).
    pub window: MotionWindow,
    pub surface: SurfaceMotion,
    /// A factor of `surface` in time (MFIX's key frames): at τ s after the run's start the
    /// surface's velocity (or angular velocity) is `surface`'s × k(τ). `None`: × 1, exactly.
    pub surface_factor: Option<KeyFrames>,
}

impl MeshWall {
    /// An immovable mesh wall of `material`.
    pub fn fixed(mesh: Mesh, material: usize) -> MeshWall {
        MeshWall {
            mesh,
            material,
            motion: MeshMotion::Fixed,
            window: MotionWindow::ALWAYS,
            surface: SurfaceMotion::None,
            surface_factor: None,
        }
    }

    /// The surface's motion at τ s after the run's start: `surface`, scaled by
    /// `surface_factor` at τ if there is one (and `surface` itself, to the bit, if not).
    #[inline]
    pub fn surface_at(&self, tau: f64) -> SurfaceMotion {
        match &self.surface_factor {
            None => self.surface,
            Some(k) => self.surface.scaled(k.value(tau)),
        }
    }

    /// The largest speed a point of the mesh reaches under its rigid motion, m/s, and how it
    /// comes about: |v| of a translation; |ω| times the largest distance of a vertex from the
    /// axis for a rotation (the ramp only rises to ω); 2π·f·|A| at the centre of an
    /// oscillation. A surface velocity (`surface`) slides the surface in its own plane and
    /// moves no point of it towards a particle, so it is not counted.
    pub fn fastest_point_speed(&self) -> (f64, String) {
        match self.motion {
            MeshMotion::Fixed => (0.0, "fixed".into()),
            MeshMotion::Translate { velocity } => {
                (velocity.length(), format!("translating at {:.4e} m/s", velocity.length()))
            }
            MeshMotion::Rotate { origin, axis, omega, .. } => {
                let reach = self
                    .mesh
                    .vertices()
                    .iter()
                    .map(|&x| {
                        let d = x - origin;
                        (d - axis * d.dot(axis)).length()
                    })
                    .fold(0.0, f64::max);
                (
                    omega.abs() * reach,
                    format!("turning at {:.4e} rad/s with a vertex {reach:.4e} m from the axis", omega.abs()),
                )
            }
            MeshMotion::Oscillate { amplitude, frequency } => {
                let v = std::f64::consts::TAU * frequency * amplitude.length();
                (v, format!("oscillating by {:.4e} m at {frequency:e} Hz", amplitude.length()))
            }
        }
    }

    /// A box holding every place the mesh's surface takes in the first `span` s of its motion
    /// (from the pose as loaded), m: its bounds for a fixed mesh; moved by the displacement
    /// for a translation (within its window) and by ± the amplitude for an oscillation; for a
    /// rotation the boxes of its vertices' circles about the axis (a point of a triangle is a
    /// mean of its corners, and its circle's extent along an axis is at most theirs).
    pub fn swept_bounds(&self, span: f64) -> (Vec3, Vec3) {
        let (lo, hi) = self.mesh.bounds();
        match self.motion {
            MeshMotion::Fixed => (lo, hi),
            MeshMotion::Translate { velocity } => {
                let moved = velocity * self.window.clock(span);
                (lo + moved.min(Vec3::ZERO), hi + moved.max(Vec3::ZERO))
            }
            MeshMotion::Oscillate { amplitude, .. } => (lo - amplitude.abs(), hi + amplitude.abs()),
            MeshMotion::Rotate { origin, axis, .. } => {
                // A circle of radius ρ in the plane normal to `axis` spans ρ·√(1 − a_k²) about
                // its centre along axis k.
                let half = Vec3::ONE - axis * axis;
                let spread =
                    Vec3::new(half.x.max(0.0).sqrt(), half.y.max(0.0).sqrt(), half.z.max(0.0).sqrt());
                let mut out = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
                for &x in self.mesh.vertices() {
                    let d = x - origin;
                    let centre = origin + axis * d.dot(axis);
                    let rho = (x - centre).length();
                    out = (out.0.min(centre - spread * rho), out.1.max(centre + spread * rho));
                }
                out
            }
        }
    }

    /// True if the contact velocity of its surface may be non-zero.
    pub fn moves(&self) -> bool {
        self.motion.moves() || self.surface != SurfaceMotion::None
    }
}
