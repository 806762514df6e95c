use super::*;

#[test]
fn quoting_is_shell_safe() {
    assert_eq!(sh("/a/b.toml"), "/a/b.toml");
    assert_eq!(sh("a b"), "'a b'");
    assert_eq!(sh("it's"), r"'it'\''s'");
    assert_eq!(sh(""), "''");
}
