//! The README and the chapters under `docs/` hold: the README stays a front page, every
//! relative link and image resolves (the file, and the heading an anchor names), and every
//! command they show parses with the current command line.

use clap::{CommandFactory, Parser};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown file under docs/, with their text.
fn pages() -> Vec<(PathBuf, String)> {
    let mut files = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            (f, text)
        })
        .collect()
}

/// The text outside fenced blocks, and the fenced blocks with their info strings.
fn split_fences(text: &str) -> (String, Vec<(String, Vec<String>)>) {
    let mut prose = String::new();
    let mut blocks = Vec::new();
    let mut open: Option<(String, Vec<String>)> = None;
    for line in text.lines() {
        let trimmed = line.trim_start();
        if let Some(info) = trimmed.strip_prefix("```") {
            match open.take() {
                Some(block) => blocks.push(block),
                None => open = Some((info.trim().to_string(), Vec::new())),
            }
        } else if let Some((_, lines)) = &mut open {
            lines.push(trimmed.to_string());
        } else {
            prose.push_str(line);
            prose.push('\n');
        }
    }
    (prose, blocks)
}

/// `text` without its inline code spans.
fn without_code(text: &str) -> String {
    text.split('`').step_by(2).collect::<Vec<_>>().join(" ")
}

/// GitHub's anchor of a heading: lower case, only letters, digits, spaces, hyphens and
/// underscores kept, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a page's headings (a repeated heading's get -1, -2, … as on GitHub).
fn anchors(text: &str) -> HashSet<String> {
    let (prose, _) = split_fences(text);
    let mut seen = HashSet::new();
    for line in prose.lines() {
        let Some(heading) = line.strip_prefix('#') else {
            continue;
        };
        let base = slug(heading.trim_start_matches('#'));
        let mut anchor = base.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

/// The targets of a page's Markdown links and images, `](target)`, outside code.
fn link_targets(text: &str) -> Vec<String> {
    let (prose, _) = split_fences(text);
    let prose = without_code(&prose);
    let mut out = Vec::new();
    let mut rest = prose.as_str();
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        if let Some(end) = rest.find(')') {
            out.push(rest[..end].trim().to_string());
            rest = &rest[end..];
        }
    }
    out
}

#[test]
fn the_readme_is_a_front_page() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(
        lines <= 220,
        "README.md has {lines} lines; chapters go in docs/"
    );
    for part in [
        "## The two commands",
        "## Prerequisites",
        "## Commands",
        "docs/",
    ] {
        assert!(readme.contains(part), "README.md lacks {part}");
    }
}

#[test]
fn every_relative_link_and_image_resolves() {
    let pages = pages();
    let mut failures = Vec::new();
    let mut checked = 0;
    for (file, text) in &pages {
        let dir = file.parent().unwrap();
        for target in link_targets(text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let linked = if path.is_empty() {
                file.clone()
            } else {
                dir.join(path)
            };
            if !linked.exists() {
                failures.push(format!("{}: {target}: no such file", file.display()));
                continue;
            }
            // mdBook builds docs/ alone: a chapter's link out of it is dead in the book.
            let docs = root().join("docs").canonicalize().unwrap();
            let in_docs = file.starts_with(root().join("docs"));
            if in_docs && !linked.canonicalize().unwrap().starts_with(&docs) {
                failures.push(format!(
                    "{}: {target}: outside docs/, dead in the book",
                    file.display()
                ));
            }
            if let Some(anchor) = anchor {
                let text = std::fs::read_to_string(&linked).unwrap_or_default();
                if !anchors(&text).contains(anchor) {
                    failures.push(format!(
                        "{}: {target}: no heading of that anchor",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(checked >= 30, "only {checked} links found");
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_broken_link_and_anchor_are_found() {
    let text = "# Title\n\n## A `code` heading: yes\n\nSee [x](#a-code-heading-yes) and [y](#nope), `[z](in code)`.\n";
    assert!(anchors(text).contains("a-code-heading-yes"));
    assert!(!anchors(text).contains("nope"));
    assert_eq!(link_targets(text), ["#a-code-heading-yes", "#nope"]);
}

/// The command line of `line` as lodlab's words, where it runs lodlab: `lodlab …`, `cargo run
/// --release -- …` or `xvfb-run -a lodlab …`; None for any other program.
fn lodlab_words(line: &str) -> Option<Vec<String>> {
    let line = line.split(" #").next().unwrap_or(line).trim();
    let line = line.strip_prefix("xvfb-run -a ").unwrap_or(line);
    let args = if let Some(rest) = line.strip_prefix("cargo run --release -- ") {
        rest
    } else if line == "cargo run --release" || line == "lodlab" {
        ""
    } else {
        line.strip_prefix("lodlab ")?
    };
    let mut words = vec!["lodlab".to_string()];
    words.extend(args.split_whitespace().map(fill_variables));
    Some(words)
}

/// A shell word with its quotes gone and its variables (`$NAME`, `${NAME}`) read as 1, as a
/// batch scheduler's task number would be.
fn fill_variables(word: &str) -> String {
    let word = word.trim_matches('"');
    let mut out = String::new();
    let mut chars = word.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '$' {
            out.push(c);
            continue;
        }
        let braced = chars.next_if_eq(&'{').is_some();
        while chars
            .next_if(|c| c.is_ascii_alphanumeric() || *c == '_')
            .is_some()
        {}
        if braced {
            chars.next_if_eq(&'}');
        }
        out.push('1');
    }
    out
}

#[test]
fn shell_variables_are_filled() {
    assert_eq!(fill_variables("\"$SLURM_ARRAY_TASK_ID/16\""), "1/16");
    assert_eq!(fill_variables("${K}/${N}x"), "1/1x");
}

/// Every line of a fenced `sh` block that runs lodlab parses with the current command line,
/// and no `sh` block holds a template (`[…]`, `|`, `…`): those are `text`.
#[test]
fn the_shell_blocks_parse() {
    let mut failures = Vec::new();
    let mut parsed = 0;
    for (file, text) in pages() {
        let (_, blocks) = split_fences(&text);
        for (info, lines) in blocks.iter().filter(|(info, _)| info == "sh") {
            let _ = info;
            for line in lines {
                let code = line.split(" #").next().unwrap_or(line).trim();
                if code.is_empty() || code.starts_with('#') {
                    continue;
                }
                if code.contains(['[', '|', '…']) {
                    failures.push(format!(
                        "{}: a template in an sh block: {code}",
                        file.display()
                    ));
                    continue;
                }
                if let Some(words) = lodlab_words(code) {
                    parsed += 1;
                    if let Err(e) = lodlab::app::cli::Cli::try_parse_from(&words) {
                        failures.push(format!("{}: {code}: {}", file.display(), e.kind()));
                    }
                }
            }
        }
    }
    assert!(parsed >= 5, "only {parsed} lodlab lines in sh blocks");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The inline commands of a page (`lodlab …`, and the `bench …`/`shot …` shorthands of its
/// tables), with their placeholders (`DIR`, `M`, `MODEL`, `T`, `FILE`, `N`, `PX`, `K/N`) filled in;
/// templates with alternatives (`[…]`, `|`, `…`) are left out.
fn inline_commands(text: &str) -> Vec<Vec<String>> {
    let (prose, _) = split_fences(text);
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
                        "K/N" => "1/2",
                        w => w,
                    })
                    .map(String::from)
                    .collect(),
            )
        })
        .collect()
}

/// Every command the README and the chapters show inline parses as lodlab's command line does:
/// no renamed or removed option lingers in the prose.
#[test]
fn the_inline_commands_parse() {
    let mut commands = Vec::new();
    for (file, text) in pages() {
        for words in inline_commands(&text) {
            commands.push((file.clone(), words));
        }
    }
    assert!(commands.len() >= 40, "{} commands found", commands.len());
    let failures: Vec<String> = commands
        .iter()
        .filter_map(|(file, words)| {
            lodlab::app::cli::Cli::try_parse_from(words)
                .err()
                .map(|e| format!("{}: {}: {}", file.display(), words.join(" "), e.kind()))
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Every `--model` help names every built-in model (a list that once named five of eight).
#[test]
fn model_help_names_every_builtin() {
    let cli = lodlab::app::cli::Cli::command();
    let models: Vec<&str> = lodlab::assets::BUILTINS
        .iter()
        .filter(|b| b.kind != lodlab::assets::Kind::Clips)
        .map(|b| b.name)
        .collect();
    let shot = cli.find_subcommand("shot").unwrap();
    let help = shot
        .get_arguments()
        .find(|a| a.get_id() == "models")
        .and_then(|a| a.get_help())
        .unwrap()
        .to_string();
    let missing: Vec<&&str> = models.iter().filter(|m| !help.contains(**m)).collect();
    assert!(
        missing.is_empty(),
        "--model's help lacks {missing:?}: {help}"
    );
}

/// The cells of a Markdown table's line: `|` outside code spans and not escaped.
fn table_cells(line: &str) -> usize {
    let (mut in_code, mut escaped, mut bars) = (false, false, 0usize);
    for c in line.chars() {
        match c {
            '`' if !escaped => in_code = !in_code,
            '|' if !in_code && !escaped => bars += 1,
            _ => {}
        }
        escaped = c == '\\' && !escaped;
    }
    bars.saturating_sub(1)
}

/// Every table of the README and the chapters (quoted ones too) has as many cells in each row
/// as in its header: a table a script rewrites, or a row added by hand, cannot lose a column.
#[test]
fn every_table_row_has_its_headers_cells() {
    // Bars in code spans and escaped ones are not cells' edges.
    assert_eq!(table_cells(r"| a | `x|y` | b \| c |"), 3);
    assert_eq!(table_cells("|---|---:|"), 2);
    for (path, text) in pages() {
        let (prose, _) = split_fences(&text);
        let mut header: Option<usize> = None;
        for (n, line) in prose.lines().enumerate() {
            let line = line.trim_start_matches('>').trim();
            if !line.starts_with('|') {
                header = None;
                continue;
            }
            let cells = table_cells(line);
            match header {
                None => header = Some(cells),
                Some(h) => assert_eq!(
                    cells,
                    h,
                    "{}: line {} of its prose has {cells} cells, its table's header {h}: {line}",
                    path.display(),
                    n + 1
                ),
            }
        }
    }
}

/// Every block a script rewrites (`<!-- NAME -->` … `<!-- /NAME -->`) is closed, and a script
/// under tools/docs names its marker: no generated table is left without its generator.
#[test]
fn generated_blocks_are_closed_and_have_their_script() {
    let scripts: String = std::fs::read_dir(root().join("tools/docs"))
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap())
        .collect();
    let mut found = 0;
    for (path, text) in pages() {
        for line in text.lines() {
            let Some(name) = line
                .strip_prefix("<!-- ")
                .and_then(|l| l.strip_suffix(" -->"))
                .filter(|n| !n.starts_with('/'))
            else {
                continue;
            };
            found += 1;
            assert!(
                text.lines().any(|l| l == format!("<!-- /{name} -->")),
                "{}: <!-- {name} --> is never closed",
                path.display()
            );
            // The scripts build the name from its parts (`speed-table $kind`): its first word.
            let stem = name.split(' ').next().unwrap();
            assert!(
                scripts.contains(stem),
                "{}: no script under tools/docs writes <!-- {name} -->",
                path.display()
            );
        }
    }
    assert!(found >= 6, "{found} generated blocks");
}
