//! `--set KEY=VALUE` of `grainflow run` and `grainflow check`: a case-file key set from the
//! command line, applied to the file's TOML before it is validated, so that it is validated
//! exactly as if the file said it.

/// One `--set KEY=VALUE` of `grainflow run` and `grainflow check`: a case-file key by its
/// dotted path, and a TOML value.
///
/// The path walks the case file's tables: `time.t_stop`, `contact.particle.kn`. An element of
/// an array of tables (`[[phases]]`, `[[insertions]]`, …) is named by its position from 0
/// (`insertions.0.count`) or by its `name` (`insertions.pour.count`; `[[insertions.phases]]`
/// by their `phase`: `insertions.pour.phases.glass.fraction`); an element of an array of
/// numbers by its position (`domain.max.2`). A table that is not written yet is created
/// (`output.interval` in a case without `[output]`).
///
/// The value is read as TOML (`0.1`, `true`, `"hertz"`, `[0, 0, -9.81]`); a bare word of
/// letters, digits, `_` and `-` that is not one is taken as a string (`contact.model=hertz`).
#[derive(Debug, Clone, PartialEq)]
pub struct SetOverride {
    /// The path as given, e.g. `time.t_stop`.
    pub path: String,
    /// The value as given.
    pub text: String,
    value: toml::Value,
}

impl SetOverride {
    /// Reads `KEY=VALUE`; the error is the message to print.
    pub fn parse(arg: &str) -> Result<SetOverride, String> {
        let Some((path, text)) = arg.split_once('=') else {
            return Err(format!(
                "--set `{arg}`: give KEY=VALUE with the key's dotted path, e.g. --set time.t_stop=0.1"
            ));
        };
        let (path, text) = (path.trim(), text.trim());
        if path.is_empty() || path.split('.').any(|s| s.trim().is_empty()) {
            return Err(format!(
                "--set `{arg}`: `{path}` is not a key path: names joined by dots, e.g. time.t_stop or insertions.0.count"
            ));
        }
        let value = match toml::from_str::<toml::Table>(&format!("v = {text}")) {
            Ok(mut t) if t.len() == 1 => t.remove("v").expect("the one key"),
            _ if !text.is_empty()
                && text.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
                && text.starts_with(|c: char| c.is_ascii_alphabetic()) =>
            {
                toml::Value::String(text.to_string())
            }
            _ => {
                return Err(format!(
                    "--set `{arg}`: `{text}` is not a TOML value (a number such as 0.1 or 2e-5, true or false, a \"string\", an [array])"
                ));
            }
        };
        Ok(SetOverride { path: path.to_string(), text: text.to_string(), value })
    }

    /// Sets the key in `root` (the case file as a table).
    pub fn apply(&self, root: &mut toml::Table) -> Result<(), String> {
        let segments: Vec<&str> = self.path.split('.').map(str::trim).collect();
        self.set_in_table(root, &segments, 0)
            .map_err(|why| format!("--set {}={}: {why}", self.path, self.text))
    }

    fn set_in_table(&self, t: &mut toml::Table, segments: &[&str], k: usize) -> Result<(), String> {
        let seg = segments[k];
        if k + 1 == segments.len() {
            t.insert(seg.to_string(), self.value.clone());
            return Ok(());
        }
        if !t.contains_key(seg) {
            if segments[k + 1].parse::<usize>().is_ok() {
                return Err(format!(
                    "the case has no `{}` entries to take entry {} of",
                    segments[..=k].join("."),
                    segments[k + 1]
                ));
            }
            t.insert(seg.to_string(), toml::Value::Table(toml::Table::new()));
        }
        self.set_in(t.get_mut(seg).expect("present"), segments, k + 1)
    }

    /// Sets `segments[k..]` in `v`, the value at `segments[..k]`.
    fn set_in(&self, v: &mut toml::Value, segments: &[&str], k: usize) -> Result<(), String> {
        let at = segments[..k].join(".");
        let seg = segments[k];
        match v {
            toml::Value::Table(t) => self.set_in_table(t, segments, k),
            toml::Value::Array(items) => {
                let n = items.len();
                let index = match seg.parse::<usize>() {
                    Ok(i) if i < n => i,
                    Ok(i) => {
                        return Err(format!(
                            "`{at}` has {n} entr{} ({}), not an entry {i} (counted from 0)",
                            if n == 1 { "y" } else { "ies" },
                            if n == 0 { "none".to_string() } else { format!("0 to {}", n - 1) }
                        ));
                    }
                    Err(_) => {
                        let named = |v: &toml::Value, key: &str| {
                            v.get(key).and_then(toml::Value::as_str) == Some(seg)
                        };
                        let found = items.iter().position(|v| named(v, "name"));
                        let found = found.or_else(|| items.iter().position(|v| named(v, "phase")));
                        found.ok_or_else(|| {
                            let names: Vec<String> = items
                                .iter()
                                .filter_map(|v| v.get("name").or_else(|| v.get("phase")))
                                .filter_map(toml::Value::as_str)
                                .map(|s| format!("`{s}`"))
                                .collect();
                            format!(
                                "no entry of `{at}` is named `{seg}` ({}; or give its position from 0)",
                                if names.is_empty() {
                                    "its entries have no names".to_string()
                                } else {
                                    format!("the names are {}", names.join(", "))
                                }
                            )
                        })?
                    }
                };
                if k + 1 == segments.len() {
                    if items[index].is_table() {
                        return Err(format!(
                            "`{}` is a table: give one of its keys, as {}.KEY",
                            self.path, self.path
                        ));
                    }
                    items[index] = self.value.clone();
                    return Ok(());
                }
                self.set_in(&mut items[index], segments, k + 1)
            }
            other => {
                Err(format!("`{at}` is a value ({}), not a table: it has no key `{seg}`", other.type_str()))
            }
        }
    }
}
