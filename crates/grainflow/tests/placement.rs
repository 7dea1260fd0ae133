//! Placement never overlaps: property tests of [`place`] over regions (a box, a box spanning
//! periodic axes, a cylinder along an axis or oblique, the inside of a closed mesh: a box or a
//! prism of triangles, turned), size distributions (constant, uniform, truncated normal and
//! log-normal, a discrete table by number or by mass; mixtures of up to three parts), 0–3
//! periodic axes of the domain box, particles already present (anywhere, also across the
//! periodic faces and outside the box), plane walls and mesh triangles, and requested solid
//! fractions from dilute (random sequential addition) to beyond what fits (the lattice).
//!
//! For every sphere placed the test checks, against its own brute-force geometry:
//!
//! - no other placed sphere closer than the sum of the radii, through the nearest periodic
//!   image (every periodic length is at least 4 largest diameters, so only the nearest image
//!   of a sphere can reach another);
//! - no present particle or periodic image of one closer than the sum of the radii;
//! - the sphere inside the region ([`Region::holds_sphere`]); on a periodic axis that the
//!   region covers, the region repeats, and the sphere may cross the periodic face, so along
//!   that axis only (for a box, or a cylinder along it) the region is extended;
//! - every wall at least its radius away, on the particle side, and every triangle;
//! - invalid diameters (NaN, zero, negative) get `None`;
//! - when the spheres asked for have more volume than the region, some are `None` (the
//!   count of those that fitted is reported, never an overlap), and, where nothing is in the
//!   way, a dilute request is placed in full and a dense one fills a good part of the region.
//!
//! ## Tolerance
//! Distances here are recomputed from coordinates no larger than S (the largest magnitude of
//! the domain's, the region's and the largest diameter), by subtraction, the nearest-image
//! shift and a square root: their rounding is a few ulps of S, below 1e-15·S. A clearance is
//! accepted down to [`TOL`]·S short, several hundred times that rounding and, for the largest
//! S here (about 0.3 m), 3e-13 m: nine orders of magnitude below the smallest radius (5e-5 m),
//! so that any overlap the engine would feel fails the test.

use grainflow::insertion::InsertRng;
use grainflow::insertion::place::{Obstacles, place};
use grainflow::insertion::psd::{Basis, Mixture, MixturePart, SizeDistribution};
use grainflow::insertion::region::Region;
use grainflow::mesh::{Mesh, MeshTransform, closest_point_on_triangle};
use grainflow::{Periodic, Vec3, Wall};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

/// Accepted shortfall of a clearance, relative to the coordinates' magnitude (see the module
/// doc).
const TOL: f64 = 1e-12;

/// The most spheres asked for in one case: enough for several lattice layers in every
/// direction, few enough for the brute-force pair check.
const MAX_COUNT: usize = 700;

/// The most spheres asked for in a roomy case: never reached below a solid fraction of 0.2.
const MAX_ROOMY_COUNT: usize = 6000;

/// What a case is made of; the continuous geometry comes from `seed`.
#[derive(Debug, Clone, Copy)]
struct Spec {
    /// 0 box, 1 box covering the periodic axes, 2 cylinder along an axis, 3 oblique
    /// cylinder, 4 mesh box, 5 mesh prism.
    region: u8,
    /// Distribution of each part (see [`distribution`]).
    sizes: [u8; 3],
    /// Parts in the mixture, 1–3.
    parts: usize,
    /// Mixture fractions by mass instead of number.
    by_mass: bool,
    /// Bit k: axis k periodic.
    periodic: u8,
    /// Particles already present.
    present: usize,
    /// Plane walls through the region (on non-periodic axes only).
    walls: usize,
    /// Triangles through the region: a tilted square and a small closed box.
    triangles: bool,
    /// Requested solid fraction of the region.
    phi: f64,
    /// Invalid diameters mixed in.
    invalid: usize,
    /// A larger domain (8–11 largest diameters a side) filled more by the region.
    roomy: bool,
    seed: u64,
}

/// A built case.
struct Case {
    region: Region,
    diameters: Vec<f64>,
    positions: Vec<Vec3>,
    radii: Vec<f64>,
    walls: Vec<Wall>,
    triangles: Vec<[Vec3; 3]>,
    periodic: Periodic,
    /// Axes along which the region covers the periodic box: the region repeats.
    covers: [bool; 3],
    /// The magnitude of the coordinates, m.
    scale: f64,
}

fn distribution(kind: u8, d: f64, rng: &mut InsertRng) -> SizeDistribution {
    let mut u = |a: f64, b: f64| a + (b - a) * rng.random::<f64>();
    match kind {
        0 => SizeDistribution::Constant { diameter: d * u(0.5, 1.0) },
        1 => SizeDistribution::Uniform { min: d * u(0.3, 0.9), max: d },
        2 => {
            SizeDistribution::Normal { mean: d * u(0.6, 0.9), sigma: d * u(0.05, 0.3), min: d * 0.4, max: d }
        }
        3 => SizeDistribution::LogNormal {
            mean: d * u(0.4, 0.8),
            sigma: d * u(0.05, 0.4),
            min: d * 0.25,
            max: d,
        },
        _ => {
            // Bidisperse or tridisperse, size ratios up to 4.
            let k = 2 + (kind as usize % 2);
            let diameters: Vec<f64> = (0..k).map(|i| if i == 0 { d } else { d * u(0.25, 0.95) }).collect();
            let w: Vec<f64> = (0..k).map(|_| u(0.1, 1.0)).collect();
            let total: f64 = w.iter().sum();
            let basis = if u(0.0, 1.0) < 0.5 { Basis::Number } else { Basis::Mass };
            SizeDistribution::Table { diameters, fractions: w.iter().map(|x| x / total).collect(), basis }
        }
    }
}

/// A closed, outward-oriented box of 12 triangles.
fn box_mesh(name: &str, lo: Vec3, hi: Vec3, transform: &MeshTransform) -> Mesh {
    let v: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    // Each face as two triangles, counter-clockwise seen from outside.
    let faces: [[u32; 4]; 6] =
        [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let t: Vec<[u32; 3]> = faces.iter().flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]).collect();
    Mesh::from_indexed(name, &v, &t, transform).expect("a valid box mesh")
}

/// A closed prism over a regular n-gon of circumradius `radius` about the z axis, from z = 0
/// to `height`, outward-oriented.
fn prism_mesh(n: u32, radius: f64, height: f64, transform: &MeshTransform) -> Mesh {
    let mut v = Vec::new();
    for z in [0.0, height] {
        for i in 0..n {
            let a = 2.0 * PI * i as f64 / n as f64;
            v.push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    v.push(Vec3::ZERO);
    v.push(Vec3::new(0.0, 0.0, height));
    let (bottom, top) = (2 * n, 2 * n + 1);
    let mut t = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        t.push([i, j, n + j]);
        t.push([i, n + j, n + i]);
        t.push([bottom, j, i]);
        t.push([top, n + i, n + j]);
    }
    Mesh::from_indexed("prism", &v, &t, transform).expect("a valid prism mesh")
}

fn build(spec: &Spec) -> Case {
    let mut rng = InsertRng::seed_from_u64(spec.seed);
    let mut u = |a: f64, b: f64| a + (b - a) * rng.random::<f64>();
    // The largest diameter, 0.1–10 mm.
    let d = 10f64.powf(u(-4.0, -2.0));
    let plo = Vec3::new(u(-30.0, 30.0), u(-30.0, 30.0), u(-30.0, 30.0)) * d;
    let (l0, l1, fill) = if spec.roomy { (8.0, 11.0, 0.8) } else { (4.0, 10.0, 0.4) };
    let plen = Vec3::new(u(l0, l1), u(l0, l1), u(l0, l1)) * d;
    let phi_ = plo + plen;
    let axes = [0, 1, 2].map(|k| spec.periodic & (1 << k) != 0);
    let periodic = Periodic { lo: plo, hi: phi_, axes };
    let (lo, hi) = (plo.to_array(), phi_.to_array());
    let mut covers = [false; 3];

    let region = match spec.region {
        0 | 1 => {
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            for k in 0..3 {
                if spec.region == 1 && axes[k] {
                    // Exactly the periodic box, or beyond it.
                    let out = if u(0.0, 1.0) < 0.5 { 0.0 } else { u(0.0, 2.0) * d };
                    a[k] = lo[k] - out;
                    b[k] = hi[k] + out;
                    covers[k] = true;
                } else {
                    let len = (hi[k] - lo[k]) * u(fill, 1.0);
                    a[k] = lo[k] + (hi[k] - lo[k] - len) * u(0.0, 1.0);
                    b[k] = a[k] + len;
                }
            }
            Region::Box { lo: Vec3::from_array(a), hi: Vec3::from_array(b) }
        }
        2 => {
            let k = (u(0.0, 3.0) as usize).min(2);
            let axis = Vec3::from_array(std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 }));
            let c = plo + 0.5 * plen;
            let radius =
                0.5 * (0..3).filter(|&i| i != k).map(|i| plen[i]).fold(f64::INFINITY, f64::min) * u(0.6, 1.0);
            let (base, length) = if axes[k] && u(0.0, 1.0) < 0.7 {
                covers[k] = true;
                let out = if u(0.0, 1.0) < 0.5 { 0.0 } else { u(0.0, 2.0) * d };
                (c - (0.5 * plen[k] + out) * axis, plen[k] + 2.0 * out)
            } else {
                let len = plen[k] * u(fill, 1.0);
                (c - 0.5 * len * axis, len)
            };
            // Off the middle, possibly across a face of the periodic box.
            let shift = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)) * d * (Vec3::ONE - axis);
            Region::cylinder(base + shift, axis, length, radius)
        }
        3 => {
            let axis = loop {
                let a = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                if a.length() > 0.3 {
                    break a;
                }
            };
            let c = plo + Vec3::new(u(0.3, 0.7), u(0.3, 0.7), u(0.3, 0.7)) * plen;
            let size = plen.min_element();
            let length = size * u(0.5, 1.0);
            Region::cylinder(c - 0.5 * length * axis.normalize(), axis, length, 0.5 * size * u(0.4, 0.8))
        }
        _ => {
            let transform = MeshTransform {
                scale: 1.0,
                rotation_deg: [u(0.0, 360.0), u(0.0, 360.0), u(0.0, 360.0)],
                translation: plo + 0.5 * plen,
                flip_normals: false,
                skip_degenerate: false,
            };
            let size = plen.min_element();
            let mesh = if spec.region == 4 {
                let f = fill.min(0.6);
                let half = 0.5 * size * Vec3::new(u(f, 0.7), u(f, 0.7), u(f, 0.7));
                box_mesh("box", -half, half, &transform)
            } else {
                let n = 5 + (u(0.0, 12.0) as u32);
                let h = size * u(0.5, 0.7);
                let transform =
                    MeshTransform { translation: transform.translation - 0.5 * h * Vec3::Z, ..transform };
                prism_mesh(n, 0.5 * size * u(0.5, 0.7), h, &transform)
            };
            Region::mesh(&mesh)
        }
    };
    region.check().expect("a valid region");

    let parts: Vec<MixturePart> = (0..spec.parts)
        .map(|i| {
            let scale = if i == 0 { d } else { d * u(0.4, 1.0) };
            let mut r = InsertRng::seed_from_u64(spec.seed ^ ((i as u64 + 1) * 0x9E37_79B9));
            MixturePart {
                phase: i as u32,
                density: 2500.0,
                fraction: 1.0 / spec.parts as f64,
                sizes: distribution(spec.sizes[i], scale, &mut r),
            }
        })
        .collect();
    let mixture = Mixture { parts, basis: if spec.by_mass { Basis::Mass } else { Basis::Number } };
    mixture.check().expect("a valid mixture");
    let cap = if spec.roomy { MAX_ROOMY_COUNT } else { MAX_COUNT };
    let volume = period_volume(&region, covers, &periodic);
    let count = ((spec.phi * volume / mixture.mean_volume()).round() as usize).clamp(1, cap);
    let mut diameters: Vec<f64> = (0..count).map(|_| mixture.sample(&mut rng).1).collect();
    for i in 0..spec.invalid {
        let at = rng.random_range(0..=diameters.len());
        diameters.insert(at, [f64::NAN, 0.0, -d, f64::INFINITY][i % 4]);
    }

    let mut u = |a: f64, b: f64| a + (b - a) * rng.random::<f64>();
    let (rlo, rhi) = region.bounds();
    // Present particles: over the region's bounds and a diameter beyond, so that some sit
    // across a periodic face or outside the periodic box; any size up to twice the largest
    // new one; they may overlap each other.
    let (positions, radii): (Vec<Vec3>, Vec<f64>) = (0..spec.present)
        .map(|_| {
            let t = Vec3::new(u(0.0, 1.0), u(0.0, 1.0), u(0.0, 1.0));
            let p = rlo - Vec3::splat(d) + t * (rhi - rlo + Vec3::splat(2.0 * d));
            // Some given as another periodic image.
            let shift = Vec3::from_array(std::array::from_fn(|k| {
                if axes[k] && u(0.0, 1.0) < 0.3 {
                    plen[k] * if u(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 }
                } else {
                    0.0
                }
            }));
            (p + shift, d * u(0.1, 1.0))
        })
        .collect();
    let free: Vec<usize> = (0..3).filter(|&k| !axes[k]).collect();
    let mut walls = Vec::new();
    if !free.is_empty() {
        for w in 0..spec.walls {
            // A normal in the non-periodic axes only (as a periodic box requires), through a
            // point of the region's inner half.
            let mut n = Vec3::ZERO;
            while n.length() < 0.3 {
                n = Vec3::from_array(std::array::from_fn(|k| if axes[k] { 0.0 } else { u(-1.0, 1.0) }));
            }
            let t = Vec3::new(u(0.25, 0.75), u(0.25, 0.75), u(0.25, 0.75));
            walls.push(Wall::plane(format!("w{w}"), rlo + t * (rhi - rlo), n, 0));
        }
    }
    let mut triangles = Vec::new();
    if spec.triangles {
        // A tilted square through the region.
        let c = rlo + Vec3::new(u(0.3, 0.7), u(0.3, 0.7), u(0.3, 0.7)) * (rhi - rlo);
        let e = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::X);
        let f = e.any_orthonormal_vector();
        let g = e.cross(f);
        let s = (rhi - rlo).max_element();
        let q = [c + s * (f + g), c + s * (f - g), c + s * (-f - g), c + s * (g - f)];
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
        // A small closed box inside.
        let c = rlo + Vec3::new(u(0.2, 0.8), u(0.2, 0.8), u(0.2, 0.8)) * (rhi - rlo);
        let half = Vec3::splat(d * u(0.3, 1.5));
        let body = box_mesh("body", c - half, c + half, &MeshTransform::default());
        triangles.extend((0..body.triangle_count() as u32).map(|t| body.corners(t)));
    }

    let scale = [plo, phi_, rlo, rhi].iter().map(|v| v.abs().max_element()).fold(d, f64::max);
    Case { region, diameters, positions, radii, walls, triangles, periodic, covers, scale }
}

/// The separation a − b through the nearest image on the periodic axes.
fn sep(a: Vec3, b: Vec3, p: &Periodic) -> Vec3 {
    let l = (p.hi - p.lo).to_array();
    let mut d = (a - b).to_array();
    for k in 0..3 {
        if p.axes[k] {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
    }
    Vec3::from_array(d)
}

/// The region as it must hold the sphere at `x`: extended along the axes it covers (where it
/// repeats).
fn holding(case: &Case, x: Vec3) -> Region {
    let l = (case.periodic.hi - case.periodic.lo).to_array();
    match &case.region {
        Region::Box { lo, hi } => {
            let (mut a, mut b) = (lo.to_array(), hi.to_array());
            for k in 0..3 {
                if case.covers[k] {
                    a[k] = a[k].min(x[k] - l[k]);
                    b[k] = b[k].max(x[k] + l[k]);
                }
            }
            Region::Box { lo: Vec3::from_array(a), hi: Vec3::from_array(b) }
        }
        Region::Cylinder { base, axis, length, radius } if case.covers.iter().any(|&c| c) => {
            let a = axis.normalize();
            let t = (x - *base).dot(a);
            let k = (0..3).find(|&k| case.covers[k]).expect("a covered axis");
            let lo = t.min(0.0) - l[k];
            let hi = t.max(*length) + l[k];
            Region::Cylinder { base: *base + lo * a, axis: a, length: hi - lo, radius: *radius }
        }
        r => r.clone(),
    }
}

/// Checks every placed sphere; returns how many were placed.
fn check(case: &Case, placed: &[Option<Vec3>]) -> Result<usize, TestCaseError> {
    prop_assert_eq!(placed.len(), case.diameters.len());
    let tol = TOL * case.scale;
    let p = &case.periodic;
    let mut done: Vec<(Vec3, f64)> = Vec::new();
    for (i, (&d, x)) in case.diameters.iter().zip(placed).enumerate() {
        let valid = d.is_finite() && d > 0.0;
        let Some(x) = *x else { continue };
        prop_assert!(valid, "sphere {} of diameter {} placed at {}", i, d, x);
        prop_assert!(x.is_finite(), "sphere {} at {}", i, x);
        let r = 0.5 * d;
        let region = holding(case, x);
        prop_assert!(
            region.holds_sphere(x, r - tol),
            "sphere {} (r {:e}) at {} sticks out of the region by {:e}",
            i,
            r,
            x,
            r - region.clearance(x, r)
        );
        for w in &case.walls {
            let dist = w.distance(x);
            prop_assert!(
                dist >= r - tol,
                "sphere {} (r {:e}) at {} is {:e} from wall {:?}",
                i,
                r,
                x,
                dist,
                w
            );
        }
        for (t, &tri) in case.triangles.iter().enumerate() {
            let dist = (x - closest_point_on_triangle(x, tri).point).length();
            prop_assert!(
                dist >= r - tol,
                "sphere {} (r {:e}) at {} is {:e} from triangle {}",
                i,
                r,
                x,
                dist,
                t
            );
        }
        for (j, (&q, &rq)) in case.positions.iter().zip(&case.radii).enumerate() {
            let dist = sep(x, q, p).length();
            prop_assert!(
                dist >= r + rq - tol,
                "sphere {} (r {:e}) at {} overlaps present particle {} (r {:e}) at {} by {:e}",
                i,
                r,
                x,
                j,
                rq,
                q,
                r + rq - dist
            );
        }
        for (j, &(q, rq)) in done.iter().enumerate() {
            let dist = sep(x, q, p).length();
            prop_assert!(
                dist >= r + rq - tol,
                "spheres {} (r {:e}) at {} and the {}th placed (r {:e}) at {} overlap by {:e}",
                i,
                r,
                x,
                j,
                rq,
                q,
                r + rq - dist
            );
        }
        done.push((x, r));
    }
    for (&d, x) in case.diameters.iter().zip(placed) {
        prop_assert!(d.is_finite() && d > 0.0 || x.is_none(), "invalid diameter {} placed", d);
    }
    Ok(done.len())
}

fn place_case(case: &Case, seed: u64) -> Vec<Option<Vec3>> {
    let obstacles = Obstacles {
        positions: &case.positions,
        radii: &case.radii,
        walls: &case.walls,
        cylinders: &[],
        triangles: &case.triangles,
        solids: &[],
        periodic: case.periodic.any().then_some(case.periodic),
    };
    place(&case.region, &case.diameters, &obstacles, &mut InsertRng::seed_from_u64(seed))
}

/// The region's volume of one period: along the axes it covers, the periodic length.
fn period_volume(region: &Region, covers: [bool; 3], periodic: &Periodic) -> f64 {
    let l = (periodic.hi - periodic.lo).to_array();
    match region {
        Region::Box { lo, hi } => (0..3).map(|k| if covers[k] { l[k] } else { hi[k] - lo[k] }).product(),
        Region::Cylinder { radius, length, .. } => {
            let k = (0..3).find(|&k| covers[k]);
            PI * radius * radius * k.map_or(*length, |k| l[k])
        }
        r => r.volume(),
    }
}

fn spec() -> impl Strategy<Value = Spec> {
    (
        0u8..6,
        prop::array::uniform3(0u8..6),
        1usize..=3,
        any::<bool>(),
        0u8..8,
        prop_oneof![Just(0usize), 1usize..80],
        0usize..3,
        any::<bool>(),
        prop_oneof![0.01f64..0.25, 0.25f64..0.6, 0.6f64..1.2],
        prop_oneof![3 => Just(0usize), 1 => 1usize..5],
        any::<u64>(),
    )
        .prop_map(
            |(region, sizes, parts, by_mass, periodic, present, walls, triangles, phi, invalid, seed)| Spec {
                region,
                sizes,
                parts,
                by_mass,
                periodic,
                present,
                walls,
                triangles,
                phi,
                invalid,
                roomy: false,
                seed,
            },
        )
}

/// A roomy case with nothing in the way.
fn clear_spec() -> impl Strategy<Value = Spec> {
    (0u8..6, prop::array::uniform3(0u8..6), 1usize..=3, any::<bool>(), 0u8..8, any::<bool>(), any::<u64>())
        .prop_map(|(region, sizes, parts, by_mass, periodic, dense, seed)| Spec {
            region,
            sizes,
            parts,
            by_mass,
            // A turned mesh or an oblique cylinder may stick out of the periodic box, where no
            // sphere goes: their fraction is of a smaller volume than the region's.
            periodic: if region <= 2 { periodic } else { 0 },
            present: 0,
            walls: 0,
            triangles: false,
            phi: if dense { 1.0 } else { 0.2 },
            invalid: 0,
            roomy: true,
            seed,
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    /// No overlap, inside the region, clear of everything in the way; more volume than the
    /// region holds leaves some out.
    #[test]
    fn placement_never_overlaps(spec in spec(), seed in any::<u64>()) {
        let case = build(&spec);
        let placed = place_case(&case, seed);
        let n = check(&case, &placed)?;
        let asked: f64 = case.diameters.iter().filter(|d| d.is_finite() && **d > 0.0).map(|d| PI / 6.0 * d.powi(3)).sum();
        if asked > period_volume(&case.region, case.covers, &case.periodic) {
            let valid = case.diameters.iter().filter(|d| d.is_finite() && **d > 0.0).count();
            prop_assert!(n < valid, "all {} spheres placed, {:e} m³ in a region of {:e} m³", n, asked, period_volume(&case.region, case.covers, &case.periodic));
        }
    }

    #[test]
    fn placement_fills_when_nothing_is_in_the_way(spec in clear_spec(), seed in any::<u64>()) {
        let case = build(&spec);
        let placed = place_case(&case, seed);
        let n = check(&case, &placed)?;
        let got: f64 = case.diameters.iter().zip(&placed).filter(|(_, x)| x.is_some()).map(|(d, _)| PI / 6.0 * d.powi(3)).sum();
        let valid = case.diameters.len();
        // The fraction asked for: the sizes drawn, not the mixture's mean, decide it (a wide
        // distribution's few hundred draws may hold a third more volume than its mean says).
        let asked: f64 = case.diameters.iter().map(|d| PI / 6.0 * d.powi(3)).sum();
        if asked <= 0.2 * period_volume(&case.region, case.covers, &case.periodic) {
            // Below RSA's jamming, in a region at least 3.2 largest diameters thick; but the
            // centres of the largest are crowded in such a region, and a few may find no room.
            prop_assert!(n as f64 >= 0.95 * valid as f64, "{} of {} placed at a solid fraction of {}", n, valid, spec.phi);
        } else if valid < MAX_ROOMY_COUNT {
            // The lattice's fraction, less the layers lost at the boundary of a region a few
            // diameters wide (boxes about 0.3–0.55, cylinders and meshes 0.2–0.45 measured over
            // 1 500 cases of these shapes and sizes): the floors leave room for the unlucky case
            // and fail for a placement that gives up early.
            // A case asking little more than the dilute 0.2 may ask less than the floor: then
            // 95 % of its volume, as in the dilute cases.
            let volume = period_volume(&case.region, case.covers, &case.periodic);
            let floor: f64 = if spec.region <= 1 { 0.25 } else { 0.15 };
            let floor = floor.min(0.95 * asked / volume);
            let phi = got / volume;
            prop_assert!(phi >= floor, "solid fraction {} reached, {} of {} placed", phi, n, valid);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// The same stream gives the same bits.
    #[test]
    fn placement_is_a_function_of_the_stream(spec in spec(), seed in any::<u64>()) {
        let case = build(&spec);
        let a = place_case(&case, seed);
        let b = place_case(&case, seed);
        let bits = |v: &[Option<Vec3>]| v.iter().map(|x| x.map(|x| x.to_array().map(f64::to_bits))).collect::<Vec<_>>();
        prop_assert_eq!(bits(&a), bits(&b));
    }
}

/// Regression: equal spheres at a solid fraction of 0.2 in a turned prism some 9 diameters
/// across. Random sequential addition left 3 of the 77 out (their centres crowded within the
/// region shrunk by a radius) and the fallback lattice, its sites fixed, found no room for
/// them; the retried random trials place all.
#[test]
fn dilute_spheres_crowded_in_a_small_mesh_are_all_placed() {
    let spec = Spec {
        region: 5,
        sizes: [0, 5, 2],
        parts: 1,
        by_mass: true,
        periodic: 0,
        present: 0,
        walls: 0,
        triangles: false,
        phi: 0.2,
        invalid: 0,
        roomy: true,
        seed: 16529031243450339799,
    };
    let case = build(&spec);
    let placed = place_case(&case, 14598255667036439615);
    assert_eq!(case.diameters.len(), 77);
    let n = check(&case, &placed).expect("no overlap");
    assert_eq!(n, 77);
}

/// Placement keeps clear of cylinder walls: in a box around a drum (particles inside, R = 8
/// mm) and a rod through it (particles outside, R = 3 mm), every centre is at least its radius
/// inside the drum and outside the rod (to the rounding [`TOL`] allows), and the annulus
/// between them (its centres 0.35 of the box) takes a dilute request (4 % solid) whole.
#[test]
fn placement_keeps_clear_of_cylinders() {
    use grainflow::{Cylinder, CylinderSide};
    let drum = Cylinder::new("drum", Vec3::ZERO, Vec3::Z, 0.008, CylinderSide::Inside, 0, 0.0);
    let rod = Cylinder::new("rod", Vec3::ZERO, Vec3::Z, 0.003, CylinderSide::Outside, 0, 0.0);
    let cylinders = [drum, rod];
    let region = Region::Box { lo: Vec3::splat(-0.01), hi: Vec3::splat(0.01) };
    let diameters = vec![1e-3; 200];
    let obstacles = Obstacles { cylinders: &cylinders, ..Obstacles::NONE };
    let placed = place(&region, &diameters, &obstacles, &mut InsertRng::seed_from_u64(3));
    let s = 0.02;
    for x in placed.iter().map(|x| x.expect("a dilute request fits")) {
        let rho = (x.x * x.x + x.y * x.y).sqrt();
        assert!(rho <= 0.008 - 5e-4 + TOL * s, "centre {x:?} {rho:e} m from the axis, outside the drum");
        assert!(rho >= 0.003 + 5e-4 - TOL * s, "centre {x:?} {rho:e} m from the axis, inside the rod");
    }
}
