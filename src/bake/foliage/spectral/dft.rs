//! The DFT of one coordinate of a cyclic trajectory (Bennett-Therkildsen, Carlsen & Schmid's thesis
//! "Animated Billboard Clouds for Foliage Simplification" (2007) §4.5), normalised so that the
//! spectrum reads as amplitudes and phases of cosines: for N samples `x_n = x(n/N)` of one loop,
//!
//! x(τ) = Σ_{k=0}^{N/2} A_k · cos(2π k τ + φ_k),
//!
//! with `A_k = 2|X_k|/N` for 0 < k < N/2, `|X_k|/N` at k = 0 (the mean, φ 0 or π) and at the
//! Nyquist bin, and `φ_k = arg X_k`. The thesis writes sines and leaves out the 1/N; its brief
//! (notes/thesis-spectral-animation.md §2.4) gives this corrected form. A real signal's
//! spectrum is Hermitian, so bins above N/2 are not kept.

use rustfft::num_complex::Complex;
use std::f32::consts::TAU;
use std::sync::Arc;

/// One axis's one-sided spectrum: bin k is k whole cycles per loop.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spectrum {
    pub amplitude: Vec<f32>,
    /// Cosine phase, radians in (−π, π].
    pub phase: Vec<f32>,
}

impl Spectrum {
    /// No motion, over `bins` bins.
    pub fn zero(bins: usize) -> Spectrum {
        Spectrum {
            amplitude: vec![0.0; bins],
            phase: vec![0.0; bins],
        }
    }

    pub fn bins(&self) -> usize {
        self.amplitude.len()
    }

    /// The signal at loop time `tau` (0..1), mean included.
    pub fn eval(&self, tau: f32) -> f32 {
        self.amplitude
            .iter()
            .zip(&self.phase)
            .enumerate()
            .map(|(k, (a, p))| a * (TAU * k as f32 * tau + p).cos())
            .sum()
    }

    /// The spectrum without its mean (bin 0): the motion about the average position.
    pub fn motion(mut self) -> Spectrum {
        if let Some(a) = self.amplitude.first_mut() {
            *a = 0.0;
            self.phase[0] = 0.0;
        }
        self
    }

    /// Sum over bins of the amplitude differences (the thesis's `amplitudeDistance`, L1 norm).
    pub fn amplitude_distance(&self, other: &Spectrum) -> f32 {
        self.amplitude
            .iter()
            .zip(&other.amplitude)
            .map(|(a, b)| (a - b).abs())
            .sum()
    }
}

/// A planned FFT for trajectories of `n` samples.
#[derive(Clone)]
pub struct Dft {
    n: usize,
    fft: Arc<dyn rustfft::Fft<f32>>,
}

impl std::fmt::Debug for Dft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Dft({})", self.n)
    }
}

impl Dft {
    /// For `n` samples a loop (n ≥ 2).
    pub fn new(n: usize) -> Dft {
        let n = n.max(2);
        Dft {
            n,
            fft: rustfft::FftPlanner::new().plan_fft_forward(n),
        }
    }

    pub fn samples(&self) -> usize {
        self.n
    }

    /// Bins of the one-sided spectrum: 0..=N/2.
    pub fn bins(&self) -> usize {
        self.n / 2 + 1
    }

    /// The spectrum of `samples` (`n` of them, evenly over one loop, starting at τ = 0).
    pub fn spectrum(&self, samples: &[f32]) -> Spectrum {
        assert_eq!(samples.len(), self.n, "one sample per frame of the loop");
        let mut buf: Vec<Complex<f32>> = samples.iter().map(|&x| Complex::new(x, 0.0)).collect();
        self.fft.process(&mut buf);
        let n = self.n as f32;
        let nyquist = self.n.is_multiple_of(2).then_some(self.n / 2);
        // Rounding noise of the transform, relative to the signal's size: bins below it are
        // still, with no phase worth keeping.
        let noise = 4e-6 * samples.iter().fold(1e-6f32, |m, x| m.max(x.abs()));
        let (amplitude, phase) = buf[..self.bins()]
            .iter()
            .enumerate()
            .map(|(k, x)| {
                let scale = if k == 0 || Some(k) == nyquist {
                    1.0 / n
                } else {
                    2.0 / n
                };
                let a = x.norm() * scale;
                if a > noise {
                    (a, x.im.atan2(x.re))
                } else {
                    (0.0, 0.0)
                }
            })
            .unzip();
        Spectrum { amplitude, phase }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dft_round_trips_a_loop() {
        let dft = Dft::new(32);
        let mut rng = fastrand::Rng::with_seed(3);
        let terms: Vec<(f32, f32, f32)> = (0..5)
            .map(|_| (rng.u32(0..16) as f32, rng.f32(), rng.f32() * TAU))
            .collect();
        let signal = |t: f32| {
            0.3 + terms
                .iter()
                .map(|(k, a, p)| a * (TAU * k * t + p).cos())
                .sum::<f32>()
        };
        let samples: Vec<f32> = (0..32).map(|i| signal(i as f32 / 32.0)).collect();
        let s = dft.spectrum(&samples);
        assert_eq!(s.bins(), 17);
        for (i, &x) in samples.iter().enumerate() {
            let y = s.eval(i as f32 / 32.0);
            assert!((x - y).abs() < 1e-4, "sample {i}: {x} vs {y}");
        }
    }

    #[test]
    fn a_cosine_reads_back_as_its_amplitude_and_phase() {
        let dft = Dft::new(64);
        let samples: Vec<f32> = (0..64)
            .map(|i| 0.25 * (TAU * 3.0 * i as f32 / 64.0 + 0.7).cos() - 1.0)
            .collect();
        let s = dft.spectrum(&samples);
        assert!((s.amplitude[3] - 0.25).abs() < 1e-5);
        assert!((s.phase[3] - 0.7).abs() < 1e-4);
        // The mean: amplitude 1, phase π.
        assert!((s.amplitude[0] - 1.0).abs() < 1e-5);
        assert!((s.phase[0].abs() - std::f32::consts::PI).abs() < 1e-4);
        let others: f32 = s
            .amplitude
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != 0 && *k != 3)
            .map(|(_, a)| a)
            .sum();
        assert!(others < 1e-4, "{others}");
        assert_eq!(s.clone().motion().amplitude[0], 0.0);
    }
}
