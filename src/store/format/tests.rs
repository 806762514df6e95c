use super::*;

#[test]
fn header_round_trips() {
    let h = Header {
        photons: 123_456_789_012,
        tiles: 7,
        bands: BandGrid::even(400.0, 700.0, 31).unwrap(),
        bounds: Aabb {
            min: Vec3::new(0.0, 0.0, -20.0),
            max: Vec3::new(100.0, 100.0, 0.0),
        },
        partition: vec![
            PartitionNode::Split {
                axis: 2,
                value: -1.5,
            },
            PartitionNode::Leaf,
            PartitionNode::Leaf,
        ],
        provenance: Provenance {
            digest: [7; 32],
            record: r#"{"photons":10}"#.into(),
        },
        metadata: Section {
            offset: 1 << 40,
            length: 99,
            crc: 0xfeed_f00d,
        },
    };
    let bytes = h.encode();
    let (back, len) = Header::decode(&bytes, Path::new("t")).unwrap();
    assert_eq!(len, bytes.len());
    assert_eq!(back, h);
}

/// A version-1 header (no provenance) or version-4 header (one zstd frame a
/// tile) is refused with a message that says what to do, not a checksum or
/// length complaint.
#[test]
fn older_maps_are_refused_clearly() {
    for version in [1u32, 4] {
        let mut out = ByteWriter::default();
        out.0.extend_from_slice(&HEADER_MAGIC);
        out.u32(version);
        let body = [0u8; 40];
        out.u32(body.len() as u32 + 4);
        out.0.extend_from_slice(&body);
        let crc = crc32fast::hash(&out.0);
        out.u32(crc);
        let e = Header::decode(&out.0, Path::new("old.map")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("old.map")
                && msg.contains(&format!("version {version}"))
                && msg.contains("emit the map again"),
            "{msg}"
        );
    }
}

#[test]
fn footer_round_trips_and_is_40_bytes() {
    let f = Footer {
        index_offset: 99,
        index_length: 128,
        tiles: 2,
        index_crc: 0xdead_beef,
        version: FORMAT_VERSION,
    };
    let bytes = f.encode();
    assert_eq!(Footer::decode(&bytes, Path::new("t")).unwrap(), f);
    let mut w = ByteWriter::default();
    TileEntry {
        offset: 1,
        length: 2,
        count: 3,
        quant: Aabb::EMPTY,
        bounds: Aabb::EMPTY,
        crc: 4,
        layer: 1,
    }
    .encode(&mut w);
    assert_eq!(w.0.len(), INDEX_ENTRY_LEN);
}

#[test]
fn box_distance() {
    let b = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    assert_eq!(b.distance_sq(Vec3::splat(0.5)), 0.0);
    assert_eq!(b.distance_sq(Vec3::new(2.0, 0.5, -1.0)), 2.0);
}
