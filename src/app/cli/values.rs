//! Parsers of the command line's values: numbers in their ranges, sizes, sample counts,
//! camera placements, and the messages that say what a wrong one should be.

use crate::bake::foliage::billboard::chain::MIN_EPSILON_GROWTH;
use crate::scene::{Camera, LodMethod};

pub(crate) fn parse_limit(s: &str) -> Result<String, String> {
    crate::import::validate::Limits::default().set(s)?;
    Ok(s.to_string())
}

pub(crate) fn parse_export_tolerance(s: &str) -> Result<f32, String> {
    parse_in(s, "tolerance", 0.25..=16.0)
}

pub(crate) fn parse_in(
    s: &str,
    what: &str,
    range: std::ops::RangeInclusive<f32>,
) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if range.contains(&x) {
            Ok(x)
        } else {
            Err(format!(
                "{what} '{s}' must be between {} and {}",
                range.start(),
                range.end()
            ))
        }
    })
}

pub(crate) fn parse_first_epsilon(s: &str) -> Result<f32, String> {
    parse_in(s, "first epsilon", 0.0005..=0.2)
}

pub(crate) fn parse_epsilon_growth(s: &str) -> Result<f32, String> {
    parse_in(s, "epsilon growth", MIN_EPSILON_GROWTH..=8.0)
}

pub(crate) fn parse_wind(s: &str) -> Result<f32, String> {
    parse_in(s, "wind strength", 0.0..=5.0)
}

pub(crate) fn parse_compare(s: &str) -> Result<(LodMethod, LodMethod), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not A,B (two methods)"))?;
    Ok((
        crate::choice::parse(a, "a method")?,
        crate::choice::parse(b, "a method")?,
    ))
}

pub(crate) fn parse_number(s: &str) -> Result<f32, String> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("'{s}' is not a number"))
}

/// A frame count: at least one, at most 100,000 (an hour at 30 frames a second).
pub(crate) fn parse_frames(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .ok()
        .filter(|n| (1..=100_000).contains(n))
        .ok_or_else(|| format!("'{s}' is not a frame count from 1 to 100000"))
}

pub(crate) fn parse_non_negative(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(format!("'{s}' must not be negative"))
        }
    })
}

/// A span of time a command runs or waits for: finite, not negative, at most a day (a larger
/// one is a slip of the keyboard that would keep the command running for ever).
pub(crate) fn parse_seconds(s: &str) -> Result<f32, String> {
    parse_in(s, "seconds", 0.0..=86_400.0)
}

/// A recorded clip's length: at most an hour (108,000 frames at 30 a second).
pub(crate) fn parse_clip_length(s: &str) -> Result<f32, String> {
    parse_in(s, "clip length in seconds", 0.0..=3600.0)
}

pub(crate) fn parse_tolerance(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if (0.25..=16.0).contains(&x) {
            Ok(x)
        } else {
            Err(format!(
                "tolerance '{s}' must be between 0.25 and 16 pixels"
            ))
        }
    })
}

pub(crate) fn parse_hysteresis(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if (0.0..=0.9).contains(&x) {
            Ok(x)
        } else {
            Err(format!("hysteresis '{s}' must be between 0 and 0.9"))
        }
    })
}

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in '{s}'"))?;
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(format!("size '{s}' must be between 1x1 and 8192x8192"));
    }
    Ok((w, h))
}

/// A [`parse_size`] that H.264 (OpenH264) can encode, refused before anything is rendered.
pub(crate) fn parse_video_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = parse_size(s)?;
    if !w.is_multiple_of(2) || !h.is_multiple_of(2) || w < 16 || h < 16 {
        return Err(format!(
            "video size '{s}': H.264 needs even sides of at least 16 pixels"
        ));
    }
    let (long, short) = (w.max(h), w.min(h));
    if long > 3840 || short > 2160 {
        return Err(format!(
            "video size '{s}': the H.264 encoder takes at most 3840x2160 (or 2160x3840)"
        ));
    }
    Ok((w, h))
}

pub(crate) fn parse_samples(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err(format!("'{s}': multisampling must be 1 or 4")),
    }
}

pub(crate) fn parse_camera(s: &str) -> Result<Camera, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not YAW,PITCH,DISTANCE[,X,Y,Z]"))?;
    if !(v.len() == 3 || v.len() == 6) || v.iter().any(|x| !x.is_finite()) || v[2] <= 0.0 {
        return Err(format!("'{s}' is not YAW,PITCH,DISTANCE[,X,Y,Z]"));
    }
    let target = if v.len() == 6 {
        glam::Vec3::new(v[3], v[4], v[5])
    } else {
        glam::Vec3::new(0.0, 1.0, 0.0)
    };
    Ok(Camera::new(target, v[0], v[1], v[2]))
}

/// A setting `lodlab soak`'s cycle changes (`--vary`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Setting {
    Method,
    Transition,
    Foliage,
    Count,
    Size,
}

/// A list of choices in the order given, each once.
pub fn dedup<T: PartialEq>(list: Vec<T>) -> Vec<T> {
    let mut out = Vec::with_capacity(list.len());
    for x in list {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

crate::choice! {
    /// What `shot` draws its figures over.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum Backdrop {
        /// The sky, the ground and the shadows, as the viewer draws them.
        #[default]
        Scene => "scene",
        /// Black, without ground, shadows or fog: the figures alone, for masks, figures and
        /// comparisons with other renderers.
        Plain => "plain",
    }
}
