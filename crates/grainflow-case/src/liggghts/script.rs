//! The words of a LIGGGHTS script: lines joined at a trailing `&`, `#` comments dropped (not
//! inside quotes), quoted words kept whole, `${name}`, `$x` and `$(expression)` replaced as
//! LIGGGHTS replaces them (when the line is read, so a variable defined later does not count),
//! and `variable` and `include` carried out on the way.

use crate::error::CaseError;
use std::collections::BTreeMap;

/// One command: its words and where it stands.
#[derive(Debug, Clone)]
pub struct Command {
    /// The file it was read from (the script or an included file).
    pub file: String,
    /// 1-based line of its first line.
    pub line: usize,
    /// The command word and its arguments, variables replaced.
    pub words: Vec<String>,
}

impl Command {
    /// "in.script, line 12".
    pub fn at(&self) -> String {
        format!("{}, line {}", self.file, self.line)
    }
}

/// The variables of a script: set by `-var` first (an `index` variable of the script does not
/// replace them, as in LIGGGHTS), then by its `variable` commands.
#[derive(Debug, Clone, Default)]
pub struct Variables {
    values: BTreeMap<String, Value>,
}

#[derive(Debug, Clone)]
enum Value {
    /// `index`, `string`, `-var`: the text.
    Text(String),
    /// `equal`: the formula, evaluated where it is used.
    Formula(String),
}

impl Variables {
    /// The variables given on the command line (`-var NAME VALUE`).
    pub fn given(pairs: &[(String, String)]) -> Self {
        let values = pairs.iter().map(|(k, v)| (k.clone(), Value::Text(v.clone()))).collect();
        Variables { values }
    }

    /// The value of `name` as text (a formula evaluated), if it is defined.
    fn get(&self, name: &str, depth: usize) -> Result<Option<String>, String> {
        match self.values.get(name) {
            None => Ok(None),
            Some(Value::Text(t)) => Ok(Some(t.clone())),
            Some(Value::Formula(f)) => evaluate(f, self, depth + 1)
                .map(|x| Some(format_number(x)))
                .map_err(|e| format!("`variable {name} equal {f}`: {e}")),
        }
    }

    /// `variable NAME STYLE ARGS…`; `Err` is the message.
    fn define(&mut self, words: &[String]) -> Result<(), String> {
        let (name, style) = match words {
            [_, name, style, ..] => (name.clone(), style.as_str()),
            _ => return Err("`variable` needs a name, a style and its values".into()),
        };
        let args = &words[3..];
        match style {
            "index" | "string" | "loop" if !args.is_empty() => {
                if style == "loop" {
                    return Err(
                        "`variable … loop` drives a `next`/`jump` loop, which grainflow does not run".into(),
                    );
                }
                self.values.entry(name).or_insert_with(|| Value::Text(args[0].clone()));
            }
            "equal" if !args.is_empty() => {
                // Evaluated where it is used, as LIGGGHTS does: a formula of the particles'
                // state (`xcm(all,x)`) that only thermo output reads is never evaluated.
                self.values.insert(name, Value::Formula(args.join(" ")));
            }
            "delete" => {
                self.values.remove(&name);
            }
            other => {
                return Err(format!(
                    "`variable {name} {other}`: grainflow reads the index, string and equal styles, with values"
                ));
            }
        }
        Ok(())
    }
}

/// A number as text that reads back to the same value (whole numbers without a point).
fn format_number(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 { format!("{}", x as i64) } else { format!("{x:?}") }
}

/// The commands of `text` (the script named `file`), with `include`d files read through
/// `read` and the variables carried out. `read` gets the name as written.
pub fn commands(
    text: &str,
    file: &str,
    vars: &mut Variables,
    read: &dyn Fn(&str) -> Result<String, CaseError>,
    depth: usize,
) -> Result<Vec<Command>, CaseError> {
    let bad =
        |line: usize, message: String| CaseError::ParticleFile { path: file.to_string(), line, message };
    if depth > 16 {
        return Err(bad(0, "`include` nests more than 16 files deep".into()));
    }
    let mut out = Vec::new();
    let mut pending = String::new();
    let mut first = 0;
    for (k, raw) in text.lines().enumerate() {
        let line = strip_comment(raw);
        if pending.is_empty() {
            first = k + 1;
        }
        let t = line.trim_end();
        if let Some(head) = t.strip_suffix('&') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(t);
        let joined = std::mem::take(&mut pending);
        let replaced = substitute(&joined, vars).map_err(|e| bad(first, e))?;
        let words = split_words(&replaced).map_err(|e| bad(first, e))?;
        if words.is_empty() {
            continue;
        }
        match words[0].as_str() {
            "variable" => vars.define(&words).map_err(|e| bad(first, e))?,
            "if" => {
                // `if "COND" then "CMD" … [elif "COND" "CMD" …]… [else "CMD" …]`: the
                // commands of the first true branch, read as lines of this one.
                let chosen = if_branch(&words, vars).map_err(|e| bad(first, e))?;
                let inner = commands(&chosen.join("\n"), file, vars, read, depth + 1)
                    .map_err(|e| bad(first, format!("in `if`: {e}")))?;
                out.extend(inner.into_iter().map(|c| Command { line: first, ..c }));
            }
            "include" => {
                let name = words.get(1).ok_or_else(|| bad(first, "`include` needs a file".into()))?;
                if depth >= 16 {
                    return Err(bad(first, format!("`include {name}` nests more than 16 files deep")));
                }
                let inner = read(name).map_err(|e| bad(first, format!("`include {name}`: {e}")))?;
                // An error in an included file is told with the script's own line too.
                let inner = commands(&inner, name, vars, read, depth + 1);
                out.extend(inner.map_err(|e| {
                    if depth == 0 { bad(first, format!("`include {name}`: {e}")) } else { e }
                })?);
            }
            _ => out.push(Command { file: file.to_string(), line: first, words }),
        }
    }
    Ok(out)
}

/// The line without its comment: from a `#` outside quotes.
fn strip_comment(line: &str) -> &str {
    let mut quote = None;
    for (i, c) in line.char_indices() {
        match (c, quote) {
            ('"' | '\'', None) => quote = Some(c),
            (q, Some(open)) if q == open => quote = None,
            ('#', None) => return &line[..i],
            _ => {}
        }
    }
    line
}

/// The words of a line; quoted text is one word, without its quotes.
fn split_words(line: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut chars = line.chars().peekable();
    while let Some(&c) = chars.peek() {
        if c.is_whitespace() {
            chars.next();
            continue;
        }
        let mut w = String::new();
        if c == '"' || c == '\'' {
            chars.next();
            loop {
                match chars.next() {
                    Some(q) if q == c => break,
                    Some(x) => w.push(x),
                    None => return Err(format!("a quote {c} is not closed")),
                }
            }
        } else {
            while let Some(&x) = chars.peek() {
                if x.is_whitespace() {
                    break;
                }
                w.push(x);
                chars.next();
            }
        }
        words.push(w);
    }
    Ok(words)
}

/// `${name}`, `$x` and `$(expression)` replaced.
fn substitute(line: &str, vars: &Variables) -> Result<String, String> {
    let mut out = String::with_capacity(line.len());
    let mut rest = line;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let (name, used, formula) = if let Some(body) = after.strip_prefix('{') {
            let end = body.find('}').ok_or("`${` without its `}`")?;
            (&body[..end], end + 2, false)
        } else if let Some(body) = after.strip_prefix('(') {
            let end = closing(body).ok_or("`$(` without its `)`")?;
            (&body[..end], end + 2, true)
        } else {
            let c = after.chars().next().ok_or("a `$` at the end of the line")?;
            (&after[..c.len_utf8()], c.len_utf8(), false)
        };
        if formula {
            out.push_str(&format_number(evaluate(name, vars, 0)?));
        } else {
            let v = vars.get(name, 0)?.ok_or_else(|| format!("variable `{name}` is not defined here"))?;
            out.push_str(&v);
        }
        rest = &after[used..];
    }
    out.push_str(rest);
    Ok(out)
}

/// The index of the `)` that closes a `(` just before `s`.
fn closing(s: &str) -> Option<usize> {
    let mut depth = 0usize;
    for (i, c) in s.char_indices() {
        match c {
            '(' => depth += 1,
            ')' if depth == 0 => return Some(i),
            ')' => depth -= 1,
            _ => {}
        }
    }
    None
}

/// The commands of the branch of an `if` whose condition holds (none if none does).
fn if_branch(words: &[String], vars: &Variables) -> Result<Vec<String>, String> {
    let holds = |c: &str| evaluate(c, vars, 0).map(|x| x != 0.0).map_err(|e| format!("`if \"{c}\"`: {e}"));
    if words.len() < 3 || words[2] != "then" {
        return Err("write `if \"CONDITION\" then \"COMMAND\" …`".into());
    }
    let mut k = 3;
    let mut taken = holds(&words[1])?;
    let mut chosen = Vec::new();
    loop {
        let start = k;
        while k < words.len() && words[k] != "elif" && words[k] != "else" {
            k += 1;
        }
        if taken {
            chosen.extend(words[start..k].iter().cloned());
            return Ok(chosen);
        }
        match words.get(k).map(String::as_str) {
            None => return Ok(chosen),
            Some("else") => {
                taken = true;
                k += 1;
            }
            _ => {
                let c = words.get(k + 1).ok_or("`elif` needs a condition")?;
                taken = holds(c)?;
                k += 2;
            }
        }
    }
}

/// Evaluates an `equal`-style formula: numbers, `+ - * / ^`, parentheses, `PI`, `sqrt()`,
/// `exp()`, `ln()`, `sin()`, `cos()`, `abs()`, other variables as `v_name`, and the
/// comparisons `< <= > >= == !=` and `&& ||` (1 if true, 0 if not).
pub fn evaluate(f: &str, vars: &Variables, depth: usize) -> Result<f64, String> {
    if depth > 32 {
        return Err("variables refer to each other in a loop".into());
    }
    let mut p = Parser { s: f.as_bytes(), i: 0, vars, depth };
    let x = p.logic()?;
    p.blank();
    if p.i != p.s.len() {
        return Err(format!("cannot read `{}` in `{f}`", &f[p.i..]));
    }
    Ok(x)
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    vars: &'a Variables,
    depth: usize,
}

impl Parser<'_> {
    fn blank(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }
    fn eat(&mut self, c: u8) -> bool {
        self.blank();
        let hit = self.s.get(self.i) == Some(&c);
        self.i += hit as usize;
        hit
    }
    fn eat_str(&mut self, t: &str) -> bool {
        self.blank();
        let hit = self.s[self.i..].starts_with(t.as_bytes());
        self.i += if hit { t.len() } else { 0 };
        hit
    }
    fn logic(&mut self) -> Result<f64, String> {
        let mut x = self.compare()?;
        loop {
            if self.eat_str("&&") {
                let y = self.compare()?;
                x = f64::from(x != 0.0 && y != 0.0);
            } else if self.eat_str("||") {
                let y = self.compare()?;
                x = f64::from(x != 0.0 || y != 0.0);
            } else {
                return Ok(x);
            }
        }
    }
    fn compare(&mut self) -> Result<f64, String> {
        let x = self.sum()?;
        for (op, test) in [
            ("<=", f64::le as fn(&f64, &f64) -> bool),
            (">=", f64::ge),
            ("==", f64::eq),
            ("!=", f64::ne),
            ("<", f64::lt),
            (">", f64::gt),
        ] {
            if self.eat_str(op) {
                let y = self.sum()?;
                return Ok(f64::from(test(&x, &y)));
            }
        }
        Ok(x)
    }
    fn sum(&mut self) -> Result<f64, String> {
        let mut x = self.product()?;
        loop {
            if self.eat(b'+') {
                x += self.product()?;
            } else if self.eat(b'-') {
                x -= self.product()?;
            } else {
                return Ok(x);
            }
        }
    }
    fn product(&mut self) -> Result<f64, String> {
        let mut x = self.power()?;
        loop {
            if self.eat(b'*') {
                x *= self.power()?;
            } else if self.eat(b'/') {
                x /= self.power()?;
            } else {
                return Ok(x);
            }
        }
    }
    fn power(&mut self) -> Result<f64, String> {
        let base = self.unary()?;
        if self.eat(b'^') { Ok(base.powf(self.power()?)) } else { Ok(base) }
    }
    fn unary(&mut self) -> Result<f64, String> {
        if self.eat(b'-') {
            return Ok(-self.unary()?);
        }
        if self.eat(b'+') {
            return self.unary();
        }
        self.atom()
    }
    fn atom(&mut self) -> Result<f64, String> {
        self.blank();
        if self.eat(b'(') {
            let x = self.logic()?;
            return if self.eat(b')') { Ok(x) } else { Err("a `(` is not closed".into()) };
        }
        let start = self.i;
        let number = |c: u8| c.is_ascii_digit() || c == b'.';
        if self.s.get(self.i).copied().is_some_and(number) {
            while self.i < self.s.len() {
                let c = self.s[self.i];
                let exp_sign = (c == b'+' || c == b'-') && matches!(self.s[self.i - 1], b'e' | b'E');
                if !(number(c) || c == b'e' || c == b'E' || exp_sign) {
                    break;
                }
                self.i += 1;
            }
            let t = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
            return t.parse().map_err(|_| format!("`{t}` is not a number"));
        }
        while self.i < self.s.len() && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_') {
            self.i += 1;
        }
        let name = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
        if name.is_empty() {
            return Err("a number, a variable or a function is missing".into());
        }
        if let Some(v) = name.strip_prefix("v_") {
            let t = self.vars.get(v, self.depth)?.ok_or_else(|| format!("variable `{v}` is not defined"))?;
            return evaluate(&t, self.vars, self.depth + 1);
        }
        if name == "PI" {
            return Ok(std::f64::consts::PI);
        }
        let f: fn(f64) -> f64 = match name {
            "sqrt" => f64::sqrt,
            "exp" => f64::exp,
            "ln" => f64::ln,
            "sin" => f64::sin,
            "cos" => f64::cos,
            "abs" => f64::abs,
            _ => return Err(format!("`{name}` is not a function or variable grainflow evaluates")),
        };
        if !self.eat(b'(') {
            return Err(format!("`{name}` needs its argument in parentheses"));
        }
        let x = self.logic()?;
        if !self.eat(b')') {
            return Err(format!("`{name}(` is not closed"));
        }
        Ok(f(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(text: &str, given: &[(&str, &str)]) -> Result<Vec<Vec<String>>, CaseError> {
        let pairs: Vec<(String, String)> =
            given.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        let mut vars = Variables::given(&pairs);
        let read = |name: &str| -> Result<String, CaseError> {
            match name {
                "./model_hm.in" => Ok("pair_style gran model hertz # included\n".into()),
                _ => Err(CaseError::Syntax(format!("no {name}"))),
            }
        };
        commands(text, "in.test", &mut vars, &read, 0).map(|c| c.into_iter().map(|c| c.words).collect())
    }

    #[test]
    fn variables_comments_continuations_and_includes() {
        let text = "variable model index hm\nvariable n index 2000 # steps\nvariable d equal 2*0.5e-3\n\
                    timestep $(v_d/100) &\n  extra\ninclude ./model_${model}.in\nrun ${n}\nprint \"a # b\"\n";
        let c = run(text, &[]).unwrap();
        assert_eq!(c[0], ["timestep", "1e-5", "extra"]);
        assert_eq!(c[1], ["pair_style", "gran", "model", "hertz"]);
        assert_eq!(c[2], ["run", "2000"]);
        assert_eq!(c[3], ["print", "a # b"]);
        // A -var value wins over the script's index variable.
        let c = run("variable n index 2000\nrun $n\n", &[("n", "10")]).unwrap();
        assert_eq!(c[0], ["run", "10"]);
    }

    #[test]
    fn formulas_follow_arithmetic() {
        let v = Variables::default();
        // Closed forms: precedence, right-associative power, unary minus, functions.
        assert_eq!(evaluate("1+2*3", &v, 0).unwrap(), 7.0);
        assert_eq!(evaluate("2^3^2", &v, 0).unwrap(), 512.0);
        assert_eq!(evaluate("-(1-3)/4", &v, 0).unwrap(), 0.5);
        assert_eq!(evaluate("sqrt(16)+1.5e1", &v, 0).unwrap(), 19.0);
        assert!((evaluate("cos(PI)", &v, 0).unwrap() + 1.0).abs() < 1e-15);
        assert!(evaluate("1+", &v, 0).is_err());
        assert!(evaluate("v_none", &v, 0).is_err());
        // Comparisons and logic give 1 or 0, below arithmetic in precedence.
        assert_eq!(evaluate("1+1 > 1.5", &v, 0).unwrap(), 1.0);
        assert_eq!(evaluate("2 <= 1 || 3 == 3", &v, 0).unwrap(), 1.0);
        assert_eq!(evaluate("0 > 0 && 1", &v, 0).unwrap(), 0.0);
        assert_eq!(evaluate("(2 != 2) + 5", &v, 0).unwrap(), 5.0);
    }

    /// `if` runs the commands of its first true branch in place; an `equal` variable is
    /// evaluated where it is used, so one of the particles' state that only output reads is
    /// never evaluated.
    #[test]
    fn if_branches_and_lazy_formulas() {
        let text = "variable nd index 0\nvariable xc equal xcm(all,x)\n\
                    if \"${nd} > 0\" then \"shell mkdir post\" \"dump d all custom\"\n\
                    if \"${nd} == 0\" then \"timestep 1e-5\" else \"timestep 2e-5\"\n\
                    if \"${nd} > 1\" then \"run 1\" elif \"${nd} < 1\" \"run 2\" \"run 3\" else \"run 4\"\n";
        let c = run(text, &[]).unwrap();
        assert_eq!(c, [vec!["timestep", "1e-5"], vec!["run", "2"], vec!["run", "3"]]);
        let c = run(text, &[("nd", "5")]).unwrap();
        assert_eq!(c[0], ["shell", "mkdir", "post"]);
        assert_eq!(c[3], ["run", "1"]);
        let e = run("variable xc equal xcm(all,x)\nrun ${xc}\n", &[]).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("xcm"), "{e}");
    }

    #[test]
    fn undefined_variables_and_open_quotes_name_their_line() {
        let e = run("units si\nrun ${steps}\n", &[]).unwrap_err().to_string();
        assert!(e.contains("in.test, line 2") && e.contains("`steps`"), "{e}");
        let e = run("print \"open\n", &[]).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("quote"), "{e}");
        let e = run("variable a loop 10\n", &[]).unwrap_err().to_string();
        assert!(e.contains("loop"), "{e}");
    }
}
