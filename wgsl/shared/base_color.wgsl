// A surface's base color from its parts, for the draw pipelines and the shadow pass's
// cutouts (after materials::DECLARATIONS, group 1).

// `color` (the instance record's) times material `material`'s base color texture at
// `uv`, if it has one. Sampled unconditionally (layer 0 stands in for untextured
// materials) to keep control flow uniform, as implicit-derivative sampling requires.
fn base_color_at(color: vec4<f32>, uv: vec2<f32>, material: u32) -> vec4<f32> {
    let layer = materials[material].base_color_layer;
    let textured = layer != 0xffffffffu;
    let texel = textureSample(base_color_textures, base_color_sampler, uv, select(0u, layer, textured));
    return color * select(vec4(1.0), texel, textured);
}
