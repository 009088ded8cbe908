// The built-in shading: glTF's metallic-roughness model. `pbr_inputs` reads a
// surface's material (its factors, and its textures through the texture transform);
// `pbr_shade` lights it with the BRDF of the glTF specification (appendix B: Lambert
// diffuse, GGX specular with the height-correlated Smith visibility, Schlick's
// Fresnel), from the frame's light through its shadow, plus an ambient term and the
// emission. Specular is seen from this eye's own position (the eye context), not the
// viewer's. src/pbr.rs is the CPU twin: the same operations in the same order.

// The light's radiance: a white diffuse surface facing it reads 0.75.
const LIGHT_RADIANCE: f32 = 2.35619449;
// Light from everywhere, as a share of the base color (times occlusion): no
// environment map, so a metal shows its color through this and its highlight.
const AMBIENT: f32 = 0.25;
// Below this perceptual roughness GGX's peak outgrows f32 (as Filament clamps).
const MIN_ROUGHNESS: f32 = 0.045;

struct Pbr {
    base: vec4<f32>,
    metallic: f32,
    roughness: f32,
    // Unit, world space, on the eye's side of the surface, the normal map applied.
    normal: vec3<f32>,
    // The geometric normal, unit, on the eye's side: for the shadow map's offset.
    geometric: vec3<f32>,
    occlusion: f32,
    emissive: vec3<f32>,
}

// A data texture's texel, or `none` where the slot has no texture. The gradients
// come with `at`, taken in uniform control flow, so the sample may sit in a branch:
// an untextured slot costs no sample.
fn data_at(layer: u32, at: TexelAt, none: vec4<f32>) -> vec4<f32> {
    if (layer == UNTEXTURED) {
        return none;
    }
    return textureSampleGrad(data_textures, texture_sampler, at.uv, layer, at.dx, at.dy);
}

fn pbr_inputs(s: Surface) -> Pbr {
    let m = materials[s.material];
    let uvs = vec4(s.uv, s.uv1);
    let mr = data_at(m.metallic_roughness_layer, material_uv(uvs, s.material, METALLIC_ROUGHNESS_SLOT), vec4(1.0));
    let ao = data_at(m.occlusion_layer, material_uv(uvs, s.material, OCCLUSION_SLOT), vec4(1.0)).r;
    let mapped = data_at(m.normal_layer, material_uv(uvs, s.material, NORMAL_SLOT), vec4(0.5, 0.5, 1.0, 1.0)).xyz;
    let lit = material_uv(uvs, s.material, EMISSIVE_SLOT);
    var emissive = m.emissive;
    if (m.emissive_layer != UNTEXTURED) {
        emissive *= textureSampleGrad(color_textures, texture_sampler, lit.uv, m.emissive_layer, lit.dx, lit.dy).rgb;
    }
    let to_eye = display.eye[s.eye].position - s.world_position;
    let n = normalize(s.normal);
    // Seen from behind (a double-sided surface), the whole tangent frame turns over.
    let facing = select(-1.0, 1.0, dot(n, to_eye) >= 0.0);
    var normal = n;
    if (m.normal_layer != UNTEXTURED) {
        normal = perturbed_normal(n, s.tangent, mapped, m.normal_scale);
    }
    let roughness = clamp(m.roughness * mr.g, MIN_ROUGHNESS, 1.0);
    let metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
    let occlusion = 1.0 + m.occlusion_strength * (ao - 1.0);
    return Pbr(base_color(s), metallic, roughness, normal * facing, n * facing, occlusion, emissive);
}

// The normal map's texel `texel` (0..1 per channel, tangent space) on unit normal `n`
// with tangent `t` (w: handedness), x and y scaled by `scale`. The tangent is made
// perpendicular to `n` first (it is interpolated); without one, `n` stays.
fn perturbed_normal(n: vec3<f32>, t: vec4<f32>, texel: vec3<f32>, scale: f32) -> vec3<f32> {
    let along = t.xyz - n * dot(n, t.xyz);
    if (dot(along, along) < 1e-12) {
        return n;
    }
    let tangent = normalize(along);
    let bitangent = cross(n, tangent) * select(-1.0, 1.0, t.w >= 0.0);
    let m = (texel * 2.0 - vec3(1.0)) * vec3(scale, scale, 1.0);
    return normalize(tangent * m.x + bitangent * m.y + n * m.z);
}

// glTF's BRDF for unit directions `v` (to the eye) and `l` (to the light): the
// diffuse and specular terms (xyz) and n . l (w), which the light's radiance scales.
fn brdf(p: Pbr, v: vec3<f32>, l: vec3<f32>) -> vec4<f32> {
    let n = p.normal;
    let h = normalize(l + v);
    let n_dot_l = clamp(dot(n, l), 0.0, 1.0);
    let n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    let n_dot_h = clamp(dot(n, h), 0.0, 1.0);
    let v_dot_h = clamp(dot(v, h), 0.0, 1.0);
    let alpha = p.roughness * p.roughness;
    let a2 = alpha * alpha;
    let f0 = mix(vec3(0.04), p.base.rgb, p.metallic);
    let f1 = 1.0 - v_dot_h;
    let f2 = f1 * f1;
    let fresnel = f0 + (vec3(1.0) - f0) * (f2 * f2 * f1);
    let d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    let distribution = a2 / (PI * d * d);
    let from_light = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    let from_eye = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    let visibility = 0.5 / (from_light + from_eye);
    let diffuse = (vec3(1.0) - fresnel) * (p.base.rgb * (1.0 - p.metallic)) / PI;
    let specular = fresnel * (distribution * visibility);
    return vec4(diffuse + specular, n_dot_l);
}

fn pbr_shade(s: Surface, p: Pbr) -> vec4<f32> {
    let v = normalize(display.eye[s.eye].position - s.world_position);
    let b = brdf(p, v, frame.light_direction);
    let reaching = light_reaching(s.world_position, p.geometric);
    let direct = b.xyz * (LIGHT_RADIANCE * b.w * reaching) + lights_shading(s, p, v);
    let ambient = p.base.rgb * (AMBIENT * p.occlusion);
    return vec4(direct + ambient + p.emissive, p.base.a);
}

// The built-in shading as the frame's camera sees it (wgsl/shared/tonemap.wgsl).
fn shade(s: Surface) -> vec4<f32> {
    return exposed(pbr_shade(s, pbr_inputs(s)));
}
