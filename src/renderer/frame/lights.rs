//! The frame's punctual lights on the GPU ([`crate::lights`]): their records, each
//! display's view of its clusters, and the clusters, cleared and built by one dispatch
//! for every display (`wgsl/light_clusters.wgsl`: a light an invocation, z the display),
//! both eyes at once, before any display draws. Without lights the buffers stay (group
//! 2 binds them) and nothing is recorded: the fragment stage sees a count of 0.

use crate::buffers::Upload;
use crate::buffers::init_buffer;
use crate::error::{Error, Result};
use crate::lights::{
    CLUSTER_Z, DISPLAY_WORDS, HEADER_WORDS, Light, LightRecord, MAX_LIGHTS, VIEW_WORDS, slice_start,
};
use crate::records::storage_bytes;
use crate::renderer::plan::FramePlan;
use crate::renderer::recorder::Recorder;
use crate::shaders::{
    LIGHT_CLUSTER_BINDINGS, Windows, bind_group, bind_group_layout, compute_pipeline,
    light_clusters_source,
};

const WORKGROUP: u32 = 64;

/// The lights' buffers and the cluster pass.
pub struct Lighting {
    pub lights: wgpu::Buffer,
    pub views: wgpu::Buffer,
    pub clusters: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    records: Vec<LightRecord>,
    /// The records changed since they were last written.
    dirty: bool,
    /// Posing on the GPU, the scene's lights and the animations that move some of
    /// them: posed at each frame's time here (until an engine sets lights itself).
    posed: Option<(crate::pose::Posing, Vec<Light>)>,
    displays: u32,
}

impl Lighting {
    /// The buffers for `displays` displays, holding `lights` (at most [`MAX_LIGHTS`]).
    pub fn new(device: &wgpu::Device, lights: &[Light], displays: u32) -> Result<Lighting> {
        let records = records(lights)?;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let room = vec![LightRecord::default(); MAX_LIGHTS];
        let lights = init_buffer(device, "stereocull.lights", &storage_bytes(&room), storage);
        let zeros = |words: u32| vec![0u32; words as usize];
        let views = init_buffer(
            device,
            "stereocull.light_views",
            bytemuck::cast_slice(&zeros(HEADER_WORDS + displays * VIEW_WORDS)),
            storage,
        );
        let clusters = init_buffer(
            device,
            "stereocull.light_clusters",
            bytemuck::cast_slice(&zeros(displays * DISPLAY_WORDS)),
            // COPY_SRC: read back by diagnostics.
            storage | wgpu::BufferUsages::COPY_SRC,
        );
        let whole = &Windows::WHOLE;
        let list = &LIGHT_CLUSTER_BINDINGS;
        let layout = bind_group_layout(device, "stereocull.light_clusters", list, whole);
        let bind_group = bind_group(
            device,
            "stereocull.light_clusters",
            &layout,
            list,
            whole,
            [&lights, &views, &clusters],
        );
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.light_clusters"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = compute_pipeline(
            device,
            "stereocull.light_clusters",
            &pipeline_layout,
            light_clusters_source(),
            "clusters",
        );
        // The buffers start zeroed: a count of 0 needs no write.
        let dirty = !records.is_empty();
        Ok(Lighting {
            lights,
            views,
            clusters,
            pipeline,
            bind_group,
            records,
            dirty,
            posed: None,
            displays,
        })
    }

    /// Replaces the lights from the next frame on (the engine's: animations no longer
    /// move them).
    pub fn set(&mut self, lights: &[Light]) -> Result<()> {
        self.records = records(lights)?;
        self.dirty = true;
        self.posed = None;
        Ok(())
    }

    /// Poses `lights` by `posing`'s animations at each frame's time (posing on the
    /// GPU, where nothing on the CPU poses the scene); nothing without lights on
    /// animated nodes.
    pub fn pose_with(&mut self, posing: &crate::pose::Posing, lights: &[Light]) {
        if !posing.lights.is_empty() {
            self.posed = Some((posing.clone(), lights.to_vec()));
        }
    }

    /// Writes the count, the slices' depths, the lights where they changed and each
    /// display's combined frustum (`plan`'s); returns the bytes. Nothing while there
    /// are no lights (the count stays 0).
    pub fn prepare(&mut self, queue: &impl Upload, plan: &FramePlan) -> u64 {
        if let Some((posing, lights)) = &mut self.posed {
            let worlds = posing.node_worlds(plan.frame.time);
            crate::pose::place_lights(&posing.lights, &worlds, lights);
            self.records = lights.iter().map(Light::record).collect();
            self.dirty = true;
        }
        if self.records.is_empty() && !self.dirty {
            return 0;
        }
        let mut header = vec![self.records.len() as u32];
        header.extend((0..=CLUSTER_Z).map(|k| slice_start(k).to_bits()));
        let mut bytes = write(queue, &self.views, 0, &header);
        for (i, d) in plan.displays.iter().map(|d| &d.context).enumerate() {
            let mut matrices = d.view_from_world.to_cols_array().to_vec();
            matrices.extend(d.clip_from_view.to_cols_array());
            let words: Vec<u32> = matrices.iter().map(|f| f.to_bits()).collect();
            let at = (HEADER_WORDS + i as u32 * VIEW_WORDS) as u64;
            bytes += write(queue, &self.views, at, &words);
        }
        if self.dirty {
            let data = storage_bytes(&self.records);
            queue.write_buffer(&self.lights, 0, &data);
            bytes += data.len() as u64;
            self.dirty = false;
        }
        bytes
    }

    /// Records the clusters of every display: cleared, then one dispatch (nothing
    /// without lights).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        if self.records.is_empty() {
            return 0;
        }
        encoder.clear_buffer(&self.clusters, 0, None);
        let (mut pass, open) = rec.frame_pass(encoder, "light_clusters");
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        let groups = (self.records.len() as u32).div_ceil(WORKGROUP);
        pass.dispatch_workgroups(groups, 1, self.displays);
        rec.close_frame_pass(encoder, pass, open);
        1
    }
}

fn write(queue: &impl Upload, buffer: &wgpu::Buffer, word: u64, words: &[u32]) -> u64 {
    let bytes: &[u8] = bytemuck::cast_slice(words);
    queue.write_buffer(buffer, 4 * word, bytes);
    bytes.len() as u64
}

/// The records of `lights`: an error past the budget or for a light that is not valid.
fn records(lights: &[Light]) -> Result<Vec<LightRecord>> {
    if lights.len() > MAX_LIGHTS {
        return Err(Error::InvalidScene(format!(
            "{} lights, past the budget of {MAX_LIGHTS} (lights::MAX_LIGHTS: a cluster keeps a bit per light)",
            lights.len()
        )));
    }
    (lights.iter().enumerate())
        .map(|(i, l)| {
            l.check()
                .map(|()| l.record())
                .map_err(|e| Error::InvalidScene(format!("light {i}: {e}")))
        })
        .collect()
}
