//! The draw pipelines' variants ([`DrawKey`]): views, clip distances or a clip
//! rectangle, multiview, the material bin's alpha mode and shading, MSAA's alpha to
//! coverage, and the source each composes from the shared includes.

use super::{
    BASE_COLOR, DRAW, DRAW_CLIP_DISTANCES, DRAW_CLIP_RECT, DRAW_COMMON, DRAW_FIRST_POSE,
    DRAW_MOTION, DRAW_MULTIVIEW, DRAW_NO_CLIP_DISTANCES, LIGHT_RECORDS, LIGHTS, MATERIAL_BINDINGS,
    MOTION, MOTION_BINDINGS, PBR, SHADOW_MAP_BINDINGS, TONEMAP, Windows, declarations,
    decode_source_with, light_constants,
};
use crate::bins::{Bin, BinKind};
use crate::scene::Shading;

/// Names a draw-pipeline variant; produces its source and a readable label.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DrawKey {
    /// 2: doubled instances into a double-wide target; 1: one view.
    pub views: u32,
    /// Hardware clip distances at the seam, or a fragment discard.
    pub clip_distances: bool,
    /// One view per instance into a two-layer target, the eye from `view_index`.
    pub multiview: bool,
    /// Views of their own sizes share the target (foveated): each is clipped at its
    /// viewport's four edges, not at one seam.
    pub viewports: bool,
    /// Multiview: the target's layers, one per view (2 for stereo, 4 foveated); 1
    /// otherwise.
    pub layers: u32,
    /// The material bin's state: opaque, cutout or blended ([`BinKind`]).
    pub alpha: BinKind,
    /// The material bin's shading function (its source comes with
    /// [`DrawKey::source_with`]).
    pub shading: Shading,
    /// A cutout under MSAA: alpha to coverage instead of a discard.
    pub coverage: bool,
    /// The material bin reads two sets of texture coordinates: a varying more.
    pub second_uv: bool,
    /// Writes each pixel's motion into a second target ([`crate::motion`]): the
    /// previous vertex as a second vertex buffer, the previous records as group 3, the
    /// previous clip position a varying more.
    pub motion: bool,
    /// Two frames per submission whose second frame is posed apart: the first frame's
    /// views read the first pose's records (group 3) and vertices (a second vertex
    /// buffer), copied before the second frame's edits and posing.
    pub first_pose: bool,
}

impl DrawKey {
    /// Every variant, for validation.
    pub const ALL: [DrawKey; 14] = [
        DrawKey::new(2, true),
        DrawKey::new(2, false),
        DrawKey::new(2, true).with_motion(true),
        DrawKey::new(2, false).with_motion(true),
        DrawKey::new(1, false).with_motion(true),
        DrawKey::new(4, true),
        DrawKey::new(4, false),
        DrawKey::new(4, true).with_first_pose(true),
        DrawKey::new(2, false).with_first_pose(true),
        DrawKey::placed(2, true),
        DrawKey::placed(2, false),
        DrawKey::new(1, false),
        DrawKey::MULTIVIEW,
        DrawKey::MULTIVIEW_QUAD,
    ];

    /// Multiview: one view per instance, the view index the eye.
    pub const MULTIVIEW: DrawKey = DrawKey {
        views: 1,
        clip_distances: false,
        multiview: true,
        viewports: false,
        layers: 2,
        alpha: BinKind::Opaque,
        shading: Shading::Lit,
        coverage: false,
        second_uv: false,
        motion: false,
        first_pose: false,
    };

    /// Multiview of a foveated display: four layers of one size, each view filling its
    /// layer (the same shader; the pipeline's view mask differs).
    pub const MULTIVIEW_QUAD: DrawKey = DrawKey {
        layers: 4,
        ..DrawKey::MULTIVIEW
    };

    /// The view mask of a multiview pipeline and its pass: one bit per layer.
    pub fn multiview_mask(self) -> Option<std::num::NonZeroU32> {
        match self.multiview {
            true => std::num::NonZeroU32::new((1 << self.layers) - 1),
            false => None,
        }
    }

    /// Back faces are culled (counter-clockwise is front, in world space: see
    /// [`crate::scene::Mesh`]), which halves the triangles that reach rasterization,
    /// except in multiview: lavapipe (Mesa 22.3) then drops front faces of the second
    /// view (the floor vanishes from the right eye in `every_stereo_mode_agrees_with_instanced`).
    pub fn face_culling(&self) -> Option<wgpu::Face> {
        (!self.multiview).then_some(wgpu::Face::Back)
    }

    /// The variant for `views` (1, 2, or 4 for foveated stereo) on a device with or
    /// without clip distances (one view never needs them).
    pub const fn new(views: u32, clip_distances_available: bool) -> DrawKey {
        DrawKey {
            views,
            clip_distances: views >= 2 && clip_distances_available,
            multiview: false,
            viewports: views == 4,
            layers: 1,
            alpha: BinKind::Opaque,
            shading: Shading::Lit,
            coverage: false,
            second_uv: false,
            motion: false,
            first_pose: false,
        }
    }

    /// This variant with or without motion vectors.
    pub const fn with_motion(self, motion: bool) -> DrawKey {
        DrawKey { motion, ..self }
    }

    /// This variant with or without the first pose of a two-frame submission.
    pub const fn with_first_pose(self, first_pose: bool) -> DrawKey {
        DrawKey { first_pose, ..self }
    }

    /// This variant for material bin `bin`, into a target of `samples` per pixel.
    pub fn with_bin(self, bin: Bin, samples: u32) -> DrawKey {
        DrawKey {
            alpha: bin.alpha,
            shading: bin.shading,
            coverage: bin.alpha == BinKind::Mask && samples > 1,
            second_uv: bin.second_uv,
            ..self
        }
    }

    /// The variants of every alpha state (cutouts with and without MSAA).
    pub fn alpha_variants(self) -> [DrawKey; 4] {
        let bin = |alpha| Bin {
            alpha,
            ..Bin::default()
        };
        [
            self,
            self.with_bin(bin(BinKind::Mask), 1),
            self.with_bin(bin(BinKind::Mask), 4),
            self.with_bin(bin(BinKind::Blend), 1),
        ]
    }

    /// `views` per visible object, each into its own viewport of a foveated target (two:
    /// the outer pair, or with the inset cull the inset pair, from their own cull).
    pub const fn placed(views: u32, clip_distances_available: bool) -> DrawKey {
        DrawKey {
            viewports: true,
            ..DrawKey::new(views, clip_distances_available)
        }
    }

    /// The pipeline's label.
    pub fn label(self) -> String {
        let alpha = match (self.alpha, self.coverage) {
            (BinKind::Opaque, _) => "",
            (BinKind::Mask, false) => ".mask",
            (BinKind::Mask, true) => ".mask.coverage",
            (BinKind::Blend, _) => ".blend",
        };
        let shading = match self.shading {
            Shading::Lit => String::new(),
            Shading::Unlit => ".unlit".into(),
            Shading::Hook(i) => format!(".hook{i}"),
            Shading::Own(i) => format!(".own{i}"),
        };
        let uvs = if self.second_uv { ".uv1" } else { "" };
        let motion = if self.motion { ".motion" } else { "" };
        let first = if self.first_pose { ".first_pose" } else { "" };
        format!("{}{alpha}{uvs}{motion}{first}{shading}", self.base_label())
    }

    fn base_label(self) -> String {
        let seam = if self.clip_distances {
            "clip"
        } else {
            "discard"
        };
        match (self.multiview, self.views) {
            (true, _) if self.layers == 4 => "stereocull.draw.multiview.quad".into(),
            (true, _) => "stereocull.draw.multiview".into(),
            (false, 1) => "stereocull.draw.mono".into(),
            (false, 4) => format!("stereocull.draw.foveated.{seam}"),
            _ if self.viewports => format!("stereocull.draw.placed.{seam}"),
            _ => format!("stereocull.draw.stereo.{seam}"),
        }
    }

    /// The variant's source with the built-in shading.
    pub fn source(self) -> String {
        self.source_with(None, &Windows::WHOLE)
    }

    /// The variant's source; `material` (WGSL defining `fn material(s: Surface) ->
    /// vec4<f32>`, see `wgsl/shared/draw_common.wgsl`: the key's shading function,
    /// [`super::UNLIT`] for [`Shading::Unlit`]) replaces the built-in shading.
    pub fn source_with(self, material: Option<&str>, windows: &Windows) -> String {
        let prelude = match (self.clip_distances, self.viewports) {
            (true, true) => DRAW_CLIP_RECT,
            (true, false) => DRAW_CLIP_DISTANCES,
            (false, _) => DRAW_NO_CLIP_DISTANCES,
        };
        let entry = match (self.multiview, self.motion, self.first_pose) {
            (true, _, _) => DRAW_MULTIVIEW,
            (false, true, _) => DRAW_MOTION,
            (false, false, true) => DRAW_FIRST_POSE,
            (false, false, false) => DRAW,
        };
        let alpha = format!(
            "const ALPHA_MODE: u32 = {}u;\nconst ALPHA_TO_COVERAGE: bool = {};\n",
            self.alpha.wgsl(),
            self.coverage
        );
        let shading = match material {
            Some(m) => format!(
                "{m}\nfn surface_color(s: Surface) -> vec4<f32> {{ return material(s); }}\n"
            ),
            None => "fn surface_color(s: Surface) -> vec4<f32> { return shade(s); }\n".into(),
        };
        let (location, accessors) = match self.second_uv {
            true => ("@location(3) uv1: vec2<f32>,", SECOND_UV_ON),
            false => ("", SECOND_UV_OFF),
        };
        let (motion_location, motion) = match (self.motion, self.first_pose) {
            (true, _) => (
                "@location(4) previous_clip: vec4<f32>,",
                motion_source(windows),
            ),
            (false, true) => ("", first_pose_source(windows)),
            (false, false) => ("", LIVE_COLOR.into()),
        };
        // The second coordinates' and the previous clip position's varyings, where the
        // variant has them, take their markers' lines in the vertex output and the
        // fragment input.
        let marked = |s: &str| {
            s.replace("// SECOND_UV", location)
                .replace("// MOTION", motion_location)
        };
        [
            &marked(prelude),
            &decode_source_with(self.views, windows),
            &alpha,
            accessors,
            &declarations(&MATERIAL_BINDINGS, 1, windows),
            BASE_COLOR,
            &declarations(&SHADOW_MAP_BINDINGS, 2, windows),
            &marked(DRAW_COMMON),
            TONEMAP,
            PBR,
            &light_constants(),
            LIGHT_RECORDS,
            LIGHTS,
            &shading,
            &motion,
            entry,
        ]
        .concat()
    }
}

/// Group 3 and the motion functions, for the variants with motion vectors.
fn motion_source(windows: &Windows) -> String {
    [
        &declarations(&MOTION_BINDINGS, 3, windows),
        MOTION,
        LIVE_COLOR,
    ]
    .concat()
}

/// Group 3 (the first frame's records) and the instance color of the first frame's
/// views from them, for the first-pose variants.
fn first_pose_source(windows: &Windows) -> String {
    let vacant = format!(
        "const VACANT_MESH: u32 = {}u;\n",
        crate::scene::Instance::VACANT_MESH
    );
    [
        &declarations(&MOTION_BINDINGS, 3, windows),
        FIRST_POSE_COLOR,
        &vacant,
    ]
    .concat()
}

/// The color of instance `id` as the fragment of view `eye` shades it: its record's.
const LIVE_COLOR: &str = "fn instance_color(id: u32, eye: u32) -> vec4<f32> {\n\
    return unpack4x8unorm(instances_at(id).color);\n}\n";
/// ... and where the first frame's views read a copy of the records: the second
/// frame's own recolors do not reach the first.
const FIRST_POSE_COLOR: &str = "fn instance_color(id: u32, eye: u32) -> vec4<f32> {\n\
    if (display.eye[eye].time_ahead > 0.0) {\n\
        return unpack4x8unorm(instances_at(id).color);\n\
    }\n\
    return unpack4x8unorm(previous_instances_at(id).color);\n}\n";

/// How the draw pipelines pass the second texture coordinates, in a bin that reads them.
const SECOND_UV_ON: &str = "const SECOND_UV: bool = true;\n\
    fn set_second_uv(out: ptr<function, VertexOutput>, d: Decoded) { (*out).uv1 = d.uv1; }\n\
    fn second_uv(in: FragmentInput) -> vec2<f32> { return in.uv1; }\n";
/// ... and in one that does not: no varying, zero coordinates.
const SECOND_UV_OFF: &str = "const SECOND_UV: bool = false;\n\
    fn set_second_uv(out: ptr<function, VertexOutput>, d: Decoded) {}\n\
    fn second_uv(in: FragmentInput) -> vec2<f32> { return vec2(0.0); }\n";
