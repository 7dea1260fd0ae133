//! Polygons of OBJ faces split into triangles.
//!
//! A strictly convex polygon (every corner turning the same way, once round) is split into the fan of
//! triangles from its first corner. Any other polygon is split by ear clipping in its own
//! plane: the polygon is projected onto the coordinate plane its (Newell) normal is most
//! nearly perpendicular to, and a corner whose triangle with its two neighbours turns the
//! polygon's way and holds no other corner (inside or on its sides) is cut off, repeatedly,
//! looking from the second corner on. For a convex polygon that gives the fan, so both paths
//! agree. The triangles keep the polygon's winding, and together they cover exactly the
//! polygon: no notch of a non-convex face is covered.
//!
//! A polygon whose sides cross or touch one another (a bow tie, a star drawn in one stroke)
//! has no such split and is refused, and so is a polygon that is not strictly convex of more than
//! [`MAX_CLIPPED_CORNERS`] corners (ear clipping takes time growing as the cube of the corners
//! at worst). A polygon with no area (all corners on one line) is left as its fan, whose
//! degenerate triangles the mesh's validation reports.

use crate::math::Vec3;

/// The most corners of a face that is not strictly convex: ear clipping takes up to n³ corner tests (10⁹ here,
/// about a second); CAD exports split such faces long before.
pub const MAX_CLIPPED_CORNERS: usize = 1000;

/// The triangles (indices into `points`, in the polygon's winding) of the polygon through
/// `points` in order; the error says why it cannot be split.
pub(crate) fn triangulate(points: &[Vec3]) -> Result<Vec<[usize; 3]>, String> {
    let n = points.len();
    let fan = || (1..n - 1).map(|j| [0, j, j + 1]).collect::<Vec<_>>();
    if n <= 3 {
        return Ok(fan());
    }
    let normal = newell_normal(points);
    // The projection that keeps the most of the polygon's area: drop the normal's largest
    // component, and order the two kept axes so that the polygon runs anticlockwise in them.
    let k = (0..3).max_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs())).unwrap_or(2);
    let (mut u, mut v) = ((k + 1) % 3, (k + 2) % 3);
    if normal[k] < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let flat: Vec<[f64; 2]> = points.iter().map(|p| [p[u], p[v]]).collect();
    let scale = longest_side_squared(&flat);
    // No area (to rounding): every corner on one line, or a figure whose parts cancel.
    if normal[k].abs() <= 1e-12 * scale || !normal[k].is_finite() {
        let flat_fan = fan().iter().all(|t| cross(flat[t[0]], flat[t[1]], flat[t[2]]).abs() <= 1e-12 * scale);
        return if flat_fan {
            Ok(fan())
        } else {
            Err("the face's sides cross one another (it encloses no area); split it into simple polygons"
                .into())
        };
    }
    if is_convex(&flat) {
        return Ok(fan());
    }
    if n > MAX_CLIPPED_CORNERS {
        return Err(format!(
            "a face of {n} corners that is not strictly convex, more than the {MAX_CLIPPED_CORNERS} such corners that are split into triangles; split it in the CAD export"
        ));
    }
    if let Some((a, b)) = crossing_sides(&flat) {
        return Err(format!(
            "the face is not a simple polygon: its side from corner {} to {} crosses or touches its side from corner {} to {}; split it into simple polygons",
            a + 1,
            (a + 1) % n + 1,
            b + 1,
            (b + 1) % n + 1
        ));
    }
    ear_clip(&flat).ok_or_else(|| {
        "the face cannot be split into triangles (no corner can be cut off; its corners are too close to a line); split it in the CAD export".to_string()
    })
}

/// The polygon's normal by Newell's formula: twice its vector area.
fn newell_normal(points: &[Vec3]) -> [f64; 3] {
    let mut n = Vec3::ZERO;
    for (i, &p) in points.iter().enumerate() {
        n += p.cross(points[(i + 1) % points.len()]);
    }
    n.to_array()
}

/// (b − a) × (c − a): positive when a, b, c turn anticlockwise.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn longest_side_squared(flat: &[[f64; 2]]) -> f64 {
    let n = flat.len();
    (0..n)
        .map(|i| {
            let (a, b) = (flat[i], flat[(i + 1) % n]);
            (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)
        })
        .fold(0.0, f64::max)
}

/// Every corner turns anticlockwise and the sides go round once. (A corner on a straight
/// side is left to ear clipping, which does not cut a flat triangle there as the fan would.)
fn is_convex(flat: &[[f64; 2]]) -> bool {
    let n = flat.len();
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (flat[(i + n - 1) % n], flat[i], flat[(i + 1) % n]);
        let z = cross(a, b, c);
        if z <= 0.0 {
            return false;
        }
        let dot = (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1]);
        turning += z.atan2(dot);
    }
    // Once round is 2π; a star drawn in one stroke goes round twice or more.
    (turning - std::f64::consts::TAU).abs() < 1.0
}

/// Two sides that are not neighbours and cross or touch, if any (their first corners).
fn crossing_sides(flat: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = flat.len();
    for i in 0..n {
        let (a, b) = (flat[i], flat[(i + 1) % n]);
        for j in i + 1..n {
            // Neighbouring sides share a corner.
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (c, d) = (flat[j], flat[(j + 1) % n]);
            if segments_meet(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

/// Whether the closed segments ab and cd have a point in common.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0]) && r[0] <= p[0].max(q[0]) && r[1] >= p[1].min(q[1]) && r[1] <= p[1].max(q[1])
    };
    (d1 == 0.0 && within(a, b, c))
        || (d2 == 0.0 && within(a, b, d))
        || (d3 == 0.0 && within(c, d, a))
        || (d4 == 0.0 && within(c, d, b))
}

/// Ear clipping of a simple polygon running anticlockwise; `None` if at some point no corner
/// can be cut off.
fn ear_clip(flat: &[[f64; 2]]) -> Option<Vec<[usize; 3]>> {
    let mut left: Vec<usize> = (0..flat.len()).collect();
    let mut triangles = Vec::with_capacity(flat.len() - 2);
    while left.len() > 3 {
        let m = left.len();
        // From the second corner on, so that a convex polygon gives its fan.
        let ear = (1..=m).map(|i| i % m).find(|&i| {
            let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
            let (pa, pb, pc) = (flat[a], flat[b], flat[c]);
            cross(pa, pb, pc) > 0.0
                && left.iter().all(|&q| {
                    q == a || q == b || q == c || {
                        let p = flat[q];
                        !(cross(pa, pb, p) >= 0.0 && cross(pb, pc, p) >= 0.0 && cross(pc, pa, p) >= 0.0)
                    }
                })
        })?;
        triangles.push([left[(ear + m - 1) % m], left[ear], left[(ear + 1) % m]]);
        left.remove(ear);
    }
    if cross(flat[left[0]], flat[left[1]], flat[left[2]]) <= 0.0 {
        return None;
    }
    triangles.push([left[0], left[1], left[2]]);
    Some(triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn a_convex_polygon_is_its_fan_and_collinear_corners_are_not_cut() {
        let square = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0)];
        assert_eq!(triangulate(&square).unwrap(), vec![[0, 1, 2], [0, 2, 3]]);
        // A corner on a side (1): a fan from 0 would hold the flat triangle (0, 1, 2).
        let five = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, 2.0, 0.0), v(0.0, 2.0, 0.0)];
        let t = triangulate(&five).unwrap();
        assert!(t.iter().all(|t| *t != [0, 1, 2]), "{t:?}");
        assert_eq!(t.len(), 3);
    }

    #[test]
    fn a_bow_tie_and_a_star_are_refused() {
        let bow = [v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        assert!(triangulate(&bow).unwrap_err().contains("cross"));
        // A pentagram in one stroke: every corner turns left, but it goes round twice.
        let star: Vec<Vec3> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                v(a.cos(), a.sin(), 0.0)
            })
            .collect();
        assert!(triangulate(&star).unwrap_err().contains("not a simple polygon"));
    }
}
