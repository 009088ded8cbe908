//! A physical camera's exposure and a tone mapper, after shading and before the
//! target's format: glTF's punctual lights are in lux and candela, and a surface a
//! 2,000 lux sun lights is hundreds of times brighter than a display's white. Engines
//! (Bevy, Filament, Unity HDRP, Godot) scale the light that reaches the camera by its
//! exposure and map what is left into the display's range with a curve; so do we, for
//! the built-in shading (`wgsl/shared/tonemap.wgsl`, whose CPU twin this is). Unlit
//! materials and custom shading functions return display values and are left as they
//! are.
//!
//! One exposure and one curve serve every eye and display of a frame: they are the
//! frame context's ([`crate::contexts::FrameContext::exposure`]).

use glam::Vec3;

use crate::lights::LightKind;
use crate::scene::Scene;

/// The camera's exposure (`--exposure`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Exposure {
    /// A scene lit in physical units (a file's `KHR_lights_punctual`) metered as an
    /// incident-light meter would ([`metered_ev100`]); a scene lit in our own units
    /// (the built-in light, generated lamps) at unit exposure, as it always was.
    #[default]
    Auto,
    /// Exposure value at ISO 100, as a camera (or Bevy's `Exposure::ev100`) states
    /// it: the light is scaled by `1 / (1.2 * 2^ev100)`.
    Ev100(f32),
}

/// The tone mapper (`--tonemap`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Tonemap {
    /// Khronos PBR Neutral where the exposure is physical (metered, or an EV100
    /// given); none where the scene is lit in our units at unit exposure.
    #[default]
    Auto,
    /// The exposed color, clamped by the target's format.
    None,
    /// Khronos PBR Neutral: the glTF ecosystem's reference, hue-preserving, the
    /// identity (less a small toe) below 0.76.
    Neutral,
    /// The ACES filmic curve as Narkowicz fitted it (2015): contrast and a soft
    /// shoulder, per channel.
    Aces,
}

impl Tonemap {
    /// Its number in the frame context (`TONEMAP_*` in `wgsl/shared/tonemap.wgsl`).
    pub fn wgsl(self) -> u32 {
        match self {
            Tonemap::None | Tonemap::Auto => 0,
            Tonemap::Neutral => 1,
            Tonemap::Aces => 2,
        }
    }
}

/// The light's scale at `ev100`: `1 / (1.2 * 2^ev100)` (the saturation-based ISO
/// speed's 78 / (100 * 0.65), as Frostbite and Bevy state it). One EV more halves it
/// exactly.
pub fn scale_of_ev100(ev100: f32) -> f32 {
    1.0 / (1.2 * ev100.exp2())
}

/// An incident-light meter's calibration constant (ISO 2720's C = 250 for a flat
/// sensor), over the ISO speed 100.
const METER_C_OVER_ISO: f32 = 2.5;

/// `auto`'s reading of a scene lit in physical units: an incident-light meter held at
/// the center of the scene's bounds, facing its brightest light, at ISO 100:
/// `EV100 = log2(E / 2.5)`, where `E` (lux) is a directional light's intensity, or a
/// point or spot light's intensity over its squared distance to that center (no
/// nearer than a tenth of the scene's radius). A 2,049 lux sun reads 9.68, Bevy's
/// default exposure (9.7). `None` where the scene's lights are not physical or it has
/// none: unit exposure.
pub fn metered_ev100(scene: &Scene) -> Option<f32> {
    if !scene.physical_lights {
        return None;
    }
    let bounds = scene.bounds()?;
    let (center, nearest) = (bounds.truncate(), 0.1 * bounds.w);
    let illuminance = |l: &crate::lights::Light| match l.kind {
        LightKind::Directional => l.intensity,
        _ => l.intensity / l.position.distance_squared(center).max(nearest * nearest),
    };
    let brightest = scene.lights.iter().map(illuminance).fold(0.0, f32::max);
    (brightest > 0.0).then(|| (brightest / METER_C_OVER_ISO).log2())
}

/// The EV100 frames are exposed at (`None`: unit exposure, a scale of 1) and their
/// curve under `exposure` and `tonemap`, for a scene whose meter read `metered`
/// ([`metered_ev100`]). The frame context takes [`scale_of_ev100`] of the first.
pub fn resolve(
    exposure: Exposure,
    tonemap: Tonemap,
    metered: Option<f32>,
) -> (Option<f32>, Tonemap) {
    let ev100 = match exposure {
        Exposure::Ev100(ev) => Some(ev),
        Exposure::Auto => metered,
    };
    let curve = match (tonemap, ev100) {
        (Tonemap::Auto, Some(_)) => Tonemap::Neutral,
        (Tonemap::Auto, None) => Tonemap::None,
        (t, _) => t,
    };
    (ev100, curve)
}

/// `rgb` (linear, exposed) through `curve`, the operations in the order the shader's
/// `tone_map` does them.
pub fn tone_map(rgb: Vec3, curve: Tonemap) -> Vec3 {
    match curve {
        Tonemap::None | Tonemap::Auto => rgb,
        Tonemap::Neutral => pbr_neutral(rgb),
        Tonemap::Aces => rgb.map(aces),
    }
}

/// Khronos PBR Neutral (KhronosGroup/ToneMapping, `PBRNeutral`): a toe that lifts
/// the darkest channel's offset, the identity up to 0.76, then a shoulder that brings
/// the peak channel towards 1 and desaturates what it compresses.
pub fn pbr_neutral(rgb: Vec3) -> Vec3 {
    const START: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let x = rgb.min_element();
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let color = rgb - Vec3::splat(offset);
    let peak = color.max_element();
    if peak < START {
        return color;
    }
    let d = 1.0 - START;
    let new_peak = 1.0 - d * d / (peak + d - START);
    let color = color * (new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    color + (Vec3::splat(new_peak) - color) * g
}

/// Narkowicz's ACES filmic fit, `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`,
/// clamped to 0..1.
pub fn aces(x: f32) -> f32 {
    let mapped = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    mapped.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_more_halves_the_light_exactly() {
        for ev in [-3.0, -0.25, 0.0, 1.5, 9.7, 15.0] {
            assert_eq!(
                scale_of_ev100(ev + 1.0),
                scale_of_ev100(ev) / 2.0,
                "EV {ev}"
            );
        }
        // Bevy's default: 1 / (1.2 * 2^9.7) = 1.0019e-3.
        assert!((scale_of_ev100(9.7) - 1.0019e-3).abs() < 1e-6);
    }

    /// The published curves at hand-worked points: PBR Neutral keeps greys grey, is
    /// the identity less 0.04 between the toe and 0.76, and brings 1.0 to
    /// 1 - 0.24^2 / 0.44 = 0.869091; ACES (Narkowicz) maps middle grey 0.18 to
    /// 0.086724 / 0.324932 = 0.266905 and 1.0 to 2.54 / 3.16 = 0.803797, and clamps.
    #[test]
    fn the_curves_give_their_published_values() {
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-5;
        let neutral = |v: [f32; 3]| pbr_neutral(Vec3::from(v));
        assert!(close(neutral([0.5; 3]), Vec3::splat(0.46)));
        assert!(close(neutral([1.0; 3]), Vec3::splat(0.869_091)));
        assert!(close(
            neutral([0.04; 3]),
            Vec3::splat(0.04 - 0.04 + 6.25 * 0.0016)
        ));
        let hue = neutral([2.0, 1.0, 0.5]);
        assert!(
            hue.x > hue.y && hue.y > hue.z && hue.max_element() < 1.0,
            "{hue}"
        );
        assert!((aces(0.18) - 0.266_905).abs() < 1e-5);
        assert!((aces(1.0) - 0.803_797).abs() < 1e-5);
        assert_eq!(aces(100.0), 1.0);
        assert_eq!(aces(0.0), 0.0);
    }

    #[test]
    fn auto_is_neutral_where_physical_and_untouched_at_unit_exposure() {
        let unit = resolve(Exposure::Auto, Tonemap::Auto, None);
        assert_eq!(unit, (None, Tonemap::None));
        let metered = resolve(Exposure::Auto, Tonemap::Auto, Some(9.0));
        assert_eq!(metered, (Some(9.0), Tonemap::Neutral));
        let given = resolve(Exposure::Ev100(2.0), Tonemap::Aces, Some(9.0));
        assert_eq!(given, (Some(2.0), Tonemap::Aces));
    }

    #[test]
    fn the_meter_reads_the_brightest_light_at_the_scene_center() {
        let mut scene = crate::procedural::scene(20, 2, 7);
        assert_eq!(metered_ev100(&scene), None, "no lights");
        let sun = crate::lights::Light {
            kind: LightKind::Directional,
            color: Vec3::ONE,
            intensity: 2049.0,
            range: None,
            position: Vec3::ZERO,
            direction: Vec3::NEG_Z,
        };
        scene.lights = vec![sun];
        assert_eq!(metered_ev100(&scene), None, "our units");
        scene.physical_lights = true;
        let ev = metered_ev100(&scene).unwrap();
        assert!((ev - 9.678).abs() < 1e-3, "{ev}");
        let center = scene.bounds().unwrap().truncate();
        let lamp = crate::lights::Light::point(center + Vec3::X * 100.0, Vec3::ONE, 1e8, None);
        scene.lights.push(lamp);
        let ev = metered_ev100(&scene).unwrap();
        assert!((ev - (1e4f32 / 2.5).log2()).abs() < 1e-3, "{ev}");
    }
}
