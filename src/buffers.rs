//! Buffer creation shared by the culling, drawing and material uploads, and where
//! writes into them go ([`Upload`]).

use wgpu::util::DeviceExt;

/// The smallest buffer we create: wgpu refuses empty bindings and slices, and 80 bytes
/// hold one element of any record we bind (the largest: the instance and material
/// records; `materials` asserts its own), so an empty scene draws nothing instead of
/// failing.
pub(crate) const MIN_BUFFER: usize = 80;
const _: () = assert!(size_of::<crate::records::InstanceRecord>() <= MIN_BUFFER);

/// A buffer holding `contents`, padded with zeros to at least [`MIN_BUFFER`] bytes.
pub(crate) fn init_buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    init_buffer_with_room(device, label, contents, 0, usage)
}

/// A buffer of at least `size` bytes (and [`MIN_BUFFER`]) starting with `contents`: room
/// for a scene to grow into without reallocating.
pub(crate) fn init_buffer_with_room(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let size = (size as usize).max(contents.len()).max(MIN_BUFFER);
    let padded;
    let contents = if size > contents.len() {
        padded = [contents, &vec![0; size - contents.len()]].concat();
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
        size: size.max(MIN_BUFFER as u64).next_multiple_of(4),
        usage,
        mapped_at_creation: false,
    })
}

/// A uniform buffer for one `T`.
pub(crate) fn uniform_buffer<T: encase::ShaderType>(
    device: &wgpu::Device,
    label: &str,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: T::min_size().get(),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Where a frame's writes into buffers go: a `wgpu::Queue` writes each straight; the
/// renderer gathers the pose's into one upload (`renderer::uploads`). Its method is
/// the queue's, so that a queue is one.
pub trait Upload {
    /// Writes `data` at `offset` of `buffer` before the next submission's commands.
    fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]);

    /// Writes `value` laid out as its WGSL uniform at `offset` of `buffer`; returns the
    /// bytes written.
    fn write_uniform<T>(&self, buffer: &wgpu::Buffer, offset: u64, value: &T) -> u64
    where
        T: encase::ShaderType + encase::internal::WriteInto,
    {
        let bytes = crate::records::uniform_bytes(value);
        self.write_buffer(buffer, offset, &bytes);
        bytes.len() as u64
    }
}

impl Upload for wgpu::Queue {
    fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        wgpu::Queue::write_buffer(self, buffer, offset, data);
    }
}

/// Writes `bytes` at the start of `buffer` (nothing for none); returns the bytes written.
pub(crate) fn write(queue: &impl Upload, buffer: &wgpu::Buffer, bytes: &[u8]) -> u64 {
    if !bytes.is_empty() {
        queue.write_buffer(buffer, 0, bytes);
    }
    bytes.len() as u64
}
