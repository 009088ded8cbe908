//! Measurement: GPU timestamps around each pass, pipeline statistics over the draw
//! passes, and the percentiles the reports use.

use crate::error::Result;
use crate::readback::read_pod;

/// Timestamp pairs around passes, resolved once per frame. `None` from [`GpuTimer::new`]
/// when the device has no `TIMESTAMP_QUERY`: reports then say so instead of printing zeros.
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    capacity: u32,
    labels: Vec<&'static str>,
    /// Nanoseconds per timestamp tick.
    period: f32,
    /// Vertex-shader invocations and clipper primitives per draw pass, where the
    /// device has `PIPELINE_STATISTICS_QUERY`.
    statistics: Option<Statistics>,
}

struct Statistics {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    used: u32,
}

/// What the GPU reported for one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameQueries {
    /// Milliseconds per pass label (`cull`, `draw`), summed over displays.
    pub passes: Vec<(&'static str, f64)>,
    /// Summed over the draw passes; `None` without pipeline statistics.
    pub vertex_invocations: Option<u64>,
    pub clipper_primitives: Option<u64>,
}

/// The statistics gathered, in the order the query results list them.
const STATISTICS: wgpu::PipelineStatisticsTypes =
    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_PRIMITIVES_OUT);

impl GpuTimer {
    /// Room for `passes` timed passes per frame.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, passes: u32) -> Option<GpuTimer> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let capacity = 2 * passes;
        Some(GpuTimer {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stereocull.timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: capacity,
            }),
            resolved: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("stereocull.timestamps"),
                size: 8 * capacity as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            capacity,
            labels: Vec::new(),
            period: queue.get_timestamp_period(),
            statistics: device
                .features()
                .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
                .then(|| Statistics {
                    queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                        label: Some("stereocull.pipeline_statistics"),
                        ty: wgpu::QueryType::PipelineStatistics(STATISTICS),
                        count: passes,
                    }),
                    resolved: device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("stereocull.pipeline_statistics"),
                        size: 16 * passes as u64,
                        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                        mapped_at_creation: false,
                    }),
                    used: 0,
                }),
        })
    }

    /// Starts counting vertex invocations and clipped primitives in `pass`; returns
    /// whether it did (then [`GpuTimer::end_statistics`] must follow in the same pass).
    pub fn begin_statistics(&mut self, pass: &mut wgpu::RenderPass) -> bool {
        match self.statistics.as_mut() {
            Some(s) if s.used < self.capacity / 2 => {
                pass.begin_pipeline_statistics_query(&s.queries, s.used);
                s.used += 1;
                true
            }
            _ => false,
        }
    }

    pub fn end_statistics(pass: &mut wgpu::RenderPass, begun: bool) {
        if begun {
            pass.end_pipeline_statistics_query();
        }
    }

    /// The next pair of query indices, or `None` once the frame's capacity is used.
    fn next(&mut self, label: &'static str) -> Option<(u32, u32)> {
        let first = 2 * self.labels.len() as u32;
        (first + 1 < self.capacity).then(|| {
            self.labels.push(label);
            (first, first + 1)
        })
    }

    pub fn compute(&mut self, label: &'static str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (begin, end) = self.next(label)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    pub fn render(&mut self, label: &'static str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (begin, end) = self.next(label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    /// Records the resolve of this frame's queries; call once, after the last pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let used = 2 * self.labels.len() as u32;
        if used > 0 {
            encoder.resolve_query_set(&self.queries, 0..used, &self.resolved, 0);
        }
        if let Some(s) = self.statistics.as_ref().filter(|s| s.used > 0) {
            encoder.resolve_query_set(&s.queries, 0..s.used, &s.resolved, 0);
        }
    }

    /// The submitted frame's pass times (summed by label) and statistics; resets for the
    /// next frame.
    pub fn read(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<FrameQueries> {
        let mut frame = FrameQueries::default();
        let used = 2 * self.labels.len() as u64;
        if used > 0 {
            let ticks: Vec<u64> = read_pod(device, queue, &self.resolved, 8 * used)?;
            for (label, pair) in self.labels.drain(..).zip(ticks.chunks_exact(2)) {
                let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period as f64 * 1e-6;
                match frame.passes.iter_mut().find(|(l, _)| *l == label) {
                    Some((_, t)) => *t += ms,
                    None => frame.passes.push((label, ms)),
                }
            }
        }
        if let Some(s) = self.statistics.as_mut() {
            let counts: Vec<u64> = match s.used {
                0 => Vec::new(),
                n => read_pod(device, queue, &s.resolved, 16 * n as u64)?,
            };
            frame.vertex_invocations = Some(counts.iter().step_by(2).sum());
            frame.clipper_primitives = Some(counts.iter().skip(1).step_by(2).sum());
            s.used = 0;
        }
        Ok(frame)
    }
}

/// Nearest-rank percentile of unsorted samples (`q` in 0..=1); 0 for no samples.
pub fn percentile(samples: &[f64], q: f64) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}
