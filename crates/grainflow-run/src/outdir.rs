//! The output folder of a run: held by one run at a time, tied to the run that wrote it, and
//! never emptied by accident.
//!
//! - **A lock.** A run holds `.grainflow.lock` locked (an advisory lock the operating system
//!   releases when the process ends, however it ends); a second run into the same folder is
//!   refused, naming the first.
//! - **A run id.** A fresh run draws an id; a run continued from a checkpoint keeps the
//!   checkpoint's ([`grainflow::Simulation::run_id`]). `run-info.toml` and `manifest.toml`
//!   record it, so a restart can tell its own run's outputs from another's.
//! - **A manifest.** `manifest.toml` lists every file the run writes, each entry appended before
//!   the file is created: after a crash it names every file of the run.
//! - **No silent reuse.** A fresh run into a folder that holds an earlier run's results (a
//!   folder with grainflow's manifest or run record) is refused unless the caller asks to
//!   overwrite them; overwriting removes only the files that run's manifest lists, never
//!   others, and nothing through a symbolic link (a linked `snapshots/` or `vtk/` that holds
//!   listed files is refused instead). A folder that holds only the user's own files is no
//!   earlier run: a run writes beside them, unless one of them has a name grainflow would
//!   write (`timeseries.csv`, `snapshots/particles_<step>.csv`, …), which is refused.

use sha2::{Digest, Sha256};
use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// The lock file a running run holds.
pub const LOCK_FILE: &str = ".grainflow.lock";
/// The list of the files a run wrote.
pub const MANIFEST_FILE: &str = "manifest.toml";
/// What produced the outputs.
pub const RUN_INFO_FILE: &str = "run-info.toml";
/// The time series.
pub const TIMESERIES_FILE: &str = "timeseries.csv";
/// Files grainflow writes at the top of an output folder: an earlier run's if that run left a
/// run record but no manifest (an earlier version wrote none).
const KNOWN_FILES: [&str; 5] =
    [TIMESERIES_FILE, RUN_INFO_FILE, MANIFEST_FILE, "checkpoint.gfc", "checkpoint-last-good.gfc"];
/// The folders grainflow writes into (shared with the user's own files).
const KNOWN_FOLDERS: [&str; 2] = ["snapshots", "vtk"];

/// True for a path (relative to the folder) that grainflow's outputs may have: one of
/// [`KNOWN_FILES`], a snapshot `snapshots/particles_<step>.csv`, or in `vtk/` a frame
/// `<kind>_<step>.vtp` or a collection `<kind>.pvd` of the particles, the contacts or a moving
/// surface, or the file `<stem>.vtp` of a fixed one (`walls.vtp`, `meshes_fixed.vtp`,
/// `cylinders.vtp`: [`grainflow::surface::surface_kinds`]).
fn grainflow_named(rel: &Path) -> bool {
    let parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    let frame = |name: &str, kinds: &[&str], ext: &str| {
        name.strip_suffix(ext).and_then(|stem| stem.rsplit_once('_')).is_some_and(|(kind, step)| {
            kinds.contains(&kind) && step.len() == 9 && step.bytes().all(|b| b.is_ascii_digit())
        })
    };
    match parts.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        [name] => KNOWN_FILES.contains(name),
        ["snapshots", name] => frame(name, &["particles"], ".csv"),
        ["vtk", name] => {
            let surfaces = grainflow::surface::surface_kinds();
            let mut kinds = vec!["particles", "contacts"];
            kinds.extend(surfaces.iter().filter(|k| k.moves).map(|k| k.stem));
            frame(name, &kinds, ".vtp")
                || ["particles.pvd", "contacts.pvd"].contains(name)
                || surfaces.iter().any(|&k| crate::vtk::collection_or_file(k) == *name)
        }
        _ => false,
    }
}

/// The first part of `rel` (relative to `dir`: a folder on the way or the file itself) that
/// is a symbolic link, if any.
fn link_on_the_way(dir: &Path, rel: &Path) -> Option<PathBuf> {
    let mut p = PathBuf::new();
    for c in rel.components() {
        p.push(c);
        if std::fs::symlink_metadata(dir.join(&p)).is_ok_and(|m| m.file_type().is_symlink()) {
            return Some(p);
        }
    }
    None
}

/// Why a folder cannot take a run's outputs.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// Another run is writing into the folder.
    #[error(
        "{dir} is in use by another grainflow run ({holder}); wait for it to end or choose another --out"
    )]
    Busy {
        /// The folder.
        dir: PathBuf,
        /// What the lock file says of the run holding it.
        holder: String,
    },
    /// The folder holds an earlier run's results, which this run would destroy.
    #[error("{dir} holds the results of an earlier run ({earlier}); they are kept. {advice}")]
    Occupied {
        /// The folder.
        dir: PathBuf,
        /// The earlier run, in words.
        earlier: String,
        /// What the user can do.
        advice: String,
    },
    /// The folder holds files with the names grainflow writes that no manifest lists, which
    /// the run would replace.
    #[error(
        "{dir} holds files with the names grainflow writes that no grainflow manifest lists ({files}): this run would replace them, and --overwrite removes only the files a manifest lists. Move them elsewhere, or choose another --out"
    )]
    Strangers {
        /// The folder.
        dir: PathBuf,
        /// Those files, relative to it.
        files: String,
    },
    /// An earlier run's files lie behind a symbolic link, through which `--overwrite` removes
    /// nothing.
    #[error(
        "{dir}: {link} is a symbolic link, and {count} of the earlier run's files lie behind it; --overwrite removes nothing through a link (its target is not this folder's). Remove those files yourself, or choose another --out"
    )]
    Linked {
        /// The folder.
        dir: PathBuf,
        /// The link, relative to the folder.
        link: String,
        /// The earlier run's files behind it.
        count: usize,
    },
    /// The folder cannot be created, locked or written.
    #[error("cannot use {path} as the output folder: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> FolderError + '_ {
    move |source| FolderError::Io { path: path.to_path_buf(), source }
}

/// What a run is about to do with its folder.
#[derive(Debug, Clone)]
pub enum Intent<'a> {
    /// Start a new run.
    Fresh,
    /// Continue the run `run_id` (empty: unknown, a checkpoint older than run ids) from the
    /// checkpoint at `checkpoint`.
    Continue {
        /// The checkpoint's run id.
        run_id: &'a str,
        /// The checkpoint file.
        checkpoint: &'a Path,
    },
}

/// An earlier run's traces in a folder.
#[derive(Debug, Clone, Default)]
struct Earlier {
    /// Its run id, if it recorded one.
    run_id: Option<String>,
    /// Its status, if it recorded one.
    status: Option<String>,
    /// Its case file, if it recorded one.
    case: Option<String>,
    /// Files of it that are there (relative paths).
    files: Vec<PathBuf>,
    /// Files with the names grainflow writes that are there but not the earlier run's (no
    /// manifest lists them).
    strangers: Vec<PathBuf>,
}

impl Earlier {
    fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(c) = &self.case {
            parts.push(format!("case {c}"));
        }
        match self.status.as_deref() {
            Some("running") => {
                parts.push("status \"running\": it stopped without closing its outputs".into())
            }
            Some(s) => parts.push(format!("status \"{s}\"")),
            None => {}
        }
        if let Some(id) = &self.run_id {
            parts.push(format!("run id {id}"));
        }
        parts.push(format!("{} file{}", self.files.len(), if self.files.len() == 1 { "" } else { "s" }));
        parts.join(", ")
    }
}

/// Reads a small text file of the folder's own (run-info, manifest): at most 64 MiB, a regular
/// file only; anything else counts as absent.
fn read_small(path: &Path) -> Option<String> {
    let meta = std::fs::symlink_metadata(path).ok()?;
    if !meta.is_file() || meta.len() > 64 << 20 {
        return None;
    }
    std::fs::read_to_string(path).ok()
}

/// The value of a top-level `key = "value"` line of a TOML file we wrote.
fn toml_string(text: &str, key: &str) -> Option<String> {
    text.lines().find_map(|l| {
        let rest = l.strip_prefix(key)?.trim_start().strip_prefix('=')?.trim();
        toml::from_str::<toml::Value>(&format!("v = {rest}")).ok()?.get("v")?.as_str().map(str::to_string)
    })
}

/// The files an earlier run left in `dir`: those its manifest lists and its own records (or,
/// for a run of a version that wrote no manifest, the files of [`KNOWN_FILES`]), that exist;
/// and the files with grainflow's names that are not among them.
fn earlier_run(dir: &Path) -> Earlier {
    let mut e = Earlier::default();
    let mut files: Vec<PathBuf> = Vec::new();
    let info = read_small(&dir.join(RUN_INFO_FILE));
    if let Some(info) = &info {
        e.run_id = toml_string(info, "run_id");
        e.status = toml_string(info, "status");
        e.case = toml_string(info, "case_file");
    }
    match read_small(&dir.join(MANIFEST_FILE)) {
        Some(manifest) => {
            if e.run_id.is_none() {
                e.run_id = toml_string(&manifest, "run_id");
            }
            files.extend(manifest_paths(&manifest));
            files.extend([MANIFEST_FILE, RUN_INFO_FILE].map(PathBuf::from));
        }
        None if info.is_some() => files.extend(KNOWN_FILES.iter().map(PathBuf::from)),
        None => {}
    }
    files.sort();
    files.dedup();
    files.retain(|f| is_inside(f) && std::fs::symlink_metadata(dir.join(f)).is_ok());
    let mut strangers: Vec<PathBuf> = KNOWN_FILES.iter().map(PathBuf::from).collect();
    for folder in KNOWN_FOLDERS {
        if link_on_the_way(dir, Path::new(folder)).is_some() {
            continue;
        }
        if let Ok(entries) = std::fs::read_dir(dir.join(folder)) {
            strangers.extend(entries.flatten().map(|entry| Path::new(folder).join(entry.file_name())));
        }
    }
    strangers.retain(|f| {
        grainflow_named(f)
            && std::fs::symlink_metadata(dir.join(f)).is_ok()
            && files.binary_search(f).is_err()
    });
    strangers.sort();
    e.files = files;
    e.strangers = strangers;
    e
}

/// A relative path that stays inside the folder (no `..`, not absolute).
fn is_inside(p: &Path) -> bool {
    p.components().all(|c| matches!(c, std::path::Component::Normal(_)))
}

/// The `path = "…"` entries of a manifest.
fn manifest_paths(text: &str) -> Vec<PathBuf> {
    text.lines()
        .filter_map(|l| toml_string(l.trim_start(), "path"))
        .map(PathBuf::from)
        .filter(|p| is_inside(p))
        .collect()
}

/// A new run id: 16 hex digits from the clock, the process and the case.
pub fn new_run_id(case_hash: &str) -> String {
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let mut h = Sha256::new();
    h.update(nanos.to_le_bytes());
    h.update(std::process::id().to_le_bytes());
    h.update(case_hash.as_bytes());
    h.finalize().iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// The time now as `YYYY-MM-DDTHH:MM:SSZ` (UTC).
pub fn utc_now() -> String {
    utc(SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()))
}

/// `secs` after 1970-01-01T00:00:00Z as `YYYY-MM-DDTHH:MM:SSZ`.
fn utc(secs: u64) -> String {
    let (days, rest) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z", rest / 3600, rest % 3600 / 60, rest % 60)
}

/// A folder held by a run (released when dropped).
#[derive(Debug)]
pub struct OutputFolder {
    dir: PathBuf,
    run_id: String,
    /// Whether the earlier rows of the time series and the earlier frames belong to this run.
    continues: bool,
    manifest: File,
    listed: std::collections::HashSet<PathBuf>,
    /// Held for the run: the lock goes with it.
    _lock: File,
}

impl OutputFolder {
    /// Takes `dir` for a run (creating it), as [`Intent`] says, or says why not. A fresh run
    /// gets a new id drawn from `case_hash`. With `overwrite`, an earlier run's files are
    /// removed first (a checkpoint being continued from is kept).
    pub fn claim(
        dir: &Path,
        intent: &Intent,
        overwrite: bool,
        case: &str,
        case_hash: &str,
    ) -> Result<OutputFolder, FolderError> {
        if dir.exists() && !dir.is_dir() {
            return Err(FolderError::Io {
                path: dir.to_path_buf(),
                source: io::Error::other("it exists and is not a folder"),
            });
        }
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let lock_path = dir.join(LOCK_FILE);
        let lock = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&lock_path)
            .map_err(io_err(&lock_path))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let holder = read_small(&lock_path)
                    .map(|t| t.trim().replace('\n', ", "))
                    .filter(|t| !t.is_empty())
                    .unwrap_or_else(|| "it is starting".into());
                return Err(FolderError::Busy { dir: dir.to_path_buf(), holder });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io_err(&lock_path)(e)),
        }
        remove_temporaries(dir)?;
        let earlier = earlier_run(dir);
        let (run_id, continues, keep) = match intent {
            Intent::Fresh => (new_run_id(case_hash), false, None),
            Intent::Continue { run_id, checkpoint, .. } => {
                let same_run = match (&earlier.run_id, run_id.is_empty()) {
                    (Some(id), false) => id == run_id,
                    // A checkpoint older than run ids: its rows can be told apart only by
                    // where it lives.
                    (None, true) => same_folder(checkpoint, dir),
                    _ => false,
                };
                let id = if run_id.is_empty() { new_run_id(case_hash) } else { run_id.to_string() };
                (id, same_run, Some(*checkpoint))
            }
        };
        if !continues && !earlier.files.is_empty() {
            if !overwrite {
                let advice = match intent {
                    Intent::Fresh => {
                        let checkpoint = dir.join("checkpoint.gfc");
                        let unfinished =
                            earlier.status.as_deref() != Some("completed") && checkpoint.is_file();
                        if unfinished {
                            format!(
                                "Choose another --out, add --overwrite to replace them, or continue that run with --restart {}",
                                checkpoint.display()
                            )
                        } else {
                            "Choose another --out, or add --overwrite to replace them".to_string()
                        }
                    }
                    Intent::Continue { .. } => format!(
                        "The checkpoint belongs to another run{}. Continue in the checkpoint's own folder (the default without --out) or an empty one, or add --overwrite to replace them",
                        match intent {
                            Intent::Continue { run_id, .. } if !run_id.is_empty() =>
                                format!(" (run id {run_id})"),
                            _ => String::new(),
                        }
                    ),
                };
                return Err(FolderError::Occupied {
                    dir: dir.to_path_buf(),
                    earlier: earlier.describe(),
                    advice,
                });
            }
            remove_files(dir, &earlier.files, keep)?;
        }
        if !continues {
            // Files with grainflow's names that no manifest lists: another run's, copied here,
            // or the user's. The run would replace them; --overwrite does not remove them.
            let keep = keep.and_then(|k| k.canonicalize().ok());
            let strangers: Vec<String> = earlier
                .strangers
                .iter()
                .filter(|f| keep.is_none() || dir.join(f).canonicalize().ok() != keep)
                .map(|f| f.display().to_string())
                .collect();
            if !strangers.is_empty() {
                let shown = strangers.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
                let more = if strangers.len() > 5 {
                    format!(" and {} more", strangers.len() - 5)
                } else {
                    String::new()
                };
                return Err(FolderError::Strangers {
                    dir: dir.to_path_buf(),
                    files: format!("{shown}{more}"),
                });
            }
        }
        let manifest_path = dir.join(MANIFEST_FILE);
        let mut listed = std::collections::HashSet::new();
        let manifest = if continues && manifest_path.exists() {
            if let Some(text) = read_small(&manifest_path) {
                listed.extend(manifest_paths(&text));
            }
            OpenOptions::new().append(true).open(&manifest_path).map_err(io_err(&manifest_path))?
        } else {
            let mut f = File::create(&manifest_path).map_err(io_err(&manifest_path))?;
            writeln!(
                f,
                "# The files grainflow run wrote into this folder (paths relative to it), each listed\n# before it was first written.\nrun_id = \"{run_id}\""
            )
            .map_err(io_err(&manifest_path))?;
            f
        };
        let mut lock = lock;
        // Who holds the folder, for a second run's message.
        let _ = lock.set_len(0);
        let _ =
            write!(lock, "pid {}\nrun id {run_id}\ncase {case}\nstarted {}\n", std::process::id(), utc_now());
        let mut folder =
            OutputFolder { dir: dir.to_path_buf(), run_id, continues, manifest, listed, _lock: lock };
        folder.record(Path::new(MANIFEST_FILE))?;
        Ok(folder)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The run's id.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// True when the folder's earlier outputs belong to the run being continued, so the rows
    /// and frames before the checkpoint are kept.
    pub fn continues(&self) -> bool {
        self.continues
    }

    /// True if the manifest lists `file` (relative to the folder): a file of this run (or of
    /// the run it continues).
    pub fn lists(&self, file: &Path) -> bool {
        self.listed.contains(file)
    }

    /// Lists `file` (relative to the folder) in the manifest, once; call before writing it.
    pub fn record(&mut self, file: &Path) -> Result<(), FolderError> {
        if self.listed.contains(file) {
            return Ok(());
        }
        let path = self.dir.join(MANIFEST_FILE);
        // One write per entry: a crash leaves whole entries.
        let entry = format!("[[file]]\npath = {}\n", toml::Value::String(file.display().to_string()));
        self.manifest.write_all(entry.as_bytes()).map_err(io_err(&path))?;
        self.listed.insert(file.to_path_buf());
        Ok(())
    }

    /// Makes the manifest durable (at checkpoints and at the end).
    pub fn sync(&self) -> Result<(), FolderError> {
        self.manifest.sync_data().map_err(io_err(&self.dir.join(MANIFEST_FILE)))
    }
}

/// A temporary file of an atomic write (`NAME.partial-PID`) or the rolling copy of the last
/// good state: a run that holds the folder owns them, and one that died left them.
fn is_temporary(name: &str) -> bool {
    name.contains(".partial-") || (name.starts_with('.') && name.ends_with(".rolling"))
}

/// Removes the temporary files a run that died left in the folder (the lock is held: no
/// living run is writing them).
fn remove_temporaries(dir: &Path) -> Result<(), FolderError> {
    for sub in std::iter::once("").chain(KNOWN_FOLDERS) {
        if !sub.is_empty() && link_on_the_way(dir, Path::new(sub)).is_some() {
            continue;
        }
        let Ok(entries) = std::fs::read_dir(dir.join(sub)) else { continue };
        for entry in entries.flatten() {
            if is_temporary(&entry.file_name().to_string_lossy())
                && entry.file_type().is_ok_and(|t| t.is_file())
            {
                let path = entry.path();
                std::fs::remove_file(&path).map_err(io_err(&path))?;
            }
        }
    }
    Ok(())
}

/// True when `file` lies in `dir`.
fn same_folder(file: &Path, dir: &Path) -> bool {
    let parent = file.parent().map(|p| if p.as_os_str().is_empty() { Path::new(".") } else { p });
    match (parent.and_then(|p| p.canonicalize().ok()), dir.canonicalize().ok()) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    }
}

/// Removes an earlier run's files (all but `keep`), then the folders grainflow writes into if
/// they are left empty. Nothing is removed through a symbolic link: if one of the files lies
/// behind one (or is one), nothing is removed and the folder is refused.
fn remove_files(dir: &Path, files: &[PathBuf], keep: Option<&Path>) -> Result<(), FolderError> {
    let linked: Vec<PathBuf> = files.iter().filter_map(|f| link_on_the_way(dir, f)).collect();
    if let Some(link) = linked.first() {
        return Err(FolderError::Linked {
            dir: dir.to_path_buf(),
            link: link.display().to_string(),
            count: linked.iter().filter(|l| *l == link).count(),
        });
    }
    let keep = keep.and_then(|k| k.canonicalize().ok());
    for f in files {
        let path = dir.join(f);
        if keep.is_some() && path.canonicalize().ok() == keep {
            continue;
        }
        match std::fs::remove_file(&path) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(io_err(&path)(e)),
        }
    }
    for folder in KNOWN_FOLDERS {
        let _ = std::fs::remove_dir(dir.join(folder));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claim(dir: &Path, intent: &Intent, overwrite: bool) -> Result<OutputFolder, FolderError> {
        OutputFolder::claim(dir, intent, overwrite, "case.toml", "hash")
    }

    #[test]
    fn a_second_run_is_refused_while_the_first_holds_the_folder() {
        let d = tempfile::tempdir().unwrap();
        let first = claim(d.path(), &Intent::Fresh, false).expect("empty folder");
        let e = claim(d.path(), &Intent::Fresh, true).expect_err("held");
        let msg = e.to_string();
        assert!(matches!(e, FolderError::Busy { .. }), "{msg}");
        assert!(msg.contains(&format!("pid {}", std::process::id())), "{msg}");
        assert!(msg.contains(first.run_id()), "{msg}");
        drop(first);
        // Released with the run; the folder now holds that run's manifest.
        claim(d.path(), &Intent::Fresh, true).expect("free again");
    }

    #[test]
    fn an_earlier_run_is_kept_unless_overwriting_removes_only_its_files() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path();
        let mut run = claim(dir, &Intent::Fresh, false).unwrap();
        for f in
            ["timeseries.csv", "snapshots/particles_000000000.csv", "vtk/particles.pvd", "checkpoint.gfc"]
        {
            run.record(Path::new(f)).unwrap();
        }
        drop(run);
        std::fs::create_dir(dir.join("snapshots")).unwrap();
        std::fs::create_dir(dir.join("vtk")).unwrap();
        let users =
            ["notes.txt", "snapshots/my-plot-data.csv", "vtk/my-state.pvsm", "snapshots/particles_1.csv"];
        for f in
            ["timeseries.csv", "snapshots/particles_000000000.csv", "vtk/particles.pvd", "checkpoint.gfc"]
                .iter()
                .chain(&users)
        {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        let e = claim(dir, &Intent::Fresh, false).expect_err("earlier results");
        assert!(matches!(e, FolderError::Occupied { .. }), "{e}");
        assert!(e.to_string().contains("5 files"), "the manifest's 4 and itself: {e}");
        assert!(dir.join("timeseries.csv").exists());
        let _new = claim(dir, &Intent::Fresh, true).expect("overwrite");
        for gone in
            ["timeseries.csv", "snapshots/particles_000000000.csv", "vtk/particles.pvd", "checkpoint.gfc"]
        {
            assert!(!dir.join(gone).exists(), "{gone} left behind");
        }
        for f in users {
            assert_eq!(std::fs::read_to_string(dir.join(f)).unwrap(), "x", "the user's {f} removed");
        }
    }

    /// `--overwrite` removes nothing through a symbolic link: an earlier run's snapshots behind
    /// a linked `snapshots/` are kept, the run is refused naming the link, and nothing else in
    /// the folder is removed either.
    #[cfg(unix)]
    #[test]
    fn overwriting_never_follows_a_link() {
        let d = tempfile::tempdir().unwrap();
        let (dir, elsewhere) = (d.path().join("out"), d.path().join("elsewhere"));
        std::fs::create_dir_all(&elsewhere).unwrap();
        let mut run = claim(&dir, &Intent::Fresh, false).unwrap();
        run.record(Path::new("timeseries.csv")).unwrap();
        run.record(Path::new("snapshots/particles_000000000.csv")).unwrap();
        drop(run);
        std::os::unix::fs::symlink(&elsewhere, dir.join("snapshots")).unwrap();
        std::fs::write(elsewhere.join("particles_000000000.csv"), "theirs").unwrap();
        std::fs::write(dir.join("timeseries.csv"), "rows").unwrap();
        let e = claim(&dir, &Intent::Fresh, true).expect_err("a linked folder");
        assert!(matches!(e, FolderError::Linked { .. }), "{e}");
        assert!(
            e.to_string().contains("snapshots is a symbolic link, and 1 of the earlier run's files"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(elsewhere.join("particles_000000000.csv")).unwrap(), "theirs");
        assert!(dir.join("timeseries.csv").exists() && dir.join("manifest.toml").exists());
    }

    /// A folder holding only the user's own files is no earlier run: a run writes beside them.
    /// One of them with a name grainflow writes is refused, with or without --overwrite, and
    /// without recommending it.
    #[test]
    fn a_folder_of_the_users_own_files_is_no_earlier_run() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path();
        std::fs::create_dir(dir.join("snapshots")).unwrap();
        std::fs::write(dir.join("snapshots/my-plot-data.csv"), "mine").unwrap();
        let run = claim(dir, &Intent::Fresh, false).expect("the user's files only");
        drop(run);
        assert_eq!(std::fs::read_to_string(dir.join("snapshots/my-plot-data.csv")).unwrap(), "mine");
        let d = tempfile::tempdir().unwrap();
        let dir = d.path();
        std::fs::create_dir(dir.join("snapshots")).unwrap();
        std::fs::write(dir.join("snapshots/particles_000001000.csv"), "copied").unwrap();
        for overwrite in [false, true] {
            let e = claim(dir, &Intent::Fresh, overwrite).expect_err("a file grainflow would replace");
            let msg = e.to_string();
            assert!(matches!(e, FolderError::Strangers { .. }), "{msg}");
            assert!(
                msg.contains("snapshots/particles_000001000.csv") && !msg.contains("add --overwrite"),
                "{msg}"
            );
        }
        assert_eq!(std::fs::read_to_string(dir.join("snapshots/particles_000001000.csv")).unwrap(), "copied");
    }

    /// The VTK names come from the surfaces' kinds: each fixed surface's file (the cylinders'
    /// among them), a moving one's frames and collection; a fixed surface has no frames, and a
    /// name of no kind is the user's.
    #[test]
    fn vtk_names_follow_the_surface_kinds() {
        for ours in [
            "vtk/walls.vtp",
            "vtk/meshes_fixed.vtp",
            "vtk/cylinders.vtp",
            "vtk/meshes.pvd",
            "vtk/meshes_000000040.vtp",
            "vtk/particles_000000040.vtp",
            "vtk/contacts.pvd",
        ] {
            assert!(grainflow_named(Path::new(ours)), "{ours}");
        }
        for theirs in
            ["vtk/walls_000000040.vtp", "vtk/cylinders.pvd", "vtk/meshes.vtp", "vtk/rods.vtp", "walls.vtp"]
        {
            assert!(!grainflow_named(Path::new(theirs)), "{theirs}");
        }
    }

    #[test]
    fn a_restart_continues_only_its_own_run() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path();
        let mut run = claim(dir, &Intent::Fresh, false).unwrap();
        let id = run.run_id().to_string();
        run.record(Path::new("timeseries.csv")).unwrap();
        run.record(Path::new("checkpoint.gfc")).unwrap();
        drop(run);
        std::fs::write(dir.join("timeseries.csv"), "rows").unwrap();
        let ckpt = dir.join("checkpoint.gfc");
        std::fs::write(&ckpt, "state").unwrap();
        let own = Intent::Continue { run_id: &id, checkpoint: &ckpt };
        let cont = claim(dir, &own, false).expect("its own run");
        assert!(cont.continues());
        assert_eq!(cont.run_id(), id);
        drop(cont);
        let other = Intent::Continue { run_id: "0123456789abcdef", checkpoint: &ckpt };
        let e = claim(dir, &other, false).expect_err("another run's folder");
        assert!(e.to_string().contains("another run (run id 0123456789abcdef)"), "{e}");
        // Overwriting keeps the checkpoint continued from.
        let over = claim(dir, &other, true).expect("overwrite");
        assert!(!over.continues());
        assert!(ckpt.exists() && !dir.join("timeseries.csv").exists());
    }

    #[test]
    fn utc_dates_are_civil_dates() {
        // Reference values from `date -u -d @SECS`.
        assert_eq!(utc(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc(1_700_000_000), "2023-11-14T22:13:20Z");
        assert_eq!(utc(4_107_542_399), "2100-02-28T23:59:59Z");
    }
}
