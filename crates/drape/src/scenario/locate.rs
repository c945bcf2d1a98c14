//! Finds the line of a key in scenario text, for error messages.

/// 1-based line of `key` inside table `table` (`""` for the top level),
/// the `index`-th occurrence of `[[table]]` for arrays of tables. Returns the
/// table header's line when the key is absent (a missing key), `None` when
/// the table is absent too.
pub fn line_of(source: &str, table: &str, index: Option<usize>, key: &str) -> Option<usize> {
    let mut current = String::new();
    let mut occurrence: std::collections::HashMap<String, usize> = Default::default();
    let mut header_line = None;
    let wanted = |name: &str, occ: usize| name == table && index.is_none_or(|i| i + 1 == occ);
    for (n, raw) in source.lines().enumerate() {
        let line = raw.trim();
        if let Some(rest) = line.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let occ = occurrence.entry(name.clone()).or_insert(0);
            *occ += 1;
            current = format!("{name}#{occ}");
            if wanted(&name, *occ) {
                header_line = Some(n + 1);
            }
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.split(']').next().unwrap_or("").trim().to_string();
            current = format!("{name}#1");
            if wanted(&name, 1) {
                header_line = Some(n + 1);
            }
            continue;
        }
        let (name, occ) = current.rsplit_once('#').unwrap_or(("", "1"));
        let occ: usize = occ.parse().unwrap_or(1);
        if !wanted(name, occ) {
            continue;
        }
        if let Some(rest) = line.strip_prefix(key) {
            let rest = rest.trim_start();
            if rest.starts_with('=') || rest.starts_with('.') {
                return Some(n + 1);
            }
        }
    }
    header_line
}

#[cfg(test)]
mod tests {
    use super::line_of;

    #[test]
    fn finds_keys_in_tables_and_arrays_of_tables() {
        let src = "title = \"x\"\n[material]\nthickness = 1\n[[load]]\nkind = \"gravity\"\n[[load]]\nramp = 2\n";
        assert_eq!(line_of(src, "", None, "title"), Some(1));
        assert_eq!(line_of(src, "material", None, "thickness"), Some(3));
        assert_eq!(line_of(src, "load", Some(1), "ramp"), Some(7));
        assert_eq!(line_of(src, "load", Some(0), "ramp"), Some(4));
        assert_eq!(line_of(src, "mesh", None, "size"), None);
    }
}
