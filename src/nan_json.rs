//! JSON conventions of the reports: JSON has no NaN or infinity, so
//! serde_json writes non-finite numbers as `null` (a Kd between two depths
//! that no photon of a band reached, say). These read `null` back as NaN,
//! so a report read back (a map's recorded emission report, a tool reading
//! `NAME.json`) is the report that was written.

use serde::{Deserialize, Deserializer};

/// A list of numbers in which `null` stands for NaN.
pub fn f64s<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    let v: Vec<Option<f64>> = Vec::deserialize(d)?;
    Ok(v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

/// A number for which `null` stands for NaN.
pub fn f64_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests;
