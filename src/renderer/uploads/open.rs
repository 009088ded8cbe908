//! Late latching's staging ([`crate::renderer::RendererOptions::late_latch`]): buffers
//! mapped for writing, which `prepare` and `latch` write in place and the latch closes
//! (unmaps) for the frame's copies to read. wgpu's `write_buffer` makes a staging
//! buffer for each call and copies into it; after a frame's passes those are cold
//! memory, and making and filling them was the largest part of a latch
//! (docs/performance.md, "Compositor outputs"). A buffer mapped before the pose is
//! sampled leaves the latch one copy into it.
//!
//! A closed buffer is mapped again at the next `open`, once the frame that reads it
//! was submitted; its map completes when the GPU is done with it (wgpu runs the map's
//! callback on a later submit or poll). Until then `open` makes another: the ring
//! grows to the frames in flight.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// The mapped buffers and the one open for this frame's writes.
pub(super) struct OpenRing {
    device: wgpu::Device,
    slots: Vec<Slot>,
    /// The slot this frame's writes went into, and its mapping while open.
    current: Option<(usize, Option<wgpu::BufferViewMut>)>,
}

struct Slot {
    buffer: wgpu::Buffer,
    /// Mapped and free: set by the map's callback.
    free: Arc<AtomicBool>,
    /// Closed by a latch and not yet asked to map again.
    closed: bool,
}

impl OpenRing {
    pub(super) fn new(device: &wgpu::Device) -> OpenRing {
        OpenRing {
            device: device.clone(),
            slots: Vec::new(),
            current: None,
        }
    }

    /// Opens a mapped buffer of at least `size` bytes for this frame's writes: the one
    /// open already where it is large enough, else a free one, else a new one. The
    /// buffers earlier frames closed are asked to map again first.
    pub(super) fn open(&mut self, size: u64) -> Result<()> {
        if let Some((at, Some(_))) = &self.current {
            if self.slots[*at].buffer.size() >= size {
                return Ok(());
            }
            self.close();
        }
        self.remap_closed();
        let at = match self.slots.iter().position(|s| s.takes(size)) {
            Some(at) => at,
            None => self.make(size),
        };
        self.slots[at].free.store(false, Ordering::Release);
        let view = (self.slots[at].buffer.get_mapped_range_mut(..))
            .map_err(|e| Error::Unsupported(format!("late latching's staging: {e}")))?;
        self.current = Some((at, Some(view)));
        Ok(())
    }

    /// The buffer this frame's writes went into (open or closed): what its copies read.
    pub(super) fn buffer(&self) -> Option<&wgpu::Buffer> {
        self.current.as_ref().map(|(at, _)| &self.slots[*at].buffer)
    }

    /// Whether the frame's buffer is still open for writes.
    pub(super) fn is_open(&self) -> bool {
        matches!(self.current, Some((_, Some(_))))
    }

    /// Writes `data` at `at` in the open buffer; nothing when none is open (the
    /// callers check [`OpenRing::is_open`]).
    pub(super) fn write(&mut self, at: u64, data: &[u8]) {
        if let Some((_, Some(view))) = &mut self.current {
            let at = at as usize;
            view.slice(at..at + data.len()).copy_from_slice(data);
        }
    }

    /// Closes the open buffer: once the frame is submitted its copies read it.
    pub(super) fn close(&mut self) {
        if let Some((at, view)) = &mut self.current
            && view.take().is_some()
        {
            self.slots[*at].buffer.unmap();
            self.slots[*at].closed = true;
        }
    }

    fn remap_closed(&mut self) {
        for slot in self.slots.iter_mut().filter(|s| s.closed) {
            slot.closed = false;
            let free = slot.free.clone();
            slot.buffer
                .map_async(wgpu::MapMode::Write, .., move |mapped| {
                    free.store(mapped.is_ok(), Ordering::Release);
                });
        }
    }

    fn make(&mut self, size: u64) -> usize {
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stereocull.pose_staging_open"),
            size: size.next_power_of_two().max(wgpu::MAP_ALIGNMENT),
            usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        });
        self.slots.push(Slot {
            buffer,
            free: Arc::default(),
            closed: false,
        });
        self.slots.len() - 1
    }
}

impl Slot {
    fn takes(&self, size: u64) -> bool {
        self.free.load(Ordering::Acquire) && self.buffer.size() >= size
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::Gpu;

    /// Frames that each open, fill, close and submit their staging, one after another:
    /// every frame's copy carries its own bytes, and the closed buffers are mapped
    /// again and reused, so the ring stays at the frames in flight.
    #[test]
    fn closed_buffers_are_mapped_again_and_reused() {
        let gpu = Gpu::headless().unwrap();
        let mut ring = OpenRing::new(&gpu.device);
        let into = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 256,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        for frame in 0..12u8 {
            let bytes: Vec<u8> = (0..200u32)
                .map(|i| (i as u8).wrapping_mul(frame + 3))
                .collect();
            ring.open(bytes.len() as u64).unwrap();
            assert!(ring.is_open());
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let staging = ring.buffer().unwrap();
            encoder.copy_buffer_to_buffer(staging, 0, &into, 0, bytes.len() as u64);
            ring.write(0, &bytes);
            ring.close();
            gpu.queue.submit([encoder.finish()]);
            let read = crate::readback::read_buffer(&gpu.device, &gpu.queue, &into, 200).unwrap();
            assert_eq!(&read[..bytes.len()], &bytes[..], "frame {frame}");
        }
        assert!(
            ring.slots.len() <= 2,
            "{} buffers for one frame in flight",
            ring.slots.len()
        );
    }
}
