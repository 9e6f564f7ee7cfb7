//! The module map of `docs/architecture.md`, checked on the source: imports point down only.
//!
//! Every `crate::<module>` path in a library file (comments and strings stripped) must name a
//! module its own module may depend on; a stage file may not name another stage kind; the
//! binary (src/main.rs, src/cli/) reaches the library only through `hdi::`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Top-level library modules and what each may import (besides itself), top to bottom as in
/// docs/architecture.md. `PHYSICS` stands for the five physics modules.
const ALLOWED: &[(&str, &[&str])] = &[
    (
        "report",
        &[
            "validation",
            "engine",
            "stages",
            "slider",
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "validation",
        &[
            "engine",
            "stages",
            "slider",
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "engine",
        &[
            "stages",
            "slider",
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "bench",
        &[
            "samples", "stages", "figures", "core", "error", PHYSICS, "signal", "numerics",
            "formats", "units",
        ],
    ),
    (
        "samples",
        &[
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "stages",
        &[
            "slider",
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "slider",
        &[
            "artefacts",
            "figures",
            "core",
            "error",
            PHYSICS,
            "signal",
            "numerics",
            "formats",
            "units",
        ],
    ),
    (
        "artefacts",
        &[
            "core", "error", PHYSICS, "signal", "numerics", "formats", "units",
        ],
    ),
    ("figures", &[PHYSICS, "signal", "numerics", "units"]),
    (
        "error",
        &["core", "figures", PHYSICS, "signal", "numerics", "units"],
    ),
    ("core", &["units"]),
    ("dynamics", &["contact", "signal", "numerics", "units"]),
    ("surface", &["signal", "numerics", "formats", "units"]),
    ("dmw", &["signal", "numerics", "formats", "units"]),
    ("contact", &["signal", "numerics", "units"]),
    ("analysis", &["signal", "numerics", "formats", "units"]),
    ("signal", &["numerics", "units"]),
    ("numerics", &["units"]),
    ("formats", &[]),
    ("units", &[]),
];
const PHYSICS: &str = "<physics>";
const PHYSICS_MODULES: [&str; 5] = ["surface", "dmw", "contact", "dynamics", "analysis"];

/// Whether `module` may import `target` under [`ALLOWED`].
fn may_import(ok: &[&str], target: &str) -> bool {
    ok.contains(&target) || (ok.contains(&PHYSICS) && PHYSICS_MODULES.contains(&target))
}

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without comments, string and char literals (so a doc line or a message
/// that mentions `crate::x` is not an import).
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let mut depth = 0;
                while i < b.len() {
                    if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                        depth += 1;
                        i += 2;
                    } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            b'r' if b.get(i + 1) == Some(&b'#')
                || (b.get(i + 1) == Some(&b'"')
                    && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'_')) =>
            {
                // Raw string r"…" or r#"…"#.
                let mut j = i + 1;
                let mut hashes = 0;
                while b.get(j) == Some(&b'#') {
                    hashes += 1;
                    j += 1;
                }
                if b.get(j) != Some(&b'"') {
                    out.push('r');
                    i += 1;
                    continue;
                }
                j += 1;
                let close: Vec<u8> = std::iter::once(b'"')
                    .chain(std::iter::repeat_n(b'#', hashes))
                    .collect();
                while j < b.len() && !b[j..].starts_with(&close) {
                    j += 1;
                }
                i = j + close.len();
                out.push_str("\"\"");
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    if b[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
                out.push_str("\"\"");
            }
            b'\'' if b.get(i + 2) == Some(&b'\'') || (b.get(i + 1) == Some(&b'\\')) => {
                // A char literal ('x' or '\n'); lifetimes ('a) are left alone.
                i += 1;
                while i < b.len() && b[i] != b'\'' {
                    if b[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
            }
            c => {
                out.push(c as char);
                i += 1;
            }
        }
    }
    out
}

/// Top-level modules named by `crate::X` paths, including `use crate::{a, b::c}` groups.
fn crate_refs(code: &str) -> BTreeSet<String> {
    let mut refs = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before_ok = at == 0 || {
            let c = rest.as_bytes()[at - 1];
            !(c.is_ascii_alphanumeric() || c == b'_' || c == b'$')
        };
        rest = &rest[at + "crate::".len()..];
        if !before_ok {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            // Names at nesting depth 0 of the group.
            let mut depth = 0;
            let mut name = String::new();
            let mut at_start = true;
            for c in group.chars() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => at_start = true,
                    c if (c.is_alphanumeric() || c == '_') && depth == 0 && at_start => {
                        name.push(c)
                    }
                    _ => {
                        if !name.is_empty() {
                            refs.insert(std::mem::take(&mut name));
                            at_start = false;
                        }
                    }
                }
            }
            if !name.is_empty() {
                refs.insert(name);
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                refs.insert(name);
            }
        }
    }
    refs
}

/// The library's top-level module a file belongs to (`None` for lib.rs and the binary).
fn module_of(rel: &Path) -> Option<String> {
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    let first = first.strip_suffix(".rs").unwrap_or(&first).to_string();
    (!matches!(first.as_str(), "lib" | "main" | "cli")).then_some(first)
}

struct Violation(String);

fn check_library() -> (usize, Vec<Violation>) {
    let allowed: BTreeMap<&str, &[&str]> = ALLOWED.iter().copied().collect();
    let root = src();
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.sort();
    let mut bad = Vec::new();
    let mut checked = 0;
    for f in &files {
        let rel = f.strip_prefix(&root).unwrap();
        let Some(module) = module_of(rel) else {
            continue;
        };
        checked += 1;
        let Some(ok) = allowed.get(module.as_str()) else {
            bad.push(Violation(format!(
                "{}: top-level module `{module}` is not in the module map (tests/architecture.rs, docs/architecture.md)",
                rel.display()
            )));
            continue;
        };
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for r in crate_refs(&code) {
            // `crate::Error`/`crate::Result` are the error module's re-exports.
            let r = if r == "Error" || r == "Result" {
                "error".to_string()
            } else {
                r
            };
            if r == module {
                continue;
            }
            if !may_import(ok, &r) {
                bad.push(Violation(format!(
                    "{}: `{module}` imports `crate::{r}`, which it may not",
                    rel.display()
                )));
            }
        }
    }
    (checked, bad)
}

#[test]
fn library_imports_point_down_only() {
    let (checked, bad) = check_library();
    assert!(
        checked > 100,
        "only {checked} library files found under src/"
    );
    let text: Vec<String> = bad.into_iter().map(|v| v.0).collect();
    assert!(
        text.is_empty(),
        "{} import(s) against the module map:\n{}",
        text.len(),
        text.join("\n")
    );
}

/// The stage contract: the registry (`mod.rs`) and the case capability every kind with
/// cases implements (`case_engine.rs`); every other file or directory of src/stages/ is a kind.
const STAGE_CONTRACT: &[&str] = &["mod", "case_engine"];

/// Stage kinds: the files and directories of src/stages/ (besides the contract).
fn stage_kinds() -> Vec<String> {
    let mut kinds = Vec::new();
    for e in std::fs::read_dir(src().join("stages")).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_str().unwrap().to_string();
        if !STAGE_CONTRACT.contains(&name.as_str()) {
            kinds.push(name);
        }
    }
    kinds.sort();
    kinds
}

#[test]
fn no_stage_imports_another_stage() {
    let kinds = stage_kinds();
    assert!(kinds.len() >= 10, "stage kinds found: {kinds:?}");
    let root = src().join("stages");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let mut bad = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&root).unwrap();
        let own = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_str()
            .unwrap();
        let own = own.strip_suffix(".rs").unwrap_or(own);
        if own == "mod" {
            continue;
        }
        // The contract names no kind either.
        let in_dir = rel.components().count() > 1;
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for other in &kinds {
            if other == own {
                continue;
            }
            // `crate::stages::other` anywhere; `super::other` from a stage file at the top of
            // src/stages/ (its `super` is the registry); `super::super::other` from inside a
            // stage's own directory.
            let mut needles = vec![format!("crate::stages::{other}")];
            needles.push(if in_dir {
                format!("super::super::{other}")
            } else {
                format!("super::{other}")
            });
            for n in needles {
                let hit = code.match_indices(&n).any(|(i, _)| {
                    let after = code[i + n.len()..].chars().next();
                    !after.is_some_and(|c| c.is_alphanumeric() || c == '_')
                });
                if hit {
                    bad.push(format!(
                        "stages/{}: names stage `{other}` ({n})",
                        rel.display()
                    ));
                }
            }
        }
    }
    assert!(bad.is_empty(), "stage → stage imports:\n{}", bad.join("\n"));
}

#[test]
fn the_binary_uses_the_library_only_through_its_public_api() {
    let root = src();
    let mut files = vec![root.join("main.rs")];
    rust_files(&root.join("cli"), &mut files);
    assert!(files.len() >= 2, "no src/cli/ files");
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        // The binary is its own crate: `crate::` there means the binary, so library paths are
        // `hdi::…`; no library module is compiled into it by `#[path]` or `mod` of lib files.
        assert!(
            !code.contains("#[path"),
            "{}: compiles a library file into the binary",
            f.display()
        );
    }
    // …and the library does not name the binary's dependencies.
    let mut lib_files = Vec::new();
    rust_files(&root, &mut lib_files);
    for f in lib_files {
        let rel = f.strip_prefix(&root).unwrap();
        if module_of(rel).is_none() && rel != Path::new("lib.rs") {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(&f).unwrap());
        for dep in ["clap::", "indicatif::", "anyhow::"] {
            assert!(
                !code.contains(dep),
                "{}: the library uses `{dep}` (CLI-only dependency)",
                rel.display()
            );
        }
    }
}

#[test]
fn the_engine_names_no_stage_kind() {
    // The engine drives stages through the contract (`Stage`, `case_engine`), so adding a
    // kind never touches it (issue 31).
    let kinds = stage_kinds();
    let mut files = Vec::new();
    rust_files(&src().join("engine"), &mut files);
    assert!(!files.is_empty());
    let mut bad = Vec::new();
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for path in module_paths(&code, &["engine".to_string()]) {
            if path.first().map(String::as_str) == Some("stages")
                && path.get(1).is_some_and(|k| kinds.contains(k))
            {
                bad.push(format!("{}: names `{}`", f.display(), path.join("::")));
            }
        }
    }
    assert!(bad.is_empty(), "engine → stage kind:\n{}", bad.join("\n"));
}

#[test]
fn every_stage_kind_writes_typed_results_and_rows() {
    // A kind's result and summary row are its own serde types, read back by consumers through
    // the same types (issue 31): never untyped JSON.
    let mut files = Vec::new();
    rust_files(&src().join("stages"), &mut files);
    let mut impls = 0;
    let mut bad = Vec::new();
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for line in code.lines().map(str::trim) {
            if line.starts_with("impl StageKind for") {
                impls += 1;
            }
            let untyped = ["Value", "Map<"].iter().any(|t| line.contains(t));
            if (line.starts_with("type Result =") || line.starts_with("type Row =")) && untyped {
                bad.push(format!("{}: `{line}`", f.display()));
            }
        }
    }
    let mut kinds = stage_kinds();
    kinds.dedup();
    assert_eq!(impls, kinds.len(), "one StageKind impl per kind: {kinds:?}");
    assert!(bad.is_empty(), "untyped stage outputs:\n{}", bad.join("\n"));
}

/// The module path of a library file (`src/slider/sweep.rs` → `slider::sweep`,
/// `src/stages/mod.rs` → `stages`).
fn module_path_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_str().unwrap().to_string())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.strip_suffix(".rs").unwrap_or(&last).to_string();
    if !matches!(stem.as_str(), "mod" | "lib" | "main") {
        parts.push(stem);
    }
    parts
}

/// Every path `crate::…`, `super::…` or `self::…` in `code` (use groups expanded), resolved
/// to an absolute module path from the file's own module path `own`.
fn module_paths(code: &str, own: &[String]) -> Vec<Vec<String>> {
    fn expand(prefix: &str, body: &str, out: &mut Vec<String>) {
        // `a::{b, c::{d, e}}` → a::b, a::c::d, a::c::e
        let body = body.trim();
        if let Some(open) = body.find('{') {
            let head = format!("{prefix}{}", &body[..open]);
            let inner = &body[open + 1..body.rfind('}').unwrap_or(body.len())];
            let mut depth = 0;
            let mut start = 0;
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(&head, &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            expand(&head, &inner[start..], out);
        } else if !body.is_empty() {
            out.push(format!("{prefix}{body}"));
        }
    }
    let mut raw = Vec::new();
    // `use` declarations, with their groups.
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let before_ok = at == 0 || {
            let c = rest.as_bytes()[at - 1];
            !(c.is_ascii_alphanumeric() || c == b'_')
        };
        rest = &rest[at + 4..];
        if !before_ok {
            continue;
        }
        if let Some(end) = rest.find(';') {
            expand("", &rest[..end], &mut raw);
        }
    }
    // Paths in expressions and types.
    let bytes = code.as_bytes();
    for root in ["crate::", "super::", "self::"] {
        for (at, _) in code.match_indices(root) {
            if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
                continue;
            }
            let tail: String = code[at..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            // `super::{…}`: a use group, expanded above.
            if !tail.ends_with("::") {
                raw.push(tail);
            }
        }
    }
    let mut paths = Vec::new();
    for r in raw {
        let r: String = r.split_whitespace().next().unwrap_or("").to_string();
        let mut parts: Vec<&str> = r.split("::").filter(|p| !p.is_empty()).collect();
        let mut base: Vec<String> = match parts.first().copied() {
            Some("crate") => Vec::new(),
            Some("self") => own.to_vec(),
            Some("super") => own.to_vec(),
            _ => continue,
        };
        if parts.first() == Some(&"crate") || parts.first() == Some(&"self") {
            parts.remove(0);
        }
        while parts.first() == Some(&"super") {
            parts.remove(0);
            base.pop();
        }
        base.extend(parts.iter().map(|p| p.to_string()));
        paths.push(base);
    }
    paths
}

/// Strongly connected components of more than one node (Tarjan), each sorted.
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let i = t.index.len();
        t.index.insert(v, i);
        t.low.insert(v, i);
        t.stack.push(v);
        t.on.insert(v);
        if let Some(next) = t.edges.get(v) {
            for w in next {
                let w = w.as_str();
                if !t.index.contains_key(w) {
                    visit(t, w);
                    let l = t.low[w].min(t.low[v]);
                    t.low.insert(v, l);
                } else if t.on.contains(w) {
                    let l = t.index[w].min(t.low[v]);
                    t.low.insert(v, l);
                }
            }
        }
        if t.low[v] == t.index[v] {
            let mut c = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                c.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if c.len() > 1 {
                c.sort();
                t.out.push(c);
            }
        }
    }
    let mut t = T {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

/// The file-level import graph inside the library's modules: an edge from a file to each
/// other file whose items it names, except to and from its own ancestors (a parent module
/// declares and re-exports its children; a child implements its parent's contract).
fn file_graph(root: &Path, files: &[PathBuf]) -> BTreeMap<String, BTreeSet<String>> {
    let modules: BTreeSet<Vec<String>> = files
        .iter()
        .map(|f| module_path_of(f.strip_prefix(root).unwrap()))
        .collect();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let own = module_path_of(f.strip_prefix(root).unwrap());
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        let node = edges.entry(own.join("::")).or_default();
        for path in module_paths(&code, &own) {
            // The deepest module the path names.
            let mut target = path.clone();
            while !target.is_empty() && !modules.contains(&target) {
                target.pop();
            }
            let related = target.starts_with(&own) || own.starts_with(&target);
            if target.is_empty() || related {
                continue;
            }
            node.insert(target.join("::"));
        }
    }
    edges
}

#[test]
fn no_circle_inside_any_module() {
    // The top-level test cannot see a circle between two files of one module (issue 31):
    // `slider::sweep` ↔ `slider::case`, `engine::distributed` ↔ its calibration worker.
    let root = src();
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.retain(|f| module_of(f.strip_prefix(&root).unwrap()).is_some());
    let mut found = circles(&file_graph(&root, &files));
    // The binary: src/main.rs and src/cli/ (`cli::run` ↔ `cli::slurm`).
    let mut binary = vec![root.join("main.rs")];
    rust_files(&root.join("cli"), &mut binary);
    found.extend(circles(&file_graph(&root, &binary)));
    let text: Vec<String> = found.iter().map(|c| c.join(" ↔ ")).collect();
    assert!(
        text.is_empty(),
        "{} circle(s) between files of one module:\n{}",
        text.len(),
        text.join("\n")
    );
}

#[test]
fn the_circle_finder_sees_circles() {
    let code = code_only("use super::{case::X, params};\nfn f() { crate::slider::sweep::g() }\n");
    let own = vec!["slider".to_string(), "calibration".to_string()];
    let paths: Vec<String> = module_paths(&code, &own)
        .into_iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        paths,
        ["slider::case::X", "slider::params", "slider::sweep::g"]
    );
    let mut edges = BTreeMap::new();
    for (a, b) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")] {
        edges
            .entry(a.to_string())
            .or_insert_with(BTreeSet::new)
            .insert(b.to_string());
    }
    assert_eq!(circles(&edges), vec![vec!["a", "b", "c"]]);
}

#[test]
fn the_checker_sees_imports() {
    // The parser itself: a group import, a path, a commented and a quoted mention.
    let code = code_only(
        "use crate::{core::store, figures};\n// crate::stages\nlet s = \"crate::engine\";\nlet x = crate::dmw::x();\n",
    );
    let refs = crate_refs(&code);
    assert_eq!(
        refs.into_iter().collect::<Vec<_>>(),
        vec!["core".to_string(), "dmw".into(), "figures".into()]
    );
}
