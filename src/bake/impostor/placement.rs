//! Where an impostor joins a chain of levels: one rule for trees' octahedral impostors and
//! characters' animated ones. It is measured, since an impostor's error is not a geometric
//! bound: by its colour error against full detail at the size where it would switch in,
//! beside the level it would stand for at that size.
//!
//! Level k comes in where its error e_k projects to the pixel tolerance τ, at a height of
//! τ·H / e_k pixels for a model H high. Scanning from the coarsest level L towards the finer
//! ones, the impostor takes level k's place (and every coarser one's) while its colour error
//! at k's switch size is no worse than level k's own there. Where it does not beat even level
//! L at L's size, it may still come in further off: at half, a quarter or an eighth of that
//! size, with error 2, 4 or 8 e_L, if it beats level L there. Otherwise the chain keeps no
//! impostor. So selection treats it like any level, and its error where it shows stays within
//! what the chain's own levels show there.
//!
//! The measurements come through [`MeasureImpostor`]: for a tree, the thesis's colour metric
//! of §5.1.3 drawn whole (wood and all); for a character, the mean colour difference over
//! five views round it (see `measure::impostor_fit`).

use crate::bake::gpu_products::MeasureImpostor;
use anyhow::Result;
use serde::{Deserialize, Serialize};

/// How far off, in multiples of the coarsest level's switch distance, an impostor that beats
/// no level where it comes in is tried.
pub const FURTHER_OFF: [f32; 3] = [2.0, 4.0, 8.0];

/// One measurement of a placement: at `px` pixels high, the impostor's colour error and
/// level `level`'s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    pub px: f32,
    pub level: usize,
    pub impostor: f32,
    pub mesh: f32,
}

/// Where the impostor comes in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// Its error bound, scene units: the error of the level it takes the place of, or a
    /// multiple of the coarsest level's; `None` where it beats no level.
    pub epsilon: Option<f32>,
    /// The pixel tolerance it was placed for: with `epsilon`, it comes in at `tolerance_px ·
    /// H / epsilon` pixels high, the size its colour error was measured at.
    pub tolerance_px: f32,
    /// Every measurement, in the order taken.
    pub measured: Vec<Measured>,
}

impl Placement {
    /// No impostor, placed for `tolerance_px`: where there is nothing for it to stand for.
    pub fn none(tolerance_px: f32) -> Placement {
        Placement {
            epsilon: None,
            tolerance_px,
            measured: Vec::new(),
        }
    }

    /// The error bound selection gives the impostor at pixel tolerance `tolerance_px`: never
    /// below what makes it come in where it was measured. Selection takes a level where its
    /// error projects to the tolerance, so at a tolerance above the placement's the bound
    /// alone would bring the impostor in at a larger size than its error was measured at
    /// (at 8 px, five times the size placed at 1.5 px: a blurred figure 170 pixels high); the
    /// bound grows with the tolerance instead, so the impostor never shows larger than that.
    pub fn epsilon_at(&self, tolerance_px: f32) -> Option<f32> {
        self.epsilon
            .map(|e| e * (tolerance_px / self.tolerance_px.max(1e-6)).max(1.0))
    }

    /// The largest figure, in pixels high, the impostor is shown for, for a model `height`
    /// scene units high.
    pub fn largest_px(&self, height: f32) -> Option<f32> {
        self.epsilon
            .map(|e| self.tolerance_px * height / e.max(1e-9))
    }
}

/// Places an impostor in a chain whose levels have the error bounds `errors` (finest first,
/// scene units; level 0 is full detail), for a model `height` high selected at
/// `tolerance_px` (see the module comment). `finest` is the finest level the impostor may
/// stand for (where the coarsest level is finer, it can still come in further off). Returns
/// the placement and the level it takes the place of (`None` where it comes in further off
/// than the coarsest level, or not at all).
pub fn place(
    errors: &[f32],
    height: f32,
    tolerance_px: f32,
    finest: usize,
    measure: &mut dyn MeasureImpostor,
) -> Result<(Placement, Option<usize>)> {
    let mut placement = Placement::none(tolerance_px);
    let coarsest = errors.len().saturating_sub(1);
    if coarsest == 0 {
        return Ok((placement, None));
    }
    let switch_px = |e: f32| tolerance_px * height / e.max(1e-6);
    let mut beats = |placement: &mut Placement, k: usize, px: f32| -> Result<bool> {
        let (impostor, mesh) = measure.errors(k, px)?;
        placement.measured.push(Measured {
            px,
            level: k,
            impostor,
            mesh,
        });
        Ok(impostor <= mesh)
    };
    let mut replaces = None;
    for k in (finest.max(1)..=coarsest).rev() {
        if !beats(&mut placement, k, switch_px(errors[k]))? {
            break;
        }
        replaces = Some(k);
    }
    placement.epsilon = replaces.map(|k| errors[k]);
    if replaces.is_none() {
        let e = errors[coarsest];
        for scale in FURTHER_OFF {
            if beats(&mut placement, coarsest, switch_px(e * scale))? {
                placement.epsilon = Some(e * scale);
                break;
            }
        }
    }
    Ok((placement, replaces))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A measurer from formulas: the impostor's error by size, a level's by level.
    struct Formula {
        impostor: fn(f32) -> f32,
        level: fn(usize) -> f32,
        asked: Vec<(usize, f32)>,
    }

    impl MeasureImpostor for Formula {
        fn errors(&mut self, level: usize, px: f32) -> Result<(f32, f32)> {
            self.asked.push((level, px));
            Ok(((self.impostor)(px), (self.level)(level)))
        }
    }

    fn measure(impostor: fn(f32) -> f32, level: fn(usize) -> f32) -> Formula {
        Formula {
            impostor,
            level,
            asked: Vec::new(),
        }
    }

    /// Levels 1–3 switch in at 200, 100 and 50 px for a model 2 m high at 1 px.
    const ERRORS: [f32; 4] = [0.0, 0.01, 0.02, 0.04];

    #[test]
    fn takes_the_finest_level_it_beats_scanning_from_the_coarse_end() {
        // The impostor's error 2/px: 0.04, 0.02, 0.01 at levels 3, 2, 1's sizes.
        let mut m = measure(|px| 2.0 / px, |k| 0.015 * k as f32);
        let (p, replaces) = place(&ERRORS, 2.0, 1.0, 1, &mut m).unwrap();
        assert_eq!(replaces, Some(1));
        assert_eq!(p.epsilon, Some(0.01));
        assert_eq!(m.asked, vec![(3, 50.0), (2, 100.0), (1, 200.0)]);

        // Level 1 is better than the impostor at its size: the scan stops there.
        let mut m = measure(|px| 2.0 / px, |k| [0.0, 0.005, 0.03, 0.045][k]);
        let (p, replaces) = place(&ERRORS, 2.0, 1.0, 1, &mut m).unwrap();
        assert_eq!((replaces, p.epsilon), (Some(2), Some(0.02)));
        assert_eq!(p.measured.len(), 3);
        assert_eq!(p.largest_px(2.0), Some(100.0));
    }

    #[test]
    fn never_stands_for_a_level_finer_than_asked() {
        let mut m = measure(|_| 0.0, |_| 0.1);
        let (p, replaces) = place(&ERRORS, 2.0, 1.0, 2, &mut m).unwrap();
        assert_eq!((replaces, p.epsilon), (Some(2), Some(0.02)));
        assert_eq!(m.asked, vec![(3, 50.0), (2, 100.0)]);

        // A chain whose only level is finer than asked: the impostor may still come in
        // further off than it, standing for none.
        let mut m = measure(|_| 0.0, |_| 0.1);
        let (p, replaces) = place(&ERRORS[..2], 2.0, 1.0, 2, &mut m).unwrap();
        assert_eq!((replaces, p.epsilon), (None, Some(0.02)));
        assert_eq!(m.asked, vec![(1, 100.0)]);
    }

    #[test]
    fn comes_in_further_off_where_it_beats_no_level_where_they_switch() {
        // An impostor whose blur small sizes hide: 0.02 at 50 px loses to level 3's 0.015,
        // 0.01 at 25 px (twice as far) wins, with twice level 3's error.
        let mut m = measure(|px| px / 2500.0, |_| 0.015);
        let (p, replaces) = place(&ERRORS, 2.0, 1.0, 1, &mut m).unwrap();
        assert_eq!((replaces, p.epsilon), (None, Some(0.08)));
        assert_eq!(m.asked, vec![(3, 50.0), (3, 25.0)]);
        assert_eq!(p.largest_px(2.0), Some(25.0));
        // At a tolerance twice the placement's, its bound doubles: it never shows larger.
        assert_eq!(p.epsilon_at(2.0), Some(0.16));

        // Worse at every distance tried: no impostor.
        let mut m = measure(|_| 1.0, |_| 0.015);
        let (p, replaces) = place(&ERRORS, 2.0, 1.0, 1, &mut m).unwrap();
        assert_eq!((replaces, p.epsilon), (None, None));
        assert_eq!(p.measured.len(), 1 + FURTHER_OFF.len());
    }

    #[test]
    fn a_chain_of_full_detail_alone_gets_no_impostor() {
        let mut m = measure(|_| 0.0, |_| 1.0);
        let (p, replaces) = place(&[0.0], 2.0, 1.0, 1, &mut m).unwrap();
        assert_eq!((p.epsilon, replaces), (None, None));
        assert!(m.asked.is_empty());
    }
}
