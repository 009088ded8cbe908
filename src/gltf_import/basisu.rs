//! `KHR_texture_basisu`: KTX2 images holding Basis Universal texels (ETC1S with BasisLZ,
//! or UASTC, raw or Zstandard-compressed), transcoded to RGBA8.
//!
//! The texture arrays hold one format per encoding and resample every layer to one
//! size, so a Basis image takes the same road as a PNG: its largest level is
//! transcoded to RGBA8 (a format every adapter samples), and the arrays build their own
//! mip chains from it. The file's own smaller levels are not read.
//!
//! The `basis-universal` crate binds Binomial's transcoder for `.basis` files only, not
//! its KTX2 reader. Both containers hold the same slices: KTX2 keeps ETC1S codebooks
//! and Huffman tables in its supercompression global data, `.basis` after its header.
//! So [`decode`] parses the KTX2 (the `ktx2` crate), inflates Zstandard levels
//! (`ruzstd`), and lays the largest level's slices out as a one-image `.basis` file
//! that the bound transcoder reads.

use image::RgbaImage;

use super::Step;

/// The extension's name, as files and `extensionsUsed` spell it.
pub const EXTENSION: &str = "KHR_texture_basisu";

/// The first bytes of every KTX2 file.
const KTX2_MAGIC: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// Basis Universal's largest side (its encoder's limit), which also bounds what a file
/// can make us allocate.
const MAX_SIDE: u32 = 16384;

/// The KTX2 channel ids that mean the texels carry alpha: ETC1S's second (alpha)
/// sample, UASTC's RGBA and RRRG.
const ETC1S_ALPHA: u8 = 15;
const UASTC_RGBA: u8 = 3;
const UASTC_RRRG: u8 = 5;

/// Whether `bytes` are a KTX2 file (glTF names an image's type only optionally).
pub fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&KTX2_MAGIC)
}

/// The texture's image: its `KHR_texture_basisu` source where it names one (the
/// extension's own choice when both are given), else its core `source`.
pub(super) fn source<'a>(
    texture: &gltf::Texture<'a>,
    document: &'a gltf::Document,
) -> Step<gltf::Image<'a>> {
    let basisu =
        (texture.extension_value(EXTENSION)).map(|e| e.get("source").and_then(|s| s.as_u64()));
    let index = match basisu {
        Some(Some(i)) => Some(i as usize),
        Some(None) => {
            return Err(format!(
                "textures[{}]: its {EXTENSION} names no image source",
                texture.index()
            ));
        }
        None => texture.source().map(|i| i.index()),
    };
    let index = index.ok_or_else(|| format!("textures[{}] has no image", texture.index()))?;
    document.images().nth(index).ok_or_else(|| {
        format!(
            "textures[{}] names images[{index}], which does not exist",
            texture.index()
        )
    })
}

/// A KTX2 file's largest level as RGBA8.
pub fn decode(bytes: &[u8]) -> Step<RgbaImage> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| format!("KTX2: {e}"))?;
    let header = reader.header();
    check_shape(&header)?;
    let basis = match header.supercompression_scheme {
        Some(ktx2::SupercompressionScheme::BasisLZ) => etc1s(&reader)?,
        None | Some(ktx2::SupercompressionScheme::Zstandard) => uastc(&reader)?,
        Some(other) => {
            return Err(format!(
                "KTX2 supercompression {other:?} is not Basis Universal"
            ));
        }
    };
    transcode(&basis.file(), header.pixel_width, header.pixel_height)
}

/// glTF's Basis images are single 2D images with undefined (universal) VkFormat.
fn check_shape(header: &ktx2::Header) -> Step<()> {
    if let Some(format) = header.format {
        return Err(format!(
            "KTX2 format {format:?}; {EXTENSION} holds Basis Universal (ETC1S or UASTC) texels"
        ));
    }
    let shape = (
        header.pixel_depth,
        header.layer_count.max(1),
        header.face_count,
    );
    let (w, h) = (header.pixel_width, header.pixel_height);
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "a KTX2 of {w}x{h} texels; Basis Universal images are at most {MAX_SIDE} a side"
        ));
    }
    if h == 0 || shape != (0, 1, 1) {
        return Err(format!(
            "a KTX2 of {}x{}x{} texels, {} layers, {} faces; glTF textures are single 2D images",
            header.pixel_width, header.pixel_height, header.pixel_depth, shape.1, shape.2
        ));
    }
    Ok(())
}

/// The DFD's first sample's channel ids and sample count.
fn channels(reader: &ktx2::Reader<&[u8]>) -> Step<(Option<ktx2::ColorModel>, Vec<u8>)> {
    let dfd = reader
        .basic_dfd()
        .ok_or("KTX2 without a basic data format descriptor")?;
    let ids = dfd
        .sample_information
        .iter()
        .map(|s| s.channel_type)
        .collect();
    Ok((dfd.color_model, ids))
}

/// The largest level's bytes (still supercompressed, if the file is).
fn level0<'a>(reader: &'a ktx2::Reader<&[u8]>) -> Step<ktx2::Level<'a>> {
    reader
        .levels()
        .next()
        .ok_or_else(|| "KTX2 without levels".to_string())
}

/// An ETC1S (BasisLZ) file: its codebooks and tables, and level 0's slices.
fn etc1s(reader: &ktx2::Reader<&[u8]>) -> Step<Basis> {
    let (model, ids) = channels(reader)?;
    if model != Some(ktx2::ColorModel::ETC1S) {
        return Err(format!(
            "BasisLZ supercompression of color model {model:?}, not ETC1S"
        ));
    }
    let alpha = ids.get(1) == Some(&ETC1S_ALPHA);
    let global = GlobalData::parse(reader.supercompression_global_data())?;
    let level = level0(reader)?.data.to_vec();
    let image = global.image;
    let mut slices = vec![(image.rgb, 0)];
    if alpha {
        slices.push((image.alpha, SLICE_HAS_ALPHA));
    }
    for &((offset, length), _) in &slices {
        if offset
            .checked_add(length)
            .is_none_or(|end| end as usize > level.len())
        {
            return Err("KTX2: an ETC1S slice lies outside its level".into());
        }
    }
    Ok(Basis {
        format: Format::Etc1s(global),
        flags: HEADER_ETC1S | if alpha { HEADER_HAS_ALPHA_SLICES } else { 0 },
        level,
        slices,
        size: (reader.header().pixel_width, reader.header().pixel_height),
    })
}

/// A UASTC file: level 0's 16-byte blocks, inflated if Zstandard-compressed.
fn uastc(reader: &ktx2::Reader<&[u8]>) -> Step<Basis> {
    let (model, ids) = channels(reader)?;
    if model != Some(ktx2::ColorModel::UASTC) {
        return Err(format!("KTX2 of color model {model:?}, not UASTC"));
    }
    let header = reader.header();
    let size = (header.pixel_width, header.pixel_height);
    let length = blocks(size.0) * blocks(size.1) * 16;
    let level = level0(reader)?;
    let data = match header.supercompression_scheme {
        Some(_) => inflate(level.data, length as usize)?,
        None => level.data.to_vec(),
    };
    if data.len() != length as usize {
        return Err(format!(
            "KTX2: level 0 holds {} bytes of UASTC, not {length}",
            data.len()
        ));
    }
    let alpha = matches!(ids.first(), Some(&UASTC_RGBA | &UASTC_RRRG));
    Ok(Basis {
        format: Format::Uastc,
        flags: 0,
        level: data,
        slices: vec![((0, length), if alpha { SLICE_HAS_ALPHA } else { 0 })],
        size,
    })
}

/// A Zstandard level, which must inflate to exactly `length` bytes (the file's own
/// count is not trusted with the allocation).
fn inflate(data: &[u8], length: usize) -> Step<Vec<u8>> {
    let mut out = vec![0; length];
    let mut decoder = ruzstd::decoding::FrameDecoder::new();
    let written =
        (decoder.decode_all(data, &mut out)).map_err(|e| format!("KTX2 Zstandard: {e}"))?;
    out.truncate(written);
    Ok(out)
}

/// 4 x 4 blocks along a side of `texels`.
fn blocks(texels: u32) -> u32 {
    texels.div_ceil(4)
}

/// RGBA8 texels of the `.basis` file's one image.
fn transcode(file: &[u8], width: u32, height: u32) -> Step<RgbaImage> {
    use basis_universal::{TranscodeParameters, Transcoder, TranscoderTextureFormat};
    let mut transcoder = Transcoder::new();
    (transcoder.prepare_transcoding(file))
        .map_err(|()| "Basis Universal: its codebooks or tables do not decode".to_string())?;
    let texels = transcoder
        .transcode_image_level(
            file,
            TranscoderTextureFormat::RGBA32,
            TranscodeParameters::default(),
        )
        .map_err(|e| format!("Basis Universal: transcoding failed ({e:?})"))?;
    RgbaImage::from_raw(width, height, texels)
        .ok_or_else(|| "Basis Universal: the transcoder wrote too few texels".to_string())
}

/// ETC1S's codebooks and Huffman tables (the KTX2's supercompression global data), and
/// the largest level's slice placement.
struct GlobalData {
    endpoint_count: u16,
    selector_count: u16,
    /// Endpoint codebook, selector codebook, tables: as the KTX2 lays them out.
    endpoints: Vec<u8>,
    selectors: Vec<u8>,
    tables: Vec<u8>,
    image: ImageDesc,
}

/// Level 0's color and alpha slices: (offset in the level, length).
#[derive(Clone, Copy)]
struct ImageDesc {
    rgb: (u32, u32),
    alpha: (u32, u32),
}

impl GlobalData {
    /// KTX2's BasisLZ global data: counts, lengths, an image descriptor per image
    /// (level 0's first), then the codebooks and tables.
    fn parse(data: &[u8]) -> Step<GlobalData> {
        let word = |at: usize| match data.get(at..at + 4) {
            Some(&[a, b, c, d]) => Ok(u32::from_le_bytes([a, b, c, d])),
            _ => Err("KTX2: BasisLZ global data is cut short".to_string()),
        };
        let counts = word(0)?;
        let lengths = [word(4)?, word(8)?, word(12)?];
        if lengths[..2].iter().any(|&l| l >= 1 << 24) {
            return Err("KTX2: a BasisLZ codebook of over 16 MiB".into());
        }
        let image = ImageDesc {
            rgb: (word(24)?, word(28)?),
            alpha: (word(32)?, word(36)?),
        };
        let mut at = GLOBAL_HEADER + IMAGE_DESC * image_count(data.len(), lengths, word(16)?)?;
        let mut take = |length: u32| -> Step<Vec<u8>> {
            let end = at + length as usize;
            let bytes = data
                .get(at..end)
                .ok_or("KTX2: BasisLZ codebooks are cut short")?;
            at = end;
            Ok(bytes.to_vec())
        };
        Ok(GlobalData {
            endpoint_count: counts as u16,
            selector_count: (counts >> 16) as u16,
            endpoints: take(lengths[0])?,
            selectors: take(lengths[1])?,
            tables: take(lengths[2])?,
            image,
        })
    }
}

/// Bytes before the image descriptors, and of each.
const GLOBAL_HEADER: usize = 20;
const IMAGE_DESC: usize = 20;

/// How many image descriptors global data of `length` bytes holds: what it leaves
/// after the codebooks, tables and `extended` data.
fn image_count(length: usize, lengths: [u32; 3], extended: u32) -> Step<usize> {
    let payload = lengths
        .iter()
        .chain([&extended])
        .map(|&l| l as usize)
        .sum::<usize>();
    match length.checked_sub(GLOBAL_HEADER + payload) {
        Some(d) if d >= IMAGE_DESC && d % IMAGE_DESC == 0 => Ok(d / IMAGE_DESC),
        _ => Err("KTX2: BasisLZ global data's lengths do not add up".into()),
    }
}

enum Format {
    Etc1s(GlobalData),
    Uastc,
}

/// `.basis` header flags and slice flags we set.
const HEADER_ETC1S: u16 = 1;
const HEADER_HAS_ALPHA_SLICES: u16 = 4;
const SLICE_HAS_ALPHA: u8 = 1;
/// The `.basis` version Binomial's transcoder reads, and its header and slice
/// descriptor sizes (packed, little-endian).
const BASIS_VERSION: u16 = 0x13;
const BASIS_HEADER: usize = 77;
const BASIS_SLICE: usize = 23;

/// One image's level 0 as the slices of a `.basis` file.
struct Basis {
    format: Format,
    flags: u16,
    /// Level 0's bytes, and its slices in them: ((offset, length), slice flags).
    level: Vec<u8>,
    slices: Vec<((u32, u32), u8)>,
    size: (u32, u32),
}

impl Basis {
    /// The `.basis` file: header, slice descriptors, codebooks and tables (ETC1S),
    /// then the level's bytes. The transcoder checks the header's sizes and offsets,
    /// not its CRCs, which stay zero.
    fn file(&self) -> Vec<u8> {
        let slices_at = BASIS_HEADER;
        let mut body = Vec::new();
        let mut sections = [(0u32, 0u32); 3];
        let (counts, tex_format) = match &self.format {
            Format::Etc1s(g) => {
                let mut at = slices_at + BASIS_SLICE * self.slices.len();
                for (section, bytes) in
                    sections
                        .iter_mut()
                        .zip([&g.endpoints, &g.selectors, &g.tables])
                {
                    *section = (at as u32, bytes.len() as u32);
                    body.extend_from_slice(bytes);
                    at += bytes.len();
                }
                ((g.endpoint_count, g.selector_count), 0u8)
            }
            Format::Uastc => ((0, 0), 1u8),
        };
        let level_at = (slices_at + BASIS_SLICE * self.slices.len() + body.len()) as u32;
        let mut file = self.header(counts, tex_format, sections, level_at);
        for &((offset, length), flags) in &self.slices {
            file.extend(self.slice(level_at + offset, length, flags));
        }
        file.extend(body);
        file.extend_from_slice(&self.level);
        file
    }

    fn header(
        &self,
        counts: (u16, u16),
        tex_format: u8,
        sections: [(u32, u32); 3],
        level_at: u32,
    ) -> Vec<u8> {
        let data_size = level_at as usize - BASIS_HEADER + self.level.len();
        let mut h = Packed::default();
        h.put(u32::from(u16::from_le_bytes(*b"sB")), 2);
        h.put(BASIS_VERSION.into(), 2);
        h.put(BASIS_HEADER as u32, 2);
        h.put(0, 2); // header CRC
        h.put(data_size as u32, 4);
        h.put(0, 2); // data CRC
        h.put(self.slices.len() as u32, 3);
        h.put(1, 3); // images
        h.put(tex_format.into(), 1);
        h.put(self.flags.into(), 2);
        h.put(0, 1); // 2D
        h.put(0, 3); // microseconds per frame
        for _ in 0..3 {
            h.put(0, 4); // reserved, user data
        }
        let [endpoints, selectors, tables] = sections;
        h.put(counts.0.into(), 2);
        h.put(endpoints.0, 4);
        h.put(endpoints.1, 3);
        h.put(counts.1.into(), 2);
        h.put(selectors.0, 4);
        h.put(selectors.1, 3);
        h.put(tables.0, 4);
        h.put(tables.1, 4);
        h.put(BASIS_HEADER as u32, 4); // slice descriptors
        h.put(0, 4); // extended data
        h.put(0, 4);
        debug_assert_eq!(h.0.len(), BASIS_HEADER);
        h.0
    }

    fn slice(&self, at: u32, length: u32, flags: u8) -> Vec<u8> {
        let (w, h) = self.size;
        let mut s = Packed::default();
        s.put(0, 3); // image
        s.put(0, 1); // level
        s.put(flags.into(), 1);
        s.put(w, 2);
        s.put(h, 2);
        s.put(blocks(w), 2);
        s.put(blocks(h), 2);
        s.put(at, 4);
        s.put(length, 4);
        s.put(0, 2); // CRC
        debug_assert_eq!(s.0.len(), BASIS_SLICE);
        s.0
    }
}

/// Little-endian integers of any byte count, packed without padding.
#[derive(Default)]
struct Packed(Vec<u8>);

impl Packed {
    fn put(&mut self, value: u32, bytes: usize) {
        self.0.extend_from_slice(&value.to_le_bytes()[..bytes]);
    }
}
