//! Occlusion with CPU culling: each display's depth pyramids, built on the GPU from its
//! early depth by the same passes as on the GPU-culled path, then read back mid-frame so
//! that the CPU culler's late phase tests against them. The pyramids, not the depth,
//! come back: a third of the bytes, and the reduction reads multisampled and layered
//! depth, which a copy cannot (`tests/occlusion.rs` holds the GPU's reduction to the
//! CPU twin's).

use crate::error::Result;
use crate::occlusion::PyramidShape;
use crate::readback::read_pod;

/// Per display, its pyramids read back and their shape (`None` without occlusion).
pub(super) type ReadPyramids = Vec<Option<(Vec<f32>, PyramidShape)>>;

/// Every occluding display's pyramids in one buffer, each at its own offset (the
/// GPU-culled path shares one region: its late cull follows each display's pyramids in
/// the same submission; here all are built before any is read).
pub(super) struct PyramidReadback {
    buffer: wgpu::Buffer,
    /// Per display: where its pyramids start (bytes) and their shape.
    regions: Vec<Option<(u64, PyramidShape)>>,
}

impl PyramidReadback {
    /// Room for the pyramids of each display with a shape.
    pub(super) fn new(device: &wgpu::Device, shapes: &[Option<PyramidShape>]) -> PyramidReadback {
        let align = device.limits().min_storage_buffer_offset_alignment as u64;
        let mut end = 0u64;
        let regions = (shapes.iter())
            .map(|shape| {
                let shape = (*shape)?;
                let at = end.next_multiple_of(align);
                end = at + 4 * shape.len() as u64;
                Some((at, shape))
            })
            .collect();
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stereocull.pyramid_readback"),
            size: end.max(4),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        PyramidReadback { buffer, regions }
    }

    /// Display `i`'s pyramids: the buffer and where they start.
    pub(super) fn texels(&self, i: usize) -> Option<(&wgpu::Buffer, u64)> {
        let (at, _) = (*self.regions.get(i)?)?;
        Some((&self.buffer, at))
    }

    /// Every display's pyramids as the last submitted frame built them (waits for it).
    pub(super) fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<ReadPyramids> {
        let all: Vec<f32> = read_pod(device, queue, &self.buffer, self.buffer.size())?;
        Ok((self.regions.iter())
            .map(|r| {
                let (at, shape) = (*r)?;
                let start = at as usize / 4;
                Some((all[start..start + shape.len() as usize].to_vec(), shape))
            })
            .collect())
    }

    /// The buffer's bytes.
    pub(super) fn bytes(&self) -> u64 {
        self.buffer.size()
    }
}
