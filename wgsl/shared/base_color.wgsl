// A surface's base color from its parts, for the draw pipelines and the shadow pass's
// cutouts (after materials::DECLARATIONS, group 1).

const UNTEXTURED: u32 = 0xffffffffu;

// Where material `material`'s textures are read for vertex coordinates `uv`, and the
// gradients to read them with. The gradients are those of the varying itself,
// transformed: lavapipe's helper lanes on a quad that crosses a triangle edge may read
// another material's record, and derivatives of anything computed from it would pick
// a far too coarse mip level there (dots along every quad's diagonal).
struct TexelAt {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
}

fn material_uv(uv: vec2<f32>, material: u32) -> TexelAt {
    let m = materials[material].uv_transform;
    let along = mat2x2(m[0], m[1]);
    return TexelAt(m * vec3(uv, 1.0), along * dpdx(uv), along * dpdy(uv));
}

// `color` (the instance record's) times material `material`'s base color texture at
// `uv`, if it has one (layer 0 stands in for untextured materials).
fn base_color_at(color: vec4<f32>, uv: vec2<f32>, material: u32) -> vec4<f32> {
    let layer = materials[material].base_color_layer;
    let textured = layer != UNTEXTURED;
    let at = material_uv(uv, material);
    let texel = textureSampleGrad(color_textures, texture_sampler, at.uv, select(0u, layer, textured), at.dx, at.dy);
    return color * select(vec4(1.0), texel, textured);
}
