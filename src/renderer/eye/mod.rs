//! The eye level: only what truly differs per eye. On the indirect path that is data,
//! not passes: the display context's `eye[e]` (view, projection, viewport), which the
//! one draw of both eyes reads as `instance_index & 1` (multiview: the view index).
//! The classic modes draw each eye on its own, so there an [`Eye`] is one view of a
//! stereo display (an eye, or a foveated display's inset): its context, its viewport in
//! the display's target, and in multi-camera its own visible list. Its display decides
//! when it draws (its own pass, or switched to per instance); the eye binds itself.

use crate::buffers::{Upload, storage_buffer};
use crate::contexts::{DisplayContext, context_buffer};
use crate::draw::{DrawScene, Drawer, Drawing, set_viewport};
use crate::renderer::uploads::Writes;
use crate::shaders::Bound;

/// One view of a stereo display in a classic mode.
pub struct Eye {
    /// The display's context narrowed to this eye ([`DisplayContext::for_eye`]).
    context: wgpu::Buffer,
    /// Its own visible list (multi-camera); `None`: it draws from its display's.
    visible: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
    /// `[x, y, width, height]` in the display's target.
    viewport: [u32; 4],
}

/// What an eye's binding reads besides its own context and list.
pub struct EyeInputs<'a> {
    /// The frame context.
    pub frame: &'a wgpu::Buffer,
    /// The pipelines and the scene as drawn.
    pub drawing: Drawing<'a>,
    /// The display's visible list, for an eye without its own.
    pub display_list: &'a wgpu::Buffer,
    /// Instance slots: an own list's length.
    pub slots: u32,
}

impl Eye {
    /// An eye drawn into `viewport`, with its own visible list where `own_list`.
    pub fn new(
        device: &wgpu::Device,
        inputs: &EyeInputs,
        own_list: bool,
        viewport: [u32; 4],
    ) -> Eye {
        let context = context_buffer(device);
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let bytes = 4 * u64::from(inputs.slots);
        let visible = own_list.then(|| storage_buffer(device, "stereocull.visible", bytes, usage));
        let list = visible.as_ref().unwrap_or(inputs.display_list);
        let contexts = [inputs.frame, &context];
        let Drawing { drawer, scene } = inputs.drawing;
        let bind_group = drawer.bind_group(device, contexts, scene, list.bound());
        Eye {
            context,
            visible,
            bind_group,
            viewport,
        }
    }

    /// Writes eye `e`'s context of the display's `context`. Returns the bytes.
    pub fn prepare(&self, to: Writes, context: &DisplayContext, e: usize) -> u64 {
        to.pose.write_uniform(&self.context, 0, &context.for_eye(e))
    }

    /// Its own visible list, where it has one.
    pub fn visible(&self) -> Option<&wgpu::Buffer> {
        self.visible.as_ref()
    }

    /// Binds everything the eye's draws read and sets its viewport.
    pub fn bind(&self, pass: &mut wgpu::RenderPass, scene: &DrawScene) {
        Drawer::bind(pass, scene, &self.bind_group);
        set_viewport(pass, self.viewport);
    }

    /// Switches a pass that drew another eye of the same display to this one: its
    /// context and list, its viewport (the scene's bindings stay).
    pub fn switch_to(&self, pass: &mut wgpu::RenderPass) {
        pass.set_bind_group(0, &self.bind_group, &[]);
        set_viewport(pass, self.viewport);
    }
}
