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
    uses_in("src/design/mod.rs", "use crate::jobs::Registry;\n", "design", &mut uses);
    uses_in("src/stage/ctx.rs", "    let x = crate::pipeline::run(d);\n#[cfg(test)]\nuse crate::pipeline::Files;\n", "stage", &mut uses);
    uses_in("src/gcode/mod.rs", "use crate::geom::DVec3; // crate::jobs in a comment\n", "gcode", &mut uses);
    let bad = breaches(&floors, &uses);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].contains("src/design/mod.rs:1") && bad[0].contains("crate::jobs"), "{}", bad[0]);
    assert!(bad[1].contains("src/stage/ctx.rs:1") && bad[1].contains("crate::pipeline"), "{}", bad[1]);
}
