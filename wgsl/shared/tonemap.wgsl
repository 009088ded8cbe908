// The frame's exposure and tone mapper (frame.exposure, frame.tonemap), applied to the
// built-in shading before the target's format. src/exposure.rs is the CPU twin: the
// same operations in the same order.

const TONEMAP_NONE: u32 = 0u;
const TONEMAP_NEUTRAL: u32 = 1u;
const TONEMAP_ACES: u32 = 2u;

// Khronos PBR Neutral: a toe that lifts the darkest channel's offset, the identity up
// to 0.76, then a shoulder towards 1 that desaturates what it compresses.
fn pbr_neutral(rgb: vec3<f32>) -> vec3<f32> {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    let x = min(rgb.r, min(rgb.g, rgb.b));
    let offset = select(0.04, x - 6.25 * x * x, x < 0.08);
    let color = rgb - vec3(offset);
    let peak = max(color.r, max(color.g, color.b));
    if (peak < start) {
        return color;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    let scaled = color * (new_peak / peak);
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return scaled + (vec3(new_peak) - scaled) * g;
}

// Narkowicz's ACES filmic fit, per channel, clamped to 0..1.
fn aces(x: vec3<f32>) -> vec3<f32> {
    let mapped = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return clamp(mapped, vec3(0.0), vec3(1.0));
}

fn tone_map(rgb: vec3<f32>, curve: u32) -> vec3<f32> {
    switch curve {
        case TONEMAP_NEUTRAL: {
            return pbr_neutral(rgb);
        }
        case TONEMAP_ACES: {
            return aces(rgb);
        }
        default: {
            return rgb;
        }
    }
}

// A shaded color as the frame's camera sees it.
fn exposed(shaded: vec4<f32>) -> vec4<f32> {
    return vec4(tone_map(shaded.rgb * frame.exposure, frame.tonemap), shaded.a);
}
