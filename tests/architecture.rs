//! The crate's architecture rules, checked by reading `src/` as a reviewer's
//! script would (plain std, no parser crate).
//!
//! # How the sources are read
//!
//! Each `.rs` file under `src/` is *stripped* first: comments (line, block,
//! nested block, doc comments) and the contents of string, raw string, byte
//! string and char literals become spaces, newlines are kept (so line numbers
//! stay right) and lifetimes (`'a`) are left alone. What remains is split into
//! tokens, and every path is collected with its line: `use` trees, groups
//! included (`use crate::{a::{b, c}, d}` names `crate::a::b`, `crate::a::c`
//! and `crate::d`), and paths in code (`crate::x::f(..)`, `super::y::Z`).
//! Inline modules are tracked, so `use super::*` inside `#[cfg(test)] mod
//! tests` in `src/a/b.rs` names `a::b` itself, and `super::super::c` there
//! names the sibling `a::c`: test code counts like any other.
//!
//! A file's module is its path: `src/a.rs` and `src/a/mod.rs` are `a`,
//! `src/a/b.rs` is `a::b`. `src/lib.rs` and `src/main.rs` are crate roots, not
//! modules, and are not sources of edges (`main.rs` is the binary, which sees
//! the library as `mirage::`). A path is resolved to a module path as rustc
//! would: `crate::x` from the root, `self::x` from the current (inline)
//! module, each `super` one level up, and a bare `y::...` only when `y` is a
//! child module of the current module (a file `y.rs` or a folder `y/` next to
//! the module's file); other bare paths (`glam::DVec3`, `std::..`) are not
//! the crate's. A name re-exported by a `mod.rs` (`pub use child::Item;`) is
//! followed to the child that defines it, so `super::Item` in a sibling is a
//! dependency on `child`.
//!
//! # The rules
//!
//! 1. **No cycle between top-level modules.** Edge A → B when a file of A
//!    (`src/A.rs` or `src/A/**`) names a path that resolves into B ≠ A.
//! 2. **No cycle between the files of one folder.** For each module folder
//!    `src/…/F/`, the nodes are its children (each `X.rs`, and each sub-folder
//!    module `Y/`, which stands for all files under it) and its `mod.rs`. Edge
//!    X → Y when a file of X names a path that resolves into child Y of F:
//!    `super::Y` from a non-mod file, `Y::`/`self::Y` from `mod.rs`,
//!    `crate::…::F::Y` from anywhere in F, or an item that `mod.rs` re-exports
//!    from Y. An item defined in `mod.rs` itself, named by a child
//!    (`super::Item`, `use super::*`), is an edge child → `mod.rs`.
//!    *Declarations are not dependencies*: in a `mod.rs`, `mod Y;`/`pub mod
//!    Y;` are not paths at all, and `pub use Y::…` re-exports (any `pub` or
//!    `pub(…)` `use` at the top level of a `mod.rs`) add no edge from
//!    `mod.rs`; they only tell where a re-exported name lives.
//! 3. **No String-typed error.** No `Result<_, E>` whose error type E is
//!    `String`, `&str`, a tuple holding a `String`, or a type alias of one
//!    of those (`type PairError = (&'static str, String)`); no error enum
//!    (name ending in `Error`) with a variant holding just a `String`; no
//!    `Failed(String)` variant anywhere.
//! 4. **No file too long**: every `.rs` file under `src/` is below 1,200
//!    lines.
//! 5. **Every named Markdown file exists.** Checked in every `.rs` file under
//!    `src/` (comments included), `README.md` and `docs/*.md`:
//!    - a Markdown link `[text](target.md#anchor)` is resolved against the
//!      linking file's folder, as GitHub does (web links are skipped);
//!    - any other mention of a name ending in `.md` (in backticks or not): a
//!      name with a `/` (`docs/model.md`) must exist relative to the
//!      repository root or to the naming file's folder; a bare name
//!      (`model.md`) must exist next to the naming file or in `docs/`.
//!      URLs and glob patterns (`*.md`) are skipped.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fs;
use std::path::{Path, PathBuf};

/// Longest file accepted under `src/` (lines, exclusive).
const MAX_LINES: usize = 1200;

/// Rule 2: whether naming an item that a `mod.rs` defines itself (not one it
/// re-exports from a child) is an edge to `mod.rs`. With it, a `mod.rs` that
/// calls into a child which in turn uses the folder's shared items from
/// `mod.rs` is a cycle.
const MOD_RS_IS_A_TARGET: bool = true;

// ---------------------------------------------------------------------------
// Reading the sources: stripping and tokens
// ---------------------------------------------------------------------------

fn is_ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The text with comments and literal contents replaced by spaces; newlines
/// and everything else are kept in place.
fn strip(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let n = c.len();
    let at = |k: usize| if k < n { c[k] } else { '\0' };
    let blank = |ch: char| if ch == '\n' { '\n' } else { ' ' };
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < n {
        let ch = c[i];
        if ch == '/' && at(i + 1) == '/' {
            while i < n && c[i] != '\n' {
                out.push(' ');
                i += 1;
            }
            continue;
        }
        if ch == '/' && at(i + 1) == '*' {
            let mut depth = 1;
            out.push_str("  ");
            i += 2;
            while i < n && depth > 0 {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                } else {
                    out.push(blank(c[i]));
                    i += 1;
                }
            }
            continue;
        }
        if is_ident_start(ch) && (i == 0 || !is_ident_char(c[i - 1])) {
            // Raw strings: r"..", r#".."#, br"..", cr#".."#.
            let mut j = i;
            if c[j] == 'b' || c[j] == 'c' {
                j += 1;
            }
            if at(j) == 'r' {
                let mut k = j + 1;
                let mut hashes = 0;
                while at(k) == '#' {
                    hashes += 1;
                    k += 1;
                }
                if at(k) == '"' {
                    let mut m = k + 1;
                    while m < n {
                        if c[m] == '"' && (0..hashes).all(|h| at(m + 1 + h) == '#') {
                            m += 1 + hashes;
                            break;
                        }
                        m += 1;
                    }
                    for &x in &c[i..m.min(n)] {
                        out.push(blank(x));
                    }
                    i = m;
                    continue;
                }
            }
            // A plain identifier (a `b"..."` prefix stays, its string is
            // blanked when the quote is reached).
            while i < n && is_ident_char(c[i]) {
                out.push(c[i]);
                i += 1;
            }
            continue;
        }
        if ch == '"' {
            out.push(' ');
            i += 1;
            while i < n {
                if c[i] == '\\' {
                    out.push(blank(c[i]));
                    if i + 1 < n {
                        out.push(blank(c[i + 1]));
                    }
                    i += 2;
                    continue;
                }
                let end = c[i] == '"';
                out.push(blank(c[i]));
                i += 1;
                if end {
                    break;
                }
            }
            continue;
        }
        if ch == '\'' {
            // A char literal ('x', '\n', '\'', '\u{..}') or a lifetime ('a).
            let end = if at(i + 1) == '\\' {
                let mut m = i + 3;
                while m < n && c[m] != '\'' && c[m] != '\n' {
                    m += 1;
                }
                Some(m + 1)
            } else if at(i + 2) == '\'' {
                Some(i + 3)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for &x in &c[i..e.min(n)] {
                        out.push(blank(x));
                    }
                    i = e;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
            continue;
        }
        out.push(ch);
        i += 1;
    }
    out
}

#[derive(Clone, Debug, PartialEq)]
struct Token {
    text: String,
    line: usize,
    ident: bool,
}

/// Tokens of stripped code: identifiers (keywords included), `::`, and single
/// punctuation characters; numbers become identifiers that no rule matches.
fn tokenize(code: &str) -> Vec<Token> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if is_ident_char(ch) {
            let start = i;
            while i < c.len() && is_ident_char(c[i]) {
                i += 1;
            }
            out.push(Token {
                text: c[start..i].iter().collect(),
                line,
                ident: is_ident_start(ch),
            });
        } else if ch == ':' && i + 1 < c.len() && c[i + 1] == ':' {
            out.push(Token {
                text: "::".into(),
                line,
                ident: false,
            });
            i += 2;
        } else {
            out.push(Token {
                text: ch.to_string(),
                line,
                ident: false,
            });
            i += 1;
        }
    }
    out
}

/// Parses a path tree starting at `t[i]` (a `use` tree, or a path in code):
/// the full paths it names, and the index after it. Groups are expanded,
/// `as` renames skipped; a path in code ends at its first non-path token
/// (`(`, `<`, `;`, ...).
fn parse_tree(t: &[Token], mut i: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix: Vec<String> = Vec::new();
    if i < t.len() && t[i].text == "::" {
        i += 1;
    }
    while i < t.len() {
        if t[i].text == "{" {
            i += 1;
            let mut out = Vec::new();
            while i < t.len() {
                if t[i].text == "}" {
                    i += 1;
                    break;
                }
                if t[i].text == "," {
                    i += 1;
                    continue;
                }
                let (subs, j) = parse_tree(t, i);
                if j == i {
                    i += 1;
                    continue;
                }
                for s in subs {
                    let mut p = prefix.clone();
                    p.extend(s);
                    out.push(p);
                }
                i = j;
            }
            return (out, i);
        }
        if t[i].text == "*" {
            prefix.push("*".into());
            i += 1;
            break;
        }
        if t[i].ident {
            prefix.push(t[i].text.clone());
            i += 1;
            if i < t.len() && t[i].text == "::" {
                i += 1;
                continue;
            }
            if i + 1 < t.len() && t[i].text == "as" {
                i += 2;
            }
            break;
        }
        break;
    }
    if prefix.is_empty() {
        (Vec::new(), i)
    } else {
        (vec![prefix], i)
    }
}

/// A path named in a file.
#[derive(Clone, Debug, PartialEq)]
struct PathRef {
    /// The segments as written (`super`, `crate`, `self` included).
    segments: Vec<String>,
    /// The (inline) module it is written in, relative to the file's module:
    /// `["tests"]` inside `mod tests { .. }`.
    inline: Vec<String>,
    /// 1-based line.
    line: usize,
    /// Part of a `pub use` (or `pub(..) use`) at the top level of the file.
    reexport: bool,
}

/// Every path named in a file's stripped code.
fn paths_in(code: &str) -> Vec<PathRef> {
    let t = tokenize(code);
    let mut out = Vec::new();
    let mut depth = 0usize;
    // (module name, brace depth inside its body)
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut i = 0;
    while i < t.len() {
        let tok = &t[i];
        match tok.text.as_str() {
            "{" => {
                depth += 1;
                i += 1;
                continue;
            }
            "}" => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
                i += 1;
                continue;
            }
            "mod" if i + 2 < t.len() && t[i + 1].ident && t[i + 2].text == "{" => {
                inline.push((t[i + 1].text.clone(), depth + 1));
                i += 2;
                continue;
            }
            "use" => {
                let public = i >= 1
                    && (t[i - 1].text == "pub"
                        || (t[i - 1].text == ")" && {
                            let mut k = i - 1;
                            while k > 0 && t[k].text != "(" {
                                k -= 1;
                            }
                            k > 0 && t[k - 1].text == "pub"
                        }));
                let (paths, j) = parse_tree(&t, i + 1);
                let names: Vec<String> = inline.iter().map(|(m, _)| m.clone()).collect();
                for p in paths {
                    out.push(PathRef {
                        segments: p,
                        inline: names.clone(),
                        line: tok.line,
                        reexport: public && depth == 0,
                    });
                }
                i = j.max(i + 1);
                continue;
            }
            _ => {}
        }
        let starts_path = tok.ident
            && i + 1 < t.len()
            && t[i + 1].text == "::"
            && (i == 0 || t[i - 1].text != "::");
        if starts_path {
            let (paths, j) = parse_tree(&t, i);
            let names: Vec<String> = inline.iter().map(|(m, _)| m.clone()).collect();
            for p in paths {
                out.push(PathRef {
                    segments: p,
                    inline: names.clone(),
                    line: tok.line,
                    reexport: false,
                });
            }
            i = j.max(i + 1);
            continue;
        }
        i += 1;
    }
    out
}

// ---------------------------------------------------------------------------
// The crate's modules
// ---------------------------------------------------------------------------

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` (recursively) whose name ends with `suffix`, sorted.
fn files_under(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(suffix) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A source file of the library and its module.
struct SourceFile {
    /// Relative to the repository root, with `/` (`src/render/sky.rs`).
    name: String,
    /// `["render", "sky"]`; empty for `lib.rs`.
    module: Vec<String>,
    code: String,
}

/// The module tree as the file system shows it, and every path named.
struct Crate {
    files: Vec<SourceFile>,
    /// Child modules of each module that has a folder (`[]` → top level).
    children: BTreeMap<Vec<String>, BTreeSet<String>>,
    /// `pub use` re-exports at the top level of a `mod.rs` or `lib.rs`:
    /// (module, exported name) → the path it names (unresolved, with the
    /// module it is written in).
    reexports: BTreeMap<(Vec<String>, String), Vec<String>>,
}

/// The module of a file below `src/` (`None` for the crate roots).
fn module_of(rel: &Path) -> Option<Vec<String>> {
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let (dirs, file) = parts.split_at(parts.len() - 1);
    let stem = file[0].strip_suffix(".rs")?;
    if dirs.is_empty() && (stem == "lib" || stem == "main") {
        return None;
    }
    let mut m = dirs.to_vec();
    if stem != "mod" {
        m.push(stem.to_string());
    }
    Some(m)
}

/// The child modules of the module whose folder is `dir`.
fn children_in(dir: &Path, top: bool) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let Ok(entries) = fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            if p.join("mod.rs").is_file() || dir.join(format!("{name}.rs")).is_file() {
                out.insert(name);
            }
        } else if let Some(stem) = name.strip_suffix(".rs") {
            let root_file = top && (stem == "lib" || stem == "main");
            if stem != "mod" && !root_file {
                out.insert(stem.to_string());
            }
        }
    }
    out
}

impl Crate {
    fn read(src: &Path) -> Crate {
        let base = src.parent().unwrap_or(src);
        let mut files = Vec::new();
        let mut children = BTreeMap::new();
        children.insert(Vec::new(), children_in(src, true));
        for path in files_under(src, ".rs") {
            let rel = path.strip_prefix(src).unwrap();
            let name = path
                .strip_prefix(base)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let text = fs::read_to_string(&path).unwrap();
            let module = module_of(rel);
            if let Some(m) = &module {
                let dir = src.join(m.join("/"));
                if dir.is_dir() {
                    children.insert(m.clone(), children_in(&dir, false));
                }
            }
            let is_lib = rel == Path::new("lib.rs");
            if module.is_none() && !is_lib {
                continue; // main.rs: the binary
            }
            files.push(SourceFile {
                name,
                module: module.unwrap_or_default(),
                code: strip(&text),
            });
        }
        let mut reexports = BTreeMap::new();
        for f in &files {
            let facade = f.name.ends_with("/mod.rs") || f.name == "src/lib.rs";
            if !facade {
                continue;
            }
            for r in paths_in(&f.code) {
                if r.reexport && r.inline.is_empty() {
                    if let Some(last) = r.segments.last().filter(|s| *s != "*" && *s != "self") {
                        reexports.insert((f.module.clone(), last.clone()), r.segments.clone());
                    }
                }
            }
        }
        Crate {
            files,
            children,
            reexports,
        }
    }

    fn children(&self, m: &[String]) -> Option<&BTreeSet<String>> {
        self.children.get(m)
    }

    /// The module path (then item names) a path written in module `here`
    /// names, or `None` when it is not the crate's (`std::..`, `glam::..`).
    fn resolve(&self, segments: &[String], here: &[String]) -> Option<Vec<String>> {
        resolve_with(segments, here, &|m| self.children(m).cloned())
            .map(|p| self.follow_reexports(p, 0))
    }

    /// Replaces a name re-exported by a façade (`pub use child::Item` in
    /// `mod.rs`) with the path of its definition.
    fn follow_reexports(&self, p: Vec<String>, depth: usize) -> Vec<String> {
        if depth > 8 {
            return p;
        }
        // The longest prefix that is a module with a folder; the next segment
        // is an item of it, or a child module.
        for k in (0..p.len()).rev() {
            let (m, rest) = p.split_at(k);
            let Some(children) = self.children(m) else {
                continue;
            };
            if children.contains(&rest[0]) {
                return p;
            }
            if let Some(target) = self.reexports.get(&(m.to_vec(), rest[0].clone())) {
                if let Some(mut q) = self.resolve_raw(target, m) {
                    q.extend(rest[1..].iter().cloned());
                    return self.follow_reexports(q, depth + 1);
                }
            }
            return p;
        }
        p
    }

    fn resolve_raw(&self, segments: &[String], here: &[String]) -> Option<Vec<String>> {
        resolve_with(segments, here, &|m| self.children(m).cloned())
    }
}

/// Resolution as rustc does it, given the child modules of each module.
fn resolve_with(
    segments: &[String],
    here: &[String],
    children: &dyn Fn(&[String]) -> Option<BTreeSet<String>>,
) -> Option<Vec<String>> {
    let first = segments.first()?;
    let mut out: Vec<String> = match first.as_str() {
        "crate" => segments[1..].to_vec(),
        "self" => here.iter().chain(&segments[1..]).cloned().collect(),
        "super" => {
            let ups = segments.iter().take_while(|s| *s == "super").count();
            if ups > here.len() {
                return None;
            }
            here[..here.len() - ups]
                .iter()
                .chain(&segments[ups..])
                .cloned()
                .collect()
        }
        name => {
            if children(here).is_some_and(|c| c.contains(name)) {
                here.iter().chain(segments).cloned().collect()
            } else {
                return None;
            }
        }
    };
    while out.last().is_some_and(|s| s == "*" || s == "self") {
        out.pop();
    }
    Some(out)
}

/// Where a dependency was seen.
#[derive(Clone, Debug)]
struct Evidence {
    file: String,
    line: usize,
    path: String,
}

type Graph = BTreeMap<String, BTreeMap<String, Vec<Evidence>>>;

fn add_edge(g: &mut Graph, from: &str, to: &str, ev: Evidence) {
    g.entry(to.to_string()).or_default();
    g.entry(from.to_string())
        .or_default()
        .entry(to.to_string())
        .or_default()
        .push(ev);
}

/// The strongly connected components with more than one node (Tarjan).
fn cycles(g: &Graph) -> Vec<Vec<String>> {
    struct State<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        next: usize,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        let g = s.g;
        for w in g[v].keys() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in g.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out.sort();
    s.out
}

/// A shortest cycle through `start` inside `comp`.
fn shortest_cycle(g: &Graph, comp: &[String], start: &str) -> Vec<String> {
    let inside: BTreeSet<&str> = comp.iter().map(|s| s.as_str()).collect();
    let mut prev: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = VecDeque::from([start]);
    while let Some(v) = queue.pop_front() {
        for w in g[v].keys().map(|w| w.as_str()) {
            if !inside.contains(w) {
                continue;
            }
            if w == start {
                let mut path = vec![v.to_string()];
                let mut x = v;
                while x != start {
                    x = prev[x];
                    path.push(x.to_string());
                }
                path.reverse();
                path.push(start.to_string());
                return path;
            }
            if !prev.contains_key(w) && w != start {
                prev.insert(w, v);
                queue.push_back(w);
            }
        }
    }
    vec![start.to_string()]
}

/// One paragraph per cycle: the cycle, then every edge inside its component
/// with where it is named.
fn describe_cycles(what: &str, g: &Graph) -> Vec<String> {
    let mut out = Vec::new();
    for comp in cycles(g) {
        let cycle = shortest_cycle(g, &comp, &comp[0]);
        let mut msg = format!(
            "{what}: cycle {}  (component: {})",
            cycle.join(" → "),
            comp.join(", ")
        );
        for a in &comp {
            for (b, evs) in &g[a] {
                if !comp.contains(b) {
                    continue;
                }
                // One line per place, with every path named there.
                let mut places: Vec<(String, usize, Vec<&str>)> = Vec::new();
                for e in evs {
                    match places.last_mut() {
                        Some((f, l, paths)) if *f == e.file && *l == e.line => paths.push(&e.path),
                        _ => places.push((e.file.clone(), e.line, vec![&e.path])),
                    }
                }
                msg.push_str(&format!("\n    {a} → {b}:"));
                for (file, line, paths) in places.iter().take(8) {
                    let paths: Vec<String> = paths.iter().map(|p| format!("`{p}`")).collect();
                    msg.push_str(&format!("\n        {file}:{line}  {}", paths.join(", ")));
                }
                if places.len() > 8 {
                    msg.push_str(&format!("\n        … and {} more places", places.len() - 8));
                }
            }
        }
        out.push(msg);
    }
    out
}

fn node_name(krate: &Crate, folder: &[String], child: &str) -> String {
    let dir: Vec<&str> = folder.iter().map(|s| s.as_str()).collect();
    let base = format!("src/{}", dir.join("/"));
    let is_dir = krate.children.contains_key(
        &folder
            .iter()
            .cloned()
            .chain([child.to_string()])
            .collect::<Vec<_>>(),
    );
    if is_dir {
        format!("{base}/{child}/")
    } else {
        format!("{base}/{child}.rs")
    }
}

/// Every resolved path of every library file: (file, its module, evidence,
/// resolved path, is a top-level re-export of a façade).
fn resolved_refs(krate: &Crate) -> Vec<(&SourceFile, Evidence, Vec<String>, bool)> {
    let mut out = Vec::new();
    for f in &krate.files {
        let facade = f.name.ends_with("/mod.rs") || f.name == "src/lib.rs";
        for r in paths_in(&f.code) {
            let here: Vec<String> = f.module.iter().chain(&r.inline).cloned().collect();
            let Some(p) = krate.resolve(&r.segments, &here) else {
                continue;
            };
            let ev = Evidence {
                file: f.name.clone(),
                line: r.line,
                path: r.segments.join("::").trim_end_matches("::self").to_string(),
            };
            out.push((f, ev, p, facade && r.reexport && r.inline.is_empty()));
        }
    }
    out
}

fn top_level_graph(krate: &Crate) -> Graph {
    let top = krate.children(&[]).cloned().unwrap_or_default();
    let mut g = Graph::new();
    for (f, ev, p, _) in resolved_refs(krate) {
        let (Some(a), Some(b)) = (f.module.first(), p.first()) else {
            continue;
        };
        if a != b && top.contains(b) {
            add_edge(&mut g, a, b, ev);
        }
    }
    g
}

/// The graph of each module folder (rule 2), by folder module path.
fn folder_graphs(krate: &Crate) -> BTreeMap<Vec<String>, Graph> {
    let mut graphs: BTreeMap<Vec<String>, Graph> = BTreeMap::new();
    let refs = resolved_refs(krate);
    for (folder, children) in &krate.children {
        if folder.is_empty() {
            continue; // src/ itself: rule 1
        }
        let k = folder.len();
        let mod_rs = format!("src/{}/mod.rs", folder.join("/"));
        let mut g = Graph::new();
        for (f, ev, p, reexport) in &refs {
            if !f.module.starts_with(folder) {
                continue;
            }
            let from = if f.module.len() == k {
                if *reexport {
                    continue; // declarations are not dependencies
                }
                mod_rs.clone()
            } else {
                node_name(krate, folder, &f.module[k])
            };
            if !p.starts_with(folder) {
                continue;
            }
            let to = match p.get(k) {
                Some(c) if children.contains(c) => node_name(krate, folder, c),
                _ if MOD_RS_IS_A_TARGET => mod_rs.clone(),
                _ => continue,
            };
            if from != to {
                add_edge(&mut g, &from, &to, ev.clone());
            }
        }
        graphs.insert(folder.clone(), g);
    }
    graphs
}

fn crate_src() -> Crate {
    Crate::read(&root().join("src"))
}

// ---------------------------------------------------------------------------
// Rule 3: String-typed errors
// ---------------------------------------------------------------------------

/// Splits the generic arguments of `t[open]` = `<` at depth 0; returns them
/// and the index after the matching `>`.
fn generic_args(t: &[Token], open: usize) -> (Vec<Vec<Token>>, usize) {
    let mut args = vec![Vec::new()];
    let mut depth = 0i32;
    let mut i = open;
    while i < t.len() {
        let s = t[i].text.as_str();
        // The `>` of `->` (in `Fn(A) -> B`) closes nothing.
        let arrow = s == ">" && i > 0 && t[i - 1].text == "-";
        match s {
            "<" | "(" | "[" => depth += 1,
            ">" if !arrow => depth -= 1,
            ")" | "]" => depth -= 1,
            _ => {}
        }
        if depth <= 0 {
            return (args, i + 1);
        }
        if i != open {
            if depth == 1 && s == "," {
                args.push(Vec::new());
            } else {
                args.last_mut().unwrap().push(t[i].clone());
            }
        }
        i += 1;
    }
    (args, i)
}

/// Whether a type, as tokens, is `String`, `&str`, a tuple holding a
/// `String`, or an alias of one of those.
fn stringy(ty: &[Token], aliases: &BTreeMap<String, Vec<Token>>, depth: usize) -> bool {
    let words: Vec<&str> = ty
        .iter()
        .map(|t| t.text.as_str())
        .filter(|s| *s != "'" && *s != "static" && *s != "::" && *s != "std" && *s != "string")
        .collect();
    match words.as_slice() {
        ["String"] | ["&", "str"] | ["Box", "<", "str", ">"] => true,
        ["(", .., ")"] => ty.iter().any(|t| t.text == "String"),
        [name] if depth < 4 => aliases
            .get(*name)
            .is_some_and(|def| stringy(def, aliases, depth + 1)),
        _ => false,
    }
}

fn string_error_violations(krate: &Crate) -> Vec<String> {
    // Type aliases across the crate: `type Name = ...;` (non-generic).
    let mut aliases: BTreeMap<String, Vec<Token>> = BTreeMap::new();
    let tokens: Vec<(&SourceFile, Vec<Token>)> =
        krate.files.iter().map(|f| (f, tokenize(&f.code))).collect();
    for (_, t) in &tokens {
        for i in 0..t.len().saturating_sub(3) {
            if t[i].text == "type" && t[i + 1].ident && t[i + 2].text == "=" {
                let end = (i + 3..t.len())
                    .find(|&k| t[k].text == ";")
                    .unwrap_or(t.len());
                aliases.insert(t[i + 1].text.clone(), t[i + 3..end].to_vec());
            }
        }
    }
    let mut out = Vec::new();
    for (f, t) in &tokens {
        let mut enum_stack: Vec<(String, i32)> = Vec::new();
        let mut depth = 0i32;
        for i in 0..t.len() {
            let s = t[i].text.as_str();
            if s == "Result" && i + 1 < t.len() && t[i + 1].text == "<" {
                let (args, _) = generic_args(t, i + 1);
                if args.len() == 2 && stringy(&args[1], &aliases, 0) {
                    let e: Vec<&str> = args[1].iter().map(|t| t.text.as_str()).collect();
                    out.push(format!(
                        "{}:{}: a Result with a String-typed error `{}`",
                        f.name,
                        t[i].line,
                        e.join(" ")
                    ));
                }
            }
            if s == "enum" && i + 2 < t.len() && t[i + 1].ident {
                // The body opens at the next `{`.
                enum_stack.push((t[i + 1].text.clone(), depth + 1));
            }
            match s {
                "{" => depth += 1,
                "}" => {
                    if enum_stack.last().is_some_and(|(_, d)| *d == depth) {
                        enum_stack.pop();
                    }
                    depth -= 1;
                }
                _ => {}
            }
            let single_string = t[i].ident
                && i + 3 < t.len()
                && t[i + 1].text == "("
                && t[i + 2].text == "String"
                && t[i + 3].text == ")";
            if single_string {
                let in_error_enum = enum_stack
                    .last()
                    .is_some_and(|(name, d)| *d == depth && name.ends_with("Error"));
                if s == "Failed" || in_error_enum {
                    out.push(format!(
                        "{}:{}: a String-typed error variant `{s}(String)`",
                        f.name, t[i].line
                    ));
                }
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------
// Rule 5: Markdown names
// ---------------------------------------------------------------------------

/// A Markdown file named somewhere, and how it must be resolved.
#[derive(Debug, PartialEq)]
enum MdName {
    /// `[text](target)`: relative to the linking file.
    Link(String),
    /// A mention in prose, code or comments.
    Mention(String),
}

fn is_path_char(c: char) -> bool {
    c.is_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

/// Every Markdown file named in `text`, with its line.
fn md_names(text: &str) -> Vec<(usize, MdName)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let c: Vec<char> = line.chars().collect();
        let mut link_spans: Vec<(usize, usize)> = Vec::new();
        // Markdown links: `](target)`.
        let mut i = 0;
        while i + 1 < c.len() {
            if c[i] == ']' && c[i + 1] == '(' {
                if let Some(len) = c[i + 2..].iter().position(|&x| x == ')') {
                    let target: String = c[i + 2..i + 2 + len].iter().collect();
                    let target = target.split_whitespace().next().unwrap_or("").to_string();
                    let file = target.split('#').next().unwrap_or("").to_string();
                    if file.ends_with(".md")
                        && !target.contains("://")
                        && !file.starts_with("mailto:")
                    {
                        out.push((n + 1, MdName::Link(file)));
                    }
                    link_spans.push((i + 2, i + 2 + len));
                    i += 2 + len;
                    continue;
                }
            }
            i += 1;
        }
        // Mentions: any word ending in `.md`.
        let mut i = 0;
        while i + 3 <= c.len() {
            let ends = c[i] == '.' && c[i + 1] == 'm' && c[i + 2] == 'd';
            let bounded = i + 3 == c.len() || !is_ident_char(c[i + 3]);
            if !(ends && bounded) || link_spans.iter().any(|&(a, b)| a <= i && i < b) {
                i += 1;
                continue;
            }
            let mut start = i;
            while start > 0 && is_path_char(c[start - 1]) {
                start -= 1;
            }
            let mut word_start = start;
            while word_start > 0 && !c[word_start - 1].is_whitespace() {
                word_start -= 1;
            }
            let word: String = c[word_start..i + 3].iter().collect();
            let name: String = c[start..i + 3].iter().collect();
            let name = name.trim_start_matches(['.', '/']).to_string();
            let skip = word.contains("://")
                || word.contains('*')
                || name == ".md"
                || name.is_empty()
                || c[start..i].is_empty();
            if !skip {
                out.push((n + 1, MdName::Mention(name)));
            }
            i += 3;
        }
    }
    out
}

/// Whether `name`, found in the file `from` (relative to the repository
/// root), names a file that exists, by the rules of the module docs.
fn md_exists(repo: &Path, from: &str, name: &MdName) -> bool {
    let folder = repo.join(from).parent().unwrap().to_path_buf();
    match name {
        MdName::Link(target) => folder.join(target).is_file(),
        MdName::Mention(m) if m.contains('/') => repo.join(m).is_file() || folder.join(m).is_file(),
        MdName::Mention(m) => folder.join(m).is_file() || repo.join("docs").join(m).is_file(),
    }
}

// ---------------------------------------------------------------------------
// The rules
// ---------------------------------------------------------------------------

#[test]
fn no_cycle_between_top_level_modules() {
    let krate = crate_src();
    let problems = describe_cycles("top-level modules", &top_level_graph(&krate));
    assert!(
        problems.is_empty(),
        "{} cycle(s) between top-level modules of the crate:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn no_cycle_between_files_of_a_folder() {
    let krate = crate_src();
    let mut problems = Vec::new();
    for (folder, g) in folder_graphs(&krate) {
        problems.extend(describe_cycles(&format!("src/{}/", folder.join("/")), &g));
    }
    assert!(
        problems.is_empty(),
        "{} cycle(s) between the files of a folder:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn no_string_typed_error() {
    let krate = crate_src();
    let problems = string_error_violations(&krate);
    assert!(
        problems.is_empty(),
        "{} String-typed error(s) (use crate::error::FieldError or a typed \
         crate::error::Error variant):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn no_source_file_is_too_long() {
    let repo = root();
    let mut problems = Vec::new();
    for path in files_under(&repo.join("src"), ".rs") {
        let lines = fs::read_to_string(&path).unwrap().lines().count();
        if lines >= MAX_LINES {
            let name = path.strip_prefix(&repo).unwrap().display();
            problems.push(format!("{name}: {lines} lines (limit: below {MAX_LINES})"));
        }
    }
    assert!(
        problems.is_empty(),
        "{} file(s) too long:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn every_named_markdown_file_exists() {
    let repo = root();
    let mut sources: Vec<PathBuf> = files_under(&repo.join("src"), ".rs");
    sources.push(repo.join("README.md"));
    sources.extend(files_under(&repo.join("docs"), ".md"));
    let mut problems = Vec::new();
    for path in sources {
        let Ok(text) = fs::read_to_string(&path) else {
            continue;
        };
        let from = path
            .strip_prefix(&repo)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        for (line, name) in md_names(&text) {
            if !md_exists(&repo, &from, &name) {
                let (kind, n) = match &name {
                    MdName::Link(n) => ("link to", n),
                    MdName::Mention(n) => ("mention of", n),
                };
                problems.push(format!("{from}:{line}: {kind} `{n}`, which does not exist"));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{} Markdown file(s) named but missing (a bare name must lie next to the \
         naming file or in docs/; a path with `/` is from the repository root):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

// ---------------------------------------------------------------------------
// The reader itself, on small inline examples
// ---------------------------------------------------------------------------

fn segs(code: &str) -> Vec<String> {
    paths_in(&strip(code))
        .into_iter()
        .map(|r| r.segments.join("::"))
        .collect()
}

#[test]
fn reader_expands_nested_use_groups() {
    assert_eq!(
        segs("use crate::{a::{b, c as d}, e, f::*};"),
        ["crate::a::b", "crate::a::c", "crate::e", "crate::f::*"]
    );
    assert_eq!(
        segs("use super::{self, x::Y};"),
        ["super::self", "super::x::Y"]
    );
    assert_eq!(
        segs("pub(crate) use ::std::io;\nuse x::y;"),
        ["std::io", "x::y"]
    );
}

#[test]
fn reader_finds_paths_in_code() {
    assert_eq!(
        segs("fn f() -> crate::a::B<T> { crate::c::g::<u8>(super::h::I) }"),
        ["crate::a::B", "crate::c::g", "super::h::I"]
    );
    // `pub(crate)` is a visibility, not a path.
    assert!(segs("pub(crate) fn f() {}").is_empty());
}

#[test]
fn reader_ignores_strings_and_comments() {
    let code = r##"
        // use crate::x;
        /* crate::y /* nested crate::z */ still crate::w */
        /// doc: [`crate::v`]
        let s = "crate::u \" crate::t";
        let r = r#"crate::s "# ;
        let b = b"crate::q";
        let c = '"'; let d = '\''; fn l<'a>(x: &'a str) -> crate::real::One {}
    "##;
    assert_eq!(segs(code), ["crate::real::One"]);
    // Lines are kept.
    let stripped = strip("/* a\nb */ crate::x::Y");
    assert_eq!(paths_in(&stripped)[0].line, 2);
}

#[test]
fn reader_tracks_inline_modules_and_reexports() {
    let code = "pub use a::B;\nmod tests { use super::*; use super::super::c::D; }";
    let refs = paths_in(&strip(code));
    assert_eq!(refs.len(), 3);
    assert!(refs[0].reexport && refs[0].inline.is_empty());
    assert_eq!(refs[1].inline, ["tests"]);
    assert!(!refs[2].reexport);
    // Resolution: in `x::y`'s tests module, super::super::c is the sibling x::c.
    let children = |m: &[String]| -> Option<BTreeSet<String>> {
        (m == ["x".to_string()]).then(|| ["y".to_string(), "c".to_string()].into())
    };
    let here = ["x", "y", "tests"].map(String::from);
    let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        resolve_with(&s(&["super", "super", "c", "D"]), &here, &children),
        Some(s(&["x", "c", "D"]))
    );
    assert_eq!(
        resolve_with(&s(&["super", "*"]), &here, &children),
        Some(s(&["x", "y"]))
    );
    // A bare path is the crate's only when it starts with a child module.
    let mod_rs = ["x".to_string()];
    assert_eq!(
        resolve_with(&s(&["c", "D"]), &mod_rs, &children),
        Some(s(&["x", "c", "D"]))
    );
    assert_eq!(
        resolve_with(&s(&["glam", "DVec3"]), &mod_rs, &children),
        None
    );
}

#[test]
fn cycles_are_found_and_described() {
    let ev = |l| Evidence {
        file: "src/a.rs".into(),
        line: l,
        path: "crate::b".into(),
    };
    let mut g = Graph::new();
    add_edge(&mut g, "a", "b", ev(1));
    add_edge(&mut g, "b", "c", ev(2));
    add_edge(&mut g, "c", "a", ev(3));
    add_edge(&mut g, "c", "d", ev(4));
    assert_eq!(cycles(&g), vec![vec!["a", "b", "c"]]);
    let d = describe_cycles("test", &g);
    assert!(d[0].starts_with("test: cycle a → b → c → a"), "{}", d[0]);
    assert!(d[0].contains("src/a.rs:3  `crate::b`"), "{}", d[0]);
    // Several paths on one line are one place.
    add_edge(&mut g, "a", "b", ev(1));
    let d = describe_cycles("test", &g);
    assert!(
        d[0].contains("src/a.rs:1  `crate::b`, `crate::b`"),
        "{}",
        d[0]
    );
}

#[test]
fn string_errors_are_recognised() {
    let t = |s: &str| tokenize(&strip(s));
    let aliases = BTreeMap::from([("PairError".to_string(), t("(&'static str, String)"))]);
    for bad in [
        "String",
        "&'static str",
        "std::string::String",
        "(usize, String)",
        "PairError",
    ] {
        assert!(stringy(&t(bad), &aliases, 0), "{bad}");
    }
    for good in ["Error", "FieldError", "(usize, f64)", "Vec<u8>"] {
        assert!(!stringy(&t(good), &aliases, 0), "{good}");
    }
    let toks = t("Result<Vec<(u8, String)>, Box<dyn Fn(u8) -> u8>>");
    let (args, _) = generic_args(&toks, 1);
    assert_eq!(args.len(), 2);
    assert!(!stringy(&args[1], &aliases, 0));
}

#[test]
fn markdown_names_are_found() {
    let text = "See [the model](docs/model.md#rays), `docs/air.md`, model.md and \
                <https://example.com/x.md>, *.md.\n//! (`problem-format.md`)";
    let names = md_names(text);
    assert_eq!(
        names,
        vec![
            (1, MdName::Link("docs/model.md".into())),
            (1, MdName::Mention("docs/air.md".into())),
            (1, MdName::Mention("model.md".into())),
            (2, MdName::Mention("problem-format.md".into())),
        ]
    );
}

#[test]
fn markdown_names_resolve_by_the_rules() {
    let repo = root();
    let exists = |from: &str, name: MdName| md_exists(&repo, from, &name);
    // A bare mention: next to the naming file, or in docs/.
    assert!(exists(
        "src/io/problem.rs",
        MdName::Mention("model.md".into())
    ));
    assert!(!exists(
        "src/io/problem.rs",
        MdName::Mention("no-such-spec.md".into())
    ));
    // A path: from the repository root (or the naming file's folder).
    assert!(exists(
        "src/io/problem.rs",
        MdName::Mention("docs/model.md".into())
    ));
    assert!(!exists(
        "src/io/problem.rs",
        MdName::Mention("spec/model.md".into())
    ));
    // A link: relative to the linking file only.
    assert!(exists("README.md", MdName::Link("docs/model.md".into())));
    assert!(!exists("README.md", MdName::Link("model.md".into())));
    assert!(exists("docs/air.md", MdName::Link("model.md".into())));
}
