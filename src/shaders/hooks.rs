//! The shading functions that materials name ([`Shading`]), as WGSL, and the check that
//! each compiles before any pipeline is built: a function that does not compile is an
//! error naming its material and the line of the function, not half a drawn frame.

use std::sync::Arc;

use super::{DrawKey, UNLIT, Windows};
use crate::bins::{Bins, MAX_BINS};
use crate::error::{Error, Result};
use crate::scene::{Scene, Shading};

/// The shading functions of a renderer's pipelines: WGSL, each defining `fn
/// material(s: Surface) -> vec4<f32>` (`wgsl/shared/draw_common.wgsl`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Shaders<'a> {
    /// Replaces the built-in lighting ([`Shading::Lit`]); `None`: the built-in.
    pub lit: Option<&'a str>,
    /// [`Shading::Hook`]'s functions, by index.
    pub hooks: &'a [Arc<str>],
}

impl<'a> Shaders<'a> {
    /// The function of `shading` (`None`: the built-in lighting; a pipeline of the
    /// caller's own has no function of ours).
    pub fn function(&self, shading: Shading) -> Option<&'a str> {
        match shading {
            Shading::Lit => self.lit,
            Shading::Unlit => Some(UNLIT),
            Shading::Hook(i) => self.hooks.get(i as usize).map(|h| &**h),
            Shading::Own(_) => None,
        }
    }
}

/// What `scene`'s materials ask of `shaders`: at most [`MAX_BINS`] bins, every hook
/// they name present, and every function they use compiling with the draw pipelines'
/// source (checked with naga, once per function, the first material naming it).
pub fn check_shading(scene: &Scene, shaders: Shaders) -> Result<()> {
    let bins = Bins::of(scene).kinds.len();
    if bins > MAX_BINS {
        return Err(Error::InvalidScene(format!(
            "{bins} material bins (alpha mode and shading pairs); at most {MAX_BINS}"
        )));
    }
    let mut checked = Vec::new();
    for m in &scene.materials {
        if let Shading::Hook(i) = m.shading
            && i as usize >= shaders.hooks.len()
        {
            return Err(Error::InvalidScene(format!(
                "material {:?} names shading hook {i} of {}",
                m.name,
                shaders.hooks.len()
            )));
        }
        if checked.contains(&m.shading) || matches!(m.shading, Shading::Own(_)) {
            continue;
        }
        checked.push(m.shading);
        if let Some(function) = shaders.function(m.shading) {
            compile(function).map_err(|(line, message)| Error::Shading {
                material: m.name.clone(),
                line,
                message,
            })?;
        }
    }
    match (scene.materials.is_empty(), shaders.lit) {
        (true, Some(function)) => compile(function).map_err(|(line, message)| Error::Shading {
            material: "default".into(),
            line,
            message,
        }),
        _ => Ok(()),
    }
}

/// Compiles `function` as a draw pipeline's shading; on failure, the line of
/// `function` at fault (when the fault lies in it) and naga's message.
fn compile(function: &str) -> std::result::Result<(), (Option<usize>, String)> {
    let source = DrawKey::new(1, false).source_with(Some(function), &Windows::WHOLE);
    let start = source.find(function).unwrap_or(0);
    let first_line = source[..start].lines().count() + 1;
    let lines = function.lines().count();
    let line_of = |at: Option<naga::SourceLocation>| {
        let line = at?.line_number as usize;
        (first_line..first_line + lines)
            .contains(&line)
            .then(|| line - first_line + 1)
    };
    let module = naga::front::wgsl::parse_str(&source)
        .map_err(|e| (line_of(e.location(&source)), e.message().to_string()))?;
    let flags = naga::valid::ValidationFlags::all();
    let capabilities = naga::valid::Capabilities::all();
    naga::valid::Validator::new(flags, capabilities)
        .validate(&module)
        .map_err(|e| (line_of(e.location(&source)), e.as_inner().to_string()))?;
    Ok(())
}
