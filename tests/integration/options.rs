//! The command line's shape: every subcommand's options walked, and an option that several
//! commands take has the same name, the same kind of value and the same meaning in each.

use clap::{CommandFactory, Parser};
use std::collections::BTreeMap;

/// One option of one command, as clap describes it.
#[derive(Debug)]
struct Seen {
    command: String,
    /// Whether it takes a value (a flag does not).
    takes_value: bool,
    value_name: String,
    /// The value's choices, where it is one of a list.
    choices: Vec<String>,
    help: String,
}

fn walk(c: &clap::Command, path: &str, out: &mut BTreeMap<String, Vec<Seen>>) {
    for a in c.get_arguments() {
        let Some(long) = a.get_long() else { continue };
        if long == "help" || long == "version" {
            continue;
        }
        let takes_value = a.get_action().takes_values();
        let choices = if takes_value {
            a.get_possible_values()
                .iter()
                .map(|p| p.get_name().to_string())
                .collect()
        } else {
            Vec::new()
        };
        out.entry(long.to_string()).or_default().push(Seen {
            command: path.to_string(),
            takes_value,
            value_name: a
                .get_value_names()
                .map(|v| {
                    v.iter()
                        .map(|s| s.to_string())
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default(),
            choices,
            help: a.get_help().map(|h| h.to_string()).unwrap_or_default(),
        });
    }
    for s in c.get_subcommands() {
        let name = format!("{path} {}", s.get_name()).trim().to_string();
        walk(s, &name, out);
    }
}

/// What an option means wherever it is, where its help is worded for each command: words
/// every command's help of it holds.
const MEANINGS: &[(&str, &str)] = &[
    ("cache", "cache folder of baked levels of detail"),
    ("size", "size"),
    ("msaa", "multisampling"),
    ("frames", "frames to render"),
    ("json", "as json"),
    ("out", "write"),
    ("model", "model"),
    ("method", "level-of-detail method"),
    ("path", "camera path"),
    ("plan", "study plan"),
    ("shard", "k of n"),
    ("no-normal-maps", "vertex normals only"),
    ("debug-view", "debug view"),
    ("tolerance", "largest projected error allowed, in pixels"),
];

/// Value names an option may take by command where one name cannot fit all: a file or a
/// folder as each command writes, one method or a list of them.
const VALUE_NAMES: &[(&str, &[&str])] = &[
    ("out", &["DIR", "FILE.png", "FILE.mp4"]),
    ("method", &["METHOD", "METHOD,..."]),
];

#[test]
fn every_option_shared_by_commands_has_one_name_syntax_and_meaning() {
    let mut options = BTreeMap::new();
    walk(&lodlab::app::cli::Cli::command(), "", &mut options);
    assert!(options.len() > 60, "{} options", options.len());
    let mut problems = Vec::new();
    for (long, seen) in &options {
        let commands: Vec<&str> = seen.iter().map(|s| s.command.as_str()).collect();
        if seen.len() < 2 {
            continue;
        }
        let first = &seen[0];
        for s in &seen[1..] {
            if s.takes_value != first.takes_value {
                problems.push(format!(
                    "--{long}: a flag in some of {commands:?}, not in others"
                ));
            }
        }
        // One value name, or one of those its kind allows.
        match VALUE_NAMES.iter().find(|(o, _)| o == long) {
            Some((_, allowed)) => {
                for s in seen {
                    if !allowed.contains(&s.value_name.as_str()) {
                        problems.push(format!(
                            "--{long} in `{}` takes {}, not one of {allowed:?}",
                            s.command, s.value_name
                        ));
                    }
                }
            }
            None => {
                for s in seen {
                    if s.value_name != first.value_name {
                        problems.push(format!(
                            "--{long}: {} in `{}`, {} in `{}`",
                            first.value_name, first.command, s.value_name, s.command
                        ));
                    }
                }
            }
        }
        // Choices spelt alike: every command's list within the longest.
        let widest = seen
            .iter()
            .map(|s| &s.choices)
            .max_by_key(|c| c.len())
            .unwrap();
        for s in seen {
            if let Some(odd) = s.choices.iter().find(|c| !widest.contains(c)) {
                problems.push(format!(
                    "--{long} in `{}` takes {odd}, which others spell otherwise ({widest:?})",
                    s.command
                ));
            }
        }
        // The same meaning: the same help, or the words its meaning is stated by.
        let same_help = seen.iter().all(|s| s.help == first.help);
        match MEANINGS.iter().find(|(o, _)| o == long) {
            Some((_, words)) => {
                for s in seen {
                    if !s.help.to_lowercase().contains(words) {
                        problems.push(format!(
                            "--{long} in `{}` does not say it means \"{words}\": {}",
                            s.command, s.help
                        ));
                    }
                }
            }
            None if !same_help => problems.push(format!(
                "--{long} is helped differently in {commands:?}: give it one help, or state its \
                 meaning in MEANINGS"
            )),
            None => {}
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// A command that compares several methods and one that shows one take them by one name:
/// `--method`, a list where a list makes sense, with `--methods` as its other spelling.
#[test]
fn methods_are_named_alike_by_every_command() {
    let mut options = BTreeMap::new();
    walk(&lodlab::app::cli::Cli::command(), "", &mut options);
    assert!(
        !options.contains_key("methods"),
        "--methods is only an alias"
    );
    let method: Vec<&str> = options["method"]
        .iter()
        .map(|s| s.command.as_str())
        .collect();
    for c in ["", "view", "shot", "record", "export", "bake", "bench"] {
        assert!(method.contains(&c), "`{c}` lacks --method: {method:?}");
    }
    for args in [
        ["bench", "--methods", "as", "--no-coverage"],
        ["bench", "--method", "as", "--no-coverage"],
    ] {
        lodlab::app::cli::Cli::try_parse_from(std::iter::once("lodlab").chain(args))
            .unwrap_or_else(|e| panic!("{args:?}: {e}"));
    }
}
