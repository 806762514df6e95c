//! Byte sizes on the command line: `64MiB`, `2GiB`, `500MB` or plain bytes.

use crate::error::{Error, Result};

/// Parse a size such as `64MiB` (binary), `500MB` (decimal) or `1048576`.
pub fn parse_size(field: &str, text: &str) -> Result<u64> {
    parse_size::parse_size(text.trim()).map_err(|e| {
        Error::invalid(
            field,
            format!("'{text}' is not a size ({e}); use e.g. 64MiB, 2GiB, 500MB or plain bytes"),
        )
    })
}

#[cfg(test)]
mod tests;
