//! KTX2 rewritten by the tests: a supercompressed file's levels stored raw.

/// `file` (a KTX2 whose levels are Zstandard-compressed) with its levels inflated and
/// stored raw: header, level index, descriptors and key-values as the KTX2 spec lays
/// them out, each level aligned to 16 bytes (the UASTC block), smallest level first.
pub fn inflated(file: &[u8]) -> Vec<u8> {
    let reader = ktx2::Reader::new(file).unwrap();
    let header = reader.header();
    let levels: Vec<Vec<u8>> = reader
        .levels()
        .map(|level| {
            let mut out = vec![0; level.uncompressed_byte_length as usize];
            let mut decoder = ruzstd::decoding::FrameDecoder::new();
            let n = decoder.decode_all(level.data, &mut out).unwrap();
            assert_eq!(n, out.len());
            out
        })
        .collect();
    let index = header.index;
    let dfd = &file[index.dfd_byte_offset as usize..][..index.dfd_byte_length as usize];
    let kvd = &file[index.kvd_byte_offset as usize..][..index.kvd_byte_length as usize];
    let mut out = file[..80].to_vec();
    out[44..48].copy_from_slice(&0u32.to_le_bytes()); // no supercompression
    let index_at = out.len();
    out.resize(index_at + 24 * levels.len(), 0);
    let dfd_at = out.len();
    out.extend_from_slice(dfd);
    let kvd_at = out.len();
    out.extend_from_slice(kvd);
    let words = [
        dfd_at as u32,
        dfd.len() as u32,
        kvd_at as u32,
        kvd.len() as u32,
    ];
    for (i, w) in words.iter().enumerate() {
        out[48 + 4 * i..52 + 4 * i].copy_from_slice(&w.to_le_bytes());
    }
    out[64..80].fill(0); // no supercompression global data
    for (level, data) in levels.iter().enumerate().rev() {
        while !out.len().is_multiple_of(16) {
            out.push(0);
        }
        let entry = [out.len() as u64, data.len() as u64, data.len() as u64];
        let at = index_at + 24 * level;
        for (i, v) in entry.iter().enumerate() {
            out[at + 8 * i..at + 8 * i + 8].copy_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(data);
    }
    out
}
