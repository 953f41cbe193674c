//! The limits on what one model file may expand to (`--limit NAME=VALUE`), which
//! [`super::validate`] checks a file against before anything reads its data.

/// What one model may ask for. Each bound keeps a small hostile file from taking the machine's
/// memory or minutes of baking; a real model past one can raise it (`--limit NAME=VALUE`).
///
/// The bounds are on what a file *expands to*, not only on what it declares piece by piece: a
/// primitive drawn by 5,000 nodes counts 5,000 times, an accessor with no data (all zeros, or
/// a few sparse values) counts every element it claims, a compressed view counts what it
/// decodes to, and a texture counts once per material that samples it (each is a layer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Size of the file and of each file it refers to, in MiB.
    pub file_mb: u64,
    /// Nodes in the file.
    pub nodes: usize,
    /// Joints of all skins together (and bones of the merged skeleton).
    pub joints: usize,
    /// Length of one clip in seconds (the animation texture holds 30 frames a second of it).
    pub clip_seconds: f32,
    /// Seconds of all clips together.
    pub clips_seconds: f32,
    /// Textured materials (each is a layer of the material texture array at every level of
    /// detail; plain colours share one, see [`super::palette`]).
    pub materials: usize,
    /// Width or height of one texture image, in texels.
    pub texture_side: u32,
    /// Decoded texels of every textured material's image together, in MiB (RGBA, 4 bytes a
    /// texel; an image two materials use counts twice).
    pub texture_mb: u64,
    /// Vertices of every primitive drawn, each as often as nodes draw it.
    pub vertices: u64,
    /// Triangles of every primitive drawn, each as often as nodes draw it.
    pub triangles: u64,
    /// Bytes of every accessor's elements and every decoded compressed view together, in MiB.
    pub decoded_mb: u64,
    /// Buffers and images may name files outside the model's folder (absolute paths, `..`,
    /// `file:` URIs, symbolic links that lead out). Off by default: a viewer that opens files
    /// from strangers reads only what lies beside the model (`--allow-outside-files`).
    pub outside_files: bool,
}

impl Limits {
    pub const DEFAULT: Limits = Limits {
        file_mb: 1024,
        nodes: 100_000,
        joints: 1024,
        clip_seconds: 600.0,
        clips_seconds: 3600.0,
        materials: 256,
        texture_side: 8192,
        texture_mb: 1024,
        vertices: 4_000_000,
        triangles: 4_000_000,
        decoded_mb: 1024,
        outside_files: false,
    };

    /// The names `--limit` takes, with what each bounds.
    pub const NAMES: [(&'static str, &'static str); 11] = [
        (
            "file-mb",
            "size of a model file and of each file it refers to, MiB",
        ),
        ("nodes", "nodes in a file"),
        (
            "joints",
            "bones: the skins' joint nodes (each once, however many skins list it), and the nodes unskinned parts ride on",
        ),
        ("clip-seconds", "length of a clip"),
        ("clips-seconds", "length of all clips together"),
        ("materials", "textured materials of a model"),
        ("texture-side", "width or height of a texture image"),
        (
            "texture-mb",
            "decoded texels of all textured materials, MiB",
        ),
        (
            "vertices",
            "vertices drawn, each primitive as often as nodes draw it",
        ),
        (
            "triangles",
            "triangles drawn, each primitive as often as nodes draw it",
        ),
        (
            "decoded-mb",
            "bytes of all accessors and decoded compressed views, MiB",
        ),
    ];

    /// The value of the limit `name` (one of [`Limits::NAMES`]), as `--limit` writes it.
    pub fn value(&self, name: &str) -> Option<String> {
        Some(match name {
            "file-mb" => self.file_mb.to_string(),
            "nodes" => self.nodes.to_string(),
            "joints" => self.joints.to_string(),
            "clip-seconds" => self.clip_seconds.to_string(),
            "clips-seconds" => self.clips_seconds.to_string(),
            "materials" => self.materials.to_string(),
            "texture-side" => self.texture_side.to_string(),
            "texture-mb" => self.texture_mb.to_string(),
            "vertices" => self.vertices.to_string(),
            "triangles" => self.triangles.to_string(),
            "decoded-mb" => self.decoded_mb.to_string(),
            _ => return None,
        })
    }

    /// Applies one `NAME=VALUE` (see [`Limits::NAMES`]).
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let names = || {
            Self::NAMES
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (name, value) = assignment
            .split_once('=')
            .ok_or_else(|| format!("'{assignment}' is not NAME=VALUE (names: {})", names()))?;
        // Sizes and counts past 2⁴⁰ are slips of the keyboard; bounding them keeps the
        // arithmetic on them (MiB to bytes) from wrapping.
        let number = |most: u64| -> Result<u64, String> {
            value
                .trim()
                .parse::<u64>()
                .ok()
                .filter(|&v| v > 0 && v <= most)
                .ok_or_else(|| {
                    format!("limit {name}: '{value}' is not a whole number from 1 to {most}")
                })
        };
        const MIB: u64 = 1 << 24; // 16 TiB in MiB
        const COUNT: u64 = 1 << 40;
        match name.trim() {
            "file-mb" => self.file_mb = number(MIB)?,
            "nodes" => self.nodes = number(COUNT)? as usize,
            "joints" => self.joints = number(1 << 20)? as usize,
            "clip-seconds" => self.clip_seconds = number(1 << 24)? as f32,
            "clips-seconds" => self.clips_seconds = number(1 << 24)? as f32,
            "materials" => self.materials = number(1 << 20)? as usize,
            "texture-side" => self.texture_side = number(u32::MAX as u64)? as u32,
            "texture-mb" => self.texture_mb = number(MIB)?,
            "vertices" => self.vertices = number(COUNT)?,
            "triangles" => self.triangles = number(COUNT)?,
            "decoded-mb" => self.decoded_mb = number(MIB)?,
            other => return Err(format!("no limit named '{other}' (names: {})", names())),
        }
        Ok(())
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}
