//! The crate's layout follows its data flow: import (glTF, generators) → bake (plain CPU code)
//! → scene → render (wgpu) → runtime (worlds, level installation) → measure (measurements that
//! draw worlds) → app (front ends). A module may use its own layer and those before it, never
//! one after: no import cycles between layers, none between the files of a layer either, and
//! the bake never reaches the GPU except through the traits of `bake::gpu_products`, which render and
//! measure implement. Test modules (`#[cfg(test)]`, at the end of a file) may use anything.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Layers in data-flow order; a module may use modules of its own rank or lower.
const RANKS: [(&str, u32); 16] = [
    ("model", 0),
    ("atomic", 0),
    ("choice", 0),
    // The macros `choice` exports at the crate root (`crate::choice!` is named as the module).
    ("named_serde", 0),
    ("error", 0),
    ("anim", 1),
    ("geometry", 1),
    ("generate", 2),
    ("assets", 3),
    ("import", 4),
    ("bake", 5),
    ("scene", 6),
    ("render", 7),
    ("runtime", 8),
    ("measure", 9),
    ("app", 10),
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

/// The module path of a file of `src/` (`["bake", "character", "lod"]` for
/// `src/bake/character/lod.rs`; a `mod.rs` is its folder's module).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut path: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if path.last().is_some_and(|l| l == "mod") {
        path.pop();
    }
    path
}

/// The file that holds the longest prefix of module path `segments` that is a file of `src/`.
fn file_of(src: &Path, segments: &[String]) -> Option<PathBuf> {
    let mut found = None;
    let mut dir = src.to_path_buf();
    for s in segments {
        let (file, module) = (dir.join(format!("{s}.rs")), dir.join(s).join("mod.rs"));
        if file.is_file() {
            found = Some(file);
        } else if module.is_file() {
            found = Some(module);
        } else {
            break;
        }
        dir = dir.join(s);
    }
    found
}

/// The files of `src/` a file's non-test code names: through `crate::`, `super::`, `self::`
/// or a child module's name. A module's declarations and re-exports of its own children
/// (`pub mod x;`, `pub use x::Y;`) are not uses: they are how Rust spells a folder.
fn file_uses(src: &Path, file: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(file).unwrap();
    let code = ungroup_uses(text.split("#[cfg(test)]").next().unwrap_or(""));
    let code = code.as_str();
    let own = module_path(src, file);
    let children: Vec<String> = code
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            let rest = l
                .strip_prefix("pub mod ")
                .or_else(|| l.strip_prefix("mod "))?;
            Some(rest.trim_end_matches(';').to_string())
        })
        .collect();
    let mut out = Vec::new();
    for line in code.lines() {
        let line = line.split("//").next().unwrap_or("");
        let trimmed = line.trim_start();
        let declares = ["pub mod ", "mod ", "pub use ", "pub(crate) use "]
            .iter()
            .any(|p| trimmed.starts_with(p));
        let words: Vec<&str> = line
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
            .filter(|w| w.contains("::"))
            .collect();
        for word in words {
            let parts: Vec<&str> = word.split("::").filter(|p| !p.is_empty()).collect();
            let Some(&first) = parts.first() else {
                continue;
            };
            let mut path: Vec<String> = match first {
                "crate" => Vec::new(),
                "super" | "self" => own.clone(),
                w if children.iter().any(|c| c == w) => own.clone(),
                _ => continue,
            };
            let mut rest = &parts[..];
            if first == "crate" {
                rest = &parts[1..];
            }
            while let Some((&p, tail)) = rest.split_first() {
                match p {
                    "super" => {
                        path.pop();
                    }
                    "self" => {}
                    _ => break,
                }
                rest = tail;
            }
            path.extend(rest.iter().map(|s| s.to_string()));
            let Some(target) = file_of(src, &path) else {
                continue;
            };
            if target == file {
                continue;
            }
            let within = module_path(src, &target).starts_with(&own);
            if declares && within {
                continue;
            }
            out.push(target);
        }
    }
    out.sort();
    out.dedup();
    out
}

/// `code` (comments dropped) with every grouped import, `use a::{b, c::{d, e}};` over one line
/// or several, written out as one `use` a path (`use a::b;`, `use a::c::d;`, …), so that every
/// file it names is seen, not only `a`.
fn ungroup_uses(code: &str) -> String {
    let mut out = String::new();
    let mut statement = String::new();
    for line in code.lines() {
        let line = line.split("//").next().unwrap_or("");
        let trimmed = line.trim_start();
        let starts = ["use ", "pub use ", "pub(crate) use ", "pub(super) use "]
            .iter()
            .any(|p| trimmed.starts_with(p));
        if statement.is_empty() && !(starts && line.contains('{')) {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        statement.push_str(trimmed);
        statement.push(' ');
        if !line.contains(';') {
            continue;
        }
        let (head, tree) = statement.split_once("use ").unwrap();
        for path in expand_use_tree(tree.trim().trim_end_matches(';')) {
            out.push_str(&format!("{head}use {path};\n"));
        }
        statement.clear();
    }
    out
}

/// The paths of a use tree: `a::{b, c::{d, self}}` gives `a::b`, `a::c::d` and `a::c`.
fn expand_use_tree(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let path = tree.split(" as ").next().unwrap_or("").trim();
        return vec![path.to_string()];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(expand_use_tree)
        .map(|p| match p.as_str() {
            "self" => prefix.trim_end_matches("::").to_string(),
            _ => format!("{prefix}{p}"),
        })
        .collect()
}

/// Every circle of uses among the files of `src` (but `lib.rs` and `main.rs`), each as the
/// files it goes round.
fn import_circles(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let uses: BTreeMap<PathBuf, Vec<PathBuf>> = files
        .iter()
        .filter(|f| {
            let name = f.strip_prefix(src).unwrap();
            name != Path::new("lib.rs") && name != Path::new("main.rs")
        })
        .map(|f| (f.clone(), file_uses(src, f)))
        .collect();
    // A depth-first search from every file: a file met again on the current path closes a
    // circle.
    let show = |p: &Path| p.strip_prefix(src).unwrap().display().to_string();
    let mut circles = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    for start in uses.keys() {
        let mut path: Vec<(PathBuf, usize)> = vec![(start.clone(), 0)];
        while let Some((file, next)) = path.last().cloned() {
            let targets = &uses[&file];
            if next >= targets.len() || done.contains(&file) {
                done.insert(file);
                path.pop();
                continue;
            }
            path.last_mut().unwrap().1 += 1;
            let target = &targets[next];
            if let Some(at) = path.iter().position(|(f, _)| f == target) {
                let circle: Vec<String> = path[at..].iter().map(|(f, _)| show(f)).collect();
                circles.push(format!("{} -> {}", circle.join(" -> "), show(target)));
            } else if uses.contains_key(target) && !done.contains(target) {
                path.push((target.clone(), 0));
            }
        }
    }
    circles.sort();
    circles.dedup();
    circles
}

/// The circle finder reads grouped imports, over one line or several: a circle closed only
/// through `use crate::{a::A, b::B};` is found.
#[test]
fn grouped_imports_close_circles_too() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    let write = |name: &str, text: &str| std::fs::write(src.join(name), text).unwrap();
    write("lib.rs", "pub mod a;\npub mod b;\npub mod c;\npub mod d;\n");
    write(
        "a.rs",
        "use crate::{\n    c::C,\n    b::{self, B as Bee},\n};\npub struct A;\n",
    );
    write("b.rs", "use crate::{d::{D}, c::C};\npub struct B;\n");
    write("c.rs", "pub struct C;\n");
    write(
        "d.rs",
        "use crate::{a::A}; // closes a -> b -> d -> a\npub struct D;\n",
    );
    let used = file_uses(src, &src.join("a.rs"));
    assert_eq!(used, vec![src.join("b.rs"), src.join("c.rs")]);
    assert_eq!(
        import_circles(src),
        vec!["a.rs -> b.rs -> d.rs -> a.rs".to_string()]
    );
    assert_eq!(
        expand_use_tree("x::{y, z::{self, w as v}}"),
        ["x::y", "x::z", "x::z::w"]
    );
}

/// No two files of the crate use each other, however indirectly: each file can be read
/// knowing only the files it uses, and the layers' order holds inside a layer too.
#[test]
fn no_file_imports_round_a_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let edges: usize = files.iter().map(|f| file_uses(&src, f).len()).sum();
    assert!(edges > 300, "only {edges} uses between files found");
    let circles = import_circles(&src);
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

/// No source file outgrows one subject: past 800 lines a file is split by what its parts do
/// (the second redesign split eleven).
#[test]
fn no_source_file_is_over_800_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let lines = std::fs::read_to_string(f).unwrap().lines().count();
            (lines > 800).then(|| format!("{}: {lines} lines", f.display()))
        })
        .collect();
    assert!(files.len() > 100, "{} files found", files.len());
    assert!(long.is_empty(), "{long:#?}");
}

/// The functions of `text` (a Rust source file formatted by rustfmt) with their lengths in
/// lines, from the `fn` line to the closing brace at the same indent.
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let body = line.trim_start();
        let indent = line.len() - body.len();
        let after_qualifiers = body
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub(super) ")
            .trim_start_matches("pub ")
            .trim_start_matches("const ")
            .trim_start_matches("unsafe ");
        let Some(rest) = after_qualifiers.strip_prefix("fn ") else {
            continue;
        };
        // A declaration without a body (in a trait) ends with `;` before any `{`.
        let opens = lines[i..]
            .iter()
            .map(|l| l.trim_end())
            .find(|l| l.ends_with('{') || l.ends_with(';'));
        if opens.is_none_or(|l| l.ends_with(';')) {
            continue;
        }
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let close = " ".repeat(indent) + "}";
        let end = lines[i + 1..]
            .iter()
            .position(|l| l.trim_end() == close)
            .map_or(lines.len(), |k| i + 1 + k);
        out.push((name, end - i + 1));
    }
    out
}

/// No function grows past 120 lines: a longer one does several things, and each is split
/// into a named step (the second redesign split thirty).
#[test]
fn no_function_is_over_120_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut long = Vec::new();
    let mut functions = 0;
    for f in &files {
        for (name, lines) in function_lengths(&std::fs::read_to_string(f).unwrap()) {
            functions += 1;
            if lines > 120 {
                long.push(format!("{}: {name}, {lines} lines", f.display()));
            }
        }
    }
    assert!(functions > 1000, "{functions} functions found");
    assert!(long.is_empty(), "{long:#?}");
    // The measure sees a long function.
    let made = format!("fn f() {{\n{}}}\n", "    let x = 1;\n".repeat(130));
    assert_eq!(function_lengths(&made), [("f".to_string(), 132)]);
}

/// The circle finder sees the circles it is there for: two files that use each other.
#[test]
fn file_uses_resolve_crate_super_and_child_paths() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lod = src.join("bake/character/lod/mod.rs");
    let used = file_uses(&src, &lod);
    for f in [
        "bake/character/simplify/mod.rs",
        "bake/gpu_data/animation_space.rs",
    ] {
        assert!(used.contains(&src.join(f)), "{f} not among {used:?}");
    }
    // A module's own declarations of its children are not uses.
    let bake = file_uses(&src, &src.join("bake/mod.rs"));
    assert!(
        !bake.contains(&src.join("bake/character/mod.rs")),
        "{bake:?}"
    );
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
