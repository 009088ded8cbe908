//! Reading GPU results back: cull buffers for tests and dumps, targets for PNGs.

use crate::error::{Error, Result};

/// Blocks until `device` has finished all submitted work.
pub fn wait_idle(device: &wgpu::Device) -> Result<()> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(drop)
        .map_err(|e| Error::Readback(e.to_string()))
}

/// Copies `size` bytes of `buffer` into a mappable buffer and waits for them.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>> {
    read_range(device, queue, (buffer, 0), size)
}

/// [`read_buffer`] from `offset` on (a multiple of 4).
pub fn read_range(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    (buffer, offset): (&wgpu::Buffer, u64),
    size: u64,
) -> Result<Vec<u8>> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stereocull.readback"),
        size: size.max(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size.max(4));
    queue.submit([encoder.finish()]);
    map(device, &staging, size)
}

/// [`read_buffer`], as a vector of `T` (`size` must be a multiple of its size).
pub fn read_pod<T: bytemuck::Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<T>> {
    read_pod_at(device, queue, (buffer, 0), size)
}

/// [`read_pod`] from `offset` on (a multiple of 4).
pub fn read_pod_at<T: bytemuck::Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    at: (&wgpu::Buffer, u64),
    size: u64,
) -> Result<Vec<T>> {
    Ok(bytemuck::pod_collect_to_vec(&read_range(
        device, queue, at, size,
    )?))
}

fn map(device: &wgpu::Device, staging: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
    let (sender, receiver) = std::sync::mpsc::channel();
    // On a lost device the staging buffer is invalid and map_async raises a validation
    // error, which without a scope would reach the (by default panicking) uncaptured
    // error handler: the scope turns it into this function's error.
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        // The receiver outlives the poll below; a failed send cannot happen.
        let _ = sender.send(r);
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Readback(format!("{e} (was the device lost?)")));
    }
    wait_idle(device)?;
    receiver
        .recv()
        .map_err(|e| Error::Readback(e.to_string()))?
        .map_err(|e| Error::Readback(e.to_string()))?;
    let bytes = staging
        .get_mapped_range(..size)
        .map_err(|e| Error::Readback(e.to_string()))?
        .to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Every layer of `texture` read back, one copy per layer (lavapipe copies a depth
/// array's layers in one copy all into the first layer's place), `texel` bytes a texel
/// of `aspect`: the bytes, rows padded to the copy alignment, layer after layer, and
/// the padded row's length.
fn read_layers(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    (texel, aspect): (u32, wgpu::TextureAspect),
) -> Result<(u32, Vec<u8>)> {
    let (w, h, layers) = (
        texture.width(),
        texture.height(),
        texture.depth_or_array_layers(),
    );
    let row = (texel * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let size = (row * h * layers) as u64;
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stereocull.readback_texture"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    for layer in 0..layers {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: u64::from(row * h * layer),
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    }
    queue.submit([encoder.finish()]);
    Ok((row, map(device, &staging, size)?))
}

/// Reads an RGBA8 texture (bytes as stored, sRGB or not) into an image; the layers of
/// an array texture are placed side by side, so a two-layer stereo target reads back
/// like a double-wide one.
pub fn read_rgba8(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<image::RgbaImage> {
    let (w, h, layers) = (
        texture.width(),
        texture.height(),
        texture.depth_or_array_layers(),
    );
    let (row, padded) = read_layers(device, queue, texture, (4, wgpu::TextureAspect::All))?;
    let mut image = image::RgbaImage::new(w * layers, h);
    for (i, chunk) in padded.chunks(row as usize).enumerate() {
        let (layer, y) = (i as u32 / h, i as u32 % h);
        for x in 0..w {
            let p = &chunk[4 * x as usize..4 * x as usize + 4];
            image.put_pixel(layer * w + x, y, image::Rgba([p[0], p[1], p[2], p[3]]));
        }
    }
    Ok(image)
}

/// Reads a motion target ([`crate::motion::MOTION_FORMAT`], single-sampled, one
/// layer): each pixel's x and y, rows from the top.
pub fn read_motion(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<[f32; 2]>> {
    let (w, h) = (texture.width(), texture.height());
    let (row, padded) = read_layers(device, queue, texture, (4, wgpu::TextureAspect::All))?;
    let mut values = Vec::with_capacity((w * h) as usize);
    for chunk in padded.chunks(row as usize).take(h as usize) {
        let halves: &[half::f16] = bytemuck::cast_slice(&chunk[..4 * w as usize]);
        values.extend(halves.chunks(2).map(|p| [p[0].to_f32(), p[1].to_f32()]));
    }
    Ok(values)
}

/// Reads a single-sampled `Depth32Float` texture: width x height values per layer, rows
/// from the top, the layers of an array texture side by side (as [`read_rgba8`] places
/// them). Returns the width of the whole (layers x width) and the values.
pub fn read_depth(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<(u32, Vec<f32>)> {
    let (w, h, layers) = (
        texture.width(),
        texture.height(),
        texture.depth_or_array_layers(),
    );
    let (row, padded) = read_layers(device, queue, texture, (4, wgpu::TextureAspect::DepthOnly))?;
    let width = w * layers;
    let mut values = vec![0.0; (width * h) as usize];
    for (i, chunk) in padded.chunks(row as usize).enumerate() {
        let (layer, y) = (i as u32 / h, i as u32 % h);
        let start = (y * width + layer * w) as usize;
        let texels: &[f32] = bytemuck::cast_slice(&chunk[..4 * w as usize]);
        values[start..start + w as usize].copy_from_slice(texels);
    }
    Ok((width, values))
}
