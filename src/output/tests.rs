use super::*;
use std::io::{Read, Seek, SeekFrom};

/// Pieces of every size, across chunk and block edges, direct or not:
/// the file holds exactly the bytes written, and a header patched in
/// after `finish` lands at the start.
#[test]
fn stream_out_writes_exactly_what_it_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for total in [
        0usize,
        1,
        4095,
        4096,
        4097,
        STREAM_CHUNK,
        3 * STREAM_CHUNK + 12_345,
    ] {
        let bytes: Vec<u8> = (0..total).map(|_| next() as u8).collect();
        let mut out = StreamOut::new(temp_in(dir.path(), "s", ".partial").unwrap());
        let mut at = 0;
        while at < total {
            let n = ((next() % 70_000) as usize).min(total - at);
            out.write_all(&bytes[at..at + n]).unwrap();
            at += n;
        }
        let mut tmp = out.finish().unwrap();
        assert_eq!(tmp.stream_position().unwrap(), total as u64);
        let header = [0xA5u8; 3];
        if total >= header.len() {
            tmp.seek(SeekFrom::Start(0)).unwrap();
            tmp.write_all(&header).unwrap();
        }
        let mut back = Vec::new();
        std::fs::File::open(tmp.path())
            .unwrap()
            .read_to_end(&mut back)
            .unwrap();
        let mut want = bytes.clone();
        if total >= header.len() {
            want[..3].copy_from_slice(&header);
        }
        assert_eq!(back, want, "{total} bytes");
    }
}

/// With direct I/O turned off the bytes are the same.
#[test]
fn stream_out_without_direct_io_matches() {
    let dir = tempfile::tempdir().unwrap();
    let bytes: Vec<u8> = (0..2 * STREAM_CHUNK + 777)
        .map(|i| (i * 31 % 251) as u8)
        .collect();
    let mut out = StreamOut::new(temp_in(dir.path(), "s", ".partial").unwrap());
    out.blocks.buffered(out.tmp.as_file());
    out.write_all(&bytes).unwrap();
    let tmp = out.finish().unwrap();
    assert_eq!(std::fs::read(tmp.path()).unwrap(), bytes);
}
