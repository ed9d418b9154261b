//! The dependency rules of ARCHITECTURE.md ("Dependency rules"): every top-level module of
//! `src/` names (`crate::…`) only modules on lower floors. The table is read from
//! ARCHITECTURE.md itself, so the document and the check cannot drift apart.

use std::collections::BTreeMap;
use std::path::Path;

/// Floor of every module, from ARCHITECTURE.md's table (`| floor | modules | … |`).
fn floors() -> BTreeMap<String, u32> {
    let text = std::fs::read_to_string(crate::common::root().join("ARCHITECTURE.md")).unwrap();
    let section = text.split("## Dependency rules").nth(1).expect("ARCHITECTURE.md has a \"Dependency rules\" section");
    let mut out = BTreeMap::new();
    for line in section.lines().take_while(|l| !l.starts_with("## ")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let Some(floor) = cells.get(1).and_then(|c| c.parse::<u32>().ok()) else { continue };
        for m in cells[2].split(',') {
            out.insert(m.trim().trim_matches('`').to_string(), floor);
        }
    }
    out
}

/// `(module, file, line number, named module)` for every `crate::X` in non-test code.
fn uses_in(file: &str, text: &str, module: &str, out: &mut Vec<(String, String, usize, String)>) {
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("#[cfg(test)]") {
            break;
        }
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            let name: String = rest[at + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if !name.is_empty() && name != module {
                out.push((module.to_string(), file.to_string(), i + 1, name));
            }
            rest = &rest[at + 7..];
        }
    }
}

/// Every `.rs` file under `dir` with its top-level module (the file stem, or the folder).
fn sources(dir: &Path, top: Option<&str>, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if p.is_dir() {
            sources(&p, Some(top.unwrap_or(&name)), out);
        } else if let Some(stem) = name.strip_suffix(".rs") {
            out.push((top.unwrap_or(stem).to_string(), p.to_string_lossy().to_string()));
        }
    }
}

/// The rule's breaches, in words: a `crate::` path to a module not below its own floor.
fn breaches(floors: &BTreeMap<String, u32>, uses: &[(String, String, usize, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (module, file, line, named) in uses {
        let (Some(a), Some(b)) = (floors.get(module), floors.get(named)) else { continue };
        if b >= a {
            out.push(format!("{file}:{line}: `{module}` (floor {a}) names `crate::{named}` (floor {b}): move the code it needs below floor {a}, or move a module in ARCHITECTURE.md's table"));
        }
    }
    out
}

#[test]
fn every_module_names_only_modules_below_it() {
    let floors = floors();
    assert!(floors.len() > 30, "ARCHITECTURE.md's table lists only {} modules", floors.len());
    let src = crate::common::root().join("src");
    let mut files = Vec::new();
    sources(&src, None, &mut files);
    let mut uses = Vec::new();
    let mut missing = Vec::new();
    for (module, file) in &files {
        if module == "lib" {
            continue; // The crate root declares the modules.
        }
        if !floors.contains_key(module) && !missing.contains(module) {
            missing.push(module.clone());
        }
        let text = std::fs::read_to_string(file).unwrap();
        uses_in(file.strip_prefix(&*crate::common::root().to_string_lossy()).unwrap_or(file), &text, module, &mut uses);
    }
    assert!(missing.is_empty(), "modules missing from ARCHITECTURE.md's dependency table: {missing:?}");
    let bad = breaches(&floors, &uses);
    assert!(bad.is_empty(), "{} dependencies point up or sideways:\n{}", bad.len(), bad.join("\n"));
    assert!(uses.len() > 300, "only {} crate:: paths read: the reader is broken", uses.len());
}

#[test]
fn an_upward_use_is_caught() {
    let floors = floors();
    // `design` (the data) naming the kinds, and the runtime naming the pipeline.
    let mut uses = Vec::new();
    uses_in("src/design/mod.rs", "use crate::kinds::Registry;\n", "design", &mut uses);
    uses_in("src/stage/ctx.rs", "    let x = crate::pipeline::run(d);\n#[cfg(test)]\nuse crate::pipeline::Files;\n", "stage", &mut uses);
    uses_in("src/gcode/mod.rs", "use crate::geom::DVec3; // crate::kinds in a comment\n", "gcode", &mut uses);
    let bad = breaches(&floors, &uses);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].contains("src/design/mod.rs:1") && bad[0].contains("crate::kinds"), "{}", bad[0]);
    assert!(bad[1].contains("src/stage/ctx.rs:1") && bad[1].contains("crate::pipeline"), "{}", bad[1]);
}

/// `(file, line number, other kind)` for each name of another kind in `kind`'s files: a kind
/// uses the runtime, the vocabulary of `kinds` and the algorithms, never another kind.
fn other_kinds_named(file: &str, text: &str, kind: &str, kinds: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        // `prefix` followed by the whole name (not `kinds::slice_report` for `slice`).
        let names = |prefix: &str, other: &str| {
            let p = format!("{prefix}{other}");
            code.match_indices(&p).any(|(at, _)| !code[at + p.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_'))
        };
        for other in kinds.iter().filter(|k| *k != kind) {
            if names("kinds::", other) || names("super::super::", other) || (file.ends_with("/mod.rs") && names("super::", other)) {
                out.push(format!("{file}:{}: the kind `{kind}` names the kind `{other}`: move what both need into an algorithm module or the runtime", i + 1));
            }
        }
    }
    out
}

/// Most lines of one file of a kind's folder: the folder reads top to bottom, a concern a file.
const MAX_KIND_FILE_LINES: usize = 500;

#[test]
fn each_kind_is_a_folder_of_small_files_that_names_no_other_kind() {
    let dir = crate::common::root().join("src/kinds");
    let mut kinds: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().to_string())
        .collect();
    kinds.sort();
    assert!(kinds.len() >= 6, "kinds found: {kinds:?}");
    let loose: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".rs") && n != "mod.rs")
        .collect();
    assert!(loose.is_empty(), "kinds outside a folder of their own: {loose:?}");
    let mut bad = Vec::new();
    for kind in &kinds {
        let mut files = Vec::new();
        sources(&dir.join(kind), Some(kind), &mut files);
        assert!(files.iter().any(|(_, f)| f.ends_with("/mod.rs")), "src/kinds/{kind}/ has no mod.rs");
        for (_, file) in &files {
            let text = std::fs::read_to_string(file).unwrap();
            let lines = text.lines().count();
            if lines > MAX_KIND_FILE_LINES {
                bad.push(format!("{file}: {lines} lines (at most {MAX_KIND_FILE_LINES}): split it by concern"));
            }
            bad.extend(other_kinds_named(file, &text, kind, &kinds));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    let caught = other_kinds_named(
        "src/kinds/foam/stages.rs",
        "use crate::kinds::lattice::LatticeJob;\nuse super::*; // kinds::slice\nlet r = crate::kinds::slice_report(&s, \"\");\n",
        "foam",
        &kinds,
    );
    assert_eq!(caught.len(), 1, "{caught:?}");
}
