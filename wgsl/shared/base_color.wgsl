// A surface's base color from its parts, for the draw pipelines and the shadow pass's
// cutouts (after materials::DECLARATIONS, group 1).

const UNTEXTURED: u32 = 0xffffffffu;

// Where material `material`'s textures are read for the vertex coordinates, and the
// gradients to read them with. The gradients are those of the varying itself,
// transformed: lavapipe's helper lanes on a quad that crosses a triangle edge may read
// another material's record, and derivatives of anything computed from it would pick
// a far too coarse mip level there (dots along every quad's diagonal).
struct TexelAt {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
}

// `uvs` holds both sets of coordinates (xy, zw); texture slot `slot` (a bit of
// MaterialRecord::second_uv) reads the second where its bit is set. Both sets'
// gradients are taken, and chosen after, for the same reason.
// SECOND_UV is false in a bin whose materials read one set: its code is then the one
// set's alone.
fn material_uv(uvs: vec4<f32>, material: u32, slot: u32) -> TexelAt {
    let m = materials[material].uv_transform;
    let along = mat2x2(m[0], m[1]);
    if (!SECOND_UV) {
        return TexelAt(m * vec3(uvs.xy, 1.0), along * dpdx(uvs.xy), along * dpdy(uvs.xy));
    }
    let dx = dpdx(uvs);
    let dy = dpdy(uvs);
    let second = (materials[material].second_uv & slot) != 0u;
    let uv = select(uvs.xy, uvs.zw, second);
    return TexelAt(m * vec3(uv, 1.0), along * select(dx.xy, dx.zw, second), along * select(dy.xy, dy.zw, second));
}

const BASE_COLOR_SLOT: u32 = 1u;
const METALLIC_ROUGHNESS_SLOT: u32 = 2u;
const NORMAL_SLOT: u32 = 4u;
const OCCLUSION_SLOT: u32 = 8u;
const EMISSIVE_SLOT: u32 = 16u;

// `color` (the instance record's) times material `material`'s base color texture at
// `uvs` (both sets, as material_uv takes them), if it has one (layer 0 stands in for
// untextured materials).
fn base_color_at(color: vec4<f32>, uvs: vec4<f32>, material: u32) -> vec4<f32> {
    let layer = materials[material].base_color_layer;
    let textured = layer != UNTEXTURED;
    let at = material_uv(uvs, material, BASE_COLOR_SLOT);
    let texel = textureSampleGrad(color_textures, texture_sampler, at.uv, select(0u, layer, textured), at.dx, at.dy);
    return color * select(vec4(1.0), texel, textured);
}
