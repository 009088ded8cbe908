//! Base color textures from glTF reach the screen: BoxTextured's rendered texels are the
//! texture's colors at the UVs the GPU interpolated there.

mod support;

use image::{Rgba, RgbaImage};
use stereocull::frustum::Fov;
use stereocull::renderer::RendererOptions;
use stereocull::rig::{Mount, Rig};
use stereocull::scene::Scene;
use stereocull::scene_spec;
use support::gpu;

const SIZE: u32 = 200;

/// Writes the UV's fractional part at 16 bits per coordinate (high byte, low byte) into
/// a linear target.
const UV_MATERIAL: &str = "
fn material(s: Surface) -> vec4<f32> {
    let q = vec2<u32>(round(fract(s.uv) * 65535.0));
    return vec4<f32>(vec4<u32>(q.x >> 8u, q.x & 255u, q.y >> 8u, q.y & 255u)) / 255.0;
}";

/// The unlit textured color, into an sRGB target: the texel's own sRGB bytes.
const BASE_COLOR_MATERIAL: &str = "
fn material(s: Surface) -> vec4<f32> {
    return vec4(base_color(s).rgb, 1.0);
}";

fn box_textured() -> Scene {
    let path = support::gltf_sample("BoxTextured", "glb");
    scene_spec::load(path.to_str().unwrap()).unwrap()
}

/// A mono view of the box's +Z face, filling the middle of the image.
fn facing_the_box() -> Rig {
    let mut rig = Rig::preset("hmd").unwrap();
    rig.viewer.position = [0.0, 0.0, 1.8];
    let display = &mut rig.displays[0];
    display.stereo = false;
    display.resolution = [SIZE, SIZE];
    if let Mount::Head(h) = &mut display.mount {
        h.fov = Fov {
            left: 0.5,
            right: 0.5,
            up: 0.5,
            down: 0.5,
        };
    }
    rig
}

fn render(scene: &Scene, material: &str, color_format: wgpu::TextureFormat) -> RgbaImage {
    let options = RendererOptions {
        material: Some(material.into()),
        color_format,
        ..Default::default()
    };
    support::render(&gpu(), scene, &facing_the_box(), options)
        .unwrap()
        .remove(0)
}

/// `procedural:N:M:SEED:textured`: the same scene, every mesh sampling one texture.
#[test]
fn a_textured_procedural_scene_is_the_plain_one_with_a_texture() {
    let plain = scene_spec::load("procedural:50:4:9").unwrap();
    let textured = scene_spec::load("procedural:50:4:9:textured").unwrap();
    assert_eq!(textured.instances, plain.instances);
    assert_eq!((textured.materials.len(), textured.textures.len()), (1, 1));
    assert_eq!(textured.materials[0].base_color_texture, Some(0));
    assert!(plain.materials.is_empty() && plain.textures.is_empty());
}

fn uv_of(p: &Rgba<u8>) -> [f32; 2] {
    let coordinate = |hi: u8, lo: u8| f32::from(u16::from(hi) << 8 | u16::from(lo)) / 65535.0;
    [coordinate(p[0], p[1]), coordinate(p[2], p[3])]
}

fn texel_at(texture: &RgbaImage, [u, v]: [f32; 2]) -> Rgba<u8> {
    let (w, h) = texture.dimensions();
    let x = ((u * w as f32) as u32).min(w - 1);
    let y = ((v * h as f32) as u32).min(h - 1);
    *texture.get_pixel(x, y)
}

/// Tolerance: a pixel matches when every channel is within 24 levels of the texel at its
/// UV (nearest texel on the CPU; the GPU filters between texels and mip levels, so pixels
/// on the logo's sharp edges can differ more), and at least 95 % of the box's pixels
/// match (96.8 % on lavapipe). The face must show several of the logo's colors, so an untextured box fails.
#[test]
fn box_textured_texels_match_the_texture_at_their_uvs() {
    let scene = box_textured();
    let texture = &scene.textures[0].image;
    let uvs = render(&scene, UV_MATERIAL, wgpu::TextureFormat::Rgba8Unorm);
    let colors = render(
        &scene,
        BASE_COLOR_MATERIAL,
        wgpu::TextureFormat::Rgba8UnormSrgb,
    );
    let (mut on_box, mut matching) = (0, 0);
    let mut seen = std::collections::HashSet::new();
    let background = *colors.get_pixel(0, 0);
    for (uv_pixel, color) in uvs.pixels().zip(colors.pixels()) {
        if *color == background {
            continue;
        }
        on_box += 1;
        let want = texel_at(texture, uv_of(uv_pixel));
        let close = (0..3).all(|c| want[c].abs_diff(color[c]) <= 24);
        matching += usize::from(close);
        seen.insert([color[0] / 64, color[1] / 64, color[2] / 64]);
    }
    assert!(on_box > 10_000, "the face fills the view: {on_box} pixels");
    let share = matching as f64 / on_box as f64;
    eprintln!(
        "{matching} of {on_box} box pixels match ({:.2} %)",
        100.0 * share
    );
    assert!(share >= 0.95, "{matching} of {on_box} match");
    assert!(seen.len() >= 3, "the logo's colors: {seen:?}");
}
