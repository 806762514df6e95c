use super::*;

#[test]
fn sizes() {
    assert_eq!(parse_size("b", "64MiB").unwrap(), 64 << 20);
    assert_eq!(parse_size("b", "2GiB").unwrap(), 2 << 30);
    assert_eq!(parse_size("b", "500MB").unwrap(), 500_000_000);
    assert_eq!(parse_size("b", "12345").unwrap(), 12345);
    let e = parse_size("--mem-budget", "lots").unwrap_err();
    assert!(e.to_string().contains("--mem-budget"));
}
