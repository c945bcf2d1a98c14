//! Issue 35: `render`'s and `plot`'s choices are typed (clap's
//! `ValueEnum` for `--view` and `--field`, a parsed `--size`): every
//! spelling accepted before is accepted, anything else is refused by the
//! argument parser naming the option and the value, before any file is
//! read.

mod issue_19_support;

use issue_19_support::{drape, text};
use std::ffi::OsStr;

/// A directory that does not exist: an argument that parses gets as far
/// as reading it, and is refused for it, not for the argument.
const NO_RUN: &str = "/nonexistent/drape-issue-35";

fn stderr_of(args: &[&str]) -> (Option<i32>, String) {
    let args: Vec<&OsStr> = args.iter().map(OsStr::new).collect();
    let o = drape(&args);
    (o.status.code(), text(&o.stderr))
}

#[test]
fn every_view_and_field_spelling_is_accepted() {
    let views = ["top", "side", "perspective"];
    let fields = [
        "displacement_z",
        "displacement",
        "velocity",
        "contact_force",
        "principal_stress_max",
        "principal_stress_min",
        "wrinkle_state",
    ];
    for view in views {
        for field in fields {
            let (code, e) = stderr_of(&["render", NO_RUN, "--view", view, "--field", field]);
            assert_eq!(code, Some(2), "{view} {field}: {e}");
            assert!(!e.contains("invalid value"), "{view} {field}: {e}");
            assert!(
                e.contains(NO_RUN),
                "{view} {field}: refused for the directory: {e}"
            );
        }
    }
    for size in ["400x300", "400X300", " 400 x 300 "] {
        for verb in ["render", "plot"] {
            let (code, e) = stderr_of(&[verb, NO_RUN, "--size", size]);
            assert_eq!(code, Some(2), "{verb} --size {size:?}: {e}");
            assert!(!e.contains("invalid value"), "{verb} --size {size:?}: {e}");
        }
    }
}

#[test]
fn an_unknown_choice_is_refused_naming_the_option_the_value_and_the_choices() {
    let cases: [(&[&str], &[&str]); 5] = [
        (
            &["render", NO_RUN, "--view", "above"],
            &["'above'", "--view", "top, side, perspective"],
        ),
        (
            &["render", NO_RUN, "--field", "stress"],
            &["'stress'", "--field", "displacement_z", "wrinkle_state"],
        ),
        (
            &["render", NO_RUN, "--view", "Top"],
            &["'Top'", "--view", "top, side, perspective"],
        ),
        (
            &["render", NO_RUN, "--size", "1200"],
            &["'1200'", "--size", "expected WxH in pixels"],
        ),
        (
            &["plot", NO_RUN, "--size", "axb"],
            &["'axb'", "--size", "expected WxH in pixels"],
        ),
    ];
    for (args, fragments) in cases {
        let (code, e) = stderr_of(args);
        assert_eq!(code, Some(2), "{args:?}: {e}");
        for f in fragments {
            assert!(e.contains(f), "{args:?}: expected {f:?} in {e}");
        }
        assert!(
            !e.contains(NO_RUN),
            "{args:?}: refused before the directory: {e}"
        );
    }
}
