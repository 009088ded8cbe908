//! KTX2 images of plain texels, which glTF files from other engines reference directly
//! (without `KHR_texture_basisu`: Bevy writes and reads them): one 2D image of R8,
//! R8G8, R8G8B8 or R8G8B8A8 texels (UNORM or SRGB) or of their 16-bit float formats,
//! stored raw or Zstandard-supercompressed. Its largest level becomes the RGBA8 image
//! a PNG would (the texture arrays build the mip chain).
//!
//! Texels become what a GPU samples from the format: missing green and blue are 0,
//! missing alpha 1. The texture's slot says how its RGBA8 is read (base color and
//! emissive as sRGB, the rest linear), so a texel whose format has the other transfer
//! function is converted to it, as sampling the format and writing the slot would.

use half::f16;
use image::RgbaImage;
use ktx2::{Format, SupercompressionScheme};

use crate::materials::{linear_from_srgb, srgb_from_linear};
use crate::scene::Encoding;

type Step<T> = std::result::Result<T, String>;

/// The largest side we read (Basis Universal's limit too), which bounds what a file can
/// make us allocate.
const MAX_SIDE: u32 = 16384;

/// How a plain format stores a texel: its channels, bytes per channel, and whether its
/// 8-bit values are sRGB-encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    channels: usize,
    float: bool,
    srgb: bool,
}

/// The layout of `format`, where it is one we read.
fn layout(format: Format) -> Option<Layout> {
    let unorm = |channels| Layout {
        channels,
        float: false,
        srgb: false,
    };
    let srgb = |channels| Layout {
        srgb: true,
        ..unorm(channels)
    };
    let float = |channels| Layout {
        float: true,
        ..unorm(channels)
    };
    Some(match format {
        Format::R8_UNORM => unorm(1),
        Format::R8G8_UNORM => unorm(2),
        Format::R8G8B8_UNORM => unorm(3),
        Format::R8G8B8A8_UNORM => unorm(4),
        Format::R8_SRGB => srgb(1),
        Format::R8G8_SRGB => srgb(2),
        Format::R8G8B8_SRGB => srgb(3),
        Format::R8G8B8A8_SRGB => srgb(4),
        Format::R16_SFLOAT => float(1),
        Format::R16G16_SFLOAT => float(2),
        Format::R16G16B16_SFLOAT => float(3),
        Format::R16G16B16A16_SFLOAT => float(4),
        _ => return None,
    })
}

/// The largest level of a KTX2 file of plain texels as RGBA8, for a texture read as
/// `encoding`; `None` where the file holds Basis Universal texels (its format
/// undefined: [`crate::basisu`]'s). Formats other than those above are refused, by name.
pub fn decode(bytes: &[u8], encoding: Encoding) -> Step<Option<RgbaImage>> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| format!("KTX2: {e}"))?;
    let header = reader.header();
    let Some(format) = header.format else {
        return Ok(None);
    };
    let layout = layout(format).ok_or_else(|| {
        format!(
            "KTX2 format {format:?}; we read R8, R8G8, R8G8B8, R8G8B8A8 (UNORM, SRGB) and R16 to R16G16B16A16 (SFLOAT)"
        )
    })?;
    let (w, h) = (header.pixel_width, header.pixel_height);
    let shape = (
        header.pixel_depth,
        header.layer_count.max(1),
        header.face_count,
    );
    if h == 0 || w > MAX_SIDE || h > MAX_SIDE || shape != (0, 1, 1) {
        return Err(format!(
            "a KTX2 of {w}x{h}x{} texels, {} layers, {} faces; glTF textures are single 2D images of at most {MAX_SIDE} a side",
            shape.0, shape.1, shape.2
        ));
    }
    let level = (reader.levels().next()).ok_or("KTX2 without levels")?;
    let size = layout.bytes_per_texel() * w as usize * h as usize;
    let texels = inflated(level.data, header.supercompression_scheme, size)?;
    let texels = (texels.get(..size))
        .ok_or_else(|| format!("a KTX2 level of {} bytes for {w}x{h} texels", texels.len()))?;
    let rgba = texels
        .chunks_exact(layout.bytes_per_texel())
        .flat_map(|texel| layout.rgba8(texel, encoding))
        .collect();
    let image = RgbaImage::from_raw(w, h, rgba).ok_or("KTX2: too few texels")?;
    Ok(Some(image))
}

/// A level's bytes as stored, or inflated from Zstandard (to at most `size` bytes:
/// the file's own count is not trusted with the allocation).
fn inflated(data: &[u8], scheme: Option<SupercompressionScheme>, size: usize) -> Step<Vec<u8>> {
    match scheme {
        None => Ok(data.to_vec()),
        Some(SupercompressionScheme::Zstandard) => crate::basisu::inflate(data, size),
        Some(other) => Err(format!(
            "KTX2 supercompression {other:?}; plain texels are read raw or Zstandard"
        )),
    }
}

impl Layout {
    fn bytes_per_texel(self) -> usize {
        self.channels * if self.float { 2 } else { 1 }
    }

    /// One texel as RGBA8 for a texture read as `encoding`.
    fn rgba8(self, texel: &[u8], encoding: Encoding) -> [u8; 4] {
        let mut rgba = [0, 0, 0, 255];
        for (c, out) in rgba.iter_mut().enumerate().take(self.channels) {
            let alpha = c == 3;
            *out = match self.float {
                true => {
                    let bits = u16::from_le_bytes([texel[2 * c], texel[2 * c + 1]]);
                    let value = f16::from_bits(bits).to_f32();
                    let color = !alpha && encoding == Encoding::Srgb;
                    unorm8(if color {
                        srgb_from_linear(value)
                    } else {
                        value
                    })
                }
                false => {
                    let value = texel[c];
                    match (alpha, self.srgb, encoding) {
                        (false, false, Encoding::Srgb) => {
                            unorm8(srgb_from_linear(value as f32 / 255.0))
                        }
                        (false, true, Encoding::Linear) => {
                            unorm8(linear_from_srgb(value as f32 / 255.0))
                        }
                        _ => value,
                    }
                }
            };
        }
        rgba
    }
}

/// `value` in [0, 1] as the nearest 8-bit level (clamped; NaN is 0).
fn unorm8(value: f32) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}
