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
