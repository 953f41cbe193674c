//! A glTF file's animations read as clips: translation, rotation and scale channels, STEP,
//! LINEAR and CUBICSPLINE, their targets renumbered as the character's joints are.

use crate::model::{Channel, ChannelTarget, Clip, Interpolation};
use glam::{Vec3, Vec4};
use gltf::animation::util::ReadOutputs;

/// The largest translation or scale a clip's key may hold: 10⁹ is a million kilometres in
/// metres, ten thousand in centimetres.
pub(crate) const MAX_KEY_VALUE: f32 = 1e9;

pub(crate) fn read_clip<'a, 's, F>(
    anim: &'a gltf::Animation<'a>,
    buffer: F,
    remap: &[u32],
) -> Result<Option<Clip>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let name = anim
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("clip{}", anim.index()));
    let mut channels = Vec::new();
    for ch in anim.channels() {
        let node = ch.target().node().index();
        if remap[node] == u32::MAX {
            continue; // animates something that is not part of this skeleton
        }
        let target = match ch.target().property() {
            gltf::animation::Property::Translation => ChannelTarget::Translation,
            gltf::animation::Property::Rotation => ChannelTarget::Rotation,
            gltf::animation::Property::Scale => ChannelTarget::Scale,
            gltf::animation::Property::MorphTargetWeights => continue,
        };
        let interpolation = match ch.sampler().interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        let reader = ch.reader(buffer.clone());
        let times: Vec<f32> = reader
            .read_inputs()
            .ok_or_else(|| format!("clip '{name}': a channel has no key times"))?
            .collect();
        let values: Vec<Vec4> = match reader.read_outputs() {
            Some(ReadOutputs::Translations(it)) => it.map(|v| Vec3::from(v).extend(0.0)).collect(),
            Some(ReadOutputs::Scales(it)) => it.map(|v| Vec3::from(v).extend(0.0)).collect(),
            Some(ReadOutputs::Rotations(it)) => it.into_f32().map(Vec4::from).collect(),
            _ => return Err(format!("clip '{name}': a channel has no key values")),
        };
        if times.is_empty() {
            return Err(format!("clip '{name}': a channel has no keys"));
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(format!(
                "clip '{name}': key times are not finite and strictly increasing"
            ));
        }
        let per_key = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if values.len() != times.len() * per_key {
            return Err(format!(
                "clip '{name}': {} key values for {} key times",
                values.len(),
                times.len()
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("clip '{name}': a key value is not finite"));
        }
        // Finite but past any scene: a translation of 10³⁰ puts the character where no
        // camera framing can see it, or anything else, and squares to infinity in every
        // distance measured on it.
        if target != ChannelTarget::Rotation
            && let Some(v) = values
                .iter()
                .find(|v| v.abs().max_element() > MAX_KEY_VALUE)
        {
            return Err(format!(
                "clip '{name}': a {} key of {} is out of range (at most {MAX_KEY_VALUE:e} in \
                 the file's units)",
                if target == ChannelTarget::Translation {
                    "translation"
                } else {
                    "scale"
                },
                v.abs().max_element()
            ));
        }
        channels.push(Channel {
            node: remap[node],
            target,
            interpolation,
            times,
            values,
        });
    }
    if channels.is_empty() {
        return Ok(None);
    }
    let duration = channels
        .iter()
        .map(|c| *c.times.last().expect("non-empty"))
        .fold(0.0f32, f32::max);
    // `-1` marks "not given in the file": the caller guesses once the model's size is known.
    let ground_speed = anim
        .extras()
        .as_ref()
        .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
        .and_then(|v| v.get("ground_speed").and_then(|s| s.as_f64()))
        .map(|s| s as f32)
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(-1.0);
    Ok(Some(Clip {
        name,
        duration,
        channels,
        ground_speed,
    }))
}
