//! The README's scenario reference lists every key the parser accepts, in
//! the right table: the accepted keys are read from the parser itself (the
//! "expected one of ..." of an unknown-key error), so the two cannot drift.

use drape::scenario::{Scenario, ScenarioError};
use std::path::Path;

fn accepted_keys(toml: &str) -> Vec<String> {
    match Scenario::parse(toml, Path::new("probe.toml")) {
        Err(ScenarioError::Parse { message, .. }) => {
            // serde says "expected `a`" for one field, "expected one of `a`, `b`" for more.
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

#[test]
fn readme_documents_every_scenario_key() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .unwrap();
    let cases = [
        ("top level", "zzz = 1\n"),
        ("`[mesh]`", "[mesh]\nzzz = 1\n"),
        ("`[material]`", "[material]\nzzz = 1\n"),
        ("`[[load]]`", "[[load]]\nzzz = 1\n"),
        ("`[[fix]]`", "[[fix]]\nzzz = 1\n"),
        ("`[[obstacle]]`", "[[obstacle]]\nzzz = 1\n"),
        ("`[contact]`", "[contact]\nzzz = 1\n"),
        ("`[analysis]`", "[analysis]\nzzz = 1\n"),
        ("`[time]`", "[time]\nzzz = 1\n"),
        ("`[solver]`", "[solver]\nzzz = 1\n"),
        ("`[output]`", "[output]\nzzz = 1\n"),
        ("`[[monitor]]`", "[[monitor]]\nzzz = 1\n"),
    ];
    for (heading, probe) in cases {
        check_section(&readme, heading, probe, "");
    }
    // Keys of the tables inside a table, documented as `table.key`.
    check_section(&readme, "`[time]`", "[time]\nrest = { zzz = 1 }\n", "rest.");
}

/// Every key the parser accepts for `probe` appears as `` `{prefix}key` ``
/// in the README section `heading` (tables of the top level under their
/// own headings).
fn check_section(readme: &str, heading: &str, probe: &str, prefix: &str) {
    let keys = accepted_keys(probe);
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
