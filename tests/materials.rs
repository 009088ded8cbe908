//! Materials: glTF alpha modes on the shared `AlphaBlendModeTest` (written by nobody
//! here), and the errors a material's data can raise.

use std::sync::Arc;

use glam::{Affine3A, DVec3, Vec2, Vec3, Vec4};
use image::RgbaImage;
use rand::{Rng, SeedableRng};
use stereocull::bins::Bins;
use stereocull::procedural;
use stereocull::records::pack_unorm4x8;
use stereocull::renderer::{CullMode, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::{AlphaMode, Animation, Instance, Material, Scene, Shading, Vertex};
use stereocull::scene_spec;
use support::Tolerance;

mod support;

fn alpha_test() -> Scene {
    let path = support::gltf_sample("AlphaBlendModeTest", "glb");
    scene_spec::load(path.to_str().unwrap()).unwrap()
}

/// The hmd at 640 x 400 per eye, 4 m in front of the three cutout quads (at x = 0,
/// 1.5 and 3, in the plane z = 0): each spans about 70 pixels, some 8 texels a pixel.
fn facing_the_cutouts() -> Rig {
    let mut rig = support::sized("hmd", 640, 400);
    rig.viewer.position = [1.5, 1.0, 4.0];
    rig
}

/// Where eye `e` of display 0 sees `p`, in the double-wide image.
fn pixel(rig: &Rig, e: usize, p: Vec3) -> Option<(u32, u32)> {
    let view = rig.resolve().ok()?.displays[0].eyes[e];
    let clip = view.clip_from_world().as_dmat4() * p.as_dvec3().extend(1.0);
    let ndc = DVec3::new(clip.x, clip.y, clip.z) / clip.w;
    let [w, h] = rig.displays[0].resolution;
    let (x, y) = (
        (ndc.x * 0.5 + 0.5) * w as f64,
        (0.5 - ndc.y * 0.5) * h as f64,
    );
    let inside = (0.0..w as f64).contains(&x) && (0.0..h as f64).contains(&y);
    inside.then(|| (x as u32 + e as u32 * w, y as u32))
}

/// The world point of instance `i` at texture coordinates `uv`: the cutout meshes are
/// flat quads whose coordinates map affinely onto their plane.
fn world_at(scene: &Scene, i: usize, uv: Vec2) -> Vec3 {
    let inst = &scene.instances[i];
    let mesh = &scene.meshes[inst.mesh as usize];
    let corner = |k: u32| {
        let index = scene.indices[(mesh.first_index + k) as usize] as i32 + mesh.base_vertex;
        scene.vertices[index as usize]
    };
    let [a, b, c] = [0, 1, 2].map(corner);
    let (pa, pb, pc) = (
        Vec3::from(a.position),
        Vec3::from(b.position),
        Vec3::from(c.position),
    );
    let (ta, tb, tc) = (Vec2::from(a.uv), Vec2::from(b.uv), Vec2::from(c.uv));
    let m = glam::Mat2::from_cols(tb - ta, tc - ta);
    let w = m.inverse() * (uv - ta);
    let local = pa + w.x * (pb - pa) + w.y * (pc - pa);
    inst.world_from_local.transform_point3(local)
}

/// The base color alpha around `uv` (`reach` texels each way, at the finest level):
/// its lowest and highest value. The GPU reads a filtered, mipmapped texture (about 8
/// texels a pixel here: trilinear between levels 3 and 4, whose texels each blend some
/// 16 to 32 finest texels), so only where the whole neighbourhood lies on one side of
/// a cutoff is the outcome certain.
fn alpha_range(image: &RgbaImage, uv: Vec2, reach: i32) -> (f32, f32) {
    let (w, h) = (image.width() as i32, image.height() as i32);
    let (cx, cy) = ((uv.x * w as f32) as i32, (uv.y * h as f32) as i32);
    let mut range = (1.0f32, 0.0f32);
    for y in cy - reach..=cy + reach {
        for x in cx - reach..=cx + reach {
            let a = image.get_pixel(x.rem_euclid(w) as u32, y.rem_euclid(h) as u32)[3];
            let a = a as f32 / 255.0;
            range = (range.0.min(a), range.1.max(a));
        }
    }
    range
}

/// A point of a quad: its texture coordinates, the alpha range around them, the pixel.
type QuadPoint = (Vec2, (f32, f32), (u32, u32));

/// Sample points of flat quad instance `i`, seen by `rig`: a 40 x 40 grid of its
/// texture coordinates (the quads read u in [0.125, 0.675], v in [0.05, 0.985]), each
/// with the range of the texture's alpha around it and the pixel of each eye that sees
/// it.
fn quad_points(scene: &Scene, rig: &Rig, i: usize) -> Vec<QuadPoint> {
    let texture = &scene.textures[material_of(scene, i).base_color_texture.unwrap() as usize];
    let mut points = Vec::new();
    for step in 0..40 * 40 {
        let f = Vec2::new((step % 40) as f32 + 0.5, (step / 40) as f32 + 0.5) / 40.0;
        let uv = Vec2::new(0.14 + 0.52 * f.x, 0.07 + 0.9 * f.y);
        let range = alpha_range(&texture.image, uv, 40);
        for e in 0..2 {
            if let Some(at) = pixel(rig, e, world_at(scene, i, uv)) {
                points.push((uv, range, at));
            }
        }
    }
    points
}

fn material_of(scene: &Scene, i: usize) -> &Material {
    let vertex = scene.meshes[scene.instances[i].mesh as usize].base_vertex as usize;
    &scene.materials[scene.vertices[vertex].material as usize]
}

/// The instances of `AlphaBlendModeTest` whose material has a cutoff, with it.
fn cutouts(scene: &Scene) -> Vec<(usize, f32)> {
    (0..scene.instances.len())
        .filter_map(|i| match material_of(scene, i).alpha {
            AlphaMode::Mask { cutoff } => Some((i, cutoff)),
            _ => None,
        })
        .collect()
}

/// `scene` without the instances `ids`.
fn without(scene: &Scene, ids: &[usize]) -> Scene {
    let mut rest = scene.clone();
    rest.instances = (scene.instances.iter().enumerate())
        .filter(|(i, _)| !ids.contains(i))
        .map(|(_, inst)| *inst)
        .collect();
    rest
}

/// `scene` with every material opaque.
fn all_opaque(scene: &Scene) -> Scene {
    let mut opaque = scene.clone();
    for m in &mut opaque.materials {
        m.alpha = AlphaMode::Opaque;
    }
    opaque
}

/// Whether two pixels differ by at most `levels` in every channel.
fn near(a: &image::Rgba<u8>, b: &image::Rgba<u8>, levels: u8) -> bool {
    (a.0.iter().zip(b.0)).all(|(x, y)| x.abs_diff(y) <= levels)
}

/// Every `MASK` quad of `AlphaBlendModeTest` shows, at each sampled point, what lies
/// behind it (the image without the cutouts) where the texture's alpha is under that
/// material's cutoff, and the quad (the image with the cutouts made opaque) where it is
/// over. The three cutoffs (0.25, 0.5 by default, 0.75) read the same texture, so the
/// same texel is a hole in one quad and solid in another: a cutoff read from the wrong
/// material, or ignored, fails. Holes are exact (the same pipelines draw what lies
/// behind); the quad's colors come from the cutout pipeline, compiled apart from the
/// opaque one, so they may round a level apart ([`Tolerance::RECOMPILED`]'s reason).
/// With MSAA (4 samples) the cutouts use alpha to coverage: where the alpha stays
/// further from the cutoff than it varies around the point, the coverage is all or
/// nothing, and the outcome the same.
#[test]
fn alpha_blend_mode_test_cuts_each_mask_at_its_own_cutoff() {
    let scene = alpha_test();
    let rig = facing_the_cutouts();
    let masks = cutouts(&scene);
    let mut cutoffs: Vec<f32> = masks.iter().map(|m| m.1).collect();
    cutoffs.sort_by(f32::total_cmp);
    assert_eq!(cutoffs, [0.25, 0.5, 0.75], "the file's three cutoffs");
    let mask_ids: Vec<usize> = masks.iter().map(|m| m.0).collect();
    for samples in [1, 4] {
        let render = |scene: &Scene| {
            let options = RendererOptions {
                sample_count: samples,
                shadows: false,
                ..support::frustum_only()
            };
            render_all(scene, &rig, options).remove(0)
        };
        let cut = render(&scene);
        let solid = render(&all_opaque(&scene));
        let behind = render(&without(&scene, &mask_ids));
        for &(i, cutoff) in &masks {
            let (mut holes, mut solids) = (0, 0);
            for (uv, (low, high), (x, y)) in quad_points(&scene, &rig, i) {
                // Coverage is (alpha - cutoff) / fwidth(alpha) + 1/2, fwidth capped at
                // COVERAGE_WIDTH (wgsl/shared/draw_common.wgsl): all or nothing where
                // the margin exceeds half of that, or how much alpha varies around.
                let spread = (high - low).max(0.125);
                let margin = 0.02 + if samples > 1 { spread } else { 0.0 };
                let hole = high < cutoff - margin;
                if !hole && low < cutoff + margin {
                    continue;
                }
                let (want, other) = match hole {
                    true => (behind.get_pixel(x, y), solid.get_pixel(x, y)),
                    false => (solid.get_pixel(x, y), behind.get_pixel(x, y)),
                };
                if near(want, other, 1) {
                    continue; // The quad is hidden here, or matches what it hides.
                }
                let got = cut.get_pixel(x, y);
                assert!(
                    near(got, want, if hole { 0 } else { 1 }),
                    "{samples} samples, instance {i} (cutoff {cutoff}) at uv {uv}, pixel \
                     ({x}, {y}): alpha in [{low}, {high}]: {got:?}, want {want:?}"
                );
                *if hole { &mut holes } else { &mut solids } += 1;
            }
            assert!(
                holes > 50 && solids > 50,
                "{samples} samples, instance {i} (cutoff {cutoff}): {holes} holes and \
                 {solids} solid points checked"
            );
        }
    }
}

/// sRGB-encoded 8-bit to linear.
fn linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// `AlphaBlendModeTest`'s `BLEND` quad mixes itself (the image with it opaque) and what
/// lies behind it (the image without it) by the texture's alpha, in linear color: at
/// each sampled point the pixel lies between the mixes at the lowest and highest alpha
/// around it, within two levels (the quad's color rounds to 8 bits in the opaque
/// image, not in the blend).
#[test]
fn alpha_blend_mode_test_blends_its_glass_by_alpha() {
    let scene = alpha_test();
    let mut rig = facing_the_cutouts();
    rig.viewer.position = [-1.5, 1.0, 4.0];
    // The test quad (at x = -1.5) alone: the decal of the same material lies nearer,
    // on the bed, and would blend over it.
    let blended: Vec<usize> = (0..scene.instances.len())
        .filter(|&i| material_of(&scene, i).alpha == AlphaMode::Blend)
        .collect();
    let is_quad = |i: &&usize| scene.instances[**i].world_from_local.translation.x == -1.5;
    let decals: Vec<usize> = blended.iter().filter(|i| !is_quad(i)).copied().collect();
    let scene = without(&scene, &decals);
    let quad = (0..scene.instances.len())
        .find(|&i| material_of(&scene, i).alpha == AlphaMode::Blend)
        .unwrap();
    let options = RendererOptions {
        shadows: false,
        ..support::frustum_only()
    };
    let glass = render_all(&scene, &rig, options.clone()).remove(0);
    let solid = render_all(&all_opaque(&scene), &rig, options.clone()).remove(0);
    let behind = render_all(&without(&scene, &[quad]), &rig, options).remove(0);
    let mut checked = 0;
    for (uv, (low, high), (x, y)) in quad_points(&scene, &rig, quad) {
        let (got, front, back) = (
            glass.get_pixel(x, y),
            solid.get_pixel(x, y),
            behind.get_pixel(x, y),
        );
        if high - low > 0.1 || near(front, back, 24) {
            continue;
        }
        for c in 0..3 {
            let mix = |a: f32| a * linear(front[c]) + (1.0 - a) * linear(back[c]);
            let (a, b) = (srgb_level(mix(low)), srgb_level(mix(high)));
            let (lo, hi) = (a.min(b), a.max(b));
            let g = got[c] as f32;
            assert!(
                g >= lo - 2.0 && g <= hi + 2.0,
                "uv {uv}, pixel ({x}, {y}), channel {c}: {g} outside [{lo}, {hi}] (alpha in \
                 [{low}, {high}], quad {}, behind {})",
                front[c],
                back[c]
            );
        }
        checked += 1;
    }
    assert!(checked > 100, "{checked} points checked");
}

/// Linear to an sRGB level (0 to 255, unrounded).
fn srgb_level(l: f32) -> f32 {
    let c = if l <= 0.0031308 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    c * 255.0
}

/// The shadow pass draws cutouts with their holes: cutouts whose cutoff no alpha
/// reaches (all hole) cast no shadow, so the image with the shadow map on equals the
/// image without those instances, exactly. Drawn depth-only, as opaque casters are,
/// they would shadow the bed behind them (checked once by making the cutout bin use
/// the depth-only pipeline: 1,500 pixels differed).
#[test]
fn cutouts_cast_shadows_with_their_holes() {
    let scene = alpha_test();
    let rig = facing_the_cutouts();
    let mut all_holes = scene.clone();
    for m in &mut all_holes.materials {
        if let AlphaMode::Mask { cutoff } = &mut m.alpha {
            *cutoff = 2.0;
        }
    }
    let mask_ids: Vec<usize> = cutouts(&scene).iter().map(|m| m.0).collect();
    let options = RendererOptions {
        shadows: true,
        ..support::frustum_only()
    };
    let got = render_all(&all_holes, &rig, options.clone()).remove(0);
    let want = render_all(&without(&scene, &mask_ids), &rig, options).remove(0);
    // Exact on any CPU: the opaque and blended bins are drawn by the same pipelines
    // (one source per bin, whatever its index) from the same draws, and the cutout
    // pipelines, compiled apart, write no fragment and no shadow texel at all.
    support::assert_images_match("all-hole cutouts", &got, &want, Tolerance::EXACT);
}

/// The image of `scene` without shadows, every display.
fn render_all(scene: &Scene, rig: &Rig, options: RendererOptions) -> Vec<RgbaImage> {
    let gpu = support::gpu();
    support::render(&gpu, scene, rig, options).unwrap()
}

/// One frame's draw calls of `scene` seen by `rig`, without shadows.
fn draw_calls(scene: &Scene, rig: &Rig, options: RendererOptions) -> u32 {
    let gpu = support::gpu();
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let stats = (renderer.submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)).unwrap();
    stats.draw_calls
}

/// A random scene whose meshes use materials of every alpha mode draws one multi-draw
/// per material bin per display, on the GPU and CPU cull paths and in every indirect
/// mode, whatever the instance count; a scene of one mode, one per display.
#[test]
fn each_material_bin_is_one_draw_call_per_display() {
    let plain = procedural::scene(3000, 12, 21);
    let binned = support::with_random_bins(plain.clone(), 21);
    let bins = Bins::of(&binned).kinds.len() as u32;
    assert_eq!(bins, 3, "the random materials use every mode");
    for preset in ["hmd", "cave"] {
        let rig = support::sized(preset, 64, 64);
        let displays = rig.displays.len() as u32;
        for (mode, cull) in [
            (StereoMode::Instanced, CullMode::Gpu),
            (StereoMode::Instanced, CullMode::Cpu),
            (StereoMode::Multiview, CullMode::Gpu),
        ] {
            let options = RendererOptions {
                mode,
                cull,
                shadows: false,
                ..support::frustum_only()
            };
            let what = format!("{preset} {mode:?} {cull:?}");
            assert_eq!(
                draw_calls(&binned, &rig, options.clone()),
                bins * displays,
                "{what}"
            );
            assert_eq!(draw_calls(&plain, &rig, options), displays, "{what}");
        }
    }
}

/// Cutouts whose alpha is never under the cutoff draw exactly what opaque materials
/// draw, from their own bin and pipeline: the bins change which call draws an
/// instance, never what it looks like. The cutout pipeline is compiled apart (it can
/// discard), so its colors may round a level apart ([`Tolerance::RECOMPILED`]).
#[test]
fn cutouts_that_cut_nothing_draw_what_opaque_materials_draw() {
    let mut scene = procedural::scene(400, 6, 22);
    scene.materials = vec![
        Material::default(),
        Material {
            alpha: AlphaMode::Mask { cutoff: 0.5 },
            ..Default::default()
        },
    ];
    // Every other mesh's vertices (each mesh's are contiguous) name the cutout.
    let starts: Vec<usize> = scene
        .meshes
        .iter()
        .map(|m| m.base_vertex as usize)
        .collect();
    for m in (1..starts.len()).step_by(2) {
        let end = starts.get(m + 1).copied().unwrap_or(scene.vertices.len());
        for v in &mut scene.vertices[starts[m]..end] {
            v.material = 1;
        }
    }
    let mut opaque = scene.clone();
    opaque.materials[1].alpha = AlphaMode::Opaque;
    let rig = support::sized("hmd", 160, 120);
    let options = RendererOptions {
        shadows: false,
        ..support::frustum_only()
    };
    let got = render_all(&scene, &rig, options.clone());
    let want = render_all(&opaque, &rig, options);
    support::assert_images_match("cutouts", &got[0], &want[0], Tolerance::RECOMPILED);
}

/// Tints for the hooks of [`shaded_scene`]: each its own function, so its own pipeline.
fn tint_hook(tint: [f32; 3]) -> Arc<str> {
    let [r, g, b] = tint;
    format!(
        "fn material(s: Surface) -> vec4<f32> {{\n    return vec4(base_color(s).rgb * vec3({r:?}, {g:?}, {b:?}), 1.0);\n}}\n"
    )
    .into()
}

/// A random scene whose meshes (each its own material, at random) are shaded by the
/// built-in lighting, unlit, and three hooks; and the options that carry the hooks.
fn shaded_scene() -> (Scene, RendererOptions) {
    let shadings = [
        Shading::Lit,
        Shading::Unlit,
        Shading::Hook(0),
        Shading::Hook(1),
        Shading::Hook(2),
    ];
    let mut scene = support::with_random_bins(procedural::scene(600, 10, 23), 23);
    for (k, m) in scene.materials.iter_mut().enumerate() {
        m.alpha = AlphaMode::Opaque;
        m.shading = shadings[k];
    }
    let options = RendererOptions {
        hooks: vec![
            tint_hook([1.0, 0.3, 0.3]),
            tint_hook([0.3, 1.0, 0.3]),
            tint_hook([0.3, 0.3, 1.0]),
        ],
        shadows: false,
        ..support::frustum_only()
    };
    (scene, options)
}

/// Every shading function is its own bin: a scene of five draws five multi-draws per
/// display, and each pixel is what the instances of its material draw alone (the
/// scene with only that material's instances, and only that material, so its one
/// bin draws with the one pipeline it must). Exact: the same pipelines draw the same
/// fragments; only which call draws them differs.
#[test]
fn each_shading_function_is_its_own_bin_and_draws_what_it_draws_alone() {
    let (scene, options) = shaded_scene();
    let rig = support::sized("hmd", 120, 90);
    let bins = Bins::of(&scene).kinds.len() as u32;
    assert_eq!(bins, 5, "five shading functions");
    assert_eq!(draw_calls(&scene, &rig, options.clone()), bins);
    let all = render_all(&scene, &rig, options.clone()).remove(0);
    let alone: Vec<RgbaImage> = (0..scene.materials.len() as u32)
        .map(|k| {
            let mut only = scene.clone();
            only.instances.retain(|i| {
                let vertex = scene.meshes[i.mesh as usize].base_vertex as usize;
                scene.vertices[vertex].material == k
            });
            for v in &mut only.vertices {
                v.material = k;
            }
            render_all(&only, &rig, options.clone()).remove(0)
        })
        .collect();
    let mut shown = vec![0; alone.len()];
    for (x, y, p) in all.enumerate_pixels() {
        let k = alone.iter().position(|a| a.get_pixel(x, y) == p);
        let k = k.unwrap_or_else(|| panic!("pixel ({x}, {y}) {p:?} is no material's alone"));
        shown[k] += 1;
    }
    let lit = render_all(&all_lit(&scene), &rig, options).remove(0);
    assert_ne!(all, lit, "the functions change the image");
    eprintln!("pixels first matched per material: {shown:?}");
}

/// `scene` with every material shaded by the built-in lighting.
fn all_lit(scene: &Scene) -> Scene {
    let mut lit = scene.clone();
    for m in &mut lit.materials {
        m.shading = Shading::Lit;
    }
    lit
}

/// A material's shading function that does not compile is an error naming the
/// material and the function's own line, before anything is drawn; a hook index the
/// options lack, an error naming the material.
#[test]
fn shading_functions_that_do_not_compile_are_errors_naming_material_and_line() {
    let gpu = support::gpu();
    let (mut scene, mut options) = shaded_scene();
    let rig = support::sized("hmd", 32, 32);
    options.hooks[1] =
        "fn material(s: Surface) -> vec4<f32> {\n    return vec4(base_color(s).rgb, 1.0)\n}\n"
            .into();
    let err = Renderer::new(&gpu.device, &scene, &rig, options.clone())
        .err()
        .unwrap();
    let msg = err.to_string();
    assert!(msg.contains("material \"material 3\""), "{msg}");
    assert!(
        msg.contains("(its line 2)") || msg.contains("(its line 3)"),
        "{msg}"
    );
    options.hooks[1] =
        "fn material(s: Surface) -> vec4<f32> {\n    return s.color.rgb;\n}\n".into();
    let msg = (Renderer::new(&gpu.device, &scene, &rig, options.clone())
        .err()
        .unwrap())
    .to_string();
    assert!(
        msg.contains("material \"material 3\"") && msg.contains("(its line"),
        "{msg}"
    );
    options.hooks.truncate(1);
    scene.materials[3].shading = Shading::Lit;
    let msg = (Renderer::new(&gpu.device, &scene, &rig, options)
        .err()
        .unwrap())
    .to_string();
    assert!(
        msg.contains("material \"material 4\" names shading hook 2 of 1"),
        "{msg}"
    );
}

/// Three unlit quads of one blended material, 2 m wide, facing +Z, centered on the
/// hmd's line of sight at distances `depths`, each its own color at alpha 1/2.
fn glass_panes(depths: [f32; 3]) -> Scene {
    let mut scene = Scene::default();
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let vertices: Vec<Vertex> = (corners.iter())
        .map(|&[x, y]| Vertex::new(Vec3::new(x, y, 0.0), Vec3::Z))
        .collect();
    let mesh = scene.add_mesh("pane", &vertices, &[0, 1, 2, 0, 2, 3]);
    scene.materials = vec![Material {
        name: "glass".into(),
        alpha: AlphaMode::Blend,
        shading: Shading::Unlit,
        ..Default::default()
    }];
    let colors = [
        Vec4::new(0.9, 0.1, 0.1, 0.5),
        Vec4::new(0.1, 0.9, 0.1, 0.5),
        Vec4::new(0.1, 0.1, 0.9, 0.5),
    ];
    for (k, (&z, color)) in depths.iter().zip(colors).enumerate() {
        let at = Vec3::new(0.05 * k as f32, 1.6, -z);
        scene.instances.push(Instance {
            world_from_local: Affine3A::from_translation(at),
            mesh,
            color,
            material: None,
            animation: Animation::NONE,
        });
    }
    scene
}

/// What a painter draws at a pixel the three panes cover: the clear color, then each
/// pane's color (as the GPU stores it: 8-bit) over it by its alpha, farthest first, in
/// linear color.
fn painted(scene: &Scene) -> [f32; 3] {
    let clear = stereocull::draw::CLEAR_COLOR;
    let mut c = [clear.r as f32, clear.g as f32, clear.b as f32];
    let mut panes: Vec<&Instance> = scene.instances.iter().collect();
    panes.sort_by(|a, b| {
        a.world_from_local
            .translation
            .z
            .total_cmp(&b.world_from_local.translation.z)
    });
    for pane in panes {
        let bytes = pack_unorm4x8(pane.color).to_le_bytes();
        let a = bytes[3] as f32 / 255.0;
        for i in 0..3 {
            c[i] = a * bytes[i] as f32 / 255.0 + (1.0 - a) * c[i];
        }
    }
    c
}

/// Blending order: three overlapping panes at random depths (fixed seeds), in every
/// order of their ids, show in both eyes the color a painter's algorithm gives (the
/// farthest first), within two levels: each blend rounds the target to 8 bits. Drawn
/// in id order instead, most of these cases miss by tens of levels. The GPU and CPU
/// culls' sorted draws are identical (asserted here, and on random scenes in
/// tests/cull_gpu.rs), one list for both eyes.
#[test]
fn overlapping_glass_blends_back_to_front_in_both_eyes() {
    let gpu = support::gpu();
    let rig = support::sized("hmd", 64, 64);
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(24);
    for case in 0..6 {
        let depths = [0; 3].map(|_| rng.random_range(2.0f32..9.0));
        let scene = glass_panes(depths);
        let options = RendererOptions {
            shadows: false,
            ..support::frustum_only()
        };
        let renderer = support::one_frame(&gpu, &scene, &rig, options.clone());
        let gpu_cull = support::read_culls(&gpu, &renderer, &rig).remove(0);
        assert_eq!(
            gpu_cull,
            support::reference_culls(&scene, &rig).remove(0),
            "case {case}"
        );
        let image = render_all(&scene, &rig, options).remove(0);
        let want = painted(&scene).map(srgb_level);
        for e in 0..2 {
            let (x, y) = pixel(&rig, e, Vec3::new(0.05, 1.6, -20.0)).unwrap();
            let got = image.get_pixel(x, y);
            for c in 0..3 {
                assert!(
                    (got[c] as f32 - want[c]).abs() <= 2.0,
                    "case {case} (depths {depths:?}), eye {e}: {got:?}, want {want:?}"
                );
            }
        }
    }
}

/// `scene` with two more opaque, lit materials (one bin: both draw with the built-in
/// pipeline) that differ in data only: material `a` untextured, `b` sampling a random
/// 4 x 4 texture (fixed seed); every vertex names `a`. Returns the scene and `b`.
fn with_two_opaque_materials(mut scene: Scene, seed: u64) -> (Scene, u32) {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let texels: Vec<u8> = (0..64)
        .map(|i| if i % 4 == 3 { 255 } else { rng.random() })
        .collect();
    scene.textures.push(stereocull::scene::Texture {
        name: "random".into(),
        image: RgbaImage::from_raw(4, 4, texels).unwrap(),
        encoding: stereocull::scene::Encoding::Srgb,
        basis: None,
    });
    let a = scene.materials.len() as u32;
    scene.materials.push(Material {
        name: "plain".into(),
        ..Default::default()
    });
    scene.materials.push(Material {
        name: "textured".into(),
        base_color_texture: Some(scene.textures.len() as u32 - 1),
        ..Default::default()
    });
    for v in &mut scene.vertices {
        v.material = a;
    }
    (scene, a + 1)
}

/// Per-instance material overrides through live edits: every instance of two meshes
/// takes material `b` in place of its mesh's `a` (a record edit each), and the frame
/// is, exactly, that of the scene whose two meshes name `b` themselves (the same
/// pipeline draws the same fragments: only where the material index comes from
/// differs); clearing the overrides gives the first image back. An override of another
/// bin, or of a material the scene lacks, is an error naming it, and so is such an
/// override in a scene a renderer is made for.
#[test]
fn instances_take_materials_of_their_own_in_a_live_scene() {
    let gpu = support::gpu();
    let (scene, b) = with_two_opaque_materials(procedural::scene(400, 6, 31), 31);
    let rig = support::sized("hmd", 96, 72);
    let options = RendererOptions {
        shadows: false,
        ..support::frustum_only()
    };
    let read = |renderer: &mut Renderer, targets: &[stereocull::renderer::DisplayTarget]| {
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, targets)
            .unwrap();
        stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap()
    };
    let mut live = stereocull::live::LiveScene::new(scene.clone());
    let mut renderer = Renderer::new(&gpu.device, live.scene(), &rig, options.clone()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let before = read(&mut renderer, &targets);

    let overridden = [1u32, 4];
    for h in live.handles() {
        if overridden.contains(&live.get(h).unwrap().mesh) {
            live.set_material(h, Some(b)).unwrap();
        }
    }
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    let after = read(&mut renderer, &targets);

    let mut reference = scene.clone();
    for &m in &overridden {
        let mesh = scene.meshes[m as usize].clone();
        let first = mesh.first_index as usize;
        for &i in &scene.indices[first..first + mesh.index_count as usize] {
            reference.vertices[(i as i32 + mesh.base_vertex) as usize].material = b;
        }
    }
    let want = render_all(&reference, &rig, options.clone()).remove(0);
    assert_ne!(after, before, "the overrides change the image");
    // Exact on any CPU: both materials are in one bin, so one compiled pipeline draws the
    // same draws in both; the fragment stage reads the same material index, from the
    // instance's record here and from the vertex there, and runs the same operations
    // on the same inputs.
    support::assert_images_match("overrides", &after, &want, Tolerance::EXACT);

    for h in live.handles() {
        live.set_material(h, None).unwrap();
    }
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    let cleared = read(&mut renderer, &targets);
    // Exact on any CPU: the same renderer, records and draws as `before`.
    support::assert_images_match("overrides cleared", &cleared, &before, Tolerance::EXACT);

    let h = live.handles()[0];
    let glass = live.scene().materials.len() as u32;
    let mut with_glass = live.scene().clone();
    with_glass.materials.push(Material {
        name: "glass".into(),
        alpha: AlphaMode::Blend,
        ..Default::default()
    });
    let mut live_glass = stereocull::live::LiveScene::new(with_glass.clone());
    let err = live_glass
        .set_material(h, Some(glass))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("\"glass\"") && err.contains("pipeline"),
        "{err}"
    );
    let err = live.set_material(h, Some(99)).unwrap_err().to_string();
    assert!(err.contains("material 99 of"), "{err}");
    with_glass.instances[0].material = Some(glass);
    let err = Renderer::new(&gpu.device, &with_glass, &rig, options)
        .err()
        .map(|e| e.to_string());
    assert!(
        err.is_some_and(|e| e.contains("\"glass\"")),
        "a renderer refuses it"
    );
}
