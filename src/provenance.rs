//! Provenance of a photon map: a SHA-256 digest of exactly the inputs that
//! determine its photons, and a readable record of what went into it.
//!
//! A map records its provenance in its header. A render reuses a map when,
//! and only when, the digest of the scene's emission inputs equals the
//! map's: editing a spectrum CSV, mesh, height field or grid the scene
//! names changes the digest; editing `[estimate]`, `[sensor]` or
//! `[[radiometer]]` does not.
//!
//! Each part is framed by its name and length before hashing, so no two
//! different sequences of parts give the same byte stream.
//!
//! Not for: integrity (tile and header checksums are CRC-32, see `store`).

use sha2::{Digest, Sha256};

/// What a map was made from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Provenance {
    /// SHA-256 over the framed input parts.
    pub digest: [u8; 32],
    /// A JSON object describing the inputs (for `littoral map info`).
    pub record: String,
}

impl Provenance {
    /// The provenance of a map whose producer recorded none: an all-zero
    /// digest that no scene's inputs produce, so it is never reused.
    pub fn unrecorded() -> Provenance {
        Provenance {
            digest: [0; 32],
            record: "{}".into(),
        }
    }

    /// The digest as lowercase hexadecimal.
    pub fn digest_hex(&self) -> String {
        hex(&self.digest)
    }

    /// The record parsed as JSON (a string value if it is not JSON).
    pub fn record_json(&self) -> serde_json::Value {
        serde_json::from_str(&self.record)
            .unwrap_or_else(|_| serde_json::Value::String(self.record.clone()))
    }
}

/// Accumulates named input parts and the readable record.
pub struct ProvenanceBuilder {
    hasher: Sha256,
    record: serde_json::Map<String, serde_json::Value>,
}

impl Default for ProvenanceBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl ProvenanceBuilder {
    pub fn new() -> Self {
        ProvenanceBuilder {
            hasher: Sha256::new(),
            record: serde_json::Map::new(),
        }
    }

    /// Hash one input part.
    pub fn part(&mut self, name: &str, bytes: &[u8]) -> &mut Self {
        self.hasher.update((name.len() as u64).to_le_bytes());
        self.hasher.update(name.as_bytes());
        self.hasher.update((bytes.len() as u64).to_le_bytes());
        self.hasher.update(bytes);
        self
    }

    /// Hash one input part and note its value in the record.
    pub fn value(&mut self, name: &str, value: impl serde::Serialize) -> &mut Self {
        let v = serde_json::to_value(value).unwrap_or(serde_json::Value::Null);
        self.part(name, v.to_string().as_bytes());
        self.record.insert(name.to_string(), v);
        self
    }

    /// Note a value in the record without hashing it (descriptive only).
    pub fn note(&mut self, name: &str, value: impl serde::Serialize) -> &mut Self {
        let v = serde_json::to_value(value).unwrap_or(serde_json::Value::Null);
        self.record.insert(name.to_string(), v);
        self
    }

    /// The finished provenance; the record carries the digest too.
    pub fn finish(mut self) -> Provenance {
        let digest: [u8; 32] = self.hasher.finalize().into();
        self.record
            .insert("digest".into(), serde_json::Value::String(hex(&digest)));
        Provenance {
            digest,
            record: serde_json::Value::Object(self.record).to_string(),
        }
    }
}

/// SHA-256 of `bytes` as lowercase hexadecimal.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests;
