//! The ENVI header: its text read (within a size limit), split into
//! `key = value` fields (values in braces may span lines), and each field
//! the reader needs checked and converted, errors naming the header, the
//! line and the key.

use super::reader::DataType;
use super::Interleave;
use crate::error::{Error, Result};
use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Headers larger than this are not ENVI headers (a data file named by
/// mistake, say).
pub(super) const MAX_HEADER_BYTES: u64 = 16 << 20;

/// The header's text: refused past [`MAX_HEADER_BYTES`] or when not UTF-8.
pub(super) fn read_header_text(path: &Path) -> Result<String> {
    let file = File::open(path).map_err(|e| Error::io(path, "open", e))?;
    let mut bytes = Vec::new();
    file.take(MAX_HEADER_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, "read", e))?;
    if bytes.len() as u64 > MAX_HEADER_BYTES {
        return Err(Error::data(
            path,
            None,
            "header",
            format!("is larger than {MAX_HEADER_BYTES} bytes: not an ENVI header"),
        ));
    }
    String::from_utf8(bytes)
        .map_err(|_| Error::data(path, None, "header", "is not text: not an ENVI header"))
}

/// A `key = value` of the header: lower-cased key, value without braces,
/// and the 1-based line the key is on.
type Field = (String, String, usize);

/// Split a header into fields. Values in braces may span lines; `;` starts
/// a comment line.
pub(super) fn parse_fields(path: &Path, text: &str) -> Result<Vec<Field>> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.by_ref().find(|(_, l)| !l.trim().is_empty()) {
        Some((_, l)) if l.trim() == "ENVI" => {}
        found => {
            return Err(Error::data(
                path,
                found.map(|(n, _)| n),
                "header",
                "does not start with 'ENVI'",
            ))
        }
    }
    let mut fields: Vec<Field> = Vec::new();
    while let Some((n, line)) = lines.next() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        let Some((key, rest)) = line.split_once('=') else {
            return Err(Error::data(
                path,
                Some(n),
                "header",
                format!("expected 'key = value', got '{line}'"),
            ));
        };
        let key = key.trim().to_ascii_lowercase();
        let rest = rest.trim();
        let value = if let Some(open) = rest.strip_prefix('{') {
            let mut body = open.to_string();
            while !body.contains('}') {
                let Some((_, more)) = lines.next() else {
                    return Err(Error::data(path, Some(n), &key, "'{' is never closed"));
                };
                body.push('\n');
                body.push_str(more);
            }
            let (inside, after) = body.split_once('}').unwrap_or((&body, ""));
            // Values never nest braces: a second '{' first means this one
            // was left open and swallowed the next field.
            if inside.contains('{') {
                return Err(Error::data(path, Some(n), &key, "'{' is never closed"));
            }
            if !after.trim().is_empty() {
                return Err(Error::data(
                    path,
                    Some(n),
                    &key,
                    format!("unexpected '{}' after the closing '}}'", after.trim()),
                ));
            }
            inside.trim().to_string()
        } else {
            rest.to_string()
        };
        if key.is_empty() {
            return Err(Error::data(path, Some(n), "header", "a value has no key"));
        }
        if fields.iter().any(|(k, _, _)| *k == key) {
            return Err(Error::data(path, Some(n), &key, "appears twice"));
        }
        fields.push((key, value, n));
    }
    Ok(fields)
}

/// Typed access to parsed header fields, with errors naming file, line and field.
pub(super) struct Header<'a> {
    pub(super) path: &'a Path,
    pub(super) fields: Vec<Field>,
}

impl Header<'_> {
    /// `data type`: the four ENVI codes the reader takes.
    pub(super) fn data_type(&self) -> Result<DataType> {
        Ok(match self.required("data type")? {
            ("2", _) => DataType::I16,
            ("12", _) => DataType::U16,
            ("4", _) => DataType::F32,
            ("5", _) => DataType::F64,
            (v, line) => {
                return Err(Error::data(
                    self.path,
                    Some(line),
                    "data type",
                    format!(
                "is '{v}': supported are 2 (int16), 12 (uint16), 4 (float32) and 5 (float64)"
            ),
                ))
            }
        })
    }

    /// `interleave`: bsq, bil or bip.
    pub(super) fn interleave(&self) -> Result<Interleave> {
        let (v, line) = self.required("interleave")?;
        Interleave::parse(v).ok_or_else(|| {
            Error::data(
                self.path,
                Some(line),
                "interleave",
                format!("is '{v}': bsq, bil or bip"),
            )
        })
    }

    /// `byte order`: 0 (little-endian, the default) or 1.
    pub(super) fn big_endian(&self) -> Result<bool> {
        Ok(match self.get("byte order") {
            None | Some(("0", _)) => false,
            Some(("1", _)) => true,
            Some((v, line)) => {
                return Err(Error::data(
                    self.path,
                    Some(line),
                    "byte order",
                    format!("is '{v}': 0 (little-endian) or 1 (big-endian)"),
                ))
            }
        })
    }

    /// `wavelength units`: the factor to nanometres.
    pub(super) fn wavelength_scale(&self) -> Result<f64> {
        Ok(match self.get("wavelength units") {
            None => 1.0,
            Some((v, line)) => match v.to_ascii_lowercase().as_str() {
                "nanometers" | "nm" => 1.0,
                "micrometers" | "microns" | "um" => 1000.0,
                _ => {
                    return Err(Error::data(
                        self.path,
                        Some(line),
                        "wavelength units",
                        format!("'{v}' is not Nanometers or Micrometers"),
                    ))
                }
            },
        })
    }
    pub(super) fn get(&self, key: &str) -> Option<(&str, usize)> {
        self.fields
            .iter()
            .find(|(k, _, _)| k == key)
            .map(|(_, v, n)| (v.as_str(), *n))
    }

    pub(super) fn required(&self, key: &str) -> Result<(&str, usize)> {
        self.get(key)
            .ok_or_else(|| Error::data(self.path, None, key, "missing"))
    }

    pub(super) fn whole(&self, key: &str) -> Result<usize> {
        let (v, n) = self.required(key)?;
        v.parse::<usize>().map_err(|_| {
            Error::data(
                self.path,
                Some(n),
                key,
                format!("expected a whole number, got '{v}'"),
            )
        })
    }

    pub(super) fn positive(&self, key: &str) -> Result<usize> {
        match self.whole(key)? {
            0 => Err(Error::data(
                self.path,
                self.get(key).map(|(_, n)| n),
                key,
                "must be at least 1",
            )),
            v => Ok(v),
        }
    }

    /// Band centres (nm) from the first number in each of `band names`
    /// that is followed by a unit (nm, um) or is the whole name (then in
    /// the header's wavelength units, `scale`), or `None` without band
    /// names or such a number in each ("Band 3" names a band, not a
    /// wavelength).
    pub(super) fn band_name_wavelengths(
        &self,
        count: usize,
        scale: f64,
    ) -> Result<Option<Vec<f64>>> {
        let Some((v, n)) = self.get("band names") else {
            return Ok(None);
        };
        let names: Vec<&str> = v.split(',').map(str::trim).collect();
        if names.len() != count {
            return Err(Error::data(
                self.path,
                Some(n),
                "band names",
                format!("has {} names but bands = {count}", names.len()),
            ));
        }
        let number = |name: &str| -> Option<f64> {
            let start = name.find(|c: char| c.is_ascii_digit())?;
            let rest = &name[start..];
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(rest.len());
            let x: f64 = rest[..end].parse().ok()?;
            let lower = rest[end..].trim_start().to_ascii_lowercase();
            let micro =
                lower.starts_with("um") || lower.starts_with("µm") || lower.starts_with("micro");
            let nano = lower.starts_with("nm") || lower.starts_with("nano");
            // A bare number, or one with a unit: "Band 3" numbers bands.
            if micro {
                Some(x * 1000.0)
            } else if nano {
                Some(x)
            } else {
                (name.trim() == &rest[..end]).then_some(x * scale)
            }
        };
        Ok(names
            .iter()
            .map(|name| number(name).filter(|x| *x > 0.0 && x.is_finite()))
            .collect())
    }

    /// A `{a, b, ...}` list of finite numbers with exactly `count` entries,
    /// or `None` if the field is absent.
    pub(super) fn list(&self, key: &str, count: usize) -> Result<Option<Vec<f64>>> {
        let Some((v, n)) = self.get(key) else {
            return Ok(None);
        };
        let values = v
            .split(',')
            .map(|s| s.trim())
            .enumerate()
            .map(|(i, s)| {
                s.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        Error::data(
                            self.path,
                            Some(n),
                            format!("{key}[{i}]"),
                            format!("expected a number, got '{s}'"),
                        )
                    })
            })
            .collect::<Result<Vec<f64>>>()?;
        if values.len() != count {
            return Err(Error::data(
                self.path,
                Some(n),
                key,
                format!("has {} values but bands = {count}", values.len()),
            ));
        }
        Ok(Some(values))
    }
}
