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

/// A KTX2 of one `w` x `h` image of plain texels in Vulkan format `format` (channels of
/// `type_size` bytes), its one level raw or, with `zstd`, Zstandard-supercompressed.
pub fn raw(format: u32, (w, h): (u32, u32), type_size: u32, texels: &[u8], zstd: bool) -> Vec<u8> {
    let level = match zstd {
        true => {
            ruzstd::encoding::compress_to_vec(texels, ruzstd::encoding::CompressionLevel::Fastest)
        }
        false => texels.to_vec(),
    };
    let mut out = vec![
        0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
    ];
    let scheme = if zstd { 2 } else { 0 };
    // vkFormat, typeSize, width, height, depth, layers, faces, levels, supercompression.
    for word in [format, type_size, w, h, 0, 0, 1, 1, scheme] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    // The data format descriptor: its total size alone (no blocks), after the index.
    let dfd_at = 80 + 24;
    let level_at = (dfd_at + 4u64).next_multiple_of(16);
    for word in [dfd_at as u32, 4, 0, 0] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    for word in [0u64, 0, level_at, level.len() as u64, texels.len() as u64] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&4u32.to_le_bytes());
    out.resize(level_at as usize, 0);
    out.extend_from_slice(&level);
    out
}
