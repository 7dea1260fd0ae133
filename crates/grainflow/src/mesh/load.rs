//! Mesh files: STL (ASCII and binary) and Wavefront OBJ.
//!
//! The parsers are small and written here, so that every message names the file and the line
//! (or the facet) at fault, and no dependency is carried for two simple formats.
//!
//! ## STL
//! A file is binary when its size is exactly 84 + 50·n bytes, n the little-endian `u32` in
//! bytes 80..84: an 80-byte header, the count, and 50 bytes per facet. The size decides, not
//! the header, since some binary exporters start their header with `solid` too. (An ASCII file
//! passes the size test only by accident: its bytes 80..84 are text, which read as a count
//! exceed 5·10⁸ triangles, 27 GB.) Otherwise a file starting with `solid` is ASCII:
//! `solid` … (`facet normal` … `outer loop`, three `vertex x y z`, `endloop`, `endfacet`)* …
//! `endsolid`, keywords in any case, several solids in one file allowed.
//!
//! The facets' normals are ignored: the winding defines a triangle's normal (right hand), and
//! exporters often write zeros or stale normals. Binary coordinates are `f32`, widened to `f64`
//! exactly; ASCII coordinates are read as `f64`. A UTF-8 byte-order mark before an ASCII STL
//! (or an OBJ file) is skipped.
//!
//! ## OBJ
//! `v x y z` lines (further numbers, a weight or a colour, ignored) and `f` lines of three or
//! more vertex references, each `i`, `i/t`, `i//n` or `i/t/n` of which only the vertex index
//! `i` is used: from 1, or negative counting back from the last vertex read so far (−1 is
//! the last). A polygon is split into triangles in its own plane: a convex one into the fan
//! from its first vertex, any other by ear clipping, so that the triangles cover the polygon
//! and nothing else; one whose sides cross is refused ([`polygon`](super::polygon)). Everything else (texture coordinates, normals,
//! groups, materials, lines, points) is ignored, and so is anything after a `#`.

use super::build::{build, check_count};
use super::{Location, Mesh, MeshError, MeshTransform};
use crate::math::Vec3;
use std::path::Path;

impl Mesh {
    /// The mesh in the file at `path`, an STL or OBJ file by its extension (`.stl`, `.obj`, in
    /// any case), in file units brought to metres by `transform`. Welded and validated (see
    /// [`build`](super::build)); messages name the file by `path`.
    pub fn load(path: &Path, transform: &MeshTransform) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let read =
            || std::fs::read(path).map_err(|e| MeshError::Read { file: name.clone(), reason: e.to_string() });
        match ext.as_deref() {
            Some("stl") => Mesh::from_stl(&name, &read()?, transform),
            Some("obj") => Mesh::from_obj(&name, &read()?, transform),
            _ => Err(MeshError::Format { file: name }),
        }
    }

    /// The mesh of an STL file's contents, ASCII or binary (see the [module doc](self));
    /// `name` names it in messages.
    pub fn from_stl(name: &str, bytes: &[u8], transform: &MeshTransform) -> Result<Mesh, MeshError> {
        let (positions, lines) = if let Some(n) = binary_stl_count(bytes) {
            (binary_stl(bytes, n), None)
        } else {
            let bytes = without_bom(bytes);
            let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
            let ascii = bytes[start..].get(..5).is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
            if !ascii || bytes.contains(&0) {
                return Err(MeshError::BinarySize { file: name.to_string(), reason: not_stl(bytes, ascii) });
            }
            let (positions, lines) = ascii_stl(name, &String::from_utf8_lossy(bytes))?;
            (positions, Some(lines))
        };
        check_count(name, positions.len() / 3)?;
        let triangles: Vec<[u32; 3]> =
            (0..positions.len() as u32 / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        build(name, &positions, &triangles, lines.as_deref(), transform)
    }

    /// The mesh of an OBJ file's contents (see the [module doc](self)); `name` names it in
    /// messages.
    pub fn from_obj(name: &str, bytes: &[u8], transform: &MeshTransform) -> Result<Mesh, MeshError> {
        let (positions, triangles, lines) = obj(name, &String::from_utf8_lossy(without_bom(bytes)))?;
        build(name, &positions, &triangles, Some(&lines), transform)
    }
}

/// `bytes` without a leading UTF-8 byte-order mark (some Windows editors write one before
/// `solid` or the first `v`).
fn without_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes)
}

/// The facet count n of a binary STL: the file's size is 84 + 50·n.
fn binary_stl_count(bytes: &[u8]) -> Option<usize> {
    let count = bytes.get(80..84)?;
    let n = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as u64;
    (84 + 50 * n == bytes.len() as u64).then_some(n as usize)
}

/// Why `bytes` are neither a binary STL (whose size did not match) nor an ASCII one.
fn not_stl(bytes: &[u8], starts_with_solid: bool) -> String {
    let size = bytes.len();
    let ascii = if starts_with_solid {
        "it starts with 'solid' as an ASCII STL does, but holds binary data"
    } else {
        "it does not start with 'solid' as an ASCII STL does"
    };
    match bytes.get(80..84) {
        Some(c) => {
            let n = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64;
            format!(
                "as a binary STL of {n} triangles (the count in its header) it would have {} bytes, \
                 it has {size}; and {ascii}",
                84 + 50 * n
            )
        }
        None => format!("{size} bytes are fewer than a binary STL's 84-byte header; and {ascii}"),
    }
}

/// The corners of the n facets of a binary STL, three per facet.
fn binary_stl(bytes: &[u8], n: usize) -> Vec<Vec3> {
    let f = |b: &[u8], o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64;
    let mut positions = Vec::with_capacity(3 * n);
    for facet in bytes[84..].chunks_exact(50) {
        // 12 bytes of normal, then the three corners, then 2 attribute bytes.
        for o in [12, 24, 36] {
            positions.push(Vec3::new(f(facet, o), f(facet, o + 4), f(facet, o + 8)));
        }
    }
    positions
}

/// Where an ASCII STL parser is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stl {
    Outside,
    Solid,
    Facet,
    Loop,
    LoopDone,
}

impl Stl {
    fn expecting(self) -> &'static str {
        match self {
            Stl::Outside => "'solid'",
            Stl::Solid => "'facet normal' or 'endsolid'",
            Stl::Facet => "'outer loop'",
            Stl::Loop => "'vertex' or 'endloop'",
            Stl::LoopDone => "'endfacet'",
        }
    }
}

/// The corners (three per facet) of an ASCII STL and the `facet` line of each facet.
fn ascii_stl(name: &str, text: &str) -> Result<(Vec<Vec3>, Vec<u32>), MeshError> {
    let mut positions = Vec::new();
    let mut lines = Vec::new();
    let mut state = Stl::Outside;
    let (mut facet_line, mut corners, mut last) = (0, 0, 0);
    for (line, raw) in (1..).zip(text.lines()) {
        last = line;
        let err = |reason: String| MeshError::Syntax { file: name.to_string(), line, reason };
        let mut words = raw.split_whitespace();
        let Some(word) = words.next() else { continue };
        let mut second = |want: &str| {
            let next = words.next();
            if next.is_some_and(|w| w.eq_ignore_ascii_case(want)) {
                Ok(())
            } else {
                Err(err(format!("'{want}' must follow '{word}', found '{}'", next.unwrap_or(""))))
            }
        };
        state = match (word.to_ascii_lowercase().as_str(), state) {
            ("solid", Stl::Outside) => Stl::Solid,
            ("facet", Stl::Solid) => {
                second("normal")?;
                (facet_line, corners) = (line, 0);
                Stl::Facet
            }
            ("outer", Stl::Facet) => {
                second("loop")?;
                Stl::Loop
            }
            ("vertex", Stl::Loop) => {
                if corners == 3 {
                    return Err(err("a facet with more than three vertices".into()));
                }
                let xyz = words.by_ref().take(3).map(number).collect::<Result<Vec<f64>, _>>().map_err(err)?;
                if xyz.len() != 3 || words.next().is_some() {
                    return Err(err("a vertex needs exactly three coordinates".into()));
                }
                positions.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
                corners += 1;
                Stl::Loop
            }
            ("endloop", Stl::Loop) if corners == 3 => Stl::LoopDone,
            ("endloop", Stl::Loop) => return Err(err(format!("a facet with {corners} vertices, not three"))),
            ("endfacet", Stl::LoopDone) => {
                lines.push(line32(facet_line));
                Stl::Solid
            }
            ("endsolid", Stl::Solid) => Stl::Outside,
            _ => return Err(err(format!("unexpected '{word}' (expected {})", state.expecting()))),
        };
    }
    if state != Stl::Outside {
        let reason = format!("the file ends where {} should follow", state.expecting());
        return Err(MeshError::Syntax { file: name.to_string(), line: last, reason });
    }
    Ok((positions, lines))
}

/// A line number as a [`Location`] holds it (a file of more than 4·10⁹ lines, some 100 GB,
/// saturates).
fn line32(line: usize) -> u32 {
    u32::try_from(line).unwrap_or(u32::MAX)
}

/// A coordinate.
fn number(word: &str) -> Result<f64, String> {
    word.parse().map_err(|_| format!("'{word}' is not a number"))
}

/// The vertices, the faces split into triangles ([`polygon`](super::polygon)) and the line of
/// each triangle of an OBJ file.
#[allow(clippy::type_complexity)]
fn obj(name: &str, text: &str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>, Vec<u32>), MeshError> {
    let mut positions = Vec::new();
    // 0-based vertex indices; a positive reference may name a vertex defined further down, so
    // those are checked, and the faces split, at the end. Face k's corners are `corners[faces[k].0..faces[k + 1].0]`, its line `faces[k].1`.
    let mut corners: Vec<i64> = Vec::new();
    let mut faces: Vec<(usize, usize)> = Vec::new();
    // Triangles the faces read so far make (n − 2 for n corners).
    let mut made: usize = 0;
    for (line, raw) in (1..).zip(text.lines()) {
        let err = |reason: String| MeshError::Syntax { file: name.to_string(), line, reason };
        let content = raw.find('#').map_or(raw, |k| &raw[..k]);
        let mut words = content.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz = words.take(3).map(number).collect::<Result<Vec<f64>, _>>().map_err(err)?;
                if xyz.len() != 3 {
                    return Err(err("a vertex needs three coordinates".into()));
                }
                positions.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
            }
            Some("f") => {
                let start = corners.len();
                for w in words {
                    let reference = w.split('/').next().unwrap_or("");
                    let i: i64 =
                        reference.parse().map_err(|_| err(format!("'{w}' is not a vertex reference")))?;
                    let index = match i {
                        0 => return Err(err("vertex index 0 (OBJ counts vertices from 1)".into())),
                        i if i > 0 => i - 1,
                        i => positions.len() as i64 + i,
                    };
                    if index < 0 {
                        let triangle = u32::try_from(made).unwrap_or(u32::MAX);
                        let at = Location { triangle, line: Some(line32(line)) };
                        let count = positions.len();
                        return Err(MeshError::BadIndex { file: name.to_string(), at, index: i, count });
                    }
                    corners.push(index);
                }
                let n = corners.len() - start;
                if n < 3 {
                    return Err(err(format!("a face needs three or more vertices, not {n}")));
                }
                made += n - 2;
                faces.push((start, line));
            }
            _ => {}
        }
    }
    let mut triangles = Vec::with_capacity(made);
    let mut lines = Vec::with_capacity(made);
    let ends = faces.iter().skip(1).map(|f| f.0).chain([corners.len()]);
    for (&(start, line), end) in faces.iter().zip(ends) {
        let polygon = &corners[start..end];
        // The triangle of the fan from the first corner that first holds a corner (the
        // numbering of triangles in messages).
        let first = u32::try_from(triangles.len()).unwrap_or(u32::MAX);
        if let Some(j) = polygon.iter().position(|&i| i >= positions.len() as i64) {
            let triangle = first.saturating_add(j.saturating_sub(2) as u32);
            let at = Location { triangle, line: Some(line32(line)) };
            let (index, count) = (polygon[j] + 1, positions.len());
            return Err(MeshError::BadIndex { file: name.to_string(), at, index, count });
        }
        let points: Vec<Vec3> = polygon.iter().map(|&i| positions[i as usize]).collect();
        let split = super::polygon::triangulate(&points).map_err(|reason| MeshError::Syntax {
            file: name.to_string(),
            line,
            reason,
        })?;
        for t in split {
            triangles.push(t.map(|k| polygon[k] as u32));
            lines.push(line32(line));
        }
    }
    Ok((positions, triangles, lines))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_stl_is_told_by_its_size() {
        let mut b = b"solid but binary".to_vec();
        b.resize(80, b' ');
        b.extend_from_slice(&2u32.to_le_bytes());
        b.resize(84 + 100, 0);
        assert_eq!(binary_stl_count(&b), Some(2));
        b.push(0);
        assert_eq!(binary_stl_count(&b), None);
        // An ASCII file's bytes 80..84 are text: a count of at least 0x20202020 facets.
        let ascii = format!("solid a\n{}\nendsolid a\n", " ".repeat(100));
        assert_eq!(binary_stl_count(ascii.as_bytes()), None);
        assert_eq!(binary_stl_count(b"solid"), None);
    }
}
