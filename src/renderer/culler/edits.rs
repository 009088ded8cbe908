//! What [`super::super::Renderer::sync`] changes in the culler: a new layout, the
//! places filled and vacated, the moved instances' spheres (the CPU culler's own copy;
//! the GPU's are scattered), and what the scatter passes write into on the GPU.

use super::{Culler, Kind};
use crate::error::Result;
use crate::records::{CullLayout, MoveEdit, PlaceEdit};
use crate::scene::Scene;
use crate::shaders::SPAN;

impl Culler {
    /// Takes a new `layout` (instances inserted or removed, same room); returns the
    /// bytes written.
    pub fn reload(&mut self, queue: &wgpu::Queue, layout: CullLayout) -> u64 {
        match &mut self.kind {
            Kind::Gpu { scene, .. } => scene.reload(queue, &layout),
            Kind::Cpu {
                layout: own,
                visibility,
                ..
            } => {
                // Laid out afresh, no place holds what it held: every instance starts
                // as not drawn last frame, as the GPU's reload clears its words.
                let words = layout.spheres.len().div_ceil(SPAN as usize);
                for w in visibility.iter_mut().flatten() {
                    *w = vec![0; words];
                }
                *own = layout;
                0
            }
        }
    }

    /// Each slot's world sphere on the GPU (`None` culling on the CPU).
    pub fn read_spheres(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        slots: u32,
    ) -> Result<Option<Vec<[f32; 4]>>> {
        match &self.kind {
            Kind::Gpu { scene, .. } => scene.read_spheres(device, queue, slots).map(Some),
            Kind::Cpu { .. } => Ok(None),
        }
    }

    /// The GPU culler's spheres, cull positions, order, mesh bounds and occlusion
    /// words, which the scatter passes write edits into, and the visibility words' shape
    /// (words per display slot, slots); `None` for the CPU culler, which takes edits
    /// into its layout ([`Culler::place`], [`Culler::moved`]).
    pub fn scatter_targets(&self) -> (Option<[&wgpu::Buffer; 5]>, (u32, u32)) {
        match &self.kind {
            Kind::Gpu { scene, .. } => (Some(scene.scatter_targets()), scene.visibility_shape()),
            Kind::Cpu { .. } => (None, (0, 0)),
        }
    }

    /// The places filled and vacated, into the CPU culler's layout (the GPU's are
    /// scattered). Whoever now holds a place was not drawn last frame: its bit goes in
    /// every display's words, as `wgsl/scatter_places.wgsl` clears the GPU's.
    pub fn place(&mut self, placed: &[PlaceEdit]) {
        if let Kind::Cpu {
            layout, visibility, ..
        } = &mut self.kind
        {
            for edit in placed {
                layout.set_place((edit.place, edit.slot, CullLayout::VACANT_SPHERE));
                let (word, bit) = ((edit.place / SPAN) as usize, edit.place % SPAN);
                for words in visibility.iter_mut().flatten() {
                    words[word] &= !(1 << bit);
                }
            }
        }
    }

    /// The moved instances' new spheres, into the CPU culler's layout (the GPU's are
    /// scattered).
    pub fn moved(&mut self, scene: &Scene, moved: &[MoveEdit]) {
        if let Kind::Cpu { layout, .. } = &mut self.kind {
            for edit in moved {
                let slot = edit.slot as usize;
                let sphere = scene.world_sphere(&scene.instances[slot]);
                layout.set_sphere(layout.positions[slot], sphere);
            }
        }
    }

    /// A second frame's moved spheres, grown to hold both frames' poses, into the CPU
    /// culler's layout, as the moves scatter writes the GPU's in its grow mode.
    pub fn grown(&mut self, grown: &[(u32, glam::Vec4)]) {
        if let Kind::Cpu { layout, .. } = &mut self.kind {
            for &(slot, sphere) in grown {
                layout.set_sphere(layout.positions[slot as usize], sphere);
            }
        }
    }
}
