//! Line numbers for scene errors: where a key sits in the TOML text.

use std::path::{Path, PathBuf};
use toml::de::{DeArray, DeTable, DeValue};

/// One step of a key path: a table key or an array index.
#[derive(Clone, Copy, Debug)]
pub enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// The scene text, for turning key paths into line numbers in errors.
pub struct Source<'t> {
    pub text: &'t str,
    pub path: PathBuf,
}

impl<'t> Source<'t> {
    pub fn new(text: &'t str, path: &Path) -> Self {
        Source {
            text,
            path: path.to_path_buf(),
        }
    }

    /// 1-based line of the byte offset `at`.
    pub fn line_of(&self, at: usize) -> usize {
        self.text[..at.min(self.text.len())].matches('\n').count() + 1
    }

    /// Line of the deepest part of `steps` present in the file (the value if
    /// found, else its nearest enclosing key); 1 if nothing matches.
    pub fn line_of_path(&self, steps: &[Step]) -> usize {
        let Ok(root) = DeTable::parse(self.text) else {
            return 1;
        };
        let mut best = 1;
        let mut table: Option<&DeTable> = Some(root.get_ref());
        let mut value: Option<&DeValue> = None;
        for step in steps {
            let next = match (step, table, value) {
                (Step::Key(k), Some(t), _) => t
                    .iter()
                    .find(|(key, _)| key.get_ref().as_ref() == *k)
                    .map(|(key, v)| {
                        best = self.line_of(key.span().start);
                        v
                    }),
                (Step::Index(i), _, Some(DeValue::Array(a))) => a.get(*i).inspect(|v| {
                    best = self.line_of(v.span().start);
                }),
                _ => None,
            };
            let Some(v) = next else { break };
            value = Some(v.get_ref());
            table = match v.get_ref() {
                DeValue::Table(t) => Some(t),
                _ => None,
            };
        }
        best
    }

    /// The `water.layer[1].chl` style name of the deepest key whose value
    /// spans byte `at`; `None` if the text does not parse as TOML or no key
    /// spans it.
    pub fn key_at(&self, at: usize) -> Option<String> {
        let root = DeTable::parse(self.text).ok()?;
        let mut name = String::new();
        let mut table: Option<&DeTable> = Some(root.get_ref());
        let mut array: Option<&DeArray> = None;
        loop {
            // A table opened by a `[header]` spans only its header, so where
            // no value spans `at`, the container whose key last precedes it
            // holds it.
            let next = if let Some(t) = table.take() {
                t.iter()
                    .find(|(_, v)| v.span().contains(&at))
                    .or_else(|| {
                        t.iter()
                            .filter(|(k, v)| {
                                k.span().start <= at
                                    && matches!(v.get_ref(), DeValue::Table(_) | DeValue::Array(_))
                            })
                            .max_by_key(|(k, _)| k.span().start)
                    })
                    .map(|(k, v)| {
                        if !name.is_empty() {
                            name.push('.');
                        }
                        name.push_str(k.get_ref());
                        v
                    })
            } else if let Some(a) = array.take() {
                a.iter()
                    .enumerate()
                    .find(|(_, v)| v.span().contains(&at))
                    .or_else(|| {
                        a.iter()
                            .enumerate()
                            .filter(|(_, v)| v.span().start <= at)
                            .max_by_key(|(_, v)| v.span().start)
                    })
                    .map(|(i, v)| {
                        name.push_str(&format!("[{i}]"));
                        v
                    })
            } else {
                None
            };
            let Some(v) = next else { break };
            match v.get_ref() {
                DeValue::Table(t) => table = Some(t),
                DeValue::Array(a) => array = Some(a),
                _ => break,
            }
        }
        (!name.is_empty()).then_some(name)
    }

    /// An error about the value at `steps`.
    pub fn error(&self, steps: &[Step], what: impl Into<String>) -> crate::Error {
        crate::Error::Scene {
            path: self.path.clone(),
            line: self.line_of_path(steps),
            key: key_name(steps),
            what: what.into(),
        }
    }
}

/// `water.layer[1].chl` style name of a key path.
pub fn key_name(steps: &[Step]) -> String {
    let mut s = String::new();
    for step in steps {
        match step {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

#[cfg(test)]
mod tests;
