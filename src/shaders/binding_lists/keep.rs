//! The binding lists of keeping unchanged pixels ([`crate::keep`]): the GPU's marking
//! of the changed tiles, their listing and the tile pass that clears them.

use super::super::bindings::{Access, Binding};
use super::super::windows::Windowed;
use super::{COMPUTE, binding, windowed};

/// A kept frame's changed tiles marked on the GPU (`wgsl/keep_mark.wgsl`).
pub const MARK_TILES_BINDINGS: [Binding; 6] = [
    // The listed slots, each with its phases' flags.
    binding("marks", Access::StorageRead, "Marks", COMPUTE),
    // The phase this dispatch marks: MARK_BEFORE or MARK_AFTER.
    binding("phase", Access::Uniform, "u32", COMPUTE),
    binding(
        "tile_displays",
        Access::StorageRead,
        "array<TileDisplay>",
        COMPUTE,
    ),
    // Cull position of each slot.
    binding("positions", Access::StorageRead, "array<u32>", COMPUTE),
    // The GPU culler's occlusion words (CULL_BINDINGS' `occlusion`): each display's
    // tiles.
    binding(
        "tiles",
        Access::StorageReadWrite,
        "array<atomic<u32>>",
        COMPUTE,
    ),
    windowed(
        "spheres",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// A kept frame's changed tiles cleared (`wgsl/keep_tiles.wgsl`): the display's grid
/// of tiles and the changed ones' list.
pub const KEEP_TILES_BINDINGS: [Binding; 2] = [
    binding(
        "tiles",
        Access::StorageRead,
        "TileWords",
        wgpu::ShaderStages::VERTEX,
    ),
    binding(
        "list",
        Access::StorageRead,
        "array<u32>",
        wgpu::ShaderStages::VERTEX,
    ),
];

/// A kept frame's changed tiles listed (`wgsl/keep_list.wgsl`): the display's bits in,
/// the list and the tile pass's indirect draw out.
pub const KEEP_LIST_BINDINGS: [Binding; 3] = [
    binding("tiles", Access::StorageRead, "TileWords", COMPUTE),
    binding("list", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("draw", Access::StorageReadWrite, "TileDraw", COMPUTE),
];
