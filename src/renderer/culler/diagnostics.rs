//! What the culler reads back after a frame was submitted, for diagnostics and
//! `profile`: the floor kernel's and each view's cull time by the wall clock, the coarse
//! cull's candidates, the sphere tests.

use super::{CullPass, Culler, Kind};
use crate::cull::coarse::BLOCK;
use crate::error::Result;
use crate::profiling::percentile;
use crate::readback::{read_pod, wait_idle};
use crate::shaders::CullTests;

/// Wall-clock medians of culls submitted alone ([`Culler::time_against_floor`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WallCulls {
    /// The floor kernel's (with the rig cull, the rig's floor: one read per instance).
    pub floor_ms: f64,
    /// The frame's whole cull: the rig cull and every other view's.
    pub rig_ms: f64,
    /// Each view's cull alone.
    pub views_ms: Vec<f64>,
}

/// Diagnostics read back after a frame was submitted.
impl Culler {
    /// Wall-clock medians over `rounds` submissions each (submit, then wait) of the
    /// floor kernel alone, of each of `views`' culls alone (over the last frame's
    /// coarse lists, with the coarse cull; a rig member by its own three dispatches),
    /// and of the frame's whole cull of `views` (the rig cull's dispatches and every
    /// other view's), a round being one of each. `None` without the floor kernel (GPU
    /// culling with [`super::RendererOptions::cull_floor`]). For adapters whose in-pass
    /// timestamps do not bracket a compute pass's first dispatch (lavapipe): on a CPU
    /// device the wall clock is the cost. The culls rewrite the same outputs.
    pub fn time_against_floor(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        views: &[&CullPass],
        rounds: u32,
    ) -> Result<Option<WallCulls>> {
        let (
            Kind::Gpu {
                culler,
                scene,
                coarse,
                rig_groups,
                ..
            },
            Some(any),
        ) = (&self.kind, views.first())
        else {
            return Ok(None);
        };
        let Some(group) = any.bind_group.as_ref().filter(|_| culler.has_floor()) else {
            return Ok(None);
        };
        let rig = rig_groups.get().map_or(&[][..], Vec::as_slice);
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
        let encode_view = |pass: &mut wgpu::ComputePass, v: &CullPass, group| {
            let slot = super::over_candidates(coarse.as_ref(), v);
            culler.encode(pass, scene, group, (slot, v.phase));
        };
        // Rounds interleave the floor and every cull, so that each sees the host as the
        // others do (a 2-core VM's neighbours move a median by a third between seconds).
        let mut samples = vec![Vec::new(); 2 + groups.len()];
        for _ in 0..rounds.max(1) {
            samples[0].push(once(&|pass| {
                match rig.is_empty() {
                    true => culler.encode_floor(pass, scene, [group]),
                    false => culler.encode_floor(pass, scene, rig),
                };
            })?);
            samples[1].push(once(&|pass| {
                if let (Some(coarse), false) = (coarse, groups.is_empty()) {
                    culler.encode_frame(pass, scene, [group, &coarse.args]);
                }
                culler.encode_rig(pass, scene, (rig, false));
                culler.encode_rig(pass, scene, (rig, true));
                for (v, group) in groups.iter().filter(|(v, _)| v.member.is_none()) {
                    encode_view(pass, v, group);
                }
            })?);
            for ((v, group), s) in groups.iter().zip(&mut samples[2..]) {
                s.push(once(&|pass| encode_view(pass, v, group))?);
            }
        }
        let mut medians = samples.iter().map(|s| percentile(s, 0.5));
        Ok(Some(WallCulls {
            floor_ms: medians.next().unwrap_or_default(),
            rig_ms: medians.next().unwrap_or_default(),
            views_ms: medians.collect(),
        }))
    }

    /// The optional tests the GPU cull holds (`None` on the CPU).
    pub fn tests(&self) -> Option<CullTests> {
        match &self.kind {
            Kind::Gpu { culler, .. } => Some(culler.tests()),
            Kind::Cpu { .. } => None,
        }
    }

    /// The coarse cull's candidates per display (GPU culling with it on).
    pub fn read_candidates(
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
    pub fn read_sphere_tests(
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
