//! H.264 in an MP4 file: OpenH264 (crate `openh264`, built from source) encodes, the `mp4` crate
//! muxes. No external program is needed, and the file plays in common players and browsers
//! (constrained baseline profile, one IDR frame a second, `avc1` sample entry).
//!
//! The file is written under a temporary name beside the final one and renamed when complete,
//! so an interrupted recording never leaves half a file under the final name.

use crate::atomic::AtomicFile;
use anyhow::{Context, Result, anyhow, bail};
use openh264::OpenH264API;
use openh264::encoder::{
    Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod, QpRange, RateControlMode,
    UsageType,
};
use openh264::formats::{RgbaSliceU8, YUVBuffer, YUVSource};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// NAL unit types (ITU-T H.264 Table 7-1) the muxer treats apart.
const NAL_IDR: u8 = 5;
const NAL_SPS: u8 = 7;
const NAL_PPS: u8 = 8;

/// The H.264 quantizer of every frame (0 lossless … 51 coarsest; about 20 is visually clean).
const QP: u8 = 20;

/// Track time units per frame: the track's timescale is `fps` times this.
const TICKS_PER_FRAME: u32 = 1000;

pub struct Mp4Video {
    encoder: Encoder,
    yuv: YUVBuffer,
    width: u32,
    height: u32,
    fps: u32,
    /// Opened at the first frame, whose SPS and PPS the track's sample entry needs.
    mp4: Option<mp4::Mp4Writer<BufWriter<File>>>,
    frames: u32,
    /// Written beside `out` and moved there by [`Mp4Video::finish`]; an unfinished video (an
    /// error, a panic, Ctrl-C) leaves nothing behind.
    file: Option<AtomicFile>,
    out: PathBuf,
}

impl Mp4Video {
    /// A video `width`×`height` (both even) at `fps` frames a second, to be written to `out`.
    pub fn create(out: &Path, width: u32, height: u32, fps: u32) -> Result<Mp4Video> {
        if !width.is_multiple_of(2) || !height.is_multiple_of(2) || width < 16 || height < 16 {
            bail!("video size {width}x{height}: H.264 needs even sides of at least 16 pixels");
        }
        if !(1..=240).contains(&fps) {
            bail!("{fps} frames a second: must be between 1 and 240");
        }
        // Constant quality rather than a bit rate: rate control could only hold a rate by
        // skipping frames, and every frame must be in the file (exactly seconds × fps). A
        // fine quantizer keeps compression artefacts well below the level-of-detail
        // differences a study asks about.
        let config = EncoderConfig::new()
            .usage_type(UsageType::CameraVideoRealTime)
            .rate_control_mode(RateControlMode::Off)
            .qp(QpRange::new(QP, QP))
            .max_frame_rate(FrameRate::from_hz(fps as f32))
            .skip_frames(false)
            .intra_frame_period(IntraFramePeriod::from_num_frames(fps));
        let encoder = Encoder::with_api_config(OpenH264API::from_source(), config)
            .map_err(|e| anyhow!("cannot start the H.264 encoder: {e}"))?;
        Ok(Mp4Video {
            encoder,
            yuv: YUVBuffer::new(width as usize, height as usize),
            width,
            height,
            fps,
            mp4: None,
            frames: 0,
            file: Some(AtomicFile::create(out)?),
            out: out.to_path_buf(),
        })
    }

    /// Appends one frame of tightly packed RGBA8 pixels.
    pub fn push(&mut self, rgba: &[u8]) -> Result<()> {
        let (w, h) = (self.width as usize, self.height as usize);
        if rgba.len() != w * h * 4 {
            bail!("frame of {} bytes for {w}x{h} RGBA", rgba.len());
        }
        self.yuv.read_rgb(RgbaSliceU8::new(rgba, (w, h)));
        let stream = self
            .encoder
            .encode(&self.yuv)
            .map_err(|e| anyhow!("H.264 encoding failed: {e}"))?;
        let keyframe = matches!(stream.frame_type(), FrameType::IDR | FrameType::I);
        let annex_b = stream.to_vec();
        // Annex B (start codes) to the MP4's length-prefixed NAL units; SPS and PPS go into
        // the sample entry instead.
        let (mut sps, mut pps, mut sample) = (None, None, Vec::with_capacity(annex_b.len()));
        let mut idr = false;
        for nal in openh264::nal_units(&annex_b) {
            let body = strip_start_code(nal);
            let Some(&first) = body.first() else {
                continue;
            };
            match first & 0x1f {
                NAL_SPS => sps = Some(body.to_vec()),
                NAL_PPS => pps = Some(body.to_vec()),
                kind => {
                    idr |= kind == NAL_IDR;
                    sample.extend_from_slice(&(body.len() as u32).to_be_bytes());
                    sample.extend_from_slice(body);
                }
            }
        }
        if self.mp4.is_none() {
            let (Some(sps), Some(pps)) = (sps, pps) else {
                bail!("the H.264 encoder gave no SPS/PPS with its first frame");
            };
            self.mp4 = Some(self.open(sps, pps)?);
        }
        let mp4 = self.mp4.as_mut().expect("opened above");
        mp4.write_sample(
            1,
            &mp4::Mp4Sample {
                start_time: self.frames as u64 * TICKS_PER_FRAME as u64,
                duration: TICKS_PER_FRAME,
                rendering_offset: 0,
                is_sync: idr || keyframe,
                bytes: bytes::Bytes::from(sample),
            },
        )
        .with_context(|| format!("{}: cannot write", self.out.display()))?;
        self.frames += 1;
        Ok(())
    }

    fn open(&self, sps: Vec<u8>, pps: Vec<u8>) -> Result<mp4::Mp4Writer<BufWriter<File>>> {
        let file = self
            .file
            .as_ref()
            .expect("present until finished")
            .handle()
            .with_context(|| format!("{}: cannot write", self.out.display()))?;
        let brand = |s: &str| s.parse::<mp4::FourCC>().expect("four letters");
        let mut mp4 = mp4::Mp4Writer::write_start(
            BufWriter::new(file),
            &mp4::Mp4Config {
                major_brand: brand("isom"),
                minor_version: 512,
                compatible_brands: vec![brand("isom"), brand("iso2"), brand("avc1"), brand("mp41")],
                timescale: 1000,
            },
        )
        .with_context(|| format!("{}: cannot write", self.out.display()))?;
        mp4.add_track(&mp4::TrackConfig {
            track_type: mp4::TrackType::Video,
            timescale: self.fps * TICKS_PER_FRAME,
            language: "und".into(),
            media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                width: self.width as u16,
                height: self.height as u16,
                seq_param_set: sps,
                pic_param_set: pps,
            }),
        })
        .with_context(|| format!("{}: cannot write", self.out.display()))?;
        Ok(mp4)
    }

    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Completes the file and moves it under its final name.
    pub fn finish(mut self) -> Result<()> {
        let Some(mut mp4) = self.mp4.take() else {
            bail!("{}: no frame to write", self.out.display());
        };
        mp4.write_end()
            .with_context(|| format!("{}: cannot write", self.out.display()))?;
        let mut file = mp4.into_writer();
        std::io::Write::flush(&mut file)
            .with_context(|| format!("{}: cannot write", self.out.display()))?;
        drop(file);
        self.file.take().expect("present until finished").commit()
    }
}

/// A NAL unit without its Annex B start code (00 00 01 or 00 00 00 01).
fn strip_start_code(nal: &[u8]) -> &[u8] {
    let zeros = nal.iter().take_while(|&&b| b == 0).count();
    if zeros >= 2 && nal.get(zeros) == Some(&1) {
        &nal[zeros + 1..]
    } else {
        nal
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_codes_are_stripped_whatever_their_length() {
        assert_eq!(strip_start_code(&[0, 0, 0, 1, 0x67, 9]), &[0x67, 9]);
        assert_eq!(strip_start_code(&[0, 0, 1, 0x68]), &[0x68]);
        assert_eq!(strip_start_code(&[0x65, 0, 0, 1]), &[0x65, 0, 0, 1]);
    }

    #[test]
    fn a_video_holds_every_frame_pushed_and_decodes() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("clip.mp4");
        let (w, h) = (64u32, 48u32);
        let mut video = Mp4Video::create(&out, w, h, 10).unwrap();
        for k in 0..23u32 {
            let frame: Vec<u8> = (0..w * h)
                .flat_map(|i| {
                    let (x, y) = (i % w, i / w);
                    [(x * 4 + k * 8) as u8, (y * 5) as u8, 128, 255]
                })
                .collect();
            video.push(&frame).unwrap();
        }
        assert!(!out.exists(), "nothing under the final name before finish");
        video.finish().unwrap();
        let info = probe(&out).unwrap();
        assert_eq!(info.frames, 23);
        assert_eq!((info.width, info.height), (64, 48));
        assert!((info.fps - 10.0).abs() < 1e-6);
        assert_eq!(info.decoded, 23);
        let left = std::fs::read_dir(out.parent().unwrap()).unwrap().count();
        assert_eq!(left, 1, "the clip alone, no temporary file");
    }

    #[test]
    fn a_dropped_video_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("clip.mp4");
        let mut video = Mp4Video::create(&out, 32, 32, 5).unwrap();
        video.push(&vec![90; 32 * 32 * 4]).unwrap();
        drop(video);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        assert!(Mp4Video::create(&out, 33, 32, 5).is_err());
    }
}

/// What [`probe`] finds in an MP4 file.
#[derive(Clone, Debug, PartialEq)]
pub struct VideoInfo {
    pub frames: u32,
    pub width: u16,
    pub height: u16,
    pub fps: f64,
    /// Samples the H.264 decoder turned into pictures.
    pub decoded: u32,
}

/// Parses an MP4 file's video track and decodes every sample: how many frames it holds, and
/// how many decode to a picture.
pub fn probe(path: &Path) -> Result<VideoInfo> {
    let mut clip = ClipReader::open(path)?;
    let mut decoded = 0;
    while clip.next_frame()?.is_some() {
        decoded += 1;
    }
    Ok(VideoInfo {
        frames: clip.frames,
        width: clip.width,
        height: clip.height,
        fps: clip.fps,
        decoded,
    })
}

/// Plays an MP4 file's H.264 video track frame by frame, as RGBA pictures.
pub struct ClipReader {
    path: PathBuf,
    reader: mp4::Mp4Reader<std::io::Cursor<Vec<u8>>>,
    track: u32,
    /// SPS and PPS in Annex B, fed to the decoder before the first sample.
    header: Vec<u8>,
    decoder: openh264::decoder::Decoder,
    next: u32,
    pub frames: u32,
    pub width: u16,
    pub height: u16,
    pub fps: f64,
}

impl ClipReader {
    pub fn open(path: &Path) -> Result<ClipReader> {
        let bytes =
            std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
        let size = bytes.len() as u64;
        let reader = mp4::Mp4Reader::read_header(std::io::Cursor::new(bytes), size)
            .map_err(|e| anyhow!("{}: not an MP4 file: {e}", path.display()))?;
        let (&track, t) = reader
            .tracks()
            .iter()
            .find(|(_, t)| matches!(t.track_type(), Ok(mp4::TrackType::Video)))
            .ok_or_else(|| anyhow!("{}: no video track", path.display()))?;
        let avc = &t
            .trak
            .mdia
            .minf
            .stbl
            .stsd
            .avc1
            .as_ref()
            .ok_or_else(|| anyhow!("{}: the video is not H.264", path.display()))?
            .avcc;
        let mut header = Vec::new();
        for set in avc
            .sequence_parameter_sets
            .iter()
            .chain(&avc.picture_parameter_sets)
        {
            header.extend_from_slice(&[0, 0, 0, 1]);
            header.extend_from_slice(&set.bytes);
        }
        let (frames, width, height, fps) =
            (t.sample_count(), t.width(), t.height(), t.frame_rate());
        let decoder = openh264::decoder::Decoder::new()
            .map_err(|e| anyhow!("cannot start the H.264 decoder: {e}"))?;
        Ok(ClipReader {
            path: path.to_path_buf(),
            reader,
            track,
            header,
            decoder,
            next: 1,
            frames,
            width,
            height,
            fps,
        })
    }

    /// The next frame as RGBA8 pixels, `None` after the last. A sample that decodes to no
    /// picture is an error: every frame of a clip must show.
    pub fn next_frame(&mut self) -> Result<Option<image::RgbaImage>> {
        if self.next > self.frames {
            return Ok(None);
        }
        let k = self.next;
        self.next += 1;
        let path = &self.path;
        let sample = self
            .reader
            .read_sample(self.track, k)
            .map_err(|e| anyhow!("{}: sample {k}: {e}", path.display()))?
            .ok_or_else(|| anyhow!("{}: sample {k} is missing", path.display()))?;
        let mut annex_b = if k == 1 {
            self.header.clone()
        } else {
            Vec::new()
        };
        let mut rest = &sample.bytes[..];
        while rest.len() >= 4 {
            let n = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
            let body = rest
                .get(4..4 + n)
                .ok_or_else(|| anyhow!("{}: sample {k} is cut short", path.display()))?;
            annex_b.extend_from_slice(&[0, 0, 0, 1]);
            annex_b.extend_from_slice(body);
            rest = &rest[4 + n..];
        }
        let yuv = self
            .decoder
            .decode(&annex_b)
            .map_err(|e| anyhow!("{}: frame {k} does not decode: {e}", path.display()))?
            .ok_or_else(|| anyhow!("{}: frame {k} decodes to no picture", path.display()))?;
        let (w, h) = yuv.dimensions();
        let mut rgba = vec![0u8; w * h * 4];
        yuv.write_rgba8(&mut rgba);
        let image = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
            .ok_or_else(|| anyhow!("{}: frame {k} has a bad size", path.display()))?;
        Ok(Some(image))
    }
}
