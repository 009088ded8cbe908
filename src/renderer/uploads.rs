//! The frame's pose as one upload: what `prepare` and `latch` write of the pose (the
//! frame and display contexts, the cull's members, block tests and hidden areas, the
//! lights' views) is gathered into one staging buffer, written with one call, and
//! copied into place by commands `encode` records before any pass. wgpu stages every
//! `write_buffer` call on its own (a dozen for a five-wall CAVE); one call is what
//! makes a latch cheap. With late latching ([`open`]) the staging is mapped memory the
//! latch writes in place, not wgpu's. The CPU culls' results are not the pose's: they
//! go straight.

mod open;

use std::cell::RefCell;

use crate::buffers::Upload;
use crate::error::{Error, Result};
use open::OpenRing;

/// Where a frame's writes go: the pose's coalesced, the CPU culls' results straight.
#[derive(Clone, Copy)]
pub struct Writes<'a> {
    /// The pose's writes.
    pub pose: &'a Coalesced,
    /// Everything else.
    pub queue: &'a wgpu::Queue,
}

/// One write into place: `size` bytes from `from` in the staging buffer to `at` in `to`.
#[derive(Clone, Debug, PartialEq)]
struct Entry {
    to: wgpu::Buffer,
    at: u64,
    from: u64,
    size: u64,
}

impl Entry {
    /// The same destination and size: a latch's write that an encode's copy carries.
    fn lands_as(&self, other: &Entry) -> bool {
        self.lands_at(&other.to, other.at, other.size)
    }

    fn lands_at(&self, to: &wgpu::Buffer, at: u64, size: u64) -> bool {
        (&self.to, self.at, self.size) == (to, at, size)
    }
}

/// The writes gathered since [`Coalesced::begin`].
#[derive(Default)]
struct Gathered {
    bytes: Vec<u8>,
    entries: Vec<Entry>,
    /// A latch's writes while each lands as the placed write of its order: counted, not
    /// listed (a listed write holds a clone of its buffer, whose count the latch would
    /// raise and drop on the submit's path). The first that does not lists them all.
    landed: Option<usize>,
}

impl Gathered {
    /// The writes as entries: those counted are the first placed ones.
    fn entries<'a>(&'a self, placed: &'a [Entry]) -> &'a [Entry] {
        match self.landed {
            Some(n) => &placed[..n],
            None => &self.entries,
        }
    }
}

/// The gathered writes, the staging buffer and what it holds.
pub struct Coalesced {
    device: wgpu::Device,
    gathered: RefCell<Gathered>,
    staging: Staging,
    /// The entries the staging buffer holds, in its order.
    placed: Vec<Entry>,
    /// Whether an encode recorded copies of `placed` since they were placed.
    recorded: bool,
    /// Where uniforms are laid out before they are gathered: one vector for the
    /// frame's dozen, not one each.
    scratch: RefCell<Vec<u8>>,
}

/// Where the placed writes wait for the encode's copies.
enum Staging {
    /// A buffer the queue writes (grown to hold them).
    Written(Option<wgpu::Buffer>),
    /// Late latching: mapped buffers written in place, closed by the latch.
    Open(OpenRing),
}

impl Upload for Coalesced {
    fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        let gathered = &mut *self.gathered.borrow_mut();
        let size = data.len() as u64;
        if let Some(n) = gathered.landed {
            // Landing as placed, the bytes gathered so far lie as the placed ones do.
            if (self.placed.get(n)).is_some_and(|p| p.lands_at(buffer, offset, size)) {
                gathered.landed = Some(n + 1);
                gathered.bytes.extend_from_slice(data);
                return;
            }
            gathered.entries = self.placed[..n].to_vec();
            gathered.landed = None;
        }
        gathered.entries.push(Entry {
            to: buffer.clone(),
            at: offset,
            from: gathered.bytes.len() as u64,
            size,
        });
        gathered.bytes.extend_from_slice(data);
    }

    fn write_uniform<T>(&self, buffer: &wgpu::Buffer, offset: u64, value: &T) -> u64
    where
        T: encase::ShaderType + encase::internal::WriteInto,
    {
        let mut scratch = self.scratch.borrow_mut();
        crate::records::uniform_bytes_into(value, &mut scratch);
        self.write_buffer(buffer, offset, &scratch);
        scratch.len() as u64
    }
}

impl Coalesced {
    /// Placed in a buffer the queue writes, or with `late_latch` in mapped ones.
    pub fn new(device: &wgpu::Device, late_latch: bool) -> Coalesced {
        Coalesced {
            device: device.clone(),
            gathered: RefCell::default(),
            staging: match late_latch {
                true => Staging::Open(OpenRing::new(device)),
                false => Staging::Written(None),
            },
            placed: Vec::new(),
            recorded: false,
            scratch: RefCell::default(),
        }
    }

    /// Forgets what was gathered: a plan's writes come next, placed anew when `fresh`
    /// (a prepare), else a latch's.
    pub fn begin(&self, fresh: bool) {
        let gathered = &mut *self.gathered.borrow_mut();
        gathered.bytes.clear();
        gathered.entries.clear();
        gathered.landed = (self.recorded && !fresh).then_some(0);
    }

    /// Sends what was gathered. A `latch` (not `fresh`) after an encode recorded its
    /// copies writes each write where its copy reads from, in one write when the writes
    /// are those the copies carry (the latch of the frame prepared); a write no copy
    /// carries goes straight. With late latching that closes the frame's staging
    /// ([`Coalesced::check_latch`]). Otherwise (a prepare) the writes are
    /// placed anew, for the next encode to copy.
    pub fn send(&mut self, queue: &wgpu::Queue, fresh: bool) -> Result<()> {
        let mut gathered = std::mem::take(self.gathered.get_mut());
        let sent = match self.recorded && !fresh {
            true => {
                self.resend(queue, &gathered);
                Ok(())
            }
            // Moved, not cloned: a latch's `begin` would drop the clones on the
            // submit's path.
            false => {
                let entries = std::mem::take(&mut gathered.entries);
                self.place(queue, &gathered.bytes, entries)
            }
        };
        *self.gathered.get_mut() = gathered;
        sent
    }

    /// Refuses a second latch of a frame with late latching: the first closed the
    /// staging the frame's copies read.
    pub fn check_latch(&self) -> Result<()> {
        match &self.staging {
            Staging::Open(ring) if self.recorded && !ring.is_open() => Err(Error::Unsupported(
                "with late latching a frame latches once: its latch closed the staging its copies read".into(),
            )),
            _ => Ok(()),
        }
    }

    fn resend(&mut self, queue: &wgpu::Queue, gathered: &Gathered) {
        let bytes = &gathered.bytes;
        if gathered.landed == Some(self.placed.len()) {
            self.write_staging(queue, 0, bytes);
        } else {
            let placed = std::mem::take(&mut self.placed);
            for e in gathered.entries(&placed) {
                let data = &bytes[e.from as usize..(e.from + e.size) as usize];
                match placed.iter().find(|p| p.lands_as(e)) {
                    Some(p) => self.write_staging(queue, p.from, data),
                    None => queue.write_buffer(&e.to, e.at, data),
                }
            }
            self.placed = placed;
        }
        if let Staging::Open(ring) = &mut self.staging {
            ring.close();
        }
    }

    /// Writes `bytes` into the staging buffer (grown or opened to hold them) for the
    /// next encode.
    fn place(&mut self, queue: &wgpu::Queue, bytes: &[u8], entries: Vec<Entry>) -> Result<()> {
        self.placed = entries;
        self.recorded = false;
        if bytes.is_empty() {
            return Ok(());
        }
        let size = bytes.len() as u64;
        match &mut self.staging {
            Staging::Open(ring) => ring.open(size)?,
            Staging::Written(staging) => {
                if staging.as_ref().is_none_or(|s| s.size() < size) {
                    *staging = Some(self.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("stereocull.pose_staging"),
                        size: size.next_power_of_two(),
                        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }));
                }
            }
        }
        self.write_staging(queue, 0, bytes);
        Ok(())
    }

    fn write_staging(&mut self, queue: &wgpu::Queue, at: u64, data: &[u8]) {
        match &mut self.staging {
            Staging::Open(ring) => ring.write(at, data),
            Staging::Written(Some(staging)) if !data.is_empty() => {
                queue.write_buffer(staging, at, data)
            }
            Staging::Written(_) => {}
        }
    }

    /// Records the copies of the placed writes into place: first in a frame, before
    /// any pass reads them.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let staging = match &self.staging {
            Staging::Open(ring) => ring.buffer(),
            Staging::Written(staging) => staging.as_ref(),
        };
        let Some(staging) = staging else {
            return;
        };
        for e in &self.placed {
            encoder.copy_buffer_to_buffer(staging, e.from, &e.to, e.at, e.size);
        }
        self.recorded = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::Gpu;

    fn target(gpu: &Gpu) -> wgpu::Buffer {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    fn bytes(seed: u8) -> Vec<u8> {
        (0..64u8)
            .map(|i| i.wrapping_mul(seed).wrapping_add(seed))
            .collect()
    }

    /// A prepare's writes placed and their copies recorded, then a latch's: written
    /// where the copies read when they land as the placed ones in order (counted), and
    /// also when one of them goes elsewhere (listed: the placed ones through the
    /// staging, the stray one straight), under both kinds of staging.
    #[test]
    fn a_latchs_writes_land_where_the_recorded_copies_read() {
        let gpu = Gpu::headless().unwrap();
        let read = |b: &wgpu::Buffer| {
            crate::readback::read_buffer(&gpu.device, &gpu.queue, b, 64).unwrap()
        };
        for late_latch in [false, true] {
            for stray in [false, true] {
                let mut uploads = Coalesced::new(&gpu.device, late_latch);
                let [a, b, c] = [(); 3].map(|_| target(&gpu));
                uploads.begin(true);
                uploads.write_buffer(&a, 0, &bytes(3));
                uploads.write_buffer(&b, 0, &bytes(5));
                uploads.send(&gpu.queue, true).unwrap();
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                uploads.record(&mut encoder);
                uploads.begin(false);
                uploads.write_buffer(&a, 0, &bytes(7));
                match stray {
                    true => uploads.write_buffer(&c, 0, &bytes(11)),
                    false => uploads.write_buffer(&b, 0, &bytes(13)),
                }
                let counted = uploads.gathered.borrow().landed;
                assert_eq!(counted, (!stray).then_some(2), "stray {stray}");
                uploads.send(&gpu.queue, false).unwrap();
                gpu.queue.submit([encoder.finish()]);
                let case = format!("late latch {late_latch}, stray {stray}");
                assert_eq!(read(&a), bytes(7), "{case}");
                match stray {
                    true => {
                        assert_eq!(read(&b), bytes(5), "{case}");
                        assert_eq!(read(&c), bytes(11), "{case}");
                    }
                    false => assert_eq!(read(&b), bytes(13), "{case}"),
                }
            }
        }
    }
}
