//! `stereocull diff`: how far two rendered images are apart, for stating what an
//! option that trades accuracy for speed (levels of detail, the far layer) costs in
//! pixels.

use std::path::{Path, PathBuf};

use clap::Args;
use image::RgbaImage;

use crate::error::{Error, Result};

#[derive(Args, Debug)]
pub struct DiffArgs {
    /// The first image (PNG or JPEG).
    pub a: PathBuf,
    /// The second image, of the same size.
    pub b: PathBuf,
    /// A pixel differs when one of its channels differs by more than this many levels.
    #[arg(long, default_value_t = 0)]
    pub levels: u8,
    /// Also write the difference image here (per channel, scaled by 4).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// How two images of one size differ, over their RGB channels (alpha is the renderer's
/// constant 255).
#[derive(Debug, PartialEq)]
pub struct Difference {
    pub width: u32,
    pub height: u32,
    /// Pixels with a channel more than the threshold apart.
    pub differing_pixels: u64,
    pub max_levels: u8,
    /// Mean absolute difference per channel, in levels of 255.
    pub mean_levels: f64,
    /// Peak signal-to-noise ratio in dB; infinite for identical images.
    pub psnr_db: f64,
}

impl Difference {
    pub fn of(a: &RgbaImage, b: &RgbaImage, levels: u8) -> Difference {
        let (mut differing, mut max, mut sum, mut sum_sq) = (0u64, 0u8, 0u64, 0u64);
        for (p, q) in a.pixels().zip(b.pixels()) {
            let d: [u8; 3] = std::array::from_fn(|c| p[c].abs_diff(q[c]));
            let worst = d.into_iter().max().unwrap_or(0);
            differing += u64::from(worst > levels);
            max = max.max(worst);
            sum += d.iter().map(|&x| u64::from(x)).sum::<u64>();
            sum_sq += d.iter().map(|&x| u64::from(x).pow(2)).sum::<u64>();
        }
        let channels = (u64::from(a.width()) * u64::from(a.height()) * 3).max(1) as f64;
        let mse = sum_sq as f64 / channels;
        Difference {
            width: a.width(),
            height: a.height(),
            differing_pixels: differing,
            max_levels: max,
            mean_levels: sum as f64 / channels,
            psnr_db: 10.0 * (255.0f64.powi(2) / mse).log10(),
        }
    }

    /// The share of pixels that differ, in percent.
    pub fn differing_percent(&self) -> f64 {
        let pixels = (u64::from(self.width) * u64::from(self.height)).max(1);
        100.0 * self.differing_pixels as f64 / pixels as f64
    }
}

pub fn diff(args: &DiffArgs) -> Result<()> {
    let (a, b) = (open(&args.a)?, open(&args.b)?);
    if a.dimensions() != b.dimensions() {
        return Err(Error::ImageSizes(format!(
            "{} is {} x {} but {} is {} x {}",
            args.a.display(),
            a.width(),
            a.height(),
            args.b.display(),
            b.width(),
            b.height()
        )));
    }
    let d = Difference::of(&a, &b, args.levels);
    println!(
        "{} x {}: {} pixels ({:.3} %) differ by more than {} levels; largest difference {} levels, mean {:.3} levels per channel, PSNR {:.1} dB",
        d.width,
        d.height,
        d.differing_pixels,
        d.differing_percent(),
        args.levels,
        d.max_levels,
        d.mean_levels,
        d.psnr_db
    );
    if let Some(path) = &args.out {
        difference_image(&a, &b)
            .save(path)
            .map_err(|source| Error::Image {
                path: path.clone(),
                source,
            })?;
    }
    Ok(())
}

fn open(path: &Path) -> Result<RgbaImage> {
    let image = image::open(path).map_err(|source| Error::Image {
        path: path.into(),
        source,
    })?;
    Ok(image.to_rgba8())
}

fn difference_image(a: &RgbaImage, b: &RgbaImage) -> RgbaImage {
    RgbaImage::from_fn(a.width(), a.height(), |x, y| {
        let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
        let d = |c: usize| p[c].abs_diff(q[c]).saturating_mul(4);
        image::Rgba([d(0), d(1), d(2), 255])
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// A random image against a copy with chosen pixels changed by known amounts: the
    /// counts, the largest and mean difference and the PSNR follow from them.
    #[test]
    fn counts_the_pixels_changed_and_by_how_much() {
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let a = RgbaImage::from_fn(40, 30, |_, _| {
            image::Rgba([rng.random(), rng.random(), rng.random(), 255])
        });
        let mut b = a.clone();
        let changes = [((1, 2), 0, 5i16), ((7, 7), 1, -40), ((39, 29), 2, 90)];
        for &((x, y), c, by) in &changes {
            let p = b.get_pixel_mut(x, y);
            p[c] = (i16::from(p[c]) + by).clamp(0, 255) as u8;
        }
        let wanted: Vec<u8> = changes
            .iter()
            .map(|&((x, y), c, _)| a.get_pixel(x, y)[c].abs_diff(b.get_pixel(x, y)[c]))
            .collect();
        assert!(
            wanted.iter().all(|&d| d > 0),
            "every change moved: {wanted:?}"
        );
        let d = Difference::of(&a, &b, 0);
        assert_eq!(d.differing_pixels, 3);
        assert_eq!(d.max_levels, *wanted.iter().max().unwrap());
        let channels = 40.0 * 30.0 * 3.0;
        let sum: f64 = wanted.iter().map(|&x| f64::from(x)).sum();
        assert!((d.mean_levels - sum / channels).abs() < 1e-12);
        let mse: f64 = wanted.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / channels;
        assert!((d.psnr_db - 10.0 * (65025.0 / mse).log10()).abs() < 1e-9);
        let above_10 = wanted.iter().filter(|&&x| x > 10).count() as u64;
        assert_eq!(Difference::of(&a, &b, 10).differing_pixels, above_10);
        let same = Difference::of(&a, &a, 0);
        assert_eq!((same.differing_pixels, same.max_levels), (0, 0));
        assert!(same.psnr_db.is_infinite());
    }
}
