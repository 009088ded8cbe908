//! What the culler reads back after a frame was submitted, for diagnostics and
//! `profile`: the floor kernel's and each view's cull time by the wall clock, the coarse
//! cull's candidates, the sphere tests.

use super::{Culler, Kind, ViewCull};
use crate::cull::coarse::BLOCK;
use crate::error::Result;
use crate::profiling::percentile;
use crate::readback::{read_pod, wait_idle};

/// Diagnostics read back after a frame was submitted.
impl Culler {
    /// Wall-clock medians over `rounds` submissions each (submit, then wait) of the
    /// floor kernel alone and of each of `views`' culls alone (over the last frame's
    /// coarse lists, with the coarse cull), a round being one of each. `None` without
    /// the floor kernel (GPU culling with [`super::RendererOptions::cull_floor`]). For
    /// adapters whose in-pass timestamps do not bracket a compute pass's first dispatch
    /// (lavapipe): on a CPU device the wall clock is the cost. The culls rewrite the
    /// same outputs.
    pub(in crate::renderer) fn time_against_floor(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        views: &[&ViewCull],
        rounds: u32,
    ) -> Result<Option<(f64, Vec<f64>)>> {
        let (
            Kind::Gpu {
                culler,
                scene,
                coarse,
            },
            Some(any),
        ) = (&self.kind, views.first())
        else {
            return Ok(None);
        };
        let Some(group) = any.bind_group.as_ref().filter(|_| culler.has_floor()) else {
            return Ok(None);
        };
        let once = |record: &dyn Fn(&mut wgpu::ComputePass)| -> Result<f64> {
            let mut encoder = device.create_command_encoder(&Default::default());
            record(&mut encoder.begin_compute_pass(&Default::default()));
            let start = std::time::Instant::now();
            queue.submit([encoder.finish()]);
            wait_idle(device)?;
            Ok(start.elapsed().as_secs_f64() * 1e3)
        };
        let groups: Vec<_> = views
            .iter()
            .filter_map(|v| Some((v, v.bind_group.as_ref()?)))
            .collect();
        // Rounds interleave the floor and every cull, so that each sees the host as the
        // others do (a 2-core VM's neighbours move a median by a third between seconds).
        let mut samples = vec![Vec::new(); 1 + groups.len()];
        for _ in 0..rounds.max(1) {
            samples[0].push(once(&|pass| {
                culler.encode_floor(pass, scene, group);
            })?);
            for ((v, group), s) in groups.iter().zip(&mut samples[1..]) {
                let slot = coarse.as_ref().and(v.view.coarse_slot());
                let phased = (slot, v.phase);
                s.push(once(&|pass| culler.encode(pass, scene, group, phased))?);
            }
        }
        let mut medians = samples.iter().map(|s| percentile(s, 0.5));
        let floor = medians.next().unwrap_or_default();
        let culls = medians.collect();
        Ok(Some((floor, culls)))
    }

    /// The coarse cull's candidates per display (GPU culling with it on).
    pub(in crate::renderer) fn read_candidates(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        displays: usize,
    ) -> Result<Option<Vec<u32>>> {
        match &self.kind {
            Kind::Gpu {
                scene,
                coarse: Some(_),
                ..
            } => {
                let bytes = 4 * displays as u64;
                read_pod(device, queue, &scene.candidate_count, bytes).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// Sphere-against-frustum tests of the GPU cull (`None` on the CPU): every
    /// instance once per display, or with the coarse cull every instance once (for its
    /// block's sphere), every block once for the frame and once per display, and each
    /// display's candidates.
    pub(in crate::renderer) fn read_sphere_tests(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        displays: usize,
    ) -> Result<Option<u64>> {
        let Kind::Gpu { scene, .. } = &self.kind else {
            return Ok(None);
        };
        let (n, d) = (scene.instance_count as u64, displays as u64);
        let blocks = n.div_ceil(BLOCK as u64);
        Ok(Some(
            match self.read_candidates(device, queue, displays)? {
                Some(c) => n + blocks * (1 + d) + c.iter().map(|&c| c as u64).sum::<u64>(),
                None => d * n,
            },
        ))
    }
}
