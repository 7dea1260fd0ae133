//! Output writers. Every file but the time series is written atomically: into a temporary file
//! beside it, renamed over the target only when complete, so a crash never leaves a
//! half-written file in place of an earlier good one. The time series grows row by row in
//! place, so a crash keeps the rows written before it.

use grainflow::mesh::{MeshMotion, MeshWall, SurfaceMotion};
use grainflow::{Diagnostics, Particles, Vec3};
use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams what `write` writes to `path` atomically (temporary file + rename): the content
/// never has to be in memory as a whole. On an error the temporary file is removed and any
/// earlier file at `path` is left as it was.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(format!(".partial-{}", std::process::id()));
    path.with_file_name(name)
}

/// Header of the time-series CSV: its first columns, which every run writes (a case with mesh
/// walls adds its [`mesh_columns`] after them).
pub const TIMESERIES_HEADER: &str =
    "step,time,kinetic_translational,kinetic_rotational,potential,elastic,contacts,max_overlap_ratio";

/// The axis a mesh wall turns about, (a point on it, unit direction): its motion's if it
/// rotates, else its surface's if that turns; none for any other mesh.
pub fn rotation_axis(wall: &MeshWall) -> Option<(Vec3, Vec3)> {
    match (wall.motion, wall.surface) {
        (MeshMotion::Rotate { origin, axis, .. }, _) | (_, SurfaceMotion::Rotate { origin, axis, .. }) => {
            Some((origin, axis))
        }
        _ => None,
    }
}

/// A mesh name as it appears in column names: every character but an ASCII letter, digit or
/// `_` becomes `_` (`"drum shell, 2"` → `drum_shell__2`), so that a header needs no quoting.
pub fn column_name(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect()
}

/// The time series' columns of the mesh walls, mesh after mesh: `mesh_<name>_fx`, `_fy`,
/// `_fz` (N) and `_tx`, `_ty`, `_tz` (N·m), and for a mesh with a rotation axis
/// (`rotating[k]`) `_t_axis` (N·m). `<name>` is [`column_name`] of the mesh's name; should
/// two meshes' names come out the same, the later one gets `_2` (`_3`, …) appended until its
/// prefix is unique.
pub fn mesh_columns(names: &[String], rotating: &[bool]) -> Vec<String> {
    let mut prefixes: Vec<String> = Vec::with_capacity(names.len());
    for name in names {
        let base = format!("mesh_{}", column_name(name));
        let mut prefix = base.clone();
        let mut k = 2;
        while prefixes.contains(&prefix) {
            prefix = format!("{base}_{k}");
            k += 1;
        }
        prefixes.push(prefix);
    }
    let mut columns = Vec::with_capacity(7 * names.len());
    for (prefix, &turns) in prefixes.iter().zip(rotating) {
        for c in ["fx", "fy", "fz", "tx", "ty", "tz"] {
            columns.push(format!("{prefix}_{c}"));
        }
        if turns {
            columns.push(format!("{prefix}_t_axis"));
        }
    }
    columns
}

/// The header of a time series with `extra` columns after [`TIMESERIES_HEADER`]'s.
pub fn timeseries_header(extra: &[String]) -> String {
    let mut h = String::from(TIMESERIES_HEADER);
    for c in extra {
        h.push(',');
        h.push_str(c);
    }
    h
}

/// The time-series CSV, written as the run goes: every row reaches the file as it is written
/// (a crash loses no row written before it), and [`sync`](Self::sync) makes the rows durable
/// (at checkpoints), so a restart from a checkpoint finds every row up to its step.
pub struct TimeSeriesWriter {
    path: PathBuf,
    out: BufWriter<File>,
    /// Values a row holds after the diagnostics.
    extra: usize,
}

/// The longest row kept from an earlier time series, bytes: ours are under 200 bytes plus
/// at most 25 a further column (`{:e}` of an f64 and a comma); a longer line is not one of
/// ours, and ends what is kept.
fn max_row(extra: usize) -> usize {
    4096 + 32 * extra
}

impl TimeSeriesWriter {
    /// Starts `path` afresh (the header, with the `extra` columns, only), replacing any file
    /// there.
    pub fn create(path: &Path, extra: &[String]) -> io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{}", timeseries_header(extra))?;
        out.flush()?;
        Ok(TimeSeriesWriter { path: path.to_path_buf(), out, extra: extra.len() })
    }

    /// Continues the series in `path` at `step`: its rows before `step` are kept (if it is a
    /// time series with this header), and with `keep_step` also its row of `step` itself;
    /// the later ones are dropped, and the rows written next follow them. The file is
    /// replaced atomically. Also returns whether a row of `step` was kept.
    pub fn resume(path: &Path, step: u64, extra: &[String], keep_step: bool) -> io::Result<(Self, bool)> {
        let header = timeseries_header(extra);
        let last = if keep_step { Some(step) } else { step.checked_sub(1) };
        let kept = last.map_or_else(Vec::new, |l| earlier_rows(path, &header, l, extra.len()));
        let step_kept = keep_step && kept.last().and_then(|r| row_step(r)) == Some(step);
        write_atomic_with(path, |w| {
            writeln!(w, "{header}")?;
            kept.iter().try_for_each(|r| writeln!(w, "{r}"))
        })?;
        let out = BufWriter::new(std::fs::OpenOptions::new().append(true).open(path)?);
        Ok((TimeSeriesWriter { path: path.to_path_buf(), out, extra: extra.len() }, step_kept))
    }

    /// Appends one row (units: s, J, count, dimensionless), with the `extra` values after the
    /// diagnostics (as many as the header's extra columns), and hands it to the file.
    pub fn write(&mut self, d: &Diagnostics, extra: &[f64]) -> io::Result<()> {
        debug_assert_eq!(extra.len(), self.extra, "one value a column");
        write!(
            self.out,
            "{},{:e},{:e},{:e},{:e},{:e},{},{:e}",
            d.step,
            d.time,
            d.kinetic_translational,
            d.kinetic_rotational,
            d.potential,
            d.elastic,
            d.contacts,
            d.max_overlap_ratio
        )?;
        for x in extra {
            write!(self.out, ",{x:e}")?;
        }
        writeln!(self.out)?;
        self.out.flush()
    }

    /// Makes the rows written so far durable (on the disk, not only in the system's cache).
    pub fn sync(&mut self) -> io::Result<()> {
        self.out.flush()?;
        self.out.get_ref().sync_data()
    }

    /// Completes the file.
    pub fn finish(mut self) -> io::Result<()> {
        self.sync()
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The step of a time-series row.
fn row_step(row: &str) -> Option<u64> {
    row.split(',').next().and_then(|s| s.parse::<u64>().ok())
}

/// The rows of the time series in `path` up to `last` (a step), in order; none if it is not
/// a time series with `header`. Read a line at a time, each line at most [`max_row`] bytes:
/// an outsized file costs no memory. A last row without its line end (cut off by a crash) is
/// dropped.
fn earlier_rows(path: &Path, header: &str, last: u64, extra: usize) -> Vec<String> {
    use std::io::BufRead;
    let regular = std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file());
    let Some(file) = regular.then(|| File::open(path).ok()).flatten() else { return Vec::new() };
    let mut r = io::BufReader::new(file);
    let mut line = Vec::new();
    let limit = max_row(extra).max(header.len()) as u64 + 1;
    let mut next_line = |line: &mut Vec<u8>| -> Option<String> {
        line.clear();
        (&mut r).take(limit).read_until(b'\n', line).ok()?;
        line.pop_if(|c| *c == b'\n')?;
        String::from_utf8(std::mem::take(line)).ok()
    };
    if next_line(&mut line).as_deref() != Some(header) {
        return Vec::new();
    }
    let mut rows = Vec::new();
    while let Some(row) = next_line(&mut line) {
        if row_step(&row).is_none_or(|s| s > last) {
            break;
        }
        rows.push(row);
    }
    rows
}

/// Header of a particle snapshot CSV (also readable as a CSV particle file).
pub const SNAPSHOT_HEADER: &str = "id,phase,x,y,z,radius,u,v,w,wx,wy,wz";

/// The particle snapshot as CSV text; `phase` is 1-based, as in particle files.
pub fn snapshot_csv(p: &Particles) -> String {
    let mut s = String::with_capacity(64 + p.len() * 200);
    s.push_str(SNAPSHOT_HEADER);
    s.push('\n');
    for i in 0..p.len() {
        let (x, v, w) = (p.position[i], p.velocity[i], p.omega[i]);
        s.push_str(&format!(
            "{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            p.id[i],
            p.phase[i] + 1,
            x.x,
            x.y,
            x.z,
            p.radius[i],
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names with separators, quotes or other characters become safe column prefixes, and two
    /// that come out the same are told apart.
    #[test]
    fn mesh_columns_are_safe_and_unique() {
        assert_eq!(column_name("drum shell, 2"), "drum_shell__2");
        assert_eq!(column_name("\"a\"b-c.d/é"), "_a_b_c_d__");
        let names: Vec<String> = ["a b", "a,b", "a_b", "x"].map(String::from).into();
        let c = mesh_columns(&names, &[false, true, false, false]);
        assert_eq!(c.len(), 6 + 7 + 6 + 6);
        assert_eq!(c[0], "mesh_a_b_fx");
        assert_eq!(
            &c[6..13],
            ["fx", "fy", "fz", "tx", "ty", "tz", "t_axis"].map(|s| format!("mesh_a_b_2_{s}"))
        );
        assert_eq!(c[13], "mesh_a_b_3_fx");
        assert_eq!(c[19], "mesh_x_fx");
        assert!(c.iter().all(|n| n.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_')));
        let mut sorted = c.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), c.len(), "repeated column names");
    }

    /// A resumed series keeps the rows before the step, and with `keep_step` the step's own
    /// row; a series with other columns is not continued.
    #[test]
    fn a_resumed_series_keeps_the_rows_asked_for() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ts.csv");
        let extra = vec!["mesh_m_fx".to_string()];
        let mut w = TimeSeriesWriter::create(&path, &extra).unwrap();
        for step in [0, 10, 20, 30] {
            let d = Diagnostics { step, ..Default::default() };
            w.write(&d, &[step as f64]).unwrap();
        }
        w.finish().unwrap();
        let rows = |p: &Path| {
            std::fs::read_to_string(p).unwrap().lines().skip(1).map(String::from).collect::<Vec<_>>()
        };
        let all = rows(&path);
        assert_eq!(all[1], "10,0e0,0e0,0e0,0e0,0e0,0,0e0,1e1");
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, true).unwrap();
        drop(w);
        assert!(kept);
        assert_eq!(rows(&path), all[..3]);
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, false).unwrap();
        drop(w);
        assert!(!kept);
        assert_eq!(rows(&path), all[..2]);
        // The row of step 20 is gone now: asked to keep it, none is kept.
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, true).unwrap();
        drop(w);
        assert!(!kept);
        // Other columns: another series, not continued.
        let (w, _) = TimeSeriesWriter::resume(&path, 20, &[], true).unwrap();
        drop(w);
        assert!(rows(&path).is_empty());
    }
}
