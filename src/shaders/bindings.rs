//! What a binding list is and everything made from one: WGSL declarations,
//! bind-group layouts and bind groups, pipelines. The lists themselves, one per bind
//! group of every pipeline, are in `binding_lists.rs`. No WGSL file declares a binding
//! of its own (`tests/shaders.rs` holds every pipeline's globals to its lists).

use super::windows::{Windowed, Windows};

/// One binding of a bind group: its WGSL declaration and its layout entry both come
/// from here; its binding number is its position in the list (a windowed binding takes
/// one number per window, so windowed bindings come last).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// The WGSL variable's name.
    pub name: &'static str,
    /// Its address space and access.
    pub access: Access,
    /// Its WGSL type (for textures and samplers, the one their kind spells).
    pub wgsl_type: &'static str,
    /// The stages that read it.
    pub stages: wgpu::ShaderStages,
    /// A per-instance array that may outgrow one binding: bound as [`Windows`] says,
    /// read (and written) through `<name>_at(i)` (and `<name>_set(i, v)`).
    pub windowed: Option<Windowed>,
}

/// The window count of each binding of `list`, in order (1 for plain ones).
fn window_counts<'a>(windows: &'a Windows, list: &'a [Binding]) -> impl Iterator<Item = u32> + 'a {
    list.iter()
        .map(|b| b.windowed.map_or(1, |w| windows.of(w).count))
}

/// A binding's kind: a buffer's address space and access, or a texture or sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`.
    Uniform,
    /// `var<uniform>` bound at a dynamic offset (one buffer of records, one a dispatch).
    UniformDynamic,
    /// `var<storage, read>`.
    StorageRead,
    /// `var<storage, read_write>`.
    StorageReadWrite,
    /// A sampled texture.
    Texture(TextureKind),
    /// A sampler (`sampler_comparison` for [`wgpu::SamplerBindingType::Comparison`]).
    Sampler(wgpu::SamplerBindingType),
}

/// What a sampled texture binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureKind {
    /// Float (filterable or not) or depth.
    pub sample: wgpu::TextureSampleType,
    /// 2D or a 2D array.
    pub dimension: wgpu::TextureViewDimension,
    /// Several samples per texel.
    pub multisampled: bool,
}

impl TextureKind {
    /// A single-sampled 2D texture of `sample`.
    pub const fn d2(sample: wgpu::TextureSampleType) -> TextureKind {
        TextureKind {
            sample,
            dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        }
    }

    /// Its WGSL type.
    pub(super) const fn wgsl_type(self) -> &'static str {
        use wgpu::TextureSampleType as S;
        use wgpu::TextureViewDimension as D;
        match (self.sample, self.dimension, self.multisampled) {
            (S::Depth, D::D2, false) => "texture_depth_2d",
            (S::Depth, D::D2, true) => "texture_depth_multisampled_2d",
            (S::Depth, D::D2Array, false) => "texture_depth_2d_array",
            (S::Float { .. }, D::D2, false) => "texture_2d<f32>",
            (S::Float { .. }, D::D2Array, false) => "texture_2d_array<f32>",
            _ => panic!("a texture kind no pipeline binds"),
        }
    }
}

/// A pipeline layout of one bind group, `group`.
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    group: &wgpu::BindGroupLayout,
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(group)],
        immediate_size: 0,
    })
}

/// The compute pipeline of `entry` in WGSL `source`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    source: String,
    entry: &str,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Splits `groups` workgroups into x * y with x within the per-dimension limit.
pub(crate) fn dispatch_size(groups: u32, max_per_dimension: u32) -> (u32, u32) {
    let x = groups.clamp(1, max_per_dimension);
    (x, groups.div_ceil(x).max(1))
}

/// The WGSL declarations of `bindings`, in `group`, windowed ones as `windows` says,
/// each with its accessors.
pub fn declarations(bindings: &[Binding], group: u32, windows: &Windows) -> String {
    let mut number = 0;
    let mut out = String::new();
    for (b, count) in bindings.iter().zip(window_counts(windows, bindings)) {
        let space = match b.access {
            Access::Uniform | Access::UniformDynamic => "<uniform>",
            Access::StorageRead => "<storage, read>",
            Access::StorageReadWrite => "<storage, read_write>",
            Access::Texture(_) | Access::Sampler(_) => "",
        };
        let names = window_names(b.name, count);
        for name in &names {
            out += &format!(
                "@group({group}) @binding({number}) var{space} {name}: {};\n",
                b.wgsl_type
            );
            number += 1;
        }
        if let Some(w) = b.windowed {
            out += &accessors(b, &names, windows.of(w).shift);
        }
    }
    out
}

fn window_names(name: &str, count: u32) -> Vec<String> {
    match count {
        1 => vec![name.to_string()],
        n => (0..n).map(|k| format!("{name}_{k}")).collect(),
    }
}

/// `<name>_at(i)`, and for writable arrays `<name>_set(i, v)`: element `i` in window
/// `i >> shift`.
fn accessors(b: &Binding, names: &[String], shift: u32) -> String {
    let element = b
        .wgsl_type
        .strip_prefix("array<")
        .and_then(|t| t.strip_suffix('>'))
        .unwrap_or(b.wgsl_type);
    let name = b.name;
    let pick = |body: &dyn Fn(&str) -> String| match names {
        [one] => body(&format!("{one}[i]")),
        _ => {
            let mask = (1u64 << shift) - 1;
            let cases: String = names
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    let label = if k + 1 == names.len() {
                        "default".to_string()
                    } else {
                        format!("case {k}u")
                    };
                    format!(
                        "        {label}: {{ {} }}\n",
                        body(&format!("{n}[i & {mask}u]"))
                    )
                })
                .collect();
            format!("    switch (i >> {shift}u) {{\n{cases}    }}\n")
        }
    };
    let wrap = |body: String| match names {
        [_] => format!("    {body}\n"),
        _ => body,
    };
    let mut out = format!(
        "fn {name}_at(i: u32) -> {element} {{\n{}}}\n",
        wrap(pick(&|at| format!("return {at};")))
    );
    if b.access == Access::StorageReadWrite {
        out += &format!(
            "fn {name}_set(i: u32, v: {element}) {{\n{}}}\n",
            wrap(pick(&|at| format!("{at} = v;")))
        );
    }
    out
}

/// The bind-group layout of `bindings`, windowed ones as `windows` says.
pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    bindings: &[Binding],
    windows: &Windows,
) -> wgpu::BindGroupLayout {
    let mut entries = Vec::new();
    for (b, count) in bindings.iter().zip(window_counts(windows, bindings)) {
        for _ in 0..count {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: entries.len() as u32,
                visibility: b.stages,
                ty: binding_type(b.access),
                count: None,
            });
        }
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// The layout entry's type of a binding of kind `access`. No minimum sizes: wgpu checks
/// the bound sizes against the shader when a pipeline is made.
fn binding_type(access: Access) -> wgpu::BindingType {
    let buffer = |ty, has_dynamic_offset| wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset,
        min_binding_size: None,
    };
    let storage = |read_only| wgpu::BufferBindingType::Storage { read_only };
    match access {
        Access::Uniform => buffer(wgpu::BufferBindingType::Uniform, false),
        Access::UniformDynamic => buffer(wgpu::BufferBindingType::Uniform, true),
        Access::StorageRead => buffer(storage(true), false),
        Access::StorageReadWrite => buffer(storage(false), false),
        Access::Texture(kind) => wgpu::BindingType::Texture {
            sample_type: kind.sample,
            view_dimension: kind.dimension,
            multisampled: kind.multisampled,
        },
        Access::Sampler(ty) => wgpu::BindingType::Sampler(ty),
    }
}

/// What a bind group binds a buffer binding to: a whole buffer or a range of one.
pub trait Bound<'a> {
    /// The binding.
    fn bound(self) -> wgpu::BufferBinding<'a>;
}

impl<'a> Bound<'a> for &'a wgpu::Buffer {
    fn bound(self) -> wgpu::BufferBinding<'a> {
        self.as_entire_buffer_binding()
    }
}

impl<'a> Bound<'a> for wgpu::BufferBinding<'a> {
    fn bound(self) -> wgpu::BufferBinding<'a> {
        self
    }
}

/// A bind group with `buffers[i]` for `bindings[i]` (the list `layout` was made from):
/// whole or the range given, or a windowed one (always a whole buffer) as its windows,
/// each `1 << shift` elements further.
pub fn bind_group<'a, B: Bound<'a>, const N: usize>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    bindings: &[Binding],
    windows: &Windows,
    buffers: [B; N],
) -> wgpu::BindGroup {
    // A programming error, not an input's: every list names each of its buffers once.
    assert_eq!(bindings.len(), N, "{label}: one buffer per binding");
    let mut entries = Vec::new();
    for (b, bound) in bindings.iter().zip(buffers) {
        let bound = bound.bound();
        let buffer = bound.buffer;
        let window = b.windowed.map(|w| (windows.of(w), w.stride()));
        match window {
            Some((w, stride)) if w.count > 1 => {
                let bytes = stride << w.shift;
                for k in 0..w.count as u64 {
                    // A window past the buffer's end (a stand-in) binds it whole.
                    let resource = match k * bytes {
                        offset if offset < buffer.size() => {
                            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer,
                                offset,
                                size: wgpu::BufferSize::new(bytes.min(buffer.size() - offset)),
                            })
                        }
                        _ => buffer.as_entire_binding(),
                    };
                    entries.push(wgpu::BindGroupEntry {
                        binding: entries.len() as u32,
                        resource,
                    });
                }
            }
            _ => entries.push(wgpu::BindGroupEntry {
                binding: entries.len() as u32,
                resource: wgpu::BindingResource::Buffer(bound),
            }),
        }
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}
