//! The repository's layout: the files ARCHITECTURE.md names exist, and the sources keep the
//! size limits.
//!
//! **Which names are checked.** Every span in backticks in ARCHITECTURE.md that has no space
//! and either contains a `/` (a path: `docs/case-file.md`, `bench/results/`,
//! `simulation/meshes.rs`) or ends in `.rs` (a module file: `case.rs`), except those holding
//! a placeholder (`<`, `*`, or a path starting with `DIR/`). A `{a,b}` part is expanded into
//! one name per choice. A name exists when some file or folder of the repository (outside
//! `target/` and `.git/`) has exactly that path or a path ending in `/` and that name, so a
//! module file may be named from its crate (`tests/threads.rs`) or its folder (`contact/mod.rs`).
//! Module paths written with `::` are not checked.
//!
//! **Size limits** (grainflow issue 39), over every `crates/*/src/**/*.rs`: no function (free,
//! in an `impl` or a trait, nested ones included) longer than 250 lines from `fn` to its closing
//! brace, and no file longer than 1,500 lines once its `#[cfg(test)]` items are left out.

use std::path::{Path, PathBuf};
use syn::spanned::Spanned;
use syn::visit::Visit;

const MAX_FUNCTION_LINES: usize = 250;
const MAX_FILE_LINES: usize = 1_500;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repository root")
}

/// Every file and folder under `dir`, as paths relative to `base` with `/` separators.
fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("folder entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name == "target" || name == ".git" {
            continue;
        }
        let rel = path.strip_prefix(base).expect("under the root");
        out.push(rel.to_string_lossy().replace('\\', "/"));
        if path.is_dir() {
            walk(base, &path, out);
        }
    }
}

/// `a/{b,c}.rs` → `a/b.rs`, `a/c.rs` (one brace group at a time).
fn expand(name: &str) -> Vec<String> {
    match (name.find('{'), name.find('}')) {
        (Some(open), Some(close)) if open < close => name[open + 1..close]
            .split(',')
            .flat_map(|choice| expand(&format!("{}{choice}{}", &name[..open], &name[close + 1..])))
            .collect(),
        _ => vec![name.to_string()],
    }
}

/// The names ARCHITECTURE.md gives in backticks that the rule at the top counts as paths.
fn named_paths(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    for (k, span) in text.split('`').enumerate() {
        let looks_like_path = span.contains('/') || span.ends_with(".rs");
        let placeholder = span.contains(['<', '*']) || span.starts_with("DIR/");
        if k % 2 == 1
            && !span.is_empty()
            && !span.contains(char::is_whitespace)
            && looks_like_path
            && !placeholder
        {
            names.extend(expand(span));
        }
    }
    names.sort();
    names.dedup();
    names
}

#[test]
fn every_path_architecture_names_exists() {
    let root = root();
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let mut paths = Vec::new();
    walk(&root, &root, &mut paths);
    let names = named_paths(&text);
    assert!(names.len() >= 10, "the extraction found only {names:?}");
    let missing: Vec<&String> = names
        .iter()
        .filter(|name| {
            let name = name.trim_end_matches('/');
            !paths.iter().any(|p| p == name || p.ends_with(&format!("/{name}")))
        })
        .collect();
    assert!(missing.is_empty(), "ARCHITECTURE.md names files the repository does not have: {missing:?}");
}

#[test]
fn the_name_rule_picks_paths_and_module_files_only() {
    let text = "`state`, `docs/case-file.md`, `case.rs`, `contact/{lsd,hertz}.rs`, `DIR/<case>/`, \
                `simulation::meshes`, `manifest.toml`, `a b/c`";
    assert_eq!(named_paths(text), ["case.rs", "contact/hertz.rs", "contact/lsd.rs", "docs/case-file.md"]);
}

/// Functions longer than the limit: (first line, name, lines).
#[derive(Default)]
struct LongFunctions(Vec<(usize, String, usize)>);

impl LongFunctions {
    fn measure(&mut self, name: &syn::Ident, fn_token: &syn::token::Fn, body: &syn::Block) {
        let (first, last) = (fn_token.span.start().line, body.brace_token.span.close().end().line);
        let lines = last + 1 - first;
        if lines > MAX_FUNCTION_LINES {
            self.0.push((first, name.to_string(), lines));
        }
    }
}

impl<'ast> Visit<'ast> for LongFunctions {
    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        self.measure(&f.sig.ident, &f.sig.fn_token, &f.block);
        syn::visit::visit_item_fn(self, f);
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        self.measure(&f.sig.ident, &f.sig.fn_token, &f.block);
        syn::visit::visit_impl_item_fn(self, f);
    }

    fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
        if let Some(body) = &f.default {
            self.measure(&f.sig.ident, &f.sig.fn_token, body);
        }
        syn::visit::visit_trait_item_fn(self, f);
    }
}

fn is_cfg_test(attrs: &[syn::Attribute]) -> bool {
    attrs
        .iter()
        .any(|a| a.path().is_ident("cfg") && a.parse_args::<syn::Ident>().is_ok_and(|arg| arg == "test"))
}

fn item_attrs(item: &syn::Item) -> &[syn::Attribute] {
    match item {
        syn::Item::Const(i) => &i.attrs,
        syn::Item::Enum(i) => &i.attrs,
        syn::Item::Fn(i) => &i.attrs,
        syn::Item::Impl(i) => &i.attrs,
        syn::Item::Mod(i) => &i.attrs,
        syn::Item::Static(i) => &i.attrs,
        syn::Item::Struct(i) => &i.attrs,
        syn::Item::Trait(i) => &i.attrs,
        syn::Item::Use(i) => &i.attrs,
        syn::Item::Macro(i) => &i.attrs,
        _ => &[],
    }
}

/// Every violation of the size limits in one source file, as messages.
fn size_violations(rel: &str, text: &str) -> Vec<String> {
    let file = syn::parse_file(text).unwrap_or_else(|e| panic!("{rel}: does not parse: {e}"));
    let mut found = Vec::new();
    let test_lines: usize = file
        .items
        .iter()
        .filter(|item| is_cfg_test(item_attrs(item)))
        .map(|item| {
            let span = item.span();
            span.end().line + 1 - span.start().line
        })
        .sum();
    let lines = text.lines().count() - test_lines;
    if lines > MAX_FILE_LINES {
        found.push(format!("{rel}: {lines} lines outside #[cfg(test)] (limit {MAX_FILE_LINES})"));
    }
    let mut long = LongFunctions::default();
    long.visit_file(&file);
    for (line, name, n) in long.0 {
        found.push(format!("{rel}:{line}: fn {name} has {n} lines (limit {MAX_FUNCTION_LINES})"));
    }
    found
}

#[test]
fn sources_keep_the_size_limits() {
    let root = root();
    let mut paths = Vec::new();
    walk(&root, &root.join("crates"), &mut paths);
    let sources: Vec<&String> =
        paths.iter().filter(|p| p.ends_with(".rs") && p.split('/').nth(2) == Some("src")).collect();
    assert!(sources.len() > 50, "found only {} source files", sources.len());
    let mut violations = Vec::new();
    for rel in sources {
        let text = std::fs::read_to_string(root.join(rel)).expect("source file");
        violations.extend(size_violations(rel, &text));
    }
    assert!(violations.is_empty(), "the size limits of grainflow issue 39:\n{}", violations.join("\n"));
}

#[test]
fn the_size_limits_see_long_functions_and_ignore_tests() {
    let body = "    let x = 1;\n".repeat(MAX_FUNCTION_LINES - 2);
    let fits = format!("fn fits() {{\n{body}}}\n");
    assert!(size_violations("a.rs", &fits).is_empty());
    let long = format!("struct S;\nimpl S {{\n    fn long() {{\n{body}    let y = 2;\n    }}\n}}\n");
    assert_eq!(size_violations("a.rs", &long), ["a.rs:3: fn long has 251 lines (limit 250)"]);
    let filler = "const A: u8 = 0;\n".repeat(MAX_FILE_LINES);
    let tests = format!("#[cfg(test)]\nmod tests {{\n{filler}}}\n");
    assert!(size_violations("b.rs", &format!("{filler}{tests}")).is_empty());
    assert_eq!(
        size_violations("b.rs", &format!("{filler}const B: u8 = 0;\n{tests}")),
        ["b.rs: 1501 lines outside #[cfg(test)] (limit 1500)"]
    );
}
