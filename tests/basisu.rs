//! `KHR_texture_basisu`: KTX2 files with Basis Universal texels that KTX-Software wrote
//! (`tests/data/ktx2/SOURCES.md`), decoded to RGBA8, checked against the PNG they were
//! encoded from and against each other; then in a glTF file, loaded and drawn.

use std::path::PathBuf;

use image::RgbaImage;
use stereocull::basisu;

mod support;

fn data(name: &str) -> Vec<u8> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/ktx2")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn decode(name: &str) -> RgbaImage {
    basisu::decode(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Per channel, the mean absolute difference of two images of one size.
fn mean_difference(a: &RgbaImage, b: &RgbaImage) -> [f64; 4] {
    assert_eq!(a.dimensions(), b.dimensions());
    let mut sum = [0u64; 4];
    for (p, q) in a.pixels().zip(b.pixels()) {
        for c in 0..4 {
            sum[c] += u64::from(p[c].abs_diff(q[c]));
        }
    }
    sum.map(|s| s as f64 / f64::from(a.width() * a.height()))
}

/// One image encoded by KTX-Software both ways, ETC1S (BasisLZ) and UASTC (Zstandard),
/// decodes to nearly the same texels (measured: under 0.4 levels apart on average; a
/// misplaced slice or codebook would be noise), transparent corners included: both
/// files' alpha is read.
#[test]
fn etc1s_and_uastc_encodings_of_one_image_decode_alike() {
    let etc1s = decode("ktx_document_basis.ktx2");
    let uastc = decode("ktx_document_uastc_rdo4_zstd5.ktx2");
    assert_eq!(etc1s.dimensions(), (1024, 1024));
    let mean = mean_difference(&etc1s, &uastc);
    assert!(mean.iter().all(|&m| m < 2.0), "mean differences {mean:?}");
    for image in [&etc1s, &uastc] {
        assert_eq!(image.get_pixel(0, 0).0, [0; 4], "a transparent corner");
        assert_eq!(image.get_pixel(500, 800).0, [255; 4], "the white page");
        let blue = image.get_pixel(530, 540).0;
        assert!(
            blue[2] > 2 * blue[0] && blue[3] == 255,
            "the blue logo: {blue:?}"
        );
    }
}

/// ETC1S keeps alpha in a second slice: the decoded texels match the PNG the file was
/// encoded from (alpha 128, which a skipped alpha slice would read as 255).
#[test]
fn the_alpha_slice_is_read() {
    let png = image::load_from_memory(&data("alpha_simple.png"))
        .unwrap()
        .to_rgba8();
    let decoded = decode("alpha_simple_basis.ktx2");
    let mean = mean_difference(&decoded, &png);
    assert!(mean.iter().all(|&m| m <= 1.0), "mean differences {mean:?}");
    assert!(decoded.pixels().all(|p| p[3] == 128));
}

/// UASTC stored raw (no supercompression) decodes to the same texels as the Zstandard
/// file it was inflated from.
#[test]
fn raw_uastc_decodes_as_its_zstandard_original() {
    let original = data("ktx_document_uastc_rdo4_zstd5.ktx2");
    let raw = support::ktx2::inflated(&original);
    assert!(raw.len() > 2 * original.len(), "the levels were inflated");
    assert_eq!(
        basisu::decode(&raw).unwrap(),
        decode("ktx_document_uastc_rdo4_zstd5.ktx2")
    );
}

/// A KTX2 that is not Basis Universal is an error that says so; cut or damaged files
/// are errors (or, for damaged texels, images), never a crash.
#[test]
fn other_or_damaged_ktx2_files_are_errors() {
    let mut rgba = data("alpha_simple_basis.ktx2");
    rgba[12..16].copy_from_slice(&43u32.to_le_bytes()); // VK_FORMAT_R8G8B8A8_SRGB
    let error = basisu::decode(&rgba).unwrap_err();
    assert!(error.contains("Basis Universal"), "{error}");
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0xba515);
    for name in [
        "alpha_simple_basis.ktx2",
        "ktx_document_uastc_rdo4_zstd5.ktx2",
    ] {
        let file = data(name);
        for _ in 0..32 {
            let cut = rng.random_range(0..file.len());
            assert!(basisu::decode(&file[..cut]).is_err(), "{name} cut at {cut}");
        }
        for _ in 0..64 {
            let mut damaged = file.clone();
            let at = rng.random_range(0..damaged.len());
            damaged[at] ^= rng.random_range(1..=255u8);
            if let Ok(image) = basisu::decode(&damaged) {
                assert!(image.width() * image.height() > 0);
            }
        }
    }
}

/// Every level the file holds is kept: the KTX-Software files hold full chains (11
/// levels from 1024 x 1024), each of which transcodes to BC7 blocks of its own size.
#[test]
fn every_level_is_kept_and_transcodes_to_bc7() {
    for name in [
        "ktx_document_basis.ktx2",
        "ktx_document_uastc_rdo4_zstd5.ktx2",
    ] {
        let basis = basisu::BasisTexture::from_ktx2(&data(name)).unwrap();
        assert_eq!((basis.size(), basis.levels()), ((1024, 1024), 11), "{name}");
        for level in 0..basis.levels() {
            let blocks = basisu::blocks((1024 >> level).max(1));
            let bytes = basis.bc7(level).unwrap().len() as u32;
            assert_eq!(
                bytes,
                blocks * blocks * basisu::BC7_BLOCK,
                "{name} level {level}"
            );
        }
        assert!(
            basis.bc7(basis.levels()).is_err(),
            "{name}: past the last level"
        );
    }
    let one = basisu::BasisTexture::from_ktx2(&data("alpha_simple_basis.ktx2")).unwrap();
    assert_eq!((one.size(), one.levels()), ((8, 8), 1));
}
