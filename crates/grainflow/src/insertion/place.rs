//! Centres for a list of diameters inside a region: no two new spheres overlapping, none
//! overlapping a particle already present (through the nearest periodic image), a plane wall
//! or a mesh triangle, none inside a solid (a closed obstacle mesh), each wholly inside the
//! region.
//!
//! ## Two methods
//! The requested solid fraction φ = Σ πd³/6 / V (V the region's volume) chooses:
//!
//! - φ ≤ [`RSA_MAX_FRACTION`] (0.25): **random sequential addition**. Largest first, each
//!   sphere is tried at up to [`RSA_TRIALS`] uniformly random centres (uniform in the region
//!   shrunk by its radius) and kept at the first that is clear. RSA jams near φ ≈ 0.38 for
//!   equal spheres, and the chance of a clear trial falls steeply on the way (about 3 % at
//!   φ = 0.25); the spheres it fails to place go on to the lattice below, clear of those it
//!   placed, and those the lattice cannot place either (its sites all blocked, as in a region
//!   a few diameters wide, where the centres are crowded even at a low φ) are tried again at
//!   up to [`RSA_RETRY_TRIALS`] random centres each (at most as many trials in all as the
//!   first pass could take).
//! - φ > 0.25: a **jittered lattice**. Face-centred cubic (FCC) sites with nearest-neighbour
//!   spacing s fill the region's bounding box; a site is used if a sphere of the largest
//!   diameter fits there, clear of the region's boundary and the obstacles. The sites are
//!   visited in a random order and each takes the largest remaining sphere that fits among its
//!   occupied neighbours (for equal spheres: any), displaced from the site by a random offset
//!   within max(0, (s − d)/2), less any room the obstacles deny. Two offset spheres at
//!   neighbouring sites are then at least (s + d₁)/2 + (s + d₂)/2 − s ≥ (d₁ + d₂)/2 apart when
//!   both diameters are at most s, and sites farther than neighbours (s√2 and more) never meet
//!   for s ≥ d_max/√2. The lattice is fixed to the axes: in a region a few diameters wide, or
//!   at an angle to them, its sites may leave room it cannot use, so the spheres it did not
//!   place are tried again at random centres as in the dilute case (each size until
//!   [`RETRY_PATIENCE`] in a row found no room, then only sizes 10 % smaller).
//!
//! The spacing is chosen from the count: the largest s (a few spacings searched) for which
//! enough sites fit, so that the spheres spread through the whole region rather than packing
//! one end; for equal spheres never below d (touching neighbours), for unequal ones possibly
//! below d_max, down to d_max/√2, when s ≥ d_max would not give enough sites. A sphere larger
//! than s can then only sit where its neighbours are small enough: the sites of one of FCC's
//! four simple-cubic sublattices (none of them neighbours) are visited first, so the largest
//! quarter take them, and the others fill the remaining sites among them.
//!
//! ## What fraction is reachable
//! Equal spheres: FCC's 0.7405 (π/√18) in an unbounded region; a bounded one loses up to half
//! a layer at each face (a box 20 diameters wide reaches about 0.65–0.70). Random close packing
//! (≈ 0.64) is the limit of a disordered packing, so above it the lattice's order shows.
//! Unequal spheres: with spacing s ≥ d_max the fraction is 0.7405·⟨d³⟩/d_max³ (0.45 for
//! diameters uniform in 0.8–1.2 mm); the tighter spacing raises it (about 0.55 for that
//! distribution, measured in a box 40 diameters wide). Spheres that find no site are returned
//! as `None`: all those beyond the reachable fraction.
//!
//! ## Periodic axes
//! On a periodic axis that a box region spans (a cylinder's axis, for a cylinder along it),
//! the region repeats: centres are anywhere in the periodic box, wrapped into it, and a sphere
//! may cross the periodic face, overlapping nothing through the nearest image. On a periodic
//! axis the region does not span (or for a mesh region), each sphere lies wholly inside the
//! periodic box as well as the region, so that no image can meet it. Walls must not face a
//! periodic axis (as [`Periodic::check`] requires); mesh triangles are not imaged (as in the
//! contact search).
//!
//! ## Cost and determinism
//! A uniform grid of cells at least the largest diameter near the region (coarser for few
//! spheres in a large region) holds the particles present; another the spheres RSA places; the
//! lattice finds its sites' neighbours by index. All is O(N) for N spheres (and the present
//! particles and triangles near the region), and a function of the inputs and the random
//! stream's state alone: the same stream gives the same bits.
//!
//! Every clearance is required with [`MARGIN`] to spare, so that a check of the result with
//! other rounding (a distance computed another way) agrees.

use super::region::{InsideMesh, Region, cylinder_clearance};
use crate::boundary::Periodic;
use crate::math::Vec3;
use crate::mesh::closest_point_on_triangle;
use crate::wall::{Cylinder, CylinderSide, Wall};
use rand::Rng;
use std::f64::consts::{PI, SQRT_2};

/// Above this requested solid fraction the lattice is used directly.
pub const RSA_MAX_FRACTION: f64 = 0.25;

/// Random centres tried per sphere by random sequential addition.
pub const RSA_TRIALS: usize = 200;

/// The most random centres tried again per sphere that neither random sequential addition
/// nor the lattice placed.
pub const RSA_RETRY_TRIALS: usize = 20 * RSA_TRIALS;
/// Spheres in a row that a retry after the lattice finds no room for, after which it tries
/// only ones at least 10 % smaller.
pub const RETRY_PATIENCE: usize = 16;

/// Spare lattice sites asked for unequal spheres, as a fraction of their number: a site
/// whose neighbours are large takes no sphere.
pub const SPARE_SITES: f64 = 0.03;

/// The room every placed sphere has to spare, relative to the magnitude of the coordinates
/// (the region's and the periodic box's, or the largest diameter if larger): some 450 ulps,
/// far above the rounding of a distance, far below any size that matters.
pub const MARGIN: f64 = 1e-13;

/// What a new sphere must not overlap.
#[derive(Debug, Clone, Copy)]
pub struct Obstacles<'a> {
    /// Centres of the particles already present, m.
    pub positions: &'a [Vec3],
    /// Their radii, m (as many as `positions`).
    pub radii: &'a [f64],
    /// Plane walls: a new sphere's centre must be at least its radius from each, on its
    /// particle side ([`Wall::distance`] ≥ r).
    pub walls: &'a [Wall],
    /// Cylinder walls: a new sphere's centre must be at least its radius from each surface, on
    /// its particles' side.
    pub cylinders: &'a [Cylinder],
    /// Mesh walls' triangles in world coordinates (all of them; those far from the region
    /// are passed over). They must not be degenerate (as a loaded mesh's are not).
    pub triangles: &'a [[Vec3; 3]],
    /// Closed surfaces whose inside is solid (obstacle meshes): no new centre may lie inside
    /// one. With their triangles among `triangles`, a centre outside and clear of them by its
    /// radius keeps the whole sphere outside.
    pub solids: &'a [&'a InsideMesh],
    /// The periodic axes, if any: overlaps with present particles count through the nearest
    /// image, and a region spanning a periodic axis repeats along it (see the
    /// [module doc](self)).
    pub periodic: Option<Periodic>,
}

impl Obstacles<'static> {
    /// Nothing in the way.
    pub const NONE: Obstacles<'static> = Obstacles {
        positions: &[],
        radii: &[],
        walls: &[],
        cylinders: &[],
        triangles: &[],
        solids: &[],
        periodic: None,
    };
}

/// A centre for each of `diameters` (m), in their order, inside `region` and clear of
/// `obstacles` and of each other; `None` where a sphere did not fit (see the
/// [module doc](self) for the methods and the fraction they reach). A diameter that is not
/// finite and positive, or any sphere of a region that [`Region::check`] refuses, gets `None`.
pub fn place<R: Rng + ?Sized>(
    region: &Region,
    diameters: &[f64],
    obstacles: &Obstacles,
    rng: &mut R,
) -> Vec<Option<Vec3>> {
    let mut out = vec![None; diameters.len()];
    let valid: Vec<usize> =
        (0..diameters.len()).filter(|&i| diameters[i].is_finite() && diameters[i] > 0.0).collect();
    if valid.is_empty() || region.check().is_err() {
        return out;
    }
    let d_max = valid.iter().map(|&i| diameters[i]).fold(0.0, f64::max);
    let mut scene = Scene::new(region, obstacles, d_max, valid.len());
    let volume = scene.shape.volume(scene.plen);
    let solid: f64 = valid.iter().map(|&i| PI / 6.0 * diameters[i].powi(3)).sum();
    let radii: Vec<f64> = diameters.iter().map(|d| 0.5 * d).collect();
    // Largest first; equal diameters in their order.
    let mut order = valid;
    order.sort_by(|&a, &b| diameters[b].total_cmp(&diameters[a]));
    if solid <= RSA_MAX_FRACTION * volume {
        let failed = rsa(&mut scene, &order, &radii, RSA_TRIALS, &mut out, rng);
        if !failed.is_empty() {
            lattice(&scene, &failed, &radii, Spacing::Densest, &mut out, rng);
            retry(&mut scene, &failed, order.len(), &radii, &mut out, rng);
        }
    } else {
        lattice(&scene, &order, &radii, Spacing::FromCount, &mut out, rng);
        retry(&mut scene, &order, order.len(), &radii, &mut out, rng);
    }
    out
}

/// After the lattice placed what it could of `tried` (of `n` spheres asked for): its sites
/// are fixed, and where they are blocked (centres crowded in a region a few diameters wide,
/// a lattice at an angle to the region's faces) random trials may still find room. Each
/// sphere left (largest first) gets up to [`RSA_RETRY_TRIALS`], at most as many in all as a
/// first RSA pass over the `n` could take; once [`RETRY_PATIENCE`] in a row found no room,
/// the full region takes no more of that size or within 10 % below it: only smaller ones are
/// tried.
fn retry<R: Rng + ?Sized>(
    scene: &mut Scene,
    tried: &[usize],
    n: usize,
    radii: &[f64],
    out: &mut [Option<Vec3>],
    rng: &mut R,
) {
    let left: Vec<usize> = tried.iter().copied().filter(|&i| out[i].is_none()).collect();
    if left.is_empty() {
        return;
    }
    for &i in tried {
        if let Some(x) = out[i] {
            scene.placed.insert(x, radii[i]);
        }
    }
    let trials = (RSA_TRIALS * n / left.len()).min(RSA_RETRY_TRIALS);
    let (mut misses, mut blocked) = (0, f64::INFINITY);
    for &i in &left {
        if radii[i] >= blocked {
            continue;
        }
        if rsa(scene, &[i], radii, trials, out, rng).is_empty() {
            misses = 0;
        } else {
            misses += 1;
            if misses == RETRY_PATIENCE {
                // Sizes within 10 % of one that found no room would find none either (mostly):
                // a wide distribution is tried at a few sizes, not at every one.
                (misses, blocked) = (0, 0.9 * radii[i]);
            }
        }
    }
}

/// Random sequential addition of the spheres `order` (indices into `radii`), `trials` random
/// centres each; returns those not placed, in their order.
fn rsa<R: Rng + ?Sized>(
    scene: &mut Scene,
    order: &[usize],
    radii: &[f64],
    trials: usize,
    out: &mut [Option<Vec3>],
    rng: &mut R,
) -> Vec<usize> {
    let mut failed = Vec::new();
    for &i in order {
        let r = radii[i];
        let need = r + scene.margin;
        let mut at = None;
        for _ in 0..trials {
            let Some(x) = scene.sample(r, rng) else { break };
            if scene.clearance(x, need, need) >= need {
                at = Some(x);
                break;
            }
        }
        match at {
            Some(x) => {
                scene.placed.insert(x, r);
                out[i] = Some(x);
            }
            None => failed.push(i),
        }
    }
    failed
}

/// How the lattice spacing is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Spacing {
    /// As large as possible with enough sites for the spheres.
    FromCount,
    /// The densest the spheres allow: to fill the gaps RSA left.
    Densest,
}

/// The largest factor by which the lattice may have more sites than spheres (with a floor for
/// few spheres): a bound on its memory, reached only for few spheres in a large region.
const SITES_PER_SPHERE: f64 = 16.0;
const MIN_SITE_BUDGET: f64 = (1u64 << 20) as f64;
/// The most lattice sites.
const MAX_SITES: f64 = (1u64 << 28) as f64;
/// Spacings tried by the search.
const SPACING_TRIALS: usize = 12;
/// Layer counts tried by the per-axis refinement.
const LAYER_TRIALS: usize = 6;

/// The jittered-lattice placement of the spheres `todo` (indices into `radii`), clear of the
/// scene (which holds any spheres placed before); see the [module doc](self).
fn lattice<R: Rng + ?Sized>(
    scene: &Scene,
    todo: &[usize],
    radii: &[f64],
    spacing: Spacing,
    out: &mut [Option<Vec3>],
    rng: &mut R,
) {
    let margin = scene.margin;
    let r_max = todo.iter().map(|&i| radii[i]).fold(0.0, f64::max);
    let r_min = todo.iter().map(|&i| radii[i]).fold(f64::INFINITY, f64::min);
    let d_max = 2.0 * r_max;
    let equal = r_max - r_min <= 1e-12 * r_max;
    // Touching neighbours for equal spheres; second neighbours (s√2 apart) clear for unequal.
    let mut s_floor = if equal { d_max + 4.0 * margin } else { (d_max + 4.0 * margin) / SQRT_2 };
    let bounds = (0..3).map(|k| scene.qhi[k] - scene.qlo[k]).product::<f64>();
    let budget = (SITES_PER_SPHERE * todo.len() as f64).clamp(MIN_SITE_BUDGET, MAX_SITES);
    s_floor = s_floor.max((SQRT_2 * bounds / budget).cbrt());
    // On a repeating axis at least one cubic cell (s√2) fits.
    let s_top =
        (0..3).filter(|&k| scene.wrap[k]).map(|k| scene.plen[k] / SQRT_2).fold(f64::INFINITY, f64::min);
    let s_top = s_top.max(s_floor);
    // Sites hold the largest sphere with room to spare; so do their neighbours' sites.
    let r_ref = r_max + 2.0 * margin;
    let reach_of = |lat: &Lattice| ((0.5 * lat.spacing).max(r_max) + 2.0 * margin).min(scene.reach_cap());
    let need_max = r_max + margin;
    let count = |m: [usize; 3]| {
        let lat = Lattice::new(scene, m, r_ref);
        let reach = reach_of(&lat);
        (0..lat.sites())
            .filter_map(|idx| lat.decode(idx))
            .filter(|&ijk| scene.clearance(lat.position(ijk), need_max, reach) >= need_max)
            .count()
    };
    let layers = |s: f64| Lattice::layers(scene, s, r_ref);
    let m = match spacing {
        Spacing::Densest => layers(s_floor),
        Spacing::FromCount => {
            let target =
                if equal { todo.len() as f64 } else { (todo.len() as f64 * (1.0 + SPARE_SITES)).ceil() };
            let volume = scene.shape.volume(scene.plen);
            let s = search_spacing(s_floor, s_top, (SQRT_2 * volume / target).cbrt(), target, |s| {
                count(layers(s))
            });
            // The same spacing on every axis gains or loses a layer on all of them at once
            // (in a cube, a fifth of the sites): a layer fewer along some axes, where the count
            // allows, widens the spacing.
            let mut m = layers(s);
            for _ in 0..LAYER_TRIALS {
                let spacing = Lattice::new(scene, m, r_ref).spacing;
                let mut fewer: Vec<([usize; 3], f64)> = (0..3)
                    .filter_map(|k| {
                        let step = if scene.wrap[k] { 2 } else { 1 };
                        let mut f = m;
                        f[k] = f[k].checked_sub(step).filter(|&v| v >= step)?;
                        let wider = Lattice::new(scene, f, r_ref).spacing;
                        (wider > spacing).then_some((f, wider))
                    })
                    .collect();
                fewer.sort_by(|a, b| b.1.total_cmp(&a.1));
                match fewer.into_iter().find(|&(f, _)| count(f) as f64 >= target) {
                    Some((f, _)) => m = f,
                    None => break,
                }
            }
            m
        }
    };

    let lat = Lattice::new(scene, m, r_ref);
    let s = lat.spacing;
    let reach = reach_of(&lat);
    let need_min = r_min + margin;
    // Each usable site's clearance from the region's boundary and the obstacles.
    let mut clear = vec![f64::NEG_INFINITY; lat.sites()];
    let mut classes: [Vec<u32>; 4] = Default::default();
    for idx in 0..lat.sites() {
        let Some(ijk) = lat.decode(idx) else { continue };
        let c = scene.clearance(lat.position(ijk), need_min, reach);
        if c >= need_min {
            clear[idx] = c;
            classes[(ijk[0] & 1) | ((ijk[1] & 1) << 1)].push(idx as u32);
        }
    }
    // Spheres larger than s take the sites of one sublattice, visited first.
    let mut visit: Vec<u32> = Vec::with_capacity(classes.iter().map(Vec::len).sum());
    if d_max > s {
        for class in &mut classes {
            shuffle(class, rng);
            visit.append(class);
        }
    } else {
        for class in &mut classes {
            visit.append(class);
        }
        shuffle(&mut visit, rng);
    }

    // The spheres by increasing radius (equal radii in their order), and a union–find that
    // gives the largest not yet used at or below a rank: slot k + 1 stands for rank k, slot 0
    // for "none".
    let mut sorted: Vec<usize> = todo.to_vec();
    sorted.sort_by(|&a, &b| radii[a].total_cmp(&radii[b]).then(a.cmp(&b)));
    let sorted_r: Vec<f64> = sorted.iter().map(|&i| radii[i]).collect();
    let mut unused: Vec<u32> = (0..=sorted.len() as u32).collect();
    let mut left = sorted.len();

    // The occupant of each site: centre and radius (radius 0: empty).
    let mut occupant = vec![[0.0f64; 4]; lat.sites()];
    let mut near: Vec<[f64; 4]> = Vec::with_capacity(NEIGHBOURS.len());
    for &idx in &visit {
        if left == 0 {
            break;
        }
        let idx = idx as usize;
        let ijk = lat.decode(idx).expect("a visited site exists");
        let site = lat.position(ijk);
        near.clear();
        for off in NEIGHBOURS {
            if let Some(n) = lat.neighbour(ijk, off)
                && occupant[n][3] > 0.0
            {
                near.push(occupant[n]);
            }
        }
        // The clearance at p: from the site's (less the distance moved), and from the
        // occupied neighbours.
        let free_at = |p: Vec3| {
            near.iter().fold(clear[idx] - (p - site).length(), |f, o| {
                f.min(scene.sep(p - Vec3::new(o[0], o[1], o[2])).length() - o[3])
            })
        };
        let at_site = free_at(site) - margin;
        let top = find(&mut unused, sorted.len());
        let r_top = sorted_r[top - 1];
        let (x, slot) = if at_site >= r_top {
            // The largest left fits at the site: displaced at random within what leaves every
            // later neighbour its room.
            let jitter = (at_site - r_top).min((0.5 * s).min(lat.half) - r_top - margin).max(0.0);
            let mut x = site;
            if jitter > 0.0 {
                x = site + jitter * in_unit_ball(rng);
            }
            (x, top)
        } else {
            // Pushed away from the neighbours in its way, within the reach that keeps it clear
            // of the sites beyond them, the largest left may fit; else the largest that does,
            // where there is more room.
            let pushed = push(site, r_top + margin, lat.half - r_top - margin, &near, clear[idx], scene);
            let moved = free_at(pushed) - margin;
            let (x, cap) = if moved > at_site { (pushed, moved) } else { (site, at_site) };
            if cap < r_min {
                continue;
            }
            let slot = find(&mut unused, sorted_r.partition_point(|&r| r <= cap));
            if slot == 0 {
                continue;
            }
            (x, slot)
        };
        let r = sorted_r[slot - 1];
        let mut x = x;
        let wrapped = scene.wrap_free(x);
        if wrapped != x {
            // Moved across a repeating face: the triangles (not imaged) are measured again.
            let need = r + margin;
            x = if scene.clearance(wrapped, need, need) >= need { wrapped } else { site };
        }
        unused[slot] = (slot - 1) as u32;
        left -= 1;
        occupant[idx] = [x.x, x.y, x.z, r];
        out[sorted[slot - 1]] = Some(x);
    }
}

/// Pushes: a centre moved from `site` away from the spheres `near` (centre, radius) it would
/// overlap with radius `target`, and back from the site's own boundary (`clear` its clearance
/// at the site), a few times, within `reach` of the site.
fn push(site: Vec3, target: f64, reach: f64, near: &[[f64; 4]], clear: f64, scene: &Scene) -> Vec3 {
    let mut p = site;
    if reach.is_nan() || reach <= 0.0 {
        return p;
    }
    for _ in 0..PUSHES {
        let mut delta = Vec3::ZERO;
        for o in near {
            let v = scene.sep(p - Vec3::new(o[0], o[1], o[2]));
            let dist = v.length();
            let gap = dist - o[3] - target;
            if gap < 0.0 && dist > 0.0 {
                delta -= (gap / dist) * v;
            }
        }
        let back = site - p;
        let gap = clear - back.length() - target;
        if gap < 0.0 && back != Vec3::ZERO {
            delta -= gap * back.normalize();
        }
        if delta == Vec3::ZERO {
            break;
        }
        p += delta;
        let d = p - site;
        if d.length() > reach {
            p = site + d * (reach / d.length());
        }
    }
    p
}

/// Iterations of [`push`].
const PUSHES: usize = 8;

/// The largest spacing in [`floor`, `top`] with at least `target` sites by `count` (within a
/// few spacings' search, starting from the estimate `guess`), or `floor` if even it has too
/// few.
fn search_spacing(floor: f64, top: f64, guess: f64, target: f64, count: impl Fn(f64) -> usize) -> f64 {
    let mut good = None::<f64>;
    let mut bad = f64::INFINITY;
    let mut s = guess.clamp(floor, top);
    for _ in 0..SPACING_TRIALS {
        let c = count(s) as f64;
        if c >= target {
            good = Some(s);
        } else {
            bad = s;
        }
        // Sites go as s⁻³: the spacing that would give the target, kept within the bracket.
        let estimate = s * (c.max(1.0) / target).cbrt();
        let next = match good {
            None => {
                if s <= floor {
                    break;
                }
                // At least 2 % down: the count jumps a layer at a time.
                (estimate * (1.0 - 5e-3)).min(s * 0.98).max(floor)
            }
            Some(g) => {
                let e = if bad.is_finite() {
                    if estimate > g && estimate < bad { estimate } else { (g * bad).sqrt() }
                } else {
                    estimate.max(g * 1.01)
                };
                let e = e.min(top);
                if e <= g * (1.0 + 1e-3) || bad / g < 1.0 + 1e-3 {
                    break;
                }
                e
            }
        };
        s = next;
    }
    good.unwrap_or(floor)
}

/// The root of `k` in the union–find `parent` (path halving).
fn find(parent: &mut [u32], mut k: usize) -> usize {
    while parent[k] as usize != k {
        let p = parent[k] as usize;
        parent[k] = parent[p];
        k = p;
    }
    k
}

/// Fisher–Yates.
fn shuffle<T, R: Rng + ?Sized>(v: &mut [T], rng: &mut R) {
    for i in (1..v.len()).rev() {
        v.swap(i, rng.random_range(0..=i));
    }
}

/// A point uniform in the unit ball (by rejection from the cube).
fn in_unit_ball<R: Rng + ?Sized>(rng: &mut R) -> Vec3 {
    loop {
        let v = Vec3::new(rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>()) * 2.0 - Vec3::ONE;
        if v.length_squared() <= 1.0 {
            return v;
        }
    }
}

/// The 12 nearest neighbours of an FCC site, in half-cell steps.
const NEIGHBOURS: [[i8; 3]; 12] = [
    [1, 1, 0],
    [1, -1, 0],
    [-1, 1, 0],
    [-1, -1, 0],
    [1, 0, 1],
    [1, 0, -1],
    [-1, 0, 1],
    [-1, 0, -1],
    [0, 1, 1],
    [0, 1, -1],
    [0, -1, 1],
    [0, -1, -1],
];

/// FCC sites over the region's bounds: the points (i, j, k) of a grid of half-cell steps with
/// i + j + k even, stored by (k, j, i/2). Each axis's steps are stretched so that its layers
/// span the bounds (on a repeating axis, the periodic box in whole cells): neighbours are then
/// at least [`spacing`](Self::spacing) apart, and other sites at least twice
/// [`half`](Self::half).
struct Lattice {
    origin: [f64; 3],
    /// The step along each axis (0 on an axis of one layer).
    h: [f64; 3],
    m: [usize; 3],
    wrap: [bool; 3],
    /// Sites per row: ⌈m_x / 2⌉.
    hx: usize,
    /// The least distance between neighbouring sites, m.
    spacing: f64,
    /// The least step: sites that are not neighbours are at least twice this apart, m.
    half: f64,
}

impl Lattice {
    /// The layers along each axis at spacing `s` (steps s/√2), for spheres of radius `r`
    /// within the region's bounds.
    fn layers(scene: &Scene, s: f64, r: f64) -> [usize; 3] {
        let half = s / SQRT_2;
        std::array::from_fn(|k| {
            if scene.wrap[k] {
                2 * ((scene.plen[k] / (2.0 * half)).floor() as usize).max(1)
            } else {
                let e = scene.qhi[k] - scene.qlo[k] - 2.0 * r;
                if e >= 0.0 { (e / half).floor() as usize + 1 } else { 0 }
            }
        })
    }

    /// `m` layers along each axis, spanning the bounds shrunk by `r` (one layer: at the
    /// middle).
    fn new(scene: &Scene, m: [usize; 3], r: f64) -> Lattice {
        let (mut origin, mut h, mut step) = ([0.0; 3], [0.0; 3], [f64::INFINITY; 3]);
        for k in 0..3 {
            if scene.wrap[k] {
                h[k] = scene.plen[k] / m[k] as f64;
                origin[k] = scene.plo[k] + 0.5 * h[k];
                step[k] = h[k];
            } else if m[k] >= 2 {
                h[k] = (scene.qhi[k] - scene.qlo[k] - 2.0 * r) / (m[k] - 1) as f64;
                origin[k] = scene.qlo[k] + r;
                step[k] = h[k];
            } else {
                origin[k] = 0.5 * (scene.qlo[k] + scene.qhi[k]);
            }
        }
        let pair = |a: usize, b: usize| (step[a] * step[a] + step[b] * step[b]).sqrt();
        let spacing = pair(0, 1).min(pair(0, 2)).min(pair(1, 2));
        let half = step[0].min(step[1]).min(step[2]);
        Lattice { origin, h, m, wrap: scene.wrap, hx: m[0].div_ceil(2), spacing, half }
    }

    fn sites(&self) -> usize {
        self.hx * self.m[1] * self.m[2]
    }

    fn decode(&self, idx: usize) -> Option<[usize; 3]> {
        let (ic, rest) = (idx % self.hx, idx / self.hx);
        let (j, k) = (rest % self.m[1], rest / self.m[1]);
        let i = 2 * ic + ((j + k) & 1);
        (i < self.m[0]).then_some([i, j, k])
    }

    fn position(&self, ijk: [usize; 3]) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|k| self.origin[k] + ijk[k] as f64 * self.h[k]))
    }

    /// The site `off` half-cell steps from `ijk`, if it exists.
    fn neighbour(&self, ijk: [usize; 3], off: [i8; 3]) -> Option<usize> {
        let mut n = [0usize; 3];
        for k in 0..3 {
            let v = ijk[k] as isize + off[k] as isize;
            let m = self.m[k] as isize;
            n[k] = if self.wrap[k] {
                v.rem_euclid(m) as usize
            } else if v >= 0 && v < m {
                v as usize
            } else {
                return None;
            };
        }
        Some((n[2] * self.m[1] + n[1]) * self.hx + n[0] / 2)
    }
}

/// The region as the placement sees it, with the axes along which it repeats.
enum Shape<'a> {
    Box {
        lo: [f64; 3],
        hi: [f64; 3],
        /// The axes whose faces bound it (not repeating).
        bounded: [bool; 3],
    },
    Cylinder {
        base: Vec3,
        axis: Vec3,
        e1: Vec3,
        e2: Vec3,
        length: f64,
        radius: f64,
        /// The axis it repeats along (its own), if any.
        repeats: Option<usize>,
    },
    Mesh(&'a InsideMesh),
}

impl Shape<'_> {
    fn clearance(&self, x: Vec3, reach: f64) -> f64 {
        match self {
            Shape::Box { lo, hi, bounded } => {
                let x = x.to_array();
                let mut c = reach;
                for k in 0..3 {
                    if bounded[k] {
                        c = c.min(x[k] - lo[k]).min(hi[k] - x[k]);
                    }
                }
                c
            }
            Shape::Cylinder { base, axis, length, radius, repeats, .. } => {
                cylinder_clearance(x, *base, *axis, *length, *radius, repeats.is_none()).min(reach)
            }
            Shape::Mesh(m) => m.clearance(x, reach),
        }
    }

    /// The volume of one period (on the axes it repeats along: the periodic box's length).
    fn volume(&self, plen: [f64; 3]) -> f64 {
        match self {
            Shape::Box { lo, hi, bounded } => {
                (0..3).map(|k| if bounded[k] { hi[k] - lo[k] } else { plen[k] }).product()
            }
            Shape::Cylinder { length, radius, repeats, .. } => {
                PI * radius * radius * repeats.map_or(*length, |k| plen[k])
            }
            Shape::Mesh(m) => m.volume(),
        }
    }
}

/// Everything a new sphere must clear, prepared for fast queries.
struct Scene<'a> {
    shape: Shape<'a>,
    /// The axes along which the region repeats (periodic, spanned): centres wrapped, images
    /// through the face.
    wrap: [bool; 3],
    /// The periodic axes it does not span: spheres kept inside the periodic box.
    inbox: [bool; 3],
    plo: [f64; 3],
    phi: [f64; 3],
    plen: [f64; 3],
    /// Bounds of the centres: the region's, the periodic box on the repeating axes.
    qlo: [f64; 3],
    qhi: [f64; 3],
    walls: &'a [Wall],
    cylinders: &'a [Cylinder],
    solids: &'a [&'a InsideMesh],
    triangles: TriangleBins,
    present: Vec<StaticBins>,
    placed: DynamicBins,
    /// The largest query reach the bins answer exactly, m.
    reach: f64,
    margin: f64,
}

/// The largest reach of a clearance query, relative to the largest new radius: room for the
/// lattice's jitter.
const REACH: f64 = 1.5;

impl<'a> Scene<'a> {
    /// The scene of new spheres (`count` of them, diameters up to `d_max`) in `region`.
    fn new(region: &'a Region, obstacles: &Obstacles<'a>, d_max: f64, count: usize) -> Scene<'a> {
        let r_new = 0.5 * d_max;
        let (rlo, rhi) = region.bounds();
        let (rlo, rhi) = (rlo.to_array(), rhi.to_array());
        let per = obstacles.periodic.unwrap_or(Periodic::NONE);
        let (plo, phi) = (per.lo.to_array(), per.hi.to_array());
        let plen: [f64; 3] = std::array::from_fn(|k| phi[k] - plo[k]);
        let periodic: [bool; 3] =
            std::array::from_fn(|k| per.axes[k] && plen[k] > 0.0 && plen[k].is_finite());
        // Spanned: the region covers the periodic box along k, which holds a lattice cell.
        let spans = |k: usize, lo: f64, hi: f64| {
            periodic[k] && lo <= plo[k] && hi >= phi[k] && plen[k] >= 1.5 * d_max
        };
        let shape = match region {
            Region::Box { lo, hi } => {
                let (lo, hi) = (lo.to_array(), hi.to_array());
                Shape::Box { lo, hi, bounded: std::array::from_fn(|k| !spans(k, lo[k], hi[k])) }
            }
            Region::Cylinder { base, axis, length, radius } => {
                let a = axis.normalize();
                let (e1, e2) = a.any_orthonormal_pair();
                let top = *base + *length * a;
                let along = (0..3).find(|&k| a.to_array()[k].abs() == 1.0);
                let repeats = along.filter(|&k| {
                    spans(
                        k,
                        base.to_array()[k].min(top.to_array()[k]),
                        base.to_array()[k].max(top.to_array()[k]),
                    )
                });
                Shape::Cylinder { base: *base, axis: a, e1, e2, length: *length, radius: *radius, repeats }
            }
            Region::Mesh(m) => Shape::Mesh(m.as_ref()),
        };
        let wrap: [bool; 3] = match &shape {
            Shape::Box { bounded, .. } => std::array::from_fn(|k| !bounded[k]),
            Shape::Cylinder { repeats, .. } => std::array::from_fn(|k| *repeats == Some(k)),
            Shape::Mesh(_) => [false; 3],
        };
        let inbox: [bool; 3] = std::array::from_fn(|k| periodic[k] && !wrap[k]);
        let qlo: [f64; 3] = std::array::from_fn(|k| if wrap[k] { plo[k] } else { rlo[k] });
        let qhi: [f64; 3] = std::array::from_fn(|k| if wrap[k] { phi[k] } else { rhi[k] });
        let scale = (0..3)
            .flat_map(|k| {
                [
                    qlo[k],
                    qhi[k],
                    if periodic[k] { plo[k] } else { 0.0 },
                    if periodic[k] { phi[k] } else { 0.0 },
                ]
            })
            .map(f64::abs)
            .fold(d_max, f64::max);
        let margin = MARGIN * scale;
        let reach = REACH * r_new + 2.0 * margin;
        let geometry = Geometry { qlo, qhi, plo, plen, wrap };

        // Present particles near the region, wrapped into the periodic box, with their images
        // across the faces of the periodic axes the region does not span; the largest apart.
        let mut small = Vec::new();
        let mut large = Vec::new();
        let n = obstacles.positions.len().min(obstacles.radii.len());
        for (&p, &rp) in obstacles.positions[..n].iter().zip(&obstacles.radii[..n]) {
            if !(p.is_finite() && rp >= 0.0 && rp.is_finite()) {
                continue;
            }
            let mut p = p.to_array();
            for k in 0..3 {
                if periodic[k] && !(p[k] >= plo[k] && p[k] < phi[k]) {
                    p[k] = plo[k] + (p[k] - plo[k]).rem_euclid(plen[k]);
                }
            }
            let within = reach + rp;
            let shifts =
                |k: usize| if inbox[k] { [0.0, -plen[k], plen[k]] } else { [0.0, f64::NAN, f64::NAN] };
            for sx in shifts(0) {
                for sy in shifts(1) {
                    for sz in shifts(2) {
                        let q = [p[0] + sx, p[1] + sy, p[2] + sz];
                        if q.iter().any(|v| v.is_nan()) {
                            continue;
                        }
                        if (0..3).all(|k| wrap[k] || (q[k] >= qlo[k] - within && q[k] <= qhi[k] + within)) {
                            let e = [q[0], q[1], q[2], rp];
                            if rp <= 2.0 * r_new { small.push(e) } else { large.push(e) }
                        }
                    }
                }
            }
        }
        let mut present = Vec::new();
        for entries in [small, large] {
            if !entries.is_empty() {
                let r_max = entries.iter().map(|e| e[3]).fold(0.0, f64::max);
                present.push(StaticBins::new(&geometry, reach + r_max, entries));
            }
        }
        let placed = DynamicBins::new(&geometry, d_max + 4.0 * margin, count);
        let triangles = TriangleBins::new(&geometry, reach, obstacles.triangles);
        Scene {
            shape,
            wrap,
            inbox,
            plo,
            phi,
            plen,
            qlo,
            qhi,
            walls: obstacles.walls,
            cylinders: obstacles.cylinders,
            solids: obstacles.solids,
            triangles,
            present,
            placed,
            reach,
            margin,
        }
    }

    /// The largest reach a clearance query may ask for now.
    fn reach_cap(&self) -> f64 {
        if self.placed.is_empty() { self.reach } else { self.reach.min(self.placed.reach) }
    }

    /// The separation `d` through the nearest image on the repeating axes.
    #[inline]
    fn sep(&self, d: Vec3) -> Vec3 {
        let mut d = d.to_array();
        for k in 0..3 {
            if self.wrap[k] {
                if d[k] > 0.5 * self.plen[k] {
                    d[k] -= self.plen[k];
                } else if d[k] < -0.5 * self.plen[k] {
                    d[k] += self.plen[k];
                }
            }
        }
        Vec3::from_array(d)
    }

    /// `x` brought into the periodic box on the repeating axes.
    fn wrap_free(&self, x: Vec3) -> Vec3 {
        let mut x = x.to_array();
        for k in 0..3 {
            if self.wrap[k] && !(x[k] >= self.plo[k] && x[k] < self.phi[k]) {
                x[k] = self.plo[k] + (x[k] - self.plo[k]).rem_euclid(self.plen[k]);
                if x[k] >= self.phi[k] {
                    x[k] = self.plo[k];
                }
            }
        }
        Vec3::from_array(x)
    }

    /// The radius of the largest sphere about `x` clear of the region's boundary and every
    /// obstacle (and of the spheres RSA placed), or `reach` if smaller; any value below `need`
    /// as soon as one is found (m).
    fn clearance(&self, x: Vec3, need: f64, reach: f64) -> f64 {
        let mut c = self.shape.clearance(x, reach);
        if c < need {
            return c;
        }
        let xa = x.to_array();
        for k in 0..3 {
            if self.inbox[k] {
                c = c.min(xa[k] - self.plo[k]).min(self.phi[k] - xa[k]);
            }
        }
        for w in self.walls {
            c = c.min(w.distance(x));
        }
        for cyl in self.cylinders {
            c = c.min(cylinder_wall_clearance(cyl, x));
        }
        if c < need {
            return c;
        }
        if self.solids.iter().any(|m| m.contains(x)) {
            return f64::NEG_INFINITY;
        }
        c = self.triangles.clearance(x, c);
        if c < need {
            return c;
        }
        for bins in &self.present {
            c = bins.clearance(x, c, need, self);
            if c < need {
                return c;
            }
        }
        self.placed.clearance(x, c, need, self)
    }

    /// A random centre for a sphere of radius `r`, uniform in the region shrunk by `r` (a mesh:
    /// in its bounds shrunk by `r`), wrapped on the repeating axes; `None` if there is no room.
    fn sample<R: Rng + ?Sized>(&self, r: f64, rng: &mut R) -> Option<Vec3> {
        let mut u = || rng.random::<f64>();
        let within =
            |lo: f64, hi: f64, u: f64| (lo + r <= hi - r).then_some(lo + r + (hi - lo - 2.0 * r) * u);
        let x = match &self.shape {
            Shape::Box { lo, hi, bounded } => {
                let mut x = [0.0; 3];
                for k in 0..3 {
                    x[k] = if bounded[k] {
                        within(lo[k], hi[k], u())?
                    } else {
                        self.plo[k] + self.plen[k] * u()
                    };
                }
                Vec3::from_array(x)
            }
            Shape::Cylinder { base, axis, e1, e2, length, radius, repeats } => {
                let t = match repeats {
                    Some(k) => self.plen[*k] * u(),
                    None => within(0.0, *length, u())?,
                };
                if r > *radius {
                    return None;
                }
                let rho = (radius - r) * u().sqrt();
                let (sin, cos) = (2.0 * PI * u()).sin_cos();
                *base + t * *axis + rho * (cos * *e1 + sin * *e2)
            }
            Shape::Mesh(_) => {
                let (lo, hi) = (self.qlo, self.qhi);
                Vec3::new(within(lo[0], hi[0], u())?, within(lo[1], hi[1], u())?, within(lo[2], hi[2], u())?)
            }
        };
        Some(self.wrap_free(x))
    }
}

/// The extent the bins cover: the centres' bounds, and the periodic box on the repeating axes.
struct Geometry {
    qlo: [f64; 3],
    qhi: [f64; 3],
    plo: [f64; 3],
    plen: [f64; 3],
    wrap: [bool; 3],
}

/// The cells of a uniform grid over [`Geometry`]: one cell beyond the centres' bounds on each
/// side, or the periodic box (cells wrapping round) on a repeating axis.
#[derive(Debug, Clone)]
struct Frame {
    lo: [f64; 3],
    cell: [f64; 3],
    n: [usize; 3],
    wrap: [bool; 3],
}

impl Frame {
    /// Cells at least `cell` wide, coarsened until at most `budget` of them.
    fn new(g: &Geometry, cell: f64, budget: usize) -> Frame {
        let mut side = if cell > 0.0 && cell.is_finite() { cell } else { 1.0 };
        loop {
            let mut f = Frame { lo: [0.0; 3], cell: [side; 3], n: [1; 3], wrap: g.wrap };
            for k in 0..3 {
                if g.wrap[k] {
                    f.n[k] = ((g.plen[k] / side).floor() as usize).max(1);
                    f.cell[k] = g.plen[k] / f.n[k] as f64;
                    f.lo[k] = g.plo[k];
                } else {
                    f.n[k] = ((g.qhi[k] - g.qlo[k]) / side).floor() as usize + 3;
                    f.lo[k] = g.qlo[k] - side;
                }
            }
            if f.n.iter().map(|&n| n as f64).product::<f64>() <= budget as f64 {
                return f;
            }
            side *= 1.5;
        }
    }

    fn cells(&self) -> usize {
        self.n.iter().product()
    }

    fn coord(&self, k: usize, x: f64) -> usize {
        let f = ((x - self.lo[k]) / self.cell[k]).floor();
        if self.wrap[k] {
            (f as i64).rem_euclid(self.n[k] as i64) as usize
        } else if f >= 0.0 {
            (f as usize).min(self.n[k] - 1)
        } else {
            0
        }
    }

    fn cell_of(&self, x: [f64; 3]) -> usize {
        (self.coord(2, x[2]) * self.n[1] + self.coord(1, x[1])) * self.n[0] + self.coord(0, x[0])
    }

    /// The distinct cells along axis `k` within one of cell `c`.
    fn around(&self, k: usize, c: usize) -> ([usize; 3], usize) {
        let n = self.n[k];
        if self.wrap[k] {
            match n {
                1 => ([0, 0, 0], 1),
                2 => ([0, 1, 0], 2),
                _ => ([(c + n - 1) % n, c, (c + 1) % n], 3),
            }
        } else {
            let lo = c.saturating_sub(1);
            let hi = (c + 1).min(n - 1);
            ([lo, lo + 1, lo + 2], hi - lo + 1)
        }
    }

    /// Calls `f` with each cell within one cell of `x`'s along every axis.
    #[inline]
    fn for_each_near(&self, x: [f64; 3], mut f: impl FnMut(usize) -> bool) {
        let (zs, nz) = self.around(2, self.coord(2, x[2]));
        let (ys, ny) = self.around(1, self.coord(1, x[1]));
        let (xs, nx) = self.around(0, self.coord(0, x[0]));
        for &cz in &zs[..nz] {
            for &cy in &ys[..ny] {
                let row = (cz * self.n[1] + cy) * self.n[0];
                for &cx in &xs[..nx] {
                    if !f(row + cx) {
                        return;
                    }
                }
            }
        }
    }
}

/// The clearance `c` of `x`, lowered by the spheres `entries` (centre and radius).
#[inline]
fn lower(scene: &Scene, x: Vec3, entries: &[[f64; 4]], mut c: f64) -> f64 {
    for e in entries {
        let d = scene.sep(x - Vec3::new(e[0], e[1], e[2])).length_squared();
        let lim = c + e[3];
        if d < lim * lim {
            c = c.min(d.sqrt() - e[3]);
        }
    }
    c
}

/// Spheres binned once (the particles present): each cell's entries contiguous.
struct StaticBins {
    frame: Frame,
    start: Vec<u32>,
    entries: Vec<[f64; 4]>,
}

impl StaticBins {
    fn new(g: &Geometry, cell: f64, entries: Vec<[f64; 4]>) -> StaticBins {
        let frame = Frame::new(g, cell, (2 * entries.len()).max(1 << 16));
        let cells: Vec<usize> = entries.iter().map(|e| frame.cell_of([e[0], e[1], e[2]])).collect();
        let mut start = vec![0u32; frame.cells() + 1];
        for &c in &cells {
            start[c + 1] += 1;
        }
        for c in 0..frame.cells() {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut sorted = vec![[0.0; 4]; entries.len()];
        for (e, &c) in entries.iter().zip(&cells) {
            sorted[fill[c] as usize] = *e;
            fill[c] += 1;
        }
        StaticBins { frame, start, entries: sorted }
    }

    fn clearance(&self, x: Vec3, mut c: f64, need: f64, scene: &Scene) -> f64 {
        self.frame.for_each_near(x.to_array(), |cell| {
            let list = &self.entries[self.start[cell] as usize..self.start[cell + 1] as usize];
            c = lower(scene, x, list, c);
            c >= need
        });
        c
    }
}

/// Spheres binned as they are placed: a linked list per cell.
struct DynamicBins {
    frame: Frame,
    head: Vec<u32>,
    next: Vec<u32>,
    entries: Vec<[f64; 4]>,
    /// The largest query reach answered exactly, m.
    reach: f64,
}

const EMPTY: u32 = u32::MAX;

impl DynamicBins {
    /// Bins for spheres of diameter up to `cell`, expecting about `expected` of them.
    fn new(g: &Geometry, cell: f64, expected: usize) -> DynamicBins {
        let frame = Frame::new(g, cell, (2 * expected).max(1 << 16));
        let reach = frame.cell.iter().fold(f64::INFINITY, |a, &b| a.min(b)) - 0.5 * cell;
        DynamicBins { head: vec![EMPTY; frame.cells()], frame, next: Vec::new(), entries: Vec::new(), reach }
    }

    fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    fn insert(&mut self, x: Vec3, r: f64) {
        let c = self.frame.cell_of(x.to_array());
        self.next.push(self.head[c]);
        self.head[c] = self.entries.len() as u32;
        self.entries.push([x.x, x.y, x.z, r]);
    }

    fn clearance(&self, x: Vec3, mut c: f64, need: f64, scene: &Scene) -> f64 {
        if self.entries.is_empty() {
            return c;
        }
        self.frame.for_each_near(x.to_array(), |cell| {
            let mut e = self.head[cell];
            while e != EMPTY {
                c = lower(scene, x, std::slice::from_ref(&self.entries[e as usize]), c);
                e = self.next[e as usize];
            }
            c >= need
        });
        c
    }
}

/// Triangles near the region binned by the cells their bounding boxes meet.
struct TriangleBins {
    frame: Frame,
    start: Vec<u32>,
    ids: Vec<u32>,
    corners: Vec<[Vec3; 3]>,
    boxes: Vec<(Vec3, Vec3)>,
}

impl TriangleBins {
    /// The triangles within `reach` of the centres' bounds, in cells at least `reach` wide.
    fn new(g: &Geometry, reach: f64, triangles: &[[Vec3; 3]]) -> TriangleBins {
        let lo = Vec3::from_array(g.qlo) - Vec3::splat(reach);
        let hi = Vec3::from_array(g.qhi) + Vec3::splat(reach);
        let corners: Vec<[Vec3; 3]> = triangles
            .iter()
            .filter(|&&[a, b, c]| {
                let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
                !(th.cmplt(lo).any() || tl.cmpgt(hi).any())
            })
            .copied()
            .collect();
        let boxes: Vec<(Vec3, Vec3)> =
            corners.iter().map(|&[a, b, c]| (a.min(b).min(c), a.max(b).max(c))).collect();
        // Triangles are not imaged: the cells never wrap.
        let g = Geometry { wrap: [false; 3], ..*g };
        let mut cell = reach;
        let budget = (8 * corners.len()).max(1 << 16);
        let (frame, spans) = loop {
            let frame = Frame::new(&g, cell, budget);
            let spans: Vec<([usize; 3], [usize; 3])> = boxes
                .iter()
                .map(|(l, h)| {
                    let (l, h) = (l.to_array(), h.to_array());
                    (
                        std::array::from_fn(|k| frame.coord(k, l[k])),
                        std::array::from_fn(|k| frame.coord(k, h[k])),
                    )
                })
                .collect();
            let entries: usize =
                spans.iter().map(|(l, h)| (0..3).map(|k| h[k] - l[k] + 1).product::<usize>()).sum();
            if entries <= budget || cell > 1e6 * reach {
                break (frame, spans);
            }
            cell *= 2.0;
        };
        let index = |x: usize, y: usize, z: usize| (z * frame.n[1] + y) * frame.n[0] + x;
        let mut start = vec![0u32; frame.cells() + 1];
        for (l, h) in &spans {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        start[index(x, y, z) + 1] += 1;
                    }
                }
            }
        }
        for c in 0..frame.cells() {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut ids = vec![0u32; start[frame.cells()] as usize];
        for (t, (l, h)) in spans.iter().enumerate() {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        let c = index(x, y, z);
                        ids[fill[c] as usize] = t as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        TriangleBins { frame, start, ids, corners, boxes }
    }

    fn clearance(&self, x: Vec3, mut c: f64) -> f64 {
        if self.corners.is_empty() {
            return c;
        }
        self.frame.for_each_near(x.to_array(), |cell| {
            for &t in &self.ids[self.start[cell] as usize..self.start[cell + 1] as usize] {
                let (lo, hi) = self.boxes[t as usize];
                let out = (lo - x).max(x - hi).max(Vec3::ZERO);
                if out.length_squared() >= c * c {
                    continue;
                }
                let q = closest_point_on_triangle(x, self.corners[t as usize]).point;
                c = c.min((x - q).length());
            }
            true
        });
        c
    }
}

/// The distance from `x` to the surface of `cyl` on its particles' side (negative on the other
/// side), m; on the axis, a radius inside or outside.
fn cylinder_wall_clearance(cyl: &Cylinder, x: Vec3) -> f64 {
    let on_axis = if cyl.side == CylinderSide::Inside { cyl.radius } else { -cyl.radius };
    cyl.locate(x).map_or(on_axis, |k| k.distance)
}
