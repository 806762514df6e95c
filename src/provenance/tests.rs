use super::*;

#[test]
fn framing_separates_parts() {
    let digest = |parts: &[(&str, &[u8])]| {
        let mut b = ProvenanceBuilder::new();
        for (n, v) in parts {
            b.part(n, v);
        }
        b.finish().digest
    };
    assert_ne!(digest(&[("a", b"bc")]), digest(&[("ab", b"c")]));
    assert_ne!(digest(&[("a", b"b"), ("c", b"")]), digest(&[("a", b"bc")]));
    assert_eq!(digest(&[("a", b"b")]), digest(&[("a", b"b")]));
    assert_ne!(digest(&[]), Provenance::unrecorded().digest);
}

#[test]
fn sha256_of_a_known_string() {
    // FIPS 180-2 test vector.
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}

#[test]
fn record_lists_values_and_digest() {
    let mut b = ProvenanceBuilder::new();
    b.value("photons", 10u64).note("scene", "coastal");
    let p = b.finish();
    let r = p.record_json();
    assert_eq!(r["photons"], 10);
    assert_eq!(r["scene"], "coastal");
    assert_eq!(r["digest"], p.digest_hex());
}
