use super::*;

fn noise(len: usize, seed: u64) -> Vec<u8> {
    let mut state = seed | 1;
    (0..len)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state as u8
        })
        .collect()
}

/// Pieces of every size pushed, padded now and then, read back at
/// unaligned offsets: every piece reads back as written, direct or not.
#[test]
fn blocks_read_back_what_was_pushed() {
    for direct in [true, false] {
        let file = tempfile::tempfile_in(std::env::temp_dir()).unwrap();
        let mut blocks = Blocks::new(&file, 4 * DIRECT_ALIGN);
        if !direct {
            blocks.buffered(&file);
        }
        let mut pieces = Vec::new();
        let mut at = 0u64;
        for (i, len) in [1usize, 4095, 4096, 4097, 9000, 16_384, 3, 40_000, 77]
            .into_iter()
            .enumerate()
        {
            let bytes = noise(len, i as u64 + 7);
            blocks.push(&file, &bytes).unwrap();
            pieces.push((at, bytes));
            at += len as u64;
            if i % 3 == 2 {
                blocks.pad_and_drain(&file).unwrap();
                at = blocks.written() + blocks.gathered().len() as u64;
            }
        }
        blocks.pad_and_drain(&file).unwrap();
        assert!(blocks.gathered().is_empty());
        let mut buf = Vec::new();
        for (offset, bytes) in &pieces {
            let back = read_blocks(&file, *offset, bytes.len(), &mut buf).unwrap();
            assert_eq!(back, &bytes[..], "{} bytes at {offset}", bytes.len());
        }
        let end = blocks.written();
        let past = read_blocks(&file, end - 10, 11, &mut buf).unwrap_err();
        assert_eq!(past.kind(), io::ErrorKind::UnexpectedEof);
    }
}
