//! The frame's plan as plain data, built and inspected without a device: which culls a
//! frame runs for each mode and rig, with which frusta, splits and instance counts, and
//! what the frame decides once for all of them.

use stereocull::cull::CoarseCull;
use stereocull::far_layer;
use stereocull::renderer::{CullMode, CullView, FramePlan, RendererOptions, StereoMode};
use stereocull::rig::Rig;

fn plan(preset: &str, options: &RendererOptions, coarse: bool) -> FramePlan {
    let rig = Rig::preset(preset).unwrap();
    FramePlan::new(&rig, options, coarse, 0.25).unwrap()
}

fn mode(mode: StereoMode) -> RendererOptions {
    RendererOptions {
        mode,
        cull: match mode.per_instance() {
            true => CullMode::Cpu,
            false => CullMode::Gpu,
        },
        ..RendererOptions::default()
    }
}

#[test]
fn instanced_culls_each_display_once_for_both_eyes_as_the_reference_does() {
    for preset in ["hmd", "cave", "hmd-peripheral"] {
        let rig = Rig::preset(preset).unwrap();
        let plan = plan(preset, &RendererOptions::default(), false);
        let views: Vec<_> = plan.culls().iter().map(|c| c.view).collect();
        let displays: Vec<_> = (0..rig.displays.len()).map(CullView::Display).collect();
        assert_eq!(views, displays, "{preset}");
        assert_eq!(plan.jobs(), rig.cull_jobs().unwrap(), "{preset}");
        for (d, display) in rig.displays.iter().zip(&plan.displays) {
            assert_eq!(display.context.instances_per_object, d.views(), "{preset}");
        }
        assert_eq!(plan.light_cull, None, "no shadows, no light cull");
        assert!(plan.displays.iter().all(|d| d.far.is_none()));
        assert_eq!(plan.frame.time, 0.25);
    }
}

#[test]
fn multi_camera_culls_each_eye_of_a_stereo_display_against_its_own_frustum() {
    let culls = plan("hmd-peripheral", &mode(StereoMode::MultiCamera), false).culls();
    let views: Vec<_> = culls.iter().map(|c| c.view).collect();
    assert_eq!(
        views,
        [
            CullView::Eye(0, 0),
            CullView::Eye(0, 1),
            CullView::Display(1),
            CullView::Display(2)
        ]
    );
    let rig = Rig::preset("hmd-peripheral").unwrap().resolve().unwrap();
    let eyes = &rig.displays[0].eyes;
    assert_eq!(culls[0].job.planes, eyes[0].frustum().planes);
    assert_eq!(culls[1].job.planes, eyes[1].frustum().planes);
    assert_ne!(culls[0].job.planes, culls[1].job.planes);
    assert!(culls.iter().all(|c| c.job.instances_per_object == 1));
}

#[test]
fn only_instanced_doubles_the_instances_of_a_stereo_display() {
    for (m, doubled) in [
        (StereoMode::Instanced, 2),
        (StereoMode::Multiview, 1),
        (StereoMode::SinglePass, 1),
        (StereoMode::MultiPass, 1),
    ] {
        let plan = plan("hmd", &mode(m), false);
        assert_eq!(plan.culls()[0].job.instances_per_object, doubled, "{m:?}");
        let context = &plan.displays[0].context;
        assert_eq!(context.instances_per_object, doubled, "{m:?}");
    }
}

#[test]
fn the_far_layer_splits_each_stereo_display_and_adds_its_far_cull() {
    let options = RendererOptions {
        far_layer: true,
        ..RendererOptions::default()
    };
    let rig = Rig::preset("hmd-peripheral").unwrap();
    let plan = plan("hmd-peripheral", &options, false);
    let resolved = rig.resolve().unwrap();
    let want = far_layer::plans(&rig, &resolved, options.far_threshold_px);
    let planned: Vec<_> = plan.displays.iter().map(|d| d.far).collect();
    assert_eq!(planned, want);
    let far = planned[0].expect("the stereo display has a far plan");
    assert!(planned[1].is_none() && planned[2].is_none(), "mono panels");
    let culls = plan.culls();
    let views: Vec<_> = culls.iter().map(|c| c.view).collect();
    assert_eq!(
        views,
        [
            CullView::Display(0),
            CullView::Display(1),
            CullView::Display(2),
            CullView::Far(0)
        ]
    );
    assert_eq!(culls[0].job.split, Some(far.split(false)));
    assert_eq!(culls[1].job.split, None);
    assert_eq!(culls[3].job.split, Some(far.split(true)));
    assert_eq!(culls[3].job.instances_per_object, 1, "drawn once");
    assert_eq!(plan.displays[0].context.split_keep, 1);
    assert_eq!(plan.displays[0].context.split_distance, far.distance);
    assert_eq!(plan.displays[1].context.split_keep, 0);
}

#[test]
fn the_coarse_cull_and_the_light_are_decided_once_for_the_frame() {
    let shadows = RendererOptions {
        shadows: true,
        ..RendererOptions::default()
    };
    let on = plan("cave", &shadows, true);
    let off = plan("cave", &shadows, false);
    assert!(on.cull.coarse.is_some() && off.cull.coarse.is_none());
    assert_eq!(off.frame.coarse_planes, CoarseCull::EVERYTHING.planes);
    assert_eq!(on.frame.shadows, 1);
    let light = on.light_cull.clone().expect("shadows cull the light");
    assert_eq!(light.view, CullView::Light);
    assert_eq!(light.job, on.light.cull_job());
    assert_eq!(
        light.view.coarse_slot(),
        None,
        "the light never takes blocks"
    );
    assert_eq!(
        on.culls(),
        off.culls(),
        "the coarse cull changes work, not culls"
    );
}

/// Without a shadow map the light's box is not fitted (nothing reads it), yet it
/// shades alike: its direction is the fitted one's, bit for bit, for any light.
#[test]
fn without_shadows_the_light_keeps_its_direction_and_skips_the_fit() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    for _ in 0..32 {
        let mut options = RendererOptions::default();
        let d = [0; 3].map(|_| rng.random_range(-1.0f32..1.0));
        options.light.direction = glam::Vec3::from(d) * rng.random_range(0.1f32..4.0);
        let off = plan("cave", &options, false);
        options.shadows = true;
        let on = plan("cave", &options, false);
        assert_eq!(off.light.direction, on.light.direction, "{d:?}");
        assert_eq!(off.frame.light_direction, on.frame.light_direction);
        assert_eq!(off.light.clip_from_world, glam::Mat4::IDENTITY);
        assert_ne!(on.light.clip_from_world, glam::Mat4::IDENTITY);
        assert_eq!(off.frame.shadows, 0);
    }
}

#[test]
fn lod_scales_with_the_sharpest_display_and_is_off_by_default() {
    let off = plan("hmd", &RendererOptions::default(), false);
    let lod = RendererOptions {
        lod: true,
        ..RendererOptions::default()
    };
    let on = plan("hmd", &lod, false);
    assert_eq!(off.cull.lod.levels, 1);
    assert!(on.cull.lod.levels > 1);
    assert!(on.frame.lod_scale > 0.0);
    assert_eq!(on.frame.lod_scale, on.cull.lod.lod_scale);
}

#[test]
fn a_plan_of_a_bad_pose_is_an_error() {
    let mut rig = Rig::preset("hmd").unwrap();
    rig.viewer.position = [f32::NAN, 0.0, 0.0];
    assert!(FramePlan::new(&rig, &RendererOptions::default(), false, 0.0).is_err());
}

/// A subset of a rig's displays is planned as the whole rig: the frame's decisions
/// (level-of-detail density, the light's fit, the frame frustum) and each drawn
/// display's context and culls are the full plan's.
#[test]
fn a_subset_is_planned_as_the_whole_rig() {
    let options = RendererOptions {
        lod: true,
        shadows: true,
        far_layer: true,
        ..RendererOptions::default()
    };
    for (preset, names) in [
        ("hmd-peripheral", vec!["peripheral-left"]),
        ("cave", vec!["front", "floor"]),
    ] {
        let rig = Rig::preset(preset).unwrap();
        let names: Vec<String> = names.into_iter().map(String::from).collect();
        let subset = rig.subset(&names, preset).unwrap();
        let full = FramePlan::new(&rig, &options, true, 0.5).unwrap();
        let part = FramePlan::new(&subset, &options, true, 0.5).unwrap();
        assert_eq!(part.frame, full.frame, "{preset}");
        assert_eq!(part.light, full.light, "{preset}");
        assert_eq!(part.cull.lod, full.cull.lod, "{preset}");
        for (k, d) in subset.displays.iter().enumerate() {
            let i = rig.displays.iter().position(|x| x.name == d.name).unwrap();
            // The coarse cull's slot is the drawn display's index in this process.
            let mut expected = full.displays[i].context;
            expected.cull_slot = k as u32;
            assert_eq!(part.displays[k].context, expected, "{preset} {}", d.name);
            assert_eq!(
                part.displays[k].far, full.displays[i].far,
                "{preset} {}",
                d.name
            );
        }
        // Drawn alone, without the rest of the rig, the side panel would decide otherwise.
        let mut alone = subset.clone();
        alone.frame_only.clear();
        let lone = FramePlan::new(&alone, &options, true, 0.5).unwrap();
        assert_ne!(
            lone.frame, full.frame,
            "{preset}: the test must be able to fail"
        );
    }
}

#[test]
fn a_subset_naming_no_display_of_the_rig_is_an_error() {
    let rig = Rig::preset("cave").unwrap();
    let names = |n: &[&str]| n.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    for (bad, expected) in [
        (
            names(&["front", "back"]),
            "no display \"back\" (it has front, left, right, floor, ceiling)",
        ),
        (names(&["left", "left"]), "\"left\" named twice"),
        (names(&[]), "at least one"),
    ] {
        let message = rig.subset(&bad, "cave").unwrap_err().to_string();
        assert!(
            message.contains(expected) && message.contains("cave"),
            "{message}"
        );
    }
}
