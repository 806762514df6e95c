#[test]
fn reads_own_memory() {
    let peak = super::peak_rss_bytes().unwrap();
    let anon = super::rss_anon_bytes().unwrap();
    assert!(peak > 0 && anon > 0 && anon <= peak + (64 << 20));
}
