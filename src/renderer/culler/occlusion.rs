//! The culler's side of occlusion: where each display's late cull reads its pyramids
//! (the GPU culler's occlusion buffer, or, culling on the CPU, a buffer they are
//! reduced into and read back between a frame's two halves), and the CPU culler's
//! visibility words, late phases and far layers' tested culls against those read-back
//! pyramids. The pyramids, not the depth, come back: a third of the bytes, and the
//! reduction reads multisampled and layered depth, which a copy cannot
//! (`tests/occlusion.rs` holds the GPU's reduction to the CPU twin's).

use std::time::Instant;

use super::{CullPass, Culler, Kind, set_output};
use crate::error::Result;
use crate::occlusion::{self, PyramidShape};
use crate::readback::read_pod;
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::plan::{CullView, FramePlan};
use crate::shaders::SPAN;

/// Per display, its pyramids read back and their shape (`None` without occlusion).
pub type ReadPyramids = Vec<Option<(Vec<f32>, PyramidShape)>>;

/// Per display, the views its late half uploads: the late phase's and the far layer's.
pub type LateViews<'a> = (Option<&'a CullPass>, Option<&'a CullPass>);

/// Culling on the CPU with occlusion: every occluding display's pyramids in one buffer,
/// each at its own offset (as the GPU culler keeps them in its occlusion buffer), read
/// back once all are built, and the plan of the frame whose late culls they serve.
pub(super) struct LateReadback {
    buffer: wgpu::Buffer,
    /// Per display: where its pyramids start (bytes) and their shape.
    regions: Vec<Option<(u64, PyramidShape)>>,
    plan: Option<FramePlan>,
}

impl LateReadback {
    fn new(device: &wgpu::Device, shapes: &[Option<PyramidShape>]) -> LateReadback {
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
        LateReadback {
            buffer,
            regions,
            plan: None,
        }
    }

    /// Every display's pyramids as the last submitted frame built them (waits for it).
    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<ReadPyramids> {
        let all: Vec<f32> = read_pod(device, queue, &self.buffer, self.buffer.size())?;
        Ok((self.regions.iter())
            .map(|r| {
                let (at, shape) = (*r)?;
                let start = at as usize / 4;
                Some((all[start..start + shape.len() as usize].to_vec(), shape))
            })
            .collect())
    }
}

impl Culler {
    /// Culling by occlusion on the displays with a pyramid shape in `shapes`: culling on
    /// the CPU, keeps their visibility words (every place starts as not drawn) and room
    /// to read their pyramids back; the GPU culler keeps its own words.
    pub fn track_visibility(&mut self, device: &wgpu::Device, shapes: &[Option<PyramidShape>]) {
        if let Kind::Cpu {
            layout,
            visibility,
            late,
            ..
        } = &mut self.kind
        {
            let words = layout.spheres.len().div_ceil(SPAN as usize);
            *visibility = (shapes.iter()).map(|s| s.map(|_| vec![0; words])).collect();
            *late = shapes
                .iter()
                .any(Option::is_some)
                .then(|| Box::new(LateReadback::new(device, shapes)));
        }
    }

    /// Whether a frame needs its pyramids on the CPU before its late phase: CPU culling
    /// with occlusion.
    pub fn reads_back(&self) -> bool {
        matches!(&self.kind, Kind::Cpu { late: Some(_), .. })
    }

    /// Keeps `plan` for the frame's late culls where they run on the CPU; else gives it
    /// back.
    pub fn keep_for_late(&mut self, plan: FramePlan) -> Option<FramePlan> {
        match &mut self.kind {
            Kind::Cpu { late: Some(l), .. } => {
                l.plan = Some(plan);
                None
            }
            _ => Some(plan),
        }
    }

    /// Where display `i`'s pyramids are reduced into, and from where its late cull
    /// reads them: the buffer and the offset (bytes).
    pub fn pyramid_texels(&self, i: usize) -> Option<(&wgpu::Buffer, u64)> {
        match &self.kind {
            Kind::Gpu { scene, .. } => Some((scene.occlusion(), scene.pyramid_offset(i))),
            Kind::Cpu { late, .. } => {
                let l = late.as_ref()?;
                let (at, _) = (*l.regions.get(i)?)?;
                Some((&l.buffer, at))
            }
        }
    }

    /// Display `i`'s visibility words after the last frame: the CPU's, or the GPU's
    /// read back (`None` for a display without occlusion).
    pub fn read_visibility(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        i: usize,
    ) -> Result<Option<Vec<u32>>> {
        match &self.kind {
            Kind::Cpu { visibility, .. } => Ok(visibility.get(i).cloned().flatten()),
            Kind::Gpu { scene, .. } => {
                let (words, slots) = scene.visibility_shape();
                if i as u32 >= slots {
                    return Ok(None);
                }
                let bytes = 4 * words as u64 * (i as u64 + 1);
                let all: Vec<u32> = read_pod(device, queue, scene.occlusion(), bytes)?;
                Ok(Some(all[i * words as usize..].to_vec()))
            }
        }
    }

    /// Display `i`'s pyramids (of `shape`) as the last frame built them, read back.
    pub fn read_pyramid(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        i: usize,
        shape: PyramidShape,
    ) -> Result<Option<Vec<f32>>> {
        match &self.kind {
            Kind::Cpu { late: Some(l), .. } => {
                let read = l.read(device, queue)?;
                Ok(read.into_iter().nth(i).flatten().map(|(texels, _)| texels))
            }
            Kind::Gpu { scene, .. } => {
                let offset = scene.pyramid_offset(i);
                let bytes = offset + 4 * shape.len() as u64;
                let all: Vec<f32> = read_pod(device, queue, scene.occlusion(), bytes)?;
                Ok(Some(all[offset as usize / 4..].to_vec()))
            }
            Kind::Cpu { late: None, .. } => Ok(None),
        }
    }

    /// GPU bytes occlusion adds to the culler: per display, its visibility words (on
    /// the GPU; the CPU keeps its own), and once the pyramids' room (the occlusion
    /// buffer's regions, or the read-back buffer).
    pub fn occlusion_bytes(&self) -> (u64, u64) {
        match &self.kind {
            Kind::Gpu { scene, .. } => (4 * scene.visibility_words() as u64, scene.pyramid_bytes()),
            Kind::Cpu { late, .. } => (0, late.as_ref().map_or(0, |l| l.buffer.size())),
        }
    }

    /// Culling on the CPU with occlusion, after the frame's early half was submitted:
    /// reads every display's pyramids back (waiting for the GPU), culls each display's
    /// late phase and far layer against them (rewriting its visibility words), and
    /// uploads both into `views` (per display). Returns the bytes uploaded and the CPU
    /// time the culls took; nothing on the GPU.
    pub fn cull_late(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        views: &[LateViews],
    ) -> Result<FrameStats> {
        let Kind::Cpu {
            layout,
            outputs,
            visibility,
            late: Some(late),
        } = &mut self.kind
        else {
            return Ok(FrameStats::default());
        };
        let Some(plan) = &late.plan else {
            return Ok(FrameStats::default());
        };
        let read = late.read(device, queue)?;
        let start = Instant::now();
        let lod = &plan.cull.lod;
        for (i, (pyramid, words)) in read.iter().zip(visibility.iter_mut()).enumerate() {
            let (Some((texels, shape)), Some(words), Some(job)) =
                (pyramid, words, plan.job(CullView::Display(i)))
            else {
                continue;
            };
            let pyramid = (&texels[..], *shape);
            let display = (&job, &plan.displays[i].context);
            let (culled, seen) = occlusion::cull_late(layout, display, lod, words, pyramid);
            *words = seen;
            set_output(outputs, CullView::Late(i), culled);
            let d = &plan.displays[i];
            if let (Some(far), Some(far_job)) = (d.far, d.far_cull(i)) {
                let (far_job, tested) = (far_job.job, far.tested_context(&d.context));
                let kept = occlusion::cull_tested(layout, (&far_job, &tested), lod, pyramid);
                set_output(outputs, CullView::Far(i), kept);
            }
        }
        let uploads = (views.iter()).flat_map(|(late, far)| late.iter().chain(far));
        let bytes_uploaded = uploads.map(|v| self.upload(queue, v)).sum();
        Ok(FrameStats {
            bytes_uploaded,
            cpu_cull: start.elapsed(),
            ..FrameStats::default()
        })
    }
}
