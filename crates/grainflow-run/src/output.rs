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
/// walls adds its [`mesh_columns`] after them, one with cylinders its [`cylinder_columns`]).
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
    load_columns("mesh", names, rotating)
}

/// The time series' columns of the cylinder walls, cylinder after cylinder, after the
/// meshes': `cylinder_<name>_fx`, `_fy`, `_fz` (N), `_tx`, `_ty`, `_tz` (N·m, about the
/// cylinder's `origin`) and `_t_axis` (N·m, the torque's component along its axis), named as
/// [`mesh_columns`] names them.
pub fn cylinder_columns(names: &[String]) -> Vec<String> {
    load_columns("cylinder", names, &vec![true; names.len()])
}

/// [`mesh_columns`] for the walls of `kind` ("mesh", "cylinder").
fn load_columns(kind: &str, names: &[String], rotating: &[bool]) -> Vec<String> {
    let mut prefixes: Vec<String> = Vec::with_capacity(names.len());
    for name in names {
        let base = format!("{kind}_{}", column_name(name));
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

/// A number of the time series: a measured quantity, or a count (written as an integer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A real quantity, written as `{:e}` (a zero without its sign).
    Real(f64),
    /// A count of things, written as an integer.
    Count(u64),
}

impl From<f64> for Value {
    fn from(x: f64) -> Value {
        Value::Real(x)
    }
}

impl From<u64> for Value {
    fn from(n: u64) -> Value {
        Value::Count(n)
    }
}

/// `x` for a file: `{:e}`, with a negative zero written as `0e0` (the sign of a zero is an
/// accident of the roundings: a sum of nothing, a product by zero, not a measurement).
pub fn real(x: f64) -> impl std::fmt::Display {
    // −0 + 0 = +0 in round-to-nearest; any other value is unchanged.
    struct Real(f64);
    impl std::fmt::Display for Real {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "{:e}", self.0 + 0.0)
        }
    }
    Real(x)
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Value::Real(x) => write!(f, "{}", real(x)),
            Value::Count(n) => write!(f, "{n}"),
        }
    }
}

/// How far a time series had got: rows and bytes written, and the SHA-256 of those bytes.
#[derive(Debug, Clone)]
struct Mark {
    rows: u64,
    bytes: u64,
    hash: sha2::Sha256,
}

impl Mark {
    fn new() -> Mark {
        Mark { rows: 0, bytes: 0, hash: sha2::Sha256::default() }
    }

    fn add(&mut self, line: &str) {
        use sha2::Digest;
        self.hash.update(line.as_bytes());
        self.hash.update(b"\n");
        self.bytes += line.len() as u64 + 1;
    }

    fn record(&self) -> SeriesRecord {
        use sha2::Digest;
        let hash = self.hash.clone().finalize().iter().map(|b| format!("{b:02x}")).collect();
        SeriesRecord { rows: self.rows, bytes: self.bytes, sha256: hash, row_at_step: false }
    }
}

/// What a time series held before a step, as a checkpoint records it: its rows before the
/// step (the header not counted), their bytes with the header's, the SHA-256 of those bytes,
/// and whether the row of the step itself had been written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SeriesRecord {
    /// Rows before the step.
    pub rows: u64,
    /// Bytes of the header and those rows.
    pub bytes: u64,
    /// SHA-256 of those bytes, in hex.
    pub sha256: String,
    /// Whether the row of the step had been written too.
    pub row_at_step: bool,
}

/// Why an earlier time series cannot be continued.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    /// The file could not be read or written.
    #[error("{0}")]
    Io(#[from] io::Error),
    /// The file is not what the checkpoint says it was: continuing it would splice other rows
    /// onto this run's.
    #[error("{0}")]
    Changed(String),
}

/// The time-series CSV, written as the run goes: every row reaches the file as it is written
/// (a crash loses no row written before it), and [`sync`](Self::sync) makes the rows durable
/// (at checkpoints), so a restart from a checkpoint finds every row up to its step. The writer
/// keeps the SHA-256 of what it wrote, so that a checkpoint can record what the file held
/// ([`record_before`](Self::record_before)) and a restart can tell an edited, cut or replaced
/// file from its own.
pub struct TimeSeriesWriter {
    path: PathBuf,
    out: BufWriter<File>,
    /// Values a row holds after the diagnostics.
    extra: usize,
    /// What has been written.
    mark: Mark,
    /// The step of the last row and what had been written before it.
    before_last: Option<(u64, Mark)>,
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
        let header = timeseries_header(extra);
        writeln!(out, "{header}")?;
        out.flush()?;
        let mut mark = Mark::new();
        mark.add(&header);
        Ok(TimeSeriesWriter { path: path.to_path_buf(), out, extra: extra.len(), mark, before_last: None })
    }

    /// Continues the series in `path` at `step`: its rows before `step` are kept, and with
    /// `keep_step` also its row of `step` itself; the later ones are dropped, and the rows
    /// written next follow them. The file is replaced atomically. Also returns whether a row
    /// of `step` was kept.
    ///
    /// With `expected` (what the checkpoint recorded), the file must hold exactly the rows it
    /// recorded before `step` (and the row of `step` if it recorded one and `keep_step`);
    /// without it, a file that is not a time series with this header starts afresh. A file
    /// with other columns, or that is missing, edited or cut short, is refused
    /// ([`ResumeError::Changed`]), naming the file, and left as it is.
    pub fn resume(
        path: &Path,
        step: u64,
        extra: &[String],
        keep_step: bool,
        expected: Option<&SeriesRecord>,
    ) -> Result<(Self, bool), ResumeError> {
        let header = timeseries_header(extra);
        let last = if keep_step { Some(step) } else { step.checked_sub(1) };
        let found = earlier_rows(path, &header, last.unwrap_or(0), extra.len());
        let file = path.display();
        let kept = match (found, expected) {
            (Earlier::Rows(rows), _) => rows,
            (Earlier::Missing, Some(r)) => {
                return Err(ResumeError::Changed(format!(
                    "{file} is missing; it held the {} rows of this run before step {step}. Restore it, or continue into another folder with --out (whose time series then starts at step {step})",
                    r.rows
                )));
            }
            (Earlier::OtherHeader(h), Some(_)) => {
                return Err(ResumeError::Changed(format!(
                    "{file} has the columns `{h}`, but this case writes `{header}`: its rows cannot be continued. Restore the case's outputs (meshes, insertions and outlets give columns), or continue into another folder with --out (whose time series then starts at step {step})"
                )));
            }
            (Earlier::Missing | Earlier::OtherHeader(_), None) => Vec::new(),
        };
        let kept: Vec<String> = if last.is_none() { Vec::new() } else { kept };
        let mut mark = Mark::new();
        mark.add(&header);
        let mut before_last = None;
        let mut before_step = None;
        for row in &kept {
            let s = row_step(row).unwrap_or(0);
            if s >= step && before_step.is_none() {
                before_step = Some(mark.record());
            }
            before_last = Some((s, mark.clone()));
            mark.add(row);
            mark.rows += 1;
        }
        let before_step = before_step.unwrap_or_else(|| mark.record());
        let step_kept = keep_step && kept.last().and_then(|r| row_step(r)) == Some(step);
        if let Some(r) = expected {
            let same =
                before_step.rows == r.rows && before_step.bytes == r.bytes && before_step.sha256 == r.sha256;
            if !same {
                return Err(ResumeError::Changed(format!(
                    "{file} was changed since the checkpoint (step {step}) was written: it holds {} rows ({} bytes) before that step, the checkpoint recorded {} rows ({} bytes){}. Restore it, or continue into another folder with --out (whose time series then starts at step {step})",
                    before_step.rows,
                    before_step.bytes,
                    r.rows,
                    r.bytes,
                    if before_step.rows == r.rows { " with other contents" } else { "" }
                )));
            }
            if keep_step && r.row_at_step && !step_kept {
                return Err(ResumeError::Changed(format!(
                    "{file} lacks the row of step {step}, which was written before the checkpoint. Restore it, or continue into another folder with --out (whose time series then starts at step {step})"
                )));
            }
        }
        write_atomic_with(path, |w| {
            writeln!(w, "{header}")?;
            kept.iter().try_for_each(|r| writeln!(w, "{r}"))
        })?;
        let out = BufWriter::new(std::fs::OpenOptions::new().append(true).open(path)?);
        let writer =
            TimeSeriesWriter { path: path.to_path_buf(), out, extra: extra.len(), mark, before_last };
        Ok((writer, step_kept))
    }

    /// Appends one row (units: s, J, count, dimensionless), with the `extra` values after the
    /// diagnostics (as many as the header's extra columns), and hands it to the file.
    pub fn write(&mut self, d: &Diagnostics, extra: &[Value]) -> io::Result<()> {
        use std::fmt::Write as _;
        debug_assert_eq!(extra.len(), self.extra, "one value a column");
        let mut row = format!(
            "{},{},{},{},{},{},{},{}",
            d.step,
            real(d.time),
            real(d.kinetic_translational),
            real(d.kinetic_rotational),
            real(d.potential),
            real(d.elastic),
            d.contacts,
            real(d.max_overlap_ratio)
        );
        for x in extra {
            let _ = write!(row, ",{x}");
        }
        writeln!(self.out, "{row}")?;
        self.out.flush()?;
        self.before_last = Some((d.step, self.mark.clone()));
        self.mark.add(&row);
        self.mark.rows += 1;
        Ok(())
    }

    /// What the file holds before the rows of `step` (see [`SeriesRecord`]), for a checkpoint
    /// of that step.
    pub fn record_before(&self, step: u64) -> SeriesRecord {
        match &self.before_last {
            Some((s, before)) if *s == step => SeriesRecord { row_at_step: true, ..before.record() },
            _ => self.mark.record(),
        }
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

/// What an earlier time series holds.
enum Earlier {
    /// No regular file there, or an empty one.
    Missing,
    /// A file whose first line is not the header (that line, cut to 200 characters).
    OtherHeader(String),
    /// Its rows up to the step asked for.
    Rows(Vec<String>),
}

/// The rows of the time series in `path` up to `last` (a step), in order, if it is a time
/// series with `header`. Read a line at a time, each line at most [`max_row`] bytes: an
/// outsized file costs no memory. A last row without its line end (cut off by a crash) is
/// dropped.
fn earlier_rows(path: &Path, header: &str, last: u64, extra: usize) -> Earlier {
    use std::io::BufRead;
    let regular = std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file() && m.len() > 0);
    let Some(file) = regular.then(|| File::open(path).ok()).flatten() else { return Earlier::Missing };
    let mut r = io::BufReader::new(file);
    let mut line = Vec::new();
    let limit = max_row(extra).max(header.len()) as u64 + 1;
    let mut next_line = |line: &mut Vec<u8>| -> Option<String> {
        line.clear();
        (&mut r).take(limit).read_until(b'\n', line).ok()?;
        line.pop_if(|c| *c == b'\n')?;
        String::from_utf8(std::mem::take(line)).ok()
    };
    match next_line(&mut line) {
        Some(h) if h == header => {}
        Some(h) => return Earlier::OtherHeader(h.chars().take(200).collect()),
        None => return Earlier::Missing,
    }
    let mut rows = Vec::new();
    while let Some(row) = next_line(&mut line) {
        if row_step(&row).is_none_or(|s| s > last) {
            break;
        }
        rows.push(row);
    }
    Earlier::Rows(rows)
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
            "{},{},{},{},{},{},{},{},{},{},{},{}\n",
            p.id[i],
            p.phase[i] + 1,
            real(x.x),
            real(x.y),
            real(x.z),
            real(p.radius[i]),
            real(v.x),
            real(v.y),
            real(v.z),
            real(w.x),
            real(w.y),
            real(w.z)
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cylinder's columns: seven each, the axial torque always among them, named as a
    /// mesh's are.
    #[test]
    fn cylinder_columns_follow_the_meshes_pattern() {
        let names: Vec<String> = ["drum 1", "drum_1"].map(String::from).into();
        let c = cylinder_columns(&names);
        let want: Vec<String> = ["fx", "fy", "fz", "tx", "ty", "tz", "t_axis"]
            .iter()
            .map(|s| format!("cylinder_drum_1_{s}"))
            .chain(
                ["fx", "fy", "fz", "tx", "ty", "tz", "t_axis"]
                    .iter()
                    .map(|s| format!("cylinder_drum_1_2_{s}")),
            )
            .collect();
        assert_eq!(c, want);
    }

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
            w.write(&d, &[Value::Real(step as f64)]).unwrap();
        }
        w.finish().unwrap();
        let rows = |p: &Path| {
            std::fs::read_to_string(p).unwrap().lines().skip(1).map(String::from).collect::<Vec<_>>()
        };
        let all = rows(&path);
        assert_eq!(all[1], "10,0e0,0e0,0e0,0e0,0e0,0,0e0,1e1");
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, true, None).unwrap();
        drop(w);
        assert!(kept);
        assert_eq!(rows(&path), all[..3]);
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, false, None).unwrap();
        drop(w);
        assert!(!kept);
        assert_eq!(rows(&path), all[..2]);
        // The row of step 20 is gone now: asked to keep it, none is kept.
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, true, None).unwrap();
        drop(w);
        assert!(!kept);
        // Other columns: another series, not continued.
        let (w, _) = TimeSeriesWriter::resume(&path, 20, &[], true, None).unwrap();
        drop(w);
        assert!(rows(&path).is_empty());
    }

    /// Counts are integers and zeros have no sign, in the time series and the snapshots.
    #[test]
    fn counts_are_integers_and_zeros_unsigned() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ts.csv");
        let extra = vec!["inserted".to_string(), "inserted_mass".to_string()];
        let mut w = TimeSeriesWriter::create(&path, &extra).unwrap();
        let d = Diagnostics { step: 3, elastic: -0.0, potential: -2.5, ..Default::default() };
        w.write(&d, &[Value::Count(200), Value::Real(-0.0)]).unwrap();
        w.write(&d, &[Value::Count(0), Value::Real(1.25e-3)]).unwrap();
        w.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(
            rows,
            ["3,0e0,0e0,0e0,-2.5e0,0e0,0,0e0,200,0e0", "3,0e0,0e0,0e0,-2.5e0,0e0,0,0e0,0,1.25e-3"]
        );
        let p = Particles::from_init(&[grainflow::state::ParticleInit {
            id: 7,
            phase: 0,
            position: Vec3::new(-0.0, 1.0, 0.0),
            velocity: Vec3::new(0.0, -0.0, -3.0),
            omega: Vec3::new(-0.0, -0.0, -0.0),
            radius: 0.5,
            density: 1.0,
        }]);
        let csv = snapshot_csv(&p);
        assert_eq!(csv.lines().nth(1), Some("7,1,0e0,1e0,0e0,5e-1,0e0,0e0,-3e0,0e0,0e0,0e0"), "{csv}");
    }

    /// A restart's time series must be what the checkpoint recorded: an edited row, a cut or
    /// a missing file, or other columns are refused, naming the file, and left as they are.
    #[test]
    fn a_changed_series_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("timeseries.csv");
        let extra: Vec<String> = Vec::new();
        let mut w = TimeSeriesWriter::create(&path, &extra).unwrap();
        let mut record = None;
        for step in [0, 10, 20, 30] {
            w.write(&Diagnostics { step, kinetic_translational: step as f64, ..Default::default() }, &[])
                .unwrap();
            if step == 20 {
                record = Some(w.record_before(20));
            }
        }
        w.finish().unwrap();
        let record = record.unwrap();
        // Closed form: the header and two rows of known bytes before step 20.
        let expected_bytes = (TIMESERIES_HEADER.len() + 1)
            + "0,0e0,0e0,0e0,0e0,0e0,0,0e0\n".len()
            + "10,0e0,1e1,0e0,0e0,0e0,0,0e0\n".len();
        assert_eq!((record.rows, record.bytes, record.row_at_step), (2, expected_bytes as u64, true));
        let original = std::fs::read_to_string(&path).unwrap();
        let refused = |text: Option<&str>, keep: bool, columns: &[String], want: &str| {
            match text {
                Some(t) => std::fs::write(&path, t).unwrap(),
                None => {
                    let _ = std::fs::remove_file(&path);
                }
            }
            let before = std::fs::read(&path).ok();
            match TimeSeriesWriter::resume(&path, 20, columns, keep, Some(&record)) {
                Err(ResumeError::Changed(m)) => {
                    assert!(m.contains("timeseries.csv") && m.contains(want), "{m}");
                }
                Err(e) => panic!("{e}"),
                Ok(_) => panic!("accepted: {text:?}"),
            }
            assert_eq!(std::fs::read(&path).ok(), before, "a refused series was changed");
        };
        refused(Some(&original.replace("1e1", "2e1")), false, &extra, "other contents");
        refused(
            Some(&original.replacen("0,0e0,0e0,0e0,0e0,0e0,0,0e0\n", "", 1)),
            false,
            &extra,
            "holds 1 rows",
        );
        refused(None, false, &extra, "is missing");
        refused(Some(&original[..original.find("20,").unwrap()]), true, &extra, "lacks the row of step 20");
        refused(Some(&original), false, &["inserted".to_string()], "has the columns");
        // The series as written continues, keeping its rows before step 20 and with them the
        // hash that the next checkpoint records.
        std::fs::write(&path, &original).unwrap();
        let (w, kept) = TimeSeriesWriter::resume(&path, 20, &extra, true, Some(&record)).unwrap();
        assert!(kept);
        assert_eq!(w.record_before(20), record);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), original[..original.find("30,").unwrap()]);
    }
}
