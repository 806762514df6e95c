use super::*;

const BASE: &str = r#"
name = "base"
[spectral]
start_nm = 400.0
end_nm = 700.0
bands = 4
[water]
iop = { a = 0.1, b = 0.2 }
[[radiometer]]
depth_m = 1.0
view = "nadir"
"#;

/// Keys set, made, replaced and removed by dotted path; tables merged key
/// by key; array entries added; the text reads back as the same table.
#[test]
fn keys_tables_and_arrays_change_as_asked() {
    let s = SceneText::parse(BASE)
        .unwrap()
        .set("spectral.bands", 16)
        .set("sensor.pixels", vec![48, 48])
        .set("name", "deep")
        .remove("spectral.end_nm")
        .remove("no.such.key")
        .merge("[water]\nphase = { kind = \"petzold\" }\n[photons]\ncount = 10")
        .unwrap()
        .push("radiometer", "depth_m = 3.0\nview = \"zenith\"")
        .unwrap()
        .set_toml("water.iop", "{ a = 0.3, b = 0.6 }")
        .unwrap();
    let int = |k: &str| s.get(k).and_then(Value::as_integer);
    assert_eq!(int("spectral.bands"), Some(16));
    assert_eq!(
        s.get("spectral.start_nm").and_then(Value::as_float),
        Some(400.0)
    );
    assert!(s.get("spectral.end_nm").is_none());
    assert_eq!(s.get("name").and_then(Value::as_str), Some("deep"));
    assert_eq!(int("photons.count"), Some(10));
    assert_eq!(s.get("water.iop.a").and_then(Value::as_float), Some(0.3));
    assert_eq!(
        s.get("water.phase.kind").and_then(Value::as_str),
        Some("petzold")
    );
    let sensor = s.get("sensor.pixels").and_then(Value::as_array).unwrap();
    assert_eq!(sensor.len(), 2);
    let radiometers = s.get("radiometer").and_then(Value::as_array).unwrap();
    assert_eq!(radiometers.len(), 2);
    assert_eq!(radiometers[1]["view"].as_str(), Some("zenith"));
    assert_eq!(SceneText::parse(&s.text()).unwrap(), s);
}

/// A scalar in the way of a dotted key becomes a table; bad TOML and a
/// push onto a non-array are errors that say what is wrong.
#[test]
fn errors_name_what_is_wrong() {
    let s = SceneText::parse(BASE).unwrap().set("name.inner", 1);
    assert_eq!(s.get("name.inner").and_then(Value::as_integer), Some(1));
    let e = SceneText::parse("[water\n").unwrap_err().to_string();
    assert!(e.contains("scene text"), "{e}");
    let e = SceneText::parse(BASE)
        .unwrap()
        .set_toml("sensor.pixels", "[48,")
        .unwrap_err()
        .to_string();
    assert!(e.contains("sensor.pixels") && e.contains("[48,"), "{e}");
    let e = SceneText::parse(BASE)
        .unwrap()
        .push("spectral.bands", "x = 1")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("spectral.bands is not an array of tables"),
        "{e}"
    );
}

/// The built-in scene's text, rewritten, builds the same scene: the same
/// emission inputs (every value emission reads), sensor, radiometers and
/// settings.
#[test]
fn the_builtin_scene_survives_a_rewrite() {
    let o = crate::scene::Overrides::default();
    let at = std::path::Path::new("<built-in coastal scene>");
    let rewritten = crate::scene::Scene::parse(&SceneText::builtin().text(), at, &o).unwrap();
    let original = crate::scene::Scene::coastal(&o).unwrap();
    let digest = |s: &crate::scene::Scene| s.emission_inputs().unwrap().finish().digest_hex();
    assert_eq!(digest(&rewritten), digest(&original));
    assert_eq!(rewritten.summary(), original.summary());
    assert_eq!(
        format!("{:?}", rewritten.sensor),
        format!("{:?}", original.sensor)
    );
    assert_eq!(
        format!("{:?}", rewritten.radiometers),
        format!("{:?}", original.radiometers)
    );
    assert_eq!(
        format!("{:?}", rewritten.estimate),
        format!("{:?}", original.estimate)
    );
    assert_eq!(
        format!("{:?}", rewritten.render),
        format!("{:?}", original.render)
    );
}
