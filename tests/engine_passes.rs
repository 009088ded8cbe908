//! Drawing into the caller's render passes, as an engine does: the culls recorded into
//! its encoder, each display drawn into a pass it began, with its own passes before
//! (a sky) and after (a UI panel) on the same targets.

mod support;

use std::num::NonZeroU32;
use std::sync::Arc;

use image::RgbaImage;
use stereocull::device::Gpu;
use stereocull::draw::CLEAR_COLOR;
use stereocull::readback::read_rgba8;
use stereocull::renderer::{DisplayTarget, OcclusionMode, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use stereocull::scene_spec;
use support::{Tolerance, assert_images_match, gpu, sized};

const SKY: wgpu::Color = wgpu::Color {
    r: 0.2,
    g: 0.4,
    b: 0.9,
    a: 1.0,
};

/// A pass on display `index`'s target: color cleared to `clear` or loaded, depth cleared.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &DisplayTarget,
    clear: Option<wgpu::Color>,
    multiview: bool,
) -> wgpu::RenderPass<'e> {
    let views = target.views();
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("engine"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: views.color,
            depth_slice: None,
            resolve_target: views.resolve,
            ops: wgpu::Operations {
                load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: views.depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: multiview.then(|| NonZeroU32::new(0b11)).flatten(),
    })
}

/// One frame drawn into the caller's passes: `before` (if any) clears each target to
/// the sky, then the display is drawn in a pass of the caller's (clearing to
/// stereocull's clear color unless the sky is there), then `after` runs on the encoder.
fn draw_in_engine_passes(
    gpu: &Gpu,
    (scene, rig): (&Scene, &Rig),
    options: RendererOptions,
    sky: bool,
    after: impl Fn(&mut wgpu::CommandEncoder, &DisplayTarget),
) -> Vec<RgbaImage> {
    let mode = options.mode;
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer.prepare(&gpu.queue, rig, 0.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    renderer.encode_culls(&mut encoder, None).unwrap();
    for (i, target) in targets.iter().enumerate() {
        let multiview = mode == StereoMode::Multiview && rig.displays[i].stereo;
        if sky {
            drop(begin(&mut encoder, target, Some(SKY), multiview));
        }
        let clear = (!sky).then_some(CLEAR_COLOR);
        let mut pass = begin(&mut encoder, target, clear, multiview);
        assert!(renderer.draw_display(&mut pass, i).unwrap() > 0);
        drop(pass);
        after(&mut encoder, target);
    }
    gpu.queue.submit([encoder.finish()]);
    targets
        .iter()
        .map(|t| read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap())
        .collect()
}

/// In a pass of the caller's, every mode draws what its own `encode` draws, on stereo
/// and mono displays (multi-pass and multi-camera draw both eyes in turn in the one
/// pass), with and without MSAA.
#[test]
fn every_mode_draws_into_the_callers_pass_what_it_draws_itself() {
    let gpu = gpu();
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd-peripheral", 96, 80);
    for samples in [1, 4] {
        for mode in StereoMode::ALL {
            let cull = support::cull_for(mode);
            let options = RendererOptions {
                cull,
                mode,
                sample_count: samples,
                ..Default::default()
            };
            let own = support::render(&gpu, &scene, &rig, options.clone()).unwrap();
            let engine =
                draw_in_engine_passes(&gpu, (&scene, &rig), options.clone(), false, |_, _| {});
            for (d, (a, b)) in engine.iter().zip(&own).enumerate() {
                let name = format!("engine-pass-{}-{d}-msaa{samples}", mode.name());
                // Exact on any CPU: the same pipelines draw the same draws; only the pass
                // that hosts them is the caller's.
                assert_images_match(&name, a, b, Tolerance::EXACT);
            }
        }
    }
}

/// With the far layer and occlusion, a pass of the caller's (the frustum's cull, the
/// far layer culled by its frustum and composited first) draws what the renderer's
/// own passes draw (the far layer culled against the pyramids, composited in the late
/// draw), over two frames so that the second has an early phase.
#[test]
fn the_far_layer_with_occlusion_draws_alike_in_the_callers_pass() {
    let gpu = gpu();
    let scene = scene_spec::load("city:3000").unwrap();
    let rig = sized("hmd", 96, 80);
    let options = RendererOptions {
        far_layer: true,
        occlusion: OcclusionMode::On,
        ..Default::default()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options.clone()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    for _ in 0..2 {
        (renderer.submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)).unwrap();
    }
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    let split = diagnostics.far_split().unwrap()[0].expect("a far layer");
    assert!(split.far > 0 && split.near > 0, "{split:?}");
    let own = read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    let engine = draw_in_engine_passes(&gpu, (&scene, &rig), options, false, |_, _| {});
    // Exact on any CPU: the same pipelines draw the same surfaces; the composite wins
    // the same ties in either order (see src/renderer/display/far_layer.rs), and what occlusion dropped is
    // hidden.
    assert_images_match(
        "engine-pass-far-occlusion",
        &engine[0],
        &own,
        Tolerance::EXACT,
    );
}

/// A sky pass before and a UI panel after, on the same targets: the sky shows where
/// nothing is drawn, the scene where it is, and the panel over both.
#[test]
fn engine_passes_before_and_after_share_the_targets() {
    let gpu = gpu();
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd", 120, 100);
    let options = RendererOptions::default();
    let plain = support::render(&gpu, &scene, &rig, options.clone())
        .unwrap()
        .remove(0);
    let ui = UiPanel::new(&gpu.device, options.color_format);
    let panel = (10, 10, 40, 20);
    let framed = draw_in_engine_passes(
        &gpu,
        (&scene, &rig),
        options.clone(),
        true,
        |encoder, target| ui.draw(encoder, target, panel),
    )
    .remove(0);
    let background = *plain.get_pixel(0, 0);
    let sky = *framed.get_pixel(plain.width() - 1, 0);
    assert_ne!(sky, background, "the sky pass shows");
    let (mut scene_px, mut sky_px) = (0, 0);
    for (x, y, p) in framed.enumerate_pixels() {
        let in_panel =
            (panel.0..panel.0 + panel.2).contains(&x) && (panel.1..panel.1 + panel.3).contains(&y);
        let want = match (in_panel, *plain.get_pixel(x, y) == background) {
            (true, _) => image::Rgba(UiPanel::COLOR_SRGB),
            (false, true) => sky,
            (false, false) => *plain.get_pixel(x, y),
        };
        assert_eq!(*p, want, "pixel ({x}, {y}), panel {in_panel}");
        if !in_panel {
            if want == sky {
                sky_px += 1
            } else {
                scene_px += 1
            }
        }
    }
    assert!(
        scene_px > 1000 && sky_px > 1000,
        "scene {scene_px} px, sky {sky_px} px"
    );
}

/// The engine's own pipeline: a solid panel, scissored to a rectangle.
struct UiPanel {
    pipeline: wgpu::RenderPipeline,
}

impl UiPanel {
    /// (255, 128, 0) in sRGB: what the linear color below stores in an sRGB target.
    const COLOR_SRGB: [u8; 4] = [255, 128, 0, 255];

    fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> UiPanel {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ui"),
            source: wgpu::ShaderSource::Wgsl(
                "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
                     let p = vec2(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0);
                     return vec4(p, 0.0, 1.0);
                 }
                 @fragment fn fs() -> @location(0) vec4<f32> {
                     return vec4(1.0, 0.21586050, 0.0, 1.0);
                 }"
                .into(),
            ),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ui"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        UiPanel { pipeline }
    }

    fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &DisplayTarget,
        (x, y, w, h): (u32, u32, u32, u32),
    ) {
        let view = target.views().resolve.unwrap_or(target.views().color);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ui"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_scissor_rect(x, y, w, h);
        pass.draw(0..3, 0..1);
    }
}

/// Bring your own pipeline: a pipeline written here, on stereocull's decode
/// (`Renderer::decode_source`) and group 0 layout, drawing the cull outputs with the one
/// indirect call, gives the built-in pipelines' image with a hook of the same shading
/// ([`LIT`]: the own pipeline has no materials to read). Both keep the eyes apart by a
/// fragment discard here (clip distances off).
#[test]
fn a_pipeline_of_the_callers_own_draws_the_built_in_image() {
    let gpu = support::gpu_with(wgpu::Features::all() - wgpu::Features::CLIP_DISTANCES);
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd", 120, 100);
    let hook = "fn material(s: Surface) -> vec4<f32> { return lit(s.world_position, s.normal, s.color, s.eye); }";
    let options = RendererOptions {
        material: Some(format!("{LIT}\n{hook}").into()),
        ..Default::default()
    };
    let built_in = support::render(&gpu, &scene, &rig, options.clone())
        .unwrap()
        .remove(0);

    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options.clone()).unwrap();
    let pipeline = own_pipeline(&gpu.device, &renderer, options);
    let targets = renderer.create_targets(&gpu.device);
    renderer.prepare(&gpu.queue, &rig, 0.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    renderer.encode_culls(&mut encoder, None).unwrap();
    let mut pass = begin(&mut encoder, &targets[0], Some(CLEAR_COLOR), false);
    pass.set_pipeline(&pipeline);
    renderer
        .draw_display_with_own_pipeline(&mut pass, 0)
        .unwrap();
    drop(pass);
    gpu.queue.submit([encoder.finish()]);
    let own = read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    assert_images_match("own-pipeline", &own, &built_in, Tolerance::RECOMPILED);
    assert!(
        own.pixels().any(|p| *p != *own.get_pixel(0, 0)),
        "something is drawn"
    );
}

/// A flat material by eye: the left eye red, the right green.
const BY_EYE: &str = "
    fn material(s: Surface) -> vec4<f32> {
        return select(vec4(1.0, 0.0, 0.0, 1.0), vec4(0.0, 1.0, 0.0, 1.0), s.eye == 1u);
    }";

/// A shading of one light's diffuse plus specular from the eye (the built-in shading
/// before it read glTF's materials).
const LIT: &str = "
    fn lit(world: vec3<f32>, normal: vec3<f32>, color: vec4<f32>, eye: u32) -> vec4<f32> {
        let light = vec3(0.37139068, 0.74278135, 0.55708601);
        let to_eye = normalize(display.eye[eye].position - world);
        var n = normalize(normal);
        if (dot(n, to_eye) < 0.0) {
            n = -n;
        }
        let diffuse = max(dot(n, light), 0.0);
        let specular = 0.3 * pow(max(dot(n, normalize(light + to_eye)), 0.0), 48.0);
        return vec4(color.rgb * (0.25 + 0.75 * diffuse) + vec3(specular), 1.0);
    }";

/// The test's own stereo pipeline: stereocull's decode, then shading written here.
fn own_pipeline(
    device: &wgpu::Device,
    renderer: &Renderer,
    options: RendererOptions,
) -> wgpu::RenderPipeline {
    let source = renderer.decode_source(2).expect("the indirect modes")
        + "
        struct Out {
            @builtin(position) position: vec4<f32>,
            @location(0) world: vec3<f32>,
            @location(1) normal: vec3<f32>,
            @location(2) color: vec4<f32>,
            @location(3) @interpolate(flat) eye: u32,
        }
        @vertex fn vs(v: VertexInput, @builtin(instance_index) i: u32) -> Out {
            let at = decode_instance(i, VIEWS);
            let d = decode(v, at.x, at.y, true);
            return Out(d.clip, d.world_position, d.world_normal, d.color, d.eye);
        }
        @fragment fn fs(in: Out) -> @location(0) vec4<f32> {
            if ((in.position.x < display.resolution.x) != (in.eye == 0u)) {
                discard;
            }
            return lit(in.world, in.normal, in.color, in.eye);
        }"
        + LIT;
    let layouts = [renderer.bind_group_layout()];
    stereo_pipeline(device, (&source, &layouts), &options, None)
}

/// A pipeline of the test's own on `source` (entry points `vs` and `fs`) and
/// `group_layouts` (stereocull's group 0 first), into the targets `options` describe,
/// depth-tested, culling `cull_mode`.
fn stereo_pipeline(
    device: &wgpu::Device,
    (source, group_layouts): (&str, &[Option<&wgpu::BindGroupLayout>]),
    options: &RendererOptions,
    cull_mode: Option<wgpu::Face>,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("own"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("own"),
        bind_group_layouts: group_layouts,
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("own"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(stereocull::draw::VERTEX_BUFFER)],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: options.depth_format,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(options.color_format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The material hook: a caller's WGSL `material` compiled into every mode's pipeline.
/// The built-in shading composed from the parts a hook may call (`pbr_inputs`,
/// `pbr_shade`) gives the built-in image; a material that paints by eye paints exactly
/// the two halves (left red, right green).
#[test]
fn a_material_hook_shades_every_mode() {
    let same_as_built_in: Arc<str> =
        "fn material(s: Surface) -> vec4<f32> { return pbr_shade(s, pbr_inputs(s)); }".into();
    let gpu = gpu();
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd", 120, 100);
    for mode in StereoMode::ALL {
        let cull = support::cull_for(mode);
        let with = |material| RendererOptions {
            cull,
            mode,
            material,
            ..Default::default()
        };
        let draw = |options: RendererOptions| {
            support::render(&gpu, &scene, &rig, options)
                .unwrap()
                .remove(0)
        };
        let built_in = draw(with(None));
        let name = format!("material-{}", mode.name());
        assert_images_match(
            &name,
            &draw(with(Some(same_as_built_in.clone()))),
            &built_in,
            Tolerance::RECOMPILED,
        );
        let by_eye = draw(with(Some(BY_EYE.into())));
        let background = *built_in.get_pixel(0, 0);
        let half = by_eye.width() / 2;
        let mut painted = [0, 0];
        for (x, y, p) in by_eye.enumerate_pixels() {
            let eye = usize::from(x >= half);
            let drawn = *built_in.get_pixel(x, y) != background;
            let want = match (drawn, eye) {
                (false, _) => background,
                (true, 0) => image::Rgba([255, 0, 0, 255]),
                (true, _) => image::Rgba([0, 255, 0, 255]),
            };
            assert_eq!(*p, want, "{name}: pixel ({x}, {y})");
            painted[eye] += usize::from(drawn);
        }
        assert!(
            painted[0] > 1000 && painted[1] > 1000,
            "{name}: {painted:?}"
        );
    }
}

/// MSAA antialiases: with a flat material (left eye red, right eye green) the 1x image
/// holds only the background and the two flat colors, while at 4x the edges blend into
/// intermediate values.
#[test]
fn msaa_blends_edges_that_1x_leaves_hard() {
    let gpu = gpu();
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd", 120, 100);
    let blended = |sample_count| {
        let options = RendererOptions {
            sample_count,
            material: Some(BY_EYE.into()),
            ..Default::default()
        };
        let image = support::render(&gpu, &scene, &rig, options.clone())
            .unwrap()
            .remove(0);
        let flat = [
            *image.get_pixel(0, 0),
            image::Rgba([255, 0, 0, 255]),
            image::Rgba([0, 255, 0, 255]),
        ];
        image.pixels().filter(|p| !flat.contains(p)).count()
    };
    assert_eq!(blended(1), 0, "1x has hard edges");
    let at_4x = blended(4);
    eprintln!("4x: {at_4x} edge pixels blended");
    assert!(
        at_4x > 100,
        "4x blends edges: {at_4x} pixels (199 on lavapipe)"
    );
}

/// Materials drawn by pipelines of the caller's own (`Shading::Own`): each is its own
/// bin, one multi-draw per display, drawn by the caller's pipeline with its own bind
/// group (a flat color from a uniform in group 1), in the renderer's own passes and,
/// with occlusion, in both phases; the same image as hooks that return those colors.
/// The scene's cutout bin follows the own bins, so the built-in groups must be bound
/// again after them (wgpu refuses the draw otherwise).
#[test]
fn materials_of_the_callers_own_pipelines_draw_as_hooks_of_theirs_would() {
    use stereocull::scene::{AlphaMode, Shading};
    let gpu = support::gpu_with(wgpu::Features::all() - wgpu::Features::CLIP_DISTANCES);
    let rig = sized("hmd", 120, 100);
    // Pure channels: the same bytes in a linear and an sRGB target.
    let colors = [[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
    let mut scene = support::with_random_bins(stereocull::procedural::scene(600, 10, 29), 29);
    let kinds = [
        (AlphaMode::Opaque, Shading::Lit),
        (AlphaMode::Mask { cutoff: 0.3 }, Shading::Lit),
        (AlphaMode::Opaque, Shading::Own(0)),
        (AlphaMode::Opaque, Shading::Own(1)),
        (AlphaMode::Blend, Shading::Lit),
    ];
    for (m, (alpha, shading)) in scene.materials.iter_mut().zip(kinds) {
        (m.alpha, m.shading) = (alpha, shading);
    }
    let bins = stereocull::bins::Bins::of(&scene).kinds;
    assert_eq!(bins.len(), 5);
    assert_eq!(
        bins[3].shading,
        Shading::Lit,
        "a built-in bin after the own ones"
    );

    let hooks: Vec<Arc<str>> = colors.iter().map(|&c| flat_color(c).into()).collect();
    let mut hooked = scene.clone();
    for m in &mut hooked.materials {
        if let Shading::Own(i) = m.shading {
            m.shading = Shading::Hook(i);
        }
    }
    let options = RendererOptions {
        hooks,
        shadows: true,
        ..support::frustum_only()
    };
    let want = support::render(&gpu, &hooked, &rig, options.clone())
        .unwrap()
        .remove(0);
    for occlusion in [false, true] {
        use stereocull::renderer::OcclusionMode;
        let options = RendererOptions {
            occlusion: [OcclusionMode::Off, OcclusionMode::On][usize::from(occlusion)],
            ..options.clone()
        };
        let (got, draw_calls) = render_with_own(&gpu, (&scene, &rig), options, &colors);
        let name = format!("own-bins-occlusion-{occlusion}");
        assert_images_match(&name, &got, &want, Tolerance::RECOMPILED);
        let painted = |c: [f32; 3]| {
            got.pixels()
                .any(|p| p.0[..3] == c.map(|x| (x * 255.0f32).round() as u8))
        };
        assert!(
            colors.into_iter().all(painted),
            "{name}: both own pipelines paint"
        );
        // Per bin and phase one multi-draw, and the shadow pass's of every bin but glass.
        let phases = if occlusion { 2 } else { 1 };
        assert_eq!(draw_calls, 5 * phases + 4, "{name}: one multi-draw per bin");
    }

    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options.clone()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let err = renderer.submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets);
    let err = err.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("Shading::Own(0)"), "no pipeline set: {err}");
    let classic = RendererOptions {
        mode: StereoMode::MultiPass,
        cull: stereocull::renderer::CullMode::Cpu,
        ..options
    };
    let err = Renderer::new(&gpu.device, &scene, &rig, classic).err();
    let err = err.map(|e| e.to_string()).unwrap_or_default();
    assert!(
        err.contains("material \"material 2\"") && err.contains("multi-pass"),
        "{err}"
    );
}

/// A material function painting one flat color.
fn flat_color([r, g, b]: [f32; 3]) -> String {
    format!("fn material(s: Surface) -> vec4<f32> {{ return vec4({r:?}, {g:?}, {b:?}, 1.0); }}")
}

/// One frame of `scene` with display 0's `Shading::Own(i)` drawn by a flat pipeline of
/// `colors[i]`; its image and draw calls.
fn render_with_own(
    gpu: &Gpu,
    (scene, rig): (&Scene, &Rig),
    options: RendererOptions,
    colors: &[[f32; 3]],
) -> (RgbaImage, u32) {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options.clone()).unwrap();
    for (i, &color) in colors.iter().enumerate() {
        let own = flat_pipeline(&gpu.device, &renderer, &options, color);
        renderer.set_own_pipeline(0, i as u32, own).unwrap();
    }
    let targets = renderer.create_targets(&gpu.device);
    let stats = renderer.submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets);
    let draw_calls = stats.unwrap().draw_calls;
    let image = read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    (image, draw_calls)
}

/// The caller's stereo pipeline for an own bin: stereocull's decode, back faces culled
/// as the built-in pipelines cull them, the eyes kept apart by a discard, and the color
/// read from a uniform of its own group 1.
fn flat_pipeline(
    device: &wgpu::Device,
    renderer: &Renderer,
    options: &RendererOptions,
    color: [f32; 3],
) -> stereocull::draw::OwnPipeline {
    use wgpu::util::DeviceExt;
    let source = renderer.decode_source(2).expect("the indirect modes")
        + "
        @group(1) @binding(0) var<uniform> flat: vec4<f32>;
        struct Out {
            @builtin(position) position: vec4<f32>,
            @location(0) @interpolate(flat) eye: u32,
        }
        @vertex fn vs(v: VertexInput, @builtin(instance_index) i: u32) -> Out {
            let at = decode_instance(i, VIEWS);
            let d = decode(v, at.x, at.y, true);
            return Out(d.clip, d.eye);
        }
        @fragment fn fs(in: Out) -> @location(0) vec4<f32> {
            if ((in.position.x < display.resolution.x) != (in.eye == 0u)) {
                discard;
            }
            return flat;
        }";
    let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("flat"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    });
    let [r, g, b] = color;
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("flat"),
        contents: bytemuck::cast_slice(&[r, g, b, 1.0f32]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("flat"),
        layout: &group_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    let layouts = [renderer.bind_group_layout(), Some(&group_layout)];
    let pipeline = stereo_pipeline(device, (&source, &layouts), options, Some(wgpu::Face::Back));
    stereocull::draw::OwnPipeline {
        pipeline,
        bind_groups: vec![group],
    }
}
