//! The one place where input files are opened: case files, MFIX decks, `--motion` files and
//! particle files all come through here.
//!
//! Every path is checked before anything is read: only a regular file is accepted (a FIFO, a
//! character device such as `/dev/zero` or `/dev/urandom`, a directory or a socket is
//! refused with a message), and a file above the size limit of its kind is refused. Small
//! files (case files, decks, motion files) are read whole, at most their limit even when the
//! file grows or its reported size is wrong (`/proc` files report 0); particle files are
//! streamed line by line ([`Stream`]), every line at most [`MAX_LINE_BYTES`] long, so that
//! a reader holds only the particles it has accepted so far. A UTF-8 byte-order mark at the
//! start is skipped, in every kind.

use crate::error::CaseError;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// What a file is, for its size limit and its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A TOML case file.
    CaseFile,
    /// An MFIX deck (`mfix.dat`, `*.mfx`).
    Deck,
    /// A `--motion` TOML file beside a deck.
    Motion,
    /// A particle file (`particle_input.dat`, CSV, LAMMPS data).
    Particles,
}

/// Largest case file, MFIX deck or motion file: 4 MiB. The largest deck of MFIX's tutorials
/// and tests is about 60 KB; a case file lists particles inline only for small beds (a
/// particle table line is about 80 bytes, so 4 MiB holds some 50 000 of them).
pub const MAX_TEXT_BYTES: u64 = 4 << 20;

/// Largest particle file: 4 GiB. A particle line is 40-150 bytes, so this holds 10⁷
/// particles in any of the formats with room to spare; above it the run would not fit a
/// workstation's memory anyway.
pub const MAX_PARTICLE_FILE_BYTES: u64 = 4 << 30;

/// Longest line of a particle file: 64 KiB (a particle line is at most a few hundred bytes).
pub const MAX_LINE_BYTES: usize = 64 << 10;

impl Kind {
    fn limit(self) -> u64 {
        match self {
            Kind::CaseFile | Kind::Deck | Kind::Motion => MAX_TEXT_BYTES,
            Kind::Particles => MAX_PARTICLE_FILE_BYTES,
        }
    }

    fn what(self) -> &'static str {
        match self {
            Kind::CaseFile => "a case file",
            Kind::Deck => "an MFIX deck",
            Kind::Motion => "a motion file",
            Kind::Particles => "a particle file",
        }
    }
}

fn read_err(path: &Path, source: std::io::Error) -> CaseError {
    CaseError::Read { path: path.to_path_buf(), source }
}

fn refuse(path: &Path, why: String) -> CaseError {
    read_err(path, std::io::Error::new(std::io::ErrorKind::InvalidInput, why))
}

fn show_size(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else if bytes >= 1 << 20 {
        format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
    } else {
        format!("{bytes} bytes")
    }
}

/// Opens `path` if it is a regular file within the size limit of `kind`.
pub fn open(path: &Path, kind: Kind) -> Result<std::fs::File, CaseError> {
    // The type is checked on the opened file (no window between a check and the open), and
    // opening a FIFO for reading blocks until a writer appears: so the path's type is looked
    // at first, without opening it, and again after.
    let meta = std::fs::metadata(path).map_err(|e| read_err(path, e))?;
    check_type(path, &meta, kind)?;
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    let meta = file.metadata().map_err(|e| read_err(path, e))?;
    check_type(path, &meta, kind)?;
    if meta.len() > kind.limit() {
        return Err(refuse(
            path,
            format!(
                "the file has {}, more than {} can be ({}); see docs/case-file.md, \"Input limits\"",
                show_size(meta.len()),
                kind.what(),
                show_size(kind.limit())
            ),
        ));
    }
    Ok(file)
}

fn check_type(path: &Path, meta: &std::fs::Metadata, kind: Kind) -> Result<(), CaseError> {
    if meta.is_file() {
        return Ok(());
    }
    let ft = meta.file_type();
    let what = if ft.is_dir() {
        "a directory".to_string()
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if ft.is_fifo() {
                "a named pipe (FIFO)".to_string()
            } else if ft.is_char_device() {
                "a character device".to_string()
            } else if ft.is_block_device() {
                "a block device".to_string()
            } else if ft.is_socket() {
                "a socket".to_string()
            } else {
                "not a regular file".to_string()
            }
        }
        #[cfg(not(unix))]
        {
            "not a regular file".to_string()
        }
    };
    Err(refuse(path, format!("this is {what}, not a regular file; {} must be a regular file", kind.what())))
}

/// Reads a small text file whole (case file, deck, motion file): regular, at most its kind's
/// limit even if the file grows while read, UTF-8, a leading byte-order mark removed.
pub fn read_text(path: &Path, kind: Kind) -> Result<String, CaseError> {
    let file = open(path, kind)?;
    let limit = kind.limit();
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| read_err(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(refuse(
            path,
            format!("the file is larger than {} can be ({})", kind.what(), show_size(limit)),
        ));
    }
    text_of(bytes)
        .map_err(|at| refuse(path, format!("the file is not UTF-8 text (invalid byte at offset {at})")))
}

/// Text of `bytes` without a leading UTF-8 byte-order mark; the error is the offset of the
/// first invalid byte.
pub fn text_of(mut bytes: Vec<u8>) -> Result<String, usize> {
    if bytes.starts_with(BOM) {
        bytes.drain(..BOM.len());
    }
    String::from_utf8(bytes).map_err(|e| e.utf8_error().valid_up_to())
}

/// `text` without a leading byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

const BOM: &[u8] = b"\xef\xbb\xbf";

/// A particle file opened for streaming, with its name for messages.
pub struct Stream<'a> {
    reader: Box<dyn BufRead + 'a>,
    /// How the file is named in messages (as written in the case).
    pub name: String,
    line: usize,
    buf: Vec<u8>,
    started: bool,
    /// Bytes since the last line end, when read as bytes (`Read`).
    run: usize,
}

/// Opens a file named in a case (a particle file), relative to wherever the case came from.
pub type Opener<'a> = dyn Fn(&str) -> Result<Box<dyn BufRead>, CaseError> + 'a;

/// An [`Opener`] of files in the folder `dir` (particle files beside a case or deck).
pub fn open_beside(dir: &Path) -> impl Fn(&str) -> Result<Box<dyn BufRead>, CaseError> + '_ {
    move |name: &str| {
        let file = open(&dir.join(name), Kind::Particles)?;
        Ok(Box::new(BufReader::with_capacity(1 << 16, file)) as Box<dyn BufRead>)
    }
}

/// How the files a case names reach its reader, given the file's name and how to open it
/// here: an identity in one process; over ranks, one process opens each file and passes its
/// bytes on to the others, which never open it (see `grainflow_run::relay`).
pub type Relay<'a> = dyn Fn(&str, &OpenHere<'_>) -> Result<Box<dyn BufRead>, CaseError> + 'a;

/// Opens one file where the case is read (what a [`Relay`] is given).
pub type OpenHere<'a> = dyn Fn() -> Result<Box<dyn BufRead>, CaseError> + 'a;

/// The [`Relay`] of one process: each file opened where it is read.
pub fn direct(_name: &str, open: &OpenHere<'_>) -> Result<Box<dyn BufRead>, CaseError> {
    open()
}

/// `open` with every file passed through `relay`.
pub fn relayed<'a>(
    open: &'a Opener<'a>,
    relay: &'a Relay<'a>,
) -> impl Fn(&str) -> Result<Box<dyn BufRead>, CaseError> + 'a {
    move |name: &str| relay(name, &|| open(name))
}

/// An [`Opener`] over a function that returns a file's text (tests, fuzzing, the library's
/// in-memory entry points).
pub fn open_text<'a>(
    read_file: &'a dyn Fn(&str) -> Result<String, CaseError>,
) -> impl Fn(&str) -> Result<Box<dyn BufRead>, CaseError> + 'a {
    move |name: &str| {
        let text = read_file(name)?;
        Ok(Box::new(std::io::Cursor::new(text.into_bytes())) as Box<dyn BufRead>)
    }
}

impl Read for Stream<'_> {
    /// The bytes as they are (after a leading byte-order mark), with the line-length cap.
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if !self.started {
            self.started = true;
            let head = self.reader.fill_buf()?;
            if head.starts_with(BOM) {
                self.reader.consume(BOM.len());
            }
        }
        let n = self.reader.read(out)?;
        for &b in &out[..n] {
            if b == b'\n' {
                self.run = 0;
            } else {
                self.run += 1;
                if self.run > MAX_LINE_BYTES {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!(
                            "a line is longer than {MAX_LINE_BYTES} bytes (a particle line has a few hundred at most); is this a particle file?"
                        ),
                    ));
                }
            }
        }
        Ok(n)
    }
}

impl<'a> Stream<'a> {
    /// A stream over any reader (a file, or text in memory).
    pub fn new(reader: impl BufRead + 'a, name: impl Into<String>) -> Self {
        Stream {
            reader: Box::new(reader),
            name: name.into(),
            line: 0,
            buf: Vec::new(),
            started: false,
            run: 0,
        }
    }

    /// A stream over text in memory.
    pub fn from_text(text: &'a str, name: impl Into<String>) -> Self {
        Stream::new(text.as_bytes(), name)
    }

    /// Opens a particle file (regular, within [`MAX_PARTICLE_FILE_BYTES`]).
    pub fn open(path: &Path, name: impl Into<String>) -> Result<Stream<'static>, CaseError> {
        let file = open(path, Kind::Particles)?;
        Ok(Stream::new(BufReader::with_capacity(1 << 16, file), name))
    }

    fn err(&self, line: usize, message: String) -> CaseError {
        CaseError::ParticleFile { path: self.name.clone(), line, message }
    }

    /// The next line (1-based number, text without its line end), or `None` at the end. A
    /// line longer than [`MAX_LINE_BYTES`] or not UTF-8 is an error naming it.
    pub fn next_line(&mut self) -> Result<Option<(usize, &str)>, CaseError> {
        self.buf.clear();
        let n = (&mut self.reader)
            .take(MAX_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| self.err(self.line + 1, format!("cannot read: {e}")))?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        if self.buf.len() > MAX_LINE_BYTES && self.buf.last() != Some(&b'\n') {
            return Err(self.err(
                self.line,
                format!(
                    "the line is longer than {MAX_LINE_BYTES} bytes (a particle line has a few hundred at most); is this a particle file?"
                ),
            ));
        }
        if !self.started {
            self.started = true;
            if self.buf.starts_with(BOM) {
                self.buf.drain(..BOM.len());
            }
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        let line = self.line;
        match std::str::from_utf8(&self.buf) {
            Ok(s) => Ok(Some((line, s))),
            Err(e) => Err(CaseError::ParticleFile {
                path: self.name.clone(),
                line,
                message: format!(
                    "the line is not UTF-8 text (invalid byte at column {}); is this a particle file?",
                    e.valid_up_to() + 1
                ),
            }),
        }
    }

    /// Lines read so far.
    pub fn lines_read(&self) -> usize {
        self.line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused() {
        for p in ["/dev/zero", "/dev/null", "/dev/urandom"] {
            let path = Path::new(p);
            if !path.exists() {
                continue;
            }
            let e = read_text(path, Kind::CaseFile).expect_err(p).to_string();
            assert!(e.contains("character device, not a regular file"), "{e}");
            let e = Stream::open(path, p).err().expect(p).to_string();
            assert!(e.contains("character device"), "{e}");
        }
        let dir = tempfile::tempdir().unwrap();
        let e = read_text(dir.path(), Kind::Deck).expect_err("a directory").to_string();
        assert!(e.contains("a directory, not a regular file"), "{e}");
    }

    #[test]
    fn text_limits_and_byte_order_marks() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.toml");
        // One byte over the limit is refused; the limit itself is read.
        std::fs::write(&p, vec![b'#'; MAX_TEXT_BYTES as usize + 1]).unwrap();
        let e = read_text(&p, Kind::CaseFile).expect_err("too large").to_string();
        assert!(e.contains("4.0 MiB"), "{e}");
        std::fs::write(&p, vec![b'#'; MAX_TEXT_BYTES as usize]).unwrap();
        assert_eq!(read_text(&p, Kind::CaseFile).expect("at the limit").len(), MAX_TEXT_BYTES as usize);
        std::fs::write(&p, b"\xef\xbb\xbfversion = 1\n").unwrap();
        assert_eq!(read_text(&p, Kind::CaseFile).unwrap(), "version = 1\n");
        std::fs::write(&p, b"a\xff").unwrap();
        let e = read_text(&p, Kind::CaseFile).expect_err("not UTF-8").to_string();
        assert!(e.contains("offset 1"), "{e}");
    }

    #[test]
    fn stream_lines() {
        let long = "1 ".repeat(MAX_LINE_BYTES);
        let text = format!("\u{feff}a b\r\n\nc\n{long}\n");
        let mut s = Stream::from_text(&text, "t.dat");
        assert_eq!(s.next_line().unwrap(), Some((1, "a b")));
        assert_eq!(s.next_line().unwrap(), Some((2, "")));
        assert_eq!(s.next_line().unwrap(), Some((3, "c")));
        let e = s.next_line().expect_err("too long").to_string();
        assert!(e.starts_with("t.dat, line 4: the line is longer than 65536 bytes"), "{e}");
        // A line of exactly the limit, with its line end, is read.
        let exact = format!("{}\nx", "2".repeat(MAX_LINE_BYTES));
        let mut s = Stream::from_text(&exact, "t.dat");
        assert_eq!(s.next_line().unwrap().map(|l| l.1.len()), Some(MAX_LINE_BYTES));
        assert_eq!(s.next_line().unwrap(), Some((2, "x")));
        assert_eq!(s.next_line().unwrap(), None);
    }
}
