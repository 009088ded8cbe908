//! The GPU culler's buffers: the scene data its passes read (uploaded once, written
//! again by a reload or a scatter) with the scratch all displays share. Each view's
//! outputs are [`crate::cull::targets`].

use crate::bins::BinKind;
use crate::buffers::Upload;
use crate::buffers::{init_buffer, init_buffer_with_room, storage_buffer};
use crate::cull::HiddenArea;
use crate::cull::coarse::{BLOCK, CoarseCull};
use crate::cull::rig::{MAX_RIG_VIEWS, RigCull, RigOcclusion, RigSets, RigView};
use crate::records::CullLayout;
use crate::records::{storage_bytes, uniform_bytes};
use crate::shaders::{SPAN, WORKGROUP_SIZE, dispatch_size};
use encase::ShaderType;
use glam::Vec4;

/// The uniform the cull passes read besides the display context (`CullParams` in
/// `wgsl/shared/records.wgsl`); encase lays it out as WGSL does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, encase::ShaderType)]
pub struct CullParams {
    /// Places of the cull order (instances when laid out tight).
    pub instance_count: u32,
    /// Meshes in the scene: draws per level.
    pub mesh_count: u32,
    /// The device's limit of workgroups per dimension: the coarse pass splits the
    /// candidates' dispatch into x and y with it.
    pub max_groups: u32,
    /// Levels of detail in use: 1 (off) or [`crate::scene::MAX_LODS`].
    pub lod_levels: u32,
    /// Words of the occlusion bits per display slot: one per span of places.
    pub visibility_words: u32,
    /// Where the depth pyramids start in the occlusion buffer, in words.
    pub pyramid_offset: u32,
    /// Words from one display slot's pyramids to the next's.
    pub pyramid_stride: u32,
    /// Where the changed tiles' bits start in the occlusion buffer, in words
    /// ([`crate::keep`]).
    pub tile_offset: u32,
    /// Words from one display slot's tiles to the next's.
    pub tile_stride: u32,
    /// Material bins ([`crate::bins::Bins`]): each has its own range of the draws.
    pub bin_count: u32,
    /// The first blended bin ([`crate::bins::Bins::first_blend_bin`]): blended
    /// instances are never marked drawn.
    pub first_blend_bin: u32,
    /// Where the blended bins' ranges of the draws start.
    pub blend_first: u32,
    /// Cull positions of room (a multiple of [`SPAN`]): the rig cull
    /// ([`crate::cull::rig`]) keeps a word per span of them for the rig's levels and one
    /// per span per member.
    pub position_room: u32,
    /// Words of `span_sums` per member of the rig cull.
    pub member_sums: u32,
}

/// Scene data the cull passes read, uploaded once, plus scratch shared by all displays
/// (displays cull one after another, so one scratch suffices).
pub struct CullScene {
    /// Places of the cull order the passes run over.
    pub instance_count: u32,
    /// The grids over every position (the compact pass, the floor), every span (the
    /// cull pass) and every block (the coarse cull).
    pub(super) groups: Grids,
    pub(super) max_groups: u32,
    /// Levels of detail culled into.
    pub levels: u32,
    pub(super) params: wgpu::Buffer,
    pub(super) spheres: wgpu::Buffer,
    pub(super) order: wgpu::Buffer,
    pub(super) positions: wgpu::Buffer,
    pub(super) mesh_of: wgpu::Buffer,
    pub(super) meshes: wgpu::Buffer,
    pub(super) mesh_bounds: wgpu::Buffer,
    pub(super) lods: wgpu::Buffer,
    pub(super) entries: wgpu::Buffer,
    pub(super) span_sums: wgpu::Buffer,
    /// Cull positions of room, and words of `span_sums` per rig member.
    member_strides: (u32, u32),
    /// The rig cull's members, a [`RigCull`] per group of [`MAX_RIG_VIEWS`] (at least
    /// one: every cull pass binds it), [`CullScene::rig_stride`] bytes apart.
    pub(super) rig: wgpu::Buffer,
    pub(super) rig_stride: u64,
    /// The rig cull's members (none: it does not run).
    pub(super) rig_sets: RigSets,
    /// The coarse cull's slots (displays; 0 without it) and its buffers per slot.
    pub(super) coarse_slots: u32,
    pub(super) block_marks: wgpu::Buffer,
    pub(super) block_list: wgpu::Buffer,
    /// Each slot's listed positions (the coarse passes write it; read back for
    /// statistics).
    pub candidate_count: wgpu::Buffer,
    pub(super) candidate_ranges: wgpu::Buffer,
    pub(super) block_tests: wgpu::Buffer,
    /// The display passes' indirect dispatches, two per slot (the cull pass's over
    /// spans, then the compact pass's over positions), written by the coarse passes.
    pub(super) coarse_args: wgpu::Buffer,
    /// Occlusion: per display slot, a word of bits per span of places (what the display
    /// drew last frame), then per display slot its depth pyramids
    /// ([`crate::occlusion::PyramidShape`]), all built before any late cull reads them.
    pub(super) occlusion: wgpu::Buffer,
    occlusion_layout: (u32, u32, u32),
    /// Where the changed tiles start in `occlusion` and the words per display slot.
    tile_layout: (u32, u32),
    /// Display slots with visibility words (0 without occlusion).
    visibility_slots: u32,
    /// Per display slot its hidden area ([`HiddenArea`]; one unused record where no
    /// display's cull drops by one), and how many slots are written each frame.
    pub(super) hidden: wgpu::Buffer,
    hidden_slots: u32,
}

/// What occlusion culling needs room for: how many displays keep visibility bits and
/// pyramids (a region each, of the most texels of any display's pyramids; both 0
/// without occlusion).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OcclusionRoom {
    /// Display slots with bits.
    pub displays: u32,
    /// Texels of the largest display's pyramids: every slot's region holds as many.
    pub pyramid_texels: u32,
    /// Keeping unchanged pixels: display slots with changed tiles and the words of the
    /// largest one's tiles (zeros without).
    pub tiles: (u32, u32),
}

impl CullScene {
    /// Uploads `layout`, with room for `slots` instances (a live scene's capacity), for
    /// culling into `levels` levels of detail (1: LOD off), with room for the coarse
    /// cull's lists of `coarse_slots` displays (0: no coarse cull), for occlusion, for
    /// the scratch of the rig cull's members `rig_sets` (none: it does not run) and
    /// for the hidden areas of `hidden_slots` displays (0: no cull drops by one).
    pub fn new(
        device: &wgpu::Device,
        layout: &CullLayout,
        (slots, levels): (u32, u32),
        (coarse_slots, occlusion, rig_sets, hidden_slots): (u32, OcclusionRoom, RigSets, u32),
    ) -> CullScene {
        let slots = slots
            .max(layout.positions.len() as u32)
            .max(layout.order.len() as u32);
        let max_groups = device.limits().max_compute_workgroups_per_dimension;
        let words = slots.next_multiple_of(BLOCK) / SPAN;
        // The pyramids are bound on their own from here: a storage binding's offset is
        // aligned.
        let align = device.limits().min_storage_buffer_offset_alignment / 4;
        let pyramid_offset = (occlusion.displays * words).next_multiple_of(align);
        let pyramid_stride = occlusion.pyramid_texels.next_multiple_of(align);
        let occlusion_layout = (words, pyramid_offset, pyramid_stride);
        let tile_offset = pyramid_offset + occlusion.displays * pyramid_stride;
        let tile_layout = (tile_offset, occlusion.tiles.1);
        // The display passes may run past the last instance to the end of its block.
        let positions = slots.next_multiple_of(BLOCK);
        let (spans, scan_groups) = span_shape(positions);
        let member_strides = (positions, (spans + scan_groups) * levels);
        let room = Room {
            max_groups,
            levels,
            occlusion: occlusion_layout,
            tiles: tile_layout,
            members: member_strides,
        };
        let (params, groups) = cull_params(layout, room);
        let scratch_members =
            (rig_sets.first.max(rig_sets.late)).clamp(1, MAX_RIG_VIEWS as u32) as u64;
        let rig_stride = (RigCull::min_size().get())
            .next_multiple_of(device.limits().min_uniform_buffer_offset_alignment as u64);
        let room = |label: &str, contents: &[u8], per_slot: u64| {
            // COPY_SRC: the spheres are read back by diagnostics (`spheres`).
            let usage = wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC;
            init_buffer_with_room(device, label, contents, per_slot * slots as u64, usage)
        };
        let scratch = wgpu::BufferUsages::STORAGE;
        let per_slot = |bytes: u64| bytes * coarse_slots as u64;
        let block_bytes = per_slot(4 * slots.div_ceil(BLOCK) as u64);
        let meshes = layout.meshes.len() as u64;
        CullScene {
            instance_count: params.instance_count,
            groups,
            max_groups,
            levels,
            params: init_buffer(
                device,
                "stereocull.cull_params",
                &uniform_bytes(&params),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            spheres: room(
                "stereocull.spheres",
                bytemuck::cast_slice(&layout.spheres),
                16,
            ),
            order: room("stereocull.order", bytemuck::cast_slice(&layout.order), 4),
            positions: room(
                "stereocull.positions",
                bytemuck::cast_slice(&layout.positions),
                4,
            ),
            mesh_of: room(
                "stereocull.mesh_of",
                bytemuck::cast_slice(&layout.mesh_of),
                4,
            ),
            meshes: room("stereocull.meshes", bytemuck::cast_slice(&layout.meshes), 0),
            mesh_bounds: room(
                "stereocull.mesh_bounds",
                bytemuck::cast_slice(&layout.mesh_bounds),
                0,
            ),
            lods: room("stereocull.lods", bytemuck::cast_slice(&layout.lods), 0),
            entries: storage_buffer(
                device,
                "stereocull.entries",
                // A word per position (a view's own cull), or with the rig cull a word
                // per span for the levels and one per span per member.
                4 * (positions as u64).max((1 + scratch_members) * (spans as u64)),
                scratch,
            ),
            span_sums: storage_buffer(
                device,
                "stereocull.span_sums",
                // The coarse cull's group totals use it before the display culls do.
                4 * (member_strides.1 as u64 * scratch_members)
                    .max((coarse_slots * slots.div_ceil(BLOCK).div_ceil(WORKGROUP_SIZE)) as u64),
                scratch,
            ),
            member_strides,
            rig: init_buffer(
                device,
                "stereocull.rig",
                &rig_groups(rig_sets, rig_stride),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            rig_stride,
            rig_sets,
            coarse_slots,
            block_marks: storage_buffer(device, "stereocull.block_marks", block_bytes, scratch),
            block_list: storage_buffer(device, "stereocull.block_list", block_bytes, scratch),
            candidate_count: storage_buffer(
                device,
                "stereocull.candidate_count",
                per_slot(4),
                scratch | wgpu::BufferUsages::COPY_SRC,
            ),
            candidate_ranges: storage_buffer(
                device,
                "stereocull.candidate_ranges",
                per_slot(8 * meshes),
                scratch,
            ),
            block_tests: storage_buffer(
                device,
                "stereocull.block_tests",
                per_slot(CoarseCull::min_size().get()),
                scratch | wgpu::BufferUsages::COPY_DST,
            ),
            coarse_args: storage_buffer(
                device,
                "stereocull.coarse_args",
                per_slot(2 * 12),
                scratch | wgpu::BufferUsages::INDIRECT,
            ),
            occlusion: storage_buffer(
                device,
                "stereocull.occlusion",
                4 * (tile_offset + occlusion.tiles.0 * occlusion.tiles.1).max(1) as u64,
                // A reload clears the visibility words from the queue.
                scratch | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
            occlusion_layout,
            tile_layout,
            visibility_slots: occlusion.displays,
            hidden: init_buffer(
                device,
                "stereocull.hidden",
                &storage_bytes(&vec![HiddenArea::NONE; hidden_slots.max(1) as usize]),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            ),
            hidden_slots,
        }
    }

    /// Writes a new `layout` (instances inserted or removed) into the buffers, which must
    /// have room for it (same meshes, no more slots than made for); returns the bytes.
    pub fn reload(&mut self, queue: &wgpu::Queue, layout: &CullLayout) -> u64 {
        let room = Room {
            max_groups: self.max_groups,
            levels: self.levels,
            occlusion: self.occlusion_layout,
            tiles: self.tile_layout,
            members: self.member_strides,
        };
        let (params, groups) = cull_params(layout, room);
        (self.instance_count, self.groups) = (params.instance_count, groups);
        let writes: [(&wgpu::Buffer, &[u8]); 6] = [
            (&self.params, &uniform_bytes(&params)),
            (&self.spheres, bytemuck::cast_slice(&layout.spheres)),
            (&self.order, bytemuck::cast_slice(&layout.order)),
            (&self.positions, bytemuck::cast_slice(&layout.positions)),
            (&self.mesh_of, bytemuck::cast_slice(&layout.mesh_of)),
            (&self.meshes, bytemuck::cast_slice(&layout.meshes)),
        ];
        // Laid out afresh, no place holds what it held: every instance starts as not
        // drawn last frame.
        let cleared = vec![0u8; 4 * (self.visibility_slots * self.occlusion_layout.0) as usize];
        let clear = (&self.occlusion, cleared.as_slice());
        (writes.iter().chain([&clear]))
            .filter(|(_, bytes)| !bytes.is_empty())
            .map(|(buffer, bytes)| {
                queue.write_buffer(buffer, 0, bytes);
                bytes.len() as u64
            })
            .sum()
    }

    /// Each slot's world sphere as the GPU culler holds it (vacant slots: whatever
    /// their place holds), read back.
    pub fn read_spheres(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        slots: u32,
    ) -> crate::error::Result<Vec<[f32; 4]>> {
        use crate::readback::read_pod;
        let spheres: Vec<[f32; 4]> = read_pod(device, queue, &self.spheres, self.spheres.size())?;
        let positions: Vec<u32> = read_pod(device, queue, &self.positions, self.positions.size())?;
        Ok((positions.iter().take(slots as usize))
            .map(|&p| spheres.get(p as usize).copied().unwrap_or([f32::NAN; 4]))
            .collect())
    }

    /// Where the changed tiles start in the occlusion buffer and the words from one
    /// display slot's to the next's.
    pub fn tile_layout(&self) -> (u32, u32) {
        self.tile_layout
    }

    /// Where the scatter passes write (the spheres in cull order, each slot's
    /// position, each position's slot, the places' visibility bits) and what they read
    /// (each mesh's local bounds).
    pub fn scatter_targets(&self) -> [&wgpu::Buffer; 5] {
        [
            &self.spheres,
            &self.positions,
            &self.order,
            &self.mesh_bounds,
            &self.occlusion,
        ]
    }

    /// The visibility words per display slot and the slots (zeros without occlusion).
    pub fn visibility_shape(&self) -> (u32, u32) {
        match self.visibility_slots {
            0 => (0, 0),
            slots => (self.occlusion_layout.0, slots),
        }
    }

    /// Bytes on the GPU per instance for culling (spheres, order, positions, mesh, the
    /// entry), whatever the levels of detail (their span sums add 4 bytes per level per
    /// [`SPAN`] instances).
    pub const BYTES_PER_INSTANCE: u64 = 16 + 4 + 4 + 4 + 4;

    /// The occlusion buffer: per display slot [`CullScene::visibility_words`] words of
    /// visibility bits, then per display slot its depth pyramids
    /// ([`CullScene::pyramid_offset`]).
    pub fn occlusion(&self) -> &wgpu::Buffer {
        &self.occlusion
    }

    /// Words of visibility bits per display slot.
    pub fn visibility_words(&self) -> u32 {
        self.occlusion_layout.0
    }

    /// The rig cull's members, as the frame runs them.
    pub fn rig_sets(&self) -> RigSets {
        self.rig_sets
    }

    /// Bytes of every display slot's pyramids.
    pub fn pyramid_bytes(&self) -> u64 {
        let (_, _, stride) = self.occlusion_layout;
        4 * self.visibility_slots as u64 * stride as u64
    }

    /// Where display slot `slot`'s pyramids start in [`CullScene::occlusion`], in bytes
    /// (aligned for a storage binding).
    pub fn pyramid_offset(&self, slot: usize) -> u64 {
        let (_, first, stride) = self.occlusion_layout;
        4 * (first as u64 + slot as u64 * stride as u64)
    }
}

/// The rig cull's groups of `sets`, `stride` bytes apart (at least one): each its
/// member count, its records written each frame ([`CullScene::write_rig_member`]).
fn rig_groups(sets: RigSets, stride: u64) -> Vec<u8> {
    let groups = sets.groups().max(1);
    let mut bytes = vec![0; (stride * groups as u64) as usize];
    for g in 0..sets.groups() {
        let views = vec![RigView::default(); sets.members_in(g) as usize];
        let set = uniform_bytes(&RigCull::new(&views));
        let at = (g as u64 * stride) as usize;
        bytes[at..at + set.len()].copy_from_slice(&set);
    }
    bytes
}

/// Spans and groups of spans (the cull pass's workgroups) over `positions` cull positions, as
/// `span_count` and `group_count` in `wgsl/shared/cull_math.wgsl` count them.
fn span_shape(positions: u32) -> (u32, u32) {
    let spans = positions.div_ceil(SPAN);
    (spans, spans.div_ceil(WORKGROUP_SIZE))
}

/// A pass's workgroups as (x, y), x within the device's limit.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grids {
    /// An invocation per position.
    pub positions: (u32, u32),
    /// An invocation per span of [`SPAN`] positions.
    pub spans: (u32, u32),
    /// An invocation per coarse block of [`BLOCK`] positions, along x alone (the
    /// limit of 65,535 workgroups is a billion positions).
    pub blocks: u32,
}

/// What a scene's buffers were made with room for: the device's workgroup limit, the
/// levels, the occlusion words per slot and where the pyramids start, and the cull
/// positions of room and the words of `span_sums` per rig member.
#[derive(Clone, Copy)]
struct Room {
    max_groups: u32,
    levels: u32,
    occlusion: (u32, u32, u32),
    tiles: (u32, u32),
    members: (u32, u32),
}

fn cull_params(layout: &CullLayout, room: Room) -> (CullParams, Grids) {
    let Room {
        max_groups,
        levels,
        occlusion: (visibility_words, pyramid_offset, pyramid_stride),
        tiles: (tile_offset, tile_stride),
        members: (position_room, member_sums),
    } = room;
    let n = layout.spheres.len() as u32;
    let groups = Grids {
        positions: dispatch_size(n.div_ceil(WORKGROUP_SIZE), max_groups),
        spans: dispatch_size(span_shape(n).1, max_groups),
        blocks: n.div_ceil(BLOCK).div_ceil(WORKGROUP_SIZE).max(1),
    };
    let params = CullParams {
        instance_count: n,
        mesh_count: layout.meshes.len() as u32,
        max_groups,
        lod_levels: levels,
        visibility_words,
        pyramid_offset,
        pyramid_stride,
        tile_offset,
        tile_stride,
        bin_count: layout.bins.kinds.len() as u32,
        first_blend_bin: layout.bins.first_blend_bin(),
        blend_first: (layout.bin_ranges(levels).iter())
            .find(|r| r.kind.alpha == BinKind::Blend)
            .map_or(0, |r| r.first),
        position_room,
        member_sums,
    };
    (params, groups)
}

// The GPU culler's per-frame writes into its buffers: the hidden areas, the coarse
// cull's block tests and the rig cull's members.
impl CullScene {
    /// Writes this frame's hidden areas, one per display slot (in order; `None` drops
    /// nothing). Returns the bytes written; nothing where no display's cull drops by one.
    pub fn write_hidden<'a>(
        &self,
        queue: &impl Upload,
        areas: impl Iterator<Item = Option<&'a HiddenArea>>,
    ) -> u64 {
        if self.hidden_slots == 0 {
            return 0;
        }
        let records: Vec<HiddenArea> = (areas.take(self.hidden_slots as usize))
            .map(|a| a.copied().unwrap_or(HiddenArea::NONE))
            .collect();
        let bytes = storage_bytes(&records);
        queue.write_buffer(&self.hidden, 0, &bytes);
        bytes.len() as u64
    }

    /// Writes this frame's block tests, one per coarse slot (display, in order): the
    /// display frustums' planes grown for rounding ([`CoarseCull::around`]). Returns the
    /// bytes written; nothing without the coarse cull.
    pub fn write_block_tests(&self, queue: &impl Upload, planes: &[[Vec4; 6]]) -> u64 {
        if self.coarse_slots == 0 {
            return 0;
        }
        let tests: Vec<CoarseCull> = planes.iter().map(|p| CoarseCull::around(*p)).collect();
        let bytes = storage_bytes(&tests);
        queue.write_buffer(&self.block_tests, 0, &bytes);
        bytes.len() as u64
    }

    /// Writes rig member `m`'s record for this frame, and a late member's occlusion
    /// test; returns the bytes written.
    pub fn write_rig_member(
        &self,
        queue: &impl Upload,
        m: u32,
        (record, test): (&RigView, Option<&RigOcclusion>),
    ) -> u64 {
        let (group, index) = self.rig_sets.place(m);
        let base = group as u64 * self.rig_stride;
        let (view_at, test_at) = RigCull::offsets(index as usize);
        let written = queue.write_uniform(&self.rig, base + view_at, record);
        written + test.map_or(0, |t| queue.write_uniform(&self.rig, base + test_at, t))
    }
}
