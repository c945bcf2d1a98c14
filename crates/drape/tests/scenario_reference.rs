//! The README's scenario reference and the parser agree both ways: every
//! key the parser accepts is documented in its table's section, and every
//! key documented there is accepted. The accepted keys (and the accepted
//! values of the choices) are read from the parser itself — the "expected
//! one of ..." of an unknown-key or unknown-value error — so the two cannot
//! drift.

use drape::scenario::{Scenario, ScenarioError};
use std::collections::BTreeSet;
use std::path::Path;

/// The least a scenario needs to get past the top level, so that a probe of
/// a table read apart (`[[obstacle]]`, `[contact]`) reaches that table.
const BASE: &str = "[mesh]\nshape = \"rectangle\"\n[material]\nyoungs_modulus = 1.0\n\
    poisson_ratio = 0.3\ndensity = 1.0\nthickness = 1.0\n";

/// The names listed in the parse error of `toml` after "expected": the
/// keys of a table with an unknown key, the values of a choice with an
/// unknown value. Empty when serde says "there are no fields".
fn expected(toml: &str) -> BTreeSet<String> {
    match Scenario::parse(toml, Path::new("probe.toml")) {
        Err(ScenarioError::Parse { message, .. }) => {
            if message.ends_with("there are no fields") {
                return BTreeSet::new();
            }
            // serde says "expected `a`" for one, "expected one of `a`, `b`" or
            // "expected `a` or `b`" for more.
            let list = message
                .split("expected")
                .nth(1)
                .unwrap_or_else(|| panic!("{message}"));
            list.split('`')
                .skip(1)
                .step_by(2)
                .map(String::from)
                .collect()
        }
        other => panic!("expected an unknown-field error, got {other:?}"),
    }
}

/// The README text between `### <heading>` and the next heading.
fn section<'a>(readme: &'a str, heading: &str) -> &'a str {
    let start = readme
        .find(&format!("### {heading}"))
        .unwrap_or_else(|| panic!("README lacks ### {heading}"));
    let rest = &readme[start + 4..];
    let end = rest
        .find("\n### ")
        .or_else(|| rest.find("\n## "))
        .unwrap_or(rest.len());
    &rest[..end]
}

/// The rows of the key tables of a section: the keys of the first cell
/// (`` `a`, `b` ``) and the row's text.
fn documented(text: &str) -> Vec<(Vec<String>, &str)> {
    text.lines()
        .filter(|l| l.starts_with("| `"))
        .map(|row| {
            let first = row.split('|').nth(1).unwrap_or("");
            let keys = first
                .split(',')
                .map(|k| k.trim().trim_matches('`').to_string())
                .collect();
            (keys, row)
        })
        .collect()
}

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap()
}

/// The tables whose keys are fixed, with a probe giving an unknown key.
const TABLES: [(&str, &str); 14] = [
    ("top level", "zzz = 1\n"),
    ("`[mesh]`", "[mesh]\nzzz = 1\n"),
    ("`[material]`", "[material]\nzzz = 1\n"),
    ("`[[load]]`", "[[load]]\nzzz = 1\n"),
    ("`[[fix]]`", "[[fix]]\nzzz = 1\n"),
    ("`[[cavity]]`", "[[cavity]]\nzzz = 1\n"),
    ("`[analysis]`", "[analysis]\nzzz = 1\n"),
    ("`[time]`", "[time]\nzzz = 1\n"),
    ("`[solver]`", "[solver]\nzzz = 1\n"),
    ("`[output]`", "[output]\nzzz = 1\n"),
    ("`[[monitor]]`", "[[monitor]]\nzzz = 1\n"),
    ("`[refine]`", "[refine]\nzzz = 1\n"),
    ("`[test]`", "[test]\nzzz = 1\n"),
    ("`[specimen]`", "[specimen]\nzzz = 1\n"),
];

/// Tables inside a table, documented as `key.inner` in their table's
/// section: the section, the prefix and the probe of their keys.
const NESTED: [(&str, &str, &str); 5] = [
    ("`[time]`", "rest.", "[time]\nrest = { zzz = 1 }\n"),
    ("`[material]`", "kes.", "[material]\nkes = { zzz = 1 }\n"),
    ("`[material]`", "fast.", "[material]\nfast = { zzz = 1 }\n"),
    (
        "`[[cavity]]`",
        "inflator.",
        "[[cavity]]\ninflator = { zzz = 1 }\n",
    ),
    (
        "`[[cavity]]`",
        "vent.",
        "[[cavity]]\n[[cavity.vent]]\nzzz = 1\n",
    ),
];

/// The choices of a table read apart: its heading, its tag, and a probe
/// prefix to which `tag = "<choice>"` and an unknown key are appended.
const CHOICES: [(&str, &str, &str); 2] = [
    ("`[[obstacle]]`", "shape", "[[obstacle]]\n"),
    ("`[contact]`", "method", "[contact]\n"),
];

/// The keys of each choice of a table read apart, by choice.
fn choice_keys(tag: &str, prefix: &str) -> Vec<(String, BTreeSet<String>)> {
    let choices = expected(&format!("{BASE}{prefix}{tag} = \"zzz\"\n"));
    assert!(!choices.is_empty(), "{prefix}");
    choices
        .into_iter()
        .map(|choice| {
            let keys = expected(&format!("{BASE}{prefix}{tag} = \"{choice}\"\nzzz = 1\n"));
            (choice, keys)
        })
        .collect()
}

#[test]
fn readme_documents_every_scenario_key() {
    let readme = readme();
    for (heading, probe) in TABLES {
        check_section(&readme, heading, &expected(probe), "");
    }
    // Keys of the tables inside a table, documented as `table.key`.
    for (heading, prefix, probe) in NESTED {
        check_section(&readme, heading, &expected(probe), prefix);
    }
    // Tables read apart: the tag and every choice's keys.
    for (heading, tag, prefix) in CHOICES {
        let mut keys = BTreeSet::from([tag.to_string()]);
        for (_, own) in choice_keys(tag, prefix) {
            keys.extend(own);
        }
        check_section(&readme, heading, &keys, "");
    }
}

/// Every key in `keys` appears as `` `{prefix}key` `` in the README section
/// `heading` (tables of the top level under their own headings).
fn check_section(readme: &str, heading: &str, keys: &BTreeSet<String>, prefix: &str) {
    assert!(!keys.is_empty(), "{heading}");
    let text = section(readme, heading);
    for key in keys {
        if heading == "top level" && key != "title" {
            // Tables, documented under their own headings.
            assert!(
                readme.contains(&format!("`[{key}]`")) || readme.contains(&format!("`[[{key}]]`")),
                "README lacks table {key}"
            );
            continue;
        }
        assert!(
            text.contains(&format!("`{prefix}{key}`")),
            "README section {heading} lacks `{prefix}{key}`"
        );
    }
}

#[test]
fn readme_documents_no_key_the_parser_refuses() {
    let readme = readme();
    for (heading, probe) in TABLES {
        let mut accepted = expected(probe);
        for (_, prefix, nested) in NESTED.iter().filter(|n| n.0 == heading) {
            accepted.extend(expected(nested).iter().map(|k| format!("{prefix}{k}")));
        }
        for (keys, row) in documented(section(&readme, heading)) {
            for key in keys {
                assert!(
                    accepted.contains(&key),
                    "README section {heading} documents `{key}`, which the parser refuses: {row}"
                );
            }
        }
    }
    // A key of a table read apart is accepted by some choice, and its row
    // names exactly the choices that accept it (unless all do).
    for (heading, tag, prefix) in CHOICES {
        let choices = choice_keys(tag, prefix);
        for (keys, row) in documented(section(&readme, heading)) {
            for key in keys.iter().filter(|k| *k != tag) {
                let takers: BTreeSet<&str> = (choices.iter())
                    .filter(|(_, own)| own.contains(key))
                    .map(|(c, _)| c.as_str())
                    .collect();
                assert!(
                    !takers.is_empty(),
                    "README section {heading} documents `{key}`, which no {tag} accepts: {row}"
                );
                if takers.len() == choices.len() {
                    continue;
                }
                let meaning = row.split('|').nth(2).unwrap_or("");
                let named: BTreeSet<&str> = (choices.iter())
                    .map(|(c, _)| c.as_str())
                    .filter(|c| {
                        meaning
                            .split(|ch: char| !ch.is_ascii_alphanumeric())
                            .any(|w| w == *c)
                    })
                    .collect();
                assert_eq!(
                    named, takers,
                    "README section {heading}: the row of `{key}` must name the {tag}s that take it: {row}"
                );
            }
        }
    }
}

#[test]
fn readme_documents_every_value_of_each_choice() {
    let readme = readme();
    let obstacle = format!("{BASE}[[obstacle]]\nshape = \"zzz\"\n");
    let contact = format!("{BASE}[contact]\nmethod = \"zzz\"\n");
    let choices = [
        ("`[material]`", "model", "[material]\nmodel = \"zzz\"\n"),
        (
            "`[material]`",
            "wrinkling",
            "[material]\nwrinkling = \"zzz\"\n",
        ),
        ("`[[obstacle]]`", "shape", obstacle.as_str()),
        ("`[[cavity]]`", "gas", "[[cavity]]\ngas = \"zzz\"\n"),
        ("`[mesh]`", "shape", "[mesh]\nshape = \"zzz\"\n"),
        ("`[contact]`", "method", contact.as_str()),
    ];
    for (heading, key, probe) in choices {
        let values = expected(probe);
        assert!(!values.is_empty(), "{heading} {key}");
        let text = section(&readme, heading);
        for value in values {
            assert!(
                text.contains(&format!("\"{value}\"")),
                "README section {heading} lacks the value \"{value}\" of `{key}`"
            );
        }
    }
}
