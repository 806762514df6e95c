use super::*;

#[test]
fn finds_lines_of_nested_keys() {
    let text = "name = \"x\"\n[water]\nchl = 1.0\n\n[[target]]\nkind = \"box\"\n[[target]]\nkind = \"panel\"\nreflectance = 2.0\n";
    let src = Source::new(text, Path::new("s.toml"));
    assert_eq!(src.line_of_path(&[Step::Key("water"), Step::Key("chl")]), 3);
    assert_eq!(
        src.line_of_path(&[
            Step::Key("target"),
            Step::Index(1),
            Step::Key("reflectance")
        ]),
        9
    );
    // A missing key points at its enclosing table.
    assert_eq!(
        src.line_of_path(&[Step::Key("water"), Step::Key("cdom_440")]),
        2
    );
    let e = src.error(
        &[
            Step::Key("target"),
            Step::Index(1),
            Step::Key("reflectance"),
        ],
        "too big",
    );
    assert_eq!(e.to_string(), "s.toml:9: target[1].reflectance: too big");
}
