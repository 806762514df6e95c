//! Scene files made in code: a base text with keys set or removed, tables
//! merged in and entries added to arrays of tables ([`SceneText`]), for
//! tests, benchmark scripts (`littoral scene set`) and parameter sweeps.
//! The result is TOML text that [`super::Scene::load`] validates like any
//! file; nothing here knows the scene's keys, so a misspelt key is caught
//! there, naming it.
//!
//! Keys are dotted paths (`water.iop.a`, `sensor.pixels`); tables on the
//! way are made as needed. Comments and the base's key order are not kept:
//! the text is written with each table's keys sorted.

use crate::error::{Error, Result};
use toml::{Table, Value};

/// A scene file's TOML being changed in code.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneText {
    table: Table,
}

/// What the errors of this module are about.
const WHAT: &str = "scene text";

impl SceneText {
    /// `text` as a scene to change; an error if it is not TOML.
    pub fn parse(text: &str) -> Result<SceneText> {
        let table = text
            .parse::<Table>()
            .map_err(|e| Error::invalid(WHAT, one_line(&e)))?;
        Ok(SceneText { table })
    }

    /// The built-in coastal scene (`littoral scene default`).
    pub fn builtin() -> SceneText {
        Self::parse(super::COASTAL_TOML).expect("the built-in scene is TOML")
    }

    /// Set `key` (dotted) to `value`, making the tables on its way.
    pub fn set(mut self, key: &str, value: impl Into<Value>) -> SceneText {
        let (parent, last) = self.parent_of(key);
        parent.insert(last.to_string(), value.into());
        self
    }

    /// Set `key` to a value written in TOML (`[48, 48]`, `"deep"`,
    /// `{ a = 0.1, b = 0.4 }`), as `littoral scene set KEY=VALUE` gives it.
    pub fn set_toml(self, key: &str, value: &str) -> Result<SceneText> {
        let holder = format!("value = {value}").parse::<Table>().map_err(|e| {
            Error::invalid(
                WHAT,
                format!("{key}: '{value}' is not a TOML value: {}", one_line(&e)),
            )
        })?;
        let value = holder
            .get("value")
            .cloned()
            .ok_or_else(|| Error::invalid(WHAT, format!("{key}: '{value}' is not a TOML value")))?;
        Ok(self.set(key, value))
    }

    /// Remove `key` (dotted), if present.
    pub fn remove(mut self, key: &str) -> SceneText {
        let mut parts: Vec<&str> = key.split('.').collect();
        let Some(last) = parts.pop() else {
            return self;
        };
        let mut table = &mut self.table;
        for p in parts {
            match table.get_mut(p) {
                Some(Value::Table(t)) => table = t,
                _ => return self,
            }
        }
        table.remove(last);
        self
    }

    /// Merge the TOML `fragment` in: its tables into tables of the same
    /// name, key by key; any other value (arrays of tables included)
    /// replaces the one it names.
    pub fn merge(mut self, fragment: &str) -> Result<SceneText> {
        let other = Self::parse(fragment)?;
        merge_into(&mut self.table, other.table);
        Ok(self)
    }

    /// Add the TOML table `entry` to the array of tables `array` (e.g. a
    /// `[[radiometer]]` or a `[[target]]`), making the array if needed.
    pub fn push(mut self, array: &str, entry: &str) -> Result<SceneText> {
        let entry = Self::parse(entry)?.table;
        let (parent, last) = self.parent_of(array);
        match parent
            .entry(last.to_string())
            .or_insert_with(|| Value::Array(Vec::new()))
        {
            Value::Array(items) => items.push(Value::Table(entry)),
            _ => {
                return Err(Error::invalid(
                    WHAT,
                    format!("{array} is not an array of tables"),
                ))
            }
        }
        Ok(self)
    }

    /// The value at `key` (dotted), if any.
    pub fn get(&self, key: &str) -> Option<&Value> {
        let mut parts = key.split('.');
        let mut value = self.table.get(parts.next()?)?;
        for p in parts {
            value = value.as_table()?.get(p)?;
        }
        Some(value)
    }

    /// The scene as TOML text.
    pub fn text(&self) -> String {
        toml::to_string(&self.table).expect("a TOML table is written as TOML")
    }

    /// The table holding `key`'s last part, made (and any non-table on the
    /// way replaced by a table) as needed; with that last part.
    fn parent_of<'k>(&mut self, key: &'k str) -> (&mut Table, &'k str) {
        let (path, last) = match key.rsplit_once('.') {
            Some((path, last)) => (Some(path), last),
            None => (None, key),
        };
        let mut table = &mut self.table;
        for p in path.into_iter().flat_map(|p| p.split('.')) {
            let slot = table
                .entry(p.to_string())
                .or_insert_with(|| Value::Table(Table::new()));
            if !slot.is_table() {
                *slot = Value::Table(Table::new());
            }
            table = slot.as_table_mut().expect("made a table above");
        }
        (table, last)
    }
}

/// `littoral scene set BASE KEY=VALUE... [--merge FILE]...`: the scene at
/// `base` (`default`: the built-in scene) with each fragment file of
/// `merges` merged in, then each `KEY=VALUE` (a TOML value) set.
pub fn from_command_line(
    base: &std::path::Path,
    changes: &[String],
    merges: &[std::path::PathBuf],
) -> Result<SceneText> {
    let read = |path: &std::path::Path| {
        std::fs::read_to_string(path).map_err(|e| Error::io(path, "read", e))
    };
    let in_file = |path: &std::path::Path, e: Error| {
        Error::invalid(format!("{}", path.display()), e.to_string())
    };
    let mut scene = if base.as_os_str() == "default" {
        SceneText::builtin()
    } else {
        SceneText::parse(&read(base)?).map_err(|e| in_file(base, e))?
    };
    for m in merges {
        scene = scene.merge(&read(m)?).map_err(|e| in_file(m, e))?;
    }
    for change in changes {
        let Some((key, value)) = change.split_once('=') else {
            return Err(Error::invalid(
                WHAT,
                format!("'{change}' is not KEY=VALUE (e.g. sensor.pixels=[48,48])"),
            ));
        };
        scene = scene.set_toml(key.trim(), value.trim())?;
    }
    Ok(scene)
}

impl std::fmt::Display for SceneText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text())
    }
}

/// A TOML parse error on one line: its message without the source
/// excerpt (lines drawn with `|`).
fn one_line(e: &toml::de::Error) -> String {
    e.to_string()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.contains('|'))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Merge `from` into `into`: tables key by key, other values replaced.
fn merge_into(into: &mut Table, from: Table) {
    for (key, value) in from {
        match (into.get_mut(&key), value) {
            (Some(Value::Table(mine)), Value::Table(theirs)) => merge_into(mine, theirs),
            (_, value) => {
                into.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests;
