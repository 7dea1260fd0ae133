//! A key-frame table: a factor that varies in time, given at key times and interpolated
//! between them, in MFIX's key-frame file format (its tutorials' `data_kf_NNNN.txt`, read by
//! `read_keyframe_data` and evaluated by `interpolate_keyframe_data` in their `usr_mod.f`).
//!
//! The file:
//! ```text
//! 4, 1          <- number of rows, number of variables
//! linear        <- 'linear' or 'step'
//! ! time var1   <- one header line, ignored
//! 0.0    0.0    <- rows: a time and the variables, separated by commas or blanks
//! 0.5   20.0
//! ...
//! ```
//!
//! Its value at t ([`KeyFrames::value`]), as MFIX's: at or before the first time, the first
//! row's; at or after the last, the last row's; between, with tᵢ < t ≤ tᵢ₊₁, the linear
//! interpolation between rows i and i + 1 (`linear`) or row i's value (`step`). So a pair of
//! rows with the same time is a jump, the value at that time being the first row's (the
//! interpolation is continuous from the left).

use thiserror::Error;

/// The most rows a key-frame file may declare.
pub const MAX_ROWS: usize = 1_000_000;
/// The most variables a key-frame file may declare.
pub const MAX_VARS: usize = 1_000;

/// How a key-frame table is interpolated between its key times.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// Linearly between the bracketing rows.
    Linear,
    /// The earlier row's value (a staircase).
    Step,
}

/// A refused key-frame table: what is wrong and, for a file, on which line (1-based).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{}{message}", line.map_or(String::new(), |l| format!("line {l}: ")))]
pub struct KeyFrameError {
    pub line: Option<usize>,
    pub message: String,
}

impl KeyFrameError {
    fn at(line: usize, message: impl Into<String>) -> KeyFrameError {
        KeyFrameError { line: Some(line), message: message.into() }
    }
    fn table(message: impl Into<String>) -> KeyFrameError {
        KeyFrameError { line: None, message: message.into() }
    }
}

/// One variable of a key-frame table as a function of time: key times (finite,
/// non-decreasing, at least one) and the values there (finite), interpolated by
/// `interpolation`.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyFrames {
    times: Vec<f64>,
    values: Vec<f64>,
    interpolation: Interpolation,
}

impl KeyFrames {
    /// A table of `values` at `times`, validated: as many values as times, at least one row,
    /// finite times in non-decreasing order, finite values.
    pub fn new(
        times: Vec<f64>,
        values: Vec<f64>,
        interpolation: Interpolation,
    ) -> Result<KeyFrames, KeyFrameError> {
        if times.is_empty() {
            return Err(KeyFrameError::table("a key-frame table needs at least one row"));
        }
        if times.len() != values.len() {
            return Err(KeyFrameError::table(format!(
                "{} times but {} values: a key-frame table needs one value per time",
                times.len(),
                values.len()
            )));
        }
        if let Some(i) = times.iter().position(|t| !t.is_finite()) {
            return Err(KeyFrameError::table(format!("row {}: the time {} is not finite", i + 1, times[i])));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(KeyFrameError::table(format!(
                "row {}: the value {} is not finite",
                i + 1,
                values[i]
            )));
        }
        if let Some(i) = (1..times.len()).find(|&i| times[i] < times[i - 1]) {
            return Err(KeyFrameError::table(format!(
                "row {}: the time {} is before the previous row's {}: times must not decrease",
                i + 1,
                times[i],
                times[i - 1]
            )));
        }
        Ok(KeyFrames { times, values, interpolation })
    }

    /// A constant table: `value` at every time.
    pub fn constant(value: f64) -> Result<KeyFrames, KeyFrameError> {
        KeyFrames::new(vec![0.0], vec![value], Interpolation::Linear)
    }

    /// Column `column` (1-based: the first variable after the time) of a table in MFIX's
    /// key-frame file format (see the [module](self)). Numbers are read as Fortran's
    /// list-directed input reads them: separated by commas and/or blanks, with `d` or `D`
    /// allowed as the exponent letter. The interpolation's name may be quoted and in any case.
    /// Each row is one line with the time and exactly the declared number of variables;
    /// blank lines are skipped; the rows present must be as many as declared. A file that
    /// declares more than [`MAX_ROWS`] rows or [`MAX_VARS`] variables is refused before
    /// anything is allocated for them.
    pub fn from_mfix(text: &str, column: usize) -> Result<KeyFrames, KeyFrameError> {
        let mut lines =
            text.lines().enumerate().map(|(i, l)| (i + 1, l)).filter(|(_, l)| !l.trim().is_empty());
        let end = text.lines().count().max(1);
        let mut next = |what: &str| {
            lines.next().ok_or_else(|| KeyFrameError::at(end, format!("the file ends before {what}")))
        };

        // Counts.
        let (line, counts) = next("its first line (the number of rows and of variables)")?;
        let counts = fields(counts);
        if counts.len() != 2 {
            return Err(KeyFrameError::at(
                line,
                format!(
                    "expected the number of rows and the number of variables (as `4, 1`), found {} value(s)",
                    counts.len()
                ),
            ));
        }
        let count = |s: &str, what: &str, max: usize| -> Result<usize, KeyFrameError> {
            let n: u64 = s.parse().map_err(|_| {
                KeyFrameError::at(
                    line,
                    format!("the number of {what} `{s}` is not a non-negative whole number"),
                )
            })?;
            if n == 0 || n > max as u64 {
                return Err(KeyFrameError::at(
                    line,
                    format!("the number of {what} {n} must be from 1 to {max}"),
                ));
            }
            Ok(n as usize)
        };
        let nrows = count(counts[0], "rows", MAX_ROWS)?;
        let nvars = count(counts[1], "variables", MAX_VARS)?;
        if column == 0 || column > nvars {
            return Err(KeyFrameError::at(
                line,
                format!("the file has {nvars} variable(s): column {column} is not one of 1 to {nvars}"),
            ));
        }

        // Interpolation.
        let (line, method) = next("its second line (`linear` or `step`)")?;
        let method = method.trim();
        let word = fields(method).first().map(|w| w.trim_matches(|c| c == '\'' || c == '"')).unwrap_or("");
        let interpolation = if word.eq_ignore_ascii_case("linear") {
            Interpolation::Linear
        } else if word.eq_ignore_ascii_case("step") {
            Interpolation::Step
        } else {
            return Err(KeyFrameError::at(
                line,
                format!("the interpolation `{method}` is not `linear` or `step`"),
            ));
        };

        // The header, ignored.
        next("its header line")?;

        // Rows, grown as they are read (never sized by the declared count alone).
        let mut times = Vec::with_capacity(nrows.min(4096));
        let mut values = Vec::with_capacity(nrows.min(4096));
        let mut last = (0, -f64::INFINITY);
        for (line, row) in lines {
            if times.len() == nrows {
                return Err(KeyFrameError::at(
                    line,
                    format!("more rows than the {nrows} declared on the first line"),
                ));
            }
            let f = fields(row);
            if f.len() != 1 + nvars {
                return Err(KeyFrameError::at(
                    line,
                    format!("expected a time and {nvars} variable(s), found {} value(s)", f.len()),
                ));
            }
            let number = |s: &str, what: &str| -> Result<f64, KeyFrameError> {
                match s.replace(['d', 'D'], "e").parse::<f64>() {
                    Ok(x) if x.is_finite() => Ok(x),
                    _ => Err(KeyFrameError::at(line, format!("the {what} `{s}` is not a finite number"))),
                }
            };
            let t = number(f[0], "time")?;
            if t < last.1 {
                return Err(KeyFrameError::at(
                    line,
                    format!(
                        "the time {t} is before the previous row's {} (line {}): times must not decrease",
                        last.1, last.0
                    ),
                ));
            }
            last = (line, t);
            let v = number(f[column], &format!("variable {column}"))?;
            for (k, s) in f.iter().enumerate().skip(1) {
                if k != column {
                    number(s, &format!("variable {k}"))?;
                }
            }
            times.push(t);
            values.push(v);
        }
        if times.len() != nrows {
            return Err(KeyFrameError::at(
                end,
                format!("the first line declares {nrows} row(s) but the file has {}", times.len()),
            ));
        }
        KeyFrames::new(times, values, interpolation)
    }

    /// The value at time `t` (MFIX's interpolation; see the [module](self)). A NaN `t` gives
    /// the first row's value.
    pub fn value(&self, t: f64) -> f64 {
        let n = self.times.len();
        // The number of key times before t: rows p − 1 and p bracket t (t_{p−1} < t ≤ t_p).
        let p = self.times.partition_point(|&x| x < t);
        if p == 0 {
            return self.values[0];
        }
        if t >= self.times[n - 1] {
            return self.values[n - 1];
        }
        let (t0, t1, v0, v1) = (self.times[p - 1], self.times[p], self.values[p - 1], self.values[p]);
        match self.interpolation {
            // t0 < t ≤ t1, so t1 − t0 > 0.
            Interpolation::Linear => v0 + (t - t0) / (t1 - t0) * (v1 - v0),
            Interpolation::Step => v0,
        }
    }

    /// The table with its times moved by −`offset` (to time it from a run's start).
    pub fn shifted(&self, offset: f64) -> Result<KeyFrames, KeyFrameError> {
        if offset == 0.0 {
            return Ok(self.clone());
        }
        KeyFrames::new(
            self.times.iter().map(|t| t - offset).collect(),
            self.values.clone(),
            self.interpolation,
        )
    }

    pub fn times(&self) -> &[f64] {
        &self.times
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }
}

/// The fields of a list-directed line: separated by commas and/or blanks.
fn fields(line: &str) -> Vec<&str> {
    line.split(|c: char| c == ',' || c.is_whitespace()).filter(|s| !s.is_empty()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const DRUM: &str = "4, 1\nlinear\n! time var1\n0.0    0.0\n0.5   20.0\n1.0    0.0\n1.5  -20.0\n";

    /// MFIX's drum tutorial's table: 0 → 20 → 0 → −20 over 1.5 s. Linear interpolation of
    /// exactly representable numbers; the tolerance 1e-12 covers the one rounding of
    /// (t − t₀)/(t₁ − t₀)·Δv on values of order 20.
    #[test]
    fn the_drum_tutorials_table_interpolates_linearly() {
        let k = KeyFrames::from_mfix(DRUM, 1).unwrap();
        assert_eq!(k.times(), &[0.0, 0.5, 1.0, 1.5]);
        assert_eq!(k.interpolation(), Interpolation::Linear);
        for (t, v) in [(0.0, 0.0), (0.25, 10.0), (0.5, 20.0), (0.75, 10.0), (1.25, -10.0), (1.5, -20.0)] {
            assert!((k.value(t) - v).abs() < 1e-12, "t {t}: {}", k.value(t));
        }
        // Before the first time: the first row's value; at or after the last: the last's.
        assert_eq!(k.value(-3.0), 0.0);
        assert_eq!(k.value(1.5), -20.0);
        assert_eq!(k.value(100.0), -20.0);
        assert_eq!(k.value(f64::NAN), 0.0);
    }

    /// `step` holds the earlier row's value on (tᵢ, tᵢ₊₁], as MFIX's reader does: at a key time
    /// inside the table the value is still the previous row's. Exact (no arithmetic).
    #[test]
    fn a_step_table_holds_the_earlier_rows_value() {
        let k =
            KeyFrames::from_mfix("3 2\n'STEP'\nheader\n1.0 5.0 0.0\n2.0 7.0 0.0\n3.0 9.0 1.0\n", 1).unwrap();
        assert_eq!(k.interpolation(), Interpolation::Step);
        assert_eq!(k.value(0.0), 5.0); // before the first time
        assert_eq!(k.value(1.0), 5.0);
        assert_eq!(k.value(1.5), 5.0);
        assert_eq!(k.value(2.0), 5.0);
        assert_eq!(k.value(2.0000001), 7.0);
        assert_eq!(k.value(3.0), 9.0); // at the last time: the last row's
        assert_eq!(k.value(4.0), 9.0);
        let second =
            KeyFrames::from_mfix("3 2\nstep\nheader\n1.0 5.0 0.0\n2.0 7.0 0.0\n3.0 9.0 1.0\n", 2).unwrap();
        assert_eq!(second.values(), &[0.0, 0.0, 1.0]);
    }

    /// Two rows at one time are a jump: the value there is the first's, just after it the
    /// interpolation starts from the second's. One row is a constant. Tolerance as above.
    #[test]
    fn repeated_times_make_a_jump_and_one_row_is_a_constant() {
        let k = KeyFrames::new(vec![0.0, 1.0, 1.0, 2.0], vec![0.0, 1.0, 5.0, 7.0], Interpolation::Linear)
            .unwrap();
        assert!((k.value(0.5) - 0.5).abs() < 1e-12);
        assert_eq!(k.value(1.0), 1.0);
        assert!((k.value(1.5) - 6.0).abs() < 1e-12);
        assert_eq!(k.value(2.0), 7.0);
        let c = KeyFrames::from_mfix("1,1\nlinear\n!\n0.3, 2.5d0\n", 1).unwrap();
        for t in [-1.0, 0.0, 0.3, 0.31, 1e9] {
            assert_eq!(c.value(t), 2.5);
        }
        assert_eq!(KeyFrames::constant(1.0).unwrap().value(12.0), 1.0);
    }

    /// The conveyor tutorial's file parses with all its 25 rows.
    #[test]
    fn the_conveyor_tutorials_trapezoids_parse() {
        let mut text = String::from("25, 1\nlinear\n! time var1\n");
        for i in 0..6 {
            let t = 10.0 * i as f64;
            text += &format!("{t} 0.0\n{} 0.0\n{} 5.0\n{} 5.0\n", t + 4.0, t + 5.0, t + 9.0);
        }
        text += "60.0  0.0\n";
        let k = KeyFrames::from_mfix(&text, 1).unwrap();
        assert_eq!(k.times().len(), 25);
        assert_eq!(k.value(2.0), 0.0);
        assert!((k.value(4.5) - 2.5).abs() < 1e-12);
        assert_eq!(k.value(7.0), 5.0);
    }

    fn refused(text: &str, column: usize, line: Option<usize>, words: &[&str]) {
        let e = KeyFrames::from_mfix(text, column).expect_err(text);
        assert_eq!(e.line, line, "{e}");
        let m = e.to_string();
        for w in words {
            assert!(m.contains(w), "`{w}` not in: {m}");
        }
    }

    /// Malformed files are refused with the line at fault, never a panic.
    #[test]
    fn malformed_files_are_refused_with_their_line() {
        refused("", 1, Some(1), &["ends before its first line"]);
        refused("4\nlinear\n!\n", 1, Some(1), &["number of rows and the number of variables"]);
        refused("x, 1\nlinear\n!\n", 1, Some(1), &["`x`"]);
        refused("-2, 1\nlinear\n!\n", 1, Some(1), &["`-2`"]);
        refused("0, 1\nlinear\n!\n", 1, Some(1), &["from 1 to"]);
        refused("1, 0\nlinear\n!\n0 0\n", 1, Some(1), &["variables 0"]);
        refused("1, 1\nlinear\n!\n0 0\n", 2, Some(1), &["column 2"]);
        refused("1, 1\ncubic\n!\n0 0\n", 1, Some(2), &["`cubic`", "linear", "step"]);
        refused("1, 1\nlinear\n", 1, Some(2), &["header"]);
        refused("2, 1\nlinear\n!\n0 0\n1 x\n", 1, Some(5), &["variable 1 `x`"]);
        refused("2, 2\nlinear\n!\n0 0 0\n1 0 nan\n", 1, Some(5), &["variable 2 `nan`"]);
        refused("2, 1\nlinear\n!\n0 0\n1 inf\n", 1, Some(5), &["not a finite number"]);
        refused("2, 1\nlinear\n!\n0 0\n1\n", 1, Some(5), &["found 1 value"]);
        refused("2, 1\nlinear\n!\n0 0\n1 2 3\n", 1, Some(5), &["found 3 value"]);
        refused("2, 1\nlinear\n!\n1 0\n0.5 2\n", 1, Some(5), &["before the previous row's 1 (line 4)"]);
        refused("3, 1\nlinear\n!\n0 0\n1 2\n", 1, Some(5), &["declares 3 row(s) but the file has 2"]);
        refused("1, 1\nlinear\n!\n0 0\n\n1 2\n", 1, Some(6), &["more rows than the 1 declared"]);
        // A non-decreasing, finite table in memory.
        assert!(KeyFrames::new(vec![], vec![], Interpolation::Linear).is_err());
        assert!(KeyFrames::new(vec![0.0], vec![1.0, 2.0], Interpolation::Linear).is_err());
        assert!(KeyFrames::new(vec![1.0, 0.0], vec![1.0, 2.0], Interpolation::Linear).is_err());
        assert!(KeyFrames::new(vec![f64::NAN], vec![1.0], Interpolation::Linear).is_err());
        assert!(KeyFrames::new(vec![0.0], vec![f64::INFINITY], Interpolation::Step).is_err());
    }

    /// A file declaring absurd counts is refused from its first line alone (nothing sized by
    /// them is allocated); one declaring many rows but holding few is refused at its end,
    /// its vectors having grown only with the rows present.
    #[test]
    fn huge_declared_counts_are_refused_without_allocating_them() {
        refused("18446744073709551615, 1\nlinear\n!\n0 0\n", 1, Some(1), &["from 1 to 1000000"]);
        refused(
            "99999999999999999999999, 1\nlinear\n!\n0 0\n",
            1,
            Some(1),
            &["not a non-negative whole number"],
        );
        refused("1, 4000000000\nlinear\n!\n0 0\n", 1, Some(1), &["from 1 to 1000"]);
        refused("1000000, 1\nlinear\n!\n0 0\n", 1, Some(4), &["declares 1000000 row(s) but the file has 1"]);
    }
}
