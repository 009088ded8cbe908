//! Occlusion with CPU culling: between a frame's two halves, each display's depth
//! pyramids, built on the GPU from its early depth by the same passes as on the
//! GPU-culled path, are read back so that the CPU culler's late phase (and a far
//! layer's tested cull) runs against them. The pyramids, not the depth, come back: a
//! third of the bytes, and the reduction reads multisampled and layered depth, which a
//! copy cannot (`tests/occlusion.rs` holds the GPU's reduction to the CPU twin's).

use std::time::Instant;

use crate::error::Result;
use crate::occlusion::PyramidShape;
use crate::readback::read_pod;
use crate::renderer::culler::{Culler, ViewCull};
use crate::renderer::display::far_layer::Far;
use crate::renderer::plan::{FramePlan, FrameStats};

/// What the CPU culler's late phases need between a frame's two halves.
pub(in crate::renderer) struct CpuLate {
    pub(in crate::renderer) pyramids: PyramidReadback,
    pub(in crate::renderer) plan: Option<FramePlan>,
}

/// Per display, its pyramids read back and their shape (`None` without occlusion).
pub(in crate::renderer) type ReadPyramids = Vec<Option<(Vec<f32>, PyramidShape)>>;

/// Every occluding display's pyramids in one buffer, each at its own offset (the
/// GPU-culled path shares one region: its late cull follows each display's pyramids in
/// the same submission; here all are built before any is read).
pub(in crate::renderer) struct PyramidReadback {
    buffer: wgpu::Buffer,
    /// Per display: where its pyramids start (bytes) and their shape.
    regions: Vec<Option<(u64, PyramidShape)>>,
}

impl PyramidReadback {
    /// Room for the pyramids of each display with a shape.
    pub(in crate::renderer) fn new(
        device: &wgpu::Device,
        shapes: &[Option<PyramidShape>],
    ) -> PyramidReadback {
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
    pub(in crate::renderer) fn texels(&self, i: usize) -> Option<(&wgpu::Buffer, u64)> {
        let (at, _) = (*self.regions.get(i)?)?;
        Some((&self.buffer, at))
    }

    /// Every display's pyramids as the last submitted frame built them (waits for it).
    pub(in crate::renderer) fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<ReadPyramids> {
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
    pub(in crate::renderer) fn bytes(&self) -> u64 {
        self.buffer.size()
    }
}

impl CpuLate {
    /// After the frame's early half was submitted: reads every display's pyramids back
    /// (waiting for the GPU), culls each display's late phase (`late[i]`, its view) and
    /// its far layer (in `far`) against them on `culler`, and uploads both. Returns the
    /// bytes uploaded and the CPU time the culls took.
    pub(in crate::renderer) fn cull_late(
        &self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        culler: &mut Culler,
        (late, far): (&[Option<&ViewCull>], Option<&Far>),
    ) -> Result<FrameStats> {
        let Some(plan) = &self.plan else {
            return Ok(FrameStats::default());
        };
        let read = self.pyramids.read(device, queue)?;
        let start = Instant::now();
        let mut stats = FrameStats::default();
        for (i, pyramid) in read.iter().enumerate() {
            let Some((texels, shape)) = pyramid else {
                continue;
            };
            let far = far.and_then(|f| Some((f.displays[i].as_ref()?, plan.far[i]?)));
            let tested = far.map(|(layer, p)| layer.tested_context(&p, &plan.displays[i]));
            culler.cull_late((plan, i), (texels, *shape), tested.as_ref());
            let views = late[i]
                .into_iter()
                .chain(far.map(|(layer, _)| layer.view.view_cull()));
            stats.bytes_uploaded += views.map(|v| culler.upload(queue, v)).sum::<u64>();
        }
        stats.cpu_cull = start.elapsed();
        Ok(stats)
    }
}
