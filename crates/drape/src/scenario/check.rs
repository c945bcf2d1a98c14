//! Range checks of a parsed scenario's values, whose errors name the file,
//! the key path and its line.

use super::ScenarioError;
use super::locate::line_of;
use std::path::Path;

/// Range checks of the scenario's values, with messages naming the file,
/// the key path and its line.
pub(super) struct Checker<'a> {
    /// The scenario file.
    pub file: &'a Path,
    /// Its text.
    pub source: &'a str,
}

impl Checker<'_> {
    pub(super) fn invalid(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        message: String,
    ) -> ScenarioError {
        let path = match index {
            Some(i) => format!("{table}[{i}].{key}"),
            None if table.is_empty() => key.to_string(),
            None => format!("{table}.{key}"),
        };
        ScenarioError::Invalid {
            file: self.file.to_path_buf(),
            line: line_of(self.source, table, index, key),
            key: path,
            message,
        }
    }

    pub(super) fn positive(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: f64,
    ) -> Result<f64, ScenarioError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(self.invalid(
                table,
                index,
                key,
                format!("must be a positive finite number, not {v}"),
            ))
        }
    }

    pub(super) fn finite(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &[f64],
    ) -> Result<(), ScenarioError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(self.invalid(table, index, key, format!("must be finite, not {v:?}")))
        }
    }

    pub(super) fn required<T: Clone>(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &Option<T>,
        why: &str,
    ) -> Result<T, ScenarioError> {
        v.clone()
            .ok_or_else(|| self.invalid(table, index, key, format!("is required {why}")))
    }

    /// Rejects every key of `given` that is present: they do not apply (`why`).
    pub(super) fn none_of(
        &self,
        table: &str,
        index: Option<usize>,
        given: &[(&str, bool)],
        why: &str,
    ) -> Result<(), ScenarioError> {
        match given.iter().find(|(_, present)| *present) {
            Some((key, _)) => Err(self.invalid(table, index, key, format!("does not apply {why}"))),
            None => Ok(()),
        }
    }

    /// As [`Self::invalid`] for `sub` inside the table `key` of `table`
    /// (`rest = { speed = ... }`, `rest.speed = ...` or `[time.rest]`):
    /// the key path `table.key.sub`, the line of `sub` in a `[table.key]`
    /// table, else the line of `key`.
    pub(super) fn invalid_in(
        &self,
        table: &str,
        key: &str,
        sub: &str,
        message: String,
    ) -> ScenarioError {
        let nested = format!("{table}.{key}");
        ScenarioError::Invalid {
            file: self.file.to_path_buf(),
            line: line_of(self.source, &nested, None, sub)
                .or_else(|| line_of(self.source, table, None, key)),
            key: format!("{nested}.{sub}"),
            message,
        }
    }

    pub(super) fn absent<T>(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &Option<T>,
        why: &str,
    ) -> Result<(), ScenarioError> {
        match v {
            Some(_) => Err(self.invalid(table, index, key, format!("does not apply {why}"))),
            None => Ok(()),
        }
    }
}
