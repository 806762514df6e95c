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
mod tests {
    #[derive(serde::Serialize, serde::Deserialize)]
    struct R {
        #[serde(deserialize_with = "super::f64s")]
        v: Vec<f64>,
        #[serde(deserialize_with = "super::f64_or_nan")]
        x: f64,
    }

    #[test]
    fn non_finite_numbers_come_back_as_nan() {
        let text = serde_json::to_string(&R {
            v: vec![1.5, f64::NAN, f64::INFINITY, 0.1],
            x: f64::NAN,
        })
        .unwrap();
        assert_eq!(text, r#"{"v":[1.5,null,null,0.1],"x":null}"#);
        let back: R = serde_json::from_str(&text).unwrap();
        assert_eq!(back.v[0], 1.5);
        assert!(back.v[1].is_nan() && back.v[2].is_nan());
        assert_eq!(back.v[3], 0.1);
        assert!(back.x.is_nan());
    }
}
