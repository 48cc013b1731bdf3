//! The command line's changes to a scenario: `--set key=value` overrides, and where a
//! key is written (for messages that name its line).

/// The 1-based line of a dotted key's value in a TOML text, if present.
pub fn line_of(text: &str, key: &str) -> Option<usize> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut table = root.get_ref();
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let (_, v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == *part)?;
        if i + 1 == parts.len() {
            let offset = v.span().start;
            return Some(text[..offset.min(text.len())].matches('\n').count() + 1);
        }
        table = v.get_ref().as_table()?;
    }
    None
}

/// Parses a `--set key=value` override: the value as TOML (`0.5`, `"rqmc"`, `[1, 2]`),
/// or as a bare string when it is not valid TOML (`--set scheme.name=lowrank`).
pub fn parse_override(s: &str) -> Result<(String, toml::Value), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("--set {s}: write KEY=VALUE, e.g. --set kernel.coefficient=2"))?;
    let k = k.trim();
    if k.is_empty() || k.split('.').any(|p| p.is_empty()) {
        return Err(format!("--set {s}: {k:?} is not a dotted key"));
    }
    let v = v.trim();
    let value = match toml::from_str::<toml::Table>(&format!("v = {v}")) {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(v.into())),
        Err(_) => toml::Value::String(v.into()),
    };
    Ok((k.to_string(), value))
}

/// Removes a dotted key from a table, if present.
pub(crate) fn remove_key(table: &mut toml::Table, key: &str) {
    let mut t = table;
    let parts: Vec<&str> = key.split('.').collect();
    for part in &parts[..parts.len() - 1] {
        match t.get_mut(*part).and_then(|v| v.as_table_mut()) {
            Some(next) => t = next,
            None => return,
        }
    }
    t.remove(parts[parts.len() - 1]);
}

/// Sets a dotted key in a table, creating sub-tables.
pub(crate) fn set_key(
    table: &mut toml::Table,
    key: &str,
    value: toml::Value,
) -> Result<(), String> {
    let mut t = table;
    let parts: Vec<&str> = key.split('.').collect();
    for part in &parts[..parts.len() - 1] {
        let entry = t
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = entry
            .as_table_mut()
            .ok_or_else(|| format!("--set {key}: {part} is not a table"))?;
    }
    t.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}
