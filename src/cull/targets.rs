//! One view's cull outputs (per the cull contract), which its draw pass consumes: the
//! visible list, the packed draws and the counts, in buffers of the view's own or in
//! its ranges of buffers the rig cull's members share.

use crate::bins::MAX_BINS;
use crate::buffers::storage_buffer;
use crate::cull::CullOutput;
use crate::cull::rig::MemberAt;
use crate::records::DrawArgs;

/// Bytes of the counts buffer: the draw count, the visible total, then each material
/// bin's draw count ([`COUNTS_BIN_OFFSET`] on).
pub const COUNTS_BYTES: u64 = COUNTS_BIN_OFFSET + 4 * MAX_BINS as u64;

/// Where the counts buffer's per-bin draw counts start, in bytes.
pub const COUNTS_BIN_OFFSET: u64 = 8;

/// One view's cull outputs: what its draw pass consumes. A view with buffers of its own
/// has its ranges at 0; a member of the rig cull has its ranges of buffers the rig's
/// members share ([`CullTargets::bank`]), which one set of dispatches writes.
#[derive(Clone)]
pub struct CullTargets {
    /// The visible ids, per the cull contract, from [`CullTargets::visible_at`].
    pub visible: wgpu::Buffer,
    /// The packed draws (meshes times levels entries), for the multi-draw, from
    /// [`CullTargets::draws_at`].
    pub draws: wgpu::Buffer,
    /// [`COUNTS_BYTES`] from [`CullTargets::counts_at`]: the draw count (what
    /// `multi_draw_indexed_indirect_count` reads), then the visible total (for
    /// statistics without reading `visible`), then each bin's draw count.
    pub counts: wgpu::Buffer,
    /// Where the view's visible list starts in `visible`, in bytes.
    pub visible_at: u64,
    /// Where its draws start in `draws`, in bytes.
    pub draws_at: u64,
    /// Where its counts start in `counts`, in bytes.
    pub counts_at: u64,
    /// Bytes of its visible list and of its draws.
    sizes: (u64, u64),
}

impl CullTargets {
    /// Sized for every instance visible and `draws` draws (meshes times levels).
    pub fn new(device: &wgpu::Device, instance_count: u32, draws: u32) -> CullTargets {
        CullTargets::bank(device, instance_count, draws, 1).remove(0)
    }

    /// `members` views' outputs in one set of buffers, each sized as
    /// [`CullTargets::new`] and starting where a storage binding may (the draw pass
    /// binds a view's visible list, a view's own cull its three ranges); each draws
    /// range also starts on a whole draw.
    pub fn bank(
        device: &wgpu::Device,
        instance_count: u32,
        draws: u32,
        members: u32,
    ) -> Vec<CullTargets> {
        let align = device.limits().min_storage_buffer_offset_alignment as u64;
        let draw = size_of::<DrawArgs>() as u64;
        let sizes = (4 * instance_count as u64, draw * draws as u64);
        // A multiple of both the alignment and a draw's bytes.
        let draw_align = align / gcd(align, draw) * draw;
        let strides = [
            sizes.0.next_multiple_of(align).max(align),
            sizes.1.next_multiple_of(draw_align).max(draw_align),
            COUNTS_BYTES.next_multiple_of(align),
        ];
        let out = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let indirect = out | wgpu::BufferUsages::INDIRECT;
        let n = members.max(1) as u64;
        let [visible, draws_buffer, counts] = [
            ("stereocull.visible", strides[0], out),
            ("stereocull.draws", strides[1], indirect),
            ("stereocull.counts", strides[2], indirect),
        ]
        .map(|(label, stride, usage)| storage_buffer(device, label, stride * n, usage));
        (0..n)
            .map(|m| CullTargets {
                visible: visible.clone(),
                draws: draws_buffer.clone(),
                counts: counts.clone(),
                visible_at: m * strides[0],
                draws_at: m * strides[1],
                counts_at: m * strides[2],
                sizes,
            })
            .collect()
    }

    /// Where its ranges start, in elements (words, draws, words): a rig member's
    /// [`MemberAt`].
    pub fn member_at(&self) -> MemberAt {
        MemberAt {
            visible: (self.visible_at / 4) as u32,
            draws: (self.draws_at / size_of::<DrawArgs>() as u64) as u32,
            counts: (self.counts_at / 4) as u32,
        }
    }

    /// Its visible list, as a binding.
    pub fn visible_binding(&self) -> wgpu::BufferBinding<'_> {
        range(&self.visible, self.visible_at, self.sizes.0)
    }

    /// Its visible list, draws and counts, as bindings (what its own cull writes).
    pub fn bindings(&self) -> [wgpu::BufferBinding<'_>; 3] {
        [
            self.visible_binding(),
            range(&self.draws, self.draws_at, self.sizes.1),
            range(&self.counts, self.counts_at, COUNTS_BYTES),
        ]
    }

    /// Writes a CPU cull's `out` into these buffers; returns the bytes written.
    pub fn upload(&self, queue: &wgpu::Queue, out: &CullOutput) -> u64 {
        let mut counts = [0; COUNTS_BYTES as usize / 4];
        counts[0] = out.draw_count;
        counts[1] = out.visible.len() as u32;
        for (word, bin) in counts[2..].iter_mut().zip(&out.bins) {
            *word = bin.count;
        }
        let writes: [(&wgpu::Buffer, u64, &[u8]); 3] = [
            (
                &self.visible,
                self.visible_at,
                bytemuck::cast_slice(&out.visible),
            ),
            (&self.draws, self.draws_at, bytemuck::cast_slice(&out.draws)),
            (&self.counts, self.counts_at, bytemuck::cast_slice(&counts)),
        ];
        writes
            .iter()
            .filter(|(_, _, bytes)| !bytes.is_empty())
            .map(|(buffer, at, bytes)| {
                queue.write_buffer(buffer, *at, bytes);
                bytes.len() as u64
            })
            .sum()
    }
}

/// `size` bytes of `buffer` from `offset` (at least 4: an empty scene's list binds one
/// word).
fn range(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BufferBinding<'_> {
    wgpu::BufferBinding {
        buffer,
        offset,
        size: wgpu::BufferSize::new(size.max(4)),
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    match b {
        0 => a,
        _ => gcd(b, a % b),
    }
}
