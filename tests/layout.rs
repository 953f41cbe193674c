//! The crate's layout follows its data flow: import (glTF, generators) → bake (plain CPU code)
//! → scene → render (wgpu) → runtime (worlds, level installation) → app (front ends). A module
//! may use its own layer and those before it, never one after: no import cycles between
//! layers, and the bake never reaches the GPU except through the traits render implements.
//! Test modules (`#[cfg(test)]`, at the end of a file) may use anything.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Layers in data-flow order; a module may use modules of its own rank or lower.
const RANKS: [(&str, u32); 15] = [
    ("model", 0),
    ("atomic", 0),
    ("choice", 0),
    // The macros `choice` exports at the crate root.
    ("named_choice", 0),
    ("named_serde", 0),
    ("error", 0),
    ("anim", 1),
    ("generate", 2),
    ("assets", 3),
    ("import", 4),
    ("bake", 5),
    ("scene", 6),
    ("render", 7),
    ("runtime", 8),
    ("app", 9),
];

fn rank(module: &str) -> Option<u32> {
    RANKS.iter().find(|(m, _)| *m == module).map(|&(_, r)| r)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`bake` for `src/bake/character/lod.rs`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// Every `crate::NAME` a file's non-test code names, with a line number.
fn uses(text: &str) -> Vec<(usize, String)> {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = Vec::new();
    for (n, line) in code.lines().enumerate() {
        let line = line.split("//").next().unwrap_or("");
        for (i, _) in line.match_indices("crate::") {
            let name: String = line[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            out.push((n + 1, name));
        }
    }
    out
}

#[test]
fn modules_only_use_earlier_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut wrong = Vec::new();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for file in &files {
        let module = module_of(&src, file);
        let Some(own) = rank(&module) else {
            // lib.rs and main.rs declare and drive everything.
            assert!(
                module == "lib" || module == "main",
                "{}: a top-level module missing from RANKS",
                file.display()
            );
            continue;
        };
        let text = std::fs::read_to_string(file).unwrap();
        for (line, used) in uses(&text) {
            *seen.entry(used.clone()).or_default() += 1;
            match rank(&used) {
                Some(r) if r <= own => {}
                _ => wrong.push(format!(
                    "{}:{line}: {module} uses crate::{used}",
                    file.strip_prefix(&src).unwrap().display()
                )),
            }
        }
    }
    // The scan sees the crate: the bake, the renderer and the runtime are all used somewhere.
    for m in ["bake", "render", "runtime", "scene"] {
        assert!(
            seen.get(m).copied().unwrap_or(0) > 0,
            "no use of crate::{m} found"
        );
    }
    assert!(
        wrong.is_empty(),
        "uses against the data flow:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_bake_never_names_the_gpu() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join("bake");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        for word in ["wgpu::", "Gpu"] {
            assert!(
                !text.contains(word),
                "{}: the bake names {word}; GPU work comes through a trait render implements",
                file.display()
            );
        }
    }
}

/// The packages of the first `apt-get install` in `text` (continuation lines joined), the
/// options and redirections left out.
fn apt_packages(text: &str) -> Vec<String> {
    let joined = text.replace("\\\n", " ");
    let line = joined
        .lines()
        .find(|l| l.contains("apt-get install"))
        .expect("an apt-get install line");
    let after = &line[line.find("install").unwrap() + "install".len()..];
    let mut packages: Vec<String> = after
        .split_whitespace()
        .take_while(|w| !w.starts_with('>'))
        .filter(|w| !w.starts_with('-'))
        .map(String::from)
        .collect();
    packages.sort();
    packages
}

/// The README's prerequisites line is what CI installs: a fresh machine set up by the README
/// is set up as CI's.
#[test]
fn ci_installs_the_readmes_prerequisites() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let prerequisites = &readme[readme.find("## Prerequisites").unwrap()..];
    let ci = std::fs::read_to_string(root.join(".ci/run")).unwrap();
    let wanted = apt_packages(prerequisites);
    assert!(
        wanted.contains(&"libxkbcommon-x11-0".to_string()),
        "{wanted:?}"
    );
    assert_eq!(apt_packages(&ci), wanted);
}

/// The README's inline commands (`lodlab …`, and the `bench …`/`shot …` shorthands of its
/// tables), with their placeholders (`DIR`, `M`, `MODEL`, `T`, `FILE`, `N`, `PX`) filled in; templates with
/// alternatives (`[…]`, `|`, `…`) are left out.
fn readme_commands(readme: &str) -> Vec<Vec<String>> {
    // Fenced blocks hold the synopsis, a template; drop them.
    let mut prose = String::new();
    let mut fenced = false;
    for line in readme.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        } else if !fenced {
            prose.push_str(line);
            prose.push('\n');
        }
    }
    let shorthands = [
        "bench ", "shot ", "record ", "report ", "export ", "bake ", "view ",
    ];
    prose
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|span| span.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter_map(|span| {
            let span = if span.starts_with("lodlab ") || span == "lodlab" {
                span
            } else if shorthands.iter().any(|s| span.starts_with(s)) {
                format!("lodlab {span}")
            } else {
                return None;
            };
            if span.contains(['[', '|', '…']) {
                return None;
            }
            Some(
                span.split(' ')
                    .map(|w| match w {
                        "DIR" => "out-dir",
                        "M" => "as",
                        "MODEL" => "horse",
                        "T" => "alpha",
                        "FILE" => "out.png",
                        "N" => "30",
                        "PX" => "2",
                        w => w,
                    })
                    .map(String::from)
                    .collect(),
            )
        })
        .collect()
}

/// Every command the README shows parses as lodlab's command line does: no renamed or
/// removed option lingers in the prose.
#[test]
fn the_readmes_commands_parse() {
    use clap::Parser;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let commands = readme_commands(&readme);
    assert!(commands.len() >= 25, "{} commands found", commands.len());
    let failures: Vec<String> = commands
        .iter()
        .filter_map(|words| {
            lodlab::app::cli::Cli::try_parse_from(words)
                .err()
                .map(|e| format!("{}: {}", words.join(" "), e.kind()))
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}
