//! Basis Universal textures (glTF's `KHR_texture_basisu`): KTX2 files holding ETC1S
//! (BasisLZ) or UASTC (raw or Zstandard) texels, transcoded on the CPU by Binomial's
//! transcoder (the `basis-universal` crate) to what the texture arrays hold.
//!
//! A device that samples BC formats keeps them block-compressed: when every texture of
//! an encoding is a Basis texture of one size, its array is BC7, each level transcoded
//! from the file's own level (a byte a texel instead of four). Otherwise the largest
//! level is transcoded to RGBA8 and takes a PNG's road (resampled to the array's size,
//! mip chain built by the arrays). See `materials::TextureArray`.
//!
//! The crate binds the transcoder of `.basis` files only, not its KTX2 reader. Both
//! containers hold the same slices: KTX2 keeps ETC1S codebooks and Huffman tables in its
//! supercompression global data, `.basis` after its header. So
//! [`BasisTexture::from_ktx2`] parses the KTX2 (the `ktx2` crate), inflates Zstandard
//! levels (`ruzstd`), and lays every level's slices out as a one-image `.basis` file
//! that the bound transcoder reads.

use basis_universal::{TranscodeParameters, Transcoder, TranscoderTextureFormat};
use image::RgbaImage;

type Step<T> = std::result::Result<T, String>;

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

/// Bytes of a BC7 block (4 x 4 texels).
pub const BC7_BLOCK: u32 = 16;

/// Whether `bytes` are a KTX2 file (glTF names an image's type only optionally).
pub fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&KTX2_MAGIC)
}

/// One 2D image's Basis Universal texels, every level the file holds, as a `.basis`
/// file.
#[derive(Clone, Debug, PartialEq)]
pub struct BasisTexture {
    file: Vec<u8>,
    size: (u32, u32),
    levels: u32,
}

impl BasisTexture {
    /// The texels of a KTX2 file that glTF's `KHR_texture_basisu` allows: one 2D image
    /// of ETC1S or UASTC texels.
    pub fn from_ktx2(bytes: &[u8]) -> Step<BasisTexture> {
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
        Ok(BasisTexture {
            file: basis.file(),
            size: basis.size,
            levels: basis.levels.len() as u32,
        })
    }

    /// Width and height of the largest level, in texels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The levels the file holds (1 when it holds no mip chain).
    pub fn levels(&self) -> u32 {
        self.levels
    }

    /// The largest level as RGBA8.
    pub fn rgba(&self) -> Step<RgbaImage> {
        let texels = self.transcode(0, TranscoderTextureFormat::RGBA32)?;
        RgbaImage::from_raw(self.size.0, self.size.1, texels)
            .ok_or_else(|| "Basis Universal: the transcoder wrote too few texels".to_string())
    }

    /// Level `level` as BC7 blocks, rows of blocks top to bottom.
    pub fn bc7(&self, level: u32) -> Step<Vec<u8>> {
        self.transcode(level, TranscoderTextureFormat::BC7_RGBA)
    }

    fn transcode(&self, level: u32, format: TranscoderTextureFormat) -> Step<Vec<u8>> {
        let mut transcoder = Transcoder::new();
        (transcoder.prepare_transcoding(&self.file))
            .map_err(|()| "Basis Universal: its codebooks or tables do not decode".to_string())?;
        let parameters = TranscodeParameters {
            level_index: level,
            ..Default::default()
        };
        (transcoder.transcode_image_level(&self.file, format, parameters))
            .map_err(|e| format!("Basis Universal: transcoding level {level} failed ({e:?})"))
    }
}

/// A KTX2 file's largest level as RGBA8.
pub fn decode(bytes: &[u8]) -> Step<RgbaImage> {
    BasisTexture::from_ktx2(bytes)?.rgba()
}

/// glTF's Basis images are single 2D images with undefined (universal) VkFormat.
fn check_shape(header: &ktx2::Header) -> Step<()> {
    if let Some(format) = header.format {
        return Err(format!(
            "KTX2 format {format:?}; KHR_texture_basisu holds Basis Universal (ETC1S or UASTC) texels"
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
    let chain = 32 - w.max(h).leading_zeros();
    if header.level_count > chain {
        return Err(format!(
            "a KTX2 of {w}x{h} texels with {} levels",
            header.level_count
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

/// The DFD's color model and each sample's channel id.
fn channels(reader: &ktx2::Reader<&[u8]>) -> Step<(Option<ktx2::ColorModel>, Vec<u8>)> {
    let dfd = (reader.basic_dfd()).ok_or("KTX2 without a basic data format descriptor")?;
    let ids = dfd
        .sample_information
        .iter()
        .map(|s| s.channel_type)
        .collect();
    Ok((dfd.color_model, ids))
}

/// Width and height of level `level` of an image of `size`.
fn level_size(size: (u32, u32), level: u32) -> (u32, u32) {
    ((size.0 >> level).max(1), (size.1 >> level).max(1))
}

/// 4 x 4 blocks along a side of `texels`.
pub fn blocks(texels: u32) -> u32 {
    texels.div_ceil(4)
}

/// An ETC1S (BasisLZ) file: its codebooks and tables, and each level's slices.
fn etc1s(reader: &ktx2::Reader<&[u8]>) -> Step<Basis> {
    let (model, ids) = channels(reader)?;
    if model != Some(ktx2::ColorModel::ETC1S) {
        return Err(format!(
            "BasisLZ supercompression of color model {model:?}, not ETC1S"
        ));
    }
    let alpha = ids.get(1) == Some(&ETC1S_ALPHA);
    let global = GlobalData::parse(reader.supercompression_global_data())?;
    if global.images.len() < reader.levels().len() {
        return Err("KTX2: fewer ETC1S image descriptors than levels".into());
    }
    let mut levels = Vec::new();
    for (level, image) in reader.levels().zip(&global.images) {
        let mut slices = vec![(image.rgb, 0)];
        if alpha {
            slices.push((image.alpha, SLICE_HAS_ALPHA));
        }
        for &((offset, length), _) in &slices {
            if offset
                .checked_add(length)
                .is_none_or(|end| end as usize > level.data.len())
            {
                return Err("KTX2: an ETC1S slice lies outside its level".into());
            }
        }
        levels.push((level.data.to_vec(), slices));
    }
    let header = reader.header();
    Ok(Basis {
        format: Format::Etc1s(global),
        flags: HEADER_ETC1S | if alpha { HEADER_HAS_ALPHA_SLICES } else { 0 },
        levels,
        size: (header.pixel_width, header.pixel_height),
    })
}

/// A UASTC file: each level's 16-byte blocks, inflated if Zstandard-compressed.
fn uastc(reader: &ktx2::Reader<&[u8]>) -> Step<Basis> {
    let (model, ids) = channels(reader)?;
    if model != Some(ktx2::ColorModel::UASTC) {
        return Err(format!("KTX2 of color model {model:?}, not UASTC"));
    }
    let header = reader.header();
    let size = (header.pixel_width, header.pixel_height);
    let alpha = matches!(ids.first(), Some(&UASTC_RGBA | &UASTC_RRRG));
    let flags = if alpha { SLICE_HAS_ALPHA } else { 0 };
    let mut levels = Vec::new();
    for (i, level) in reader.levels().enumerate() {
        let (w, h) = level_size(size, i as u32);
        let length = blocks(w) * blocks(h) * 16;
        let data = match header.supercompression_scheme {
            Some(_) => inflate(level.data, length as usize)?,
            None => level.data.to_vec(),
        };
        if data.len() != length as usize {
            return Err(format!(
                "KTX2: level {i} holds {} bytes of UASTC, not {length}",
                data.len()
            ));
        }
        levels.push((data, vec![((0, length), flags)]));
    }
    Ok(Basis {
        format: Format::Uastc,
        flags: 0,
        levels,
        size,
    })
}

/// A Zstandard level, which must inflate to exactly `length` bytes (the file's own
/// count is not trusted with the allocation).
pub(crate) fn inflate(data: &[u8], length: usize) -> Step<Vec<u8>> {
    let mut out = vec![0; length];
    let mut decoder = ruzstd::decoding::FrameDecoder::new();
    let written =
        (decoder.decode_all(data, &mut out)).map_err(|e| format!("KTX2 Zstandard: {e}"))?;
    out.truncate(written);
    Ok(out)
}

/// ETC1S's codebooks and Huffman tables (the KTX2's supercompression global data), and
/// where each level's slices lie.
struct GlobalData {
    endpoint_count: u16,
    selector_count: u16,
    /// Endpoint codebook, selector codebook, tables: as the KTX2 lays them out.
    endpoints: Vec<u8>,
    selectors: Vec<u8>,
    tables: Vec<u8>,
    /// Per image (for one 2D image: per level, the largest first).
    images: Vec<ImageDesc>,
}

/// A level's color and alpha slices: (offset in the level, length).
#[derive(Clone, Copy)]
struct ImageDesc {
    rgb: (u32, u32),
    alpha: (u32, u32),
}

impl GlobalData {
    /// KTX2's BasisLZ global data: counts, lengths, an image descriptor per image,
    /// then the codebooks and tables.
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
        let count = image_count(data.len(), lengths, word(16)?)?;
        let images = (0..count)
            .map(|i| {
                let at = GLOBAL_HEADER + IMAGE_DESC * i;
                Ok(ImageDesc {
                    rgb: (word(at + 4)?, word(at + 8)?),
                    alpha: (word(at + 12)?, word(at + 16)?),
                })
            })
            .collect::<Step<Vec<_>>>()?;
        let mut at = GLOBAL_HEADER + IMAGE_DESC * count;
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
            images,
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

/// A slice of a level: ((offset in the level, length), slice flags).
type Slice = ((u32, u32), u8);

/// One image's levels as the slices of a `.basis` file.
struct Basis {
    format: Format,
    flags: u16,
    /// Per level (the largest first), its bytes and its slices in them.
    levels: Vec<(Vec<u8>, Vec<Slice>)>,
    size: (u32, u32),
}

impl Basis {
    /// The `.basis` file: header, slice descriptors, codebooks and tables (ETC1S),
    /// then the levels' bytes. The transcoder checks the header's sizes and offsets,
    /// not its CRCs, which stay zero.
    fn file(&self) -> Vec<u8> {
        let slices: usize = self.levels.iter().map(|(_, s)| s.len()).sum();
        let mut body = Vec::new();
        let mut sections = [(0u32, 0u32); 3];
        let (counts, tex_format) = match &self.format {
            Format::Etc1s(g) => {
                let mut at = BASIS_HEADER + BASIS_SLICE * slices;
                let tables = [&g.endpoints, &g.selectors, &g.tables];
                for (section, bytes) in sections.iter_mut().zip(tables) {
                    *section = (at as u32, bytes.len() as u32);
                    body.extend_from_slice(bytes);
                    at += bytes.len();
                }
                ((g.endpoint_count, g.selector_count), 0u8)
            }
            Format::Uastc => ((0, 0), 1u8),
        };
        let data_at = BASIS_HEADER + BASIS_SLICE * slices + body.len();
        let data: usize = self.levels.iter().map(|(d, _)| d.len()).sum();
        let mut file = self.header(counts, tex_format, sections, slices, data_at + data);
        let mut level_at = data_at as u32;
        for (level, (bytes, level_slices)) in self.levels.iter().enumerate() {
            for &((offset, length), flags) in level_slices {
                file.extend(self.slice(level as u32, level_at + offset, length, flags));
            }
            level_at += bytes.len() as u32;
        }
        file.extend(body);
        for (bytes, _) in &self.levels {
            file.extend_from_slice(bytes);
        }
        file
    }

    fn header(
        &self,
        counts: (u16, u16),
        tex_format: u8,
        sections: [(u32, u32); 3],
        slices: usize,
        file_size: usize,
    ) -> Vec<u8> {
        let mut h = Packed::default();
        h.put(u32::from(u16::from_le_bytes(*b"sB")), 2);
        h.put(BASIS_VERSION.into(), 2);
        h.put(BASIS_HEADER as u32, 2);
        h.put(0, 2); // header CRC
        h.put((file_size - BASIS_HEADER) as u32, 4);
        h.put(0, 2); // data CRC
        h.put(slices as u32, 3);
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

    fn slice(&self, level: u32, at: u32, length: u32, flags: u8) -> Vec<u8> {
        let (w, h) = level_size(self.size, level);
        let mut s = Packed::default();
        s.put(0, 3); // image
        s.put(level, 1);
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
