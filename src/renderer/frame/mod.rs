//! The frame level: passes recorded once per frame, whatever the displays and eyes,
//! before any display's cull: posing animations on the GPU (`pose.rs`), morph targets
//! (`morph.rs`), skinning (`skin.rs`) and the light's shadow map (`shadow.rs`, culled
//! like one more view).

pub(super) mod morph;
pub(super) mod pose;
pub(super) mod shadow;
pub(super) mod skin;
