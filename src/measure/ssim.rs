//! The structural similarity index (SSIM) of Wang, Bovik, Sheikh & Simoncelli, "Image Quality
//! Assessment: From Error Visibility to Structural Similarity" (IEEE TIP 13(4), 2004), the
//! image metric the study's proxy scores clips by (issue 23): how far a level-of-detail clip's
//! frames are from the full-detail clip's, without participants.
//!
//! As the paper's reference implementation (`ssim_index.m`) computes it, on luma in 0..255:
//! local means, variances and the covariance under an 11×11 Gaussian window (σ = 1.5), over
//! the windows that lie wholly inside the image; per window
//! `((2 μx μy + C1)(2 σxy + C2)) / ((μx² + μy² + C1)(σx² + σy² + C2))` with `C1 = (0.01·255)²`
//! and `C2 = (0.03·255)²` (§III-B, equation 13); the index is the mean over the windows
//! (equation 17). The window is separable, so each local moment is two 1-D passes.
//!
//! Written here: the crate that packages SSIM in Rust (`dssim-core`) is AGPL-licensed.

/// Side of the Gaussian window, and its standard deviation, in pixels (§III-B).
const WINDOW: usize = 11;
const SIGMA: f64 = 1.5;
/// `C1 = (K1 L)²` and `C2 = (K2 L)²` with `K1 = 0.01`, `K2 = 0.03`, `L = 255`.
const C1: f64 = (0.01 * 255.0) * (0.01 * 255.0);
const C2: f64 = (0.03 * 255.0) * (0.03 * 255.0);

/// A grey image: `width × height` luma values in 0..255, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Luma {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f64>,
}

impl Luma {
    /// The luma of an sRGB-encoded RGBA image (Rec. 601 weights on the encoded values, as
    /// `rgb2gray` gives the reference implementation).
    pub fn from_rgba(image: &image::RgbaImage) -> Luma {
        let values = image
            .pixels()
            .map(|p| 0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64)
            .collect();
        Luma {
            width: image.width() as usize,
            height: image.height() as usize,
            values,
        }
    }
}

/// The normalised 1-D Gaussian whose outer product is the window.
fn kernel() -> [f64; WINDOW] {
    let mut k = [0.0; WINDOW];
    let centre = (WINDOW / 2) as f64;
    for (i, w) in k.iter_mut().enumerate() {
        let d = i as f64 - centre;
        *w = (-d * d / (2.0 * SIGMA * SIGMA)).exp();
    }
    let sum: f64 = k.iter().sum();
    k.map(|w| w / sum)
}

/// `values` (`width × height`) filtered by the window, over the positions where it lies wholly
/// inside: `(width − 10) × (height − 10)` values.
fn filter_valid(values: &[f64], width: usize, height: usize, k: &[f64; WINDOW]) -> Vec<f64> {
    let (w, h) = (width + 1 - WINDOW, height + 1 - WINDOW);
    // Rows first, then columns.
    let mut rows = vec![0.0; w * height];
    for y in 0..height {
        let line = &values[y * width..(y + 1) * width];
        for x in 0..w {
            rows[y * w + x] = k.iter().zip(&line[x..x + WINDOW]).map(|(a, b)| a * b).sum();
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            out[y * w + x] = (0..WINDOW).map(|i| k[i] * rows[(y + i) * w + x]).sum();
        }
    }
    out
}

/// The mean SSIM of `a` and `b` (equal sizes, each side at least 11 pixels), 1 for identical
/// images; `None` if the sizes differ or are too small for one window.
pub fn ssim(a: &Luma, b: &Luma) -> Option<f64> {
    if (a.width, a.height) != (b.width, b.height) || a.width < WINDOW || a.height < WINDOW {
        return None;
    }
    let (w, h) = (a.width, a.height);
    let k = kernel();
    let product = |f: &dyn Fn(f64, f64) -> f64| -> Vec<f64> {
        let values: Vec<f64> = a
            .values
            .iter()
            .zip(&b.values)
            .map(|(&x, &y)| f(x, y))
            .collect();
        filter_valid(&values, w, h, &k)
    };
    let mx = filter_valid(&a.values, w, h, &k);
    let my = filter_valid(&b.values, w, h, &k);
    let xx = product(&|x, _| x * x);
    let yy = product(&|_, y| y * y);
    let xy = product(&|x, y| x * y);
    let n = mx.len();
    let sum: f64 = (0..n)
        .map(|i| {
            let (ux, uy) = (mx[i], my[i]);
            let vx = xx[i] - ux * ux;
            let vy = yy[i] - uy * uy;
            let cov = xy[i] - ux * uy;
            ((2.0 * ux * uy + C1) * (2.0 * cov + C2)) / ((ux * ux + uy * uy + C1) * (vx + vy + C2))
        })
        .sum();
    Some(sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn luma(width: usize, height: usize, f: impl Fn(usize, usize) -> f64) -> Luma {
        Luma {
            width,
            height,
            values: (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    /// A textured test image: smooth gradients and a pattern, so windows vary in mean and
    /// contrast.
    fn texture(x: usize, y: usize) -> f64 {
        let (x, y) = (x as f64, y as f64);
        128.0 + 60.0 * (0.31 * x).sin() * (0.17 * y).cos() + 0.8 * x - 0.5 * y
    }

    /// The index straight from equation 13, each window's moments summed over its 121 pixels:
    /// what the separable filtering must agree with.
    fn direct(a: &Luma, b: &Luma) -> f64 {
        let k = kernel();
        let (w, h) = (a.width + 1 - WINDOW, a.height + 1 - WINDOW);
        let mut sum = 0.0;
        for y0 in 0..h {
            for x0 in 0..w {
                let (mut ux, mut uy, mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0, 0.0, 0.0);
                for j in 0..WINDOW {
                    for i in 0..WINDOW {
                        let g = k[i] * k[j];
                        let p = (y0 + j) * a.width + x0 + i;
                        let (x, y) = (a.values[p], b.values[p]);
                        ux += g * x;
                        uy += g * y;
                        xx += g * x * x;
                        yy += g * y * y;
                        xy += g * x * y;
                    }
                }
                let (vx, vy, c) = (xx - ux * ux, yy - uy * uy, xy - ux * uy);
                sum += ((2.0 * ux * uy + C1) * (2.0 * c + C2))
                    / ((ux * ux + uy * uy + C1) * (vx + vy + C2));
            }
        }
        sum / (w * h) as f64
    }

    #[test]
    fn an_image_is_wholly_similar_to_itself() {
        let a = luma(40, 30, texture);
        assert!((ssim(&a, &a).unwrap() - 1.0).abs() < 1e-12);
    }

    /// Flat images have no variance, so the index is the luminance term alone, in closed form:
    /// `(2ab + C1) / (a² + b² + C1)`.
    #[test]
    fn flat_images_give_the_luminance_term_in_closed_form() {
        for (a, b) in [(100.0, 100.0), (100.0, 150.0), (0.0, 255.0), (30.0, 31.0)] {
            let x = luma(16, 16, |_, _| a);
            let y = luma(16, 16, |_, _| b);
            let expected = (2.0 * a * b + C1) / (a * a + b * b + C1);
            let got = ssim(&x, &y).unwrap();
            assert!(
                (got - expected).abs() < 1e-9,
                "{a}, {b}: {got} vs {expected}"
            );
        }
        // Black against white: C1 / (255² + C1), about 1e-4.
        let black = luma(16, 16, |_, _| 0.0);
        let white = luma(16, 16, |_, _| 255.0);
        assert!(ssim(&black, &white).unwrap() < 2e-4);
    }

    /// An image against its negative about its mean: the structure term is −1 where the
    /// contrast dominates C2, so the index is well below zero.
    #[test]
    fn a_negative_is_anti_similar() {
        let a = luma(40, 30, texture);
        let b = luma(40, 30, |x, y| 255.0 - texture(x, y));
        let s = ssim(&a, &b).unwrap();
        assert!(s < -0.3, "{s}");
    }

    #[test]
    fn separable_filtering_matches_the_windows_summed_directly() {
        let a = luma(37, 23, texture);
        let noise = |x: usize, y: usize| ((x * 7919 + y * 104_729) % 41) as f64 - 20.0;
        let b = luma(37, 23, |x, y| {
            (texture(x, y) + noise(x, y)).clamp(0.0, 255.0)
        });
        let (fast, slow) = (ssim(&a, &b).unwrap(), direct(&a, &b));
        assert!((fast - slow).abs() < 1e-12, "{fast} vs {slow}");
        assert!(fast > 0.3 && fast < 0.99, "{fast}");
        assert_eq!(ssim(&a, &b), ssim(&b, &a), "symmetric");
    }

    /// More noise, less similarity; and sizes that cannot be compared are refused.
    #[test]
    fn similarity_falls_with_noise_and_sizes_must_agree() {
        let a = luma(48, 48, texture);
        let noisy = |amount: f64| {
            luma(48, 48, |x, y| {
                let n = ((x * 7919 + y * 104_729) % 41) as f64 / 20.0 - 1.0;
                (texture(x, y) + amount * n).clamp(0.0, 255.0)
            })
        };
        let scores: Vec<f64> = [2.0, 10.0, 40.0]
            .iter()
            .map(|&m| ssim(&a, &noisy(m)).unwrap())
            .collect();
        assert!(scores[0] > scores[1] && scores[1] > scores[2], "{scores:?}");
        assert_eq!(ssim(&a, &luma(47, 48, texture)), None);
        assert_eq!(ssim(&luma(10, 48, texture), &luma(10, 48, texture)), None);
    }

    #[test]
    fn luma_of_rgba_uses_rec_601_weights() {
        let img = image::RgbaImage::from_pixel(2, 1, image::Rgba([255, 0, 0, 255]));
        let l = Luma::from_rgba(&img);
        assert_eq!((l.width, l.height), (2, 1));
        assert!((l.values[0] - 0.299 * 255.0).abs() < 1e-9);
    }
}
