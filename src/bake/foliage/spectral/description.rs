//! The three animation description types (§6.1) of Bennett-Therkildsen, Carlsen & Schmid's
//! thesis "Animated Billboard Clouds for Foliage Simplification" (2007), each a way to say how a
//! leaf (or a billboard standing for several) moves, with the four functions the spectral clustering
//! needs (§4.1): `describe` a trajectory, the `deviation` between two descriptions (the k-means
//! distance), the weighted `average` of several (the k-means centroid and a billboard's motion),
//! and `apply` (here [`Description::axis_spectra`], the per-axis cosines a vertex shader sums).
//!
//! Errata applied (brief §3): NEP combines amplitude and phase (or axis) errors, so neither can
//! hide the other; dominating axes are flipped to agree in sign, with π added to the flipped
//! phases, before they are averaged; phases are cosine phases; deviations ignore the mean
//! (bin 0), which is the leaf's average position, not its motion.

use super::dft::{Dft, Spectrum};
use super::{cyclic_diff, cyclic_mean, nep};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::f32::consts::PI;

crate::choice! {
    /// Which description type.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
    pub enum DescriptionType {
        /// §6.1.2: the three axes' full spectra. Lossless, but time-shifted copies deviate and
        /// averaged phases can change a line into a circle.
        Naive => "naive",
        /// §6.1.3: the line through the two samples farthest apart, and the spectrum of the motion
        /// along it. Blind to time shifts; every motion becomes a line.
        DominatingAxis => "dominating-axis",
        /// §6.1.4: amplitudes per axis, and per frequency the phase differences between the axes
        /// (which a time shift leaves alone), weighted by the smaller of the two axes' amplitudes
        /// (the thesis leaves the weight open; a relationship means nothing where one axis is
        /// still). Applied with a random base phase per frequency.
        AxisPhase => "axis-phase",
    }
}

impl DescriptionType {
    /// The description of a trajectory sampled `dft.samples()` times over one loop.
    pub fn describe(self, dft: &Dft, trajectory: &[Vec3]) -> Description {
        let axis = |c: usize| -> Spectrum {
            let x: Vec<f32> = trajectory.iter().map(|p| p[c]).collect();
            dft.spectrum(&x).motion()
        };
        match self {
            DescriptionType::Naive => Description::Naive([axis(0), axis(1), axis(2)]),
            DescriptionType::DominatingAxis => {
                let (mut best, mut axis) = (0.0f32, Vec3::Y);
                for (i, p) in trajectory.iter().enumerate() {
                    for q in &trajectory[i + 1..] {
                        let d = (*q - *p).length_squared();
                        if d > best {
                            (best, axis) = (d, (*q - *p).normalize());
                        }
                    }
                }
                let axis = canonical(axis);
                let mean = trajectory.iter().copied().sum::<Vec3>() / trajectory.len() as f32;
                let x: Vec<f32> = trajectory.iter().map(|p| (*p - mean).dot(axis)).collect();
                Description::DominatingAxis {
                    axis,
                    spectrum: dft.spectrum(&x).motion(),
                }
            }
            DescriptionType::AxisPhase => {
                let [x, y, z] = [axis(0), axis(1), axis(2)];
                let rel = |a: &Spectrum, b: &Spectrum| -> Vec<f32> {
                    a.phase
                        .iter()
                        .zip(&b.phase)
                        .map(|(p, q)| wrap(p - q))
                        .collect()
                };
                Description::AxisPhase {
                    xy: rel(&x, &y),
                    xz: rel(&x, &z),
                    amplitude: [x.amplitude, y.amplitude, z.amplitude],
                }
            }
        }
    }

    /// The weighted average of descriptions of this type (equal weights where all are 0).
    pub fn average(self, items: &[(&Description, f32)]) -> Description {
        let total: f32 = items.iter().map(|(_, w)| w.max(0.0)).sum();
        let weight = |w: f32| {
            if total > 0.0 {
                w.max(0.0) / total
            } else {
                1.0 / items.len().max(1) as f32
            }
        };
        let bins = items.first().map_or(0, |(d, _)| d.bins());
        // Per-bin mean amplitude and amplitude-weighted cyclic mean phase of spectra.
        let mean_spectrum = |spectra: &[(Spectrum, f32)]| -> Spectrum {
            let mut out = Spectrum::zero(bins);
            for k in 0..bins {
                out.amplitude[k] = spectra.iter().map(|(s, w)| w * s.amplitude[k]).sum();
                out.phase[k] = cyclic_mean(
                    spectra
                        .iter()
                        .map(|(s, w)| (s.phase[k], w * s.amplitude[k])),
                );
            }
            out
        };
        match self {
            DescriptionType::Naive => Description::Naive(std::array::from_fn(|c| {
                let spectra: Vec<(Spectrum, f32)> = items
                    .iter()
                    .filter_map(|(d, w)| match d {
                        Description::Naive(s) => Some((s[c].clone(), weight(*w))),
                        _ => None,
                    })
                    .collect();
                mean_spectrum(&spectra)
            })),
            DescriptionType::DominatingAxis => {
                // The best line through the origin: the principal eigenvector of Σ w a aᵀ.
                let mut m = nalgebra::Matrix3::<f32>::zeros();
                for (d, w) in items {
                    if let Description::DominatingAxis { axis, .. } = d {
                        let a = nalgebra::Vector3::new(axis.x, axis.y, axis.z);
                        m += a * a.transpose() * weight(*w);
                    }
                }
                let eig = m.symmetric_eigen();
                let i = eig.eigenvalues.imax();
                let v = eig.eigenvectors.column(i);
                let axis = canonical(Vec3::new(v[0], v[1], v[2]).normalize_or(Vec3::Y));
                // Flip every axis to agree with the average; a flipped axis moves its signal
                // by half a cycle.
                let spectra: Vec<(Spectrum, f32)> = items
                    .iter()
                    .filter_map(|(d, w)| match d {
                        Description::DominatingAxis { axis: a, spectrum } => {
                            let mut s = spectrum.clone();
                            if a.dot(axis) < 0.0 {
                                for p in &mut s.phase {
                                    *p = wrap(*p + PI);
                                }
                            }
                            Some((s, weight(*w)))
                        }
                        _ => None,
                    })
                    .collect();
                Description::DominatingAxis {
                    axis,
                    spectrum: mean_spectrum(&spectra),
                }
            }
            DescriptionType::AxisPhase => {
                // (amplitudes, [φ_x − φ_y, φ_x − φ_z], weight) of every member.
                let parts: Vec<AxisPhaseMember> = items
                    .iter()
                    .filter_map(|(d, w)| match d {
                        Description::AxisPhase { amplitude, xy, xz } => {
                            Some((amplitude, [xy.as_slice(), xz.as_slice()], weight(*w)))
                        }
                        _ => None,
                    })
                    .collect();
                let amplitude: [Vec<f32>; 3] = std::array::from_fn(|c| {
                    (0..bins)
                        .map(|k| parts.iter().map(|(a, _, w)| w * a[c][k]).sum())
                        .collect()
                });
                // Relationship r (0: x–y, 1: x–z), weighted by the smaller amplitude.
                let rel = |r: usize, k: usize| -> f32 {
                    cyclic_mean(
                        parts
                            .iter()
                            .map(|(a, rels, w)| (rels[r][k], w * a[0][k].min(a[r + 1][k]))),
                    )
                };
                let xy = (0..bins).map(|k| rel(0, k)).collect();
                let xz = (0..bins).map(|k| rel(1, k)).collect();
                Description::AxisPhase { amplitude, xy, xz }
            }
        }
    }
}

/// How one leaf or billboard moves, as one of the [`DescriptionType`]s. Bin k of every
/// spectrum is k whole cycles per loop; bin 0 (the mean position) is always zero.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Description {
    Naive([Spectrum; 3]),
    DominatingAxis {
        /// Unit, its largest component positive.
        axis: Vec3,
        spectrum: Spectrum,
    },
    AxisPhase {
        /// Per axis, per bin.
        amplitude: [Vec<f32>; 3],
        /// Per bin, φ_x − φ_y and φ_x − φ_z.
        xy: Vec<f32>,
        xz: Vec<f32>,
    },
}

impl Description {
    pub fn kind(&self) -> DescriptionType {
        match self {
            Description::Naive(_) => DescriptionType::Naive,
            Description::DominatingAxis { .. } => DescriptionType::DominatingAxis,
            Description::AxisPhase { .. } => DescriptionType::AxisPhase,
        }
    }

    pub fn bins(&self) -> usize {
        match self {
            Description::Naive(s) => s[0].bins(),
            Description::DominatingAxis { spectrum, .. } => spectrum.bins(),
            Description::AxisPhase { xy, .. } => xy.len(),
        }
    }

    /// How differently two descriptions of the same type move: 0 for equal ones, symmetric,
    /// in [0, 1). Descriptions of different types are as far apart as can be (1).
    pub fn deviation(&self, other: &Description) -> f32 {
        match (self, other) {
            (Description::Naive(a), Description::Naive(b)) => {
                let mut amplitude = 0.0;
                let mut phase = 0.0;
                for (s, t) in a.iter().zip(b) {
                    amplitude += s.amplitude_distance(t);
                    for k in 0..s.bins().min(t.bins()) {
                        let (wa, wb) = (s.amplitude[k], t.amplitude[k]);
                        if wa + wb <= 0.0 {
                            continue;
                        }
                        // The weighted mean of two angles lies on the shorter arc between
                        // them, θa from the first: wa·θa + wb·(d − θa) in closed form.
                        let d = cyclic_diff(s.phase[k], t.phase[k]);
                        let theta_a = (wb * d.sin()).atan2(wa + wb * d.cos());
                        phase += wa * theta_a + wb * (d - theta_a);
                    }
                }
                nep(amplitude, phase)
            }
            (
                Description::DominatingAxis {
                    axis: a,
                    spectrum: s,
                },
                Description::DominatingAxis {
                    axis: b,
                    spectrum: t,
                },
            ) => nep(1.0 - a.dot(*b).abs().min(1.0), s.amplitude_distance(t)),
            (
                Description::AxisPhase {
                    amplitude: a,
                    xy: axy,
                    xz: axz,
                },
                Description::AxisPhase {
                    amplitude: b,
                    xy: bxy,
                    xz: bxz,
                },
            ) => {
                let mut amplitude = 0.0;
                let mut phase = 0.0;
                for k in 0..axy.len().min(bxy.len()) {
                    for c in 0..3 {
                        amplitude += (a[c][k] - b[c][k]).abs();
                    }
                    // A relationship means something only where both axes move.
                    let w = |c: usize| 0.5 * (a[0][k].min(a[c][k]) + b[0][k].min(b[c][k]));
                    phase +=
                        w(1) * cyclic_diff(axy[k], bxy[k]) + w(2) * cyclic_diff(axz[k], bxz[k]);
                }
                nep(amplitude, phase)
            }
            _ => 1.0,
        }
    }

    /// The motion as cosines per axis (the thesis's `apply`): offset_c(τ) =
    /// Σ_k A_ck cos(2πkτ + φ_ck). Axis-phase draws its base phase per frequency from `seed`
    /// (a free time shift per billboard, so neighbours do not sway in step).
    pub fn axis_spectra(&self, seed: u64) -> [Spectrum; 3] {
        match self {
            Description::Naive(s) => s.clone(),
            Description::DominatingAxis { axis, spectrum } => std::array::from_fn(|c| {
                let flip = if axis[c] < 0.0 { PI } else { 0.0 };
                Spectrum {
                    amplitude: spectrum
                        .amplitude
                        .iter()
                        .map(|a| a * axis[c].abs())
                        .collect(),
                    phase: spectrum.phase.iter().map(|p| wrap(p + flip)).collect(),
                }
            }),
            Description::AxisPhase { amplitude, xy, xz } => {
                let mut rng = fastrand::Rng::with_seed(seed);
                let base: Vec<f32> = (0..xy.len())
                    .map(|_| rng.f32() * std::f32::consts::TAU)
                    .collect();
                let phase = |rel: Option<&[f32]>| -> Vec<f32> {
                    base.iter()
                        .enumerate()
                        .map(|(k, b)| wrap(b - rel.map_or(0.0, |r| r[k])))
                        .collect()
                };
                [
                    Spectrum {
                        amplitude: amplitude[0].clone(),
                        phase: phase(None),
                    },
                    Spectrum {
                        amplitude: amplitude[1].clone(),
                        phase: phase(Some(xy)),
                    },
                    Spectrum {
                        amplitude: amplitude[2].clone(),
                        phase: phase(Some(xz)),
                    },
                ]
            }
        }
    }

    /// The offset from the average position at loop time `tau` (see [`Self::axis_spectra`]).
    pub fn offset(&self, tau: f32, seed: u64) -> Vec3 {
        let s = self.axis_spectra(seed);
        Vec3::new(s[0].eval(tau), s[1].eval(tau), s[2].eval(tau))
    }
}

/// An axis-phase description's amplitudes, relationships and weight, for averaging.
type AxisPhaseMember<'a> = (&'a [Vec<f32>; 3], [&'a [f32]; 2], f32);

/// An angle in (−π, π].
fn wrap(a: f32) -> f32 {
    let w = (a + PI).rem_euclid(std::f32::consts::TAU) - PI;
    if w <= -PI {
        w + std::f32::consts::TAU
    } else {
        w
    }
}

/// The direction of a line, signed so that its largest component is positive.
fn canonical(a: Vec3) -> Vec3 {
    let i = a.abs().max_position();
    if a[i] < 0.0 { -a } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::TAU;

    const N: usize = 32;

    /// An elliptical sway at 2 cycles a loop with a faster wiggle at 5, shifted by `shift`
    /// of a loop.
    fn sway(shift: f32, tilt: f32) -> Vec<Vec3> {
        (0..N)
            .map(|n| {
                let t = n as f32 / N as f32 + shift;
                Vec3::new(
                    0.3 * (TAU * 2.0 * t).cos() + 0.05 * (TAU * 5.0 * t + 1.0).cos(),
                    2.0 + 0.1 * (TAU * 2.0 * t + 0.4).cos(),
                    tilt * (TAU * 2.0 * t + 1.5).cos(),
                )
            })
            .collect()
    }

    #[test]
    fn deviation_is_zero_for_equal_descriptions_and_symmetric() {
        let dft = Dft::new(N);
        for t in DescriptionType::ALL {
            let a = t.describe(&dft, &sway(0.0, 0.2));
            let b = t.describe(&dft, &sway(0.13, 0.05));
            assert!(a.deviation(&a) < 1e-6, "{}", t.name());
            assert!(a.deviation(&b) > 1e-3, "{}", t.name());
            assert!(
                (a.deviation(&b) - b.deviation(&a)).abs() < 1e-6,
                "{}",
                t.name()
            );
            assert_eq!(a.kind(), t);
        }
    }

    /// Time offset is unimportant for foliage (§4.2): dominating-axis and axis-phase do not see
    /// it; the naive type does.
    #[test]
    fn time_shifts_are_invisible_to_the_shift_free_types() {
        let dft = Dft::new(N);
        let shifted = |t: DescriptionType| {
            t.describe(&dft, &sway(0.0, 0.2))
                .deviation(&t.describe(&dft, &sway(3.0 / N as f32, 0.2)))
        };
        assert!(shifted(DescriptionType::DominatingAxis) < 1e-4);
        assert!(shifted(DescriptionType::AxisPhase) < 1e-4);
        assert!(shifted(DescriptionType::Naive) > 0.05);
    }

    /// The naive type is lossless; the others keep each axis's amplitudes.
    #[test]
    fn apply_reproduces_the_motion() {
        let dft = Dft::new(N);
        let tr = sway(0.0, 0.2);
        let mean = tr.iter().copied().sum::<Vec3>() / N as f32;
        let naive = DescriptionType::Naive.describe(&dft, &tr);
        for (n, p) in tr.iter().enumerate() {
            let o = naive.offset(n as f32 / N as f32, 0);
            assert!((o - (*p - mean)).length() < 1e-4);
        }
        let reach = |d: &Description| -> Vec3 {
            (0..N).fold(Vec3::ZERO, |m, n| {
                m.max(d.offset(n as f32 / N as f32, 7).abs())
            })
        };
        let ap = DescriptionType::AxisPhase.describe(&dft, &tr);
        assert_eq!(
            ap.axis_spectra(7)[1].amplitude,
            naive.axis_spectra(0)[1].amplitude
        );
        assert!((reach(&ap) - reach(&naive)).abs().max_element() < 0.08);
        // A straight sway is exactly its dominating axis.
        let line: Vec<Vec3> = (0..N)
            .map(|n| {
                Vec3::new(1.0, 2.0, -2.0) / 3.0
                    * 0.4
                    * (TAU * 3.0 * n as f32 / N as f32 + 0.3).cos()
            })
            .collect();
        let da = DescriptionType::DominatingAxis.describe(&dft, &line);
        for (n, p) in line.iter().enumerate() {
            assert!((da.offset(n as f32 / N as f32, 0) - *p).length() < 1e-4);
        }
    }

    /// Averages: one description averages to itself, and two lines swaying the same way along
    /// opposite-signed axes average to that sway, not to stillness (the sign-alignment
    /// erratum).
    #[test]
    fn averages_keep_what_the_inputs_share() {
        let dft = Dft::new(N);
        for t in DescriptionType::ALL {
            let d = t.describe(&dft, &sway(0.0, 0.2));
            assert!(t.average(&[(&d, 2.0)]).deviation(&d) < 1e-5, "{}", t.name());
        }
        let tr: Vec<Vec3> = (0..N)
            .map(|n| Vec3::new(0.0, 0.6, 0.8) * 0.3 * (TAU * 2.0 * n as f32 / N as f32).cos())
            .collect();
        let a = DescriptionType::DominatingAxis.describe(&dft, &tr);
        // The same sway, described along the opposite direction.
        let Description::DominatingAxis { axis, spectrum } = a.clone() else {
            unreachable!()
        };
        let b = Description::DominatingAxis {
            axis: -axis,
            spectrum: Spectrum {
                phase: spectrum.phase.iter().map(|p| wrap(p + PI)).collect(),
                ..spectrum
            },
        };
        for n in 0..N {
            let tau = n as f32 / N as f32;
            assert!((b.offset(tau, 0) - a.offset(tau, 0)).length() < 1e-4);
        }
        let avg = DescriptionType::DominatingAxis.average(&[(&a, 1.0), (&b, 1.0)]);
        for n in 0..N {
            let tau = n as f32 / N as f32;
            assert!((avg.offset(tau, 0) - a.offset(tau, 0)).length() < 1e-4);
        }
    }
}
