//! The file's buffers, with `EXT_meshopt_compression` decoded into place.
//!
//! A compressed buffer view names the bytes it decodes from (usually in the GLB's own
//! buffer) and keeps its own place in a buffer that holds nothing: a "fallback" buffer
//! without a `uri`, or a real one a reader without the extension would use. Each view is
//! decoded into its place with meshoptimizer's decoders (the `meshopt` crate), so every
//! accessor then reads plain bytes, as from an uncompressed file.

use std::path::Path;

use gltf::Document;
use gltf::buffer::Data;

use super::Step;

const MESHOPT: &str = "EXT_meshopt_compression";

/// Every buffer of `document`, its bytes from the GLB `blob`, a data URI or a file
/// beside it (resolved against `base`), with compressed views decoded in place.
pub(super) fn load(
    document: &Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> Step<Vec<Data>> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let fallback = (buffer.extension_value(MESHOPT))
            .and_then(|e| e.get("fallback"))
            .and_then(|f| f.as_bool())
            .unwrap_or(false);
        let data = match (fallback, buffer.source()) {
            (true, gltf::buffer::Source::Bin) => Data(vec![0; buffer.length().next_multiple_of(4)]),
            (_, source) => Data::from_source_and_blob(source, base, &mut blob)
                .map_err(|e| format!("buffers[{}]: {e}", buffer.index()))?,
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffers[{}]: {} bytes, below its byteLength {}",
                buffer.index(),
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    for view in document.views() {
        if let Some(ext) = view.extension_value(MESHOPT) {
            decode_view(&view, ext, &mut buffers)
                .map_err(|e| format!("bufferViews[{}] {MESHOPT}: {e}", view.index()))?;
        }
    }
    Ok(buffers)
}

/// What a compressed view's extension says: where its compressed bytes are, and how
/// they decode.
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: String,
    filter: String,
}

impl Compressed {
    fn of(ext: &serde_json::Value) -> Step<Compressed> {
        let number = |name: &str, default: Option<u64>| {
            (ext.get(name).map(|v| v.as_u64()))
                .unwrap_or(default)
                .map(|v| v as usize)
                .ok_or_else(|| format!("{name} is missing or not a whole number"))
        };
        let text = |name: &str, default: Option<&str>| {
            (ext.get(name).map(|v| v.as_str()))
                .unwrap_or(default)
                .map(str::to_string)
                .ok_or_else(|| format!("{name} is missing or not a string"))
        };
        Ok(Compressed {
            buffer: number("buffer", None)?,
            offset: number("byteOffset", Some(0))?,
            length: number("byteLength", None)?,
            stride: number("byteStride", None)?,
            count: number("count", None)?,
            mode: text("mode", None)?,
            filter: text("filter", Some("NONE"))?,
        })
    }
}

/// Decodes `view`'s compressed bytes into its place in `buffers`.
fn decode_view(
    view: &gltf::buffer::View,
    ext: &serde_json::Value,
    buffers: &mut [Data],
) -> Step<()> {
    let c = Compressed::of(ext)?;
    let source = (buffers.get(c.buffer))
        .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
        .ok_or_else(|| {
            format!(
                "bytes {}+{} of buffer {} do not exist",
                c.offset, c.length, c.buffer
            )
        })?
        .to_vec();
    let size = (c.count.checked_mul(c.stride)).filter(|&s| s <= view.length());
    let Some(size) = size else {
        return Err(format!(
            "count {} x byteStride {} exceeds the view's byteLength {}",
            c.count,
            c.stride,
            view.length()
        ));
    };
    let decoded = decode(&c, &source)?;
    debug_assert_eq!(decoded.len(), size);
    let target = &mut buffers[view.buffer().index()];
    let at = view.offset();
    (target.0.get_mut(at..at + size))
        .ok_or_else(|| format!("the view's bytes {at}+{size} lie past its buffer"))?
        .copy_from_slice(&decoded);
    Ok(())
}

/// `source` decoded as `c` says: `c.count` elements of `c.stride` bytes.
fn decode(c: &Compressed, source: &[u8]) -> Step<Vec<u8>> {
    let mut out = vec![0u8; c.count * c.stride];
    let status = match c.mode.as_str() {
        "ATTRIBUTES" => {
            if c.stride == 0 || !c.stride.is_multiple_of(4) || c.stride > 256 {
                return Err(format!(
                    "ATTRIBUTES byteStride {} is not a multiple of 4 up to 256",
                    c.stride
                ));
            }
            // SAFETY: `out` holds `count * stride` bytes, what the decoder writes; it
            // reads at most `source.len()` bytes of `source`.
            unsafe {
                meshopt::ffi::meshopt_decodeVertexBuffer(
                    out.as_mut_ptr().cast(),
                    c.count,
                    c.stride,
                    source.as_ptr(),
                    source.len(),
                )
            }
        }
        "TRIANGLES" | "INDICES" => {
            if c.stride != 2 && c.stride != 4 {
                return Err(format!("{} byteStride {} is not 2 or 4", c.mode, c.stride));
            }
            if c.mode == "TRIANGLES" && !c.count.is_multiple_of(3) {
                return Err(format!(
                    "TRIANGLES count {} is not a multiple of 3",
                    c.count
                ));
            }
            type Decoder =
                unsafe extern "C" fn(*mut std::ffi::c_void, usize, usize, *const u8, usize) -> i32;
            let decoder: Decoder = match c.mode.as_str() {
                "TRIANGLES" => meshopt::ffi::meshopt_decodeIndexBuffer,
                _ => meshopt::ffi::meshopt_decodeIndexSequence,
            };
            // SAFETY: as above, with `stride`-byte indices.
            unsafe {
                decoder(
                    out.as_mut_ptr().cast(),
                    c.count,
                    c.stride,
                    source.as_ptr(),
                    source.len(),
                )
            }
        }
        other => {
            return Err(format!(
                "mode {other:?} is not ATTRIBUTES, TRIANGLES or INDICES"
            ));
        }
    };
    if status != 0 {
        return Err(format!(
            "the {} data does not decode (meshopt error {status})",
            c.mode
        ));
    }
    unfilter(c, &mut out)?;
    Ok(out)
}

/// Undoes the filter an ATTRIBUTES view was encoded with, in place.
fn unfilter(c: &Compressed, data: &mut [u8]) -> Step<()> {
    type Filter = unsafe extern "C" fn(*mut std::ffi::c_void, usize, usize);
    let (filter, strides): (Filter, &[usize]) = match (c.mode.as_str(), c.filter.as_str()) {
        (_, "NONE") => return Ok(()),
        ("ATTRIBUTES", "OCTAHEDRAL") => (meshopt::ffi::meshopt_decodeFilterOct, &[4, 8]),
        ("ATTRIBUTES", "QUATERNION") => (meshopt::ffi::meshopt_decodeFilterQuat, &[8]),
        ("ATTRIBUTES", "EXPONENTIAL") => (meshopt::ffi::meshopt_decodeFilterExp, &[]),
        (mode, filter) => return Err(format!("filter {filter:?} does not apply to mode {mode}")),
    };
    if !strides.is_empty() && !strides.contains(&c.stride) {
        return Err(format!(
            "filter {} takes byteStride {strides:?}, not {}",
            c.filter, c.stride
        ));
    }
    // SAFETY: `data` holds `count` elements of `stride` bytes, a stride the filter
    // takes (EXPONENTIAL: any multiple of 4, checked with the mode).
    unsafe { filter(data.as_mut_ptr().cast(), c.count, c.stride) };
    Ok(())
}
