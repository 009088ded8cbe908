//! Measurement: GPU timestamps around each pass, and the percentiles the reports use.

use crate::error::Result;
use crate::readback::read_buffer;

/// Timestamp pairs around passes, resolved once per frame. `None` from [`GpuTimer::new`]
/// when the device has no `TIMESTAMP_QUERY`: reports then say so instead of printing zeros.
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    capacity: u32,
    labels: Vec<&'static str>,
    /// Nanoseconds per timestamp tick.
    period: f32,
}

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
        })
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
    }

    /// Milliseconds per timed pass of the submitted frame, summed by label, and resets
    /// for the next frame.
    pub fn read(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<(&'static str, f64)>> {
        let used = 2 * self.labels.len() as u64;
        if used == 0 {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> =
            bytemuck::pod_collect_to_vec(&read_buffer(device, queue, &self.resolved, 8 * used)?);
        let mut totals: Vec<(&'static str, f64)> = Vec::new();
        for (label, pair) in self.labels.drain(..).zip(ticks.chunks_exact(2)) {
            let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period as f64 * 1e-6;
            match totals.iter_mut().find(|(l, _)| *l == label) {
                Some((_, t)) => *t += ms,
                None => totals.push((label, ms)),
            }
        }
        Ok(totals)
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
