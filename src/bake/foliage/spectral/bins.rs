//! Frequency bins (Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for
//! Foliage Simplification" (2007) §6.3.3): a billboard keeps K lines per axis instead of N/2 bins.
//!
//! Averaging spectra bin by bin smears neighbouring frequencies (sin 4t and sin 5t share no
//! bin; their per-bin mean beats and looks like neither). The thesis groups frequencies into K
//! bins by 1-D k-means on frequency, weighted by amplitude, and lets each bin speak with one
//! line: its amplitude-weighted mean frequency, rounded to whole cycles per loop so the loop
//! stays seamless, the bin's total amplitude and its amplitude-weighted cyclic mean phase.
//! Here the bins are shared by the three axes (the sway of one branch shows on all of them),
//! and the reduction runs on an average already taken bin by bin, which gives the thesis's
//! amplitudes and frequencies exactly (both are sums over the members) and its phases up to
//! the weighting.

use super::cyclic_mean;
use super::dft::Spectrum;
use crate::bake::gpu_data::spectra::Line;

/// The K lines per axis of a motion given as axis spectra (bin 0, the mean, is left out).
/// Empty bins give lines of amplitude 0, so every billboard has exactly `k` per axis.
pub fn reduce(axes: &[Spectrum; 3], k: usize) -> [Vec<Line>; 3] {
    let bins = axes[0].bins();
    let k = k.max(1);
    // Frequencies 1..bins, weighted by their amplitude over all three axes.
    let freqs: Vec<usize> = (1..bins).collect();
    let weight: Vec<f32> = freqs
        .iter()
        .map(|&f| axes.iter().map(|s| s.amplitude[f]).sum())
        .collect();
    // Initial bins: consecutive runs of n / k frequencies, the last taking the rest.
    let run = (freqs.len() / k).max(1);
    let mut group: Vec<usize> = (0..freqs.len()).map(|i| (i / run).min(k - 1)).collect();
    let mut centre: Vec<f32> = (0..k)
        .map(|j| {
            let members: Vec<usize> = (0..freqs.len()).filter(|&i| group[i] == j).collect();
            members.iter().map(|&i| freqs[i] as f32).sum::<f32>() / members.len().max(1) as f32
        })
        .collect();
    for _ in 0..64 {
        // Centres: amplitude-weighted mean frequency (an empty bin keeps its centre).
        for (j, c) in centre.iter_mut().enumerate() {
            let (mut sw, mut sf) = (0.0f32, 0.0f32);
            for i in (0..freqs.len()).filter(|&i| group[i] == j) {
                sw += weight[i];
                sf += weight[i] * freqs[i] as f32;
            }
            if sw > 0.0 {
                *c = sf / sw;
            }
        }
        let mut changed = false;
        for (i, &f) in freqs.iter().enumerate() {
            if weight[i] <= 0.0 {
                continue;
            }
            let nearest = (0..k)
                .min_by(|&a, &b| {
                    (f as f32 - centre[a])
                        .abs()
                        .total_cmp(&(f as f32 - centre[b]).abs())
                })
                .unwrap_or(0);
            if nearest != group[i] {
                group[i] = nearest;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    std::array::from_fn(|c| {
        (0..k)
            .map(|j| {
                let members: Vec<usize> = (0..freqs.len()).filter(|&i| group[i] == j).collect();
                let amplitude: f32 = members.iter().map(|&i| axes[c].amplitude[freqs[i]]).sum();
                if amplitude <= 0.0 {
                    return Line::default();
                }
                let phase = cyclic_mean(
                    members
                        .iter()
                        .map(|&i| (axes[c].phase[freqs[i]], axes[c].amplitude[freqs[i]])),
                );
                Line {
                    cycles: centre[j].round().max(1.0) as u32,
                    amplitude,
                    phase,
                }
            })
            .collect()
    })
}

/// The offset the lines give at loop time `tau`.
pub fn eval(lines: &[Vec<Line>; 3], tau: f32) -> glam::Vec3 {
    let axis = |ls: &[Line]| -> f32 {
        ls.iter()
            .map(|l| l.amplitude * (std::f32::consts::TAU * l.cycles as f32 * tau + l.phase).cos())
            .sum()
    };
    glam::Vec3::new(axis(&lines[0]), axis(&lines[1]), axis(&lines[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::spectral::dft::Dft;
    use std::f32::consts::TAU;

    fn spectra(f: impl Fn(f32) -> [f32; 3]) -> [Spectrum; 3] {
        let dft = Dft::new(64);
        let samples: Vec<[f32; 3]> = (0..64).map(|n| f(n as f32 / 64.0)).collect();
        std::array::from_fn(|c| {
            dft.spectrum(&samples.iter().map(|s| s[c]).collect::<Vec<_>>())
                .motion()
        })
    }

    /// A pure sinusoid keeps its frequency, amplitude and phase in one line; the other lines
    /// are still.
    #[test]
    fn a_pure_sinusoid_keeps_its_frequency_and_amplitude() {
        let s = spectra(|t| [0.0, 0.2 * (TAU * 3.0 * t + 0.5).cos(), 0.0]);
        let lines = reduce(&s, 4);
        assert!(lines.iter().all(|l| l.len() == 4));
        let moving: Vec<&Line> = lines[1].iter().filter(|l| l.amplitude > 1e-4).collect();
        assert_eq!(moving.len(), 1);
        assert_eq!(moving[0].cycles, 3);
        assert!((moving[0].amplitude - 0.2).abs() < 1e-4);
        assert!((moving[0].phase - 0.5).abs() < 1e-3);
        assert!(lines[0].iter().chain(&lines[2]).all(|l| l.amplitude < 1e-4));
        for n in 0..64 {
            let tau = n as f32 / 64.0;
            assert!((eval(&lines, tau).y - 0.2 * (TAU * 3.0 * tau + 0.5).cos()).abs() < 1e-4);
        }
    }

    /// Well separated frequencies get bins of their own; close ones share one, at their
    /// weighted mean (§6.3.2: sin 4t and sin 5t average to about 4.5).
    #[test]
    fn bins_follow_the_amplitude() {
        let s = spectra(|t| {
            [
                0.3 * (TAU * 2.0 * t).cos() + 0.1 * (TAU * 20.0 * t).cos(),
                0.0,
                0.0,
            ]
        });
        let lines = reduce(&s, 2);
        let mut cycles: Vec<u32> = lines[0].iter().map(|l| l.cycles).collect();
        cycles.sort();
        assert_eq!(cycles, vec![2, 20]);
        let s = spectra(|t| {
            [
                0.1 * (TAU * 4.0 * t).cos() + 0.1 * (TAU * 5.0 * t).cos(),
                0.0,
                0.0,
            ]
        });
        let lines = reduce(&s, 1);
        assert!([4, 5].contains(&lines[0][0].cycles), "{:?}", lines[0]);
        assert!((lines[0][0].amplitude - 0.2).abs() < 1e-4);
    }
}
