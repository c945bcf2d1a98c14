//! Tables whose tag key chooses their keys (`[[obstacle]] shape`,
//! `[contact] method`), read with every key's position kept.
//!
//! serde's internally tagged enums (`#[serde(tag = "shape")]`) would do the
//! dispatch, but they buffer the table into serde's own content type first:
//! an error then carries the whole table's position, not its key's, and
//! `deny_unknown_fields` is not reliably honoured on them (serde issues
//! #2123 and #2294). So the table is taken from the parsed document (toml's
//! `DeValue`, which keeps the position of every key and value), its tag read
//! first, and the rest of the table given to the chosen struct, which has
//! `deny_unknown_fields`: a key of another choice is an unknown key there,
//! reported at its own line.

use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeValue, ValueDeserializer};

/// A serde error inside a table read apart: its message, the dotted key path
/// it concerns and where it is in the source.
#[derive(Debug)]
pub(super) struct Located {
    /// Dotted key path, e.g. `obstacle[0].radius`.
    pub key: String,
    /// The tag's value when it was read, e.g. `shape = "sphere"`: the keys
    /// accepted depend on it.
    pub choice: Option<String>,
    /// What is wrong (serde's message).
    pub message: String,
    /// Byte range in the scenario text.
    pub span: Option<Range<usize>>,
}

impl Located {
    /// A message about the table at `at` as a whole, spanning `span`.
    fn table(at: &str, message: String, span: Range<usize>) -> Self {
        Self {
            key: at.to_string(),
            choice: None,
            message,
            span: Some(span),
        }
    }

    /// `error` from inside the table at `at`; `choice` names the tag's value
    /// (`shape = "sphere"`) when it was read.
    fn new(at: &str, choice: Option<&str>, mut error: toml::de::Error) -> Self {
        let mut key = at.to_string();
        if let Some(inner) = super::error_key(&mut error) {
            key = format!("{key}.{inner}");
        }
        Self {
            key,
            choice: choice.map(str::to_string),
            message: error.message().trim().to_string(),
            span: error.span(),
        }
    }
}

/// Reads the table `value` at key path `at` (`contact`, `obstacle[2]`):
/// its `tag` key's value into `Tag`, then the other keys with `read`, which
/// deserializes the choice's own struct from them.
pub(super) fn read_tagged<'i, Tag, T>(
    value: Spanned<DeValue<'i>>,
    at: &str,
    tag: &str,
    read: impl FnOnce(Tag, ValueDeserializer<'i>) -> Result<T, toml::de::Error>,
) -> Result<T, Located>
where
    Tag: Deserialize<'i>,
{
    let span = value.span();
    let DeValue::Table(mut table) = value.into_inner() else {
        return Err(Located::table(
            at,
            "invalid type: expected a table".into(),
            span,
        ));
    };
    let Some((_, tag_value)) = table.remove_entry(tag) else {
        return Err(Located::table(at, format!("missing field `{tag}`"), span));
    };
    let choice = tag_value
        .get_ref()
        .as_str()
        .map(|name| format!("{tag} = {name:?}"));
    let chosen = Tag::deserialize(ValueDeserializer::from(tag_value))
        .map_err(|e| Located::new(&format!("{at}.{tag}"), None, e))?;
    let rest = ValueDeserializer::from(Spanned::new(span, DeValue::Table(table)));
    read(chosen, rest).map_err(|e| Located::new(at, choice.as_deref(), e))
}

/// Reads the array of tables `value` (`[[obstacle]]`, key `name`), each
/// with [`read_tagged`].
pub(super) fn read_tagged_array<'i, Tag, T>(
    value: Spanned<DeValue<'i>>,
    name: &str,
    tag: &str,
    read: impl Fn(Tag, ValueDeserializer<'i>) -> Result<T, toml::de::Error>,
) -> Result<Vec<T>, Located>
where
    Tag: Deserialize<'i>,
{
    let span = value.span();
    let DeValue::Array(items) = value.into_inner() else {
        return Err(Located::table(
            name,
            format!("invalid type: expected an array of tables ([[{name}]])"),
            span,
        ));
    };
    items
        .into_iter()
        .enumerate()
        .map(|(i, item)| read_tagged(item, &format!("{name}[{i}]"), tag, &read))
        .collect()
}

/// The `deserialize_with` of a field read apart by [`read_tagged`]: serde
/// never sees its key, which [`super::Scenario::parse`] takes out of the
/// document first; reaching this means the scenario was deserialized
/// without it.
pub(super) fn read_apart<'de, D, T>(_: D) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
{
    Err(serde::de::Error::custom(
        "this table is read by Scenario::parse, table by table",
    ))
}

#[cfg(test)]
mod tests {
    use crate::scenario::{
        BoxObstacleSpec, ContactSpec, ObstacleSpec, PenaltySpec, Scenario, ScenarioError,
    };
    use std::path::Path;

    const BASE: &str = "[mesh]\nshape = \"rectangle\"\n[material]\nyoungs_modulus = 1.0\n\
        poisson_ratio = 0.3\ndensity = 1.0\nthickness = 1.0\n";

    /// The line and message of the parse error of `BASE` + `tail`.
    fn refusal(tail: &str) -> (Option<usize>, String) {
        match Scenario::parse(&format!("{BASE}{tail}"), Path::new("t.toml")) {
            Err(ScenarioError::Parse { line, message, .. }) => (line, message),
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn each_shape_and_method_reads_its_own_keys() {
        let text = format!(
            "{BASE}[[obstacle]]\nmax = [1.0, 1.0, 1.0]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\n\
             [contact]\npenalty = 5.0\nmethod = \"penalty\"\n"
        );
        let s = Scenario::parse(&text, Path::new("t.toml")).unwrap();
        let expected = BoxObstacleSpec {
            min: [0.0; 3],
            max: [1.0; 3],
            edge_radius: None,
            velocity: None,
            friction: None,
        };
        assert_eq!(s.obstacles, vec![ObstacleSpec::Box(expected)]);
        assert_eq!(
            s.contact,
            Some(ContactSpec::Penalty(PenaltySpec {
                penalty: 5.0,
                friction: 0.0,
                stick_speed: crate::contact::DEFAULT_STICK_SPEED,
                self_contact: false,
                self_distance: None,
                features: false,
            }))
        );
    }

    /// Another shape's key is refused at its own line, before or after
    /// `shape` (toml hands the keys over sorted, so both orders are tried).
    #[test]
    fn another_shapes_key_is_refused_at_its_line() {
        for (tail, line) in [
            (
                "[[obstacle]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\nmin = [0, 0, 0]\n",
                12,
            ),
            (
                "[[obstacle]]\nmin = [0, 0, 0]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\n",
                9,
            ),
            (
                "[[obstacle]]\nshape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n[[obstacle]]\nshape = \"sphere\"\nzzz = 1\ncenter = [0, 0, 0]\nradius = 1.0\n",
                14,
            ),
        ] {
            let (at, message) = refusal(tail);
            assert_eq!(at, Some(line), "{message}");
            assert!(message.contains("(shape = \"sphere\")"), "{message}");
            assert!(message.contains("unknown field"), "{message}");
        }
        let (_, message) = refusal(
            "[[obstacle]]\nshape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             [[obstacle]]\nshape = \"sphere\"\nzzz = 1\ncenter = [0, 0, 0]\nradius = 1.0\n",
        );
        assert!(message.starts_with("`obstacle[1]`"), "{message}");
    }

    #[test]
    fn another_methods_key_and_wrong_types_are_refused_at_their_line() {
        let (line, message) = refusal("[contact]\nmethod = \"lagrange\"\npenalty = 1.0\n");
        assert_eq!(line, Some(10), "{message}");
        assert!(
            message.contains("`contact` (method = \"lagrange\")"),
            "{message}"
        );
        let (line, message) =
            refusal("[[obstacle]]\nshape = \"box\"\nmin = [0, 0, 0]\nmax = \"high\"\n");
        assert_eq!(line, Some(11), "{message}");
        assert!(message.starts_with("`obstacle[0].max`"), "{message}");
        let (line, message) = refusal("[[obstacle]]\nshape = \"torus\"\n");
        assert_eq!(line, Some(9), "{message}");
        assert!(message.contains("unknown variant `torus`"), "{message}");
        let text = format!("obstacle = 3\n{BASE}");
        let Err(ScenarioError::Parse { line, message, .. }) =
            Scenario::parse(&text, Path::new("t.toml"))
        else {
            panic!("obstacle = 3 accepted")
        };
        assert_eq!(line, Some(1), "{message}");
        assert!(message.contains("array of tables"), "{message}");
    }
}
