//! Reading deck text: lines, comments, `KEY(i) = values`, repeat counts, `@( )` arithmetic.
//!
//! The syntax is MFIX's namelist style. Each line holds one or more assignments
//! `KEY = v1 v2 …` (values separated by blanks or commas); a line without a `KEY =` head
//! continues the value list of the previous assignment. Keywords are case-insensitive.
//! Values are numbers (Fortran exponents `1.0d-3` included), logicals (`.T.`, `.FALSE.`, `T`,
//! …), strings in `'…'` or `"…"` (a doubled quote stands for one), bare words, `@( … )`
//! arithmetic, and repeats `n*value` (`n*` alone leaves n entries unset, as Fortran's null
//! value does). `!` and `#` start a comment outside quotes.

use crate::error::CaseError;
use std::fmt;

/// Where an assignment came from, for messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Loc {
    /// A line of the deck (1-based).
    Line {
        /// The deck's name as given.
        file: String,
        /// 1-based line number.
        line: usize,
    },
    /// A `KEY=VALUE` argument on the command line.
    Arg {
        /// The argument as written.
        text: String,
    },
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Loc::Line { file, line } => write!(f, "{file}, line {line}"),
            Loc::Arg { text } => write!(f, "command-line override `{text}`"),
        }
    }
}

/// One value as written.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A quoted string (quotes removed, doubled quotes undone).
    Str(String),
    /// Anything unquoted: a number, a logical, a bare word.
    Word(String),
    /// The inside of `@( … )`.
    Expr(String),
}

impl Value {
    /// The value as it was written, for messages.
    pub fn written(&self) -> String {
        match self {
            Value::Str(s) => format!("'{s}'"),
            Value::Word(w) => w.clone(),
            Value::Expr(e) => format!("@({e})"),
        }
    }
}

/// One subscript dimension: `i` or `i:j`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sub {
    /// A single index.
    Index(i64),
    /// An inclusive range.
    Range(i64, i64),
}

/// `KEY(subscript) = values` as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// The keyword, upper case.
    pub key: String,
    /// The subscript, if any, one entry per dimension.
    pub subscript: Option<Vec<Sub>>,
    /// The values; `None` is a null value (`n*` without a value).
    pub values: Vec<Option<Value>>,
    /// Where it is.
    pub loc: Loc,
}

/// What a deck holds besides assignments.
#[derive(Debug, Default)]
pub struct Lexed {
    /// Every assignment, in order.
    pub assignments: Vec<Assignment>,
    /// `#!MFIX-GUI key = value` comments (the GUI's project data in `.mfx` files), key lower case;
    /// continuation lines (`#!MFIX-GUI` and two or more blanks) are joined to the value with one
    /// blank, the location being the first line's.
    pub gui: Vec<(String, String, Loc)>,
    /// Lines of `@(RXNS)`/`@(DES_RXNS)` chemistry blocks: where the first block starts.
    pub reactions: Option<Loc>,
    /// Where a `THERMO DATA` section starts (everything after it is thermochemical data).
    pub thermo_data: Option<Loc>,
}

fn syntax(loc: &Loc, msg: impl fmt::Display) -> CaseError {
    CaseError::Syntax(format!("{loc}: {msg}"))
}

/// Splits a deck into assignments. `file` names the deck in messages.
pub fn lex_deck(text: &str, file: &str) -> Result<Lexed, CaseError> {
    // A byte-order mark (some Windows editors write one) is not part of the first keyword.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = Lexed::default();
    let mut in_block = false;
    let mut total = 0usize;
    for (k, line) in text.lines().enumerate() {
        let loc = Loc::Line { file: file.to_string(), line: k + 1 };
        let trimmed = line.trim();
        let upper = trimmed.to_ascii_uppercase();
        if out.thermo_data.is_some() {
            break;
        }
        if in_block {
            if upper.starts_with("@(END)") || upper.starts_with("@(DES_END)") {
                in_block = false;
            }
            continue;
        }
        if upper.starts_with("@(RXNS)") || upper.starts_with("@(DES_RXNS)") {
            in_block = true;
            out.reactions.get_or_insert(loc);
            continue;
        }
        if upper.starts_with("THERMO DATA") {
            out.thermo_data = Some(loc);
            continue;
        }
        if let Some(rest) = trimmed.strip_prefix("#!MFIX-GUI") {
            // The GUI wraps long (JSON) values: a line whose text starts with two or more
            // blanks continues the previous value (MFIX's `project.py` reads it so), whatever
            // it holds, `=` included.
            if rest.starts_with("  ") {
                if let Some((_, value, _)) = out.gui.last_mut() {
                    let more = rest.trim();
                    if !more.is_empty() {
                        if !value.is_empty() {
                            value.push(' ');
                        }
                        value.push_str(more);
                    }
                }
                continue;
            }
            if let Some((key, value)) = rest.split_once('=') {
                out.gui.push((key.trim().to_ascii_lowercase(), value.trim().to_string(), loc));
            }
            continue;
        }
        lex_line(line, &loc, &mut out.assignments, true, &mut total)?;
    }
    Ok(out)
}

/// Parses one `KEY=VALUE` command-line override.
pub fn lex_override(text: &str) -> Result<Assignment, CaseError> {
    let loc = Loc::Arg { text: text.to_string() };
    let mut v = Vec::new();
    lex_line(text, &loc, &mut v, false, &mut 0)?;
    match v.len() {
        1 => Ok(v.remove(0)),
        0 => Err(syntax(&loc, "expected KEYWORD=VALUE, e.g. TSTOP=0.5")),
        _ => Err(syntax(&loc, "one override per argument: give each KEYWORD=VALUE separately")),
    }
}

/// Lexes one line into `out`. With `continuation`, a line without a `KEY =` head continues the
/// previous assignment.
fn lex_line(
    line: &str,
    loc: &Loc,
    out: &mut Vec<Assignment>,
    continuation: bool,
    total: &mut usize,
) -> Result<(), CaseError> {
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    let mut current: Option<usize> = None;
    loop {
        while i < chars.len() && (chars[i].is_whitespace() || chars[i] == ',') {
            i += 1;
        }
        if i >= chars.len() || chars[i] == '!' || chars[i] == '#' {
            break;
        }
        if let Some((key, subscript, next)) = assignment_head(&chars, i, loc)? {
            out.push(Assignment { key, subscript, values: Vec::new(), loc: loc.clone() });
            current = Some(out.len() - 1);
            i = next;
            continue;
        }
        let (items, next) = value_item(&chars, i, loc)?;
        let target = match current {
            Some(c) => c,
            None if continuation
                && !out.is_empty()
                && i == first_non_blank(&chars)
                && !looks_like_name(&items) =>
            {
                // A continuation line: the values belong to the previous assignment, if it
                // came from the line just before (same deck).
                current = Some(out.len() - 1);
                out.len() - 1
            }
            None => {
                let word: String = chars[i..].iter().take_while(|c| !c.is_whitespace()).collect();
                let expected = if continuation {
                    "expected `KEYWORD = value`"
                } else {
                    "expected KEYWORD=VALUE (e.g. TSTOP=0.5)"
                };
                return Err(syntax(
                    loc,
                    format!("{expected}, found `{word}` (a keyword name followed by `=`)"),
                ));
            }
        };
        *total += items.len();
        if *total > MAX_TOTAL_VALUES {
            return Err(syntax(
                loc,
                format!(
                    "the deck holds more than {MAX_TOTAL_VALUES} values up to this line (counting each `n*value` as n); MFIX's arrays hold at most a few thousand elements: is a repeat count mistyped?"
                ),
            ));
        }
        out[target].values.extend(items);
        i = next;
    }
    if let Some(c) = current
        && out[c].values.is_empty()
    {
        return Err(syntax(
            loc,
            format!("`{}` has no value after `=`; give a value, e.g. `{} = 1.0`", out[c].key, out[c].key),
        ));
    }
    Ok(())
}

/// A bare word that reads as a keyword name rather than a value (a value continuing the
/// previous line is a number, a logical, a string or an expression).
fn looks_like_name(items: &[Option<Value>]) -> bool {
    match items.first() {
        Some(Some(Value::Word(w))) => {
            let u = w.to_ascii_uppercase();
            w.starts_with(|c: char| c.is_ascii_alphabetic())
                && !matches!(u.as_str(), "T" | "F" | "TRUE" | "FALSE")
        }
        _ => false,
    }
}

fn first_non_blank(chars: &[char]) -> usize {
    chars.iter().position(|c| !c.is_whitespace() && *c != ',').unwrap_or(chars.len())
}

/// `NAME [ (subscript) ] =` at `i`: the keyword, its subscript and the index after `=`.
#[allow(clippy::type_complexity)]
fn assignment_head(
    chars: &[char],
    i: usize,
    loc: &Loc,
) -> Result<Option<(String, Option<Vec<Sub>>, usize)>, CaseError> {
    if !chars[i].is_ascii_alphabetic() {
        return Ok(None);
    }
    let mut j = i;
    while j < chars.len() && (chars[j].is_ascii_alphanumeric() || chars[j] == '_') {
        j += 1;
    }
    let name: String = chars[i..j].iter().collect::<String>().to_ascii_uppercase();
    let mut k = j;
    while k < chars.len() && chars[k] == ' ' {
        k += 1;
    }
    let mut subscript = None;
    if k < chars.len() && chars[k] == '(' {
        let Some(close) = chars[k..].iter().position(|&c| c == ')').map(|p| p + k) else {
            return Ok(None);
        };
        let inside: String = chars[k + 1..close].iter().collect();
        // Only a subscript if `=` follows; `T(` or similar in values is not a head.
        let mut m = close + 1;
        while m < chars.len() && chars[m] == ' ' {
            m += 1;
        }
        if m >= chars.len() || chars[m] != '=' {
            return Ok(None);
        }
        subscript = Some(parse_subscript(&inside, &name, loc)?);
        k = close + 1;
    }
    while k < chars.len() && chars[k] == ' ' {
        k += 1;
    }
    if k < chars.len() && chars[k] == '=' { Ok(Some((name, subscript, k + 1))) } else { Ok(None) }
}

/// The largest array a deck can address: far above MFIX's (phases, walls, boundary regions
/// count in the hundreds), small enough that a mistyped repeat count or subscript cannot make
/// the reader allocate without bound.
const MAX_ELEMENTS: usize = 100_000;

/// The most values a deck may hold in all, each `n*value` counted as n: as many as the largest
/// array. MFIX's own arrays hold at most a few thousand elements; the cap keeps one line of
/// repeats (`1000 x 100000*0.7`) from taking gigabytes.
pub const MAX_TOTAL_VALUES: usize = MAX_ELEMENTS;

/// The deepest nesting of an `@( )` expression (parentheses, signs and `**` exponents): 64.
/// Real decks nest two or three levels; the evaluator recurses once a level.
pub const MAX_EXPR_DEPTH: usize = 64;

fn parse_subscript(inside: &str, name: &str, loc: &Loc) -> Result<Vec<Sub>, CaseError> {
    let bad = |what: &str| {
        CaseError::invalid(
            loc.to_string(),
            format!("{name}({inside})"),
            format!("({inside})"),
            format!(
                "{what}; a subscript is one or two whole numbers, e.g. {name}(1) or {name}(1,2), or a range {name}(1:3)"
            ),
        )
    };
    let mut subs = Vec::new();
    for part in inside.split(',') {
        let part = part.trim();
        let int = |s: &str| {
            let v =
                s.trim().parse::<i64>().map_err(|_| bad(&format!("`{}` is not a whole number", s.trim())))?;
            if v.abs() > MAX_ELEMENTS as i64 {
                return Err(bad(&format!(
                    "`{v}` is beyond any MFIX array (at most {MAX_ELEMENTS} elements)"
                )));
            }
            Ok(v)
        };
        if let Some((a, b)) = part.split_once(':') {
            let (a, b) = (int(a)?, int(b)?);
            if a > b {
                return Err(bad("the range is empty (first index above the last)"));
            }
            subs.push(Sub::Range(a, b));
        } else {
            subs.push(Sub::Index(int(part)?));
        }
    }
    Ok(subs)
}

/// A value at `i` (possibly `n*value`): the values it stands for and the index after it.
#[allow(clippy::type_complexity)]
fn value_item(chars: &[char], i: usize, loc: &Loc) -> Result<(Vec<Option<Value>>, usize), CaseError> {
    // Repeat count `n*`.
    let digits = chars[i..].iter().take_while(|c| c.is_ascii_digit()).count();
    if digits > 0 && chars.get(i + digits) == Some(&'*') {
        let count_text: String = chars[i..i + digits].iter().collect();
        let j = i + digits + 1;
        let count: usize = count_text.parse().unwrap_or(usize::MAX);
        if count > MAX_ELEMENTS {
            return Err(syntax(
                loc,
                format!(
                    "repeat count `{count_text}*` is beyond any MFIX array (at most {MAX_ELEMENTS} elements)"
                ),
            ));
        }
        if count == 0 {
            return Err(syntax(
                loc,
                format!("repeat count `{count_text}*` must be at least 1, e.g. `3*0.9`"),
            ));
        }
        if j >= chars.len() || chars[j].is_whitespace() || chars[j] == ',' {
            return Ok((vec![None; count], j));
        }
        let (v, next) = single_value(chars, j, loc)?;
        return Ok((vec![Some(v); count], next));
    }
    let (v, next) = single_value(chars, i, loc)?;
    Ok((vec![Some(v)], next))
}

fn single_value(chars: &[char], i: usize, loc: &Loc) -> Result<(Value, usize), CaseError> {
    let c = chars[i];
    if c == '\'' || c == '"' {
        let mut s = String::new();
        let mut j = i + 1;
        loop {
            if j >= chars.len() {
                return Err(syntax(
                    loc,
                    format!(
                        "the string starting `{}` has no closing {c}",
                        chars[i..].iter().collect::<String>()
                    ),
                ));
            }
            if chars[j] == c {
                if chars.get(j + 1) == Some(&c) {
                    s.push(c);
                    j += 2;
                    continue;
                }
                return Ok((Value::Str(s), j + 1));
            }
            s.push(chars[j]);
            j += 1;
        }
    }
    if c == '@' && chars.get(i + 1) == Some(&'(') {
        let mut depth = 0usize;
        for (j, &ch) in chars.iter().enumerate().skip(i + 1) {
            match ch {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        let inside: String = chars[i + 2..j].iter().collect();
                        return Ok((Value::Expr(inside), j + 1));
                    }
                }
                _ => {}
            }
        }
        return Err(syntax(
            loc,
            format!(
                "`{}` has no closing parenthesis; write @( expression ) with balanced parentheses",
                chars[i..].iter().collect::<String>().trim_end()
            ),
        ));
    }
    let mut j = i;
    while j < chars.len()
        && !chars[j].is_whitespace()
        && !matches!(chars[j], ',' | '!' | '#' | '\'' | '"' | '=')
    {
        j += 1;
    }
    if j == i {
        return Err(syntax(loc, format!("unexpected `{c}`; expected a value")));
    }
    Ok((Value::Word(chars[i..j].iter().collect()), j))
}

/// Parses a number as Fortran writes it: `1`, `-2.5`, `.5`, `5.`, `1.0e-3`, `1.0D-3`, `1.0d+3`.
pub fn fortran_number(s: &str) -> Option<f64> {
    let t = s.trim();
    if t.is_empty()
        || !t.chars().all(|c| c.is_ascii_digit() || matches!(c, '.' | '+' | '-' | 'e' | 'E' | 'd' | 'D'))
    {
        return None;
    }
    let v: f64 = t.replace(['d', 'D'], "e").parse().ok()?;
    v.is_finite().then_some(v)
}

/// Evaluates the inside of `@( … )`: numbers, `+ - * / **` and parentheses. `**` binds
/// tighter than a leading sign, as in Fortran (`-2**2` is −4), and is right-associative.
pub fn eval_expr(text: &str) -> Result<f64, String> {
    let mut p = ExprParser { s: text.as_bytes(), i: 0, depth: 0 };
    let v = p.expr()?;
    p.blanks();
    if p.i < p.s.len() {
        return Err(format!("unexpected `{}` at position {}", text[p.i..].trim(), p.i + 1));
    }
    if v.is_finite() { Ok(v) } else { Err("the result is not a finite number".into()) }
}

struct ExprParser<'a> {
    s: &'a [u8],
    i: usize,
    /// Nesting depth of `factor` calls (every recursion passes through it).
    depth: usize,
}

impl ExprParser<'_> {
    fn blanks(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.blanks();
        self.s.get(self.i).copied()
    }

    fn expr(&mut self) -> Result<f64, String> {
        let mut v = match self.peek() {
            Some(b'-') => {
                self.i += 1;
                -self.term()?
            }
            Some(b'+') => {
                self.i += 1;
                self.term()?
            }
            _ => self.term()?,
        };
        loop {
            match self.peek() {
                Some(b'+') => {
                    self.i += 1;
                    v += self.term()?;
                }
                Some(b'-') => {
                    self.i += 1;
                    v -= self.term()?;
                }
                _ => return Ok(v),
            }
        }
    }

    fn term(&mut self) -> Result<f64, String> {
        let mut v = self.factor()?;
        loop {
            match self.peek() {
                Some(b'*') if self.s.get(self.i + 1) != Some(&b'*') => {
                    self.i += 1;
                    v *= self.factor()?;
                }
                Some(b'/') => {
                    self.i += 1;
                    let d = self.factor()?;
                    if d == 0.0 {
                        return Err("division by zero".into());
                    }
                    v /= d;
                }
                _ => return Ok(v),
            }
        }
    }

    fn factor(&mut self) -> Result<f64, String> {
        self.depth += 1;
        if self.depth > MAX_EXPR_DEPTH {
            return Err(format!(
                "the expression nests deeper than {MAX_EXPR_DEPTH} levels (parentheses, signs or ** exponents)"
            ));
        }
        let v = self.factor_inner();
        self.depth -= 1;
        v
    }

    fn factor_inner(&mut self) -> Result<f64, String> {
        let base = self.primary()?;
        if self.peek() == Some(b'*') && self.s.get(self.i + 1) == Some(&b'*') {
            self.i += 2;
            // The exponent may carry its own sign: 2**-1.
            let exponent = match self.peek() {
                Some(b'-') => {
                    self.i += 1;
                    -self.factor()?
                }
                Some(b'+') => {
                    self.i += 1;
                    self.factor()?
                }
                _ => self.factor()?,
            };
            return Ok(base.powf(exponent));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<f64, String> {
        match self.peek() {
            Some(b'(') => {
                self.i += 1;
                let v = self.expr()?;
                if self.peek() != Some(b')') {
                    return Err("missing `)`".into());
                }
                self.i += 1;
                Ok(v)
            }
            Some(b'-') => {
                self.i += 1;
                Ok(-self.factor()?)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let start = self.i;
                while self.i < self.s.len() && (self.s[self.i].is_ascii_digit() || self.s[self.i] == b'.') {
                    self.i += 1;
                }
                if self.i < self.s.len() && matches!(self.s[self.i], b'e' | b'E' | b'd' | b'D') {
                    let save = self.i;
                    self.i += 1;
                    if self.i < self.s.len() && matches!(self.s[self.i], b'+' | b'-') {
                        self.i += 1;
                    }
                    let digits = self.s[self.i..].iter().take_while(|c| c.is_ascii_digit()).count();
                    if digits == 0 {
                        self.i = save;
                    } else {
                        self.i += digits;
                    }
                }
                let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                fortran_number(&text).ok_or_else(|| format!("`{text}` is not a number"))
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_')
                {
                    self.i += 1;
                }
                Err(format!(
                    "unknown name `{}`; only numbers, + - * / ** and parentheses are allowed",
                    String::from_utf8_lossy(&self.s[start..self.i])
                ))
            }
            Some(c) => Err(format!("unexpected `{}`", c as char)),
            None => Err("the expression ends too early (an operand is missing)".into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(line: &str) -> Assignment {
        let l = lex_deck(line, "t.dat").expect("lexes");
        assert_eq!(l.assignments.len(), 1, "{line}");
        l.assignments[0].clone()
    }

    #[test]
    fn namelist_forms() {
        let a = one("  des_en_input(2) = 0.9, 0.8 ! comment");
        assert_eq!(a.key, "DES_EN_INPUT");
        assert_eq!(a.subscript, Some(vec![Sub::Index(2)]));
        assert_eq!(a.values, vec![Some(Value::Word("0.9".into())), Some(Value::Word("0.8".into()))]);
        let a = one("SOLIDS_MODEL = 2*'DEM'");
        assert_eq!(a.values, vec![Some(Value::Str("DEM".into())); 2]);
        let a = one("RUN_NAME = 'it''s'  # comment");
        assert_eq!(a.values, vec![Some(Value::Str("it's".into()))]);
        let a = one("BC_UW_S(1:2, 1) = 0.0 0.0");
        assert_eq!(a.subscript, Some(vec![Sub::Range(1, 2), Sub::Index(1)]));
        let a = one("KN = @( 2 * (1.0d3 + 4) )");
        assert_eq!(a.values, vec![Some(Value::Expr(" 2 * (1.0d3 + 4) ".into()))]);
        let l = lex_deck("IMAX = 10 JMAX = 20\nDES_EN_INPUT = 0.9\n   0.8 0.7\n", "t.dat").expect("lexes");
        assert_eq!(l.assignments.len(), 3);
        assert_eq!(l.assignments[2].values.len(), 3);
    }

    #[test]
    fn total_expansion_and_byte_order_mark() {
        // 100 items of 1000 repeats are the cap exactly; one more value is refused, naming
        // the line where the total passes it.
        let at_cap = format!("KN = 1\nA = {}\n", vec!["1000*0.7"; 100].join(" "));
        let e = lex_deck(&at_cap, "t.dat").expect_err("one over").to_string();
        assert!(e.starts_with("t.dat, line 2: the deck holds more than 100000 values"), "{e}");
        let l = lex_deck(&at_cap.replace("KN = 1\n", ""), "t.dat").expect("at the cap");
        assert_eq!(l.assignments[0].values.len(), MAX_TOTAL_VALUES);
        // The line: 1000 items of 100000 repeats, refused at once.
        let huge = format!("A = {}\n", vec!["100000*0.7"; 1000].join(" "));
        assert!(lex_deck(&huge, "t.dat").is_err());
        let l = lex_deck("\u{feff}RUN_NAME = 'x'\n", "t.dat").expect("a BOM is skipped");
        assert_eq!(l.assignments[0].key, "RUN_NAME");
    }

    #[test]
    fn arithmetic() {
        assert_eq!(eval_expr("1 + 2 * 3"), Ok(7.0));
        assert_eq!(eval_expr("(1 + 2) * 3"), Ok(9.0));
        assert_eq!(eval_expr("-2**2"), Ok(-4.0));
        assert_eq!(eval_expr("2**3**2"), Ok(512.0));
        assert_eq!(eval_expr("2**-1"), Ok(0.5));
        assert_eq!(eval_expr("1.48d7/1.72D7"), Ok(1.48e7 / 1.72e7));
        assert_eq!(eval_expr("1.0e-3 * 4"), Ok(4.0e-3));
        assert!(eval_expr("1/0").is_err());
        assert!(eval_expr("1 +").is_err());
        assert!(eval_expr("(1").is_err());
        assert!(eval_expr("pi").is_err());
        // 64 levels evaluate; 65 are refused with the reason, whichever way they nest.
        let nest = |n: usize| format!("{}1{}", "(".repeat(n), ")".repeat(n));
        assert_eq!(eval_expr(&nest(MAX_EXPR_DEPTH - 1)), Ok(1.0));
        for deep in [
            nest(MAX_EXPR_DEPTH),
            "-".repeat(MAX_EXPR_DEPTH + 1) + "1",
            vec!["2"; MAX_EXPR_DEPTH + 1].join("**"),
        ] {
            let e = eval_expr(&deep).expect_err("too deep");
            assert!(e.contains("nests deeper than 64 levels"), "{e}");
        }
        // 30 000 levels (which overflowed the stack) are refused the same way.
        assert!(eval_expr(&nest(30_000)).expect_err("too deep").contains("nests deeper"));
    }

    #[test]
    fn fortran_numbers() {
        assert_eq!(fortran_number("1.0d-3"), Some(1.0e-3));
        assert_eq!(fortran_number("5."), Some(5.0));
        assert_eq!(fortran_number(".5D0"), Some(0.5));
        assert_eq!(fortran_number("1.0e4.5"), None);
        assert_eq!(fortran_number(".T."), None);
    }
}
