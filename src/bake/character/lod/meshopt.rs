//! Levels of detail by meshoptimizer's simplifier on the rest pose: what engines ship today,
//! set up as gltfpack sets it up for a skinned mesh (its `simplifyMesh`: normals as attributes
//! of weight 0.5, small parts pruned, triangles kept regular), cut at the same error targets and
//! floor as the papers' methods and drawn by the same renderer, so that the viewer, `shot`,
//! `bench`, `record`, `study` and `export` compare them as equals (issue: comparisons with error
//! bars).
//!
//! meshoptimizer (Kapoulkine, `simplifier.cpp`: half-edge collapses ranked by quadric error with
//! attribute metrics) returns index buffers, not its collapses. Level k+1 is simplified from
//! level k's triangles, so each level's vertices are a subset of the last's, every kept vertex
//! with its own skin weights (meshoptimizer keeps original vertices). Each vertex that goes
//! morphs towards the nearest vertex of the next level in its material (Houle & Poulin §5.1's
//! geomorph, its target found by distance where the papers' methods follow their collapses).
//!
//! Copies of one point (a texture seam's wedges) are given meshoptimizer at one position, the
//! simplifier's welded one ([`weld_positions`]): it finds seams by equal positions, and
//! exporters' copies differ by rounding, which it would take for open borders and never move.

use crate::bake::character::lod::cut::{LevelProbes, MIN_ERROR_GROWTH, RESOLUTION};
use crate::bake::character::lod::levels::{LodLevel, LodOptions};
use crate::bake::character::lod::replay::compact_level;
use crate::bake::character::simplify::mesh::weld_positions;
use crate::bake::character::simplify::{SimplifyInput, influences64};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::Model;
use glam::DVec3;
use rstar::RTree;
use rstar::primitives::GeomWithData;

/// Tries at one error target: each halves meshoptimizer's error target when the level measured
/// over it (as [`CUT_PROBES`](super::cut::CUT_PROBES) for the papers' methods).
const TRIES: usize = 4;

/// What meshoptimizer is handed: the mesh at rest with seams welded, its normals and the
/// vertices it must not move. `report`'s meshopt curve hands it the same, in other listings.
pub(crate) struct Input {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    locks: Vec<bool>,
}

/// How far below its target count meshoptimizer's own stopping may leave a level, in
/// triangles: at least [`OVERSHOOT_MIN`] and [`OVERSHOOT_SHARE`] of the target. It stops after
/// the pass of collapses that passes its target, each collapse taking two triangles: here 2 to
/// 4 below (the walker at 122 keeps 120, the robot at 380 keeps 376). Pruning falls far more
/// (the robot at 122 keeps 10 pruned, 352 not), which is what the floor rule is for.
const OVERSHOOT_MIN: usize = 4;
const OVERSHOOT_SHARE: f32 = 0.02;

impl Input {
    pub(crate) fn new(model: &Model, base: &AnimationSpaceMesh) -> Input {
        let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
        let rest: Vec<DVec3> = base
            .rest_positions(&rest_bones)
            .iter()
            .map(|p| p.as_dvec3())
            .collect();
        let position = weld_positions(&rest, &influences64(base));
        // One point for every copy at it, whatever its skin: meshoptimizer finds seams and
        // connected parts by equal positions, and a part whose halves differ in skin (a plate
        // riveted to two bones) would be two to it, each pruned alone. Where the skins differ,
        // the copies are locked (`skin_seams`).
        let points: Vec<glam::Vec3> = rest.iter().map(|p| p.as_vec3()).collect();
        let groups = crate::geometry::weld::position_groups(
            &points,
            crate::geometry::weld::tolerance_for(&points),
        );
        let mut first = rustc_hash::FxHashMap::default();
        let positions = groups
            .iter()
            .enumerate()
            .map(|(v, g)| first.entry(*g).or_insert(points[v]).to_array())
            .collect();
        let normals = base
            .rest_normals(&rest_bones)
            .iter()
            .map(|n| n.to_array())
            .collect();
        Input {
            locks: skin_seams(&groups, &position),
            positions,
            normals,
        }
    }

    /// The same input with vertex `k` of the new listing being vertex `old[k]` of this one.
    pub(crate) fn listed(&self, old: &[u32]) -> Input {
        fn pick<T: Copy>(a: &[T], old: &[u32]) -> Vec<T> {
            old.iter().map(|&v| a[v as usize]).collect()
        }
        Input {
            positions: pick(&self.positions, old),
            normals: pick(&self.normals, old),
            locks: pick(&self.locks, old),
        }
    }

    /// `indices` simplified towards `floor` triangles and an absolute error of `error` (scene
    /// units; `f32::MAX` for none), whichever comes first. Pruning small parts can overshoot
    /// the count: where it leaves fewer than `floor` triangles, the level is made again
    /// without it, and if that too is under the floor there is none (`None`), the floor
    /// rule of the papers' methods.
    pub(crate) fn simplify(&self, indices: &[u32], floor: u32, error: f32) -> Option<Vec<u32>> {
        let adapter =
            meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&self.positions), 12, 0).ok()?;
        let run = |prune: bool| {
            let mut options = meshopt::SimplifyOptions::Regularize
                | meshopt::SimplifyOptions::ErrorAbsolute
                | meshopt::SimplifyOptions::LockBorder;
            if prune {
                options |= meshopt::SimplifyOptions::Prune;
            }
            meshopt::simplify_with_attributes_and_locks(
                indices,
                &adapter,
                bytemuck::cast_slice(&self.normals),
                &[0.5; 3],
                12,
                &self.locks,
                floor as usize * 3,
                error,
                options,
                None,
            )
        };
        let slack = OVERSHOOT_MIN.max((floor as f32 * OVERSHOOT_SHARE) as usize);
        let least = (floor as usize).saturating_sub(slack) * 3;
        let pruned = run(true);
        if !pruned.is_empty() && pruned.len() >= least {
            return Some(pruned);
        }
        let kept = run(false);
        (!kept.is_empty() && kept.len() >= least).then_some(kept)
    }
}

/// Which render vertices meshoptimizer must not move: those where two welded positions meet
/// at one point (`groups`: each vertex's point) (copies whose skin weights differ, [`weld_positions`]). The two sides of such a
/// skin seam part when the character moves, so each is a border to meshoptimizer, and it
/// would slide each side along its own border and open the seam; the papers' simplifier keeps
/// them as border positions of its own (`CAN_COLLAPSE`).
fn skin_seams(groups: &[u32], position: &[u32]) -> Vec<bool> {
    // Per point: the first welded position met there, or u32::MAX once a second one is.
    let mut first: rustc_hash::FxHashMap<u32, u32> = rustc_hash::FxHashMap::default();
    for (v, &g) in groups.iter().enumerate() {
        let e = first.entry(g).or_insert(position[v]);
        if *e != position[v] {
            *e = u32::MAX;
        }
    }
    groups.iter().map(|g| first[g] == u32::MAX).collect()
}

/// The levels of `model` (full detail `base`) by meshoptimizer under `opts`, finest first, each
/// with its measured error (the largest distance from full detail over the sampled poses, as
/// `probes` measure the papers' methods' levels) and its geomorph map. Returns them and, where
/// meshoptimizer stopped above the floor, how many triangles it kept.
pub fn meshopt_levels(
    model: &Model,
    base: &AnimationSpaceMesh,
    opts: &LodOptions,
    probes: &LevelProbes,
    progress: &(dyn Fn(f32) + Sync),
) -> (Vec<LodLevel>, Option<u32>) {
    let input = Input::new(model, base);
    let full = base.triangle_count() as u32;
    let floor = opts.floor_triangles.min(full);
    let measure = |indices: &[u32], e: f32| -> f32 {
        let tris: Vec<[u32; 3]> = triangles(indices);
        probes
            .label
            .measure(
                &tris,
                |r| base.influences_of(r as usize),
                None,
                (RESOLUTION * e) as f64,
            )
            .max as f32
    };
    // (indices, error) of each level, finest first.
    let mut chain: Vec<(Vec<u32>, f32)> = vec![(base.indices.clone(), 0.0)];
    let push = |chain: &mut Vec<(Vec<u32>, f32)>, indices: Vec<u32>, measured: f32| {
        let last = chain.last().map_or(0.0, |l| l.1);
        let error = measured.max(last);
        if indices.len() >= chain.last().map_or(usize::MAX, |l| l.0.len()) {
            return;
        }
        // A level whose next one is barely less exact would be drawn over a sliver of
        // distances: replaced, as the papers' methods' are.
        if opts.budgets.is_none() && chain.len() > 1 && last * MIN_ERROR_GROWTH >= error {
            chain.pop();
        }
        chain.push((indices, error));
    };
    let mut stopped_short = None;
    match &opts.budgets {
        Some(budgets) => {
            let mut budgets = budgets.clone();
            budgets.sort_unstable_by(|a, b| b.cmp(a));
            for b in budgets {
                let from = &chain.last().expect("full detail").0;
                if let Some(next) = input.simplify(from, b.max(floor), f32::MAX) {
                    let measured = measure(&next, 0.0);
                    push(&mut chain, next, measured);
                }
            }
        }
        None => {
            let diagonal = crate::model::Bounds::of(input.positions.iter().map(|&p| p.into()))
                .map_or(1.0, |b| b.diagonal());
            let mut e = opts.base_error.max(f32::MIN_POSITIVE);
            // Past twice the model's size, no error target asks for less.
            while e <= 2.0 * diagonal {
                let from = chain.last().expect("full detail").0.clone();
                if let Some((next, measured)) = level_within(&input, &from, floor, e, &measure) {
                    push(&mut chain, next, measured);
                }
                let left = chain.last().map_or(full, |l| l.0.len() as u32 / 3);
                progress(1.0 - (left as f32 / full.max(1) as f32));
                if left <= floor {
                    break;
                }
                e *= 2.0;
            }
            let left = chain.last().map_or(full, |l| l.0.len() as u32 / 3);
            if left > floor {
                stopped_short = Some(left);
            }
        }
    }
    progress(1.0);
    let mut levels: Vec<LodLevel> = chain
        .iter()
        .enumerate()
        .map(|(k, (indices, error))| {
            let mut level = compact_level(base, triangles(indices).into_iter(), |r| {
                base.influences_of(r as usize)
            });
            // No collapse sequence: a level's place in the chain stands for its prefix.
            level.prefix = k as u32;
            level.error = *error;
            level.bound = *error;
            level
        })
        .collect();
    link_geomorphs(base, &input, &mut levels);
    (levels, stopped_short)
}

/// The coarsest level meshoptimizer makes from `from` whose measured error is within `e`:
/// its error target `e` first, halved while the level measures over `e` ([`TRIES`] in all).
/// If none is within `e`, the first within `2e` stands, as for the papers' methods; else none.
fn level_within(
    input: &Input,
    from: &[u32],
    floor: u32,
    e: f32,
    measure: &dyn Fn(&[u32], f32) -> f32,
) -> Option<(Vec<u32>, f32)> {
    let mut target = e;
    let mut fallback = None;
    for _ in 0..TRIES {
        let next = input.simplify(from, floor, target)?;
        if next.len() >= from.len() {
            return None;
        }
        let measured = measure(&next, e);
        if measured <= e {
            return Some((next, measured));
        }
        if measured <= 2.0 * e && fallback.is_none() {
            fallback = Some((next, measured));
        }
        target *= 0.5;
    }
    fallback
}

fn triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect()
}

/// A vertex of a level, found by its rest position.
type Located = GeomWithData<[f32; 3], u32>;

/// Each level's geomorph map: a vertex the next level keeps morphs to itself there; one it
/// loses, to the nearest vertex of the next level at rest of the same material (of any, where
/// the next level has none of it).
fn link_geomorphs(base: &AnimationSpaceMesh, input: &Input, levels: &mut [LodLevel]) {
    for k in 0..levels.len().saturating_sub(1) {
        let next = &levels[k + 1];
        let mut index = vec![u32::MAX; base.vertex_count()];
        for (i, &r) in next.source.iter().enumerate() {
            index[r as usize] = i as u32;
        }
        let located: RTree<Located> = RTree::bulk_load(
            next.source
                .iter()
                .enumerate()
                .map(|(i, &r)| Located::new(input.positions[r as usize], i as u32))
                .collect(),
        );
        let material = |r: u32| base.materials.get(r as usize).copied();
        let map: Vec<u32> = levels[k]
            .source
            .iter()
            .map(|&r| match index[r as usize] {
                u32::MAX => {
                    let p = input.positions[r as usize];
                    let mut near = located.nearest_neighbor_iter(p);
                    let first = near.next().map_or(0, |l| l.data);
                    std::iter::once(first)
                        .chain(near.take(64).map(|l| l.data))
                        .find(|&i| material(next.source[i as usize]) == material(r))
                        .unwrap_or(first)
                }
                i => i,
            })
            .collect();
        levels[k].geomorph = map;
    }
}
