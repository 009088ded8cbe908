//! Diagnostics: reading a submitted frame back ([`Renderer::diagnostics`]): each
//! display's cull buffers (and its far layer's), visible totals, the far/near split,
//! and what the coarse cull saved. None of it is needed to draw.

use super::display::Display;
use super::display::indirect::{Gpu, IndirectDisplay};
use super::{OcclusionCounts, Renderer, WallCulls};
use crate::cull::CullOutput;
use crate::error::Result;
use crate::keep::clear::TileGrid;
use crate::occlusion::PyramidShape;
use crate::readback::read_pod;
use crate::shaders::CullTests;

/// One display's far/near split in a frame ([`Diagnostics::far_split`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FarSplit {
    /// Meters from the display's apex beyond which whole instances are far.
    pub distance: f32,
    /// Visible instances drawn once into the far layer.
    pub far: u32,
    /// Visible instances drawn for both eyes.
    pub near: u32,
}

/// The last submitted frame as the GPU has it, read back (each call waits for the GPU):
/// for tests, statistics and tools, never needed to draw.
pub struct Diagnostics<'a> {
    renderer: &'a Renderer,
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
}

impl<'a> Diagnostics<'a> {
    pub(super) fn new(
        renderer: &'a Renderer,
        device: &'a wgpu::Device,
        queue: &'a wgpu::Queue,
    ) -> Diagnostics<'a> {
        Diagnostics {
            renderer,
            device,
            queue,
        }
    }
}

impl Diagnostics<'_> {
    /// The coarse cull's candidates in the last frame per display, read back after it
    /// was submitted (GPU culling with the coarse cull; `None` otherwise): the cull
    /// positions of the blocks listed for each display, all its cull tested.
    pub fn candidates(&self) -> Result<Option<Vec<u32>>> {
        let (culler, displays) = self.culler();
        culler.read_candidates(self.device, self.queue, displays)
    }

    /// Sphere-against-frustum tests of the last frame with GPU culling (read back after
    /// it was submitted; `None` otherwise): every instance once per display, or with the
    /// coarse cull every instance once (for its block's sphere), every block once for
    /// the frame and once per display, and each display's candidates.
    pub fn sphere_tests(&self) -> Result<Option<u64>> {
        let (culler, displays) = self.culler();
        culler.read_sphere_tests(self.device, self.queue, displays)
    }

    /// The optional tests the GPU cull's pipelines hold ([`CullTests`]: those a frame
    /// of this renderer can use, the rest compiled out); `None` on the CPU.
    pub fn cull_tests(&self) -> Option<CullTests> {
        self.culler().0.tests()
    }

    /// Display `index`'s changed tiles in the last frame, a bit each (row-major over its
    /// target, [`crate::cull::tiles::TileMask::words`]), as its draw pass cleared them
    /// (whether the CPU or the GPU marked them); `None` where it was drawn whole or on a
    /// classic path.
    pub fn changed_tiles(&self, index: usize) -> Result<Option<Vec<u32>>> {
        Ok(self.changed_tiles_in_grid(index)?.map(|(words, _)| words))
    }

    fn changed_tiles_in_grid(&self, index: usize) -> Result<Option<(Vec<u32>, TileGrid)>> {
        match self.indirect(index) {
            Some(d) => d.read_changed_tiles(self.gpu(), self.renderer.shared.keep()),
            None => Ok(None),
        }
    }

    /// Display `index` on the GPU-driven path (`None` past the displays or in a classic
    /// mode).
    fn indirect(&self, index: usize) -> Option<&IndirectDisplay> {
        self.renderer.displays.get(index)?.indirect()
    }

    /// The frame's culler, and how many displays it culls for.
    fn culler(&self) -> (&super::culler::Culler, usize) {
        (&self.renderer.shared.culler, self.renderer.displays.len())
    }

    fn gpu(&self) -> Gpu<'_> {
        (self.device, self.queue)
    }

    /// Pixels the last frame's displays redrew: a kept display's changed tiles (those
    /// at its target's edges clipped to it), every view of a display drawn whole.
    pub fn pixels_redrawn(&self) -> Result<u64> {
        let mut pixels = 0;
        for (i, shape) in self
            .renderer
            .displays
            .iter()
            .map(Display::shape)
            .enumerate()
        {
            pixels += match self.changed_tiles_in_grid(i)? {
                Some((words, grid)) => grid.pixels(&words),
                None => (shape
                    .layout
                    .viewports
                    .iter()
                    .take(shape.layout.views as usize))
                .map(|v| u64::from(v[2]) * u64::from(v[3]))
                .sum(),
            };
        }
        Ok(pixels)
    }

    /// Tiles the last frame's displays redrew (0 where all were drawn whole).
    pub fn tiles_changed(&self) -> Result<u32> {
        let mut count = 0;
        for i in 0..self.renderer.displays.len() {
            let words = self.changed_tiles(i)?.unwrap_or_default();
            count += words.iter().map(|w| w.count_ones()).sum::<u32>();
        }
        Ok(count)
    }

    /// Display `index`'s cull result of the last frame: on the indirect path its buffers
    /// read back (after the frame was submitted: the visible list up to the visible
    /// total, all draws, the draw count); in the classic modes the CPU cull they drew
    /// from (multi-camera: the left eye's).
    pub fn cull(&self, index: usize) -> Result<CullOutput> {
        let culler = &self.renderer.shared.culler;
        self.renderer.display(index)?.read_cull(self.gpu(), culler)
    }

    /// Display `index`'s far layer cull of the last frame (the far instances, each drawn
    /// once; the contract's buffers with V = 1), read back after it was submitted;
    /// `None` for a display without a far layer.
    pub fn far_cull(&self, index: usize) -> Result<Option<CullOutput>> {
        match self.indirect(index) {
            Some(d) => d.read_far_cull(self.gpu(), &self.renderer.shared.culler),
            None => Ok(None),
        }
    }

    /// Display `index`'s inset cull of the last frame (a foveated display's inset pair,
    /// with [`super::RendererOptions::inset_cull`]; the contract's buffers with V = 2),
    /// read back after it was submitted; `None` for a display without one.
    pub fn inset_cull(&self, index: usize) -> Result<Option<CullOutput>> {
        match self.indirect(index) {
            Some(d) => d.read_inset_cull(self.gpu(), &self.renderer.shared.culler),
            None => Ok(None),
        }
    }

    /// Display `index`'s late occlusion phase of the last frame (what its early phase
    /// did not draw and its pyramids do not hide; the contract's buffers), read back
    /// after it was submitted; `None` for a display without occlusion.
    pub fn late_cull(&self, index: usize) -> Result<Option<CullOutput>> {
        match self.indirect(index) {
            Some(d) => d.read_late_cull(self.gpu(), &self.renderer.shared.culler),
            None => Ok(None),
        }
    }

    /// Per display, what its two occlusion phases drew in the last frame (read back
    /// from their counts buffers); `None` for a display without occlusion.
    pub fn occlusion_counts(&self) -> Result<Vec<Option<OcclusionCounts>>> {
        (self.renderer.displays.iter())
            .map(|d| match d.indirect() {
                Some(d) => d.read_occlusion_counts(self.gpu()),
                None => Ok(None),
            })
            .collect()
    }

    /// Display `index`'s occlusion state after the last frame: its pyramids' shape and
    /// its visibility words (one per span of [`crate::shaders::SPAN`] places, bit `k %
    /// SPAN` of word `k / SPAN` set where the late phase found place `k` not hidden),
    /// read back; `None` for a display without occlusion.
    pub fn visibility(&self, index: usize) -> Result<Option<(PyramidShape, Vec<u32>)>> {
        let Some(shape) = self.pyramid_shape(index) else {
            return Ok(None);
        };
        let culler = &self.renderer.shared.culler;
        let words = culler.read_visibility(self.device, self.queue, index)?;
        Ok(words.map(|words| (shape, words)))
    }

    /// Display `index`'s pyramids' shape (`None` without occlusion).
    fn pyramid_shape(&self, index: usize) -> Option<PyramidShape> {
        self.indirect(index)?.pyramid_shape()
    }

    /// The depth pyramids display `index` built in the last frame, read back; `None`
    /// for a display without occlusion.
    pub fn pyramid(&self, index: usize) -> Result<Option<Vec<f32>>> {
        match self.pyramid_shape(index) {
            Some(shape) => {
                (self.renderer.shared.culler).read_pyramid(self.device, self.queue, index, shape)
            }
            None => Ok(None),
        }
    }

    /// The last frame's far/near split per display (`None` for displays without a far
    /// layer): the far distance and the visible far and near instances, read back.
    pub fn far_split(&self) -> Result<Vec<Option<FarSplit>>> {
        let culler = &self.renderer.shared.culler;
        (self.renderer.displays.iter())
            .map(|d| {
                let Some(d) = d.indirect() else {
                    return Ok(None);
                };
                let (near, far) = (
                    d.visible_count(self.gpu())?,
                    d.read_far_cull(self.gpu(), culler)?,
                );
                Ok(d.far_distance().zip(far).map(|(distance, far)| FarSplit {
                    distance,
                    far: far.visible.len() as u32,
                    near,
                }))
            })
            .collect()
    }

    /// The floor kernel's, the frame's whole cull's and each display's GPU cull's
    /// wall-clock milliseconds, medians over `rounds` submissions each, submitted and
    /// waited for alone (made with [`super::RendererOptions::cull_floor`] on the indirect
    /// path; `None` otherwise). Where timestamps are unreliable (lavapipe), this is the
    /// cost; on a GPU it adds a submission's latency to each.
    pub fn cull_against_floor(&self, rounds: u32) -> Result<Option<WallCulls>> {
        let views: Vec<_> = (self.renderer.displays.iter())
            .filter_map(|d| Some(d.indirect()?.cull_pass()))
            .collect();
        if views.is_empty() {
            return Ok(None);
        }
        let culler = &self.renderer.shared.culler;
        culler.time_against_floor(self.device, self.queue, &views, rounds)
    }

    /// The scene's vertices as the frame drew them: skinned meshes as the skinning
    /// pass posed them (in their instances' local space), the rest as uploaded.
    pub fn vertices(&self) -> Result<Vec<crate::scene::Vertex>> {
        let buffer = &self.renderer.shared.draw_scene.vertices;
        read_pod(self.device, self.queue, buffer, buffer.size())
    }

    /// The clusters buffer as the frame left it ([`crate::lights`]): per display its
    /// clusters' records ([`crate::lights::cluster_bits`]).
    pub fn light_clusters(&self) -> Result<Vec<u32>> {
        let buffer = &self.renderer.frame.lighting().clusters;
        read_pod(self.device, self.queue, buffer, buffer.size())
    }

    /// The light cluster pass of the last prepared frame (its clear and dispatch)
    /// submitted alone `rounds` times, each waited for: the median wall time in
    /// milliseconds (0 without lights).
    pub fn light_clusters_wall_ms(&self, rounds: u32) -> Result<f64> {
        let mut times: Vec<f64> = (0..rounds.max(1))
            .map(|_| {
                let mut encoder = self.device.create_command_encoder(&Default::default());
                let mut rec = super::recorder::Recorder::new(None, Vec::new());
                self.renderer
                    .frame
                    .lighting()
                    .encode(&mut encoder, &mut rec);
                let start = std::time::Instant::now();
                self.queue.submit([encoder.finish()]);
                crate::readback::wait_idle(self.device)?;
                Ok(start.elapsed().as_secs_f64() * 1e3)
            })
            .collect::<Result<_>>()?;
        times.sort_by(f64::total_cmp);
        Ok(times[times.len() / 2])
    }

    /// Every slot's instance record as the frame drew it (a posed instance's
    /// transform as the pose pass wrote it, with GPU posing).
    pub fn instance_records(&self) -> Result<Vec<crate::records::InstanceRecord>> {
        let buffer = &self.renderer.shared.draw_scene.instances;
        let mut records: Vec<crate::records::InstanceRecord> =
            read_pod(self.device, self.queue, buffer, buffer.size())?;
        records.truncate(self.renderer.slots as usize);
        Ok(records)
    }

    /// Every slot's world sphere as the GPU cull tested it (GPU culling; `None`
    /// otherwise): with GPU posing, what the pose pass wrote.
    pub fn spheres(&self) -> Result<Option<Vec<[f32; 4]>>> {
        let (culler, _) = self.culler();
        culler.read_spheres(self.device, self.queue, self.renderer.slots)
    }

    /// The joint matrices the frame's skinning pass applied (`None` without skins).
    pub fn joint_matrices(&self) -> Result<Option<Vec<crate::skin::JointMatrix>>> {
        let Some(skin) = &self.renderer.frame.passes.skin else {
            return Ok(None);
        };
        let buffer = skin.joint_matrices();
        read_pod(self.device, self.queue, buffer, buffer.size()).map(Some)
    }

    /// Visible totals of every display: read back from the counts buffers on the
    /// indirect path (with occlusion both phases': what the display drew), taken from
    /// this frame's CPU culls in the classic modes.
    pub fn visible_counts(&self) -> Result<Vec<u32>> {
        let culler = &self.renderer.shared.culler;
        (self.renderer.displays.iter())
            .map(|d| d.visible_count(self.gpu(), culler))
            .collect()
    }
}
