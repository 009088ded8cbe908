//! Each program in `examples/` run headless for a few frames, as an embedder would start
//! from it: the examples are compiled into this test, so a change that breaks one fails
//! here, not only in `cargo build --examples`.

#[allow(dead_code)]
#[path = "../examples/own_device.rs"]
mod own_device;

#[allow(dead_code)]
#[path = "../examples/live_scene.rs"]
mod live_scene;

#[allow(dead_code)]
#[path = "../examples/engine_pass.rs"]
mod engine_pass;

use image::Rgba;

/// Pixels of `image` other than its top-left one (the clear color, looking at the sky
/// or the background).
fn drawn(image: &image::RgbaImage) -> usize {
    let clear = *image.get_pixel(0, 0);
    image.pixels().filter(|p| **p != clear).count()
}

#[test]
fn own_device_draws_the_room_into_the_engines_textures() {
    let image = own_device::run(3).unwrap();
    assert_eq!(image.dimensions(), (320, 120), "both eyes side by side");
    assert!(
        drawn(&image) > 320 * 120 / 4,
        "{} pixels drawn",
        drawn(&image)
    );
}

#[test]
fn live_scene_moves_every_tenth_instance_each_frame() {
    let syncs = live_scene::run(3).unwrap();
    assert_eq!(syncs.len(), 3);
    for (frame, sync) in syncs.iter().enumerate() {
        assert_eq!(sync.moved, 200, "frame {frame}");
        assert!(!sync.reallocated, "frame {frame}: moves never reallocate");
        assert!(sync.bytes_uploaded >= 200 * 56, "frame {frame}");
    }
}

#[test]
fn engine_pass_draws_between_the_engines_sky_and_what_follows() {
    let image = engine_pass::run(2).unwrap();
    // The clear color is linear; the sRGB target stores it encoded.
    let sky = |c: f64| (255.0 * (1.055 * c.powf(1.0 / 2.4) - 0.055)).round();
    let sky_pixels = image
        .pixels()
        .filter(|p| {
            let want = [engine_pass::SKY.r, engine_pass::SKY.g, engine_pass::SKY.b].map(sky);
            (0..3).all(|c| (p[c] as f64 - want[c]).abs() <= 1.0)
        })
        .count();
    let total = (image.width() * image.height()) as usize;
    assert!(
        sky_pixels > 0,
        "the engine's sky shows where nothing is drawn"
    );
    assert!(sky_pixels < total, "the room is drawn over it");
    // The per-eye tint: the left half leans red, the right half blue.
    let lean = |x0: u32| {
        let (mut r, mut b) = (0i64, 0i64);
        for y in 0..image.height() {
            for x in x0..x0 + image.width() / 2 {
                let Rgba([pr, _, pb, _]) = *image.get_pixel(x, y);
                (r, b) = (r + pr as i64, b + pb as i64);
            }
        }
        r - b
    };
    assert!(lean(0) > lean(image.width() / 2), "the eyes' tints differ");
}
