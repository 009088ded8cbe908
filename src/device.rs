//! A headless device for the CLI, tests and benches. Embedders bring their own
//! `wgpu::Device` instead and never need this module.

use std::sync::{Arc, Mutex};

use wgpu::Features;

use crate::draw::DEPTH_FORMAT;
use crate::error::{Error, Result};

/// Optional features the pipeline uses when present, with what it does without them.
pub const OPTIONAL_FEATURES: [(Features, &str, &str); 11] = [
    (
        Features::MULTI_DRAW_INDIRECT_COUNT,
        "multi_draw_indirect_count",
        "fixed-count multi-draw over every mesh's draw, zeroed when culled: the GPU walks one draw per mesh each frame (same image)",
    ),
    (
        Features::INDIRECT_FIRST_INSTANCE,
        "indirect_first_instance",
        "instanced and multiview unavailable (they need per-mesh first_instance); the classic modes draw with one CPU call per instance",
    ),
    (
        Features::CLIP_DISTANCES,
        "clip_distances",
        "eyes kept in their half by a fragment discard: triangles crossing the seam are shaded, then discarded (same image)",
    ),
    (
        Features::MULTIVIEW,
        "multiview",
        "the multiview mode is unavailable (instanced draws both eyes anyway)",
    ),
    (
        Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
        "texture_adapter_specific_format_features",
        "MSAA at 1x and 4x only (WebGPU's guarantee), not the adapter's other counts",
    ),
    (
        Features::MULTISAMPLE_ARRAY,
        "multisample_array",
        "no MSAA in the multiview mode (it needs multisampled two-layer targets)",
    ),
    (
        Features::TIMESTAMP_QUERY,
        "timestamp_query",
        "CPU timings only",
    ),
    (
        Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        "timestamp_query_inside_encoders",
        "traces time each pass but not each display's whole scope",
    ),
    (
        Features::PIPELINE_STATISTICS_QUERY,
        "pipeline_statistics_query",
        "no vertex-invocation counts",
    ),
    (
        Features::TEXTURE_COMPRESSION_BC,
        "texture_compression_bc",
        "Basis Universal textures transcoded to RGBA8, four times the memory of BC7 (same image within the codec's error)",
    ),
    (
        Features::SUBGROUP,
        "subgroup",
        "the cull's workgroup scans go through workgroup memory alone (same buffers)",
    ),
];

/// The optional features ([`OPTIONAL_FEATURES`]) among `adapter`'s: what an embedder
/// opening its own device asks for, so that every path runs without a fallback it need
/// not take.
pub fn features_for(adapter: Features) -> Features {
    let optional = OPTIONAL_FEATURES
        .iter()
        .fold(Features::empty(), |all, (f, ..)| all | *f);
    adapter & optional
}

/// Sample counts WebGPU guarantees for rendering `color` with `depth` (what every
/// device has without `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`).
pub fn guaranteed_sample_counts(
    features: Features,
    color: wgpu::TextureFormat,
    depth: wgpu::TextureFormat,
) -> Vec<u32> {
    let flags = |f: wgpu::TextureFormat| f.guaranteed_format_features(features).flags;
    (flags(color) & flags(depth)).supported_sample_counts()
}

/// `1, 4`: counts for messages.
pub fn list_counts(counts: &[u32]) -> String {
    counts
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// How much of the stereo pipeline a device runs as designed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// Every drawing feature present: one indirect-count draw per display, hardware
    /// clip distances at the seam, multiview available.
    Full,
    /// The GPU-driven instanced path runs, with one or more fallbacks.
    GpuDriven,
    /// No first-instance in indirect draws: only the classic per-eye modes run.
    Classic,
}

impl Tier {
    /// The tier a device with `features` runs.
    pub fn of(features: Features) -> Tier {
        let drawing = Features::MULTI_DRAW_INDIRECT_COUNT
            | Features::INDIRECT_FIRST_INSTANCE
            | Features::CLIP_DISTANCES
            | Features::MULTIVIEW;
        if features.contains(drawing) {
            Tier::Full
        } else if features.contains(Features::INDIRECT_FIRST_INSTANCE) {
            Tier::GpuDriven
        } else {
            Tier::Classic
        }
    }

    /// How `info` names the tier.
    pub fn name(self) -> &'static str {
        match self {
            Tier::Full => "full (GPU-driven stereo, no fallbacks)",
            Tier::GpuDriven => "gpu-driven with fallbacks",
            Tier::Classic => "classic (per-eye modes only)",
        }
    }
}

/// The adapter, device and queue that the CLI and tests use.
pub struct Gpu {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device, with every optional feature the adapter has.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The instance's flags: whether wgpu validates indirect draws with an extra pass
    /// (`VALIDATION_INDIRECT_CALL`, on by default, off with
    /// `WGPU_VALIDATION_INDIRECT_CALL=0`) matters for GPU timings.
    pub flags: wgpu::InstanceFlags,
    /// Keeps the instance alive for [`Gpu::live_resources`].
    pub instance: wgpu::Instance,
    /// Set by the device-lost callback: why the device was lost.
    lost: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Picks an adapter (honouring `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`), preferring
    /// real GPUs over software ones, and opens a device with every optional feature the
    /// adapter has and the adapter's own limits (large scenes need large buffers).
    pub fn headless() -> Result<Gpu> {
        Self::headless_on(None, Features::all())
    }

    /// As [`Gpu::headless`], but never enables optional features outside `allowed`
    /// (to test the fallback tiers).
    pub fn headless_with(allowed: Features) -> Result<Gpu> {
        Self::headless_on(None, allowed)
    }

    /// As [`Gpu::headless_with`], on `backends` when given (else as `WGPU_BACKEND` says).
    pub fn headless_on(backends: Option<wgpu::Backends>, allowed: Features) -> Result<Gpu> {
        pollster::block_on(Self::headless_async(backends, allowed))
    }

    async fn headless_async(backends: Option<wgpu::Backends>, allowed: Features) -> Result<Gpu> {
        let (instance, adapter, flags) = find_adapter(backends).await?;
        let features = features_for(adapter.features()) & allowed;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("stereocull"),
                required_features: features,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await?;
        let info = adapter.get_info();
        log::info!(
            "adapter: {} ({:?}, {})",
            info.name,
            info.backend,
            info.driver
        );
        let lost = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut lost) = sink.lock() {
                *lost = Some(format!("{reason:?} {message}").trim_end().to_string());
            }
        });
        Ok(Gpu {
            adapter,
            device,
            queue,
            flags,
            instance,
            lost,
        })
    }

    /// Waits until the GPU has finished all submitted work, then [`Gpu::check_lost`]:
    /// what every CLI frame loop does at the end of a frame.
    pub fn wait(&self) -> Result<()> {
        crate::readback::wait_idle(&self.device)?;
        self.check_lost()
    }

    /// `Err(Error::DeviceLost)` once the device has been lost (wgpu reports it at the
    /// next poll): loops check it each frame so that a lost device ends the run with its
    /// reason instead of drawing nothing forever.
    pub fn check_lost(&self) -> Result<()> {
        // The poll's own result says nothing new: a lost device polls as empty.
        let _ = self.device.poll(wgpu::PollType::Poll);
        match self.lost.lock().ok().and_then(|l| l.clone()) {
            Some(reason) => Err(Error::DeviceLost(reason)),
            None => Ok(()),
        }
    }

    /// Live wgpu objects (buffers, textures, views, bind groups, query sets, command
    /// buffers) held by this instance: the soak test's measure of GPU allocations, which
    /// must not grow from frame to frame.
    pub fn live_resources(&self) -> Option<usize> {
        let hub = self.instance.generate_report()?.hub;
        let kept = [
            hub.buffers,
            hub.textures,
            hub.texture_views,
            hub.bind_groups,
            hub.query_sets,
            hub.command_buffers,
        ];
        Some(kept.iter().map(|r| r.num_allocated).sum())
    }

    /// MSAA sample counts this device can render `color_format` (with the renderer's own
    /// depth format) at: the
    /// adapter's when the device has `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`, else
    /// WebGPU's guarantee.
    pub fn sample_counts(&self, color_format: wgpu::TextureFormat) -> Vec<u32> {
        let features = self.device.features();
        if !features.contains(Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
            return guaranteed_sample_counts(features, color_format, DEPTH_FORMAT);
        }
        let flags = |f| self.adapter.get_texture_format_features(f).flags;
        (flags(color_format) & flags(DEPTH_FORMAT)).supported_sample_counts()
    }

    /// Whether wgpu validates indirect calls (which costs software adapters milliseconds).
    pub fn indirect_validation(&self) -> bool {
        self.flags
            .contains(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL)
    }

    /// One line naming the adapter, its backend and driver.
    pub fn adapter_line(&self) -> String {
        let i = self.adapter.get_info();
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        )
    }
}

/// `backends` or `WGPU_BACKEND` when set; otherwise the primary backends, then GL only if they have
/// no adapter (probing EGL is slow and noisy where Vulkan works).
async fn find_adapter(
    backends: Option<wgpu::Backends>,
) -> Result<(wgpu::Instance, wgpu::Adapter, wgpu::InstanceFlags)> {
    let from_env = backends.or_else(wgpu::Backends::from_env);
    let tries = match from_env {
        Some(b) => vec![b],
        None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::GL],
    };
    let mut last = None;
    for backends in tries {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.backends = backends;
        let flags = descriptor.flags;
        let instance = wgpu::Instance::new(descriptor);
        match choose_adapter(instance.enumerate_adapters(backends).await, backends) {
            Err(Error::NoAdapter { .. }) => last = Some(backends),
            other => return other.map(|a| (instance, a, flags)),
        }
    }
    Err(Error::NoAdapter {
        backends: format!("{:?}", last.unwrap_or(wgpu::Backends::all())),
    })
}

fn choose_adapter(adapters: Vec<wgpu::Adapter>, backends: wgpu::Backends) -> Result<wgpu::Adapter> {
    let names = || {
        adapters
            .iter()
            .map(|a| a.get_info().name)
            .collect::<Vec<_>>()
            .join(", ")
    };
    let wanted = std::env::var("WGPU_ADAPTER_NAME")
        .ok()
        .map(|s| s.to_lowercase());
    if let Some(wanted) = &wanted
        && !adapters
            .iter()
            .any(|a| a.get_info().name.to_lowercase().contains(wanted))
    {
        return Err(Error::AdapterNotFound {
            wanted: wanted.clone(),
            present: names(),
        });
    }
    let rank = |a: &wgpu::Adapter| {
        let info = a.get_info();
        let kind = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        (kind, info.backend != wgpu::Backend::Vulkan)
    };
    adapters
        .into_iter()
        .filter(|a| {
            wanted
                .as_ref()
                .is_none_or(|w| a.get_info().name.to_lowercase().contains(w))
        })
        .min_by_key(rank)
        .ok_or_else(|| Error::NoAdapter {
            backends: format!("{backends:?}"),
        })
}
