//! Buffer creation shared by the culling, drawing and material uploads.

use wgpu::util::DeviceExt;

/// The smallest buffer we create: wgpu refuses empty bindings and slices, and 64 bytes
/// hold one element of any record we bind, so an empty scene draws nothing instead of
/// failing.
const MIN_BUFFER: usize = 64;

/// A buffer holding `contents`, padded with zeros to at least [`MIN_BUFFER`] bytes.
pub(crate) fn init_buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let padded;
    let contents = if contents.len() < MIN_BUFFER {
        padded = [contents, &[0; MIN_BUFFER][contents.len()..]].concat();
        &padded[..]
    } else {
        contents
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage,
    })
}

/// A buffer of `size` bytes (at least [`MIN_BUFFER`]).
pub(crate) fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(MIN_BUFFER as u64),
        usage,
        mapped_at_creation: false,
    })
}
