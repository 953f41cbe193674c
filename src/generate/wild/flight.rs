//! A creature whose clip carries it: root motion, as a flying or swooping clip is exported,
//! the whole skeleton moved along the flight by its root node's translation. The union of its
//! poses is the flight's size, not the creature's.

use crate::model::{Channel, ChannelTarget, Interpolation, Model};
use glam::{Vec3, Vec4};

/// Keys of the flight, evenly spread over the clip (ends included).
const KEYS: usize = 33;

/// `model` with its first clip (limbs and all) also flying: its skeleton's root node carried
/// once round a circle of `radius` (in the root's parent space, which for the project's
/// models is the scene's metres) while climbing to `climb` above its start and back, over the
/// clip's length. The clip keeps its name; a root translation channel it had is replaced.
pub fn flying(model: &Model, radius: f32, climb: f32) -> Model {
    let mut out = model.clone();
    out.name = format!("{} flying", model.name);
    let Some(root) = out.skeleton.nodes.iter().position(|n| n.parent.is_none()) else {
        return out;
    };
    let rest = out.skeleton.nodes[root].rest.translation;
    let Some(clip) = out.clips.first_mut() else {
        return out;
    };
    let duration = clip.duration.max(1e-3);
    let times: Vec<f32> = (0..KEYS)
        .map(|k| duration * k as f32 / (KEYS - 1) as f32)
        .collect();
    let values: Vec<Vec4> = times
        .iter()
        .map(|&t| (rest + flight_offset(radius, climb, duration, t)).extend(0.0))
        .collect();
    clip.channels
        .retain(|c| !(c.node as usize == root && c.target == ChannelTarget::Translation));
    clip.channels.push(Channel {
        node: root as u32,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times,
        values,
    });
    out
}

/// Where [`flying`] has carried the root at `t` seconds into a clip of `duration`, against
/// its start.
pub fn flight_offset(radius: f32, climb: f32, duration: f32, t: f32) -> Vec3 {
    let a = std::f32::consts::TAU * t / duration.max(1e-3);
    Vec3::new(
        radius * a.sin(),
        climb * 0.5 * (1.0 - a.cos()),
        radius * (1.0 - a.cos()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flight_carries_the_root_round_its_circle() {
        let robot = crate::import::load_model("robot").unwrap();
        let flyer = flying(&robot, 3.0, 2.0);
        let clip = &flyer.clips[0];
        let at = |t: f32| {
            let g = crate::anim::bone_matrices(&flyer.skeleton, Some(clip), t);
            let p = crate::anim::linear_blend_skinning(&flyer.mesh, &flyer.skeleton, &g);
            p.iter().sum::<Vec3>() / p.len() as f32
        };
        let d = clip.duration;
        let moved = at(d / 2.0) - at(0.0);
        // Half way round: 2 radii along z and the whole climb, whatever the limbs do.
        let expect = flight_offset(3.0, 2.0, d, d / 2.0);
        assert!((moved - expect).length() < 0.3, "{moved} against {expect}");
    }
}
